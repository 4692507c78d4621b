#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/MeshTopology.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <Eigen/Eigenvalues>
#include <omp.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Parallel.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/geometry/BoxFit.h"
#include "rastercheck/geometry/EigenDevice.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;
using CornersMap = Eigen::Map<const Vec>;
using device::kNodeRounding;

// Levels of the tree split by the surface area heuristic (the rest at the median): 24 +
// log2(2^31) stays below MeshBvh::kMaxDepth. And the bins it weighs cuts between (32 gave up to 3 %
// fewer node pairs on OMPL.app's scenes, 5 % on the 1e5-triangle terrain).
constexpr int kSahLevels = 24;
constexpr int kSahBins = 16;

// A node's box is fitted along the frame of least surface area (leastAreaAxes) among the principal
// axes of the corners' covariance (FCL's OBB fit) and the frames about each of these normals: those
// axes, the mesh's axes (architectural models and OMPL.app's scenes are mostly built along them)
// and the normals of up to kFitTriangleNormals of the node's triangles (appendFitNormals).
// Tighter boxes keep fewer node pairs in every walk: against the principal axes alone, distance
// queries per core 17-44 % faster on OMPL.app's scenes and the Panda (bench/distance), collision
// queries near contact 1.2x-1.9x (bench/meshes).
//
// Above kFitCorners corners a node is fitted to its extreme corners (ExtremePoints), below to all
// its vertices (192 against 48: distance queries per core 2-8 % faster on OMPL.app's bugtrap,
// alpha-1.5, Easy and spirelli, the 1e6-triangle terrain's build 6.9 -> 7.1 s; 768: bugtrap 25 ->
// 30 us).
constexpr std::size_t kFitCorners = 192;

float roundedUp(double x)
{
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x)
        f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

// The caller's workspace for a query of a and b: the tree with fewer nodes is the one moved.
device::ExactScratch lend(ExactWorkspace *workspace, const MeshBvh &a, const MeshBvh &b)
{
    return workspace ? workspace->lend(std::min(a.numNodes(), b.numNodes())) : device::ExactScratch{};
}

MeshContact fromDevice(const device::ExactContact &c)
{
    MeshContact contact;
    contact.position = Vec(c.position.x, c.position.y, c.position.z);
    contact.triangleA = c.triangleA;
    contact.triangleB = c.triangleB;
    return contact;
}
}  // namespace

Eigen::Matrix3d nodeAxes(const MeshBvh::Node &node)
{
    const float *a = node.axes;
    Eigen::Matrix3d m;
    m << a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8];
    return m;
}

Eigen::Vector3d nodeCentre(const MeshBvh::Node &node)
{
    return {node.centre[0], node.centre[1], node.centre[2]};
}

Eigen::Vector3d nodeExtents(const MeshBvh::Node &node)
{
    return {node.halfExtents[0], node.halfExtents[1], node.halfExtents[2]};
}

bool nodeContains(const MeshBvh::Node &node, const Eigen::Vector3d &p, double margin)
{
    const Vec local = nodeAxes(node).transpose() * (p - nodeCentre(node));
    return (local.array().abs() <= nodeExtents(node).array() + margin).all();
}

void MeshBvh::useSharedArrays(const Arrays &arrays)
{
    nodes_ = arrays.nodes;
    triangleOrder_ = arrays.triangleOrder;
    corners_ = arrays.corners;
    gridCells_ = arrays.gridCells;
    ownNodes_ = {};
    ownTriangleOrder_ = {};
    ownCorners_ = {};
    ownGridCells_ = {};
}

std::vector<MeshBvh::SlotRange> MeshBvh::nodeSlotRanges() const
{
    // Children come after their parent in the array (build() appends them), so one pass from the
    // last node up has both children's ranges ready at every inner node.
    std::vector<SlotRange> ranges(numNodes_);
    for (std::size_t i = numNodes_; i-- > 0;)
    {
        const Node &node = nodes_[i];
        ranges[i] = node.isLeaf() ? SlotRange{node.firstSlot(), node.firstSlot() + node.count}
                                  : SlotRange{ranges[node.first].begin, ranges[node.first + 1].end};
    }
    return ranges;
}

std::size_t MeshBvh::bytes() const
{
    return numNodes_ * sizeof(Node) + mesh_->triangles.size() * sizeof(std::uint32_t) +
           9 * mesh_->triangles.size() * sizeof(double) + numGridCells_;
}

/** \brief What build() reads and reuses across the nodes: the triangles' centroids and the frame
    fit's scratch. */
struct MeshBvh::BuildScratch
{
    const std::vector<Vec> *centroids = nullptr;  // per triangle (mesh order), shared by the threads
    std::vector<Vec> fitPoints, fitNormals;
    std::vector<std::uint32_t> fitVertices;
    BoxFitScratch fit;
};

MeshBvh::MeshBvh(const Mesh &mesh, unsigned maxLeafTriangles, bool insideGrid) : mesh_(&mesh)
{
    const std::size_t n = mesh.triangles.size();
    if (n == 0)
        return;
    if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 2))
        throw ConfigurationError("MeshBvh: " + std::to_string(n) + " triangles exceed the index range");
    std::vector<Vec> centroids(n);
    for (std::size_t i = 0; i < n; ++i)
    {
        for (std::uint32_t v : mesh.triangles[i])
        {
            if (v >= mesh.vertices.size())
                throw ConfigurationError("MeshBvh: triangle " + std::to_string(i) + " names vertex " +
                                         std::to_string(v) + " of " + std::to_string(mesh.vertices.size()));
            // The splits and fits sort by coordinates, which a NaN would leave unordered.
            if (!mesh.vertices[v].allFinite())
                throw ConfigurationError("MeshBvh: triangle " + std::to_string(i) + " has vertex " + std::to_string(v) +
                                         " at a coordinate that is not finite");
        }
        const Mesh::Triangle &t = mesh.triangles[i];
        centroids[i] = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0;
    }
    ownTriangleOrder_.resize(n);
    std::iota(ownTriangleOrder_.begin(), ownTriangleOrder_.end(), 0u);
    const unsigned leafSize = std::max(1u, maxLeafTriangles);
    BuildScratch scratch;
    scratch.centroids = &centroids;
    // A large mesh (a site, a terrain) on every thread: the upper levels here, the subtrees below
    // them as jobs (about 8 per thread), then laid out as this thread alone would have (the same
    // nodes in the same order). Not within another parallel region (a model's meshes already
    // build side by side there).
    const int threads = omp_in_parallel() ? 1 : omp_get_max_threads();
    const std::uint32_t jobTriangles =
        threads > 1 && n > 2 * kMinJobTriangles
            ? static_cast<std::uint32_t>(std::max<std::size_t>(kMinJobTriangles, n / (8 * threads)))
            : 0;
    std::vector<BuildJob> jobs;
    std::vector<Node> upper;
    upper.reserve(jobTriangles > 0 ? 4 * (n / jobTriangles + 1) : 2 * (n / leafSize + 1));
    upper.emplace_back();
    depth_ = build(0, static_cast<std::uint32_t>(n), upper, 0, 0, scratch, leafSize, jobTriangles,
                   jobTriangles > 0 ? &jobs : nullptr);
    if (jobs.empty())
        ownNodes_ = std::move(upper);
    else
    {
        std::vector<std::vector<Node>> subtrees(jobs.size());
        parallelFor(jobs.size(),
                    [&](std::size_t j)
                    {
                        BuildScratch own;
                        own.centroids = &centroids;
                        subtrees[j].reserve(2 * ((jobs[j].end - jobs[j].begin) / leafSize + 1));
                        subtrees[j].emplace_back();
                        build(jobs[j].begin, jobs[j].end, subtrees[j], 0, jobs[j].level, own, leafSize);
                    });
        layOutDepthFirst(upper, jobs, subtrees);
    }
    ownNodes_.shrink_to_fit();
    nodes_ = ownNodes_.data();
    numNodes_ = ownNodes_.size();
    triangleOrder_ = ownTriangleOrder_.data();
    if (depth_ > kMaxDepth)  // cannot happen for a median split of fewer than 2^31 triangles
        throw ConfigurationError("MeshBvh: tree depth " + std::to_string(depth_) + " exceeds the query stacks");
    // Containment probes per connected shell: its first vertex, then its extreme vertices along
    // the six axis directions (spread out, so that some lie far from wherever the other mesh is near).
    std::size_t shells = 0;
    const std::vector<std::uint32_t> shellOf = triangleShells(mesh, shells);
    constexpr std::uint32_t kNone = ~0u;
    std::vector<std::uint32_t> firstVertex(shells, kNone);
    std::vector<std::array<std::uint32_t, 6>> extremes(shells);
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t v : mesh.triangles[i])
        {
            std::array<std::uint32_t, 6> &extreme = extremes[shellOf[i]];
            if (firstVertex[shellOf[i]] == kNone)
            {
                firstVertex[shellOf[i]] = v;
                extreme.fill(v);
            }
            for (int k = 0; k < 3; ++k)
            {
                if (mesh.vertices[v][k] < mesh.vertices[extreme[2 * k]][k])
                    extreme[2 * k] = v;
                if (mesh.vertices[v][k] > mesh.vertices[extreme[2 * k + 1]][k])
                    extreme[2 * k + 1] = v;
            }
        }
    std::vector<std::uint32_t> probes;
    for (std::size_t shell = 0; shell < shells; ++shell)
    {
        probes.assign(1, firstVertex[shell]);
        for (std::uint32_t v : extremes[shell])
            if (std::find(probes.begin(), probes.end(), v) == probes.end())
                probes.push_back(v);
        for (std::uint32_t v : probes)
            shellProbePoints_.insert(shellProbePoints_.end(), mesh.vertices[v].data(), mesh.vertices[v].data() + 3);
        shellProbeStart_.push_back(static_cast<std::uint32_t>(shellProbePoints_.size() / 3));
    }
    ownCorners_.resize(9 * n);
    for (std::size_t slot = 0; slot < n; ++slot)
    {
        const Mesh::Triangle &t = mesh.triangles[ownTriangleOrder_[slot]];
        for (int k = 0; k < 3; ++k)
            std::copy(mesh.vertices[t[k]].data(), mesh.vertices[t[k]].data() + 3,
                      ownCorners_.data() + 9 * slot + 3 * k);
    }
    corners_ = ownCorners_.data();
    if (insideGrid)
        buildInsideGrid();
}

void MeshBvh::buildInsideGrid()
{
    // About 64 cells per triangle, at least 16^3 and at most 2^21 (2 MB). With the shells' probes
    // (solidsOverlap) it took the rays cast on OMPL.app's Abstract (closed, 700 triangles) from 0.9
    // to below 0.001 per uniform state and from 1.0 to 0.002 per near-contact state.
    const std::size_t n = mesh_->triangles.size();
    const std::size_t wanted = std::clamp<std::size_t>(64 * n, 4096, std::size_t(1) << 21);
    Vec lower = Vec::Constant(std::numeric_limits<double>::infinity()), upper = -lower;
    for (std::size_t i = 0; i < 3 * n; ++i)
    {
        const CornersMap p(corners_ + 3 * i);
        lower = lower.cwiseMin(p);
        upper = upper.cwiseMax(p);
    }
    // Far above the rounding of a cell index or a plane distance (1e-16 of the coordinates), far
    // below any feature: a cell this close to a triangle is left to the ray.
    const double margin = kNodeRounding * (device::treeScale(exactTree()) + std::max(lower.norm(), upper.norm()));
    lower.array() -= 2.0 * margin;
    upper.array() += 2.0 * margin;
    const Vec size = upper - lower;
    // Flat meshes: thin extents count as 1/256 of the largest, so no axis gets more than about
    // 256 x the cells of the others and the total stays near `wanted`.
    const Vec counted = size.cwiseMax(size.maxCoeff() / 256.0);
    const double cell = std::cbrt(counted.prod() / static_cast<double>(wanted));
    if (!(cell > 0.0) || !std::isfinite(cell))
        return;  // a mesh of one point at the origin: nothing is inside it
    Vec cellSize;
    for (int k = 0; k < 3; ++k)
    {
        gridSize_[k] = std::clamp(static_cast<int>(std::ceil(size[k] / cell)), 1, 1024);
        cellSize[k] = size[k] / gridSize_[k];
        gridInverseCell_[k] = 1.0 / cellSize[k];
    }
    gridLower_ = lower;
    const int nx = gridSize_[0], ny = gridSize_[1], nz = gridSize_[2];
    const auto index = [nx, ny](int i, int j, int k) { return (static_cast<std::size_t>(k) * ny + j) * nx + i; };
    std::vector<std::uint8_t> touched(static_cast<std::size_t>(nx) * ny * nz, 0);
    // A cell is touched when a triangle's bounds, grown by the margin, meet it and the triangle's
    // plane passes within the margin of the cell's bounding sphere.
    const double halfDiagonal = 0.5 * cellSize.norm();
    for (std::size_t slot = 0; slot < n; ++slot)
    {
        const Vec t[3] = {CornersMap(slotCorners(static_cast<std::uint32_t>(slot))),
                          CornersMap(slotCorners(static_cast<std::uint32_t>(slot)) + 3),
                          CornersMap(slotCorners(static_cast<std::uint32_t>(slot)) + 6)};
        const Vec lo = t[0].cwiseMin(t[1]).cwiseMin(t[2]).array() - margin;
        const Vec hi = t[0].cwiseMax(t[1]).cwiseMax(t[2]).array() + margin;
        int first[3], last[3];
        for (int k = 0; k < 3; ++k)
        {
            first[k] =
                std::clamp(static_cast<int>(std::floor((lo[k] - lower[k]) * gridInverseCell_[k])), 0, gridSize_[k] - 1);
            last[k] =
                std::clamp(static_cast<int>(std::floor((hi[k] - lower[k]) * gridInverseCell_[k])), 0, gridSize_[k] - 1);
        }
        const Vec normal = (t[1] - t[0]).cross(t[2] - t[0]);
        const double reach = (halfDiagonal + margin) * normal.norm();
        for (int k = first[2]; k <= last[2]; ++k)
            for (int j = first[1]; j <= last[1]; ++j)
                for (int i = first[0]; i <= last[0]; ++i)
                {
                    const Vec centre = lower + cellSize.cwiseProduct(Vec(i + 0.5, j + 0.5, k + 0.5));
                    if (std::abs(normal.dot(centre - t[0])) <= reach)
                        touched[index(i, j, k)] = 1;
                }
    }
    // Face-adjacent untouched cells share a region: the segment between their centres stays in
    // their union, which no triangle meets. One ray per region, from a cell centre far from the
    // surface, classifies the whole region.
    ownGridCells_.assign(touched.size(), 0);
    std::vector<std::uint32_t> queue;
    for (std::size_t seed = 0; seed < touched.size(); ++seed)
    {
        if (touched[seed] || ownGridCells_[seed])
            continue;
        const int si = static_cast<int>(seed % nx), sj = static_cast<int>(seed / nx % ny),
                  sk = static_cast<int>(seed / nx / ny);
        const Vec centre = lower + cellSize.cwiseProduct(Vec(si + 0.5, sj + 0.5, sk + 0.5));
        const std::uint8_t answer = device::pointInsideClosedTree(exactTree(), toDevice(centre)) ? 2 : 1;
        ownGridCells_[seed] = answer;
        queue.assign(1, static_cast<std::uint32_t>(seed));
        while (!queue.empty())
        {
            const std::uint32_t c = queue.back();
            queue.pop_back();
            const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx % ny),
                      k = static_cast<int>(c / nx / ny);
            const int neighbours[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                                          {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
            for (const auto &m : neighbours)
            {
                if (m[0] < 0 || m[1] < 0 || m[2] < 0 || m[0] >= nx || m[1] >= ny || m[2] >= nz)
                    continue;
                const std::size_t next = index(m[0], m[1], m[2]);
                if (touched[next] || ownGridCells_[next])
                    continue;
                ownGridCells_[next] = answer;
                queue.push_back(static_cast<std::uint32_t>(next));
            }
        }
    }
    gridCells_ = ownGridCells_.data();
    numGridCells_ = ownGridCells_.size();
}

int MeshBvh::insideGridAnswer(const Eigen::Vector3d &point) const
{
    return device::insideGridAnswer(exactTree(), toDevice(point));
}

bool MeshBvh::sahSplit(std::uint32_t begin, std::uint32_t end, const Eigen::Matrix3d &axes,
                       const std::vector<Vec> &centroids, Vec &direction, double &cut) const
{
    struct Bin
    {
        Vec lower = Vec::Constant(std::numeric_limits<double>::infinity());
        Vec upper = Vec::Constant(-std::numeric_limits<double>::infinity());
        double triangles = 0.0;
        void add(const Bin &other)
        {
            lower = lower.cwiseMin(other.lower);
            upper = upper.cwiseMax(other.upper);
            triangles += other.triangles;
        }
        double cost() const
        {
            const Vec e = upper - lower;
            return (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]) * triangles;
        }
    };
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
    {
        const Vec along = axes.col(k);
        double low = std::numeric_limits<double>::infinity(), high = -low;
        for (std::uint32_t slot = begin; slot < end; ++slot)
        {
            const double c = along.dot(centroids[ownTriangleOrder_[slot]]);
            low = std::min(low, c);
            high = std::max(high, c);
        }
        if (!(high > low))
            continue;
        const double scale = kSahBins / (high - low);
        std::array<Bin, kSahBins> bins;
        for (std::uint32_t slot = begin; slot < end; ++slot)
        {
            const int b =
                std::min(kSahBins - 1, static_cast<int>((along.dot(centroids[ownTriangleOrder_[slot]]) - low) * scale));
            Bin &bin = bins[b];
            bin.triangles += 1.0;
            for (std::uint32_t v : mesh_->triangles[ownTriangleOrder_[slot]])
            {
                const Vec local = axes.transpose() * mesh_->vertices[v];
                bin.lower = bin.lower.cwiseMin(local);
                bin.upper = bin.upper.cwiseMax(local);
            }
        }
        // Cut b puts bins 0..b-1 on the left.
        std::array<double, kSahBins> leftCost{};
        Bin left;
        for (int b = 1; b < kSahBins; ++b)
        {
            left.add(bins[b - 1]);
            leftCost[b] = left.cost();
        }
        Bin right;
        for (int b = kSahBins - 1; b > 0; --b)
        {
            right.add(bins[b]);
            const double leftTriangles = static_cast<double>(end - begin) - right.triangles;
            if (right.triangles == 0.0 || leftTriangles == 0.0)
                continue;
            const double cost = leftCost[b] + right.cost();
            if (cost < best)
            {
                best = cost;
                direction = along;
                cut = low + b / scale;
            }
        }
    }
    return best < std::numeric_limits<double>::infinity();
}

Eigen::Matrix3d MeshBvh::fitAxes(std::uint32_t begin, std::uint32_t end, const Eigen::Matrix3d &principal,
                                 BuildScratch &scratch) const
{
    // The corners the frame is chosen by: a small node's vertices, each once (neighbouring triangles
    // share corners), or a large node's extreme corners.
    std::vector<Vec> &points = scratch.fitPoints;
    points.clear();
    if (3 * static_cast<std::size_t>(end - begin) <= kFitCorners)
    {
        std::vector<std::uint32_t> &vertices = scratch.fitVertices;
        vertices.clear();
        for (std::uint32_t slot = begin; slot < end; ++slot)
            for (std::uint32_t v : mesh_->triangles[ownTriangleOrder_[slot]])
                vertices.push_back(v);
        std::sort(vertices.begin(), vertices.end());
        vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
        for (std::uint32_t v : vertices)
            points.push_back(mesh_->vertices[v]);
    }
    else
    {
        ExtremePoints extremes;
        for (std::uint32_t slot = begin; slot < end; ++slot)
            for (std::uint32_t v : mesh_->triangles[ownTriangleOrder_[slot]])
                extremes.add(mesh_->vertices[v]);
        extremes.appendTo(points);
    }
    std::vector<Vec> &normals = scratch.fitNormals;
    normals.clear();
    appendFitNormals(
        principal, end - begin, [&](std::size_t i) { return mesh_->triangleNormal(ownTriangleOrder_[begin + i]); },
        normals);
    return leastAreaAxes(points, principal, normals, scratch.fit);
}

int MeshBvh::build(std::uint32_t begin, std::uint32_t end, std::vector<Node> &nodes, std::int32_t node, int level,
                   BuildScratch &scratch, unsigned maxLeafTriangles, std::uint32_t jobTriangles,
                   std::vector<BuildJob> *jobs)
{
    if (jobs && end - begin <= jobTriangles)
    {
        jobs->push_back(BuildJob{begin, end, node, level});
        return 0;
    }
    const std::vector<Vec> &centroids = *scratch.centroids;
    // The box: its axes fitted (fitAxes, starting from the principal axes of the corners'
    // covariance), rounded to float first, then the centre and extents about those axes (rounded
    // outwards), so the stored box holds every corner.
    const auto forEachCorner = [&](auto &&visit)
    {
        for (std::uint32_t slot = begin; slot < end; ++slot)
            for (std::uint32_t v : mesh_->triangles[ownTriangleOrder_[slot]])
                visit(mesh_->vertices[v]);
    };
    Vec mean = Vec::Zero();
    double corners = 0;
    forEachCorner([&](const Vec &p) { mean += p, corners += 1; });
    mean /= corners;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    forEachCorner([&](const Vec &p) { covariance += (p - mean) * (p - mean).transpose(); });
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Node &box = nodes[node];
    Eigen::Matrix3d axes = fitAxes(
        begin, end, solver.info() == Eigen::Success ? solver.eigenvectors() : Eigen::Matrix3d::Identity(), scratch);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            box.axes[3 * r + c] = static_cast<float>(axes(r, c));
    axes = nodeAxes(box);
    Vec lower = Vec::Constant(std::numeric_limits<double>::infinity()), upper = -lower;
    forEachCorner(
        [&](const Vec &p)
        {
            const Vec local = axes.transpose() * p;
            lower = lower.cwiseMin(local);
            upper = upper.cwiseMax(local);
        });
    const Vec centre = axes * (0.5 * (lower + upper));
    for (int k = 0; k < 3; ++k)
        box.centre[k] = static_cast<float>(centre[k]);
    Vec extents = Vec::Zero();
    double radius = 0.0;
    forEachCorner(
        [&](const Vec &p)
        {
            const Vec offset = p - nodeCentre(box);
            extents = extents.cwiseMax((axes.transpose() * offset).cwiseAbs());
            radius = std::max(radius, offset.norm());
        });
    for (int k = 0; k < 3; ++k)
        box.halfExtents[k] = roundedUp(extents[k]);
    box.radius = roundedUp(radius);

    const std::uint32_t count = end - begin;
    if (count <= maxLeafTriangles)
    {
        box.first = -static_cast<std::int32_t>(begin) - 1;
        box.count = count;
        return 0;
    }
    // For the first kSahLevels levels the split that the surface area heuristic prefers: of the
    // box's three axes and the kSahBins - 1 cuts between equal bins of the centroids along each,
    // the one whose children (boxes along this box's axes) have the least surface area times
    // triangles. Node pairs per query on FCL's env/rob, 20 000 uniform poses: 131 for the median
    // of the longest axis, 95 for its mean (FCL's rule; FCL's own traversal tests 103), 70 for the
    // mean of the best axis, 51 for this; per near-contact OMPL.app state, Apartment 437 (mean of
    // the longest axis) -> 163, Home 91 -> 51. Below, and where every centroid projects alike, the
    // median of the longest axis: it halves the triangles, which bounds the depth whatever the mesh.
    Vec axis;
    double cut = 0.0;
    std::uint32_t middle = begin;
    if (level < kSahLevels && sahSplit(begin, end, axes, centroids, axis, cut))
        middle = static_cast<std::uint32_t>(
            std::partition(ownTriangleOrder_.begin() + begin, ownTriangleOrder_.begin() + end,
                           [&](std::uint32_t i) { return axis.dot(centroids[i]) < cut; }) -
            ownTriangleOrder_.begin());
    if (middle == begin || middle == end)  // no cut, or a centroid rounded across it
    {
        int longest = 0;
        extents.maxCoeff(&longest);
        axis = axes.col(longest);
        middle = begin + count / 2;
        std::nth_element(ownTriangleOrder_.begin() + begin, ownTriangleOrder_.begin() + middle,
                         ownTriangleOrder_.begin() + end,
                         [&centroids, &axis](std::uint32_t i, std::uint32_t j)
                         { return axis.dot(centroids[i]) < axis.dot(centroids[j]); });
    }
    const auto child = static_cast<std::int32_t>(nodes.size());
    nodes.emplace_back();
    nodes.emplace_back();
    nodes[node].first = child;
    nodes[node].count = 0;
    const int left = build(begin, middle, nodes, child, level + 1, scratch, maxLeafTriangles, jobTriangles, jobs);
    const int right = build(middle, end, nodes, child + 1, level + 1, scratch, maxLeafTriangles, jobTriangles, jobs);
    return 1 + std::max(left, right);
}

void MeshBvh::layOutDepthFirst(const std::vector<Node> &upper, const std::vector<BuildJob> &jobs,
                               const std::vector<std::vector<Node>> &subtrees)
{
    std::vector<int> jobOf(upper.size(), -1);
    for (std::size_t j = 0; j < jobs.size(); ++j)
        jobOf[static_cast<std::size_t>(jobs[j].node)] = static_cast<int>(j);
    std::size_t total = upper.size() - jobs.size();
    for (const std::vector<Node> &subtree : subtrees)
        total += subtree.size();
    ownNodes_.clear();
    ownNodes_.reserve(total);
    ownNodes_.emplace_back();
    // Node \a index of \a from goes to slot \a at; a split appends its pair of children, then lays
    // out the first child's subtree, then the second's: build()'s own order.
    const auto place = [&](const auto &self, const std::vector<Node> *from, std::int32_t index, std::size_t at) -> void
    {
        if (from == &upper && jobOf[static_cast<std::size_t>(index)] >= 0)
        {
            from = &subtrees[static_cast<std::size_t>(jobOf[static_cast<std::size_t>(index)])];
            index = 0;
        }
        Node node = (*from)[static_cast<std::size_t>(index)];
        if (node.isLeaf())
        {
            ownNodes_[at] = node;
            return;
        }
        const std::int32_t children = node.first;
        node.first = static_cast<std::int32_t>(ownNodes_.size());
        ownNodes_[at] = node;
        ownNodes_.emplace_back();
        ownNodes_.emplace_back();
        self(self, from, children, static_cast<std::size_t>(node.first));
        self(self, from, children + 1, static_cast<std::size_t>(node.first) + 1);
    };
    place(place, &upper, 0, 0);
    // Heights from the leaves up: children come after their parent.
    std::vector<int> height(ownNodes_.size(), 0);
    for (std::size_t i = ownNodes_.size(); i-- > 0;)
        if (!ownNodes_[i].isLeaf())
            height[i] = 1 + std::max(height[static_cast<std::size_t>(ownNodes_[i].first)],
                                     height[static_cast<std::size_t>(ownNodes_[i].first) + 1]);
    depth_ = height[0];
}

device::ExactScratch ExactWorkspace::lend(std::size_t movingNodes)
{
    if (movingNodes <= kMaxPlacedNodes && stamps.size() < movingNodes)
    {
        placed.resize(movingNodes);
        stamps.resize(movingNodes, 0);
    }
    return device::ExactScratch{placed.data(), stamps.data(), stamps.size(), &query, hints.data(), hints.size()};
}

device::ExactTree MeshBvh::exactTree() const
{
    device::ExactTree t{};
    t.tree = view();
    t.numTriangles = static_cast<std::uint32_t>(mesh_->triangles.size());
    t.corners = corners_;
    for (int k = 0; k < 3; ++k)
    {
        t.grid.lower[k] = gridLower_[k];
        t.grid.inverseCell[k] = gridInverseCell_[k];
        t.grid.size[k] = gridSize_[k];
    }
    t.gridCells = numGridCells_ > 0 ? gridCells_ : nullptr;
    t.probePoints = shellProbePoints_.data();
    t.shellProbeStart = shellProbeStart_.data();
    t.numShells = static_cast<std::uint32_t>(numShells());
    return t;
}

bool surfacesWithin(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                    double padding, MeshContact *contact, ExactWorkspace *workspace)
{
    device::ExactScratch scratch = lend(workspace, a, b);
    device::ExactContact found;
    const bool within = device::surfacesWithin(a.exactTree(), toDevicePose(poseA), b.exactTree(), toDevicePose(poseB),
                                               padding, contact ? &found : nullptr, &scratch);
    if (within && contact)
        *contact = fromDevice(found);
    return within;
}

bool pointInsideClosedMesh(const MeshBvh &bvh, const Vec &point)
{
    return device::pointInsideClosedTree(bvh.exactTree(), toDevice(point));
}

bool solidsOverlap(const MeshBvh &a, const Eigen::Isometry3d &poseA, bool closedA, const MeshBvh &b,
                   const Eigen::Isometry3d &poseB, bool closedB, double padding, MeshContact *contact,
                   ExactWorkspace *workspace)
{
    device::ExactScratch scratch = lend(workspace, a, b);
    device::ExactContact found;
    const bool overlap =
        device::solidsOverlap(a.exactTree(), toDevicePose(poseA), closedA, b.exactTree(), toDevicePose(poseB), closedB,
                              padding, contact ? &found : nullptr, &scratch);
    if (overlap && contact)
        *contact = fromDevice(found);
    return overlap;
}
}  // namespace rastercheck
