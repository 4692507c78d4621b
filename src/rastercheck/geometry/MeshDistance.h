#pragma once

#include <cstdint>
#include <limits>

#include <Eigen/Geometry>

#include "rastercheck/geometry/MeshBvh.h"

namespace rastercheck
{
/** \brief The closest points of two meshes' surfaces. */
struct SurfaceDistance
{
    double distance = std::numeric_limits<double>::infinity();  ///< metres; 0 when the surfaces cross or touch
    Eigen::Vector3d pointA = Eigen::Vector3d::Zero();           ///< on A's triangle, world frame
    Eigen::Vector3d pointB = Eigen::Vector3d::Zero();           ///< on B's triangle, world frame
    std::int32_t triangleA = -1;                                ///< triangle number within A's mesh
    std::int32_t triangleB = -1;
};

/** \brief Lower bound on the distance between a fixed tree's node and a moving tree's node placed in
    the fixed frame (its axes the columns of \a axesM, its centre at \a between from the fixed node's
    centre): the larger of the bounding spheres' gap and the widest gap between the boxes along
    any of the 15 separating axes (each axis normalised, so its gap is a Euclidean lower bound).
    0 when the boxes overlap. Not grown by any rounding slack: the caller subtracts it. */
double nodeDistanceLowerBound(const MeshBvh::Node &fixed, const Eigen::Matrix3d &axesM, const MeshBvh::Node &moving,
                              const Eigen::Vector3d &between);

/** \brief The smallest distance between the surfaces of A (placed by \a poseA) and B (placed by
    \a poseB) when it is below \a bound (metres): true, and \a result holds it with a closest pair
    of points and their triangles. False when every pair of triangles is at least \a bound apart
    (result untouched); with an infinite bound, false only for an empty mesh.

    FCL's and Coal's distance traversal over the two trees (device::walkPairs): a node pair is
    skipped when its lower bound (nodeDistanceLowerBound, less a slack for the nodes' float
    storage) is not below the best distance found so far, and leaf pairs are measured by
    triangleDistance() with the smaller tree's triangles placed in the other's frame. So the
    distance is exact for the coordinates after that one rigid transform (an intersection is decided
    by exact predicates); the walk stops at the first crossing. Surfaces only: a solid inside
    another is apart by this measure (solidInside() tells). \a workspace (optional) caches the
    placed nodes as for surfacesWithin. Thread-safe given one workspace per thread. */
bool surfaceDistance(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                     double bound, SurfaceDistance &result, ExactWorkspace *workspace = nullptr);

/** \brief Is the closed solid of \a inner (placed by \a innerPose) inside the closed solid of
    \a outer, given that their surfaces do not meet? Then every shell of inner lies wholly inside
    or wholly outside outer, and one vertex per shell decides (outer's inside grid, else a ray).
    On true, \a point (optional) receives that vertex (world frame). */
bool solidInside(const MeshBvh &inner, const Eigen::Isometry3d &innerPose, const MeshBvh &outer,
                 const Eigen::Isometry3d &outerPose, Eigen::Vector3d *point = nullptr);
}  // namespace rastercheck
