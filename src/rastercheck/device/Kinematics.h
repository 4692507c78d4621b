#pragma once

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"

namespace rastercheck::device
{
/** \brief One joint of the kinematic tree in device layout (RobotModel::kinematicJoints), in
    topological order: a joint's parent link is placed by an earlier joint. */
struct KinematicJoint
{
    JointKind kind;
    int parentLink;
    int childLink;
    int firstCoordinate;  ///< -1 for fixed and mimic joints
    int mimicOf;          ///< -1 unless a mimic joint (of a joint that is not itself a mimic)
    double mimicMultiplier;
    double mimicOffset;
    Pose<double> origin;
    Vec3<double> axis;
};

/** \brief Forward kinematics of a whole tree: \a links[l] = pose of link l in the world frame for
    configuration \a q; link 0 (the root) sits at the origin. \a jointValues: scratch of one value
    per joint. One implementation for the CPU backend and the GPU's FK kernel (one thread a state). */
RC_HD void linkPoses(const KinematicJoint *joints, int numJoints, const double *q, double *jointValues,
                     Pose<double> *links)
{
    // Values first: a mimic joint may come before its source in the depth-first order (the
    // Panda's second finger mimics the first, in a sibling branch).
    for (int j = 0; j < numJoints; ++j)
        jointValues[j] = joints[j].firstCoordinate >= 0 ? q[joints[j].firstCoordinate] : 0.0;
    for (int j = 0; j < numJoints; ++j)
        if (joints[j].mimicOf >= 0)
            jointValues[j] = joints[j].mimicMultiplier * jointValues[joints[j].mimicOf] + joints[j].mimicOffset;
    links[0] = Pose<double>::identity();
    for (int j = 0; j < numJoints; ++j)
    {
        const KinematicJoint &joint = joints[j];
        const double *values = joint.mimicOf >= 0 || coordinateCount(joint.kind) == 1
                                   ? &jointValues[j]
                                   : (joint.firstCoordinate >= 0 ? q + joint.firstCoordinate : nullptr);
        links[joint.childLink] =
            compose(links[joint.parentLink], jointPose(joint.kind, joint.origin, joint.axis, values));
    }
}

/** \brief The float pose the pipeline stages use: the double FK result with its translation taken
    relative to \a origin (CollisionModel::origin) before the rounding to float. A state far beyond
    float's range (an unbounded floating joint at 1e300) saturates: the culls then let the pair
    through to the exact phase, which works in double. */
RC_HD Pose<float> toFloatPose(const Pose<double> &pose, const double origin[3])
{
    const double largest = 3.4028234663852886e38;  // FLT_MAX
    Pose<float> p;
    for (int r = 0; r < 3; ++r)
    {
        // Rotation entries are within [-1, 1] (rounding aside): only the translation can overflow.
        for (int c = 0; c < 3; ++c)
            p.m[4 * r + c] = static_cast<float>(pose.m[4 * r + c]);
        const double value = pose.m[4 * r + 3] - origin[r];
        p.m[4 * r + 3] = static_cast<float>(value < -largest ? -largest : (value > largest ? largest : value));
    }
    return p;
}
}  // namespace rastercheck::device
