#include "rastercheck/geometry/TriangleTests.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/geometry/Predicates.h"

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;

// ---- exact part: only orient3d/orient2d decide ---------------------------------------------

// A point projected on a coordinate plane by dropping one axis. Dropping a coordinate is exact,
// and when the dropped axis has a non-zero component along the normal of the plane holding the
// points, orient2d of the projections has the sign of the 3-D orientation within that plane.
struct Point2
{
    double x, y;
};

Point2 project(const Vec &p, int dropped)
{
    return {p[(dropped + 1) % 3], p[(dropped + 2) % 3]};
}

int orient(const Point2 &a, const Point2 &b, const Point2 &c)
{
    return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

bool sameStrictSign(const int s[3])
{
    return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

bool allZero(const int s[3])
{
    return s[0] == 0 && s[1] == 0 && s[2] == 0;
}

// (b - a) x (c - a) is zero exactly when its three components, the orientations of the three
// coordinate projections, are.
bool collinear(const Vec &a, const Vec &b, const Vec &c)
{
    for (int dropped = 0; dropped < 3; ++dropped)
        if (orient(project(a, dropped), project(b, dropped), project(c, dropped)) != 0)
            return false;
    return true;
}

// An axis whose projection keeps the non-degenerate triangle abc a triangle, preferring the one
// the (rounded) normal points along most, which keeps later floating-point work well conditioned.
int projectionAxis(const Vec &a, const Vec &b, const Vec &c)
{
    const Vec n = ((b - a).cross(c - a)).cwiseAbs();
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&n](int i, int j) { return n[i] > n[j]; });
    for (int dropped : order)
        if (orient(project(a, dropped), project(b, dropped), project(c, dropped)) != 0)
            return dropped;
    return order[0];  // unreachable for a non-degenerate triangle
}

bool intervalsOverlap(double a0, double a1, double b0, double b1)
{
    return std::min(a0, a1) <= std::max(b0, b1) && std::min(b0, b1) <= std::max(a0, a1);
}

// Collinear points are ordered along the line by any coordinate that is not the same for all of
// them, so the segments overlap exactly when those 1-D intervals do.
bool collinearSegmentsOverlap(const Point2 &a, const Point2 &b, const Point2 &c, const Point2 &d)
{
    if (a.x != b.x || a.x != c.x || a.x != d.x)
        return intervalsOverlap(a.x, b.x, c.x, d.x);
    return intervalsOverlap(a.y, b.y, c.y, d.y);
}

// Closed segments ab and cd in the plane, given the four orientations of their endpoints.
bool segmentsCross(int abc, int abd, int cda, int cdb)
{
    // One segment wholly on one side of the other's line separates them. Otherwise they meet,
    // unless all four points are collinear, which the caller decides by coordinates.
    return abc * abd <= 0 && cda * cdb <= 0;
}

bool segmentsIntersect2d(const Point2 &a, const Point2 &b, const Point2 &c, const Point2 &d)
{
    const int abc = orient(a, b, c), abd = orient(a, b, d), cda = orient(c, d, a), cdb = orient(c, d, b);
    if (abc == 0 && abd == 0 && cda == 0 && cdb == 0)
        return collinearSegmentsOverlap(a, b, c, d);
    return segmentsCross(abc, abd, cda, cdb);
}

bool segmentsIntersect3d(const Vec &a, const Vec &b, const Vec &c, const Vec &d)
{
    if (orient3d(a, b, c, d) != 0)
        return false;
    // Coplanar: a projection in which some triple is not collinear is one-to-one on their plane.
    for (int dropped = 0; dropped < 3; ++dropped)
    {
        const Point2 a2 = project(a, dropped), b2 = project(b, dropped), c2 = project(c, dropped),
                     d2 = project(d, dropped);
        const int abc = orient(a2, b2, c2), abd = orient(a2, b2, d2), cda = orient(c2, d2, a2),
                  cdb = orient(c2, d2, b2);
        if (abc != 0 || abd != 0 || cda != 0 || cdb != 0)
            return segmentsCross(abc, abd, cda, cdb);
    }
    // All four points on one line: compare along a coordinate in which they differ.
    for (int k = 0; k < 3; ++k)
        if (a[k] != b[k] || a[k] != c[k] || a[k] != d[k])
            return intervalsOverlap(a[k], b[k], c[k], d[k]);
    return true;  // four copies of one point
}

bool insideTriangle2d(const Point2 &x, const Point2 &p, const Point2 &q, const Point2 &r, int orientation)
{
    return orient(p, q, x) * orientation >= 0 && orient(q, r, x) * orientation >= 0 &&
           orient(r, p, x) * orientation >= 0;
}

// ---- floating-point part: distances and witness points -------------------------------------

double clamp01(double x)
{
    return std::min(1.0, std::max(0.0, x));
}

double pointSegment(const Vec &p, const Vec &a, const Vec &b, Vec &onSegment)
{
    const Vec u = b - a;
    const double uu = u.squaredNorm();
    const double s = uu > 0.0 ? clamp01((p - a).dot(u) / uu) : 0.0;
    onSegment = a + s * u;
    return (p - onSegment).squaredNorm();
}

// Squared distance between segments ab and cd, with a closest pair. The distance is convex in the
// two segment parameters: an interior critical point is the minimum, and otherwise the minimum lies
// on the boundary of the parameter square, where it is an endpoint-to-segment distance. Taking the
// boundary route for (nearly) parallel segments avoids the ill-conditioned solve.
double segmentSegment(const Vec &a, const Vec &b, const Vec &c, const Vec &d, Vec &x, Vec &y)
{
    const Vec u = b - a, v = d - c, w = a - c;
    const double uu = u.dot(u), uv = u.dot(v), vv = v.dot(v), uw = u.dot(w), vw = v.dot(w);
    const double denominator = uu * vv - uv * uv;
    if (denominator > 1e-12 * uu * vv)
    {
        const double s = (uv * vw - vv * uw) / denominator;
        const double t = (uu * vw - uv * uw) / denominator;
        if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0)
        {
            x = a + s * u;
            y = c + t * v;
            return (x - y).squaredNorm();
        }
    }
    Vec onSegment;
    double best = pointSegment(a, c, d, onSegment);
    x = a;
    y = onSegment;
    double candidate = pointSegment(b, c, d, onSegment);
    if (candidate < best)
    {
        best = candidate;
        x = b;
        y = onSegment;
    }
    candidate = pointSegment(c, a, b, onSegment);
    if (candidate < best)
    {
        best = candidate;
        x = onSegment;
        y = c;
    }
    candidate = pointSegment(d, a, b, onSegment);
    if (candidate < best)
    {
        best = candidate;
        x = onSegment;
        y = d;
    }
    return best;
}

Vec segmentsMeetingPoint(const Vec &a, const Vec &b, const Vec &c, const Vec &d)
{
    Vec x, y;
    segmentSegment(a, b, c, d, x, y);
    return 0.5 * (x + y);
}

// Squared distance from p to triangle abc when p projects inside it (the vertex/face case of the
// triangle distance); infinity otherwise or for a zero-area triangle, whose distances the
// edge/edge cases already cover.
double vertexFace(const Vec &p, const Vec &a, const Vec &b, const Vec &c, Vec &onFace)
{
    const Vec n = (b - a).cross(c - a);
    const double nn = n.squaredNorm();
    if (!(nn > 0.0))
        return std::numeric_limits<double>::infinity();
    if (n.dot((b - a).cross(p - a)) < 0.0 || n.dot((c - b).cross(p - b)) < 0.0 || n.dot((a - c).cross(p - c)) < 0.0)
        return std::numeric_limits<double>::infinity();
    const double h = n.dot(p - a);
    onFace = p - (h / nn) * n;
    return h * h / nn;
}

// ---- exact segment/triangle --------------------------------------------------------------

// Closed segment ab against the coplanar, non-degenerate triangle pqr.
bool coplanarSegmentTriangle(const Vec &a, const Vec &b, const Vec &p, const Vec &q, const Vec &r, Vec *point)
{
    const int dropped = projectionAxis(p, q, r);
    const Point2 a2 = project(a, dropped), b2 = project(b, dropped);
    const Point2 tri[3] = {project(p, dropped), project(q, dropped), project(r, dropped)};
    const int orientation = orient(tri[0], tri[1], tri[2]);
    if (insideTriangle2d(a2, tri[0], tri[1], tri[2], orientation))
    {
        if (point)
            *point = a;
        return true;
    }
    if (insideTriangle2d(b2, tri[0], tri[1], tri[2], orientation))
    {
        if (point)
            *point = b;
        return true;
    }
    const Vec *corners[3] = {&p, &q, &r};
    for (int i = 0; i < 3; ++i)
        if (segmentsIntersect2d(a2, b2, tri[i], tri[(i + 1) % 3]))
        {
            if (point)
                *point = segmentsMeetingPoint(a, b, *corners[i], *corners[(i + 1) % 3]);
            return true;
        }
    return false;
}

// Closed segment ab against the non-degenerate triangle pqr; sideA / sideB are
// orient3d(p, q, r, a / b).
bool segmentTriangle(const Vec &a, const Vec &b, int sideA, int sideB, const Vec &p, const Vec &q, const Vec &r,
                     Vec *point)
{
    if (sideA * sideB > 0)
        return false;
    if (sideA == 0 && sideB == 0)
        return coplanarSegmentTriangle(a, b, p, q, r, point);
    // The line ab crosses the plane at one point of the segment; it lies in the closed triangle
    // when the line passes on no strict side of any edge (the signs of the three tetrahedra).
    const int s0 = orient3d(a, b, p, q), s1 = orient3d(a, b, q, r), s2 = orient3d(a, b, r, p);
    if ((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0))
        return false;
    if (point)
    {
        const Vec n = (q - p).cross(r - p);
        const double da = n.dot(a - p), db = n.dot(b - p);
        *point = da == db ? a : Vec(a + (da / (da - db)) * (b - a));
    }
    return true;
}

// Every edge of the (possibly degenerate) triangle a against the non-degenerate triangle b;
// sides[i] is orient3d(b0, b1, b2, a_i). The edges cover a, so this is the whole test.
bool edgesHitTriangle(const Vec *const a[3], const int sides[3], const Vec *const b[3], Vec *point)
{
    for (int i = 0; i < 3; ++i)
    {
        const int j = (i + 1) % 3;
        if (segmentTriangle(*a[i], *a[j], sides[i], sides[j], *b[0], *b[1], *b[2], point))
            return true;
    }
    return false;
}

bool coplanarTriangles(const Vec *const p[3], const Vec *const q[3], Vec *point)
{
    const int dropped = projectionAxis(*p[0], *p[1], *p[2]);
    Point2 p2[3], q2[3];
    for (int i = 0; i < 3; ++i)
    {
        p2[i] = project(*p[i], dropped);
        q2[i] = project(*q[i], dropped);
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (segmentsIntersect2d(p2[i], p2[(i + 1) % 3], q2[j], q2[(j + 1) % 3]))
            {
                if (point)
                    *point = segmentsMeetingPoint(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3]);
                return true;
            }
    // No boundaries meet: either one triangle holds the other or they are apart.
    if (insideTriangle2d(p2[0], q2[0], q2[1], q2[2], orient(q2[0], q2[1], q2[2])))
    {
        if (point)
            *point = *p[0];
        return true;
    }
    if (insideTriangle2d(q2[0], p2[0], p2[1], p2[2], orient(p2[0], p2[1], p2[2])))
    {
        if (point)
            *point = *q[0];
        return true;
    }
    return false;
}
}  // namespace

bool trianglesIntersect(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                        Vec *point)
{
    // Disjoint bounds decide most pairs a BVH leaf offers; comparisons are exact.
    for (int k = 0; k < 3; ++k)
        if (std::max({p0[k], p1[k], p2[k]}) < std::min({q0[k], q1[k], q2[k]}) ||
            std::max({q0[k], q1[k], q2[k]}) < std::min({p0[k], p1[k], p2[k]}))
            return false;
    // If the triangles meet, their intersection is a segment or convex polygon whose extreme points
    // lie on an edge of one triangle and in the other, so testing edges against triangles decides.
    const Vec *const p[3] = {&p0, &p1, &p2};
    const Vec *const q[3] = {&q0, &q1, &q2};
    const int sideQ[3] = {orient3d(p0, p1, p2, q0), orient3d(p0, p1, p2, q1), orient3d(p0, p1, p2, q2)};
    if (sameStrictSign(sideQ))
        return false;
    const int sideP[3] = {orient3d(q0, q1, q2, p0), orient3d(q0, q1, q2, p1), orient3d(q0, q1, q2, p2)};
    if (sameStrictSign(sideP))
        return false;

    // A degenerate triangle puts everything on its "plane", so all-zero sides mean either a
    // degenerate triangle or two coplanar ones.
    const bool flatP = allZero(sideQ), flatQ = allZero(sideP);
    if (flatP || flatQ)
    {
        const bool degenerateP = flatP && collinear(p0, p1, p2);
        const bool degenerateQ = flatQ && collinear(q0, q1, q2);
        if (degenerateP && degenerateQ)
        {
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    if (segmentsIntersect3d(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3]))
                    {
                        if (point)
                            *point = segmentsMeetingPoint(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3]);
                        return true;
                    }
            return false;
        }
        if (degenerateP)
            return edgesHitTriangle(p, sideP, q, point);
        if (degenerateQ)
            return edgesHitTriangle(q, sideQ, p, point);
        return coplanarTriangles(p, q, point);
    }

    // General position: only edges that touch or straddle the other plane can carry an extreme
    // point of the intersection segment.
    for (int i = 0; i < 3; ++i)
    {
        const int j = (i + 1) % 3;
        if (sideQ[i] * sideQ[j] <= 0 && segmentTriangle(*q[i], *q[j], sideQ[i], sideQ[j], p0, p1, p2, point))
            return true;
        if (sideP[i] * sideP[j] <= 0 && segmentTriangle(*p[i], *p[j], sideP[i], sideP[j], q0, q1, q2, point))
            return true;
    }
    return false;
}

double triangleDistance(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                        Vec *pointOnP, Vec *pointOnQ)
{
    Vec x, y;
    if (trianglesIntersect(p0, p1, p2, q0, q1, q2, &x))
    {
        if (pointOnP)
            *pointOnP = x;
        if (pointOnQ)
            *pointOnQ = x;
        return 0.0;
    }
    // Disjoint closed triangles: a closest pair has a vertex of one facing the other's interior,
    // or lies on two edges.
    const Vec *const p[3] = {&p0, &p1, &p2};
    const Vec *const q[3] = {&q0, &q1, &q2};
    double best = std::numeric_limits<double>::infinity();
    Vec bestP = p0, bestQ = q0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
        {
            const double d = segmentSegment(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3], x, y);
            if (d < best)
            {
                best = d;
                bestP = x;
                bestQ = y;
            }
        }
    for (int i = 0; i < 3; ++i)
    {
        double d = vertexFace(*p[i], q0, q1, q2, y);
        if (d < best)
        {
            best = d;
            bestP = *p[i];
            bestQ = y;
        }
        d = vertexFace(*q[i], p0, p1, p2, x);
        if (d < best)
        {
            best = d;
            bestP = x;
            bestQ = *q[i];
        }
    }
    if (pointOnP)
        *pointOnP = bestP;
    if (pointOnQ)
        *pointOnQ = bestQ;
    return std::sqrt(best);
}

namespace
{
// Are all three points farther than distance from the plane of abc, on the same side?
bool beyondPlane(const Vec &a, const Vec &b, const Vec &c, const Vec &x0, const Vec &x1, const Vec &x2, double distance)
{
    const Vec n = (b - a).cross(c - a);
    const double reach = distance * n.norm();
    const double h0 = n.dot(x0 - a), h1 = n.dot(x1 - a), h2 = n.dot(x2 - a);
    return (h0 > reach && h1 > reach && h2 > reach) || (h0 < -reach && h1 < -reach && h2 < -reach);
}
}  // namespace

bool trianglesWithin(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                     double distance, Vec *point)
{
    if (beyondPlane(p0, p1, p2, q0, q1, q2, distance) || beyondPlane(q0, q1, q2, p0, p1, p2, distance))
        return false;
    if (trianglesIntersect(p0, p1, p2, q0, q1, q2, point))
        return true;
    const double limit = distance * distance;
    const Vec *const p[3] = {&p0, &p1, &p2};
    const Vec *const q[3] = {&q0, &q1, &q2};
    Vec x, y;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (segmentSegment(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3], x, y) <= limit)
            {
                if (point)
                    *point = 0.5 * (x + y);
                return true;
            }
    for (int i = 0; i < 3; ++i)
    {
        if (vertexFace(*p[i], q0, q1, q2, y) <= limit)
        {
            if (point)
                *point = 0.5 * (*p[i] + y);
            return true;
        }
        if (vertexFace(*q[i], p0, p1, p2, x) <= limit)
        {
            if (point)
                *point = 0.5 * (x + *q[i]);
            return true;
        }
    }
    return false;
}

int rayTriangle(const Vec &origin, const Vec &direction, const Vec &a, const Vec &b, const Vec &c, double tolerance,
                double &t)
{
    const auto v = [](const Vec &x) { return device::Vec3<double>{x.x(), x.y(), x.z()}; };
    return device::rayCrossesTriangle(v(origin), v(direction), v(a), v(b), v(c), tolerance, t);
}
}  // namespace rastercheck
