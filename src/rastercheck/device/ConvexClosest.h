#pragma once

// The distance between two convex shapes (primitives, triangles, hulls) with a closest pair of
// points: what a distance query measures curved primitives by, where convexWithin() only answers
// yes or no; and, when the shapes overlap, the simplex that encloses the origin, where the
// penetration depth's expanding polytope starts (Penetration.h).

#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Separation.h"

namespace rastercheck::device
{
/** \brief A ConvexShape as the support function the GJK below reads. */
struct ShapeSupport
{
    const ConvexShape *shape;
    RC_HD Vec3<double> operator()(const Vec3<double> &d) const { return supportPoint(*shape, d); }
};

/** \brief GJK's last simplex: points of the Minkowski difference A - B, each with the point of A
    it was made from. With \a overlap, the origin lies in the simplex's hull (a tetrahedron that
    encloses it, or, when the origin fell exactly on a vertex, edge or face, that sub-simplex). */
struct GjkSimplex
{
    Vec3<double> points[4];
    Vec3<double> pointsOfA[4];
    int count = 0;
    bool overlap = false;
};

/** \brief A lower bound closestPoints() keeps (optional), and when it may stop for it. */
struct GjkLowerBound
{
    /** \brief Out: the largest gap a support plane showed. Every step's v . w / |v| (w the
        difference's point extreme along -v, so every point x of A - B has v . x >= v . w) bounds
        the distance from below however GJK ends, to the rounding of the support points; 0 when
        none showed a gap. */
    double value = 0.0;
    /** \brief In: stop once the bound reaches this (a caller that needs no more). */
    double enough = HUGE_VAL;
    /** \brief In: stop once the bound is within this fraction of the upper bound |v| (the
        distance's own stop, 1e-12, when smaller). */
    double tolerance = 1e-12;
};

/** \brief Distance between the convex solids given by the support functions \a a and \a b (each
    callable on a world direction, returning the solid's point farthest along it; 0 when they touch
    or overlap), with \a onA / \a onB a closest pair of points (world frame; one point of both when
    they overlap). GJK (van den Bergen) on their Minkowski difference, A's support points kept
    beside the simplex so that the closest point's barycentric weights give the witnesses. Stops
    when the upper bound |v| and the support plane's lower bound meet within 1e-12 of |v|^2 (so the
    distance is exact to about 1e-6 of itself at worst, far better in practice), when the origin is
    enclosed, or when the simplex stops shrinking (rounding); at most 128 steps. \a terminal
    (optional) receives the last simplex. \a lower (optional) keeps the support planes' lower
    bound and may stop GJK early for it (GjkLowerBound): the distance and points returned are then
    those of the last step, an upper bound. */
template <class SupportA, class SupportB>
RC_HD double closestPoints(const SupportA &a, const SupportB &b, Vec3<double> &onA, Vec3<double> &onB,
                           GjkSimplex *terminal = nullptr, GjkLowerBound *lower = nullptr)
{
    Vec3<double> simplex[4], pointsOfA[4];
    double weights[4] = {1.0, 0.0, 0.0, 0.0};
    int count = 1;
    pointsOfA[0] = a(Vec3<double>{1.0, 0.0, 0.0});
    simplex[0] = pointsOfA[0] - b(Vec3<double>{-1.0, 0.0, 0.0});
    Vec3<double> v = simplex[0];
    bool overlap = false;
    double size = sqrt(dot(v, v));  // the largest simplex point: what rounding is relative to
    for (int step = 0; step < 128; ++step)
    {
        const double vv = dot(v, v);
        if (!(vv > 0.0))
        {
            overlap = true;
            break;
        }
        const Vec3<double> pointOfA = a(Vec3<double>{-v.x, -v.y, -v.z});
        const Vec3<double> w = pointOfA - b(v);
        if (lower)
        {
            const double length = sqrt(vv);
            lower->value = fmax(lower->value, dot(v, w) / length);
            if (lower->value >= lower->enough || length - lower->value <= lower->tolerance * length)
                break;
        }
        if (vv - dot(v, w) <= 1e-12 * vv)
            break;  // the support plane along v is as far as the simplex's nearest point
        size = fmax(size, sqrt(dot(w, w)));
        // The simplex before this step: it stands when the step gets no closer.
        Vec3<double> previous[4], previousOfA[4];
        for (int k = 0; k < count; ++k)
        {
            previous[k] = simplex[k];
            previousOfA[k] = pointsOfA[k];
        }
        const int previousCount = count;
        pointsOfA[count] = pointOfA;
        simplex[count++] = w;
        Vec3<double> closest = v;
        double stepWeights[4] = {0.0, 0.0, 0.0, 0.0};
        const detail::SimplexStep result = detail::closestOnSimplex(simplex, count, closest, pointsOfA, stepWeights);
        if (result == detail::SimplexStep::OriginInside)
        {
            for (int k = 0; k < 4; ++k)
                weights[k] = stepWeights[k];
            overlap = true;
            break;
        }
        if (!(dot(closest, closest) < vv))
        {
            // No progress left: v is the nearest within rounding, on the simplex before this step
            // (rounding may leave the reduced one's point no nearer, or a flat simplex's a little
            // farther). The origin itself within rounding is a contact.
            for (int k = 0; k < previousCount; ++k)
            {
                simplex[k] = previous[k];
                pointsOfA[k] = previousOfA[k];
            }
            count = previousCount;
            overlap = vv <= 1e-24 * size * size;
            break;
        }
        // The simplex was reduced in place: its weights and closest point go with it.
        for (int k = 0; k < 4; ++k)
            weights[k] = stepWeights[k];
        v = closest;
    }
    if (terminal)
    {
        for (int k = 0; k < count; ++k)
        {
            terminal->points[k] = simplex[k];
            terminal->pointsOfA[k] = pointsOfA[k];
        }
        terminal->count = count;
        terminal->overlap = overlap;
    }
    Vec3<double> p{0.0, 0.0, 0.0};
    for (int k = 0; k < count; ++k)
        p = p + weights[k] * pointsOfA[k];
    onA = p;
    if (overlap)
    {
        onB = p;
        return 0.0;
    }
    onB = p - v;
    return sqrt(dot(v, v));
}

/** \brief A convex piece's hull points (ConvexProxy) placed by a pose, as the support function
    closestPoints() reads. */
struct HullSupport
{
    const ConvexProxy *piece;
    const Pose<double> *pose;
    RC_HD Vec3<double> operator()(const Vec3<double> &d) const { return detail::placedSupport(*piece, *pose, d); }
};

/** \brief How close to the hulls' distance hullDistanceLowerBound() takes its bound by default: a
    step sized by it is at most this fraction shorter than one sized by the hulls' distance. */
constexpr double kHullBoundTolerance = 1e-3;

/** \brief A lower bound on the distance between the solids of pieces \a a and \a b (placed by their
    poses, world frame), from their hulls: a few GJK steps over the hull points, where the exact
    distance walks two triangle trees. 0 when the hulls may touch or overlap. GJK stops once the
    bound reaches \a enough (a caller that needs no more) or comes within \a tolerance of the
    hulls' distance.

    Why it is a proof: each piece (its triangles, and the inside of a closed one) lies in the convex
    hull of its vertices, and no vertex lies farther than the piece's hull slack from the hull of its
    hull points, so the vertices' hull lies within that slack of the hull points' hull (the points
    within a distance of a convex set form a convex set). GJK's support planes bound the distance
    between the hull points' hulls from below (GjkLowerBound: v . w / |v| for its every v), up to the rounding of the
   support search and of the placed points, which kSeparationSlack of the coordinates' magnitudes covers (as
   relateHulls' proofs). So the solids are at least that bound less both slacks less the rounding apart; in particular a
    positive bound shows that neither solid lies inside the other. */
RC_HD double hullDistanceLowerBound(const ConvexProxy &a, const Pose<double> &poseA, const ConvexProxy &b,
                                    const Pose<double> &poseB, double enough = HUGE_VAL,
                                    double tolerance = kHullBoundTolerance)
{
    if (a.numHullPoints == 0 || b.numHullPoints == 0)
        return 0.0;
    const Vec3<double> ta = translationOf(poseA), tb = translationOf(poseB);
    const double rounding = kSeparationSlack * (a.radius + b.radius + sqrt(dot(ta, ta)) + sqrt(dot(tb, tb)));
    const double slack = a.hullSlack + b.hullSlack + rounding;
    Vec3<double> onA, onB;
    GjkLowerBound lower;
    lower.enough = enough + slack;
    lower.tolerance = tolerance;
    closestPoints(HullSupport{&a, &poseA}, HullSupport{&b, &poseB}, onA, onB, nullptr, &lower);
    return fmax(0.0, lower.value - slack);
}

/** \brief closestPoints() of two ConvexShapes. */
RC_HD double convexClosest(const ConvexShape &a, const ConvexShape &b, Vec3<double> &onA, Vec3<double> &onB)
{
    return closestPoints(ShapeSupport{&a}, ShapeSupport{&b}, onA, onB);
}
}  // namespace rastercheck::device
