#pragma once

// The distance between two convex shapes (primitives, triangles) with a closest pair of points:
// what a distance query measures curved primitives by, where convexWithin() only answers yes or no.

#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Separation.h"

namespace rastercheck::device
{
/** \brief Distance between the convex solids \a a and \a b (0 when they touch or overlap), with
    \a onA / \a onB a closest pair of points (world frame; one point of both when they overlap).
    GJK (van den Bergen) on their Minkowski difference, A's support points kept beside the simplex
    so that the closest point's barycentric weights give the witnesses. Stops when the upper bound
    |v| and the support plane's lower bound meet within 1e-12 of |v|^2 (so the distance is exact to
    about 1e-6 of itself at worst, far better in practice), when the origin is enclosed, or when
    the simplex stops shrinking (rounding); at most 128 steps. */
RC_HD double convexClosest(const ConvexShape &a, const ConvexShape &b, Vec3<double> &onA, Vec3<double> &onB)
{
    Vec3<double> simplex[4], pointsOfA[4];
    double weights[4] = {1.0, 0.0, 0.0, 0.0};
    int count = 1;
    pointsOfA[0] = supportPoint(a, Vec3<double>{1.0, 0.0, 0.0});
    simplex[0] = pointsOfA[0] - supportPoint(b, Vec3<double>{-1.0, 0.0, 0.0});
    Vec3<double> v = simplex[0];
    bool overlap = false;
    for (int step = 0; step < 128; ++step)
    {
        const double vv = dot(v, v);
        if (!(vv > 0.0))
        {
            overlap = true;
            break;
        }
        const Vec3<double> pointOfA = supportPoint(a, Vec3<double>{-v.x, -v.y, -v.z});
        const Vec3<double> w = pointOfA - supportPoint(b, v);
        if (vv - dot(v, w) <= 1e-12 * vv)
            break;  // the support plane along v is as far as the simplex's nearest point
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
        if (result == detail::SimplexStep::Flat)
        {
            --count;  // nothing written: the old simplex and weights stand
            break;
        }
        // The simplex was reduced in place: its weights and closest point go with it.
        for (int k = 0; k < 4; ++k)
            weights[k] = stepWeights[k];
        const bool progress = dot(closest, closest) < vv;
        v = closest;
        if (!progress)
            break;  // no progress left: v is the nearest within rounding
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
}  // namespace rastercheck::device
