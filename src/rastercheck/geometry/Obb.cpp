#include "rastercheck/geometry/Obb.h"

#include <algorithm>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>

#include "rastercheck/geometry/BoxFit.h"
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
    if (mesh.empty())
        return Obb::fromAabb(mesh.bounds());
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d &v : mesh.vertices)
        mean += v;
    mean /= static_cast<double>(mesh.vertices.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d &v : mesh.vertices)
        covariance += (v - mean) * (v - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    const Eigen::Matrix3d principal =
        solver.info() == Eigen::Success ? solver.eigenvectors() : Eigen::Matrix3d::Identity();

    // The frame of least surface area (as the triangle trees' boxes, MeshBvh): the principal axes,
    // or the frames about them, the mesh's axes and a few triangles' normals, each turned to the
    // least rectangle about the mesh's extreme vertices.
    std::vector<Eigen::Vector3d> points, normals;
    ExtremePoints extremes;
    for (const Mesh::Triangle &t : mesh.triangles)
        for (std::uint32_t i : t)
            extremes.add(mesh.vertices[i]);
    extremes.appendTo(points);
    appendFitNormals(
        principal, mesh.triangles.size(), [&](std::size_t i) { return mesh.triangleNormal(i); }, normals);
    BoxFitScratch scratch;
    Eigen::Matrix3d axes = leastAreaAxes(points, principal, normals, scratch);
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
    Obb box;
    box.axes = axes;
    box.center = axes * (0.5 * (lo + hi));
    box.halfExtents = 0.5 * (hi - lo);
    return box;
}
}  // namespace rastercheck
