#pragma once

#include <Eigen/Core>

#include "rastercheck/device/Pose.h"

namespace rastercheck
{
/** \brief Conversions between Eigen's vectors and the per-element code's (device/) vectors. */
inline device::Vec3<double> toDevice(const Eigen::Vector3d &v)
{
    return {v.x(), v.y(), v.z()};
}

inline Eigen::Vector3d toEigen(const device::Vec3<double> &v)
{
    return Eigen::Vector3d(v.x, v.y, v.z);
}
}  // namespace rastercheck
