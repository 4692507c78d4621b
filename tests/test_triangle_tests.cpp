// Exact predicates, triangle/triangle intersection and distance, and ray/triangle parity hits, against
// hand-made answers, exact integer arithmetic and FCL.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>

#include "rastercheck/device/Predicates.h"
#include "rastercheck/device/TriangleTests.h"
#include "rastercheck/geometry/TriangleTests.h"

namespace rc = rastercheck;
using Vec = Eigen::Vector3d;

namespace
{
using Triangle = std::array<Vec, 3>;

rc::device::Vec3<double> toDevice(const Vec &v)
{
    return {v.x(), v.y(), v.z()};
}

bool intersect(const Triangle &p, const Triangle &q)
{
    return rc::trianglesIntersect(p[0], p[1], p[2], q[0], q[1], q[2]);
}

double distance(const Triangle &p, const Triangle &q, Vec *x = nullptr, Vec *y = nullptr)
{
    return rc::triangleDistance(p[0], p[1], p[2], q[0], q[1], q[2], x, y);
}

bool fclIntersect(const Triangle &p, const Triangle &q)
{
    return fcl::detail::Intersect<double>::intersect_Triangle(p[0], p[1], p[2], q[0], q[1], q[2]);
}

double fclDistance(const Triangle &p, const Triangle &q)
{
    Vec x, y;
    return fcl::detail::TriangleDistance<double>::triDistance(p.data(), q.data(), x, y);
}

// Is x on the closed triangle t, within eps (metres)? Plane distance and distances inside the three
// edge lines, independent of the code under test.
bool onTriangle(const Vec &x, const Triangle &t, double eps)
{
    const Vec n = (t[1] - t[0]).cross(t[2] - t[0]);
    const double area2 = n.norm();
    if (std::abs(n.dot(x - t[0])) > eps * area2)
        return false;
    for (int i = 0; i < 3; ++i)
    {
        const Vec edge = t[(i + 1) % 3] - t[i];
        if (n.dot(edge.cross(x - t[i])) < -eps * area2 * edge.norm())
            return false;
    }
    return true;
}

// Every answer must be the same for either argument order and any cyclic or mirrored vertex order.
void expectIntersect(const Triangle &p, const Triangle &q, bool expected)
{
    const int orders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
    for (const auto &o : orders)
    {
        const Triangle pp = {p[o[0]], p[o[1]], p[o[2]]};
        EXPECT_EQ(intersect(pp, q), expected);
        EXPECT_EQ(intersect(q, pp), expected);
    }
}

// ---- exact reference on small integer coordinates -----------------------------------------
// Disjoint compact convex sets are strictly separated along the direction between their closest
// points. For triangles (degenerate ones included) that direction is a face normal (a x b of two
// point differences), an edge/edge normal (a x b), a vertex/edge direction e x (d x e), or a
// vertex/vertex difference d. Trying all of those in exact integer arithmetic decides
// intersection without any of the code under test.
using IVec = std::array<std::int64_t, 3>;

IVec sub(const IVec &a, const IVec &b)
{
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
IVec cross(const IVec &a, const IVec &b)
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
std::int64_t dot(const IVec &a, const IVec &b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

bool separatedAlong(const IVec &axis, const std::array<IVec, 3> &p, const std::array<IVec, 3> &q)
{
    std::int64_t pMin = dot(axis, p[0]), pMax = pMin, qMin = dot(axis, q[0]), qMax = qMin;
    for (int i = 1; i < 3; ++i)
    {
        pMin = std::min(pMin, dot(axis, p[i]));
        pMax = std::max(pMax, dot(axis, p[i]));
        qMin = std::min(qMin, dot(axis, q[i]));
        qMax = std::max(qMax, dot(axis, q[i]));
    }
    return pMax < qMin || qMax < pMin;
}

bool integerTrianglesIntersect(const std::array<IVec, 3> &p, const std::array<IVec, 3> &q)
{
    std::vector<IVec> differences, edges;
    for (int i = 0; i < 3; ++i)
    {
        edges.push_back(sub(p[(i + 1) % 3], p[i]));
        edges.push_back(sub(q[(i + 1) % 3], q[i]));
        for (int j = 0; j < 3; ++j)
            differences.push_back(sub(p[i], q[j]));
    }
    differences.insert(differences.end(), edges.begin(), edges.end());
    for (const IVec &d : differences)
    {
        if (separatedAlong(d, p, q))
            return false;
        for (const IVec &e : differences)
            if (separatedAlong(cross(d, e), p, q))
                return false;
    }
    for (const IVec &e : edges)
        for (const IVec &d : differences)
            if (separatedAlong(cross(e, cross(d, e)), p, q))
                return false;
    return true;
}

Vec toVec(const IVec &v)
{
    return Vec(double(v[0]), double(v[1]), double(v[2]));
}

// Random integer triangles biased towards the hard cases: shared planes, collinear or repeated
// vertices, shared vertices and parallel edges all occur often in a small grid.
struct IntegerPairs
{
    std::mt19937_64 rng{12345};

    IVec point(int range)
    {
        std::uniform_int_distribution<int> coordinate(-range, range);
        return {coordinate(rng), coordinate(rng), coordinate(rng)};
    }

    std::array<IVec, 3> triangle(int kind, int range)
    {
        std::array<IVec, 3> t = {point(range), point(range), point(range)};
        switch (kind)
        {
            case 1:  // in the plane z = 1
                for (IVec &v : t)
                    v[2] = 1;
                break;
            case 2:  // in the tilted plane z = x - y
                for (IVec &v : t)
                    v[2] = v[0] - v[1];
                break;
            case 3:  // collinear: third vertex on the line of the first two
            {
                const IVec d = sub(t[1], t[0]);
                const int k = std::uniform_int_distribution<int>(-1, 2)(rng);
                t[2] = {t[0][0] + k * d[0], t[0][1] + k * d[1], t[0][2] + k * d[2]};
                break;
            }
            case 4:  // a repeated vertex, or a single point
                t[1] = t[0];
                if (std::uniform_int_distribution<int>(0, 3)(rng) == 0)
                    t[2] = t[0];
                break;
            default:
                break;
        }
        return t;
    }
};
}  // namespace

TEST(Predicates, MatchExactIntegerArithmeticOnNearlyDegenerateInput)
{
    // Coordinates k * 2^-30 with |k| < 2^38 are exact doubles and their orientation determinant is
    // exact in 128-bit integers. Points are built nearly coplanar, where naive evaluation fails.
    std::mt19937_64 rng(7);
    std::uniform_int_distribution<std::int64_t> coordinate(-(std::int64_t(1) << 37), std::int64_t(1) << 37);
    std::uniform_int_distribution<int> nudge(-1, 1);
    const double unit = std::ldexp(1.0, -30);
    int wrongNaive = 0;
    for (int trial = 0; trial < 20000; ++trial)
    {
        std::int64_t k[4][3];
        for (int i = 0; i < 3; ++i)
            for (int c = 0; c < 3; ++c)
                k[i][c] = coordinate(rng) / 4;
        // d = a + m (b - a) + n (c - a): exactly coplanar, or one grid step off it.
        const int m = nudge(rng) * 2 + 1, n = nudge(rng) - 1;
        const bool exact = trial % 2 == 0;
        for (int c = 0; c < 3; ++c)
            k[3][c] = k[0][c] + m * (k[1][c] - k[0][c]) + n * (k[2][c] - k[0][c]) + (exact ? 0 : nudge(rng));
        Vec p[4];
        for (int i = 0; i < 4; ++i)
            p[i] = Vec(double(k[i][0]) * unit, double(k[i][1]) * unit, double(k[i][2]) * unit);
        __int128 u[3], v[3], w[3];
        for (int c = 0; c < 3; ++c)
        {
            u[c] = k[1][c] - k[0][c];
            v[c] = k[2][c] - k[0][c];
            w[c] = k[3][c] - k[0][c];
        }
        const __int128 det = w[0] * (u[1] * v[2] - u[2] * v[1]) + w[1] * (u[2] * v[0] - u[0] * v[2]) +
                             w[2] * (u[0] * v[1] - u[1] * v[0]);
        const int expected = (det > 0) - (det < 0);
        ASSERT_EQ(rc::device::orient3d(toDevice(p[0]), toDevice(p[1]), toDevice(p[2]), toDevice(p[3])), expected)
            << "trial " << trial;
        const double naive = (p[3] - p[0]).dot((p[1] - p[0]).cross(p[2] - p[0]));
        wrongNaive += ((naive > 0) - (naive < 0)) != expected;

        const __int128 det2 = u[0] * v[1] - u[1] * v[0];
        ASSERT_EQ(rc::device::orient2d(p[0].x(), p[0].y(), p[1].x(), p[1].y(), p[2].x(), p[2].y()),
                  (det2 > 0) - (det2 < 0));
    }
    std::printf("[ info     ] naive orient3d got %d of 20000 nearly coplanar signs wrong\n", wrongNaive);
}

TEST(Predicates, ClassicNearlyCollinearGrid)
{
    // Shewchuk's example: (0.5 + i ulp, 0.5 + j ulp) against the line through (12, 12) and (24, 24).
    // Exactly, the sign is that of j - i.
    const double ulp = std::ldexp(1.0, -53);
    for (int i = 0; i < 64; ++i)
        for (int j = 0; j < 64; ++j)
        {
            const int expected = (j > i) - (j < i);
            EXPECT_EQ(rc::device::orient2d(12.0, 12.0, 24.0, 24.0, 0.5 + i * ulp, 0.5 + j * ulp), expected);
        }
}

TEST(TrianglesIntersect, HandMadeCases)
{
    const Triangle base = {Vec(0, 0, 0), Vec(2, 0, 0), Vec(0, 2, 0)};
    // Crossing: a vertical triangle piercing the base's interior.
    expectIntersect(base, {Vec(0.5, 0.5, -1), Vec(0.5, 0.5, 1), Vec(1.5, -1, 0.5)}, true);
    // Separated: above the base.
    expectIntersect(base, {Vec(0, 0, 0.1), Vec(2, 0, 0.1), Vec(0, 2, 0.2)}, false);
    // Separated, planes crossing but the line of intersection outside both.
    expectIntersect(base, {Vec(3, 3, -1), Vec(3, 3, 1), Vec(4, 2, 0)}, false);
    // Touching at a vertex: Q's vertex on P's vertex, Q otherwise above.
    expectIntersect(base, {Vec(2, 0, 0), Vec(3, 0, 1), Vec(2, 1, 1)}, true);
    // Q's vertex touching P's interior from above.
    expectIntersect(base, {Vec(0.5, 0.5, 0), Vec(1, 1, 1), Vec(0, 1, 1)}, true);
    // Edge on edge: crossing edges, Q standing on P's hypotenuse.
    expectIntersect(base, {Vec(1, 1, 0), Vec(1, 1, 2), Vec(2, 2, 1)}, true);
    // Edge/edge crossing in mid-air without either vertex inside: x axis segment vs skew segment.
    expectIntersect({Vec(-1, 0, 0), Vec(1, 0, 0), Vec(0, -1, -1)}, {Vec(0, -1, 0), Vec(0, 1, 0), Vec(1, 0, 1)}, true);
    // The same, lifted by a hair: now disjoint.
    expectIntersect({Vec(-1, 0, 0), Vec(1, 0, 0), Vec(0, -1, -1)}, {Vec(0, -1, 1e-12), Vec(0, 1, 1e-12), Vec(1, 0, 1)},
                    false);
    // Coplanar overlapping, disjoint, contained, sharing an edge, touching at a vertex.
    expectIntersect(base, {Vec(1, 1, 0), Vec(3, 1, 0), Vec(1, 3, 0)}, true);
    expectIntersect(base, {Vec(1.1, 1.1, 0), Vec(3, 1, 0), Vec(1, 3, 0)}, false);
    expectIntersect(base, {Vec(0.2, 0.2, 0), Vec(0.5, 0.2, 0), Vec(0.2, 0.5, 0)}, true);
    expectIntersect(base, {Vec(2, 0, 0), Vec(0, 2, 0), Vec(2, 2, 0)}, true);
    expectIntersect(base, {Vec(2, 0, 0), Vec(3, 0, 0), Vec(3, 1, 0)}, true);
    expectIntersect(base, {Vec(2.5, 0, 0), Vec(3, 0, 0), Vec(3, 1, 0)}, false);
    // Star of David: coplanar, no vertex inside the other, edges crossing.
    expectIntersect({Vec(0, 2, 0), Vec(-1.7, -1, 0), Vec(1.7, -1, 0)}, {Vec(0, -2, 0), Vec(1.7, 1, 0), Vec(-1.7, 1, 0)},
                    true);
    // Degenerate: a segment piercing the base, one lying on it, one beside it; a point on and off.
    expectIntersect(base, {Vec(0.5, 0.5, -1), Vec(0.5, 0.5, 1), Vec(0.5, 0.5, 0.3)}, true);
    expectIntersect(base, {Vec(-1, 0.5, 0), Vec(3, 0.5, 0), Vec(1, 0.5, 0)}, true);
    expectIntersect(base, {Vec(-1, 3, 0), Vec(3, 3, 0), Vec(1, 3, 0)}, false);
    expectIntersect(base, {Vec(1, 1, 0), Vec(1, 1, 0), Vec(1, 1, 0)}, true);
    expectIntersect(base, {Vec(1, 1, 1e-300), Vec(1, 1, 1e-300), Vec(1, 1, 1e-300)}, false);
    // Both degenerate: crossing segments, collinear overlapping, collinear apart, skew.
    expectIntersect({Vec(0, 0, 0), Vec(2, 2, 2), Vec(1, 1, 1)}, {Vec(2, 0, 0), Vec(0, 2, 2), Vec(1, 1, 1)}, true);
    expectIntersect({Vec(0, 0, 0), Vec(2, 2, 2), Vec(0, 0, 0)}, {Vec(1, 1, 1), Vec(3, 3, 3), Vec(3, 3, 3)}, true);
    expectIntersect({Vec(0, 0, 0), Vec(1, 1, 1), Vec(0, 0, 0)}, {Vec(2, 2, 2), Vec(3, 3, 3), Vec(3, 3, 3)}, false);
    expectIntersect({Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 0, 0)}, {Vec(0, 1, 1), Vec(0, -1, 1), Vec(0, 1, 1)}, false);
}

TEST(TrianglesIntersect, IntersectionPointLiesOnBothTriangles)
{
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> coordinate(0.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 20000; ++trial)
    {
        Triangle p, q;
        for (int i = 0; i < 3; ++i)
        {
            p[i] = Vec(coordinate(rng), coordinate(rng), coordinate(rng));
            q[i] = Vec(coordinate(rng), coordinate(rng), coordinate(rng));
        }
        Vec point;
        if (!rc::trianglesIntersect(p[0], p[1], p[2], q[0], q[1], q[2], &point))
            continue;
        ++checked;
        EXPECT_TRUE(onTriangle(point, p, 1e-9));
        EXPECT_TRUE(onTriangle(point, q, 1e-9));
    }
    EXPECT_GT(checked, 1000);
}

TEST(TrianglesIntersect, MatchesExactIntegerSeparatingAxes)
{
    IntegerPairs pairs;
    int counts[2] = {0, 0};
    for (int trial = 0; trial < 60000; ++trial)
    {
        const int kindP = trial % 5, kindQ = (trial / 5) % 5;
        const int range = trial % 3 == 0 ? 2 : 4;
        const std::array<IVec, 3> p = pairs.triangle(kindP, range), q = pairs.triangle(kindQ, range);
        const Triangle fp = {toVec(p[0]), toVec(p[1]), toVec(p[2])}, fq = {toVec(q[0]), toVec(q[1]), toVec(q[2])};
        const bool expected = integerTrianglesIntersect(p, q);
        ++counts[expected];
        ASSERT_EQ(intersect(fp, fq), expected) << "trial " << trial;
        ASSERT_EQ(intersect(fq, {fp[2], fp[0], fp[1]}), expected) << "trial " << trial;
    }
    std::printf("[ info     ] integer pairs: %d intersecting, %d disjoint\n", counts[1], counts[0]);
    EXPECT_GT(counts[0], 10000);
    EXPECT_GT(counts[1], 10000);
}

TEST(TrianglesIntersect, AgreesWithFclOnRandomPairs)
{
    // FCL's test is a floating-point separating-axis test without tolerance: it may differ only
    // where the triangles nearly touch.
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> coordinate(0.0, 1.0);
    int intersecting = 0, disagreements = 0;
    double worstGap = 0.0;
    for (int trial = 0; trial < 100000; ++trial)
    {
        Triangle p, q;
        for (int i = 0; i < 3; ++i)
        {
            p[i] = Vec(coordinate(rng), coordinate(rng), coordinate(rng));
            q[i] = Vec(coordinate(rng), coordinate(rng), coordinate(rng));
        }
        const bool ours = intersect(p, q);
        intersecting += ours;
        ASSERT_EQ(ours, intersect(q, p));
        if (ours != fclIntersect(p, q))
        {
            ++disagreements;
            worstGap = std::max(worstGap, fclDistance(p, q));
        }
    }
    std::printf(
        "[ info     ] 100000 random pairs: %d intersecting, %d disagreements with FCL (largest FCL "
        "distance among them %.3g)\n",
        intersecting, disagreements, worstGap);
    EXPECT_GT(intersecting, 10000);
    EXPECT_LE(disagreements, 10);
    EXPECT_LT(worstGap, 1e-9);
}

TEST(TriangleDistance, MatchesFclOnRandomPairs)
{
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> coordinate(0.0, 1.0);
    std::uniform_real_distribution<double> offset(-0.5, 0.5);
    double worst = 0.0;
    int positive = 0;
    for (int trial = 0; trial < 50000; ++trial)
    {
        Triangle p, q;
        const Vec shift(offset(rng), offset(rng), offset(rng));
        const double scale = trial % 2 ? 1.0 : 0.2;  // small triangles are more often apart
        for (int i = 0; i < 3; ++i)
        {
            p[i] = scale * Vec(coordinate(rng), coordinate(rng), coordinate(rng));
            q[i] = scale * Vec(coordinate(rng), coordinate(rng), coordinate(rng)) + shift;
        }
        Vec x, y;
        const double ours = distance(p, q, &x, &y);
        const double reference = fclDistance(p, q);
        worst = std::max(worst, std::abs(ours - reference));
        ASSERT_NEAR(ours, reference, 1e-9) << "trial " << trial;
        ASSERT_NEAR((x - y).norm(), ours, 1e-12);
        // The witnesses lie on their triangles.
        ASSERT_TRUE(onTriangle(x, p, 1e-12));
        ASSERT_TRUE(onTriangle(y, q, 1e-12));
        positive += ours > 0.0;
        // trianglesWithin agrees with the distance away from the threshold.
        const double threshold = 0.1 * std::abs(offset(rng));
        if (std::abs(ours - threshold) > 1e-12)
        {
            ASSERT_EQ(rc::trianglesWithin(p[0], p[1], p[2], q[0], q[1], q[2], threshold), ours <= threshold);
        }
    }
    std::printf("[ info     ] 50000 random pairs (%d apart): largest |distance - FCL| %.3g\n", positive, worst);
    EXPECT_GT(positive, 10000);
}

TEST(TriangleDistance, MatchesFclOnIntegerPairsWithParallelEdges)
{
    // Integer triangles are full of parallel edges and coplanar faces, the ill-conditioned cases of
    // the edge/edge distance. FCL is only trusted on non-degenerate triangles here.
    IntegerPairs pairs;
    double worst = 0.0;
    int compared = 0;
    for (int trial = 0; trial < 20000; ++trial)
    {
        const int kind = trial % 3;  // general, z = 1 plane, tilted plane
        std::array<IVec, 3> p = pairs.triangle(kind, 3), q = pairs.triangle(kind, 3);
        const Triangle fp = {toVec(p[0]), toVec(p[1]), toVec(p[2])}, fq = {toVec(q[0]), toVec(q[1]), toVec(q[2])};
        if ((fp[1] - fp[0]).cross(fp[2] - fp[0]).norm() == 0.0 || (fq[1] - fq[0]).cross(fq[2] - fq[0]).norm() == 0.0)
            continue;
        const double ours = distance(fp, fq);
        EXPECT_EQ(ours == 0.0, integerTrianglesIntersect(p, q));
        const double reference = fclDistance(fp, fq);
        worst = std::max(worst, std::abs(ours - reference));
        ASSERT_NEAR(ours, reference, 1e-9) << "trial " << trial;
        ++compared;
    }
    std::printf("[ info     ] %d integer pairs: largest |distance - FCL| %.3g\n", compared, worst);
}

TEST(TriangleDistance, IsTheSmallestOfAllFifteenFeatures)
{
    // triangleDistance ends its search at the first edge pair whose closest points the corners show
    // to be the nearest; measured against every edge/edge and corner/face distance, it must still be
    // their smallest, on pairs near each other (where the search ends early), slivers (whose
    // normals carry rounding) and nearly parallel edges, far from the origin too.
    using rc::device::triangles::segmentSegment;
    using rc::device::triangles::vertexFace;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    int apart = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 30000; ++trial)
    {
        const int kind = trial % 3;  // general, sliver, nearly parallel edges
        const Vec origin = trial % 2 ? Vec(1e3, -2e3, 5e2) : Vec::Zero();
        Triangle p, q;
        for (int i = 0; i < 3; ++i)
        {
            p[i] = origin + Vec(coordinate(rng), coordinate(rng), coordinate(rng));
            q[i] = origin + Vec(coordinate(rng), coordinate(rng), coordinate(rng)) + Vec(1.2, 0.0, 0.0);
        }
        if (kind == 1)
            p[2] = p[0] + (0.5 + 1e-7 * coordinate(rng)) * (p[1] - p[0]) + Vec::Constant(1e-9 * coordinate(rng));
        if (kind == 2)
            q[1] = q[0] + (p[1] - p[0]) + Vec::Constant(1e-8 * coordinate(rng));
        Vec x, y;
        const double ours = distance(p, q, &x, &y);
        if (ours == 0.0)
            continue;
        ++apart;
        const rc::device::Vec3<double> dp[3] = {toDevice(p[0]), toDevice(p[1]), toDevice(p[2])};
        const rc::device::Vec3<double> dq[3] = {toDevice(q[0]), toDevice(q[1]), toDevice(q[2])};
        double smallest = HUGE_VAL;
        rc::device::Vec3<double> a, b;
        for (int i = 0; i < 3; ++i)
        {
            for (int j = 0; j < 3; ++j)
                smallest = std::min(smallest, segmentSegment(dp[i], dp[(i + 1) % 3], dq[j], dq[(j + 1) % 3], a, b));
            smallest = std::min(smallest, vertexFace(dp[i], dq[0], dq[1], dq[2], b));
            smallest = std::min(smallest, vertexFace(dq[i], dp[0], dp[1], dp[2], a));
        }
        ASSERT_NEAR(ours, std::sqrt(smallest), 1e-12 * (1.0 + origin.norm())) << "trial " << trial;
        ASSERT_NEAR((x - y).norm(), ours, 1e-9);
        worst = std::max(worst, std::abs(ours - std::sqrt(smallest)) / (1.0 + origin.norm()));
    }
    std::printf("[ info     ] %d pairs apart: largest |distance - smallest feature| %.3g of the coordinates\n", apart,
                worst);
    EXPECT_GT(apart, 10000);
}

TEST(TriangleDistance, HandMadeCases)
{
    const Triangle base = {Vec(0, 0, 0), Vec(2, 0, 0), Vec(0, 2, 0)};
    Vec x, y;
    // Vertex over the face.
    EXPECT_DOUBLE_EQ(distance(base, {Vec(0.5, 0.5, 0.3), Vec(1, 1, 1), Vec(0, 1, 1)}, &x, &y), 0.3);
    EXPECT_TRUE(x.isApprox(Vec(0.5, 0.5, 0)));
    EXPECT_TRUE(y.isApprox(Vec(0.5, 0.5, 0.3)));
    // Parallel edges, offset sideways and up: distance between the lines.
    EXPECT_NEAR(distance(base, {Vec(-1, -0.3, 0.4), Vec(3, -0.3, 0.4), Vec(1, -2, 0.4)}), 0.5, 1e-15);
    // Crossing: zero, with the same point twice.
    EXPECT_EQ(distance(base, {Vec(0.5, 0.5, -1), Vec(0.5, 0.5, 1), Vec(1.5, -1, 0.5)}, &x, &y), 0.0);
    EXPECT_EQ(x, y);
    // Degenerate (a point) beside the hypotenuse.
    EXPECT_NEAR(distance(base, {Vec(2, 2, 0), Vec(2, 2, 0), Vec(2, 2, 0)}), std::sqrt(2.0), 1e-15);
}

TEST(RayTriangle, CrossingsMissesAndGrazes)
{
    const Vec a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    const double tol = 1e-9;
    double t = -1.0;
    EXPECT_EQ(rc::rayTriangle(Vec(0.25, 0.25, -2), Vec(0, 0, 2), a, b, c, tol, t), 1);
    EXPECT_DOUBLE_EQ(t, 1.0);  // direction need not be unit: t is in its units
    EXPECT_EQ(rc::rayTriangle(Vec(0.25, 0.25, 2), Vec(0, 0, -1), a, b, c, tol, t), 1);
    EXPECT_EQ(rc::rayTriangle(Vec(0.25, 0.25, 2), Vec(0, 0, 1), a, b, c, tol, t), 0);    // behind
    EXPECT_EQ(rc::rayTriangle(Vec(0.8, 0.8, -1), Vec(0, 0, 1), a, b, c, tol, t), 0);     // past the hypotenuse
    EXPECT_EQ(rc::rayTriangle(Vec(0.5, 0.5, -1), Vec(0, 0, 1), a, b, c, tol, t), -1);    // on the hypotenuse
    EXPECT_EQ(rc::rayTriangle(Vec(0, 0, -1), Vec(0, 0, 1), a, b, c, tol, t), -1);        // through a vertex
    EXPECT_EQ(rc::rayTriangle(Vec(0.3, 1e-10, -1), Vec(0, 0, 1), a, b, c, tol, t), -1);  // within tolerance
    EXPECT_EQ(rc::rayTriangle(Vec(0.3, 1e-8, -1), Vec(0, 0, 1), a, b, c, tol, t), 1);    // just beyond it
    EXPECT_EQ(rc::rayTriangle(Vec(-1, 0.3, 0), Vec(1, 0, 0), a, b, c, tol, t), -1);      // in the plane
    EXPECT_EQ(rc::rayTriangle(Vec(-1, 0.3, 1), Vec(1, 0, 0), a, b, c, tol, t), 0);       // parallel above
    EXPECT_EQ(rc::rayTriangle(Vec(0.2, 0.2, 0), Vec(0, 0, 1), a, b, c, tol, t), -1);     // starts on it
    EXPECT_EQ(rc::rayTriangle(Vec(0.2, 0.2, -1), Vec(0, 0, 1), a, a, c, tol, t), 0);     // zero area
}
