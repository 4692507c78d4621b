#pragma once

#include <Eigen/Core>

namespace rastercheck
{
/** \brief Exact sign of the orientation of \a d against the plane through \a a, \a b, \a c:
    sign of ((b - a) x (c - a)) . (d - a). Positive when \a d lies on the side the normal of the
    counter-clockwise triangle abc points to, 0 when the four points are coplanar (exactly, for
    the double coordinates given). A floating-point filter decides almost every call; the rest
    are evaluated exactly with floating-point expansions (Shewchuk's method), so the sign is
    right barring overflow or underflow of the products. */
int orient3d(const Eigen::Vector3d &a, const Eigen::Vector3d &b, const Eigen::Vector3d &c, const Eigen::Vector3d &d);

/** \brief Exact sign of (b - a) x (c - a) in the plane: positive when a, b, c turn counter-clockwise,
    0 when collinear. Same filter and exact fallback as orient3d(). */
int orient2d(double ax, double ay, double bx, double by, double cx, double cy);
}  // namespace rastercheck
