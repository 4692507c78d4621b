#pragma once

#include <cmath>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"

namespace rastercheck::device
{
/** \brief Axis-aligned box in the world frame. */
struct Box
{
    float min[3];
    float max[3];
};

/** \brief Oriented box: centre, axes as the columns of a row-major 3x3, half extents. */
struct OrientedBox
{
    float center[3];
    float axes[9];  // axes[3 * row + column]; column k is box axis k
    float half[3];
};

RC_HD Box emptyBox() { return Box{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }

RC_HD void extend(Box &box, const Box &other)
{
    for (int k = 0; k < 3; ++k)
    {
        box.min[k] = minOf(box.min[k], other.min[k]);
        box.max[k] = maxOf(box.max[k], other.max[k]);
    }
}

RC_HD void extend(Box &box, const Vec3<float> &p)
{
    const float c[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k)
    {
        box.min[k] = minOf(box.min[k], c[k]);
        box.max[k] = maxOf(box.max[k], c[k]);
    }
}

RC_HD bool boxesOverlap(const Box &a, const Box &b, float margin)
{
    for (int k = 0; k < 3; ++k)
        if (a.min[k] > b.max[k] + margin || b.min[k] > a.max[k] + margin)
            return false;
    return true;
}

/** \brief Intersection of two boxes (may be empty: min > max on some axis). */
RC_HD Box intersection(const Box &a, const Box &b)
{
    Box c;
    for (int k = 0; k < 3; ++k)
    {
        c.min[k] = maxOf(a.min[k], b.min[k]);
        c.max[k] = minOf(a.max[k], b.max[k]);
    }
    return c;
}

RC_HD bool isEmpty(const Box &box)
{
    return box.min[0] > box.max[0] || box.min[1] > box.max[1] || box.min[2] > box.max[2];
}

/** \brief pose * box (box given in the link frame), grown by 1e-6 of the translation's size: the
    float pose rounded it to about 6e-8 of that, and a cull must not cut off geometry however far
    from the origin the component is. */
RC_HD OrientedBox transformBox(const Pose<float> &pose, const OrientedBox &local)
{
    OrientedBox world;
    const Vec3<float> c = transformPoint(pose, Vec3<float>{local.center[0], local.center[1], local.center[2]});
    world.center[0] = c.x;
    world.center[1] = c.y;
    world.center[2] = c.z;
    for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 3; ++col)
            world.axes[3 * r + col] = pose.m[4 * r] * local.axes[col] + pose.m[4 * r + 1] * local.axes[3 + col] +
                                      pose.m[4 * r + 2] * local.axes[6 + col];
    const float rounding = 1e-6f * (fabsf(pose.m[3]) + fabsf(pose.m[7]) + fabsf(pose.m[11]));
    for (int k = 0; k < 3; ++k)
        world.half[k] = local.half[k] + rounding;
    return world;
}

/** \brief Tight world-axis bounds of an oriented box. */
RC_HD Box boundsOf(const OrientedBox &box)
{
    Box b;
    for (int r = 0; r < 3; ++r)
    {
        const float reach = fabsf(box.axes[3 * r]) * box.half[0] + fabsf(box.axes[3 * r + 1]) * box.half[1] +
                            fabsf(box.axes[3 * r + 2]) * box.half[2];
        b.min[r] = box.center[r] - reach;
        b.max[r] = box.center[r] + reach;
    }
    return b;
}

/** \brief Separating-axis test of two oriented boxes, each grown by \a margin on every side
    (15 axes). A small relative epsilon keeps nearly parallel edge axes from producing false
    separations, so the test errs towards "overlap" (conservative for a cull). */
RC_HD bool orientedBoxesOverlap(const OrientedBox &a, const OrientedBox &b, float margin)
{
    // Rotation of b in a's frame and translation in a's frame.
    float R[3][3], AbsR[3][3], t[3];
    const float d[3] = {b.center[0] - a.center[0], b.center[1] - a.center[1], b.center[2] - a.center[2]};
    for (int i = 0; i < 3; ++i)
    {
        t[i] = a.axes[i] * d[0] + a.axes[3 + i] * d[1] + a.axes[6 + i] * d[2];
        for (int j = 0; j < 3; ++j)
        {
            R[i][j] = a.axes[i] * b.axes[j] + a.axes[3 + i] * b.axes[3 + j] + a.axes[6 + i] * b.axes[6 + j];
            AbsR[i][j] = fabsf(R[i][j]) + 1e-6f;
        }
    }
    const float ea[3] = {a.half[0] + margin, a.half[1] + margin, a.half[2] + margin};
    const float eb[3] = {b.half[0] + margin, b.half[1] + margin, b.half[2] + margin};
    for (int i = 0; i < 3; ++i)
        if (fabsf(t[i]) > ea[i] + eb[0] * AbsR[i][0] + eb[1] * AbsR[i][1] + eb[2] * AbsR[i][2])
            return false;
    for (int j = 0; j < 3; ++j)
        if (fabsf(t[0] * R[0][j] + t[1] * R[1][j] + t[2] * R[2][j]) >
            ea[0] * AbsR[0][j] + ea[1] * AbsR[1][j] + ea[2] * AbsR[2][j] + eb[j])
            return false;
    for (int i = 0; i < 3; ++i)
    {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j)
        {
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const float ra = ea[i1] * AbsR[i2][j] + ea[i2] * AbsR[i1][j];
            const float rb = eb[j1] * AbsR[i][j2] + eb[j2] * AbsR[i][j1];
            if (fabsf(t[i2] * R[i1][j] - t[i1] * R[i2][j]) > ra + rb)
                return false;
        }
    }
    return true;
}

/** \brief The box cull of a pair of solids (two components, or a component and an object): their
    world AABBs (six comparisons) settle most pairs far apart, their OBBs (15 axes) most of the
    rest. */
RC_HD bool solidsMayMeet(const Box &boundsA, const OrientedBox &boxA, const Box &boundsB, const OrientedBox &boxB,
                             float margin)
{
    return boxesOverlap(boundsA, boundsB, margin) && orientedBoxesOverlap(boxA, boxB, margin);
}
}  // namespace rastercheck::device
