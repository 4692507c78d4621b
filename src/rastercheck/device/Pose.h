#pragma once

#include <cmath>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/SinCos.h"

namespace rastercheck::device
{
/** \brief Rigid transform as a row-major 3x4 matrix [R | t]; 12 scalars, the layout of every
    pose buffer (`n_states x n_links x 12`). */
template <class T>
struct Pose
{
    T m[12];

    RC_HD static Pose identity()
    {
        return Pose{{T(1), T(0), T(0), T(0), T(0), T(1), T(0), T(0), T(0), T(0), T(1), T(0)}};
    }
};

template <class T>
struct Vec3
{
    T x, y, z;

    RC_HD T operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
};

template <class T>
RC_HD Vec3<T> operator-(const Vec3<T> &a, const Vec3<T> &b)
{
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
RC_HD Vec3<T> operator+(const Vec3<T> &a, const Vec3<T> &b)
{
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class T>
RC_HD Vec3<T> operator*(T s, const Vec3<T> &a)
{
    return {s * a.x, s * a.y, s * a.z};
}
template <class T>
RC_HD T dot(const Vec3<T> &a, const Vec3<T> &b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
RC_HD Vec3<T> cross(const Vec3<T> &a, const Vec3<T> &b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// fminf/fmaxf are library calls on the host (their NaN rules forbid inlining); coordinates in the
// pipeline are finite (states are checked first), so plain comparisons serve.
RC_HD float minOf(float a, float b) { return a < b ? a : b; }
RC_HD float maxOf(float a, float b) { return a > b ? a : b; }

/** \brief p' = pose * p. */
template <class T>
RC_HD Vec3<T> transformPoint(const Pose<T> &pose, const Vec3<T> &p)
{
    const T *m = pose.m;
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

/** \brief v' = R * v (direction, no translation). */
template <class T>
RC_HD Vec3<T> rotateVector(const Pose<T> &pose, const Vec3<T> &v)
{
    const T *m = pose.m;
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
}

/** \brief a * b. */
template <class T>
RC_HD Pose<T> compose(const Pose<T> &a, const Pose<T> &b)
{
    Pose<T> c;
    for (int r = 0; r < 3; ++r)
    {
        for (int col = 0; col < 3; ++col)
            c.m[4 * r + col] =
                a.m[4 * r] * b.m[col] + a.m[4 * r + 1] * b.m[4 + col] + a.m[4 * r + 2] * b.m[8 + col];
        c.m[4 * r + 3] =
            a.m[4 * r] * b.m[3] + a.m[4 * r + 1] * b.m[7] + a.m[4 * r + 2] * b.m[11] + a.m[4 * r + 3];
    }
    return c;
}

/** \brief to^-1 * from: the pose of \a from's frame in \a to's frame (rigid poses). */
template <class T>
RC_HD Pose<T> relativePose(const Pose<T> &to, const Pose<T> &from)
{
    Pose<T> c;
    const T *a = to.m, *b = from.m;
    for (int r = 0; r < 3; ++r)
    {
        for (int col = 0; col < 3; ++col)
            c.m[4 * r + col] = a[r] * b[col] + a[4 + r] * b[4 + col] + a[8 + r] * b[8 + col];
        c.m[4 * r + 3] = a[r] * (b[3] - a[3]) + a[4 + r] * (b[7] - a[7]) + a[8 + r] * (b[11] - a[11]);
    }
    return c;
}

/** \brief Rotation by \a angle (rad) about unit \a axis, Rodrigues' formula. */
template <class T>
RC_HD Pose<T> axisAngle(const Vec3<T> &axis, T angle)
{
    double sine = 0, cosine = 0;
    sinCos(static_cast<double>(angle), sine, cosine);
    const T c = static_cast<T>(cosine), s = static_cast<T>(sine), t = T(1) - c;
    const T x = axis.x, y = axis.y, z = axis.z;
    return Pose<T>{{t * x * x + c, t * x * y - s * z, t * x * z + s * y, T(0), t * x * y + s * z, t * y * y + c,
                    t * y * z - s * x, T(0), t * x * z - s * y, t * y * z + s * x, t * z * z + c, T(0)}};
}

/** \brief Columns \a u and \a v of \a pose's rotation mixed by a turn (cosine \a c, sine \a s)
    that maps u to c u + s v and v to c v - s u. */
template <int u, int v, class T>
RC_HD Pose<T> turnColumns(const Pose<T> &pose, T c, T s)
{
    Pose<T> turned = pose;
    for (int r = 0; r < 3; ++r)
    {
        turned.m[4 * r + u] = c * pose.m[4 * r + u] + s * pose.m[4 * r + v];
        turned.m[4 * r + v] = c * pose.m[4 * r + v] - s * pose.m[4 * r + u];
    }
    return turned;
}

/** \brief \a pose followed by a turn of \a angle about \a axis (unit, in \a pose's frame):
    compose(pose, axisAngle(axis, angle)). About a coordinate axis (most joints: URDF axes are
    written "0 0 1"), only the two columns the turn mixes change: the Panda's forward kinematics
    280 -> 252 ns (build machine, one core). */
template <class T>
RC_HD Pose<T> rotateAbout(const Pose<T> &pose, const Vec3<T> &axis, T angle)
{
    const bool alongX = axis.y == T(0) && axis.z == T(0), alongY = axis.x == T(0) && axis.z == T(0),
               alongZ = axis.x == T(0) && axis.y == T(0);
    if (!(alongX || alongY || alongZ))
        return compose(pose, axisAngle(axis, angle));
    // The sign of a unit coordinate axis folded into the angle.
    const T sign = alongX ? axis.x : (alongY ? axis.y : axis.z);
    if (!(sign == T(1) || sign == T(-1)))
        return compose(pose, axisAngle(axis, angle));
    double sine = 0, cosine = 0;
    sinCos(static_cast<double>(sign * angle), sine, cosine);
    const T c = static_cast<T>(cosine), s = static_cast<T>(sine);
    if (alongZ)
        return turnColumns<0, 1>(pose, c, s);
    if (alongX)
        return turnColumns<1, 2>(pose, c, s);
    return turnColumns<2, 0>(pose, c, s);
}

/** \brief Rotation from a unit quaternion (x, y, z, w) and a translation. The quaternion is
    normalised here, so a slightly off-unit input is harmless. */
template <class T>
RC_HD Pose<T> fromQuaternion(T px, T py, T pz, T qx, T qy, T qz, T qw)
{
    const T n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
    qx /= n;
    qy /= n;
    qz /= n;
    qw /= n;
    return Pose<T>{{T(1) - T(2) * (qy * qy + qz * qz), T(2) * (qx * qy - qz * qw), T(2) * (qx * qz + qy * qw), px,
                    T(2) * (qx * qy + qz * qw), T(1) - T(2) * (qx * qx + qz * qz), T(2) * (qy * qz - qx * qw), py,
                    T(2) * (qx * qz - qy * qw), T(2) * (qy * qz + qx * qw), T(1) - T(2) * (qx * qx + qy * qy), pz}};
}

/** \brief The kinds of joint the kinematics understands; the numbers are stable (device buffers). */
enum class JointKind : int
{
    Fixed = 0,
    Revolute = 1,  // also URDF "continuous"
    Prismatic = 2,
    Floating = 3,  // 7 coordinates: x y z qx qy qz qw
    Planar = 4     // 3 coordinates: x y theta, motion in the joint frame's xy plane
};

/** \brief Number of configuration coordinates a joint kind consumes. */
RC_HD int coordinateCount(JointKind kind)
{
    switch (kind)
    {
        case JointKind::Revolute:
        case JointKind::Prismatic:
            return 1;
        case JointKind::Floating:
            return 7;
        case JointKind::Planar:
            return 3;
        default:
            return 0;
    }
}

/** \brief Forward kinematics of one joint: pose of the child link in the parent link frame,
    origin * motion(values). \a values points at the joint's coordinates (already mimic-resolved
    for one-coordinate joints). One implementation for the CPU (double) and GPU (float) backends. */
template <class T>
RC_HD Pose<T> jointPose(JointKind kind, const Pose<T> &origin, const Vec3<T> &axis, const T *values)
{
    switch (kind)
    {
        case JointKind::Revolute:
            return rotateAbout(origin, axis, values[0]);
        case JointKind::Prismatic:
        {
            Pose<T> p = origin;
            const Vec3<T> d = rotateVector(origin, values[0] * axis);
            p.m[3] += d.x;
            p.m[7] += d.y;
            p.m[11] += d.z;
            return p;
        }
        case JointKind::Floating:
            return compose(origin, fromQuaternion(values[0], values[1], values[2], values[3], values[4], values[5],
                                                  values[6]));
        case JointKind::Planar:
        {
            double sine = 0, cosine = 0;
            sinCos(static_cast<double>(values[2]), sine, cosine);
            const T c = static_cast<T>(cosine), s = static_cast<T>(sine);
            return compose(origin, Pose<T>{{c, -s, T(0), values[0], s, c, T(0), values[1], T(0), T(0), T(1), T(0)}});
        }
        default:
            return origin;
    }
}
}  // namespace rastercheck::device
