#include "rastercheck/geometry/Mesh.h"

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
