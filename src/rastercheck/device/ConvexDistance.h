#pragma once

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"

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

/** \brief The point of the simplex \a w (count points, 1 to 4) nearest the origin, and the
    smallest sub-simplex whose hull holds it (written back into \a w and \a count). Every face of
    the simplex is tried: its affine hull's point nearest the origin is a candidate when its
    barycentric coordinates are all positive, and the nearest candidate is the answer (it lies in
    exactly one face's interior). The whole tetrahedron's candidate is the origin itself (count 4,
    result zero). Degenerate faces (a zero Gram determinant) are skipped: a face of them has one. */
RC_HD Vec3<double> nearestOnSimplex(Vec3<double> *w, int &count)
{
    Vec3<double> best{0.0, 0.0, 0.0};
    double bestNorm2 = -1.0;
    int bestMask = 0;
    for (int mask = 1; mask < (1 << count); ++mask)
    {
        int index[4] = {0, 0, 0, 0}, k = 0;
        for (int i = 0; i < count; ++i)
            if (mask & (1 << i))
                index[k++] = i;
        const Vec3<double> p0 = w[index[0]];
        Vec3<double> e[3];
        for (int i = 1; i < k; ++i)
            e[i - 1] = w[index[i]] - p0;
        // Normal equations G mu = r of min |p0 + sum mu_i e_i|; lambda_0 = 1 - sum mu.
        double mu[3] = {0.0, 0.0, 0.0};
        const int n = k - 1;
        if (n == 1)
        {
            const double g = dot(e[0], e[0]);
            if (!(g > 0))
                continue;
            mu[0] = -dot(e[0], p0) / g;
        }
        else if (n == 2)
        {
            const double g00 = dot(e[0], e[0]), g01 = dot(e[0], e[1]), g11 = dot(e[1], e[1]);
            const double r0 = -dot(e[0], p0), r1 = -dot(e[1], p0);
            const double det = g00 * g11 - g01 * g01;
            if (!(det > 1e-30 * g00 * g11))
                continue;
            mu[0] = (r0 * g11 - r1 * g01) / det;
            mu[1] = (g00 * r1 - g01 * r0) / det;
        }
        else if (n == 3)
        {
            // The origin as p0 + E mu: Cramer's rule on E mu = -p0.
            const Vec3<double> c12 = cross(e[1], e[2]);
            const double det = dot(e[0], c12);
            const double scale = sqrt(dot(e[0], e[0]) * dot(e[1], e[1]) * dot(e[2], e[2]));
            if (!(det > 1e-15 * scale || det < -1e-15 * scale))
                continue;
            const Vec3<double> minus{-p0.x, -p0.y, -p0.z};
            mu[0] = dot(minus, c12) / det;
            mu[1] = dot(e[0], cross(minus, e[2])) / det;
            mu[2] = dot(e[0], cross(e[1], minus)) / det;
        }
        double lambda0 = 1.0;
        bool inside = true;
        for (int i = 0; i < n; ++i)
        {
            inside = inside && mu[i] > 0;
            lambda0 -= mu[i];
        }
        if (!inside || !(lambda0 > 0))
            continue;
        Vec3<double> point = p0;
        for (int i = 0; i < n; ++i)
            point = point + mu[i] * e[i];
        if (n == 3)
            point = {0.0, 0.0, 0.0};
        const double norm2 = dot(point, point);
        if (bestNorm2 < 0 || norm2 < bestNorm2)
        {
            best = point;
            bestNorm2 = norm2;
            bestMask = mask;
        }
    }
    if (bestMask == 0)  // every face degenerate (repeated points): keep the nearest vertex
    {
        int nearest = 0;
        for (int i = 1; i < count; ++i)
            if (dot(w[i], w[i]) < dot(w[nearest], w[nearest]))
                nearest = i;
        w[0] = w[nearest];
        count = 1;
        return w[0];
    }
    int kept = 0;
    for (int i = 0; i < count; ++i)
        if (bestMask & (1 << i))
            w[kept++] = w[i];
    count = kept;
    return best;
}

/** \brief Do the convex solids \a a and \a b come within \a padding (>= 0) of each other (touching
    or overlapping included)? GJK on their Minkowski difference: each step gives an upper bound on
    the distance (the nearest point of the simplex) and a lower bound (the support plane along it),
    and the answer is given once a bound decides it. When the bounds meet within the relative
    tolerance 1e-12 (or after 128 steps) without deciding, the answer is "within": a contact within
    rounding of the padding may go either way, a deeper one never reads as apart. */
RC_HD bool convexWithin(const ConvexShape &a, const ConvexShape &b, double padding)
{
    auto support = [&](const Vec3<double> &d)
    { return supportPoint(a, d) - supportPoint(b, Vec3<double>{-d.x, -d.y, -d.z}); };
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
        v = nearestOnSimplex(w, count);
        if (count == 4 || !(dot(v, v) < vv))
            return count == 4 || lower <= padding;  // origin enclosed, or no progress: the bounds have met
    }
    return true;
}
}  // namespace rastercheck::device
