#pragma once

#include <Eigen/Core>

namespace rastercheck
{
/** \brief Exact-in-double triangle/triangle intersection (closed triangles: touching counts),
    including the coplanar case. Robust to degenerate input (a degenerate triangle is treated as
    its segment/point). */
bool trianglesIntersect(const Eigen::Vector3d &p0, const Eigen::Vector3d &p1, const Eigen::Vector3d &p2,
                        const Eigen::Vector3d &q0, const Eigen::Vector3d &q1, const Eigen::Vector3d &q2);

/** \brief Distance between two triangles (0 when they intersect); \a pointOnP / \a pointOnQ, when
    not null, receive a closest pair. */
double triangleDistance(const Eigen::Vector3d &p0, const Eigen::Vector3d &p1, const Eigen::Vector3d &p2,
                        const Eigen::Vector3d &q0, const Eigen::Vector3d &q1, const Eigen::Vector3d &q2,
                        Eigen::Vector3d *pointOnP = nullptr, Eigen::Vector3d *pointOnQ = nullptr);

/** \brief Ray (origin + t * direction, t >= 0) against triangle: 1 for a proper crossing of the
    interior, 0 for a miss, -1 when the ray passes within \a tolerance of an edge or vertex or lies
    in the triangle's plane (the caller should retry with another direction). On a hit \a t gets
    the ray parameter. */
int rayTriangle(const Eigen::Vector3d &origin, const Eigen::Vector3d &direction, const Eigen::Vector3d &a,
                const Eigen::Vector3d &b, const Eigen::Vector3d &c, double tolerance, double &t);
}  // namespace rastercheck
