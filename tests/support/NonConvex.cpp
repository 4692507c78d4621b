#include "NonConvex.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace rastercheck::test
{
Aabb box(const Eigen::Vector3d &min, const Eigen::Vector3d &max)
{
    Aabb b;
    b.min = min;
    b.max = max;
    return b;
}

Mesh blockSolid(const std::vector<Aabb> &boxes, double maxCell)
{
    // The grid lines of each axis: every box face, then long intervals split evenly.
    std::array<std::vector<double>, 3> lines;
    for (int a = 0; a < 3; ++a)
    {
        std::vector<double> faces;
        for (const Aabb &b : boxes)
        {
            faces.push_back(b.min[a]);
            faces.push_back(b.max[a]);
        }
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        for (std::size_t i = 0; i < faces.size(); ++i)
        {
            lines[a].push_back(faces[i]);
            if (i + 1 == faces.size())
                break;
            const double length = faces[i + 1] - faces[i];
            const int pieces = std::isfinite(maxCell) ? std::max(1, int(std::ceil(length / maxCell - 1e-9))) : 1;
            for (int p = 1; p < pieces; ++p)
                lines[a].push_back(faces[i] + length * p / pieces);
        }
    }
    const std::array<int, 3> cells{int(lines[0].size()) - 1, int(lines[1].size()) - 1, int(lines[2].size()) - 1};
    if (cells[0] < 1 || cells[1] < 1 || cells[2] < 1)
        return {};
    const auto cellIndex = [&](const std::array<int, 3> &c) { return (c[2] * cells[1] + c[1]) * cells[0] + c[0]; };
    std::vector<std::uint8_t> filled(std::size_t(cells[0]) * cells[1] * cells[2], 0);
    for (int k = 0; k < cells[2]; ++k)
        for (int j = 0; j < cells[1]; ++j)
            for (int i = 0; i < cells[0]; ++i)
            {
                const Eigen::Vector3d centre(0.5 * (lines[0][i] + lines[0][i + 1]),
                                             0.5 * (lines[1][j] + lines[1][j + 1]),
                                             0.5 * (lines[2][k] + lines[2][k + 1]));
                for (const Aabb &b : boxes)
                    if ((b.min.array() < centre.array()).all() && (centre.array() < b.max.array()).all())
                    {
                        filled[cellIndex({i, j, k})] = 1;
                        break;
                    }
            }
    const auto isFilled = [&](std::array<int, 3> c)
    {
        for (int a = 0; a < 3; ++a)
            if (c[a] < 0 || c[a] >= cells[a])
                return false;
        return filled[cellIndex(c)] != 0;
    };

    Mesh mesh;
    std::vector<std::int64_t> vertexOf(std::size_t(cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1), -1);
    const auto vertex = [&](const std::array<int, 3> &g)
    {
        std::int64_t &id = vertexOf[(std::size_t(g[2]) * (cells[1] + 1) + g[1]) * (cells[0] + 1) + g[0]];
        if (id < 0)
        {
            id = std::int64_t(mesh.vertices.size());
            mesh.vertices.emplace_back(lines[0][g[0]], lines[1][g[1]], lines[2][g[2]]);
        }
        return std::uint32_t(id);
    };
    for (int k = 0; k < cells[2]; ++k)
        for (int j = 0; j < cells[1]; ++j)
            for (int i = 0; i < cells[0]; ++i)
            {
                const std::array<int, 3> c{i, j, k};
                if (!isFilled(c))
                    continue;
                for (int a = 0; a < 3; ++a)
                    for (int side = 0; side < 2; ++side)
                    {
                        std::array<int, 3> next = c;
                        next[a] += side ? 1 : -1;
                        if (isFilled(next))
                            continue;
                        // The face's corners counter-clockwise about +e_a (e_b x e_d = e_a for the
                        // cyclic a, b, d), reversed on the -e_a side, so that normals point out.
                        const int b = (a + 1) % 3, d = (a + 2) % 3;
                        std::array<std::array<int, 3>, 4> corner;
                        for (int n = 0; n < 4; ++n)
                        {
                            corner[n] = c;
                            corner[n][a] += side;
                        }
                        corner[1][b] += 1;
                        corner[2][b] += 1;
                        corner[2][d] += 1;
                        corner[3][d] += 1;
                        std::array<std::uint32_t, 4> v;
                        for (int n = 0; n < 4; ++n)
                            v[n] = vertex(corner[n]);
                        if (side)
                        {
                            mesh.triangles.push_back({v[0], v[1], v[2]});
                            mesh.triangles.push_back({v[0], v[2], v[3]});
                        }
                        else
                        {
                            mesh.triangles.push_back({v[0], v[2], v[1]});
                            mesh.triangles.push_back({v[0], v[3], v[2]});
                        }
                    }
            }
    return mesh;
}

Mesh roomWithDoorway(double maxCell)
{
    using V = Eigen::Vector3d;
    return blockSolid({box(V(0, 0, 0), V(4, 3, 0.2)),       // floor
                       box(V(0, 0, 2.2), V(4, 3, 2.4)),     // ceiling
                       box(V(0, 0, 0.2), V(0.2, 3, 2.2)),   // -x wall
                       box(V(0, 0, 0.2), V(4, 0.2, 2.2)),   // -y wall
                       box(V(0, 2.8, 0.2), V(4, 3, 2.2)),   // +y wall
                       box(V(3.8, 0, 0.2), V(4, 1, 2.2)),   // +x wall beside the door
                       box(V(3.8, 2, 0.2), V(4, 3, 2.2)),   // and on its other side
                       box(V(3.8, 1, 2.0), V(4, 2, 2.2))},  // lintel
                      maxCell);
}

Mesh uShape(double maxCell)
{
    using V = Eigen::Vector3d;
    return blockSolid({box(V(0, 0, 0), V(2, 0.4, 1)), box(V(0, 0.4, 0), V(0.4, 2, 1)), box(V(1.6, 0.4, 0), V(2, 2, 1))},
                      maxCell);
}

Mesh lBar(double scale)
{
    using V = Eigen::Vector3d;
    return blockSolid({box(scale * V(-0.3, -0.05, -0.05), scale * V(0.3, 0.05, 0.05)),
                       box(scale * V(-0.3, 0.05, -0.05), scale * V(-0.2, 0.35, 0.05))});
}

Mesh mazeOnSlab(double maxCell)
{
    Mesh maze;
    const auto add = [&maze, maxCell](double x0, double x1, double y0, double y1, double z0, double z1)
    { maze.append(blockSolid({box(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1))}, maxCell)); };
    add(-0.05, 4.05, -0.05, 4.05, 0, 0.2);  // the slab
    // Walls along y (thin in x) stand in z [0.15, 1.15], walls along x in [0.12, 1.1], and each
    // wall's ends lie inside the wall it meets: no two faces of different boxes are coplanar where
    // they overlap.
    const double alongY[][4] = {{0, 0.1, 0.02, 3.98},
                                {3.9, 4, 0.02, 3.98},
                                {0.95, 1.05, 0.05, 3.0},
                                {1.95, 2.05, 1.0, 3.95},
                                {2.95, 3.05, 0.05, 3.0}};
    const double alongX[][4] = {{0.05, 3.95, 0, 0.1},   {0.05, 3.95, 3.9, 4},   {0.05, 0.5, 1.45, 1.55},
                                {1.5, 2.0, 2.45, 2.55}, {2.5, 3.0, 0.95, 1.05}, {3.4, 3.95, 3.2, 3.3}};
    for (const auto &w : alongY)
        add(w[0], w[1], w[2], w[3], 0.15, 1.15);
    for (const auto &w : alongX)
        add(w[0], w[1], w[2], w[3], 0.12, 1.1);
    return maze;
}

Mesh bookshelf(double maxCell)
{
    using V = Eigen::Vector3d;
    std::vector<Aabb> parts{box(V(0.8, -0.6, 0), V(0.85, 0.6, 1.2)), box(V(0.45, -0.6, 0), V(0.8, -0.56, 1.2)),
                            box(V(0.45, 0.56, 0), V(0.8, 0.6, 1.2))};
    for (double z : {0.0, 0.4, 0.8, 1.17})
        parts.push_back(box(V(0.45, -0.56, z), V(0.8, 0.56, z + 0.03)));
    return blockSolid(parts, maxCell);
}
}  // namespace rastercheck::test
