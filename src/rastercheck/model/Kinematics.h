#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
/** \brief Per-thread scratch for one robot (Pinocchio's Data): never shared between threads. */
struct RobotData
{
    explicit RobotData(const RobotModel &model);

    /** \brief oMl[l]: pose of link l in the world frame, after forwardKinematics(). */
    std::vector<Eigen::Isometry3d> oMl;
    /** \brief Value of each one-coordinate joint (mimic resolved); unused for other kinds. */
    std::vector<double> jointValues;
    /** \brief The same poses as oMl in device layout, as the shared chain computes them. */
    std::vector<device::Pose<double>> linkPoses;
};

/** \brief Computes data.oMl from configuration \a q (model.numCoordinates() values, active-joint
    order). The root link sits at the world origin. Runs the chain the GPU backend runs
    (device::linkPoses), so both backends place links identically. */
void forwardKinematics(const RobotModel &model, RobotData &data, const double *q);
inline void forwardKinematics(const RobotModel &model, RobotData &data, const std::vector<double> &q)
{
    forwardKinematics(model, data, q.data());
}

/** \brief Conversions between Eigen and the flat device pose layout. */
device::Pose<double> toDevicePose(const Eigen::Isometry3d &pose);
Eigen::Isometry3d fromDevicePose(const device::Pose<double> &pose);
}  // namespace rastercheck
