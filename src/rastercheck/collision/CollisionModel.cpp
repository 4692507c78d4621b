#include "rastercheck/collision/CollisionModel.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Parallel.h"
#include "rastercheck/geometry/EigenDevice.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
CollisionModel::MeshSlice appendMesh(const Mesh &mesh, bool closed, const Eigen::Vector3d &origin,
                                     std::vector<float> &vertices, std::vector<std::uint32_t> &triangles)
{
    CollisionModel::MeshSlice slice{static_cast<std::uint32_t>(vertices.size() / 3),
                                    static_cast<std::uint32_t>(mesh.numVertices()),
                                    static_cast<std::uint32_t>(triangles.size() / 3),
                                    static_cast<std::uint32_t>(mesh.numTriangles()),
                                    closed,
                                    0,
                                    0};
    for (const Eigen::Vector3d &v : mesh.vertices)
        for (int k = 0; k < 3; ++k)
            vertices.push_back(static_cast<float>(v[k] - origin[k]));
    for (const Mesh::Triangle &t : mesh.triangles)
        triangles.insert(triangles.end(), t.begin(), t.end());
    return slice;
}

/** \brief Triangles per leaf of every tree (the robot's links and the scene's objects). Two per leaf
    halve the nodes, and the simultaneous traversal then tests fewer node pairs for a few more
    triangle pairs. In the robot's trees since 2026-11-25 (rastercheck_bench_meshes, 3 000 states,
    safe / FCL, uniform and near contact: alpha-1.5 2.99-3.08 -> 3.33-3.49, FCL's env/rob 3.45-4.08
    -> 3.88-4.54); in the scene's since the boxes are fitted by least area (which made the scene's
    leaf boxes as tight as the robot's): against one per leaf, distance queries (Checker::distance
    timed alone, 1000 uniform poses) bugtrap 30.4 -> 25.8 us, alpha-1.5 55.7 -> 46.5, and collision
    queries' worst ratio to FCL (same bench) 3.26 -> 3.47 uniform, 4.39 -> 4.71 near contact (before
    the fit, two per leaf in the scene's trees cost the terrain's near-contact states 3.23 ->
    2.55-2.89). Four: bugtrap's distance 25.8 -> 29.6 us. */
constexpr unsigned kLeafTriangles = 2;

/** \brief The triangle tree of each of \a parts (Component or SceneObject), each on an OpenMP
    thread: they are independent, and a few large meshes take most of the time (a UR5's gripper and
    force sensor 80 % of its trees'). A tree's error (a mesh edited by hand that names a missing
    vertex) names its \a kind and part. */
template <class Part>
std::vector<std::shared_ptr<MeshBvh>> buildTrees(const std::vector<Part> &parts, const char *kind)
{
    std::vector<std::shared_ptr<MeshBvh>> trees(parts.size());
    parallelFor(parts.size(),
                [&](std::size_t k)
                {
                    const Part &part = parts[k];
                    try
                    {
                        trees[k] = std::make_shared<MeshBvh>(part.mesh, kLeafTriangles, part.topology.closed);
                    }
                    catch (const ConfigurationError &e)
                    {
                        throw ConfigurationError(std::string(kind) + " '" + part.name + "': " + e.what());
                    }
                });
    return trees;
}

/** \brief Moves the trees' nodes and triangle orders into one flat pair of arrays (the slices say
    where each mesh's part starts) and points every tree at its part, so each node is stored once. */
void shareTrees(const std::vector<std::shared_ptr<MeshBvh>> &trees, std::vector<CollisionModel::MeshSlice> &slices,
                CollisionModel::TreeArrays &arrays)
{
    std::size_t numNodes = 0, numTriangles = 0, numCells = 0;
    for (const std::shared_ptr<MeshBvh> &tree : trees)
    {
        numNodes += tree->numNodes();
        numTriangles += tree->mesh().triangles.size();
        numCells += tree->numGridCells();
    }
    arrays.nodes.reserve(numNodes);
    arrays.triangleOrder.reserve(numTriangles);
    arrays.corners.reserve(9 * numTriangles);
    arrays.gridCells.reserve(numCells);
    for (std::size_t k = 0; k < trees.size(); ++k)
    {
        const MeshBvh &tree = *trees[k];
        const std::size_t triangles = tree.mesh().triangles.size();
        slices[k].firstNode = static_cast<std::uint32_t>(arrays.nodes.size());
        slices[k].numNodes = static_cast<std::uint32_t>(tree.numNodes());
        if (arrays.triangleOrder.size() != slices[k].firstTriangle)
            throw std::logic_error("shareTrees: the triangle orders do not follow the triangle slices");
        const MeshBvh::Arrays own = tree.arrays();
        arrays.nodes.insert(arrays.nodes.end(), own.nodes, own.nodes + tree.numNodes());
        arrays.triangleOrder.insert(arrays.triangleOrder.end(), own.triangleOrder, own.triangleOrder + triangles);
        arrays.corners.insert(arrays.corners.end(), own.corners, own.corners + 9 * triangles);
        device::ExactMeshInfo info{};
        info.grid = tree.exactTree().grid;
        info.firstGridCell = arrays.gridCells.size();
        info.firstProbe = static_cast<std::uint32_t>(arrays.probePoints.size() / 3);
        info.firstShell = static_cast<std::uint32_t>(arrays.shellProbeStart.size());
        info.numShells = static_cast<std::uint32_t>(tree.numShells());
        arrays.meshes.push_back(info);
        arrays.gridCells.insert(arrays.gridCells.end(), own.gridCells, own.gridCells + tree.numGridCells());
        arrays.probePoints.insert(arrays.probePoints.end(), tree.shellProbePoints().begin(),
                                  tree.shellProbePoints().end());
        arrays.shellProbeStart.insert(arrays.shellProbeStart.end(), tree.shellProbeStart().begin(),
                                      tree.shellProbeStart().end());
    }
    for (std::size_t k = 0; k < trees.size(); ++k)
        trees[k]->useSharedArrays(MeshBvh::Arrays{
            arrays.nodes.data() + slices[k].firstNode, arrays.triangleOrder.data() + slices[k].firstTriangle,
            arrays.corners.data() + 9 * static_cast<std::size_t>(slices[k].firstTriangle),
            trees[k]->numGridCells() > 0 ? arrays.gridCells.data() + arrays.meshes[k].firstGridCell : nullptr});
}

/** \brief Largest vertices x triangles product a piece's convexity is measured over: a finer
    piece gets no face planes (its hull proves only separation), which bounds load time. */
constexpr std::size_t kMaxConvexityTests = std::size_t(4) << 20;

/** \brief A closed piece keeps its face planes for overlap proofs only when no vertex lies farther
    than this fraction of its box diagonal in front of a face's plane: beyond, the region behind
    every plane (where proofs look) is too small to be found often, and each failed look costs a
    pass over the planes. The Panda's MotionBenchMaker links (convex shapes with small dents) are
    within 0.7 %. */
constexpr double kMaxConvexityDefect = 0.02;

/** \brief A face whose edges' cross product is shorter than this fraction of the product of
    their lengths (an angle under 0.006 degrees) has a normal that rounding may tilt by more than
    device::kPlaneSlack allows for; a piece with one gets no planes. */
constexpr double kMinFaceSine = 1e-4;

/** \brief Unit outward normal and offset of each triangle of \a mesh (x y z d), a closed shell, or
    none when the mesh is too fine to measure, too far from convex (kMaxConvexityDefect), has a
    sliver face (kMinFaceSine), or is not oriented outward. */
std::vector<double> facePlanes(const Mesh &mesh)
{
    std::vector<double> planes;
    if (mesh.triangles.empty() || mesh.numVertices() * mesh.numTriangles() > kMaxConvexityTests ||
        !(signedVolume(mesh) > 0.0))
        return planes;
    const double limit = kMaxConvexityDefect * (mesh.bounds().max - mesh.bounds().min).norm();
    for (const Mesh::Triangle &t : mesh.triangles)
    {
        const Eigen::Vector3d &a = mesh.vertices[t[0]];
        const Eigen::Vector3d e1 = mesh.vertices[t[1]] - a, e2 = mesh.vertices[t[2]] - a;
        const Eigen::Vector3d n = e1.cross(e2);
        const double length = n.norm();
        if (!(length > kMinFaceSine * e1.norm() * e2.norm()))
            return {};
        const Eigen::Vector3d unit = n / length;
        const double offset = unit.dot(a);
        for (const Eigen::Vector3d &v : mesh.vertices)
            if (unit.dot(v) - offset > limit)
                return {};
        planes.insert(planes.end(), {unit.x(), unit.y(), unit.z(), offset});
    }
    return planes;
}

/** \brief Per direction cell of \a points (a piece's hull points; device::supportCell's order),
    the points, ascending, that can be extreme along a direction of the cell.

    Why no point is missed: a cell's directions are the cone spanned by the four corners of a
    square of the cube's face. First, scaled to unit length, they lie within the chord \a reach of
    the unit direction c through the square's centre (the cap about c through the farthest
    corner holds the cell). Relative to the points' mean o, a point p's value along such a unit
    direction d is then within |p - o| reach of (p - o) . c, so no point beats best = max (p - o)
    . c - |p - o| reach, and a point whose highest possible value, (p - o) . c + |p - o| reach,
    stays below it is beaten in the whole cell by the point that gives best. Among the points
    left, a point q is dropped when another point p beats it at all four corners: (p - q) . d is
    linear in d, so p then beats q along every direction of the cone. The squares are grown by
    1e-6 (far beyond the rounding of the cell a direction is put in), and a point counts as
    beaten only by a ten-billionth of the points' size (far beyond the rounding of the dot
    products, which compare the points as placed, not relative to o). */
std::vector<std::vector<device::HullPointNumber>> supportCellCandidates(const std::vector<Eigen::Vector3d> &points)
{
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double size = 0.0;
    for (const Eigen::Vector3d &p : points)
    {
        mean += p / static_cast<double>(points.size());
        size = std::max(size, p.norm());
    }
    const double tolerance = 1e-10 * size;
    std::vector<Eigen::Vector3d> relative;  // p - o
    std::vector<double> distance;           // |p - o|
    for (const Eigen::Vector3d &p : points)
    {
        relative.push_back(p - mean);
        distance.push_back(relative.back().norm());
    }
    // The unit direction of face f at face coordinates (s, t), as device::supportCell reads them.
    auto direction = [](std::uint32_t face, double s, double t)
    {
        const double sign = face % 2 == 0 ? 1.0 : -1.0;
        Eigen::Vector3d d;
        switch (face / 2)
        {
            case 0:
                d = Eigen::Vector3d(sign, s, t);
                break;
            case 1:
                d = Eigen::Vector3d(t, sign, s);
                break;
            default:
                d = Eigen::Vector3d(s, t, sign);
                break;
        }
        return d.normalized();
    };
    constexpr std::uint32_t side = device::kSupportCellsPerSide;
    constexpr double grown = 1e-6;
    std::vector<std::vector<device::HullPointNumber>> cells;
    for (std::uint32_t face = 0; face < 6; ++face)
        for (std::uint32_t row = 0; row < side; ++row)
            for (std::uint32_t column = 0; column < side; ++column)
            {
                const double s0 = -1.0 + 2.0 * row / side - grown, s1 = -1.0 + 2.0 * (row + 1) / side + grown;
                const double t0 = -1.0 + 2.0 * column / side - grown, t1 = -1.0 + 2.0 * (column + 1) / side + grown;
                const Eigen::Vector3d centre = direction(face, 0.5 * (s0 + s1), 0.5 * (t0 + t1));
                std::vector<Eigen::Vector3d> corners;
                double reach = 0.0;
                for (const double s : {s0, s1})
                    for (const double t : {t0, t1})
                    {
                        corners.push_back(direction(face, s, t));
                        reach = std::max(reach, (corners.back() - centre).norm());
                    }
                reach *= 1.0 + 1e-9;
                std::vector<double> atCentre(points.size());  // (p - o) . c
                double best = -std::numeric_limits<double>::infinity();
                for (std::size_t i = 0; i < points.size(); ++i)
                {
                    atCentre[i] = relative[i].dot(centre);
                    best = std::max(best, atCentre[i] - distance[i] * reach);
                }
                std::vector<device::HullPointNumber> near;
                for (std::size_t i = 0; i < points.size(); ++i)
                    if (atCentre[i] + distance[i] * reach >= best - tolerance)
                        near.push_back(static_cast<device::HullPointNumber>(i));
                // A point beaten by another of near is beaten by one kept before it: the winner has the
                // higher value at the centre (a positive sum of the corners), and a dropped winner was
                // itself beaten by a kept point, which then beats the loser too. So the points are
                // taken best first and tried against those kept.
                std::sort(near.begin(), near.end(),
                          [&](device::HullPointNumber a, device::HullPointNumber b)
                          { return atCentre[a] > atCentre[b]; });
                std::vector<device::HullPointNumber> cell;
                for (const device::HullPointNumber q : near)
                {
                    const bool beaten =
                        std::any_of(cell.begin(), cell.end(),
                                    [&](device::HullPointNumber p)
                                    {
                                        return std::all_of(corners.begin(), corners.end(),
                                                           [&](const Eigen::Vector3d &corner)
                                                           { return (points[p] - points[q]).dot(corner) > tolerance; });
                                    });
                    if (!beaten)
                        cell.push_back(q);
                }
                std::sort(cell.begin(), cell.end());
                cells.push_back(std::move(cell));
            }
    return cells;
}

/** \brief Appends triangle \a t of \a mesh to \a part, its corners renumbered through \a renumbered
    (one entry per vertex of \a mesh; ~0u: not yet in \a part, set when added). Cuts a mesh into
    parts: its shells, or its patches. */
void appendTriangle(const Mesh &mesh, std::size_t t, Mesh &part, std::vector<std::uint32_t> &renumbered)
{
    Mesh::Triangle triangle{};
    for (int k = 0; k < 3; ++k)
    {
        const std::uint32_t v = mesh.triangles[t][k];
        if (renumbered[v] == ~0u)
        {
            renumbered[v] = static_cast<std::uint32_t>(part.vertices.size());
            part.vertices.push_back(mesh.vertices[v]);
        }
        triangle[k] = renumbered[v];
    }
    part.triangles.push_back(triangle);
}

/** \brief True when the triangles order[begin, end) of \a mesh lie in a slab, normal to their mean
    normal, no thicker than \a thickness: a patch whose hull hugs its surface (a piece of a wall, of
    a gently curved shell), not one that wraps a corner. */
bool patchIsFlat(const Mesh &mesh, const std::uint32_t *order, std::size_t begin, std::size_t end, double thickness)
{
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (std::size_t i = begin; i < end; ++i)
        normal += mesh.triangleNormal(order[i]);
    const double length = normal.norm();
    if (!(length > 0.0))
        return false;
    normal /= length;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (std::size_t i = begin; i < end; ++i)
        for (std::uint32_t v : mesh.triangles[order[i]])
        {
            low = std::min(low, normal.dot(mesh.vertices[v]));
            high = std::max(high, normal.dot(mesh.vertices[v]));
        }
    return high - low <= thickness;
}

device::OrientedBox toDeviceBox(const Obb &box)
{
    device::OrientedBox b;
    for (int r = 0; r < 3; ++r)
    {
        b.center[r] = static_cast<float>(box.center[r]);
        b.half[r] = static_cast<float>(box.halfExtents[r]);
        for (int c = 0; c < 3; ++c)
            b.axes[3 * r + c] = static_cast<float>(box.axes(r, c));
    }
    return b;
}
}  // namespace

device::ConvexPiece ConvexSolids::makePiece(const Mesh &mesh, bool closedShell)
{
    device::ConvexPiece piece{static_cast<std::uint32_t>(vertices_.size() / 3),
                              static_cast<std::uint32_t>(mesh.numVertices()),
                              static_cast<std::uint32_t>(hullPoints_.size() / 3),
                              0,
                              0.0,
                              0.0,
                              static_cast<std::uint32_t>(planes_.size() / 4),
                              0,
                              {0.0, 0.0, 0.0},
                              0,
                              static_cast<std::uint32_t>(edges_.size() / 2),
                              0,
                              0,
                              0,
                              0,
                              0,
                              0};
    std::vector<std::uint8_t> used(mesh.numVertices(), 0);
    for (const Mesh::Triangle &t : mesh.triangles)
        for (std::uint32_t v : t)
            used[v] = 1;
    piece.surfaceVertices = !mesh.triangles.empty() && std::find(used.begin(), used.end(), 0) == used.end() ? 1u : 0u;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (const Mesh::Triangle &t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (const auto &[from, to] : edges)
        edges_.insert(edges_.end(), {from, to});
    piece.numEdges = static_cast<std::uint32_t>(edges.size());
    if (closedShell)
    {
        const std::vector<double> planes = facePlanes(mesh);
        planes_.insert(planes_.end(), planes.begin(), planes.end());
        piece.numPlanes = static_cast<std::uint32_t>(planes.size() / 4);
    }
    for (const Eigen::Vector3d &v : mesh.vertices)
    {
        vertices_.insert(vertices_.end(), v.data(), v.data() + 3);
        piece.radius = std::max(piece.radius, v.norm());
    }
    std::vector<std::uint32_t> extreme = mesh.extremeVertices(kConvexHullDirections);
    piece.numHullPoints = static_cast<std::uint32_t>(extreme.size());
    if (piece.numHullPoints >= device::kSupportCellsMinPoints)
    {
        // The cells number hull points in HullPointNumber (Mesh::extremeVertices gives at most one a direction).
        static_assert(kConvexHullDirections - 1 <= std::numeric_limits<device::HullPointNumber>::max(),
                      "hull point numbers must fit the cells' HullPointNumber");
        std::vector<Eigen::Vector3d> points;
        for (std::uint32_t i : extreme)
            points.push_back(mesh.vertices[i]);
        piece.firstSupportCell = static_cast<std::uint32_t>(supportCellStart_.size());
        piece.hasSupportCells = 1;
        for (const std::vector<device::HullPointNumber> &cell : supportCellCandidates(points))
        {
            supportCellStart_.push_back(static_cast<std::uint32_t>(supportCandidates_.size()));
            supportCandidates_.insert(supportCandidates_.end(), cell.begin(), cell.end());
        }
        supportCellStart_.push_back(static_cast<std::uint32_t>(supportCandidates_.size()));
    }
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::uint32_t i : extreme)
    {
        hullPoints_.insert(hullPoints_.end(), mesh.vertices[i].data(), mesh.vertices[i].data() + 3);
        centre += mesh.vertices[i] / static_cast<double>(extreme.size());
    }
    std::copy(centre.data(), centre.data() + 3, piece.centre);
    if (extreme.size() < mesh.numVertices())
    {
        // How far the other vertices may stick out of the hull points' hull: with it, a gap
        // between hull points alone can prove a pair apart (device::relateHulls). The
        // slack added covers the rounding of the bound's inside test.
        std::vector<std::uint8_t> isHullPoint(mesh.numVertices(), 0);
        for (std::uint32_t i : extreme)
            isHullPoint[i] = 1;
        const device::ConvexProxy hull = device::convexProxy(arrays(), piece);  // its cells too
        for (std::size_t i = 0; i < mesh.numVertices(); ++i)
            if (!isHullPoint[i])
            {
                const Eigen::Vector3d &v = mesh.vertices[i];
                piece.hullSlack =
                    std::max(piece.hullSlack, device::hullDistanceBound(toDevice(v), hull, piece.hullSlack));
            }
        piece.hullSlack += 1e-6 * piece.radius;
    }
    return piece;
}

void ConvexSolids::addPatches(const MeshBvh &tree, double patchThickness)
{
    const Mesh &mesh = tree.mesh();
    const MeshBvh::Node *treeNodes = tree.nodes();
    const std::uint32_t *order = tree.triangleOrder();
    const std::vector<MeshBvh::SlotRange> slots = tree.nodeSlotRanges();
    const std::size_t root = patchNodes_.size();
    std::vector<std::uint32_t> renumbered(mesh.numVertices(), ~0u);
    // Depth-first down the triangle tree with an explicit list of (patch node, tree node); the
    // patch tree's inner nodes mirror the tree's, children stored in pairs.
    struct Pending
    {
        std::size_t node;
        std::int32_t treeNode;
    };
    std::vector<Pending> pending{{root, 0}};
    patchNodes_.emplace_back();
    while (!pending.empty())
    {
        const Pending job = pending.back();
        pending.pop_back();
        const MeshBvh::SlotRange range = slots[job.treeNode];
        Aabb box;
        for (std::uint32_t slot = range.begin; slot < range.end; ++slot)
            for (std::uint32_t v : mesh.triangles[order[slot]])
                box.extend(mesh.vertices[v]);
        device::PatchNode &node = patchNodes_[job.node];
        for (int k = 0; k < 3; ++k)
        {
            node.min[k] = box.min[k];
            node.max[k] = box.max[k];
        }
        node.treeNode = static_cast<std::uint32_t>(job.treeNode);
        const MeshBvh::Node &treeNode = treeNodes[job.treeNode];
        if (treeNode.isLeaf() || (range.end - range.begin <= kPatchTriangles &&
                                  patchIsFlat(mesh, order, range.begin, range.end, patchThickness)))
        {
            // A patch: its triangles as a mesh of their own (vertices renumbered), in slot order.
            Mesh patch;
            for (std::uint32_t slot = range.begin; slot < range.end; ++slot)
                appendTriangle(mesh, order[slot], patch, renumbered);
            for (std::uint32_t slot = range.begin; slot < range.end; ++slot)
                for (std::uint32_t v : mesh.triangles[order[slot]])
                    renumbered[v] = ~0u;
            device::ConvexPiece piece = makePiece(patch, false);
            piece.firstTriangle = static_cast<std::uint32_t>(patchTriangles_.size() / 3);
            piece.numTriangles = static_cast<std::uint32_t>(patch.numTriangles());
            for (const Mesh::Triangle &t : patch.triangles)
                patchTriangles_.insert(patchTriangles_.end(), t.begin(), t.end());
            patchNodes_[job.node].first = -1 - static_cast<std::int32_t>(patchPieces_.size());
            patchPieces_.push_back(piece);
            continue;
        }
        const std::size_t child = patchNodes_.size();
        patchNodes_[job.node].first = static_cast<std::int32_t>(child - root);
        patchNodes_.emplace_back();
        patchNodes_.emplace_back();
        pending.push_back({child + 1, treeNode.first + 1});
        pending.push_back({child, treeNode.first});
    }
}

std::size_t ConvexSolids::bytes() const
{
    return vertices_.size() * sizeof(double) + hullPoints_.size() * sizeof(double) +
           pieces_.size() * sizeof(device::ConvexPiece) + solidPieces_.size() * sizeof(std::uint32_t) +
           planes_.size() * sizeof(double) + edges_.size() * sizeof(std::uint32_t) +
           supportCellStart_.size() * sizeof(std::uint32_t) +
           supportCandidates_.size() * sizeof(device::HullPointNumber) +
           patchNodes_.size() * sizeof(device::PatchNode) + solidPatchNodes_.size() * sizeof(std::uint32_t) +
           patchPieces_.size() * sizeof(device::ConvexPiece) + solidPatches_.size() * sizeof(std::uint32_t) +
           patchTriangles_.size() * sizeof(std::uint32_t);
}

void ConvexSolids::add(const MeshBvh &tree, bool closed, double patchThickness)
{
    const Mesh &mesh = tree.mesh();
    std::size_t shells = 0;
    const std::vector<std::uint32_t> shellOf = triangleShells(mesh, shells);
    // The whole mesh proves overlaps only as a single shell: the region behind every face of
    // several shells is rarely more than their overlap.
    const std::size_t wholePiece = pieces_.size();
    pieces_.push_back(makePiece(mesh, closed && shells == 1));
    pieces_[wholePiece].closed = closed ? 1u : 0u;
    bool nearConvex = pieces_[wholePiece].numPlanes > 0;
    if (shells >= 2 && shells <= kMaxConvexShells)
    {
        // Each shell as a mesh of its own. Shells are linked through shared vertices, so every
        // vertex belongs to one shell; a closed mesh's shells are each closed.
        std::vector<Mesh> parts(shells);
        std::vector<std::uint32_t> renumbered(mesh.numVertices(), ~0u);
        for (std::size_t t = 0; t < mesh.numTriangles(); ++t)
        {
            appendTriangle(mesh, t, parts[shellOf[t]], renumbered);
        }
        nearConvex = true;
        for (const Mesh &part : parts)
        {
            pieces_.push_back(makePiece(part, closed));
            nearConvex = nearConvex && pieces_.back().numPlanes > 0;
        }
    }
    solidPieces_.push_back(static_cast<std::uint32_t>(pieces_.size()));
    if (!nearConvex && mesh.numTriangles() > kMinPatchedTriangles)
        addPatches(tree, patchThickness >= 0.0 ? patchThickness
                                               : kPatchFlatness * (mesh.bounds().max - mesh.bounds().min).norm());
    solidPatchNodes_.push_back(static_cast<std::uint32_t>(patchNodes_.size()));
    solidPatches_.push_back(static_cast<std::uint32_t>(patchPieces_.size()));
}

namespace
{
/** \brief The diagonal of each component's box, in component order. */
std::vector<double> componentDiagonals(const RobotModel &robot)
{
    std::vector<double> diagonals;
    for (const Component &component : robot.components)
        diagonals.push_back(2.0 * component.localObb.halfExtents.norm());
    return diagonals;
}
}  // namespace

CollisionModel::CollisionModel(RobotModelConstPtr robotModel, SceneConstPtr sceneModel)
    : robot(std::move(robotModel)), scene(std::move(sceneModel))
{
    if (!robot)
        throw ConfigurationError("CollisionModel needs a robot model");
    if (!scene)
        scene = std::make_shared<Scene>();
    copyRobotPart(sharedRobotPart(*robot));

    if (!scene->objects.empty())
        origin = 0.5 * (scene->bounds().min + scene->bounds().max);
    else if (!robot->components.empty())
    {
        RobotData data(*robot);
        forwardKinematics(*robot, data, robot->neutralConfiguration());
        for (const Component &component : robot->components)
            origin += data.oMl[component.link].translation() / static_cast<double>(robot->components.size());
    }

    // Objects' patches are held to the robot's scale: a patch as thick as a link hides gaps
    // the size of one.
    std::vector<double> diagonals = componentDiagonals(*robot);
    std::sort(diagonals.begin(), diagonals.end());
    const double robotScale = diagonals.empty() ? 0.0 : diagonals[diagonals.size() / 2];
    const std::vector<std::shared_ptr<MeshBvh>> trees = buildTrees(scene->objects, "scene object");
    for (std::size_t o = 0; o < scene->objects.size(); ++o)
    {
        const SceneObject &object = scene->objects[o];
        objects.push_back(appendMesh(object.mesh, object.topology.closed, origin, objectVertices, objectTriangles));
        // Float rounding must not cut off geometry: grow by a relative 1e-5 of the size and 1e-6 of
        // the distance from the origin (each vertex was rounded to about 6e-8 of it).
        Aabb shifted;
        shifted.min = object.bounds.min - origin;
        shifted.max = object.bounds.max - origin;
        const double distance = std::max(shifted.min.cwiseAbs().maxCoeff(), shifted.max.cwiseAbs().maxCoeff());
        const Aabb grown = shifted.inflated(1e-5 * (shifted.max - shifted.min).norm() + 1e-6 * distance + 1e-9);
        device::Box box;
        for (int k = 0; k < 3; ++k)
        {
            box.min[k] = static_cast<float>(grown.min[k]);
            box.max[k] = static_cast<float>(grown.max[k]);
        }
        objectBoxes.push_back(box);
        objectSpheres.push_back(device::boundingSphere(box));
        Obb fitted = Obb::fit(object.mesh);
        fitted.center -= origin;
        fitted.halfExtents.array() += 1e-5 * fitted.halfExtents.norm() + 1e-6 * distance + 1e-9;
        objectOrientedBoxes.push_back(toDeviceBox(fitted));
        convex.add(*trees[o], object.topology.closed,
                   kPatchFlatness * (robotScale > 0.0 ? robotScale : (object.bounds.max - object.bounds.min).norm()));
    }
    shareTrees(trees, objects, objectTrees);
    objectBvhs.assign(trees.begin(), trees.end());
    for (int k = 0; k < 3; ++k)
        objectTreePlacement.m[4 * k + 3] = static_cast<float>(-origin[k]);

    curved = CurvedSolids(*this);  // reads selfPairs and the trees

    if (!diagonals.empty())
        defaultPixelSize = diagonals[diagonals.size() / 2] / 32.0;
    if (!(defaultPixelSize > 0))
        defaultPixelSize = 1e-3;
}

CollisionModel::CollisionModel(RobotModelConstPtr robotModel, RobotPartOnly)
    : robot(std::move(robotModel)), scene(std::make_shared<Scene>())
{
    buildRobotPart();
}

void CollisionModel::buildRobotPart()
{
    const std::vector<double> diagonals = componentDiagonals(*robot);
    const std::vector<std::shared_ptr<MeshBvh>> trees = buildTrees(robot->components, "component");
    for (std::size_t k = 0; k < robot->components.size(); ++k)
    {
        const Component &component = robot->components[k];
        components.push_back(appendMesh(component.mesh, component.topology.closed, Eigen::Vector3d::Zero(),
                                        componentVertices, componentTriangles));
        // Float rounding of the transformed box must not cut off geometry: grow by a relative 1e-5.
        Obb box = component.localObb;
        box.halfExtents.array() += 1e-5 * box.halfExtents.norm() + 1e-9;
        componentLocalBoxes.push_back(toDeviceBox(box));
        componentLink.push_back(component.link);
        // The component's own tree: its patches are a cut of it (one tree per mesh).
        convex.add(*trees[k], component.topology.closed, kPatchFlatness * diagonals[k]);
    }
    componentSubtreeEnd = robot->componentSubtreeEnd;
    shareTrees(trees, components, componentTrees);
    componentBvhs.assign(trees.begin(), trees.end());

    for (std::size_t a = 0; a < components.size(); ++a)
        for (std::size_t b = a + 1; b < components.size(); ++b)
            if (!robot->isCollisionAllowed(static_cast<int>(a), static_cast<int>(b)))
                selfPairs.emplace_back(static_cast<int>(a), static_cast<int>(b));

    boundedCoordinates.assign(robot->numCoordinates(), 1);
    for (const Joint &joint : robot->joints)
    {
        if (joint.firstCoordinate < 0)
            continue;
        if (joint.continuous)
            boundedCoordinates[joint.firstCoordinate] = 0;
        if (joint.kind == JointKind::Floating)
            quaternionStarts.push_back(joint.firstCoordinate + 3);
    }
    selfPairTables = SelfPairTables(*this);  // reads selfPairs, convex (the components' solids), componentLink,
                                             // quaternionStarts
}

void CollisionModel::copyRobotPart(const std::shared_ptr<const CollisionModel> &part)
{
    componentVertices = part->componentVertices;
    componentTriangles = part->componentTriangles;
    components = part->components;
    componentLocalBoxes = part->componentLocalBoxes;
    componentLink = part->componentLink;
    componentSubtreeEnd = part->componentSubtreeEnd;
    componentTrees = part->componentTrees;
    // The trees read the part's own arrays (equal to the copies): each keeps the part alive.
    for (const std::shared_ptr<const MeshBvh> &tree : part->componentBvhs)
        componentBvhs.emplace_back(part, tree.get());
    convex = part->convex;  // the components' solids; the objects' follow
    selfPairs = part->selfPairs;
    boundedCoordinates = part->boundedCoordinates;
    quaternionStarts = part->quaternionStarts;
    selfPairTables = part->selfPairTables;
}

std::shared_ptr<const CollisionModel> CollisionModel::sharedRobotPart(const RobotModel &robot)
{
    struct Entry
    {
        std::string content;
        std::weak_ptr<const CollisionModel> part;
    };
    static std::mutex mutex;
    static std::vector<Entry> entries;                              // every part some model may hold
    static std::deque<std::shared_ptr<const CollisionModel>> kept;  // the last used, newest first
    std::string content = contentBytes(robot);
    // Makes \a part the newest kept; the oldest beyond kKeptRobotParts are let go.
    auto keep = [&](const std::shared_ptr<const CollisionModel> &part)
    {
        kept.erase(std::remove(kept.begin(), kept.end(), part), kept.end());
        kept.push_front(part);
        kept.resize(std::min(kept.size(), kKeptRobotParts));
        return part;
    };
    auto find = [&]() -> std::shared_ptr<const CollisionModel>
    {
        entries.erase(std::remove_if(entries.begin(), entries.end(), [](const Entry &e) { return e.part.expired(); }),
                      entries.end());
        for (const Entry &entry : entries)
            if (entry.content == content)
                if (std::shared_ptr<const CollisionModel> part = entry.part.lock())
                    return keep(part);
        return nullptr;
    };
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (std::shared_ptr<const CollisionModel> part = find())
            return part;
    }
    // Built outside the lock (seconds for a large robot); a model built meanwhile by another
    // thread for the same content wins, so that both share one.
    std::shared_ptr<const CollisionModel> built(
        new CollisionModel(std::make_shared<const RobotModel>(robot), RobotPartOnly{}));
    std::lock_guard<std::mutex> lock(mutex);
    if (std::shared_ptr<const CollisionModel> part = find())
        return part;
    entries.push_back(Entry{std::move(content), built});
    return keep(built);
}

int CollisionModel::firstInadmissibleCoordinate(const double *q) const
{
    const double epsilon = std::numeric_limits<double>::epsilon();
    for (std::size_t i = 0; i < boundedCoordinates.size(); ++i)
    {
        if (!std::isfinite(q[i]))
            return static_cast<int>(i);
        if (boundedCoordinates[i] && (q[i] - epsilon > robot->upperBounds[i] || q[i] + epsilon < robot->lowerBounds[i]))
            return static_cast<int>(i);
    }
    for (int start : quaternionStarts)
    {
        const double norm2 = q[start] * q[start] + q[start + 1] * q[start + 1] + q[start + 2] * q[start + 2] +
                             q[start + 3] * q[start + 3];
        if (!(norm2 > 1e-12))
            return start;
    }
    return -1;
}

void CollisionModel::nameParties(std::uint32_t pair, Contact &contact) const
{
    const std::size_t environmentPairs = numObjects() * numComponents();
    if (pair < environmentPairs)
    {
        contact.kind = Contact::Kind::Environment;
        contact.object = static_cast<int>(pair / numComponents());
        contact.component = static_cast<int>(pair % numComponents());
        contact.otherComponent = -1;
        return;
    }
    const std::pair<int, int> &self = selfPairs.at(pair - environmentPairs);
    contact.kind = Contact::Kind::SelfCollision;
    contact.component = self.first;
    contact.otherComponent = self.second;
    contact.object = -1;
}

void appendPaddingRows(const CollisionModel &model, const PairPadding *own, const PairPadding *wider, std::size_t rows,
                       PairPadding &out)
{
    const std::size_t components = model.numComponents(), selfPairs = model.selfPairs.size();
    const std::size_t before = out.environment.empty() && out.self.empty() ? 0 : out.rows;
    out.environment.reserve(out.environment.size() + rows * components);
    out.self.reserve(out.self.size() + rows * selfPairs);
    for (std::size_t r = 0; r < rows; ++r)
    {
        const PairPaddings sum(model, 0.0, own, r, wider);
        for (std::size_t c = 0; c < components; ++c)
            out.environment.push_back(sum.component(c));
        for (std::size_t p = 0; p < selfPairs; ++p)
            out.self.push_back(sum.self(p));
    }
    out.rows = before + rows;
}
}  // namespace rastercheck
