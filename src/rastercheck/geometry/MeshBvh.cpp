#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/MeshTopology.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <Eigen/Eigenvalues>

#include "rastercheck/core/Error.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/geometry/TriangleTests.h"

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;
using CornersMap = Eigen::Map<const Vec>;

// Separating-axis test (Gottschalk's 15 axes) of a fixed-tree node's box against a moving-tree
// node's box placed in the fixed frame (its axes the columns of P, its centre at `between` from the
// fixed box's centre): false when some axis shows a gap wider than reach. Lazy: the fixed box's
// face axes first, one row of the relative rotation at a time (on FCL's env/rob, 73 % of the
// rejections come from those three axes), and a moving box whose centre lies in the fixed box
// meets it without further test. The cross-product axes are not normalised; their length is at
// most 1, so comparing their projected gap against the full reach only keeps more pairs.
bool boxesMayMeet(const MeshBvh::Node &nf, const Eigen::Matrix3d &P, const MeshBvh::Node &nm, const Vec &between,
                  double reach)
{
    const float *f = nf.axes;  // row-major: the fixed box's axis i is (f[i], f[3 + i], f[6 + i])
    const double ea[3] = {nf.halfExtents[0], nf.halfExtents[1], nf.halfExtents[2]};
    const double eb[3] = {nm.halfExtents[0], nm.halfExtents[1], nm.halfExtents[2]};
    double d[3];
    for (int i = 0; i < 3; ++i)
        d[i] = f[i] * between[0] + f[3 + i] * between[1] + f[6 + i] * between[2];
    if (std::abs(d[0]) <= ea[0] && std::abs(d[1]) <= ea[1] && std::abs(d[2]) <= ea[2])
        return true;
    const double *p = P.data();  // column-major: the moving box's axis j is p[3j .. 3j + 2]
    double R[3][3], Q[3][3];     // R(i, j) = axis i of the fixed box . axis j of the moving box; Q = |R|
    for (int i = 0; i < 3; ++i)
    {
        const double a0 = f[i], a1 = f[3 + i], a2 = f[6 + i];
        for (int j = 0; j < 3; ++j)
        {
            R[i][j] = a0 * p[3 * j] + a1 * p[3 * j + 1] + a2 * p[3 * j + 2];
            Q[i][j] = std::abs(R[i][j]);
        }
        if (std::abs(d[i]) > ea[i] + Q[i][0] * eb[0] + Q[i][1] * eb[1] + Q[i][2] * eb[2] + reach)
            return false;
    }
    for (int j = 0; j < 3; ++j)
        if (std::abs(d[0] * R[0][j] + d[1] * R[1][j] + d[2] * R[2][j]) >
            ea[0] * Q[0][j] + ea[1] * Q[1][j] + ea[2] * Q[2][j] + eb[j] + reach)
            return false;
    for (int i = 0; i < 3; ++i)
    {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j)
        {
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const double gap = std::abs(d[i2] * R[i1][j] - d[i1] * R[i2][j]);
            const double radii = ea[i1] * Q[i2][j] + ea[i2] * Q[i1][j] + eb[j1] * Q[i][j2] + eb[j2] * Q[i][j1];
            if (gap > radii + reach)
                return false;
        }
    }
    return true;
}

// What the float storage of the nodes may be off by, as a fraction of the coordinates'
// magnitude: their axes depart from orthonormal by a few float ulps (about 1e-7), so a corner may
// sit that fraction of the node's size outside its stored box. Ten times that is the slack every
// node test adds; it only keeps more pairs.
constexpr double kNodeRounding = 1e-6;

// Levels of the tree split by the surface area heuristic (the rest at the median): 24 +
// log2(2^31) stays below MeshBvh::kMaxDepth. And the bins it weighs cuts between (32 gave up to 3 %
// fewer node pairs on OMPL.app's scenes, 5 % on the 1e5-triangle terrain).
constexpr int kSahLevels = 24;
constexpr int kSahBins = 16;

float roundedUp(double x)
{
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x)
        f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

// A magnitude of a tree's coordinates: its root's radius plus its distance from the origin.
double treeScale(const MeshBvh &bvh)
{
    const MeshBvh::Node &root = bvh.nodes()[0];
    return root.radius + nodeCentre(root).norm();
}
// pointInsideClosedMesh() without the inside grid: device::pointInsideTree.
bool insideByRays(const MeshBvh &bvh, const Vec &point)
{
    if (bvh.empty())
        return false;
    const MeshBvh::Node &root = bvh.nodes()[0];
    // Large against the rounding of the ray/triangle arithmetic (1e-16 of these magnitudes), small
    // against any feature a mesh is meant to resolve.
    const double tolerance = 1e-9 * (2.0 * root.radius + (point - nodeCentre(root)).norm());
    const double margin = tolerance + kNodeRounding * (treeScale(bvh) + point.norm());
    if (!nodeContains(root, point, margin))
        return false;
    return device::pointInsideTree(bvh.view(), bvh.slotCorners(0), {point.x(), point.y(), point.z()}, tolerance,
                                   margin);
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

std::size_t MeshBvh::bytes() const
{
    return numNodes_ * sizeof(Node) + mesh_->triangles.size() * sizeof(std::uint32_t) +
           9 * mesh_->triangles.size() * sizeof(double) + numGridCells_;
}

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
            if (v >= mesh.vertices.size())
                throw ConfigurationError("MeshBvh: triangle " + std::to_string(i) + " names vertex " +
                                         std::to_string(v) + " of " + std::to_string(mesh.vertices.size()));
        const Mesh::Triangle &t = mesh.triangles[i];
        centroids[i] = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0;
    }
    ownTriangleOrder_.resize(n);
    std::iota(ownTriangleOrder_.begin(), ownTriangleOrder_.end(), 0u);
    const unsigned leafSize = std::max(1u, maxLeafTriangles);
    ownNodes_.reserve(2 * (n / leafSize + 1));
    ownNodes_.emplace_back();
    depth_ = build(0, static_cast<std::uint32_t>(n), 0, 0, centroids, leafSize);
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
    for (std::size_t shell = 0; shell < shells; ++shell)
    {
        const std::size_t begin = shellProbes_.size();
        shellProbes_.push_back(firstVertex[shell]);
        for (std::uint32_t v : extremes[shell])
            if (std::find(shellProbes_.begin() + static_cast<std::ptrdiff_t>(begin), shellProbes_.end(), v) ==
                shellProbes_.end())
                shellProbes_.push_back(v);
        shellProbeStart_.push_back(static_cast<std::uint32_t>(shellProbes_.size()));
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
    const double margin = kNodeRounding * (treeScale(*this) + std::max(lower.norm(), upper.norm()));
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
        const std::uint8_t answer = insideByRays(*this, centre) ? 2 : 1;
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
    if (numGridCells_ == 0)
        return 0;
    int cell[3];
    for (int k = 0; k < 3; ++k)
    {
        const double at = (point[k] - gridLower_[k]) * gridInverseCell_[k];
        // Beyond the grid (grown past every vertex) is outside; NaN is too, as the ray would say.
        if (!(at >= 0.0 && at < gridSize_[k]))
            return 1;
        cell[k] = static_cast<int>(at);
    }
    return gridCells_[(static_cast<std::size_t>(cell[2]) * gridSize_[1] + cell[1]) * gridSize_[0] + cell[0]];
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

int MeshBvh::build(std::uint32_t begin, std::uint32_t end, std::int32_t node, int level, std::vector<Vec> &centroids,
                   unsigned maxLeafTriangles)
{
    // The box: principal axes of the corners' covariance, rounded to float first, then the
    // centre and extents about those axes (rounded outwards), so the stored box holds every corner.
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
    Node &box = ownNodes_[node];
    Eigen::Matrix3d axes = solver.info() == Eigen::Success ? solver.eigenvectors() : Eigen::Matrix3d::Identity();
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
    const auto child = static_cast<std::int32_t>(ownNodes_.size());
    ownNodes_.emplace_back();
    ownNodes_.emplace_back();
    ownNodes_[node].first = child;
    ownNodes_[node].count = 0;
    const int left = build(begin, middle, child, level + 1, centroids, maxLeafTriangles);
    const int right = build(middle, end, child + 1, level + 1, centroids, maxLeafTriangles);
    return 1 + std::max(left, right);
}

namespace
{
using PlacedNode = ExactWorkspace::PlacedNode;
using LeafHint = ExactWorkspace::LeafHint;

LeafHint &leafHint(ExactWorkspace &workspace, const MeshBvh &fixed, const MeshBvh &moving)
{
    const auto key = reinterpret_cast<std::uintptr_t>(&fixed) * 0x9E3779B97F4A7C15ull ^
                     reinterpret_cast<std::uintptr_t>(&moving) * 0xC2B2AE3D27D4EB4Full;
    return workspace.hints[(key >> 32) % ExactWorkspace::kLeafHints];
}

// The exact phase's query for device::walkPairs, with `fixed`'s frame as the working frame and
// `moving` placed there by R, T: bounding spheres, then boxesMayMeet(), both grown by `reach`;
// leaf pairs by the triangle tests, in the order (a, b) of the caller (`movingIsA` says which tree
// is A). Stops at the first contact.
struct ExactQuery
{
    const MeshBvh &fixed, &moving;
    const MeshBvh::Node *nodesF, *nodesM;
    Eigen::Matrix3d R;
    Vec T;
    bool movingIsA;
    double padding, reach;
    ExactWorkspace *workspace;  // null: nodes placed per visit, no hint
    bool cached;                // the moving tree's placed nodes are kept in the workspace
    LeafHint *hint;
    Vec *point;  // receives the contact's point (working frame)
    PlacedNode scratch{};
    Vec between = Vec::Zero();  // of the pair last tested: the moving node's centre less the fixed one's
    double nearestGap = std::numeric_limits<double>::infinity();
    std::uint32_t slotFixed = 0, slotMoving = 0;

    const PlacedNode &placed(std::int32_t index)
    {
        PlacedNode &slot = cached ? workspace->placed[index] : scratch;
        if (!cached || workspace->stamps[index] != workspace->query)
        {
            slot.axes = R * nodeAxes(nodesM[index]);
            slot.centre = R * nodeCentre(nodesM[index]) + T;
            if (cached)
                workspace->stamps[index] = workspace->query;
        }
        return slot;
    }

    // The moving tree's triangle in slot sm, placed in the working frame.
    void place(std::uint32_t sm, Vec placedTriangle[3]) const
    {
        const double *cm = moving.slotCorners(sm);
        for (int k = 0; k < 3; ++k)
            placedTriangle[k] = R * CornersMap(cm + 3 * k) + T;
    }

    bool triangles(std::uint32_t sf, const Vec placedTriangle[3])
    {
        const double *cf = fixed.slotCorners(sf);
        const Vec fixedTriangle[3] = {CornersMap(cf), CornersMap(cf + 3), CornersMap(cf + 6)};
        const Vec *ta = movingIsA ? placedTriangle : fixedTriangle, *tb = movingIsA ? fixedTriangle : placedTriangle;
        return padding > 0.0 ? trianglesWithin(ta[0], ta[1], ta[2], tb[0], tb[1], tb[2], padding, point)
                             : trianglesIntersect(ta[0], ta[1], ta[2], tb[0], tb[1], tb[2], point);
    }

    void remember(std::uint32_t sf, std::uint32_t sm)
    {
        if (!hint)
            return;
        hint->fixed = &fixed;
        hint->moving = &moving;
        hint->slotFixed = sf;
        hint->slotMoving = sm;
    }

    bool test(device::NodePair pair)
    {
        const MeshBvh::Node &nf = nodesF[pair.a], &nm = nodesM[pair.b];
        const PlacedNode &pm = placed(pair.b);
        // Bounding spheres first: they settle most pairs that are far apart for one dot product.
        between = pm.centre - nodeCentre(nf);
        const double spheres = static_cast<double>(nf.radius) + nm.radius + reach;
        if (between.squaredNorm() > spheres * spheres)
            return false;
        return boxesMayMeet(nf, pm.axes, nm, between, reach);
    }

    bool leaves(device::NodePair pair)
    {
        const MeshBvh::Node &nf = nodesF[pair.a], &nm = nodesM[pair.b];
        Vec placedTriangle[3];
        for (std::uint32_t sm = nm.firstSlot(); sm < nm.firstSlot() + nm.count; ++sm)
        {
            place(sm, placedTriangle);
            for (std::uint32_t sf = nf.firstSlot(); sf < nf.firstSlot() + nf.count; ++sf)
                if (triangles(sf, placedTriangle))
                {
                    remember(sf, sm);
                    slotFixed = sf;
                    slotMoving = sm;
                    return false;
                }
        }
        const double gap = std::sqrt(between.squaredNorm()) - (static_cast<double>(nf.radius) + nm.radius);
        if (gap < nearestGap)
        {
            nearestGap = gap;
            remember(nf.firstSlot(), nm.firstSlot());
        }
        return true;
    }

    // Descend into the bigger node, so both trees shrink at a similar pace.
    bool splitA(device::NodePair pair) const { return nodesF[pair.a].radius >= nodesM[pair.b].radius; }

    // The child nearer the other node first: in a colliding state the contact is more likely
    // there, and the walk stops at the first one.
    bool secondFirst(device::NodePair first, device::NodePair second)
    {
        if (first.a != second.a)
        {
            const Vec centre = placed(first.b).centre;
            return (nodeCentre(nodesF[second.a]) - centre).squaredNorm() <
                   (nodeCentre(nodesF[first.a]) - centre).squaredNorm();
        }
        // One at a time: placed() may hand back the same scratch node for both.
        const Vec fixedCentre = nodeCentre(nodesF[first.a]);
        const double toSecond = (placed(second.b).centre - fixedCentre).squaredNorm();
        return toSecond < (placed(first.b).centre - fixedCentre).squaredNorm();
    }
};

// The query's outcome: no contact, a contact (slots set), or a walk its stack could not hold.
enum class Traversal
{
    Apart,
    Contact,
    Overflow
};

Traversal traverse(const MeshBvh &fixed, const MeshBvh &moving, const Eigen::Isometry3d &fMm, bool movingIsA,
                   double padding, double reach, bool useHint, ExactWorkspace *workspace, Vec *point,
                   std::uint32_t *slotFixed, std::uint32_t *slotMoving)
{
    const bool cached = workspace && moving.numNodes() <= ExactWorkspace::kMaxPlacedNodes;
    if (cached)
    {
        if (workspace->stamps.size() < moving.numNodes())
        {
            workspace->placed.resize(moving.numNodes());
            workspace->stamps.resize(moving.numNodes(), 0);
        }
        if (++workspace->query == 0)  // the stamps wrapped: forget them all
        {
            std::fill(workspace->stamps.begin(), workspace->stamps.end(), 0);
            workspace->query = 1;
        }
    }
    ExactQuery query{fixed,
                     moving,
                     fixed.nodes(),
                     moving.nodes(),
                     fMm.linear(),
                     fMm.translation(),
                     movingIsA,
                     padding,
                     reach,
                     workspace,
                     cached,
                     workspace ? &leafHint(*workspace, fixed, moving) : nullptr,
                     point};
    const LeafHint *hint = query.hint;
    Vec placedTriangle[3];
    if (useHint && hint && hint->fixed == &fixed && hint->moving == &moving &&
        hint->slotFixed < fixed.mesh().triangles.size() && hint->slotMoving < moving.mesh().triangles.size() &&
        (query.place(hint->slotMoving, placedTriangle), query.triangles(hint->slotFixed, placedTriangle)))
    {
        *slotFixed = hint->slotFixed;
        *slotMoving = hint->slotMoving;
        return Traversal::Contact;
    }
    const device::WalkEnd end = device::walkPairs(fixed.nodes(), moving.nodes(), query);
    if (end == device::WalkEnd::Finished)
        return Traversal::Apart;
    *slotFixed = query.slotFixed;
    *slotMoving = query.slotMoving;
    return end == device::WalkEnd::Stopped ? Traversal::Contact : Traversal::Overflow;
}
}  // namespace

bool surfacesWithin(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                    double padding, MeshContact *contact, ExactWorkspace *workspace)
{
    if (a.empty() || b.empty())
        return false;
    padding = std::max(0.0, padding);
    // The tree with fewer nodes is the one moved (its nodes placed once per query); the other's
    // frame is the working frame, where the moved tree's triangles are placed by one transform
    // before the exact tests.
    const bool movingIsA = a.numNodes() <= b.numNodes();
    const MeshBvh &fixed = movingIsA ? b : a, &moving = movingIsA ? a : b;
    const Eigen::Isometry3d &fixedPose = movingIsA ? poseB : poseA, &movingPose = movingIsA ? poseA : poseB;
    const Eigen::Isometry3d fMm = fixedPose.inverse(Eigen::Isometry) * movingPose;
    // The node tests must never drop a pair the triangle test would accept: the slack covers the
    // nodes' float storage (kNodeRounding) and the rounding of the transform and the projections.
    const double reach = padding + kNodeRounding * (fMm.translation().norm() + treeScale(a) + treeScale(b));
    Vec point;
    std::uint32_t slotFixed = 0, slotMoving = 0;
    // A caller that asks for the contact gets the walk's own first one, independent of what this
    // workspace asked before (the backends promise the same first contacts); the others may start
    // from the remembered leaf pair.
    const Traversal outcome = traverse(fixed, moving, fMm, movingIsA, padding, reach, contact == nullptr, workspace,
                                       &point, &slotFixed, &slotMoving);
    if (outcome == Traversal::Apart)
        return false;
    if (contact && outcome == Traversal::Overflow)  // the safe answer, with no triangle to name
    {
        contact->position = fixedPose * nodeCentre(fixed.nodes()[0]);
        contact->triangleA = -1;
        contact->triangleB = -1;
    }
    else if (contact)
    {
        contact->position = fixedPose * point;
        const std::int32_t triangleFixed = static_cast<std::int32_t>(fixed.triangleOrder()[slotFixed]);
        const std::int32_t triangleMoving = static_cast<std::int32_t>(moving.triangleOrder()[slotMoving]);
        contact->triangleA = movingIsA ? triangleMoving : triangleFixed;
        contact->triangleB = movingIsA ? triangleFixed : triangleMoving;
    }
    return true;
}

bool pointInsideClosedMesh(const MeshBvh &bvh, const Vec &point)
{
    const int known = bvh.insideGridAnswer(point);
    return known != 0 ? known == 2 : insideByRays(bvh, point);
}

bool solidsOverlap(const MeshBvh &a, const Eigen::Isometry3d &poseA, bool closedA, const MeshBvh &b,
                   const Eigen::Isometry3d &poseB, bool closedB, double padding, MeshContact *contact,
                   ExactWorkspace *workspace)
{
    if (surfacesWithin(a, poseA, b, poseB, padding, contact, workspace))
        return true;
    if (a.empty() || b.empty())
        return false;
    // The surfaces do not meet, so each shell of one solid lies wholly inside or wholly outside
    // the other: any one vertex of a shell tells which. The first probe the outer mesh's inside
    // grid knows answers; a ray is cast only when it knows none (near-contact states of OMPL.app's
    // Home: 80 % of the free states needed a ray from the first vertex alone, 9 % with the probes).
    const auto containedIn = [contact](const MeshBvh &inner, const Eigen::Isometry3d &innerPose, const MeshBvh &outer,
                                       const Eigen::Isometry3d &outerPose)
    {
        const Eigen::Isometry3d innerToOuter = outerPose.inverse(Eigen::Isometry) * innerPose;
        const std::uint32_t *probes = inner.shellProbes(), *start = inner.shellProbeStart();
        for (std::size_t shell = 0; shell < inner.numShells(); ++shell)
        {
            int known = 0;
            Vec vertex;
            for (std::uint32_t k = start[shell]; k < start[shell + 1]; ++k)
            {
                vertex = inner.mesh().vertices[probes[k]];
                known = outer.insideGridAnswer(innerToOuter * vertex);
                if (known != 0)
                    break;
            }
            if (known == 0)
                vertex = inner.mesh().vertices[probes[start[shell]]];
            if (known == 0 ? !insideByRays(outer, innerToOuter * vertex) : known == 1)
                continue;
            if (contact)
            {
                contact->position = innerPose * vertex;
                contact->triangleA = -1;
                contact->triangleB = -1;
            }
            return true;
        }
        return false;
    };
    return (closedB && containedIn(a, poseA, b, poseB)) || (closedA && containedIn(b, poseB, a, poseA));
}
}  // namespace rastercheck
