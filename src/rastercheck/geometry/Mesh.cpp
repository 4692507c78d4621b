#include "rastercheck/geometry/Mesh.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace rastercheck
{
Aabb Mesh::bounds() const
{
    Aabb box;
    for (const Triangle &t : triangles)
        for (std::uint32_t i : t)
            box.extend(vertices[i]);
    return box;
}

std::vector<std::uint32_t> Mesh::extremeVertices(std::size_t directions) const
{
    std::vector<std::uint32_t> chosen;
    if (vertices.size() <= directions)
    {
        chosen.resize(vertices.size());
        std::iota(chosen.begin(), chosen.end(), 0u);
        return chosen;
    }
    const double golden = M_PI * (3.0 - std::sqrt(5.0));  // the golden angle
    for (std::size_t k = 0; k < directions; ++k)
    {
        const double z = 1.0 - (2.0 * static_cast<double>(k) + 1.0) / static_cast<double>(directions);
        const double r = std::sqrt(1.0 - z * z), phi = golden * static_cast<double>(k);
        const Eigen::Vector3d d(r * std::cos(phi), r * std::sin(phi), z);
        std::uint32_t best = 0;
        for (std::uint32_t i = 1; i < vertices.size(); ++i)
            if (d.dot(vertices[i]) > d.dot(vertices[best]))
                best = i;
        chosen.push_back(best);
    }
    std::sort(chosen.begin(), chosen.end());
    chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
    return chosen;
}

void Mesh::transform(const Eigen::Isometry3d &transform)
{
    for (Eigen::Vector3d &v : vertices)
        v = transform * v;
}

void Mesh::scale(const Eigen::Vector3d &factors)
{
    for (Eigen::Vector3d &v : vertices)
        v = v.cwiseProduct(factors);
    const int negatives = (factors.x() < 0) + (factors.y() < 0) + (factors.z() < 0);
    if (negatives % 2 == 1)
        for (Triangle &t : triangles)
            std::swap(t[1], t[2]);
}

void Mesh::append(const Mesh &other, const Eigen::Isometry3d &transform)
{
    const auto offset = static_cast<std::uint32_t>(vertices.size());
    vertices.reserve(vertices.size() + other.vertices.size());
    for (const Eigen::Vector3d &v : other.vertices)
        vertices.push_back(transform * v);
    triangles.reserve(triangles.size() + other.triangles.size());
    for (const Triangle &t : other.triangles)
        triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}
}  // namespace rastercheck
