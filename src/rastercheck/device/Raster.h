#pragma once

#include <cmath>
#include <cstdint>

#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"

namespace rastercheck::device
{
/** \brief The image plane of one (component, object) pair: parallel rays along +axis through the
    centres of width x height square pixels of side \a pixel (world units), the grid's corner at
    world coordinates (origin[0], origin[1]) on the axes u = (axis + 1) % 3, v = (axis + 2) % 3. */
struct RasterGrid
{
    int axis;
    float origin[2];
    float pixel;
    int width;
    int height;
};

/** \brief Projected vertex positions are snapped to 1/256 of a pixel and edge functions are
    evaluated in exact 64-bit integer arithmetic. Two triangles sharing an edge then agree exactly on
    which side of it a pixel centre lies, and the top-left tie rule gives each centre to exactly
    one of them: a ray never crosses a closed surface an odd number of times by rounding. */
constexpr int kSubpixelBits = 8;
constexpr std::int64_t kSubpixel = std::int64_t(1) << kSubpixelBits;
/** \brief Snapped coordinates are clamped to this range (about 4 million pixels from the grid);
    triangles reaching farther are distorted beyond that distance only. */
constexpr std::int64_t kSnapLimit = std::int64_t(1) << 30;

/** \brief One fragment: where a triangle crosses a pixel's ray. \a code is the party bit
    (kPartyB for the second solid of the pair), the entering bit (the triangle faces against the
    ray: the ray enters the solid there) and the triangle's index in its mesh. */
struct Fragment
{
    float depth;
    std::uint32_t code;
};
constexpr std::uint32_t kPartyB = 0x80000000u;
constexpr std::uint32_t kEntering = 0x40000000u;
constexpr std::uint32_t kTriangleMask = 0x3fffffffu;
RC_HD bool isPartyB(const Fragment &f) { return (f.code & kPartyB) != 0; }
RC_HD bool isEntering(const Fragment &f) { return (f.code & kEntering) != 0; }
RC_HD std::uint32_t triangleOf(const Fragment &f) { return f.code & kTriangleMask; }
/** \brief Fragments are ordered by depth, ties by code, so the walk is deterministic. */
RC_HD bool fragmentBefore(const Fragment &a, const Fragment &b)
{
    return a.depth < b.depth || (a.depth == b.depth && a.code < b.code);
}

/** \brief Chooses the ray axis (the window's thinnest extent, so rays cross the fewest layers and
    the image covers the widest face) and a grid over \a window at \a pixel, enlarging the pixel
    when a side would exceed \a maxSide pixels. */
RC_HD RasterGrid makeGrid(const Box &window, float pixel, int maxSide)
{
    const float extent[3] = {window.max[0] - window.min[0], window.max[1] - window.min[1],
                             window.max[2] - window.min[2]};
    int axis = 0;
    if (extent[1] < extent[axis])
        axis = 1;
    if (extent[2] < extent[axis])
        axis = 2;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const float largest = extent[u] > extent[v] ? extent[u] : extent[v];
    // The 0.1 % slack keeps ceil(extent / pixel) within maxSide despite rounding, so the grid
    // always covers the whole window (the separation proof relies on it).
    if (largest > pixel * static_cast<float>(maxSide))
        pixel = largest / static_cast<float>(maxSide) * 1.001f;
    RasterGrid grid;
    grid.axis = axis;
    grid.origin[0] = window.min[u];
    grid.origin[1] = window.min[v];
    grid.pixel = pixel;
    grid.width = static_cast<int>(ceilf(extent[u] / pixel));
    grid.height = static_cast<int>(ceilf(extent[v] / pixel));
    if (grid.width < 1)
        grid.width = 1;
    if (grid.height < 1)
        grid.height = 1;
    return grid;
}

RC_HD float coordinate(const Vec3<float> &p, int axis) { return axis == 0 ? p.x : (axis == 1 ? p.y : p.z); }

/** \brief A projected, snapped vertex. */
struct SnappedVertex
{
    std::int64_t x, y;
    float depth;
};

RC_HD std::int64_t snap(float value)
{
    const double scaled = static_cast<double>(value) * static_cast<double>(kSubpixel);
    const double limit = static_cast<double>(kSnapLimit);
    const double limited = scaled < -limit ? -limit : (scaled > limit ? limit : scaled);
    // Round half away from zero (llround's rule), written out so it inlines on both compilers.
    return static_cast<std::int64_t>(limited < 0 ? limited - 0.5 : limited + 0.5);
}

RC_HD SnappedVertex project(const RasterGrid &grid, const Vec3<float> &p)
{
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    return SnappedVertex{snap((coordinate(p, u) - grid.origin[0]) / grid.pixel),
                         snap((coordinate(p, v) - grid.origin[1]) / grid.pixel), coordinate(p, grid.axis)};
}

RC_HD std::int64_t edgeFunction(const SnappedVertex &a, const SnappedVertex &b, std::int64_t px, std::int64_t py)
{
    return (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x);
}

/** \brief Top-left rule for counter-clockwise triangles: a centre exactly on edge a->b belongs to
    this triangle iff the edge points "up", or "left" when horizontal. The neighbour across the edge
    sees it reversed and gets the complement, so each centre is counted once. */
RC_HD bool ownsEdge(const SnappedVertex &a, const SnappedVertex &b)
{
    const std::int64_t dx = b.x - a.x, dy = b.y - a.y;
    return dy > 0 || (dy == 0 && dx < 0);
}

/** \brief Calls emit(pixelIndex, depth, entering) for every pixel centre inside the projection of
    triangle (p0, p1, p2) (world frame), with the depth along the ray interpolated at the centre;
    \a entering is true when the triangle (outward, counter-clockwise) faces against the ray.
    Triangles seen edge-on make no fragments (a ray grazing a face does not cross the surface).
    Returns the number of fragments. Used twice per triangle: once to count (pre-rasterization),
    once to write. */
template <class Emit>
RC_HD int rasterizeTriangle(const RasterGrid &grid, const Vec3<float> &p0, const Vec3<float> &p1,
                            const Vec3<float> &p2, Emit &&emit)
{
    SnappedVertex a = project(grid, p0), b = project(grid, p1), c = project(grid, p2);
    std::int64_t area = edgeFunction(a, b, c.x, c.y);
    if (area == 0)
        return 0;
    // (u, v, axis) is right-handed: a counter-clockwise projection means the normal points along
    // the ray, so the ray leaves the solid there.
    const bool entering = area < 0;
    if (area < 0)
    {
        const SnappedVertex t = b;
        b = c;
        c = t;
        area = -area;
    }
    // Pixel i's centre is at (i + 1/2) pixels: the covered range of i is [ceil(min - 1/2), floor(max - 1/2)].
    const std::int64_t half = kSubpixel / 2;
    auto firstPixel = [&](std::int64_t lo) {
        const std::int64_t t = lo - half;
        return t <= 0 ? std::int64_t(0) : (t + kSubpixel - 1) / kSubpixel;
    };
    auto lastPixel = [&](std::int64_t hi, int size) {
        const std::int64_t t = hi - half;
        if (t < 0)
            return std::int64_t(-1);
        const std::int64_t i = t / kSubpixel;
        return i < size - 1 ? i : std::int64_t(size - 1);
    };
    const std::int64_t minX = a.x < b.x ? (a.x < c.x ? a.x : c.x) : (b.x < c.x ? b.x : c.x);
    const std::int64_t maxX = a.x > b.x ? (a.x > c.x ? a.x : c.x) : (b.x > c.x ? b.x : c.x);
    const std::int64_t minY = a.y < b.y ? (a.y < c.y ? a.y : c.y) : (b.y < c.y ? b.y : c.y);
    const std::int64_t maxY = a.y > b.y ? (a.y > c.y ? a.y : c.y) : (b.y > c.y ? b.y : c.y);
    const std::int64_t x0 = firstPixel(minX), x1 = lastPixel(maxX, grid.width);
    const std::int64_t y0 = firstPixel(minY), y1 = lastPixel(maxY, grid.height);
    const bool ownsBC = ownsEdge(b, c), ownsCA = ownsEdge(c, a), ownsAB = ownsEdge(a, b);
    const float inverseArea = 1.0f / static_cast<float>(area);
    int count = 0;
    for (std::int64_t j = y0; j <= y1; ++j)
    {
        const std::int64_t py = j * kSubpixel + half;
        RC_ROLLED_LOOP
        for (std::int64_t i = x0; i <= x1; ++i)
        {
            const std::int64_t px = i * kSubpixel + half;
            const std::int64_t w0 = edgeFunction(b, c, px, py);
            const std::int64_t w1 = edgeFunction(c, a, px, py);
            const std::int64_t w2 = edgeFunction(a, b, px, py);
            if (w0 < 0 || w1 < 0 || w2 < 0 || (w0 == 0 && !ownsBC) || (w1 == 0 && !ownsCA) || (w2 == 0 && !ownsAB))
                continue;
            const float depth = (static_cast<float>(w0) * a.depth + static_cast<float>(w1) * b.depth +
                                 static_cast<float>(w2) * c.depth) *
                                inverseArea;
            emit(static_cast<int>(j * grid.width + i), depth, entering);
            ++count;
        }
    }
    return count;
}

/** \brief Sorts one pixel's fragments by depth (insertion sort: a pixel holds few fragments; the
    batched stages group each pair's pixel runs by a radix sort and then sort each run here too). */
RC_HD void sortFragments(Fragment *fragments, int count)
{
    for (int i = 1; i < count; ++i)
    {
        const Fragment f = fragments[i];
        int j = i - 1;
        while (j >= 0 && fragmentBefore(f, fragments[j]))
        {
            fragments[j + 1] = fragments[j];
            --j;
        }
        fragments[j + 1] = f;
    }
}

/** \brief Sort_Search_Pair (Cai et al., Alg. 2), symmetric: walks one pixel's depth-sorted
    fragments keeping an inside state per party. A fragment of B met while inside closed A, or a
    fragment of A met while inside closed B, means the solids overlap on this ray. Returns the index
    of that fragment, or -1. An open party's state means nothing and is not used.

    The paper toggles a parity flag. We count windings instead (+1 entering, -1 leaving; inside
    while positive): a component merged from several overlapping closed shells (a link with a
    cylinder and two spheres) is inside where any shell is, which parity gets wrong where two shells
    overlap. For a single closed shell the two agree. */
RC_HD int sortSearchPair(const Fragment *sorted, int count, bool closedA, bool closedB)
{
    int windingA = 0, windingB = 0;
    for (int k = 0; k < count; ++k)
    {
        const int step = isEntering(sorted[k]) ? 1 : -1;
        if (isPartyB(sorted[k]))
        {
            windingB += step;
            if (closedA && windingA > 0)
                return k;
        }
        else
        {
            windingA += step;
            if (closedB && windingB > 0)
                return k;
        }
    }
    return -1;
}

}  // namespace rastercheck::device
