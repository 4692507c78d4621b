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

/** \brief Where a pair of trees was nearest at the last query: a triangle slot of each
    (MeshBvh::triangleOrder positions). surfaceDistance() measures that triangle pair first, so a
    query at a nearby state starts with a distance at or near the answer and prunes from its first
    node pair. It only reorders work: the distance is the same with or without it (the pair named
    may differ between pairs of equal distance). A stale or foreign hint (slots out of range) is
    ignored. */
struct SurfaceHint
{
    std::uint32_t slotA = UINT32_MAX;
    std::uint32_t slotB = UINT32_MAX;
};

/** \brief Lower bound on the distance between a fixed tree's node and a moving tree's node placed in
    the fixed frame (its axes the columns of \a axesM, its centre at \a between from the fixed node's
    centre): the larger of the bounding spheres' gap, the widest gap between the boxes along any of
    the six axes of their faces and each box against the other's centre. 0 when the boxes overlap
    (or come apart only across an edge of each). Not grown by any rounding slack: the caller
    subtracts it. Returns as soon as the bound reaches \a reach (then a value at least \a reach, not
    necessarily the largest): a walk that prunes at its best distance needs no more. */
double nodeDistanceLowerBound(const MeshBvh::Node &fixed, const Eigen::Matrix3d &axesM, const MeshBvh::Node &moving,
                              const Eigen::Vector3d &between, double reach = std::numeric_limits<double>::infinity());

/** \brief The smallest distance between the surfaces of A (placed by \a poseA) and B (placed by
    \a poseB) when it is below \a bound (metres): true, and \a result holds it with a closest pair
    of points and their triangles. False when every pair of triangles is at least \a bound apart
    (result untouched); with an infinite bound, false only for an empty mesh.

    A best-first walk of the two trees (FCL's distance traversal with a queue): node pairs wait in a
    heap by their lower bound (nodeDistanceLowerBound, less a slack for the nodes' float storage),
    nearest first, and the walk ends when the nearest waiting bound reaches the best distance found,
    so it visits only the node pairs whose bound is below the answer. Leaf pairs are measured with
    the smaller tree's triangles placed in the other's frame: a pair one of whose triangles lies
    beyond the other's plane by the best distance is skipped, a corner over the other's face is
    measured as that corner/face distance, and any other pair by triangleDistance(). So the distance
    is exact for the coordinates after that one rigid transform (an intersection is decided by exact
    predicates); the walk stops at the first crossing. Surfaces only: a solid inside another is apart
    by this measure (solidInside() tells). \a workspace (optional) caches the placed nodes as for
    surfacesWithin; \a hint (optional) is read first and receives this query's nearest pair when one
    is found. Thread-safe given one workspace and hint per thread. */
bool surfaceDistance(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                     double bound, SurfaceDistance &result, ExactWorkspace *workspace = nullptr,
                     SurfaceHint *hint = nullptr);

/** \brief The distance between the triangle pair \a hint names, when below \a bound: true and
    \a result (as surfaceDistance's, computed as its walk computes it, so the same value). False for
    a pair at least \a bound apart or a hint that names no pair of these trees. An upper bound on
    surfaceDistance() for one triangle distance: a caller with many pairs to measure seeds its best
    distance with these before walking any tree. */
bool hintedDistance(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                    const SurfaceHint &hint, double bound, SurfaceDistance &result);

/** \brief Is the closed solid of \a inner (placed by \a innerPose) inside the closed solid of
    \a outer, given that their surfaces do not meet? Then every shell of inner lies wholly inside
    or wholly outside outer, and one vertex per shell decides (outer's inside grid, else a ray).
    On true, \a point (optional) receives that vertex (world frame). */
bool solidInside(const MeshBvh &inner, const Eigen::Isometry3d &innerPose, const MeshBvh &outer,
                 const Eigen::Isometry3d &outerPose, Eigen::Vector3d *point = nullptr);
}  // namespace rastercheck
