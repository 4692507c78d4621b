#pragma once

#include <cstddef>
#include <cstdint>

#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Raster.h"

namespace rastercheck::device
{
/** \brief A mesh's slice of the flat vertex, triangle and tree buffers (its triangle order, one
    entry per triangle, starts at firstTriangle too). */
struct MeshSlice
{
    std::uint32_t firstVertex;
    std::uint32_t numVertices;
    std::uint32_t firstTriangle;
    std::uint32_t numTriangles;
    bool closed;
    std::uint32_t firstNode;
    std::uint32_t numNodes;
};

/** \brief Bounding sphere of a box: its centre and half diagonal. */
struct Sphere
{
    float center[3];
    float radius;
};

RC_HD Sphere boundingSphere(const Box &box)
{
    Sphere s;
    float radius2 = 0;
    for (int k = 0; k < 3; ++k)
    {
        s.center[k] = 0.5f * (box.min[k] + box.max[k]);
        const float half = 0.5f * (box.max[k] - box.min[k]);
        radius2 += half * half;
    }
    s.radius = sqrtf(radius2);
    return s;
}

/** \brief The distance filter over obstacles: false when the object's bounding sphere lies farther
    from the robot's than their radii plus the padding. */
RC_HD bool objectWithinReach(const Sphere &robot, const Sphere &object, float padding)
{
    float distance2 = 0;
    for (int k = 0; k < 3; ++k)
    {
        const float d = object.center[k] - robot.center[k];
        distance2 += d * d;
    }
    return !(sqrtf(distance2) > robot.radius + object.radius + padding);
}

/** \brief Layer values of the hybrid hierarchy: layers[k] = own(k) joined with every layer of a
    child of k, so that it stands for component k's whole subtree. Children before parents; in
    depth-first order k's children are k + 1, then each one's subtree end. With an exact join (min,
    max) the result equals joining the values of the whole subtree, for m joins instead of m^2 / 2. */
template <class T, class Own, class Join>
RC_HD void joinLayers(const int *subtreeEnd, int numComponents, T *layers, Own &&own, Join &&join)
{
    for (int k = numComponents - 1; k >= 0; --k)
    {
        layers[k] = own(k);
        for (int child = k + 1; child < subtreeEnd[k]; child = subtreeEnd[child])
            join(layers[k], layers[child]);
    }
}

/** \brief Layer boxes of the hybrid hierarchy: layer k bounds components [k, subtreeEnd[k]), the
    component's link and everything the chain carries beyond it. */
RC_HD void computeLayerBounds(const Box *componentBounds, const int *subtreeEnd, int numComponents, Box *layers)
{
    joinLayers(
        subtreeEnd, numComponents, layers, [&](int k) { return componentBounds[k]; },
        [](Box &layer, const Box &child) { extend(layer, child); });
}

/** \brief Where a pair can meet: A's bounds grown by the padding, cut by B's (may be empty). */
RC_HD Box pairWindow(const Box &a, const Box &b, float padding)
{
    Box grownA = a;
    for (int k = 0; k < 3; ++k)
    {
        grownA.min[k] -= padding;
        grownA.max[k] += padding;
    }
    return intersection(grownA, b);
}

/** \brief The padding of \a pair at one state: \a base plus the pair's entry in the state's rows of
    extra padding (CollisionRequest::pairPadding; null rows: none). Pairs are numbered environment
    pairs first (component pair % numComponents), then self pairs. The one lookup the CPU backend
    (PairPaddings) and the stages (pairPadding) both read a pair's padding through. */
RC_HD double paddingOfPair(double base, const double *environmentRow, const double *selfRow, std::size_t numComponents,
                           std::size_t numEnvironmentPairs, std::uint32_t pair)
{
    if (!environmentRow)
        return base;
    return base + (pair < numEnvironmentPairs ? environmentRow[pair % numComponents] : selfRow[pair - numEnvironmentPairs]);
}

/** \brief The padding for the float culls: a double beyond float's range (a padding of 1e300 m is
    allowed: everything collides) saturates instead of overflowing the conversion. */
RC_HD float floatPadding(double padding)
{
    const double largest = 3.4028234663852886e38;  // FLT_MAX
    return static_cast<float>(padding < largest ? padding : largest);
}

/** \brief Largest coordinate magnitude of a box: float rounding there is about 6e-8 of it. */
RC_HD float magnitudeOf(const Box &box)
{
    float magnitude = 0;
    for (int k = 0; k < 3; ++k)
        magnitude = maxOf(magnitude, maxOf(fabsf(box.min[k]), fabsf(box.max[k])));
    return magnitude;
}

/** \brief Whether the raster can decide a pair: parity needs a closed solid, and fragments placed
    well within a pixel. Far from CollisionModel::origin (a robot 1e6 m from its scene's centre)
    float rounding is not, and the raster would see overlaps that are not there: such pairs, like
    pairs of two open meshes, are decided exactly. */
RC_HD bool rasterUsable(bool closedA, bool closedB, const Box &window, float pixel)
{
    return (closedA || closedB) && 1e-6f * magnitudeOf(window) < 0.1f * pixel;
}

/** \brief How far outside the image a triangle may lie and still be kept: the padding plus the
    float pipeline's rounding allowance (a few ulps of the largest coordinate in play). */
RC_HD float pairMargin(const Box &window, const RasterGrid &grid, float padding)
{
    return padding + 1e-6f * magnitudeOf(window) + 1e-6f * grid.pixel;
}

/** \brief Per-triangle cull: whether the triangle's projection meets the image rectangle grown by
    \a margin. Every triangle a ray of the image can cross is kept, so the parity stays exact. */
RC_HD bool triangleMeetsImage(const Vec3<float> &a, const Vec3<float> &b, const Vec3<float> &c, const RasterGrid &grid,
                              float margin)
{
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    const float uLo = grid.origin[0] - margin, uHi = grid.origin[0] + grid.width * grid.pixel + margin;
    const float vLo = grid.origin[1] - margin, vHi = grid.origin[1] + grid.height * grid.pixel + margin;
    const float au = coordinate(a, u), bu = coordinate(b, u), cu = coordinate(c, u);
    const float av = coordinate(a, v), bv = coordinate(b, v), cv = coordinate(c, v);
    return !(maxOf(au, maxOf(bu, cu)) < uLo || minOf(au, minOf(bu, cu)) > uHi || maxOf(av, maxOf(bv, cv)) < vLo ||
             minOf(av, minOf(bv, cv)) > vHi);
}

/** \brief The contact a raster hit reports: the triangle of the pair's second solid met last at or
    before the hit fragment on the ray, and the hit's position (pixel centre at the hit's depth).
    \a run: the pixel's depth-sorted fragments; \a hit: index returned by sortSearchPair. */
RC_HD void hitContact(const Fragment *run, int hit, const RasterGrid &grid, int pixel, int &triangle, float position[3])
{
    int objectFragment = hit;
    while (objectFragment > 0 && !isPartyB(run[objectFragment]))
        --objectFragment;
    triangle = static_cast<int>(triangleOf(run[objectFragment]));
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    position[grid.axis] = run[hit].depth;
    position[u] = grid.origin[0] + (static_cast<float>(pixel % grid.width) + 0.5f) * grid.pixel;
    position[v] = grid.origin[1] + (static_cast<float>(pixel / grid.width) + 0.5f) * grid.pixel;
}

/** \brief Pair numbering shared by the backends, in the order the CPU visits pairs (so "first
    contact" means the same pair everywhere): environment pairs object-major, (o, k) -> o * m + k,
    then the self pairs in CollisionModel::selfPairs order. */
RC_HD std::uint32_t environmentPair(int object, int component, int numComponents)
{
    return static_cast<std::uint32_t>(object) * static_cast<std::uint32_t>(numComponents) +
           static_cast<std::uint32_t>(component);
}

/** \brief The number of self pair \a index (CollisionModel::selfPairs order) in the same numbering:
    after every environment pair. */
RC_HD std::uint32_t selfPair(int index, int numObjects, int numComponents)
{
    return environmentPair(numObjects, index, numComponents);
}

/** \brief Largest c in [0, n) with starts[c] <= i; starts ascending, starts[0] <= i. Maps an item of
    a flattened list back to its segment (the last of several empty segments that start there is
    the one holding the item). */
template <class Offset>
RC_HD std::uint32_t findSegment(const Offset *starts, std::uint32_t n, Offset i)
{
    std::uint32_t lo = 0, hi = n;  // answer in [lo, hi)
    while (hi - lo > 1)
    {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (starts[mid] <= i)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/** \brief Bits that number \a n + 1 values (0 to \a n). */
RC_HD int bitsToNumber(unsigned long long n)
{
    int bits = 1;
    while (bits < 64 && (n >> bits) != 0)
        ++bits;
    return bits;
}

/** \brief Bits that number the pixels of an image whose sides makeGrid holds to \a maxImageSide
    (one more each, for its rounding). */
RC_HD int imagePixelBits(int maxImageSide)
{
    const unsigned long long side = static_cast<unsigned long long>(maxImageSide) + 1;
    return bitsToNumber(side * side - 1);
}

/** \brief A fragment's sort key in the stages: its pair's number in the chunk above the pixel's,
    so that one stable sort of a chunk's fragments groups each pair's, and in it each pixel's, in
    order (the depth order within a pixel is sortFragments'). A pair number of \a numPairs (one
    past the chunk's) keys the slots past the fragments' count, after every real fragment. */
RC_HD unsigned long long fragmentKey(std::size_t pair, int pixel, int pixelBits)
{
    return (static_cast<unsigned long long>(pair) << pixelBits) | static_cast<unsigned long long>(pixel);
}

RC_HD std::uint32_t pairOfKey(unsigned long long key, int pixelBits)
{
    return static_cast<std::uint32_t>(key >> pixelBits);
}

RC_HD int pixelOfKey(unsigned long long key, int pixelBits)
{
    return static_cast<int>(key & ((1ull << pixelBits) - 1));
}
}  // namespace rastercheck::device
