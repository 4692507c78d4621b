// The shared per-element raster functions (device/Raster.h, device/Boxes.h), tested through the CPU:
// the CUDA kernels call the same code.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rastercheck/device/Raster.h"
#include "rastercheck/device/Stages.h"

namespace rd = rastercheck::device;
using V = rd::Vec3<float>;

namespace
{
// A closed, outward-oriented icosphere-like mesh: an octahedron subdivided, projected to a sphere.
struct TriangleSoup
{
    std::vector<V> vertices;
    std::vector<std::array<int, 3>> triangles;
};

TriangleSoup sphere(V center, float radius, int subdivisions)
{
    TriangleSoup soup;
    soup.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    soup.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int s = 0; s < subdivisions; ++s)
    {
        std::vector<std::array<int, 3>> next;
        std::map<std::pair<int, int>, int> midpoints;
        auto midpoint = [&](int a, int b) {
            auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = midpoints.find(key);
            if (it != midpoints.end())
                return it->second;
            const V &p = soup.vertices[a], &q = soup.vertices[b];
            V m{0.5f * (p.x + q.x), 0.5f * (p.y + q.y), 0.5f * (p.z + q.z)};
            const float n = std::sqrt(rd::dot(m, m));
            soup.vertices.push_back({m.x / n, m.y / n, m.z / n});
            return midpoints[key] = static_cast<int>(soup.vertices.size() - 1);
        };
        for (const auto &t : soup.triangles)
        {
            const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
            next.push_back({t[0], ab, ca});
            next.push_back({ab, t[1], bc});
            next.push_back({ca, bc, t[2]});
            next.push_back({ab, bc, ca});
        }
        soup.triangles = next;
    }
    for (V &v : soup.vertices)
        v = {center.x + radius * v.x, center.y + radius * v.y, center.z + radius * v.z};
    return soup;
}

rd::Box boxAround(const TriangleSoup &soup)
{
    rd::Box box = rd::emptyBox();
    for (const V &v : soup.vertices)
        rd::extend(box, v);
    return box;
}

std::vector<int> crossingsPerPixel(const rd::RasterGrid &grid, const TriangleSoup &soup)
{
    std::vector<int> count(static_cast<std::size_t>(grid.width * grid.height), 0);
    for (const auto &t : soup.triangles)
        rd::rasterizeTriangle(grid, soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]],
                              [&](int pixel, float, bool) { ++count[pixel]; });
    return count;
}
}  // namespace

TEST(Raster, ClosedSurfaceIsCrossedAnEvenNumberOfTimesOnEveryRay)
{
    // Pixel centres fall exactly on vertices and shared edges of this sphere (grid aligned to the
    // vertices): the snapped integer edge functions and the top-left rule must still give every
    // ray an even count, and the rays through the middle exactly two.
    const TriangleSoup soup = sphere({0, 0, 0}, 1.0f, 3);
    for (int axis = 0; axis < 3; ++axis)
    {
        rd::Box window = boxAround(soup);
        rd::RasterGrid grid = rd::makeGrid(window, 1.0f / 32, 256);
        grid.axis = axis;
        grid.origin[0] = grid.origin[1] = -1.0f - 0.5f / 32;  // centres on the grid lines through vertices
        grid.width = grid.height = 66;
        const std::vector<int> count = crossingsPerPixel(grid, soup);
        int inside = 0;
        for (std::size_t p = 0; p < count.size(); ++p)
        {
            EXPECT_EQ(count[p] % 2, 0) << "axis " << axis << " pixel " << p;
            inside += count[p] == 2;
        }
        // About pi / 4 of the 66 x 66 image lies inside the unit disc.
        EXPECT_NEAR(inside / (66.0 * 66.0), M_PI / 4 * (64.0 * 64.0) / (66.0 * 66.0), 0.02);
    }
}

TEST(Raster, RandomGridsKeepParityEven)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> offset(-0.3f, 0.3f), size(0.01f, 0.2f);
    const TriangleSoup soup = sphere({0.1f, -0.2f, 0.3f}, 0.7f, 2);
    for (int trial = 0; trial < 50; ++trial)
    {
        rd::Box window = boxAround(soup);
        for (int k = 0; k < 3; ++k)
        {
            window.min[k] += offset(rng);
            window.max[k] += offset(rng);
        }
        const rd::RasterGrid grid = rd::makeGrid(window, size(rng), 128);
        for (int c : crossingsPerPixel(grid, soup))
            ASSERT_EQ(c % 2, 0) << "trial " << trial;
    }
}

TEST(Raster, DepthIsInterpolatedAtPixelCentres)
{
    // A triangle in the plane z = 0.5 x over the window [0,1]^2 seen along z: depth = 0.5 * u.
    rd::RasterGrid grid{2, {0.0f, 0.0f}, 0.25f, 4, 4};
    int fragments = 0;
    rd::rasterizeTriangle(grid, V{0, 0, 0}, V{1, 0, 0.5f}, V{0, 1, 0}, [&](int pixel, float depth, bool entering) {
        EXPECT_FALSE(entering);  // counter-clockwise seen from +z: the normal points along the ray
        const float u = (pixel % 4 + 0.5f) * 0.25f;
        EXPECT_NEAR(depth, 0.5f * u, 1e-6f);
        ++fragments;
    });
    // Six centres strictly inside u + v < 1, and four on the hypotenuse, which this triangle owns
    // (top-left rule: the edge (1,0)->(0,1) points up).
    EXPECT_EQ(fragments, 10);

    // The other half of the square gets exactly the remaining six centres: each is covered once.
    std::vector<int> count(16, 0);
    for (const auto &t : {std::array<V, 3>{V{0, 0, 0}, V{1, 0, 0}, V{0, 1, 0}},
                          std::array<V, 3>{V{1, 0, 0}, V{1, 1, 0}, V{0, 1, 0}}})
        rd::rasterizeTriangle(grid, t[0], t[1], t[2], [&](int pixel, float, bool) { ++count[pixel]; });
    for (int c : count)
        EXPECT_EQ(c, 1);
}

TEST(Raster, GridCoversTheWindowAndCapsItsSide)
{
    const rd::Box window{{0, 0, 0}, {10.0f, 0.5f, 3.0f}};
    const rd::RasterGrid grid = rd::makeGrid(window, 0.001f, 256);
    EXPECT_EQ(grid.axis, 1);  // thinnest extent
    EXPECT_LE(grid.width, 256);
    EXPECT_LE(grid.height, 256);
    EXPECT_GE(grid.width * grid.pixel, 3.0f);   // u = z
    EXPECT_GE(grid.height * grid.pixel, 10.0f);  // v = x
}

TEST(Raster, SortSearchPairFindsOverlapInBothDirections)
{
    // Along a ray, a solid's first crossing enters it and the next leaves it.
    auto a = [](float d, bool in) { return rd::Fragment{d, 1u | (in ? rd::kEntering : 0u)}; };
    auto b = [](float d, bool in) { return rd::Fragment{d, 2u | rd::kPartyB | (in ? rd::kEntering : 0u)}; };
    // A spans [0, 2], B spans [1, 3]: B's entry at 1 is inside A.
    std::vector<rd::Fragment> overlap{b(3, false), a(0, true), b(1, true), a(2, false)};
    rd::sortFragments(overlap.data(), 4);
    EXPECT_EQ(rd::sortSearchPair(overlap.data(), 4, true, true), 1);
    // Disjoint intervals.
    std::vector<rd::Fragment> apart{a(0, true), a(1, false), b(2, true), b(3, false)};
    EXPECT_EQ(rd::sortSearchPair(apart.data(), 4, true, true), -1);
    // A buried in B: only the symmetric test sees it (A's fragments inside closed B).
    std::vector<rd::Fragment> buried{b(0, true), a(1, true), a(2, false), b(3, false)};
    EXPECT_EQ(rd::sortSearchPair(buried.data(), 4, true, true), 1);
    EXPECT_EQ(rd::sortSearchPair(buried.data(), 4, true, false), -1);  // B open: its parity means nothing
    // B buried in A: the paper's one-way test suffices.
    std::vector<rd::Fragment> contains{a(0, true), b(1, true), b(2, false), a(3, false)};
    EXPECT_EQ(rd::sortSearchPair(contains.data(), 4, true, false), 1);
    // A is two overlapping shells [0, 2] and [1, 3]; B sits in their overlap [1.2, 1.8]. Parity
    // would say "outside A" there; windings say inside twice.
    std::vector<rd::Fragment> shells{a(0, true), a(1, true), b(1.2f, true), b(1.8f, false), a(2, false), a(3, false)};
    EXPECT_EQ(rd::sortSearchPair(shells.data(), 6, true, false), 2);
}

TEST(Raster, ClosedSphereIsEnteredThenLeftOnEveryRay)
{
    const TriangleSoup soup = sphere({0, 0, 0}, 1.0f, 3);
    const rd::RasterGrid grid = rd::makeGrid(boxAround(soup), 1.0f / 16, 256);
    std::vector<std::vector<rd::Fragment>> perPixel(static_cast<std::size_t>(grid.width * grid.height));
    for (const auto &t : soup.triangles)
        rd::rasterizeTriangle(grid, soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]],
                              [&](int pixel, float depth, bool entering) {
                                  perPixel[pixel].push_back({depth, entering ? rd::kEntering : 0u});
                              });
    for (auto &fragments : perPixel)
    {
        rd::sortFragments(fragments.data(), static_cast<int>(fragments.size()));
        ASSERT_TRUE(fragments.empty() || fragments.size() == 2);
        if (fragments.size() == 2)
        {
            EXPECT_TRUE(rd::isEntering(fragments[0]));
            EXPECT_FALSE(rd::isEntering(fragments[1]));
        }
    }
}

TEST(Boxes, OrientedBoxTestsAgreeWithSeparationByHand)
{
    rd::OrientedBox unit{{0, 0, 0}, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {1, 1, 1}};
    // Rotated by 45 degrees about z, centred at x = 2.3: its corner reaches 2.3 - sqrt(2) = 0.886 < 1.
    const float c = std::sqrt(0.5f);
    rd::OrientedBox turned{{2.3f, 0, 0}, {c, -c, 0, c, c, 0, 0, 0, 1}, {1, 1, 1}};
    EXPECT_TRUE(rd::orientedBoxesOverlap(unit, turned, 0.0f));
    turned.center[0] = 2.5f;  // corner at 1.086: separated along x
    EXPECT_FALSE(rd::orientedBoxesOverlap(unit, turned, 0.0f));
    EXPECT_TRUE(rd::orientedBoxesOverlap(unit, turned, 0.1f));  // padding closes the 0.086 gap
    const rd::OrientedBox slab{{1.525f, 0, 0}, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0.475f, 1, 1}};  // x from 1.05 to 2
    EXPECT_FALSE(rd::orientedBoxesOverlap(unit, slab, 0.0f));
    EXPECT_TRUE(rd::orientedBoxesOverlap(unit, slab, 0.03f));  // each grows by 0.03: the 0.05 gap closes

    // The pair cull: world AABBs first, then OBBs. Turned 45 degrees at (2.2, 2.2), the box's AABB
    // reaches the unit box's (x and y from 0.786), the box itself stays 0.697 away along the diagonal.
    const auto mayMeet = [](const rd::OrientedBox &a, const rd::OrientedBox &b, float margin)
    { return rd::solidsMayMeet(rd::boundsOf(a), a, rd::boundsOf(b), b, margin); };
    rd::OrientedBox diagonal{{2.2f, 2.2f, 0}, {c, -c, 0, c, c, 0, 0, 0, 1}, {1, 1, 1}};
    EXPECT_TRUE(rd::boxesOverlap(rd::boundsOf(unit), rd::boundsOf(diagonal), 0.0f));
    EXPECT_FALSE(mayMeet(unit, diagonal, 0.0f));
    EXPECT_FALSE(mayMeet(unit, diagonal, 0.1f));
    EXPECT_TRUE(mayMeet(unit, diagonal, 0.3f));  // grown by 0.3 each, they meet along the diagonal
    // Their AABBs 0.586 apart along x: a margin below that is settled by the AABBs alone.
    turned.center[0] = 3.0f;
    EXPECT_FALSE(mayMeet(unit, turned, 0.5f));
    EXPECT_TRUE(mayMeet(unit, turned, 0.6f));
}

TEST(Boxes, LayerBoundsJoinEveryComponentOfTheSubtree)
{
    // Components in depth-first order: 0 carries 1 (which carries 2 and 3), 4 (which carries 5) and 6.
    const int subtreeEnd[7] = {7, 4, 3, 4, 6, 6, 7};
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> coordinate(-5.0f, 5.0f);
    for (int trial = 0; trial < 100; ++trial)
    {
        rd::Box bounds[7], layers[7];
        for (rd::Box &b : bounds)
            for (int k = 0; k < 3; ++k)
            {
                const float a = coordinate(rng), c = coordinate(rng);
                b.min[k] = std::min(a, c);
                b.max[k] = std::max(a, c);
            }
        rd::computeLayerBounds(bounds, subtreeEnd, 7, layers);
        for (int k = 0; k < 7; ++k)
        {
            rd::Box expected = bounds[k];
            for (int j = k + 1; j < subtreeEnd[k]; ++j)
                rd::extend(expected, bounds[j]);
            for (int axis = 0; axis < 3; ++axis)
            {
                EXPECT_EQ(layers[k].min[axis], expected.min[axis]) << "layer " << k;
                EXPECT_EQ(layers[k].max[axis], expected.max[axis]) << "layer " << k;
            }
        }
    }
}
