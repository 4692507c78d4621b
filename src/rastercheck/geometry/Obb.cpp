#include "rastercheck/geometry/Obb.h"

#include <Eigen/Eigenvalues>

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
Obb Obb::transformed(const Eigen::Isometry3d &pose) const
{
    Obb box;
    box.center = pose * center;
    box.axes = pose.linear() * axes;
    box.halfExtents = halfExtents;
    return box;
}

Aabb Obb::aabb() const
{
    const Eigen::Vector3d reach = axes.cwiseAbs() * halfExtents;
    Aabb box;
    box.min = center - reach;
    box.max = center + reach;
    return box;
}

Obb Obb::fromAabb(const Aabb &box)
{
    Obb obb;
    if (box.empty())
        return obb;
    obb.center = box.center();
    obb.halfExtents = box.halfExtents();
    return obb;
}

Obb Obb::fit(const Mesh &mesh)
{
    const Aabb bounds = mesh.bounds();
    Obb best = Obb::fromAabb(bounds);
    if (mesh.empty())
        return best;

    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d &v : mesh.vertices)
        mean += v;
    mean /= static_cast<double>(mesh.vertices.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d &v : mesh.vertices)
        covariance += (v - mean) * (v - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Eigen::Matrix3d axes = solver.eigenvectors();
    if (axes.determinant() < 0)
        axes.col(2) = -axes.col(2);

    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (const Mesh::Triangle &t : mesh.triangles)
        for (std::uint32_t i : t)
        {
            const Eigen::Vector3d local = axes.transpose() * mesh.vertices[i];
            lo = lo.cwiseMin(local);
            hi = hi.cwiseMax(local);
        }
    Obb principal;
    principal.axes = axes;
    principal.center = axes * (0.5 * (lo + hi));
    principal.halfExtents = 0.5 * (hi - lo);
    return principal.volume() < best.volume() ? principal : best;
}
}  // namespace rastercheck
