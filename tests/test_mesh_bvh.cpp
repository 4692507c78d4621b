// The exact oracle over whole meshes: BVH structure, surfacesWithin against brute force and FCL,
// point-in-solid parity (grazing rays included) and containment in solidsOverlap.
#include <cmath>
#include <cstring>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <thread>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/Stages.h"
#include "rastercheck/device/Traversal.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Obb.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/geometry/TriangleTests.h"
#include "rastercheck/model/Kinematics.h"
#include "NonConvex.h"

namespace rc = rastercheck;
using Vec = Eigen::Vector3d;

namespace
{
// ---- test meshes, closed and outward-oriented (checked by cleanMesh below) -----------------

class MeshBuilder
{
public:
    std::uint32_t vertex(const Vec &p)
    {
        const auto key = std::make_tuple(p.x(), p.y(), p.z());
        const auto found = index_.find(key);
        if (found != index_.end())
            return found->second;
        mesh.vertices.push_back(p);
        return index_[key] = static_cast<std::uint32_t>(mesh.vertices.size() - 1);
    }
    void triangle(const Vec &a, const Vec &b, const Vec &c)
    {
        mesh.triangles.push_back({vertex(a), vertex(b), vertex(c)});
    }

    rc::Mesh mesh;

private:
    std::map<std::tuple<double, double, double>, std::uint32_t> index_;
};

// A box of half extents \a half centred at the origin, each face split into divisions^2 squares.
// Grid coordinates come from one table per axis, so faces that share an edge share its vertices
// bit for bit and the mesh is closed without welding.
rc::Mesh boxMesh(const Vec &half, int divisions = 1)
{
    std::vector<double> grid[3];
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i <= divisions; ++i)
            grid[k].push_back(i == divisions ? half[k] : -half[k] + 2.0 * half[k] * i / divisions);
    MeshBuilder builder;
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {0, divisions})
        {
            const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            const auto corner = [&](int i, int j)
            {
                Vec p;
                p[axis] = grid[axis][side];
                p[a1] = grid[a1][i];
                p[a2] = grid[a2][j];
                return p;
            };
            // e_a1 x e_a2 = e_axis: counter-clockwise in (a1, a2) faces +axis, so flip the low side.
            for (int i = 0; i < divisions; ++i)
                for (int j = 0; j < divisions; ++j)
                {
                    const Vec c00 = corner(i, j), c10 = corner(i + 1, j), c11 = corner(i + 1, j + 1),
                              c01 = corner(i, j + 1);
                    if (side > 0)
                    {
                        builder.triangle(c00, c10, c11);
                        builder.triangle(c00, c11, c01);
                    }
                    else
                    {
                        builder.triangle(c00, c11, c10);
                        builder.triangle(c00, c01, c11);
                    }
                }
        }
    return builder.mesh;
}

// An icosphere of 20 * 4^subdivisions triangles with vertices on the sphere of \a radius.
rc::Mesh sphereMesh(double radius, int subdivisions)
{
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec> vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (Vec &v : vertices)
        v.normalize();
    for (int level = 0; level < subdivisions; ++level)
    {
        std::map<std::pair<int, int>, int> midpoints;
        const auto midpoint = [&](int i, int j)
        {
            const auto key = std::minmax(i, j);
            const auto found = midpoints.find(key);
            if (found != midpoints.end())
                return found->second;
            vertices.push_back((vertices[i] + vertices[j]).normalized());
            return midpoints[key] = static_cast<int>(vertices.size() - 1);
        };
        std::vector<std::array<int, 3>> finer;
        for (const auto &f : faces)
        {
            const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
            finer.push_back({f[0], a, c});
            finer.push_back({f[1], b, a});
            finer.push_back({f[2], c, b});
            finer.push_back({a, b, c});
        }
        faces = finer;
    }
    rc::Mesh mesh;
    for (const Vec &v : vertices)
        mesh.vertices.push_back(radius * v);
    for (const auto &f : faces)
        mesh.triangles.push_back({std::uint32_t(f[0]), std::uint32_t(f[1]), std::uint32_t(f[2])});
    return mesh;
}

void expectClosedOutward(rc::Mesh mesh)
{
    const rc::MeshTopology topology = rc::cleanMesh(mesh);
    EXPECT_TRUE(topology.closed) << topology.summary();
    EXPECT_GT(rc::signedVolume(mesh), 0.0);
}

Eigen::Isometry3d randomPose(std::mt19937_64 &rng, double reach)
{
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> uniform(-reach, reach);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
    pose.translation() = Vec(uniform(rng), uniform(rng), uniform(rng));
    return pose;
}

// ---- references ----------------------------------------------------------------------------

// All triangle pairs, with B's triangles moved into A's frame exactly as surfacesWithin does.
bool bruteForceWithin(const rc::Mesh &a, const Eigen::Isometry3d &poseA, const rc::Mesh &b,
                      const Eigen::Isometry3d &poseB, double padding)
{
    const Eigen::Isometry3d aMb = poseA.inverse(Eigen::Isometry) * poseB;
    const Eigen::Matrix3d R = aMb.linear();
    const Vec T = aMb.translation();
    for (const rc::Mesh::Triangle &tb : b.triangles)
    {
        const Vec q0 = R * b.vertices[tb[0]] + T, q1 = R * b.vertices[tb[1]] + T, q2 = R * b.vertices[tb[2]] + T;
        for (const rc::Mesh::Triangle &ta : a.triangles)
        {
            const Vec &p0 = a.vertices[ta[0]], &p1 = a.vertices[ta[1]], &p2 = a.vertices[ta[2]];
            if (padding > 0.0 ? rc::trianglesWithin(p0, p1, p2, q0, q1, q2, padding)
                              : rc::trianglesIntersect(p0, p1, p2, q0, q1, q2))
                return true;
        }
    }
    return false;
}

double bruteForceDistance(const rc::Mesh &a, const Eigen::Isometry3d &poseA, const rc::Mesh &b,
                          const Eigen::Isometry3d &poseB)
{
    double best = std::numeric_limits<double>::infinity();
    for (const rc::Mesh::Triangle &tb : b.triangles)
        for (const rc::Mesh::Triangle &ta : a.triangles)
            best = std::min(best, rc::triangleDistance(poseA * a.vertices[ta[0]], poseA * a.vertices[ta[1]],
                                                       poseA * a.vertices[ta[2]], poseB * b.vertices[tb[0]],
                                                       poseB * b.vertices[tb[1]], poseB * b.vertices[tb[2]]));
    return best;
}

std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> fclModel(const rc::Mesh &mesh)
{
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    std::vector<fcl::Triangle> triangles;
    for (const rc::Mesh::Triangle &t : mesh.triangles)
        triangles.emplace_back(t[0], t[1], t[2]);
    model->beginModel();
    model->addSubModel(mesh.vertices, triangles);
    model->endModel();
    return model;
}

// Independent inside test: the generalised winding number (1 inside, 0 outside).
double windingNumber(const rc::Mesh &mesh, const Vec &point)
{
    double total = 0.0;
    for (const rc::Mesh::Triangle &t : mesh.triangles)
    {
        const Vec a = mesh.vertices[t[0]] - point, b = mesh.vertices[t[1]] - point, c = mesh.vertices[t[2]] - point;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        total += 2.0 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la);
    }
    return total / (4.0 * M_PI);
}

struct Scenario
{
    const char *name;
    rc::Mesh a, b;
    double reach;  // translations drawn from [-reach, reach]^3
};

std::vector<Scenario> scenarios()
{
    return {{"sphere320/box48", sphereMesh(1.0, 2), boxMesh(Vec(0.6, 0.3, 0.2), 2), 1.0},
            {"sphere80/sphere320", sphereMesh(0.7, 1), sphereMesh(1.0, 2), 1.2},
            {"box12/box108", boxMesh(Vec(0.5, 0.5, 0.5)), boxMesh(Vec(1.0, 0.2, 0.4), 3), 1.0}};
}
}  // namespace

TEST(MeshBvh, TestMeshesAreClosedAndOutward)
{
    expectClosedOutward(boxMesh(Vec(1, 2, 3)));
    expectClosedOutward(boxMesh(Vec(1, 2, 3), 4));
    expectClosedOutward(sphereMesh(1.0, 0));
    expectClosedOutward(sphereMesh(2.0, 3));
}

TEST(MeshBvh, TreeCoversEveryTriangleOnceAndBoxesNest)
{
    for (unsigned leafSize : {1u, 4u, 7u})
    {
        const rc::Mesh mesh = sphereMesh(1.0, 3);  // 1280 triangles
        const rc::MeshBvh bvh(mesh, leafSize);
        std::vector<int> seen(mesh.numTriangles(), 0);
        std::vector<int> parent(bvh.numNodes(), -1);
        for (std::size_t i = 0; i < bvh.numNodes(); ++i)
            if (!bvh.nodes()[i].isLeaf())
                parent[bvh.nodes()[i].first] = parent[bvh.nodes()[i].first + 1] = static_cast<int>(i);
        for (std::size_t i = 0; i < bvh.numNodes(); ++i)
        {
            const rc::MeshBvh::Node &node = bvh.nodes()[i];
            if (!node.isLeaf())
            {
                ASSERT_EQ(node.count, 0u);
                for (int child : {node.first, node.first + 1})
                {
                    ASSERT_GT(child, static_cast<int>(i));
                    ASSERT_LT(child, static_cast<int>(bvh.numNodes()));
                }
                continue;
            }
            ASSERT_GE(node.count, 1u);
            ASSERT_LE(node.count, leafSize);
            for (std::uint32_t slot = node.firstSlot(); slot < node.firstSlot() + node.count; ++slot)
            {
                const std::uint32_t triangle = bvh.triangleOrder()[slot];
                ++seen[triangle];
                for (int k = 0; k < 3; ++k)
                {
                    const Vec &corner = mesh.vertices[mesh.triangles[triangle][k]];
                    EXPECT_EQ(Vec(Eigen::Map<const Vec>(bvh.slotCorners(slot) + 3 * k)), corner);
                    // Every node on the way down holds the corner (up to the float storage's
                    // rounding, 1e-6 of the size, which the queries' slack covers).
                    for (int up = static_cast<int>(i); up >= 0; up = parent[up])
                    {
                        const rc::MeshBvh::Node &holder = bvh.nodes()[up];
                        EXPECT_TRUE(rc::nodeContains(holder, corner, 1e-6)) << "node " << up;
                        EXPECT_LE((corner - rc::nodeCentre(holder)).norm(), holder.radius + 1e-6);
                    }
                }
            }
        }
        for (int count : seen)
            ASSERT_EQ(count, 1);
        // A subtree's leaves hold consecutive slots, its first child's first (subtreeSlots, which
        // the image walk reads a subtree's triangles by), and the root's are all of them.
        const rc::device::TreeView view = bvh.view();
        std::uint32_t begin = 1, end = 0;
        rc::device::subtreeSlots(view.nodes, view.nodes[0], begin, end);
        EXPECT_EQ(begin, 0u);
        EXPECT_EQ(end, mesh.numTriangles());
        for (std::size_t i = 0; i < bvh.numNodes(); ++i)
        {
            const rc::device::TreeNode &node = view.nodes[i];
            if (node.isLeaf())
                continue;
            std::uint32_t firstBegin, firstEnd, secondBegin, secondEnd;
            rc::device::subtreeSlots(view.nodes, node, begin, end);
            rc::device::subtreeSlots(view.nodes, view.nodes[node.first], firstBegin, firstEnd);
            rc::device::subtreeSlots(view.nodes, view.nodes[node.first + 1], secondBegin, secondEnd);
            ASSERT_EQ(firstBegin, begin) << "node " << i;
            ASSERT_EQ(firstEnd, secondBegin) << "node " << i;
            ASSERT_EQ(secondEnd, end) << "node " << i;
        }
        // The surface area heuristic's splits stay near balanced on an even mesh.
        EXPECT_LE(bvh.depth(), 2 * static_cast<int>(std::ceil(std::log2(double(mesh.numTriangles()) / leafSize))));
    }
}

// A cube's corners have an isotropic covariance, so its principal axes are whatever the eigen solver
// returns (the mesh's axes here, 1.4x to 1.8x too wide for this turned cube); the least-area fit about
// its faces' normals finds the cube itself. Turned about two axes so that neither the mesh's axes
// nor the covariance's give it.
TEST(MeshBvh, BoxesFitATurnedCubeExactly)
{
    const Eigen::Matrix3d turn =
        (Eigen::AngleAxisd(0.4, Vec::UnitZ()) * Eigen::AngleAxisd(0.7, Vec::UnitX())).toRotationMatrix();
    for (int divisions : {1, 3})
    {
        rc::Mesh mesh = boxMesh(Vec(1.0, 1.0, 1.0), divisions);
        for (Vec &v : mesh.vertices)
            v = turn * v + Vec(5.0, -2.0, 1.0);
        const rc::MeshBvh bvh(mesh);  // one triangle per leaf
        const rc::MeshBvh::Node &root = bvh.nodes()[0];
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(root.halfExtents[k], 1.0, 1e-5) << divisions << " divisions, axis " << k;
        // Every leaf's box is flat: its thinnest extent is the float rounding's.
        for (std::size_t i = 0; i < bvh.numNodes(); ++i)
        {
            const rc::MeshBvh::Node &node = bvh.nodes()[i];
            if (node.isLeaf())
            {
                EXPECT_LT(std::min({node.halfExtents[0], node.halfExtents[1], node.halfExtents[2]}), 1e-5)
                    << "leaf " << i;
            }
        }
    }
}

// The robot's and the scene's oriented boxes (the culls') are fitted the same way: a turned cube's
// box is the cube, right-handed.
TEST(Obb, FitsATurnedCubeExactly)
{
    const Eigen::Matrix3d turn =
        (Eigen::AngleAxisd(0.4, Vec::UnitZ()) * Eigen::AngleAxisd(0.7, Vec::UnitX())).toRotationMatrix();
    rc::Mesh mesh = boxMesh(Vec(1.0, 1.0, 1.0), 2);  // its covariance is isotropic: any axes are principal
    for (Vec &v : mesh.vertices)
        v = turn * v + Vec(5.0, -2.0, 1.0);
    const rc::Obb box = rc::Obb::fit(mesh);
    EXPECT_NEAR(box.volume(), 8.0, 1e-9);
    EXPECT_NEAR(box.axes.determinant(), 1.0, 1e-12);
    EXPECT_LT((box.center - Vec(5.0, -2.0, 1.0)).norm(), 1e-9);
    for (const Vec &v : mesh.vertices)  // and it holds every vertex
        EXPECT_TRUE(((box.axes.transpose() * (v - box.center)).cwiseAbs() - box.halfExtents).maxCoeff() < 1e-9);
}

TEST(MeshBvh, DepthStaysBoundedWhenEverySplitPeelsOneTriangle)
{
    // Triangles at x = 2^-(i/40): equal bins of the centroids put all but the largest in the first bin,
    // so each heuristic split peels one triangle off. The median below level 24 bounds the depth.
    rc::Mesh mesh;
    const int n = 4000;
    for (int i = 0; i < n; ++i)
    {
        const double x = std::ldexp(1.0, -i / 40), size = 1e-3 * x;
        const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back(Vec(x, 0.01 * (i % 4), 0));
        mesh.vertices.push_back(Vec(x + size, 0.01 * (i % 4), 0));
        mesh.vertices.push_back(Vec(x, 0.01 * (i % 4) + size, size));
        mesh.triangles.push_back({first, first + 1, first + 2});
    }
    const rc::MeshBvh bvh(mesh);
    EXPECT_GT(bvh.depth(), 20);  // the peeling happened
    EXPECT_LE(bvh.depth(), 24 + static_cast<int>(std::ceil(std::log2(double(n)))) + 1);
    EXPECT_LE(bvh.depth(), rc::MeshBvh::kMaxDepth);
    // Queries walk it with their fixed stacks: a copy in place touches, one moved away does not.
    EXPECT_TRUE(rc::surfacesWithin(bvh, Eigen::Isometry3d::Identity(), bvh, Eigen::Isometry3d::Identity(), 0.0));
    Eigen::Isometry3d away = Eigen::Isometry3d::Identity();
    away.translation() = Vec(0, 0, 1.0);
    EXPECT_FALSE(rc::surfacesWithin(bvh, Eigen::Isometry3d::Identity(), bvh, away, 0.0));
}

TEST(MeshBvh, TheNodeCullKeepsEveryTriangleAScanOfTheImageKeeps)
{
    // The batched stages pick a pair's triangles by walking the tree (device::forEachTriangleNearImage)
    // instead of testing every triangle (triangleMeetsImage): the walk must keep every triangle the
    // scan keeps, for components (vertices placed by a float pose) and for objects (vertices stored
    // relative to a far origin), read a small part of the mesh when the image is small, and give
    // the triangles of a walk that tests every node, in its order.
    const rc::Mesh meshes[] = {rc::test::mazeOnSlab(0.1), sphereMesh(1.0, 5)};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const rc::Mesh &mesh : meshes)
    {
        const rc::MeshBvh bvh(mesh);
        const rc::Aabb bounds = mesh.bounds();
        const Vec size = bounds.max - bounds.min;
        std::size_t kept = 0, walked = 0, windows = 0, walkedSmall = 0, smallWindows = 0, insideNodes = 0,
                    splitWalks = 0;
        for (int trial = 0; trial < 400; ++trial)
        {
            // Half the trials place the mesh as a component, half as an object far from its origin.
            const bool component = trial % 2 == 0;
            Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
            Vec origin = Vec::Zero();
            if (component)
            {
                pose.linear() =
                    Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
                pose.translation() = Vec(unit(rng), unit(rng), unit(rng)) * 3.0;
            }
            else
                origin = Vec(unit(rng), unit(rng), unit(rng)) * 1e5;
            rc::device::Pose<float> placement = rc::device::Pose<float>::identity();
            for (int r = 0; r < 3; ++r)
            {
                for (int c = 0; c < 3; ++c)
                    placement.m[4 * r + c] = static_cast<float>(pose.linear()(r, c));
                placement.m[4 * r + 3] = static_cast<float>(component ? pose.translation()[r] : -origin[r]);
            }
            std::vector<rc::device::Vec3<float>> placed(mesh.vertices.size());
            for (std::size_t v = 0; v < placed.size(); ++v)
            {
                const Vec &p = mesh.vertices[v];
                if (component)
                    placed[v] = rc::device::transformPoint(
                        placement, rc::device::Vec3<float>{float(p.x()), float(p.y()), float(p.z())});
                else  // as CollisionModel stores object vertices: rounded after the shift
                    placed[v] = {float(p.x() - origin.x()), float(p.y() - origin.y()), float(p.z() - origin.z())};
            }
            // A window somewhere over the placed mesh, from a tenth of its size to all of it.
            const Vec centre =
                pose * (bounds.min + 0.5 * (size + size.cwiseProduct(Vec(unit(rng), unit(rng), unit(rng))))) - origin;
            const double side = size.norm() * (trial % 3 == 0 ? 1.0 : 0.1);
            rc::device::Box window;
            for (int k = 0; k < 3; ++k)
            {
                window.min[k] = static_cast<float>(centre[k] - 0.5 * side);
                window.max[k] = static_cast<float>(centre[k] + 0.5 * side);
            }
            const rc::device::RasterGrid grid = rc::device::makeGrid(window, static_cast<float>(side / 64), 256);
            const float margin = rc::device::pairMargin(window, grid, 0.0f);
            std::vector<char> fromTree(mesh.triangles.size(), 0);
            std::size_t treeCount = 0;
            std::vector<std::uint32_t> order;
            rc::device::forEachTriangleNearImage(bvh.view(), placement, grid, margin,
                                                 [&](std::uint32_t t)
                                                 {
                                                     ASSERT_LT(t, mesh.triangles.size());
                                                     EXPECT_EQ(fromTree[t], 0) << "triangle " << t << " visited twice";
                                                     fromTree[t] = 1;
                                                     ++treeCount;
                                                     order.push_back(t);
                                                 });
            // The walk takes a subtree well inside the image at once: the triangles and order of
            // testing every node.
            std::vector<std::uint32_t> everyNode;
            rc::device::walkTree(
                bvh.view().nodes, bvh.view().numNodes,
                [&](const rc::device::TreeNode &node)
                {
                    const rc::device::ImageSide side = rc::device::nodeAgainstImage(node, placement, grid, margin);
                    insideNodes += side == rc::device::ImageSide::Inside && !node.isLeaf();
                    return side != rc::device::ImageSide::Outside;
                },
                [&](const rc::device::TreeNode &leaf)
                {
                    for (std::uint32_t slot = leaf.firstSlot(); slot < leaf.firstSlot() + leaf.count; ++slot)
                        everyNode.push_back(bvh.view().triangleOrder[slot]);
                    return true;
                });
            ASSERT_EQ(order, everyNode) << "trial " << trial;
            // Split into 2^depth parts (each finds its start on its own), one after the other: the
            // same triangles in the same order, spread over the parts.
            for (std::uint32_t depth = 1; depth <= 4; ++depth)
            {
                std::vector<std::uint32_t> parts;
                int nonEmpty = 0;
                for (std::uint32_t part = 0; part < (1u << depth); ++part)
                {
                    const std::size_t before = parts.size();
                    rc::device::forEachTriangleNearImage(
                        bvh.view(), placement, grid, margin, [&](std::uint32_t t) { parts.push_back(t); }, part, depth);
                    nonEmpty += parts.size() > before;
                }
                ASSERT_EQ(parts, order) << "trial " << trial << ", " << (1u << depth) << " parts";
                splitWalks += depth == 2 && nonEmpty >= 2;
            }
            for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
            {
                const rc::Mesh::Triangle &tri = mesh.triangles[t];
                if (rc::device::triangleMeetsImage(placed[tri[0]], placed[tri[1]], placed[tri[2]], grid, margin))
                {
                    ++kept;
                    ASSERT_TRUE(fromTree[t])
                        << "trial " << trial << ": triangle " << t << " meets the image but the walk skipped it";
                }
            }
            walked += treeCount;
            ++windows;
            if (trial % 3 != 0)
            {
                walkedSmall += treeCount;
                ++smallWindows;
            }
        }
        // The walk reads about what the scan keeps, not the whole mesh.
        EXPECT_LT(walked, 2 * kept + windows * 16) << mesh.triangles.size() << " triangles";
        EXPECT_GT(insideNodes, windows) << "no subtree was taken at once";
        EXPECT_GT(splitWalks, 300u) << "walks in four parts must spread over at least two of them";
        EXPECT_LT(walkedSmall, smallWindows * mesh.triangles.size() / 4);
    }
}

TEST(MeshBvh, EmptyMeshesNeverTouch)
{
    const rc::Mesh empty, box = boxMesh(Vec(1, 1, 1));
    const rc::MeshBvh emptyBvh(empty), boxBvh(box);
    EXPECT_TRUE(emptyBvh.empty());
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    EXPECT_FALSE(rc::surfacesWithin(emptyBvh, identity, boxBvh, identity, 1.0));
    EXPECT_FALSE(rc::solidsOverlap(boxBvh, identity, true, emptyBvh, identity, true, 0.0));
    EXPECT_FALSE(rc::pointInsideClosedMesh(emptyBvh, Vec::Zero()));
}

TEST(MeshBvh, AVertexNotFiniteIsRefusedByName)
{
    rc::Mesh mesh = boxMesh(Vec(1, 1, 1));
    mesh.vertices[3].y() = std::numeric_limits<double>::quiet_NaN();
    try
    {
        const rc::MeshBvh bvh(mesh);
        FAIL() << "a NaN vertex was accepted";
    }
    catch (const rc::ConfigurationError &error)
    {
        EXPECT_NE(std::string(error.what()).find("has vertex 3 at a coordinate that is not finite"), std::string::npos)
            << error.what();
    }
}

TEST(SurfacesWithin, MatchesBruteForceOverAllTrianglePairs)
{
    std::mt19937_64 rng(21);
    for (const Scenario &s : scenarios())
    {
        const rc::MeshBvh a(s.a), b(s.b);
        int hits[2] = {0, 0};
        for (int trial = 0; trial < 120; ++trial)
        {
            const Eigen::Isometry3d poseA = randomPose(rng, s.reach), poseB = randomPose(rng, s.reach);
            for (int p = 0; p < 2; ++p)
            {
                const double padding = p == 0 ? 0.0 : 0.05;
                rc::MeshContact contact;
                const bool ours = rc::surfacesWithin(a, poseA, b, poseB, padding, &contact);
                ASSERT_EQ(ours, bruteForceWithin(s.a, poseA, s.b, poseB, padding))
                    << s.name << " trial " << trial << " padding " << padding;
                ASSERT_EQ(rc::surfacesWithin(b, poseB, a, poseA, padding), ours) << s.name << " swapped";
                if (!ours)
                    continue;
                ++hits[p];
                // The reported triangles are within the padding of each other and of the point.
                ASSERT_GE(contact.triangleA, 0);
                ASSERT_GE(contact.triangleB, 0);
                const rc::Mesh::Triangle &ta = s.a.triangles[contact.triangleA], &tb = s.b.triangles[contact.triangleB];
                const Vec p0 = poseA * s.a.vertices[ta[0]], p1 = poseA * s.a.vertices[ta[1]],
                          p2 = poseA * s.a.vertices[ta[2]];
                const Vec q0 = poseB * s.b.vertices[tb[0]], q1 = poseB * s.b.vertices[tb[1]],
                          q2 = poseB * s.b.vertices[tb[2]];
                EXPECT_LE(rc::triangleDistance(p0, p1, p2, q0, q1, q2), padding + 1e-12);
                const Vec &x = contact.position;
                EXPECT_LE(rc::triangleDistance(p0, p1, p2, x, x, x), padding + 1e-9);
                EXPECT_LE(rc::triangleDistance(q0, q1, q2, x, x, x), padding + 1e-9);
            }
        }
        std::printf("[ info     ] %s: %d of 120 poses touch, %d within 0.05\n", s.name, hits[0], hits[1]);
        EXPECT_GT(hits[0], 20);
        EXPECT_LT(hits[0], 100);
    }
}

TEST(SurfacesWithin, AWalkSplitIntoPartsFindsTheWholeWalksFirstContact)
{
    // The stages share one pair's walk among threads (WalkPart, walkPartStart): walked one after the
    // other, the parts must decide as the whole walk does, and the first part that finds a contact
    // must find the whole walk's first contact (the CPU backend's), whatever the number of parts;
    // a part stops for an earlier part's contact, and for a later one's only where any contact
    // decides.
    std::mt19937_64 rng(5);
    for (const Scenario &s : scenarios())
    {
        const rc::MeshBvh a(s.a), b(s.b);
        const rc::device::ExactTree ta = a.exactTree(), tb = b.exactTree();
        int split = 0, touching = 0, stoppedByAnEarlierPart = 0, stoppedByALaterPart = 0;
        for (int trial = 0; trial < 60; ++trial)
        {
            const rc::device::Pose<double> poseA = rc::toDevicePose(randomPose(rng, s.reach)),
                                           poseB = rc::toDevicePose(randomPose(rng, s.reach));
            for (double padding : {0.0, 0.05})
            {
                rc::device::ExactContact whole;
                const bool meet = rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, &whole);
                touching += meet;
                for (std::uint32_t depth : {1u, 2u, 3u, 5u, rc::device::walkPartDepth(rc::device::kMaxWalkParts)})
                {
                    const std::uint32_t numParts = 1u << depth;
                    bool found = false;
                    int meeting = 0;  // parts whose walk alone finds a contact
                    for (std::uint32_t j = 0; j < numParts; ++j)
                    {
                        rc::device::ExactContact contact;
                        const bool partFinds = rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, &contact,
                                                                          nullptr, rc::device::WalkPart{j, depth});
                        meeting += partFinds;
                        if (partFinds && found)
                        {
                            // A part stops once an earlier part has found a contact (its own cannot
                            // be the walk's first), and not for a later one's.
                            const unsigned long long earlier = j - 1, itself = j;
                            EXPECT_FALSE(rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, nullptr, nullptr,
                                                                    rc::device::WalkPart{j, depth, &earlier}))
                                << s.name << " trial " << trial;
                            EXPECT_TRUE(rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, nullptr, nullptr,
                                                                   rc::device::WalkPart{j, depth, &itself}))
                                << s.name << " trial " << trial;
                            ++stoppedByAnEarlierPart;
                        }
                        if (partFinds && j + 1 < numParts)
                        {
                            // A later part's contact stops it only where any contact decides
                            // (WalkPart::anyContact: no contact is read).
                            const unsigned long long later = j + 1;
                            rc::device::WalkPart anyContact{j, depth, &later};
                            anyContact.anyContact = true;
                            EXPECT_TRUE(rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, nullptr, nullptr,
                                                                   rc::device::WalkPart{j, depth, &later}))
                                << s.name << " trial " << trial;
                            EXPECT_FALSE(
                                rc::device::surfacesWithin(ta, poseA, tb, poseB, padding, nullptr, nullptr, anyContact))
                                << s.name << " trial " << trial;
                            ++stoppedByALaterPart;
                        }
                        if (partFinds && !found)
                        {
                            EXPECT_EQ(contact.triangleA, whole.triangleA) << s.name << " trial " << trial;
                            EXPECT_EQ(contact.triangleB, whole.triangleB) << s.name << " trial " << trial;
                            EXPECT_EQ(contact.position.x, whole.position.x) << s.name << " trial " << trial;
                            EXPECT_EQ(contact.position.z, whole.position.z) << s.name << " trial " << trial;
                        }
                        found = found || partFinds;
                    }
                    split += meeting > 1;
                    ASSERT_EQ(found, meet) << s.name << " trial " << trial << ", " << numParts << " parts";
                }
            }
        }
        EXPECT_GT(split, 0) << s.name << ": no walk's contacts were ever in two parts";
        EXPECT_GT(touching, 0) << s.name;
        EXPECT_GT(stoppedByAnEarlierPart, 0) << s.name << ": no contact was found past the first part";
        EXPECT_GT(stoppedByALaterPart, 0) << s.name << ": no contact was found before the last part";
    }
}

TEST(SurfacesWithin, LeafHintsBetweenNearbyPosesNeverChangeAVerdict)
{
    // Each thread remembers, per pair of trees, the leaf pair where its last query touched or came
    // nearest, and tests it first next time. Walk poses through contact and back in small steps
    // (what a motion validator asks), from several threads at once, each from its own starting
    // point: every verdict must be the brute force's.
    const Scenario s = scenarios()[0];
    const rc::MeshBvh a(s.a), b(s.b);
    std::mt19937_64 rng(31);
    std::vector<Eigen::Isometry3d> poses;
    for (int walk = 0; walk < 12; ++walk)
    {
        const Eigen::Isometry3d start = randomPose(rng, 3.0 * s.reach), through = randomPose(rng, 0.3 * s.reach);
        const Eigen::Quaterniond q0(start.linear()), q1(through.linear());
        for (int step = 0; step <= 60; ++step)
        {
            const double t = step / 60.0;
            Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
            pose.linear() = q0.slerp(t, q1).toRotationMatrix();
            pose.translation() = (1 - t) * start.translation() + t * through.translation();
            poses.push_back(pose);
        }
    }
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    std::vector<std::array<bool, 2>> expected(poses.size());
    int touching = 0;
    for (std::size_t i = 0; i < poses.size(); ++i)
    {
        for (int p = 0; p < 2; ++p)
            expected[i][p] = bruteForceWithin(s.a, poses[i], s.b, identity, p == 0 ? 0.0 : 0.05);
        touching += expected[i][0];
    }
    ASSERT_GT(touching, 100);
    ASSERT_LT(touching, static_cast<int>(poses.size()) - 100);
    std::vector<int> mismatches(4, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back(
            [&, t]
            {
                for (int round = 0; round < 3; ++round)
                    for (std::size_t k = 0; k < poses.size(); ++k)
                    {
                        // Forward from an offset, or backward: each thread's hints differ.
                        const std::size_t i = t % 2 == 0 ? (k + 97 * t) % poses.size() : poses.size() - 1 - k;
                        for (int p = 0; p < 2; ++p)
                        {
                            const double padding = p == 0 ? 0.0 : 0.05;
                            mismatches[t] += rc::surfacesWithin(a, poses[i], b, identity, padding) != expected[i][p];
                            mismatches[t] += rc::surfacesWithin(b, identity, a, poses[i], padding) != expected[i][p];
                        }
                    }
            });
    for (std::thread &thread : threads)
        thread.join();
    for (int t = 0; t < 4; ++t)
        EXPECT_EQ(mismatches[t], 0) << "thread " << t;
}

TEST(SurfacesWithin, AgreesWithFclCollideAndDistance)
{
    // FCL works in floating point with its own tolerances, so the two may differ where the meshes
    // (nearly) touch: such cases are counted, and any disagreement farther than 1e-9 from touching
    // fails. Distances within 1e-9 of the padding are likewise counted, not compared.
    std::mt19937_64 rng(33);
    const double padding = 0.05, band = 1e-9;
    for (const Scenario &s : scenarios())
    {
        const rc::MeshBvh a(s.a), b(s.b);
        const auto modelA = fclModel(s.a), modelB = fclModel(s.b);
        int collideDisagree = 0, distanceDisagree = 0, inBand = 0, colliding = 0;
        for (int trial = 0; trial < 1000; ++trial)
        {
            const Eigen::Isometry3d poseA = randomPose(rng, s.reach), poseB = randomPose(rng, s.reach);
            const fcl::CollisionObjectd objectA(modelA, poseA), objectB(modelB, poseB);

            fcl::CollisionRequestd request;
            fcl::CollisionResultd result;
            fcl::collide(&objectA, &objectB, request, result);
            const bool touching = rc::surfacesWithin(a, poseA, b, poseB, 0.0);
            colliding += touching;
            if (touching != result.isCollision())
            {
                ++collideDisagree;
                const double gap = bruteForceDistance(s.a, poseA, s.b, poseB);
                EXPECT_LT(gap, band) << s.name << " trial " << trial << ": ours " << touching << ", FCL "
                                     << result.isCollision();
            }

            fcl::DistanceRequestd distanceRequest;
            fcl::DistanceResultd distanceResult;
            fcl::distance(&objectA, &objectB, distanceRequest, distanceResult);
            const double d = std::max(0.0, distanceResult.min_distance);
            if (std::abs(d - padding) < band)
            {
                ++inBand;
                continue;
            }
            if (rc::surfacesWithin(a, poseA, b, poseB, padding) != (d <= padding))
            {
                ++distanceDisagree;
                ADD_FAILURE() << s.name << " trial " << trial << ": FCL distance " << d;
            }
        }
        std::printf(
            "[ info     ] %s: 1000 poses, %d touching; disagreements with fcl::collide %d, with "
            "fcl::distance at padding %.2f %d (%d in the +-%.0e band)\n",
            s.name, colliding, collideDisagree, padding, distanceDisagree, inBand, band);
    }
}

TEST(SurfacesWithin, ExactContactsAreTouching)
{
    // Boxes stacked face on face, turned about the vertical and slid sideways: the rigid transform
    // keeps the contact plane exact, so the oracle must call every one touching, and a gap of a
    // picometre apart. FCL decides these in floating point; its answers are counted, not asserted.
    const rc::Mesh lower = boxMesh(Vec(0.5, 0.5, 0.5), 2), upper = boxMesh(Vec(0.3, 0.2, 0.25));
    const rc::MeshBvh lowerBvh(lower), upperBvh(upper);
    const auto lowerModel = fclModel(lower), upperModel = fclModel(upper);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> angle(-M_PI, M_PI), slide(-0.6, 0.6);
    int fclMisses = 0, touching = 0;
    const int trials = 500;
    for (int trial = 0; trial < trials; ++trial)
    {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = Eigen::AngleAxisd(angle(rng), Vec::UnitZ()).toRotationMatrix();
        pose.translation() = Vec(slide(rng), slide(rng), 0.75);
        const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
        // Slid too far, the footprints can miss each other; brute force says which ones touch.
        const bool expected = bruteForceWithin(lower, identity, upper, pose, 0.0);
        ASSERT_EQ(rc::surfacesWithin(lowerBvh, identity, upperBvh, pose, 0.0), expected);
        if (!expected)
            continue;
        ++touching;
        const fcl::CollisionObjectd objectA(lowerModel, identity), objectB(upperModel, pose);
        fcl::CollisionRequestd request;
        fcl::CollisionResultd result;
        fcl::collide(&objectA, &objectB, request, result);
        fclMisses += !result.isCollision();
        Eigen::Isometry3d lifted = pose;
        lifted.translation().z() += 1e-12;
        EXPECT_FALSE(rc::surfacesWithin(lowerBvh, identity, upperBvh, lifted, 0.0));
        EXPECT_TRUE(rc::surfacesWithin(lowerBvh, identity, upperBvh, lifted, 2e-12));
        EXPECT_TRUE(rc::solidsOverlap(lowerBvh, identity, true, upperBvh, pose, true, 0.0));
    }
    std::printf("[ info     ] exact face-on-face contacts: fcl::collide calls %d of %d touching poses free\n",
                fclMisses, touching);
}

TEST(PointInsideClosedMesh, BoxInsideOutsideAndNearFaces)
{
    const rc::Mesh mesh = boxMesh(Vec(1.0, 0.5, 0.25), 3);
    const rc::MeshBvh bvh(mesh);
    EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, Vec::Zero()));
    EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, Vec(1.0 - 1e-6, 0, 0)));
    EXPECT_FALSE(rc::pointInsideClosedMesh(bvh, Vec(1.0 + 1e-6, 0, 0)));
    EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, Vec(0.3, -0.5 + 1e-6, 0.25 - 1e-6)));
    EXPECT_FALSE(rc::pointInsideClosedMesh(bvh, Vec(0.3, -0.5 - 1e-6, 0.1)));
    EXPECT_FALSE(rc::pointInsideClosedMesh(bvh, Vec(5, 5, 5)));
    // On a face, an edge or a corner every ray starts on the surface and grazes: the answer is
    // inside, the safe one (a solid touching another collides), for the tree's test and the
    // patches' alike (one function, device::pointInsideSolid).
    for (const Vec &onSurface : {Vec(0.3, 0.5, 0.1), Vec(1.0, 0.5, 0.0), Vec(1.0, 0.5, 0.25), Vec(-1.0, -0.5, -0.25)})
    {
        EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, onSurface)) << onSurface.transpose();
        EXPECT_TRUE(rc::device::pointInsideSolid(
            bvh.nodes(), static_cast<std::uint32_t>(bvh.numNodes()), {onSurface.x(), onSurface.y(), onSurface.z()},
            1e-9, [](const rc::MeshBvh::Node &node, const rc::device::Ray &ray)
            { return rc::device::rayMeetsTreeNode(ray, node, 1e-6); },
            [&](const rc::MeshBvh::Node &leaf, auto &&visit)
            {
                for (std::uint32_t slot = leaf.firstSlot(); slot < leaf.firstSlot() + leaf.count; ++slot)
                {
                    const double *c = bvh.slotCorners(slot);
                    if (!visit(rc::device::Vec3<double>{c[0], c[1], c[2]}, rc::device::Vec3<double>{c[3], c[4], c[5]},
                               rc::device::Vec3<double>{c[6], c[7], c[8]}))
                        return false;
                }
                return true;
            }));
    }
    // Points on the lines of the box's edges and face diagonals, just inside and just outside.
    for (double s : {-0.9, -1.0 / 3.0, 0.0, 1.0 / 3.0, 0.9})
    {
        EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, Vec(s, 0.5 - 1e-7, 0.25 - 1e-7)));
        EXPECT_FALSE(rc::pointInsideClosedMesh(bvh, Vec(s, 0.5 + 1e-7, 0.25 + 1e-7)));
        EXPECT_TRUE(rc::pointInsideClosedMesh(bvh, Vec(s, s * 0.5 * 0.999, 0)));
    }
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> coordinate(-1.5, 1.5);
    for (int trial = 0; trial < 5000; ++trial)
    {
        const Vec p(coordinate(rng), coordinate(rng) / 2, coordinate(rng) / 4);
        const Vec margin = Vec(1.0, 0.5, 0.25) - p.cwiseAbs();
        if (std::abs(margin.minCoeff()) < 1e-9)
            continue;
        ASSERT_EQ(rc::pointInsideClosedMesh(bvh, p), margin.minCoeff() > 0) << p.transpose();
    }
}

TEST(PointInsideClosedMesh, GrazingRaysAreRetried)
{
    // The first of the fixed ray directions; from these points it runs exactly through a corner or
    // along a line meeting an edge of the box, which rayTriangle must flag as ambiguous.
    const Vec direction(0.4142135623730951, 0.6180339887498949, 0.7320508075688772);
    const rc::Mesh mesh = boxMesh(Vec(1, 1, 1));
    const rc::MeshBvh bvh(mesh);
    const std::vector<std::pair<Vec, bool>> cases = {
        {Vec(1, 1, 1) - 0.5 * direction, true},        // leaves through the corner
        {Vec(1, 1, 0.3) - 3.0 * direction, false},     // enters through a face, leaves through an edge
        {Vec(1, 1, 0.3) - 0.2 * direction, true},      // leaves through that edge
        {Vec(0.2, -1, -1) - 0.01 * direction, false},  // enters through an edge
        {Vec(1, 0.2, 1) - 0.1 * direction, true},      // leaves through an edge
    };
    for (const auto &[point, inside] : cases)
    {
        int grazes = 0;
        for (const rc::Mesh::Triangle &t : mesh.triangles)
        {
            double hit = 0.0;
            grazes += rc::rayTriangle(point, direction, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]],
                                      1e-9, hit) < 0;
        }
        EXPECT_GT(grazes, 0) << "the case no longer grazes: " << point.transpose();
        EXPECT_EQ(rc::pointInsideClosedMesh(bvh, point), inside) << point.transpose();
    }
}

TEST(PointInsideClosedMesh, SphereMatchesWindingNumber)
{
    const rc::Mesh mesh = sphereMesh(1.0, 2);
    const rc::MeshBvh bvh(mesh);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> coordinate(-1.2, 1.2);
    int inside = 0;
    for (int trial = 0; trial < 3000; ++trial)
    {
        // Every tenth point sits on the ray from the centre through a vertex, near the surface.
        const Vec p = trial % 10 == 0
                          ? Vec(mesh.vertices[trial % mesh.numVertices()] * (trial % 20 == 0 ? 0.999 : 1.001))
                          : Vec(coordinate(rng), coordinate(rng), coordinate(rng));
        const double winding = windingNumber(mesh, p);
        ASSERT_TRUE(winding < 0.01 || winding > 0.99) << p.transpose();
        ASSERT_EQ(rc::pointInsideClosedMesh(bvh, p), winding > 0.5) << p.transpose();
        inside += winding > 0.5;
    }
    EXPECT_GT(inside, 500);
}

TEST(PointInsideClosedMesh, InsideGridAgreesWithRays)
{
    // The grid answers only where no triangle comes near its cell, so every point, near the
    // surface or not, must get the ray's answer; and far from the surface it must answer most.
    const std::vector<std::pair<const char *, rc::Mesh>> meshes = {
        {"box", boxMesh(Vec(1.0, 0.5, 0.25), 3)},
        {"sphere", sphereMesh(1.0, 3)},
        {"room with doorway", rc::test::roomWithDoorway()},
        {"U", rc::test::uShape()},
        {"maze of overlapping boxes", rc::test::mazeOnSlab()},
        {"bookshelf", rc::test::bookshelf()}};
    std::mt19937_64 rng(21);
    for (const auto &[name, mesh] : meshes)
    {
        const rc::MeshBvh rays(mesh), grid(mesh, 1, true);
        ASSERT_FALSE(rays.hasInsideGrid());
        ASSERT_TRUE(grid.hasInsideGrid());
        Vec lower = mesh.vertices[0], upper = lower;
        for (const Vec &v : mesh.vertices)
        {
            lower = lower.cwiseMin(v);
            upper = upper.cwiseMax(v);
        }
        const Vec pad = 0.2 * (upper - lower);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        int known = 0, inside = 0;
        const int trials = 20000;
        for (int trial = 0; trial < trials; ++trial)
        {
            Vec p;
            if (trial % 4 == 0)  // near a vertex: within 1e-7 .. 1e-2 of the surface
                p = mesh.vertices[trial % mesh.numVertices()] +
                    std::pow(10.0, -7.0 + 5.0 * unit(rng)) * Vec(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
            else
                p = lower - pad + (upper - lower + 2 * pad).cwiseProduct(Vec(unit(rng), unit(rng), unit(rng)));
            const bool expected = rc::pointInsideClosedMesh(rays, p);
            ASSERT_EQ(rc::pointInsideClosedMesh(grid, p), expected) << name << ": " << p.transpose();
            const int answer = grid.insideGridAnswer(p);
            if (answer != 0)
            {
                ASSERT_EQ(answer == 2, expected) << name << ": " << p.transpose();
            }
            known += answer != 0 && trial % 4 != 0;
            inside += expected;
        }
        EXPECT_GT(inside, trials / 50) << name;
        EXPECT_GT(known, trials * 3 / 4 * 8 / 10)
            << name << ": the grid should answer most points away from the surface";
        EXPECT_LT(grid.bytes() - rays.bytes(), (std::size_t(1) << 21) + 1) << name;
    }
}

TEST(SolidsOverlap, ContainmentByGridAndProbesMatchesRays)
{
    // A U and a bar at random poses: solidsOverlap with inside grids (the probes' first known
    // answer) and without (one ray per shell) must agree on every pose, inside the notch, in the
    // arms, and crossing.
    const rc::Mesh u = rc::test::uShape(), bar = rc::test::lBar(0.3);
    const rc::MeshBvh uRays(u), barRays(bar), uGrid(u, 1, true), barGrid(bar, 1, true);
    std::mt19937_64 rng(22);
    std::uniform_real_distribution<double> x(-0.3, 2.3), y(-0.3, 2.3), z(-0.3, 1.3), angle(-M_PI, M_PI);
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    int contained = 0, crossing = 0;
    for (int trial = 0; trial < 4000; ++trial)
    {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.translation() = Vec(x(rng), y(rng), z(rng));
        pose.linear() =
            Eigen::AngleAxisd(angle(rng), Vec(x(rng), y(rng), z(rng) + 0.5).normalized()).toRotationMatrix();
        const bool expected = rc::solidsOverlap(barRays, pose, true, uRays, identity, true, 0.0);
        ASSERT_EQ(rc::solidsOverlap(barGrid, pose, true, uGrid, identity, true, 0.0), expected) << trial;
        ASSERT_EQ(rc::solidsOverlap(uGrid, identity, true, barGrid, pose, true, 0.0), expected) << trial;
        const bool surfaces = rc::surfacesWithin(barRays, pose, uRays, identity, 0.0);
        contained += expected && !surfaces;
        crossing += surfaces;
    }
    EXPECT_GT(contained, 100);
    EXPECT_GT(crossing, 100);
}

TEST(SolidsOverlap, ContainmentNeedsAClosedContainer)
{
    const rc::Mesh big = boxMesh(Vec(1, 1, 1), 2), small = boxMesh(Vec(0.1, 0.2, 0.1));
    rc::Mesh open = big;
    open.triangles.resize(open.triangles.size() - 8);  // drop the last face (+z): a box without a lid
    const rc::MeshBvh bigBvh(big), smallBvh(small), openBvh(open);
    Eigen::Isometry3d inside = Eigen::Isometry3d::Identity();
    inside.translation() = Vec(0.3, -0.2, 0.1);
    inside.linear() = Eigen::AngleAxisd(0.7, Vec(1, 2, 3).normalized()).toRotationMatrix();
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();

    EXPECT_FALSE(rc::surfacesWithin(smallBvh, inside, bigBvh, identity, 0.0));
    rc::MeshContact contact;
    EXPECT_TRUE(rc::solidsOverlap(smallBvh, inside, true, bigBvh, identity, true, 0.0, &contact));
    EXPECT_EQ(contact.triangleA, -1);
    EXPECT_EQ(contact.triangleB, -1);
    EXPECT_TRUE(rc::pointInsideClosedMesh(bigBvh, contact.position));
    EXPECT_TRUE(rc::solidsOverlap(bigBvh, identity, true, smallBvh, inside, true, 0.0));
    // The small box is no container: only "big is closed" makes the answer true.
    EXPECT_TRUE(rc::solidsOverlap(smallBvh, inside, false, bigBvh, identity, true, 0.0));
    EXPECT_FALSE(rc::solidsOverlap(smallBvh, inside, true, bigBvh, identity, false, 0.0));

    // An open container claims nothing, in either argument order ...
    EXPECT_FALSE(rc::solidsOverlap(smallBvh, inside, true, openBvh, identity, false, 0.0));
    EXPECT_FALSE(rc::solidsOverlap(openBvh, identity, false, smallBvh, inside, true, 0.0));
    // ... but its surface still counts once within the padding (the small box is 0.66 from a wall).
    EXPECT_TRUE(rc::solidsOverlap(smallBvh, inside, true, openBvh, identity, false, 0.7));

    // Apart: no overlap at all.
    Eigen::Isometry3d outside = inside;
    outside.translation() = Vec(3, 0, 0);
    EXPECT_FALSE(rc::solidsOverlap(smallBvh, outside, true, bigBvh, identity, true, 0.0));
    EXPECT_FALSE(rc::solidsOverlap(bigBvh, identity, true, smallBvh, outside, true, 0.0));
}

TEST(SurfacesWithin, TreesTooLargeForThePlacedNodeCacheGiveTheSameAnswers)
{
    // Two spheres of 81 920 triangles each: both trees exceed the per-thread cache (2^17 nodes), so
    // the smaller tree's nodes are placed at every visit instead. Known answers from the radii
    // (1 and 0.8; the tessellation is within 2e-4 of the spheres): nested surfaces do not meet,
    // crossing ones do, distant ones do not, and the padding reaches across a 0.05 gap.
    const rc::Mesh a = sphereMesh(1.0, 6), b = sphereMesh(0.8, 6);
    const rc::MeshBvh bvhA(a), bvhB(b);
    ASSERT_GT(bvhA.numNodes(), std::size_t(1) << 17);
    ASSERT_GT(bvhB.numNodes(), std::size_t(1) << 17);
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    const auto at = [](double x)
    {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = Eigen::AngleAxisd(0.7, Vec(1, 2, 3).normalized()).toRotationMatrix();
        pose.translation() = Vec(x, 0, 0);
        return pose;
    };
    EXPECT_FALSE(rc::surfacesWithin(bvhA, identity, bvhB, at(0.1), 0.0));
    EXPECT_TRUE(rc::solidsOverlap(bvhA, identity, true, bvhB, at(0.1), true, 0.0));
    rc::MeshContact contact;
    EXPECT_TRUE(rc::surfacesWithin(bvhA, identity, bvhB, at(1.0), 0.0, &contact));
    EXPECT_NEAR(contact.position.norm(), 1.0, 1e-3);
    EXPECT_FALSE(rc::surfacesWithin(bvhA, identity, bvhB, at(1.85), 0.0));
    EXPECT_TRUE(rc::surfacesWithin(bvhA, identity, bvhB, at(1.85), 0.06));
    EXPECT_FALSE(rc::surfacesWithin(bvhB, at(1.85), bvhA, identity, 0.04));
}

namespace
{
// A tree of the walk's node convention whose leaves hold points on a line: a chain (every inner
// node's second child a leaf) or a balanced tree over points[begin, end).
struct LineNode
{
    double lower, upper;  // the points' range below the node
    std::int32_t first;   // inner: first child; leaf: -(1 + point index)
};

std::int32_t buildLine(std::vector<LineNode> &nodes, const std::vector<double> &points, std::size_t begin,
                       std::size_t end, std::int32_t at)
{
    nodes[at].lower = points[begin];
    nodes[at].upper = points[end - 1];
    if (end - begin == 1)
    {
        nodes[at].first = -1 - static_cast<std::int32_t>(begin);
        return 0;
    }
    const auto child = static_cast<std::int32_t>(nodes.size());
    nodes[at].first = child;
    nodes.push_back({});
    nodes.push_back({});
    const std::size_t middle = (begin + end) / 2;
    const int left = buildLine(nodes, points, begin, middle, child);
    return 1 + std::max(left, buildLine(nodes, points, middle, end, child + 1));
}

/** \brief Two sets of random points on a line, sorted, B's shifted by \a offset, and their trees. */
struct LinePair
{
    std::vector<double> a, b;
    std::vector<LineNode> treeA{1}, treeB{1};

    LinePair(std::mt19937_64 &rng, std::size_t sizeA, std::size_t sizeB, double offset) : a(sizeA), b(sizeB)
    {
        std::uniform_real_distribution<double> u(0.0, 100.0);
        for (double &x : a)
            x = u(rng);
        for (double &x : b)
            x = u(rng) + offset;
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        buildLine(treeA, a, 0, a.size(), 0);
        buildLine(treeB, b, 0, b.size(), 0);
    }

    /** The distance between two nodes' ranges: a lower bound on their points' distances. */
    double gap(rc::device::NodePair p) const
    {
        const LineNode &na = treeA[p.a], &nb = treeB[p.b];
        return std::max({0.0, nb.lower - na.upper, na.lower - nb.upper});
    }

    /** Descend into the wider node. */
    bool splitA(rc::device::NodePair p) const
    {
        return treeA[p.a].upper - treeA[p.a].lower >= treeB[p.b].upper - treeB[p.b].lower;
    }
};

std::vector<LineNode> chain(int depth)
{
    std::vector<LineNode> nodes(1);
    for (int level = 0; level < depth; ++level)
    {
        const std::size_t at = nodes.size() - (level == 0 ? 1 : 2);  // the previous inner node
        nodes[at] = {0.0, 1.0, static_cast<std::int32_t>(nodes.size())};
        nodes.push_back({0.0, 1.0, 0});           // inner, linked next level
        nodes.push_back({0.0, 1.0, -1 - level});  // a leaf
    }
    nodes[nodes.size() - 2].first = -1 - depth;  // the deepest node is a leaf
    return nodes;
}
}  // namespace

TEST(Traversal, ATreeTooDeepForTheStackEndsInOverflowNotPastTheStack)
{
    // walkTree holds at most depth + 1 entries of the pair walk's kPairStackSize: the deepest
    // chain that fits, and one level more.
    const int fits = rc::device::kPairStackSize - 1;
    for (int depth : {10, fits, fits + 1, 3 * rc::device::kPairStackSize})
    {
        const std::vector<LineNode> nodes = chain(depth);
        int leaves = 0;
        const rc::device::WalkEnd end = rc::device::walkTree(
            nodes.data(), static_cast<std::uint32_t>(nodes.size()), [](const LineNode &) { return true; },
            [&](const LineNode &)
            {
                ++leaves;
                return true;
            });
        if (depth <= fits)
        {
            EXPECT_EQ(end, rc::device::WalkEnd::Finished) << depth;
            EXPECT_EQ(leaves, depth + 1) << depth;
        }
        else
            EXPECT_EQ(end, rc::device::WalkEnd::Overflow) << depth;
    }
}

TEST(Traversal, APairWalkWithAShrinkingReachFindsTheNearestPairAsADistanceQueryWould)
{
    // The nearest pair of two point sets on a line: the node test is a lower bound on the
    // distance of a node pair against the best distance so far, which the leaf visitor lowers.
    std::mt19937_64 rng(33);
    for (int trial = 0; trial < 20; ++trial)
    {
        const LinePair lines(rng, 300, 200, 100.5);  // apart by at least half a unit
        const std::vector<double> &a = lines.a, &b = lines.b;
        const std::vector<LineNode> &treeA = lines.treeA, &treeB = lines.treeB;
        struct Nearest
        {
            const LinePair &lines;
            double best = std::numeric_limits<double>::infinity();
            int leafPairs = 0;
            bool test(rc::device::NodePair p) const { return lines.gap(p) < best; }
            bool leaves(rc::device::NodePair p)
            {
                ++leafPairs;
                best = std::min(
                    best, std::abs(lines.a[-(lines.treeA[p.a].first + 1)] - lines.b[-(lines.treeB[p.b].first + 1)]));
                return true;
            }
            bool splitA(rc::device::NodePair p) const { return lines.splitA(p); }
            bool secondFirst(rc::device::NodePair first, rc::device::NodePair second) const
            {
                return lines.gap(second) < lines.gap(first);
            }
        } query{lines};
        ASSERT_EQ(rc::device::walkPairs(treeA.data(), treeB.data(), query), rc::device::WalkEnd::Finished);
        EXPECT_DOUBLE_EQ(query.best, b.front() - a.back()) << trial;
        EXPECT_LT(query.leafPairs, 50) << "the reach did not shrink: " << query.leafPairs << " of "
                                       << a.size() * b.size();
    }
}

TEST(Traversal, TheWalksPartsOneAfterTheOtherVisitTheWholeWalksLeafPairsInItsOrder)
{
    // Pairs of points on two lines within a reach: the parts of the walk (walkPartStart, 2^depth of
    // them), walked one after the other, visit exactly the leaf pairs of the whole walk, in its order;
    // and a long walk spreads over many parts, pruned or not.
    std::mt19937_64 rng(41);
    std::uniform_real_distribution<double> u(0.0, 100.0);
    int longWalks = 0, spreadWalks = 0;  // of 32 leaf pairs or more; of those, over 8 parts or more
    for (int trial = 0; trial < 40; ++trial)
    {
        const std::size_t sizeA = 1 + rng() % 120, sizeB = 1 + rng() % 90;
        const LinePair lines(rng, sizeA, sizeB, 20.0 * (trial % 4));
        const std::vector<LineNode> &treeA = lines.treeA, &treeB = lines.treeB;
        struct Within
        {
            const LinePair &lines;
            double reach;
            std::vector<std::pair<std::int32_t, std::int32_t>> visited;
            bool test(rc::device::NodePair p) const { return lines.gap(p) <= reach; }
            bool leaves(rc::device::NodePair p)
            {
                visited.emplace_back(p.a, p.b);
                return true;
            }
            bool splitA(rc::device::NodePair p) const { return lines.splitA(p); }
            bool secondFirst(rc::device::NodePair first, rc::device::NodePair second) const
            {
                return lines.gap(second) < lines.gap(first);
            }
        };
        const double reach = 0.5 + u(rng) / 20.0;
        Within whole{lines, reach, {}};
        ASSERT_EQ(rc::device::walkPairs(treeA.data(), treeB.data(), whole), rc::device::WalkEnd::Finished);
        for (std::uint32_t depth = 0; depth <= rc::device::walkPartDepth(rc::device::kMaxWalkParts); ++depth)
        {
            Within parts{lines, reach, {}};
            int partsVisiting = 0;
            for (std::uint32_t index = 0; index < (1u << depth); ++index)
            {
                rc::device::NodePair start{};
                if (!rc::device::walkPartStart(treeA.data(), treeB.data(), parts, index, depth, start))
                    continue;
                const std::size_t before = parts.visited.size();
                ASSERT_EQ(rc::device::walkPairs(treeA.data(), treeB.data(), parts, start),
                          rc::device::WalkEnd::Finished);
                partsVisiting += parts.visited.size() > before;
            }
            EXPECT_EQ(parts.visited, whole.visited) << "trial " << trial << ", depth " << depth;
            if (depth == 5 && whole.visited.size() >= 32)
            {
                ++longWalks;
                spreadWalks += partsVisiting >= 8;
            }
        }
    }
    // The node test keeps pairs whose leaves it then drops (overlapping ranges of distant points), so
    // a part may visit nothing; but long walks spread.
    EXPECT_GT(longWalks, 5);
    EXPECT_GT(spreadWalks, longWalks / 2) << spreadWalks << " of " << longWalks;
}

TEST(MeshBvh, ALargeMeshBuiltOnManyThreadsIsTheTreeOneThreadBuilds)
{
    // Above 2 x kMinJobTriangles triangles the subtrees below the upper levels are built as jobs on
    // OpenMP's threads and laid out again in one build's order: node for node the same tree.
    // A bumpy grid (19 602 triangles) and a sphere (11 448): 4 threads give each several jobs.
    rc::Mesh bumpy;
    const int side = 100;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j)
            bumpy.vertices.emplace_back(0.01 * i, 0.01 * j,
                                        0.05 * std::sin(0.3 * i) * std::cos(0.17 * j) + 0.01 * ((7 * i + 13 * j) % 5));
    for (int i = 0; i + 1 < side; ++i)
        for (int j = 0; j + 1 < side; ++j)
        {
            const auto v = static_cast<std::uint32_t>(i * side + j);
            bumpy.triangles.push_back({v, v + side, v + 1});
            bumpy.triangles.push_back({v + 1, v + side, v + side + 1});
        }
    for (const rc::Mesh &mesh : {bumpy, rc::makeSphere(1.0, 1e-3)})
    {
        ASSERT_GT(mesh.numTriangles(), 2 * rc::MeshBvh::kMinJobTriangles);
        const int threads = omp_get_max_threads();
        omp_set_num_threads(1);
        const rc::MeshBvh serial(mesh, 2, false);
        omp_set_num_threads(4);
        const rc::MeshBvh parallel(mesh, 2, false);
        omp_set_num_threads(threads);
        ASSERT_EQ(serial.numNodes(), parallel.numNodes());
        EXPECT_EQ(serial.depth(), parallel.depth());
        EXPECT_EQ(0, std::memcmp(serial.nodes(), parallel.nodes(), serial.numNodes() * sizeof(rc::MeshBvh::Node)));
        EXPECT_EQ(0, std::memcmp(serial.triangleOrder(), parallel.triangleOrder(),
                                 mesh.numTriangles() * sizeof(std::uint32_t)));
    }
}
