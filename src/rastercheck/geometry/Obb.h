#pragma once

#include <Eigen/Geometry>

#include "rastercheck/geometry/Aabb.h"

namespace rastercheck
{
struct Mesh;

/** \brief Oriented box: centre and axes (columns of \a axes, orthonormal, right-handed) in the
    owner's frame, half extents along those axes. */
struct Obb
{
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    Eigen::Vector3d halfExtents = Eigen::Vector3d::Zero();

    /** \brief The box expressed in another frame: pose * box. */
    Obb transformed(const Eigen::Isometry3d &pose) const;
    /** \brief Tight world-axis bounds of this box. */
    Aabb aabb() const;
    double volume() const { return 8.0 * halfExtents.prod(); }

    /** \brief A tight box around \a mesh: along the frame of least surface area among the principal
        axes of the vertex covariance and the frames about a few normals (those axes, the mesh's
        axes, a few triangles' normals; leastAreaAxes). Empty mesh gives a zero box. */
    static Obb fit(const Mesh &mesh);
    static Obb fromAabb(const Aabb &box);
};
}  // namespace rastercheck
