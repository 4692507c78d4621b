#pragma once

// The penetration depth of two overlapping convex solids: the shortest translation that separates
// them. EPA (the expanding polytope algorithm, van den Bergen) on their Minkowski difference,
// started from the simplex with which GJK (ConvexClosest.h) found the origin inside it. Fixed-size
// arrays and plain doubles, so that the GPU can run the same code.

#include "rastercheck/device/ConvexClosest.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Separation.h"

namespace rastercheck::device
{
/** \brief Most points the expanding polytope grows to before it gives up converging (a closed
    triangulated surface of n points has 2n - 4 faces). Random overlapping pairs to 1e-9 m: boxes and
    12-point hulls 9-10 points (median; 21 at most), a cylinder or cone with a box 12-16 (58-91), two
    curved ones about 22 (the few that reach 128 are nearly concentric). On the device the polytope
    is a 24 KB stack frame. */
constexpr int kPolytopePoints = 128;
constexpr int kPolytopeFaces = 2 * kPolytopePoints;

/** \brief How deep two convex solids A and B overlap. Both bounds are sound up to rounding:
    \a lowerBound is the distance from the origin to the boundary of a polytope inside A - B (its
    points are support points), \a depth the support value of A - B along \a separation's
    opposite, so that moving A by depth * separation (or B by the opposite) leaves them at most
    touching. The penetration depth (the length of the shortest separating translation) lies
    between the two; \a converged: they met within the tolerance asked for. */
struct ConvexPenetration
{
    double depth = 0.0;
    double lowerBound = 0.0;
    /** \brief Unit, world frame: the way to move A out of B; zero when the solids do not overlap. */
    Vec3<double> separation{0.0, 0.0, 0.0};
    /** \brief The deepest points, a point of A and a point of B (world frame): onB - onA is
        separation times the lower bound of the face they were read on (the depth when converged). */
    Vec3<double> onA{0.0, 0.0, 0.0};
    Vec3<double> onB{0.0, 0.0, 0.0};
    bool converged = false;
};

/** \brief The support function of the convex hull of \a count points (x y z, in the solid's own
    frame), placed by \a pose, shrunk by \a scale (0 < scale <= 1) towards \a centre (own frame):
    scale 1 is the hull itself; less, a convex body the caller knows to lie inside the solid
    (collision/Penetration.cpp). */
struct PointsSupport
{
    const double *points;
    std::uint32_t count;
    Pose<double> pose;
    Vec3<double> centre;
    double scale;
    RC_HD Vec3<double> operator()(const Vec3<double> &d) const
    {
        std::uint32_t index = 0;
        supportValue(points, count, inverseRotate(pose, d), &index);
        const double *p = points + 3 * static_cast<std::size_t>(index);
        const Vec3<double> local{p[0], p[1], p[2]};
        return transformPoint(pose, centre + scale * (local - centre));
    }
};

/** \brief The support function of the convex hull of \a count ConvexShapes (count >= 1). */
struct ShapesSupport
{
    const ConvexShape *shapes;
    int count;
    RC_HD Vec3<double> operator()(const Vec3<double> &d) const
    {
        Vec3<double> best = supportPoint(shapes[0], d);
        double value = dot(best, d);
        for (int k = 1; k < count; ++k)
        {
            const Vec3<double> p = supportPoint(shapes[k], d);
            if (dot(p, d) > value)
            {
                best = p;
                value = dot(p, d);
            }
        }
        return best;
    }
};

namespace detail
{
/** \brief A face of the expanding polytope: corners counter-clockwise seen from outside, unit
    outward normal and the plane's signed distance from the origin (infinity for a face too thin
    to have a normal: its points lie on its neighbours' edges, so the nearest face is never one). */
struct PolytopeFace
{
    int corner[3];
    Vec3<double> normal;
    double distance;
    bool alive;
};

constexpr double kThinFace = 1e300;

/** \brief The expanding polytope: points of A - B (each with the point of A it was made from) and
    a closed surface of triangles over them, kept convex up to rounding. */
struct Polytope
{
    Vec3<double> points[kPolytopePoints];
    Vec3<double> pointsOfA[kPolytopePoints];
    int count = 0;
    PolytopeFace faces[kPolytopeFaces];
    int numFaces = 0;

    RC_HD PolytopeFace face(int i, int j, int k) const
    {
        PolytopeFace f{{i, j, k}, {0.0, 0.0, 0.0}, kThinFace, true};
        const Vec3<double> n = cross(points[j] - points[i], points[k] - points[i]);
        const double length = sqrt(dot(n, n));
        if (length > 0.0)
        {
            f.normal = (1.0 / length) * n;
            f.distance = dot(f.normal, points[i]);
        }
        return f;
    }

    /** \brief The tetrahedron of points i, j, k, l (not flat), faces turned outward. */
    RC_HD void tetrahedron(int i, int j, int k, int l)
    {
        const int corners[4][3] = {{i, j, k}, {i, l, j}, {i, k, l}, {j, l, k}};
        const Vec3<double> centre = 0.25 * (points[i] + points[j] + points[k] + points[l]);
        numFaces = 0;
        for (const auto &c : corners)
        {
            PolytopeFace f = face(c[0], c[1], c[2]);
            if (dot(cross(points[c[1]] - points[c[0]], points[c[2]] - points[c[0]]), centre - points[c[0]]) > 0.0)
                f = face(c[0], c[2], c[1]);
            faces[numFaces++] = f;
        }
    }

    /** \brief Weights on face \a f's corners of the origin's projection on its plane, clamped to
        the face; true when they needed no clamping (the projection lies in the face). */
    RC_HD bool projection(int f, double weights[3]) const
    {
        const PolytopeFace &face = faces[f];
        const Vec3<double> &c0 = points[face.corner[0]], &c1 = points[face.corner[1]], &c2 = points[face.corner[2]];
        const Vec3<double> e0 = c1 - c0, e1 = c2 - c0, e2 = face.distance * face.normal - c0;
        const double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(e2, e0), d21 = dot(e2, e1);
        const double det = d00 * d11 - d01 * d01;
        double w1 = det > 0.0 ? (d11 * d20 - d01 * d21) / det : 0.0;
        double w2 = det > 0.0 ? (d00 * d21 - d01 * d20) / det : 0.0;
        const bool inside = det > 0.0 && w1 >= -1e-9 && w2 >= -1e-9 && w1 + w2 <= 1.0 + 1e-9;
        w1 = fmax(w1, 0.0);
        w2 = fmax(w2, 0.0);
        if (w1 + w2 > 1.0)
        {
            w1 /= w1 + w2;
            w2 = 1.0 - w1;
        }
        weights[0] = 1.0 - w1 - w2;
        weights[1] = w1;
        weights[2] = w2;
        return inside;
    }

    enum class Grown
    {
        Added,   ///< the point is a corner now
        Inside,  ///< no face sees it: nothing changed
        Failed   ///< no room, or rounding left no clean horizon: nothing changed
    };

    /** \brief Adds point \a p (with A's point \a pointOfA) as a corner: every face that sees it by
        more than \a visible goes, and each edge of the region they leave (the horizon) makes a new
        face with it. */
    RC_HD Grown add(const Vec3<double> &p, const Vec3<double> &pointOfA, double visible)
    {
        if (count == kPolytopePoints)
            return Grown::Failed;
        int seen = 0;
        for (int f = 0; f < numFaces; ++f)  // a thin face (distance infinite) is never seen
            if (faces[f].alive && dot(faces[f].normal, p) - faces[f].distance > visible)
            {
                faces[f].alive = false;
                ++seen;
            }
        if (seen == 0)
            return Grown::Inside;
        int horizon[kPolytopeFaces][2];
        int numHorizon = 0;
        bool clean = true;
        for (int f = 0; f < numFaces && clean; ++f)
        {
            if (faces[f].alive)
                continue;
            for (int k = 0; k < 3 && clean; ++k)
            {
                const int from = faces[f].corner[k], to = faces[f].corner[(k + 1) % 3];
                bool inner = false;  // the edge's other face is seen too
                for (int g = 0; g < numFaces && !inner; ++g)
                    if (g != f && !faces[g].alive)
                        for (int m = 0; m < 3; ++m)
                            inner = inner || (faces[g].corner[m] == to && faces[g].corner[(m + 1) % 3] == from);
                if (inner)
                    continue;
                clean = numHorizon < kPolytopeFaces;
                if (clean)
                {
                    horizon[numHorizon][0] = from;
                    horizon[numHorizon++][1] = to;
                }
            }
        }
        // A clean horizon is one loop: every corner on it starts one edge and ends one.
        for (int e = 0; e < numHorizon && clean; ++e)
        {
            int starts = 0, ends = 0;
            for (int g = 0; g < numHorizon; ++g)
            {
                starts += horizon[g][0] == horizon[e][0] ? 1 : 0;
                ends += horizon[g][1] == horizon[e][0] ? 1 : 0;
            }
            clean = starts == 1 && ends == 1;
        }
        if (!clean || numHorizon < 3 || numFaces - seen + numHorizon > kPolytopeFaces)
        {
            for (int f = 0; f < numFaces; ++f)
                faces[f].alive = true;  // only live faces are kept, so every face was alive before
            return Grown::Failed;
        }
        int kept = 0;
        for (int f = 0; f < numFaces; ++f)
            if (faces[f].alive)
                faces[kept++] = faces[f];
        numFaces = kept;
        points[count] = p;
        pointsOfA[count] = pointOfA;
        for (int e = 0; e < numHorizon; ++e)
            faces[numFaces++] = face(horizon[e][0], horizon[e][1], count);
        ++count;
        return Grown::Added;
    }
};

RC_HD double distanceFromLine(const Vec3<double> &p, const Vec3<double> &a, const Vec3<double> &b)
{
    const Vec3<double> u = b - a, c = cross(u, p - a);
    const double uu = dot(u, u);
    return uu > 0.0 ? sqrt(dot(c, c) / uu) : sqrt(dot(p - a, p - a));
}

/** \brief Of \a count points, four that span a tetrahedron thicker than \a flat (greedy: the
    first, the farthest from it, the farthest from their line, the farthest from their plane),
    written to \a corner; returns how many it found (the dimension of their span plus one), and in
    \a normal the normal of the plane of the first three when it found three or more. */
RC_HD int spanningCorners(const Vec3<double> *points, int count, double flat, int corner[4], Vec3<double> &normal)
{
    corner[0] = 0;
    int found = 1;
    // The point farthest by \a measure, when farther than flat, is the next corner.
    const auto farthest = [&](const auto &measure)
    {
        double best = flat;
        int index = -1;
        for (int k = 1; k < count; ++k)
        {
            const double d = measure(points[k]);
            if (d > best)
            {
                best = d;
                index = k;
            }
        }
        if (index >= 0)
            corner[found++] = index;
        return index >= 0;
    };
    if (!farthest([&](const Vec3<double> &p) { return sqrt(dot(p - points[0], p - points[0])); }) ||
        !farthest([&](const Vec3<double> &p) { return distanceFromLine(p, points[0], points[corner[1]]); }))
        return found;
    const Vec3<double> n = cross(points[corner[1]] - points[0], points[corner[2]] - points[0]);
    normal = (1.0 / sqrt(dot(n, n))) * n;
    farthest([&](const Vec3<double> &p) { return fabs(dot(normal, p - points[0])); });
    return found;
}
}  // namespace detail

/** \brief The penetration depth of the convex solids given by the support functions \a a and \a b
    (as closestPoints()), from GJK's terminal simplex \a start (start.overlap: the origin lies in
    its hull). EPA: the polytope spanned by support points of A - B grows, face nearest the origin
    first, by the support point along that face's normal, until that point's height along the
    normal (an upper bound on the depth) and the face's distance (a lower bound) meet within
    \a tolerance (metres, >= 0), or kPolytopePoints are used, or rounding leaves the surface
    without a clean horizon. \a result holds the bounds reached (ConvexPenetration): converged,
    along that face's normal; else along the normal of the least upper bound met, with that face's
    witnesses. The first polytope is the hull of the start's points and, where they span less than
    a tetrahedron (the origin on a vertex, an edge or a face of A - B, or GJK's last point on the
    others' plane), of support points off their span: it holds the origin as they do. A difference
    too flat for any (two flat solids) has depth 0. */
template <class SupportA, class SupportB>
RC_HD void expandPolytope(const SupportA &a, const SupportB &b, const GjkSimplex &start, double tolerance,
                          ConvexPenetration &result)
{
    result = ConvexPenetration{};
    const auto support = [&](const Vec3<double> &d, Vec3<double> &pointOfA)
    {
        pointOfA = a(d);
        return pointOfA - b(Vec3<double>{-d.x, -d.y, -d.z});
    };
    // The start's points and the support points that widen their span (6 at a time at most).
    constexpr int kCandidates = 4 + 3 * 6;
    Vec3<double> candidates[kCandidates], candidatesOfA[kCandidates];
    int numCandidates = 0;
    double size = 0.0;
    for (int k = 0; k < start.count; ++k)
    {
        candidates[numCandidates] = start.points[k];
        candidatesOfA[numCandidates++] = start.pointsOfA[k];
        size = fmax(size, sqrt(dot(start.points[k], start.points[k])));
    }
    int corner[4] = {0, 0, 0, 0};
    Vec3<double> normal{0.0, 0.0, 0.0};
    int spanned = 0;
    for (int widen = 0;; ++widen)
    {
        // Apart by more than rounding of coordinates this large.
        const double flat = 1e-12 * size;
        spanned = detail::spanningCorners(candidates, numCandidates, flat, corner, normal);
        if (spanned == 4 || widen == 3)
            break;
        Vec3<double> directions[6];
        int numDirections = 0;
        if (spanned == 1)  // a point: the axes
        {
            const Vec3<double> axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            for (const Vec3<double> &d : axes)
                directions[numDirections++] = d;
        }
        else if (spanned == 2)  // a segment: six directions normal to it, 60 degrees apart
        {
            const Vec3<double> u = candidates[corner[1]] - candidates[corner[0]];
            const Vec3<double> axis = fabs(u.x) <= fabs(u.y) && fabs(u.x) <= fabs(u.z) ? Vec3<double>{1, 0, 0}
                                      : fabs(u.y) <= fabs(u.z)                         ? Vec3<double>{0, 1, 0}
                                                                                       : Vec3<double>{0, 0, 1};
            const Vec3<double> p = cross(u, axis), q = cross(u, p);
            const double lp = sqrt(dot(p, p)), lq = sqrt(dot(q, q));
            for (int k = 0; k < 6; ++k)
            {
                const double angle = k * (3.14159265358979323846 / 3.0);
                directions[numDirections++] = (cos(angle) / lp) * p + (sin(angle) / lq) * q;
            }
        }
        else  // a plane: either side of it
        {
            directions[numDirections++] = normal;
            directions[numDirections++] = Vec3<double>{-normal.x, -normal.y, -normal.z};
        }
        for (int k = 0; k < numDirections; ++k)
        {
            candidates[numCandidates] = support(directions[k], candidatesOfA[numCandidates]);
            size = fmax(size, sqrt(dot(candidates[numCandidates], candidates[numCandidates])));
            ++numCandidates;
        }
    }
    if (spanned < 4)
    {
        // A - B has no volume: depth 0, and any way off its span is a way out (which matters to
        // grown cores: convexPenetration).
        result.converged = true;
        if (spanned == 3)
            result.separation = normal;
        else if (spanned == 2)
        {
            const Vec3<double> u = candidates[corner[1]] - candidates[corner[0]];
            const Vec3<double> off =
                fabs(u.x) <= fabs(u.y) ? cross(u, Vec3<double>{1, 0, 0}) : cross(u, Vec3<double>{0, 1, 0});
            result.separation = (1.0 / sqrt(dot(off, off))) * off;
        }
        else
            result.separation = Vec3<double>{1.0, 0.0, 0.0};
        result.onA = candidatesOfA[0];
        result.onB = candidatesOfA[0] - candidates[0];
        return;
    }
    detail::Polytope polytope;
    for (int k = 0; k < 4; ++k)
    {
        polytope.points[k] = candidates[corner[k]];
        polytope.pointsOfA[k] = candidatesOfA[corner[k]];
    }
    polytope.count = 4;
    polytope.tetrahedron(0, 1, 2, 3);
    const double visible = 1e-13 * size;  // a face sees a point this far in front of it
    for (int k = 0; k < numCandidates; ++k)
        if (k != corner[0] && k != corner[1] && k != corner[2] && k != corner[3])
            polytope.add(candidates[k], candidatesOfA[k], visible);

    double upper = 1e300, lower = 0.0;
    double depth = 1e300;  // the support value along deepest: upper, or the closing face's (within tolerance of it)
    Vec3<double> deepest{0.0, 0.0, 0.0};
    while (true)
    {
        int nearest = -1;
        for (int f = 0; f < polytope.numFaces; ++f)
            if (nearest < 0 || polytope.faces[f].distance < polytope.faces[nearest].distance)
                nearest = f;
        if (nearest < 0 || !(polytope.faces[nearest].distance < detail::kThinFace))
            break;  // every face too thin to have a normal: rounding has the upper hand
        const detail::PolytopeFace face = polytope.faces[nearest];
        // The polytope lies inside A - B and holds the origin, so its boundary is no farther from
        // the origin than A - B's: the nearest face's plane distance is a lower bound.
        lower = fmax(lower, face.distance);
        Vec3<double> pointOfA;
        const Vec3<double> p = support(face.normal, pointOfA);
        const double height = dot(face.normal, p);
        // Moving A by -height along the normal leaves A - B behind the plane through the origin,
        // whichever face's normal it is; the nearest face's own gap closing is convergence.
        const bool closed = height - face.distance <= tolerance;
        if (closed || height < upper)
        {
            upper = fmin(upper, height);
            depth = height;
            deepest = face.normal;
            // The witnesses: the origin's projection on the face, as weights of its corners. A face
            // of a flat side of A - B is one of several in its plane: the projection may lie in another.
            double weights[3];
            int holder = nearest;
            if (!polytope.projection(nearest, weights))
                for (int f = 0; f < polytope.numFaces; ++f)
                {
                    const detail::PolytopeFace &g = polytope.faces[f];
                    if (f != nearest && fabs(g.distance - face.distance) <= 1e-12 * size &&
                        dot(g.normal, face.normal) >= 1.0 - 1e-12 && polytope.projection(f, weights))
                    {
                        holder = f;
                        break;
                    }
                }
            if (holder == nearest)
                polytope.projection(nearest, weights);  // outside: the nearest point of the face
            result.onA = Vec3<double>{0.0, 0.0, 0.0};
            result.onB = result.onA;
            for (int k = 0; k < 3; ++k)
            {
                const int corner = polytope.faces[holder].corner[k];
                result.onA = result.onA + weights[k] * polytope.pointsOfA[corner];
                result.onB = result.onB + weights[k] * (polytope.pointsOfA[corner] - polytope.points[corner]);
            }
        }
        if (closed)
        {
            result.converged = true;
            break;
        }
        // Not converged, so the nearest face sees p by more than the tolerance.
        if (polytope.add(p, pointOfA, visible) != detail::Polytope::Grown::Added)
            break;  // full, or rounding broke the surface: the bounds so far stand
    }
    result.depth = fmax(depth, 0.0);
    result.lowerBound = fmin(lower, result.depth);
    result.separation = Vec3<double>{-deepest.x, -deepest.y, -deepest.z};
}

/** \brief The support function \a core grown by a ball of radius \a margin. */
template <class Support>
struct GrownSupport
{
    const Support *core;
    double margin;
    RC_HD Vec3<double> operator()(const Vec3<double> &d) const
    {
        const double length = sqrt(dot(d, d));
        const Vec3<double> p = (*core)(d);
        return length > 0.0 ? p + (margin / length) * d : p;
    }
};

/** \brief The penetration depth of the convex solids A = core A grown by a ball of radius
    \a marginA and B likewise (margins >= 0; 0: the solid is its core), the cores given by the
    support functions \a a and \a b (as closestPoints()). A sphere is its centre grown by its
    radius (a capsule its segment), so that no polytope need approach its curved surface.
    GJK (closestPoints) on the cores; when they overlap, expandPolytope() on them with
    \a tolerance, its bounds grown by both margins. When they are apart by d below the margins'
    sum, the depth is that sum less d, along the line of the cores' nearest points: bounded below
    by GJK's distance (an upper bound on d) and above by the support value along that line; where
    GJK's distance was not tight enough for those to meet within the tolerance, expandPolytope()
    on the grown solids decides. False when the solids do not overlap: \a result is then depth 0
    with no separation, and onA / onB a closest pair of the cores. */
template <class SupportA, class SupportB>
RC_HD bool convexPenetration(const SupportA &a, const SupportB &b, double tolerance, ConvexPenetration &result,
                             double marginA = 0.0, double marginB = 0.0)
{
    GjkSimplex simplex;
    Vec3<double> onA, onB;
    const double apart = closestPoints(a, b, onA, onB, &simplex);
    const double margins = marginA + marginB;
    result = ConvexPenetration{};
    if (!simplex.overlap)
    {
        result.onA = onA;
        result.onB = onB;
        result.converged = true;
        if (!(apart < margins))
            return false;
        // B to A along the cores' nearest points is the way out; n, its opposite, the normal.
        const Vec3<double> out = (1.0 / apart) * (onA - onB), n{-out.x, -out.y, -out.z};
        const double upper = margins + dot(n, a(n) - b(out));
        if (upper - (margins - apart) <= tolerance)
        {
            result.depth = upper;
            result.lowerBound = fmin(margins - apart, upper);
            result.separation = out;
            result.onA = onA - marginA * out;
            result.onB = onB + marginB * out;
            return true;
        }
        const GrownSupport<SupportA> grownA{&a, marginA};
        const GrownSupport<SupportB> grownB{&b, marginB};
        closestPoints(grownA, grownB, onA, onB, &simplex);
        if (!simplex.overlap)  // rounding near contact: the bounds above stand
        {
            result.depth = upper;
            result.lowerBound = fmin(margins - apart, upper);
            result.separation = out;
            result.converged = false;
            return true;
        }
        expandPolytope(grownA, grownB, simplex, tolerance, result);
        return true;
    }
    expandPolytope(a, b, simplex, tolerance, result);
    result.depth += margins;
    result.lowerBound += margins;
    result.onA = result.onA - marginA * result.separation;
    result.onB = result.onB + marginB * result.separation;
    return true;
}
}  // namespace rastercheck::device
