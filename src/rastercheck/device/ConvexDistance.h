#pragma once

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Separation.h"

namespace rastercheck::device
{
/** \brief The exact shapes the primitives' meshes stand for, and a triangle. */
enum class ConvexKind : int
{
    Box = 0,
    Sphere = 1,
    Cylinder = 2,  ///< axis z, centred on the frame's origin (URDF, MoveIt)
    Cone = 3,      ///< axis z, apex at +half length, base at -half length (MoveIt)
    Triangle = 4
};

/** \brief A convex solid in the world frame, described by what GJK needs: its support point along
    any direction. Primitives are placed by \a pose (primitive frame -> world) with \a size: box
    half sizes; sphere radius; cylinder and cone radius, half length. A triangle is its three
    corners (world). Plain doubles, so that the GPU can run the same test. */
struct ConvexShape
{
    ConvexKind kind;
    Pose<double> pose;
    double size[3];
    Vec3<double> corner[3];
};

/** \brief The point of \a shape farthest along \a d (world frame; d need not be unit). */
RC_HD Vec3<double> supportPoint(const ConvexShape &shape, const Vec3<double> &d)
{
    if (shape.kind == ConvexKind::Triangle)
    {
        const double a = dot(shape.corner[0], d), b = dot(shape.corner[1], d), c = dot(shape.corner[2], d);
        return a >= b && a >= c ? shape.corner[0] : (b >= c ? shape.corner[1] : shape.corner[2]);
    }
    const double *m = shape.pose.m;
    // The direction in the primitive's frame: R^T d.
    const Vec3<double> l{m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z,
                         m[2] * d.x + m[6] * d.y + m[10] * d.z};
    const double *s = shape.size;
    Vec3<double> p{0.0, 0.0, 0.0};
    switch (shape.kind)
    {
        case ConvexKind::Box:
            p = {l.x >= 0 ? s[0] : -s[0], l.y >= 0 ? s[1] : -s[1], l.z >= 0 ? s[2] : -s[2]};
            break;
        case ConvexKind::Sphere:
        {
            const double n = sqrt(dot(l, l));
            p = n > 0 ? (s[0] / n) * l : Vec3<double>{s[0], 0.0, 0.0};
            break;
        }
        case ConvexKind::Cylinder:
        case ConvexKind::Cone:
        {
            const double radial = sqrt(l.x * l.x + l.y * l.y);
            const Vec3<double> rim{radial > 0 ? s[0] * l.x / radial : 0.0, radial > 0 ? s[0] * l.y / radial : 0.0,
                                   shape.kind == ConvexKind::Cone || l.z < 0 ? -s[1] : s[1]};
            p = rim;
            // A cone's support is its apex or a point of its base's rim, whichever is farther.
            if (shape.kind == ConvexKind::Cone && s[1] * l.z > dot(rim, l))
                p = {0.0, 0.0, s[1]};
            break;
        }
        case ConvexKind::Triangle:
            break;
    }
    return transformPoint(shape.pose, p);
}

/** \brief Do the convex solids \a a and \a b come within \a padding (>= 0) of each other (touching
    or overlapping included)? GJK on their Minkowski difference: each step gives an upper bound on
    the distance (the nearest point of the simplex) and a lower bound (the support plane along it),
    and the answer is given once a bound decides it. When the bounds meet within the relative
    tolerance 1e-12 (or after 128 steps) without deciding, the answer is "within": a contact within
    rounding of the padding may go either way, a deeper one never reads as apart. */
RC_HD bool convexWithin(const ConvexShape &a, const ConvexShape &b, double padding)
{
    auto support = [&](const Vec3<double> &d) {
        return supportPoint(a, d) - supportPoint(b, Vec3<double>{-d.x, -d.y, -d.z});
    };
    Vec3<double> w[4];
    int count = 1;
    w[0] = support(Vec3<double>{1.0, 0.0, 0.0});
    Vec3<double> v = w[0];
    double lower = 0.0;
    for (int step = 0; step < 128; ++step)
    {
        const double vv = dot(v, v);
        const double upper = sqrt(vv);
        if (upper <= padding)
            return true;
        const Vec3<double> next = support(Vec3<double>{-v.x, -v.y, -v.z});
        const double vw = dot(v, next);
        if (vw > 0 && vw / upper > lower)
            lower = vw / upper;
        if (lower > padding)
            return false;
        if (vv - vw <= 1e-12 * vv)
            return true;  // converged with the distance within rounding of the padding or below it
        w[count++] = next;
        Vec3<double> closest{0.0, 0.0, 0.0};
        const detail::SimplexStep simplex = detail::closestOnSimplex(w, count, closest);
        if (simplex != detail::SimplexStep::Closer || !(dot(closest, closest) < vv))
            return true;  // the origin enclosed (they overlap), or no progress: the bounds have met
        v = closest;
    }
    return true;
}
}  // namespace rastercheck::device
