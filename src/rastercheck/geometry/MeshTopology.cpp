#include "rastercheck/geometry/MeshTopology.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace rastercheck
{
std::string MeshTopology::summary() const
{
    if (closed)
        return "closed";
    std::string text = "open (";
    std::string separator;
    auto add = [&](std::size_t count, const char *what) {
        if (count == 0)
            return;
        text += separator + std::to_string(count) + " " + what;
        separator = ", ";
    };
    add(boundaryEdges, "boundary edges");
    add(nonManifoldEdges, "non-manifold edges");
    add(misorientedEdges, "misoriented edges");
    if (separator.empty())
        text += "no triangles";
    return text + ")";
}

std::vector<std::uint32_t> triangleShells(const Mesh &mesh, std::size_t &shells)
{
    // Union-find over vertices joined by triangles.
    std::vector<std::uint32_t> parent(mesh.vertices.size());
    for (std::uint32_t i = 0; i < parent.size(); ++i)
        parent[i] = i;
    auto root = [&](std::uint32_t i) {
        while (parent[i] != i)
            i = parent[i] = parent[parent[i]];
        return i;
    };
    for (const Mesh::Triangle &t : mesh.triangles)
        for (int k = 1; k < 3; ++k)
            parent[root(t[k])] = root(t[0]);
    std::map<std::uint32_t, std::uint32_t> shellOfRoot;
    std::vector<std::uint32_t> shellOf(mesh.triangles.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
        shellOf[i] = shellOfRoot.emplace(root(mesh.triangles[i][0]), static_cast<std::uint32_t>(shellOfRoot.size()))
                         .first->second;
    shells = shellOfRoot.size();
    return shellOf;
}

double signedVolume(const Mesh &mesh)
{
    double volume = 0.0;
    for (const Mesh::Triangle &t : mesh.triangles)
        volume += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]]));
    return volume / 6.0;
}

namespace
{
// Welds vertices that fall into the same cell of a grid of size `tolerance`, or a neighbouring
// cell with a distance below it. Returns the old-to-new index map.
std::vector<std::uint32_t> weldVertices(Mesh &mesh, double tolerance, std::size_t &merged)
{
    struct CellHash
    {
        // Unsigned: the products wrap, where signed ones would overflow (undefined) for cells far
        // from the origin (a scene object 6 km away, found by fuzz_scene).
        std::size_t operator()(const std::array<std::int64_t, 3> &c) const
        {
            return (static_cast<std::size_t>(c[0]) * 73856093u) ^ (static_cast<std::size_t>(c[1]) * 19349663u) ^
                   (static_cast<std::size_t>(c[2]) * 83492791u);
        }
    };
    const double cell = tolerance > 0 ? tolerance : 1e-12;
    // Cell coordinates are clamped so the conversion to an integer is defined (and key +- 1 cannot
    // overflow) for coordinates beyond 2^62 cells, or not finite; vertices in a clamped cell are
    // still welded only by their distance.
    auto cellOf = [cell](double coordinate)
    {
        constexpr double limit = 4611686018427387904.0;  // 2^62
        const double c = std::floor(coordinate / cell);
        return static_cast<std::int64_t>(c > -limit ? (c < limit ? c : limit) : -limit);
    };
    std::unordered_map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>, CellHash> grid;
    std::vector<Eigen::Vector3d> welded;
    std::vector<std::uint32_t> remap(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    {
        const Eigen::Vector3d &v = mesh.vertices[i];
        const std::array<std::int64_t, 3> key{cellOf(v.x()), cellOf(v.y()), cellOf(v.z())};
        long found = -1;
        for (int dx = -1; dx <= 1 && found < 0; ++dx)
            for (int dy = -1; dy <= 1 && found < 0; ++dy)
                for (int dz = -1; dz <= 1 && found < 0; ++dz)
                {
                    auto it = grid.find({key[0] + dx, key[1] + dy, key[2] + dz});
                    if (it == grid.end())
                        continue;
                    for (std::uint32_t candidate : it->second)
                        if ((welded[candidate] - v).norm() <= tolerance)
                        {
                            found = candidate;
                            break;
                        }
                }
        if (found >= 0)
        {
            remap[i] = static_cast<std::uint32_t>(found);
            ++merged;
            continue;
        }
        remap[i] = static_cast<std::uint32_t>(welded.size());
        grid[key].push_back(remap[i]);
        welded.push_back(v);
    }
    mesh.vertices = std::move(welded);
    return remap;
}
}  // namespace

MeshTopology cleanMesh(Mesh &mesh, double weldTolerance)
{
    MeshTopology topology;
    const std::vector<std::uint32_t> remap = weldVertices(mesh, weldTolerance, topology.mergedVertices);

    // Drop degenerate triangles and duplicate faces (same vertex set, either orientation).
    std::vector<Mesh::Triangle> kept;
    kept.reserve(mesh.triangles.size());
    std::map<std::array<std::uint32_t, 3>, std::size_t> seen;
    for (const Mesh::Triangle &original : mesh.triangles)
    {
        const Mesh::Triangle t{remap[original[0]], remap[original[1]], remap[original[2]]};
        const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (b - a).cross(c - a).squaredNorm() == 0.0)
        {
            ++topology.degenerateTriangles;
            continue;
        }
        std::array<std::uint32_t, 3> key = t;
        std::sort(key.begin(), key.end());
        if (!seen.emplace(key, kept.size()).second)
        {
            ++topology.removedDuplicateFaces;
            continue;
        }
        kept.push_back(t);
    }
    mesh.triangles = std::move(kept);

    // Edge use: each undirected edge should be used twice, once in each direction.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> edges;  // (forward, backward) uses
    for (const Mesh::Triangle &t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
        {
            const std::uint32_t a = t[k], b = t[(k + 1) % 3];
            auto &use = edges[{std::min(a, b), std::max(a, b)}];
            (a < b ? use.first : use.second) += 1;
        }
    for (const auto &[edge, use] : edges)
    {
        const int total = use.first + use.second;
        if (total == 1)
            ++topology.boundaryEdges;
        else if (total > 2)
            ++topology.nonManifoldEdges;
        else if (use.first != 1)
            ++topology.misorientedEdges;
    }
    topology.closed = !mesh.triangles.empty() && topology.boundaryEdges == 0 && topology.nonManifoldEdges == 0 &&
                      topology.misorientedEdges == 0;

    const std::vector<std::uint32_t> shellOfTriangle = triangleShells(mesh, topology.shells);
    std::vector<double> shellVolume(topology.shells, 0.0);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    {
        const Mesh::Triangle &t = mesh.triangles[i];
        shellVolume[shellOfTriangle[i]] += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]])) / 6.0;
    }
    if (topology.closed)
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
            if (shellVolume[shellOfTriangle[i]] < 0)
                std::swap(mesh.triangles[i][1], mesh.triangles[i][2]);

    // Drop vertices no triangle uses, so bounds and vertex tests see only the surface.
    std::vector<std::int64_t> used(mesh.vertices.size(), -1);
    std::vector<Eigen::Vector3d> compact;
    for (Mesh::Triangle &t : mesh.triangles)
        for (std::uint32_t &i : t)
        {
            if (used[i] < 0)
            {
                used[i] = static_cast<std::int64_t>(compact.size());
                compact.push_back(mesh.vertices[i]);
            }
            i = static_cast<std::uint32_t>(used[i]);
        }
    mesh.vertices = std::move(compact);
    return topology;
}

MeshTopology cleanAndMerge(std::vector<Mesh> parts, Mesh &merged, double weldTolerance)
{
    MeshTopology total;
    total.closed = false;
    bool allClosed = !parts.empty();
    merged = Mesh{};
    for (Mesh &part : parts)
    {
        const MeshTopology t = cleanMesh(part, weldTolerance);
        if (part.empty())
            continue;
        allClosed = allClosed && t.closed;
        total.boundaryEdges += t.boundaryEdges;
        total.nonManifoldEdges += t.nonManifoldEdges;
        total.misorientedEdges += t.misorientedEdges;
        total.degenerateTriangles += t.degenerateTriangles;
        total.mergedVertices += t.mergedVertices;
        total.removedDuplicateFaces += t.removedDuplicateFaces;
        total.shells += t.shells;
        merged.append(part);
    }
    total.closed = allClosed && !merged.empty();
    return total;
}
}  // namespace rastercheck
