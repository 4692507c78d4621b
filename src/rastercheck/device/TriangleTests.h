#pragma once

// The exact phase's triangle tests, on doubles, for both backends: intersection decided by exact
// orientation predicates only (device/Predicates.h), so the answer is the true one for the
// coordinates given and symmetric in the triangles and their vertex order; distances and witness
// points in floating point. geometry/TriangleTests.h offers them on Eigen vectors.

#include <cmath>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Predicates.h"

namespace rastercheck::device
{
namespace triangles
{
using V = Vec3<double>;

// ---- exact part: only orient3d/orient2d decide ---------------------------------------------

// A point projected on a coordinate plane by dropping one axis. Dropping a coordinate is exact,
// and when the dropped axis has a non-zero component along the normal of the plane holding the
// points, orient2d of the projections has the sign of the 3-D orientation within that plane.
struct Point2
{
    double x, y;
};

RC_HD Point2 project(const V &p, int dropped)
{
    return {p[(dropped + 1) % 3], p[(dropped + 2) % 3]};
}

RC_HD int orient(const Point2 &a, const Point2 &b, const Point2 &c)
{
    return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

RC_HD bool sameStrictSign(const int s[3])
{
    return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

RC_HD bool allZero(const int s[3])
{
    return s[0] == 0 && s[1] == 0 && s[2] == 0;
}

RC_HD double smaller(double a, double b)
{
    return a < b ? a : b;
}
RC_HD double larger(double a, double b)
{
    return a > b ? a : b;
}

// (b - a) x (c - a) is zero exactly when its three components, the orientations of the three
// coordinate projections, are.
RC_HD bool collinear(const V &a, const V &b, const V &c)
{
    for (int dropped = 0; dropped < 3; ++dropped)
        if (orient(project(a, dropped), project(b, dropped), project(c, dropped)) != 0)
            return false;
    return true;
}

// An axis whose projection keeps the non-degenerate triangle abc a triangle, preferring the one
// the (rounded) normal points along most, which keeps later floating-point work well conditioned.
RC_HD int projectionAxis(const V &a, const V &b, const V &c)
{
    const V n = cross(b - a, c - a);
    const double size[3] = {std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)};
    int order[3] = {0, 1, 2};  // by decreasing size, ties in axis order (a stable sort's)
    for (int i = 1; i < 3; ++i)
        for (int j = i; j > 0 && size[order[j]] > size[order[j - 1]]; --j)
        {
            const int t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    for (int dropped : order)
        if (orient(project(a, dropped), project(b, dropped), project(c, dropped)) != 0)
            return dropped;
    return order[0];  // unreachable for a non-degenerate triangle
}

RC_HD bool intervalsOverlap(double a0, double a1, double b0, double b1)
{
    return smaller(a0, a1) <= larger(b0, b1) && smaller(b0, b1) <= larger(a0, a1);
}

// Collinear points are ordered along the line by any coordinate that is not the same for all of
// them, so the segments overlap exactly when those 1-D intervals do.
RC_HD bool collinearSegmentsOverlap(const Point2 &a, const Point2 &b, const Point2 &c, const Point2 &d)
{
    if (a.x != b.x || a.x != c.x || a.x != d.x)
        return intervalsOverlap(a.x, b.x, c.x, d.x);
    return intervalsOverlap(a.y, b.y, c.y, d.y);
}

// Closed segments ab and cd in the plane, given the four orientations of their endpoints.
RC_HD bool segmentsCross(int abc, int abd, int cda, int cdb)
{
    // One segment wholly on one side of the other's line separates them. Otherwise they meet,
    // unless all four points are collinear, which the caller decides by coordinates.
    return abc * abd <= 0 && cda * cdb <= 0;
}

RC_HD bool segmentsIntersect2d(const Point2 &a, const Point2 &b, const Point2 &c, const Point2 &d)
{
    const int abc = orient(a, b, c), abd = orient(a, b, d), cda = orient(c, d, a), cdb = orient(c, d, b);
    if (abc == 0 && abd == 0 && cda == 0 && cdb == 0)
        return collinearSegmentsOverlap(a, b, c, d);
    return segmentsCross(abc, abd, cda, cdb);
}

RC_HD_CALL bool segmentsIntersect3d(const V &a, const V &b, const V &c, const V &d)
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

RC_HD bool insideTriangle2d(const Point2 &x, const Point2 &p, const Point2 &q, const Point2 &r, int orientation)
{
    return orient(p, q, x) * orientation >= 0 && orient(q, r, x) * orientation >= 0 &&
           orient(r, p, x) * orientation >= 0;
}

// ---- floating-point part: distances and witness points -------------------------------------

RC_HD double clamp01(double x)
{
    return smaller(1.0, larger(0.0, x));
}

RC_HD double pointSegment(const V &p, const V &a, const V &b, V &onSegment)
{
    const V u = b - a;
    const double uu = dot(u, u);
    const double s = uu > 0.0 ? clamp01(dot(p - a, u) / uu) : 0.0;
    onSegment = a + s * u;
    const V d = p - onSegment;
    return dot(d, d);
}

// Squared distance between segments ab and cd, with a closest pair. The distance is convex in the
// two segment parameters: an interior critical point is the minimum, and otherwise the minimum lies
// on the boundary of the parameter square, where it is an endpoint-to-segment distance. Taking the
// boundary route for (nearly) parallel segments avoids the ill-conditioned solve.
RC_HD_CALL double segmentSegment(const V &a, const V &b, const V &c, const V &d, V &x, V &y)
{
    const V u = b - a, v = d - c, w = a - c;
    const double uu = dot(u, u), uv = dot(u, v), vv = dot(v, v), uw = dot(u, w), vw = dot(v, w);
    const double denominator = uu * vv - uv * uv;
    if (denominator > 1e-12 * uu * vv)
    {
        const double s = (uv * vw - vv * uw) / denominator;
        const double t = (uu * vw - uv * uw) / denominator;
        if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0)
        {
            x = a + s * u;
            y = c + t * v;
            const V e = x - y;
            return dot(e, e);
        }
    }
    V onSegment;
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

RC_HD V segmentsMeetingPoint(const V &a, const V &b, const V &c, const V &d)
{
    V x, y;
    segmentSegment(a, b, c, d, x, y);
    return 0.5 * (x + y);
}

// Squared distance from p to triangle abc when p projects inside it (the vertex/face case of the
// triangle distance); infinity otherwise or for a zero-area triangle, whose distances the
// edge/edge cases already cover.
RC_HD double vertexFace(const V &p, const V &a, const V &b, const V &c, V &onFace)
{
    const V n = cross(b - a, c - a);
    const double nn = dot(n, n);
    if (!(nn > 0.0))
        return HUGE_VAL;
    if (dot(n, cross(b - a, p - a)) < 0.0 || dot(n, cross(c - b, p - b)) < 0.0 || dot(n, cross(a - c, p - c)) < 0.0)
        return HUGE_VAL;
    const double h = dot(n, p - a);
    onFace = p - (h / nn) * n;
    return h * h / nn;
}

// ---- exact segment/triangle --------------------------------------------------------------

// Closed segment ab against the coplanar, non-degenerate triangle pqr.
RC_HD_CALL bool coplanarSegmentTriangle(const V &a, const V &b, const V &p, const V &q, const V &r, V *point)
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
    const V *corners[3] = {&p, &q, &r};
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
RC_HD bool segmentTriangle(const V &a, const V &b, int sideA, int sideB, const V &p, const V &q, const V &r, V *point)
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
        const V n = cross(q - p, r - p);
        const double da = dot(n, a - p), db = dot(n, b - p);
        *point = da == db ? a : a + (da / (da - db)) * (b - a);
    }
    return true;
}

// Every edge of the (possibly degenerate) triangle a against the non-degenerate triangle b;
// sides[i] is orient3d(b0, b1, b2, a_i). The edges cover a, so this is the whole test.
RC_HD bool edgesHitTriangle(const V *const a[3], const int sides[3], const V *const b[3], V *point)
{
    for (int i = 0; i < 3; ++i)
    {
        const int j = (i + 1) % 3;
        if (segmentTriangle(*a[i], *a[j], sides[i], sides[j], *b[0], *b[1], *b[2], point))
            return true;
    }
    return false;
}

RC_HD_CALL bool coplanarTriangles(const V *const p[3], const V *const q[3], V *point)
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

// Are all three points farther than distance from the plane of abc, on the same side?
RC_HD bool beyondPlane(const V &a, const V &b, const V &c, const V &x0, const V &x1, const V &x2, double distance)
{
    const V n = cross(b - a, c - a);
    const double reach = distance * std::sqrt(dot(n, n));
    const double h0 = dot(n, x0 - a), h1 = dot(n, x1 - a), h2 = dot(n, x2 - a);
    return (h0 > reach && h1 > reach && h2 > reach) || (h0 < -reach && h1 < -reach && h2 < -reach);
}
}  // namespace triangles

/** \brief Exact triangle/triangle intersection of closed triangles (touching counts), including
    the coplanar case. Every decision is an exact orientation predicate (orient3d/orient2d) on the
    double coordinates given, so the answer is the true one for those coordinates: it is
    symmetric in the two triangles and in the order of their vertices. A degenerate triangle
    (collinear or repeated vertices) is treated as the segment or point it covers.

    When \a point is not null and the triangles meet, it receives a point of the intersection
    (computed in floating point, so it lies on both triangles only up to rounding). */
RC_HD_CALL bool trianglesIntersect(const Vec3<double> &p0, const Vec3<double> &p1, const Vec3<double> &p2,
                              const Vec3<double> &q0, const Vec3<double> &q1, const Vec3<double> &q2,
                              Vec3<double> *point = nullptr)
{
    using namespace triangles;
    // Disjoint bounds decide most pairs a BVH leaf offers; comparisons are exact.
    for (int k = 0; k < 3; ++k)
        if (larger(larger(p0[k], p1[k]), p2[k]) < smaller(smaller(q0[k], q1[k]), q2[k]) ||
            larger(larger(q0[k], q1[k]), q2[k]) < smaller(smaller(p0[k], p1[k]), p2[k]))
            return false;
    // If the triangles meet, their intersection is a segment or convex polygon whose extreme points
    // lie on an edge of one triangle and in the other, so testing edges against triangles decides.
    const V *const p[3] = {&p0, &p1, &p2};
    const V *const q[3] = {&q0, &q1, &q2};
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

namespace triangles
{
/** \brief The closest-feature pairs of two disjoint triangles, nearest first: \a visit(squared
    distance, point on p, point on q) for the nine edge pairs (those at the two nearest corners
    first: the edges each starts and ends, then the third) and the six vertex/face pairs, until it
    returns true (then walkFeatures returns true) or an edge pair's closest points are the
    triangles' own: the plane through each, normal to the segment between them, has the other
    corner of its triangle behind it (PQP's test), so nothing is nearer and the remaining features
    need not be measured (650 -> 200 ns against FCL's 190 on random near pairs). */
template <class Visit>
RC_HD bool walkFeatures(const V &p0, const V &p1, const V &p2, const V &q0, const V &q1, const V &q2, Visit &&visit)
{
    const V *const p[3] = {&p0, &p1, &p2};
    const V *const q[3] = {&q0, &q1, &q2};
    int nearestP = 0, nearestQ = 0;
    double nearestCorners = HUGE_VAL;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
        {
            const V between = *q[j] - *p[i];
            if (dot(between, between) < nearestCorners)
            {
                nearestCorners = dot(between, between);
                nearestP = i;
                nearestQ = j;
            }
        }
    const int edgesP[3] = {nearestP, (nearestP + 2) % 3, (nearestP + 1) % 3};
    const int edgesQ[3] = {nearestQ, (nearestQ + 2) % 3, (nearestQ + 1) % 3};
    const int rankP[9] = {0, 0, 1, 1, 0, 1, 2, 2, 2}, rankQ[9] = {0, 1, 0, 1, 2, 2, 0, 1, 2};
    V x, y;
    for (int k = 0; k < 9; ++k)
    {
        const int i = edgesP[rankP[k]], j = edgesQ[rankQ[k]];
        if (visit(segmentSegment(*p[i], *p[(i + 1) % 3], *q[j], *q[(j + 1) % 3], x, y), x, y))
            return true;
        const V between = y - x;
        if (dot(*p[(i + 2) % 3] - x, between) <= 0.0 && dot(*q[(j + 2) % 3] - y, between) >= 0.0)
            return false;
    }
    for (int i = 0; i < 3; ++i)
    {
        if (visit(vertexFace(*p[i], q0, q1, q2, y), *p[i], y))
            return true;
        if (visit(vertexFace(*q[i], p0, p1, p2, x), x, *q[i]))
            return true;
    }
    return false;
}
}  // namespace triangles

/** \brief Euclidean distance between two closed triangles (0 when they intersect, decided by
    trianglesIntersect()); \a pointOnP / \a pointOnQ, when not null, receive a closest pair (the
    same intersection point twice when the distance is 0). The positive distance is the smallest
    of the nine edge/edge and six vertex/face distances, computed in floating point, as far as
    triangles::walkFeatures goes. */
RC_HD_CALL double triangleDistance(const Vec3<double> &p0, const Vec3<double> &p1, const Vec3<double> &p2,
                              const Vec3<double> &q0, const Vec3<double> &q1, const Vec3<double> &q2,
                              Vec3<double> *pointOnP = nullptr, Vec3<double> *pointOnQ = nullptr)
{
    using namespace triangles;
    V x;
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
    double best = HUGE_VAL;
    V bestP = p0, bestQ = q0;
    walkFeatures(p0, p1, p2, q0, q1, q2,
                 [&](double d, const V &onP, const V &onQ)
                 {
                     if (d < best)
                     {
                         best = d;
                         bestP = onP;
                         bestQ = onQ;
                     }
                     return false;
                 });
    if (pointOnP)
        *pointOnP = bestP;
    if (pointOnQ)
        *pointOnQ = bestQ;
    return std::sqrt(best);
}

/** \brief Is triangleDistance() <= \a distance (metres, >= 0)? Cheaper than computing the
    distance: rejects early when one triangle lies beyond \a distance of the other's plane, stops
    at the first pair of features close enough, and ends where triangleDistance's walk ends (a
    pair farther than \a distance that is the triangles' nearest). \a point, when not null and the
    answer is true, receives the midpoint of a pair of points no farther apart than \a distance. */
RC_HD_CALL bool trianglesWithin(const Vec3<double> &p0, const Vec3<double> &p1, const Vec3<double> &p2,
                           const Vec3<double> &q0, const Vec3<double> &q1, const Vec3<double> &q2, double distance,
                           Vec3<double> *point = nullptr)
{
    using namespace triangles;
    if (beyondPlane(p0, p1, p2, q0, q1, q2, distance) || beyondPlane(q0, q1, q2, p0, p1, p2, distance))
        return false;
    if (trianglesIntersect(p0, p1, p2, q0, q1, q2, point))
        return true;
    const double limit = distance * distance;
    return walkFeatures(p0, p1, p2, q0, q1, q2,
                        [&](double d, const V &onP, const V &onQ)
                        {
                            if (!(d <= limit))
                                return false;
                            if (point)
                                *point = 0.5 * (onP + onQ);
                            return true;
                        });
}
}  // namespace rastercheck::device
