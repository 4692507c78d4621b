#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
RobotData::RobotData(const RobotModel &model)
  : oMl(model.links.size(), Eigen::Isometry3d::Identity()), jointValues(model.joints.size(), 0.0)
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
    // Joint values first: a mimic joint may come before its source in the depth-first order
    // (the Panda's second finger mimics the first, in a sibling branch).
    for (std::size_t j = 0; j < model.joints.size(); ++j)
        if (model.joints[j].firstCoordinate >= 0)
            data.jointValues[j] = q[model.joints[j].firstCoordinate];
    for (std::size_t j = 0; j < model.joints.size(); ++j)
    {
        const Joint &joint = model.joints[j];
        if (joint.mimicOf >= 0)
            data.jointValues[j] = joint.mimicMultiplier * data.jointValues[joint.mimicOf] + joint.mimicOffset;
    }

    data.oMl[0] = Eigen::Isometry3d::Identity();
    for (std::size_t j = 0; j < model.joints.size(); ++j)
    {
        const Joint &joint = model.joints[j];
        const double *values = joint.mimicOf >= 0 || device::coordinateCount(joint.kind) == 1
                                   ? &data.jointValues[j]
                                   : (joint.firstCoordinate >= 0 ? q + joint.firstCoordinate : nullptr);
        const device::Vec3<double> axis{joint.axis.x(), joint.axis.y(), joint.axis.z()};
        const device::Pose<double> local = device::jointPose(joint.kind, toDevicePose(joint.origin), axis, values);
        data.oMl[joint.childLink] = data.oMl[joint.parentLink] * fromDevicePose(local);
    }
}
}  // namespace rastercheck
