#pragma once

#include <Eigen/Core>

namespace rastercheck
{
/** \brief Exact triangle/triangle intersection of closed triangles (touching counts), including
    the coplanar case (device::trianglesIntersect on these coordinates). Every decision is an exact orientation predicate (orient3d/orient2d) on the
    double coordinates given, so the answer is the true one for those coordinates: it is
    symmetric in the two triangles and in the order of their vertices. A degenerate triangle
    (collinear or repeated vertices) is treated as the segment or point it covers.

    When \a point is not null and the triangles meet, it receives a point of the intersection
    (computed in floating point, so it lies on both triangles only up to rounding). */
bool trianglesIntersect(const Eigen::Vector3d &p0, const Eigen::Vector3d &p1, const Eigen::Vector3d &p2,
                        const Eigen::Vector3d &q0, const Eigen::Vector3d &q1, const Eigen::Vector3d &q2,
                        Eigen::Vector3d *point = nullptr);

/** \brief Euclidean distance between two closed triangles (0 when they intersect, decided by
    trianglesIntersect()); \a pointOnP / \a pointOnQ, when not null, receive a closest pair (the
    same intersection point twice when the distance is 0). The positive distance is the smallest
    of the nine edge/edge and six vertex/face distances, computed in floating point. */
double triangleDistance(const Eigen::Vector3d &p0, const Eigen::Vector3d &p1, const Eigen::Vector3d &p2,
                        const Eigen::Vector3d &q0, const Eigen::Vector3d &q1, const Eigen::Vector3d &q2,
                        Eigen::Vector3d *pointOnP = nullptr, Eigen::Vector3d *pointOnQ = nullptr);

/** \brief Is triangleDistance() <= \a distance (metres, >= 0)? Cheaper than computing the
    distance: rejects early when one triangle lies beyond \a distance of the other's plane and
    stops at the first pair of features close enough. \a point, when not null and the answer is
    true, receives the midpoint of a pair of points no farther apart than \a distance. */
bool trianglesWithin(const Eigen::Vector3d &p0, const Eigen::Vector3d &p1, const Eigen::Vector3d &p2,
                     const Eigen::Vector3d &q0, const Eigen::Vector3d &q1, const Eigen::Vector3d &q2, double distance,
                     Eigen::Vector3d *point = nullptr);

/** \brief Ray (origin + t * direction, t >= 0, direction non-zero, any length) against triangle
    abc, for parity counting: 1 for a crossing of the interior that stays at least \a tolerance
    (metres) from every edge line, 0 for a clear miss (the ray's hit point on the plane is more than
    \a tolerance outside an edge line, the plane is behind the origin, or the ray is parallel to
    and off the plane), -1 when the answer is ambiguous: the hit point is within \a tolerance of
    the boundary, the ray lies in the triangle's plane, or the origin itself is within
    \a tolerance of the triangle. The caller should retry along another direction on -1.
    A zero-area triangle is a miss (its neighbours in a closed mesh catch the ray). On 1, \a t
    receives the ray parameter of the hit. */
int rayTriangle(const Eigen::Vector3d &origin, const Eigen::Vector3d &direction, const Eigen::Vector3d &a,
                const Eigen::Vector3d &b, const Eigen::Vector3d &c, double tolerance, double &t);
}  // namespace rastercheck
