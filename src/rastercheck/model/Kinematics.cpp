#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
RobotData::RobotData(const RobotModel &model)
  : oMl(model.links.size(), Eigen::Isometry3d::Identity())
  , jointValues(model.joints.size(), 0.0)
  , linkPoses(model.links.size(), device::Pose<double>::identity())
{
}

device::Pose<double> toDevicePose(const Eigen::Isometry3d &pose)
{
    device::Pose<double> p;
    for (int r = 0; r < 3; ++r)
    {
        for (int c = 0; c < 3; ++c)
            p.m[4 * r + c] = pose.linear()(r, c);
        p.m[4 * r + 3] = pose.translation()(r);
    }
    return p;
}

Eigen::Isometry3d fromDevicePose(const device::Pose<double> &p)
{
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
    {
        for (int c = 0; c < 3; ++c)
            pose.linear()(r, c) = p.m[4 * r + c];
        pose.translation()(r) = p.m[4 * r + 3];
    }
    return pose;
}

void forwardKinematics(const RobotModel &model, RobotData &data, const double *q)
{
    device::linkPoses(model.kinematicJoints.data(), static_cast<int>(model.kinematicJoints.size()), q,
                      data.jointValues.data(), data.linkPoses.data());
    for (std::size_t l = 0; l < model.links.size(); ++l)
        data.oMl[l] = fromDevicePose(data.linkPoses[l]);
}
}  // namespace rastercheck
