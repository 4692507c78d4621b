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

/** \brief The value of joint \a j in configuration \a q: its coordinate (0 for a fixed joint), or
    for a mimic joint its source's times the multiplier plus the offset (a source is never a mimic
    itself). */
RC_HD double jointValue(const KinematicJoint *joints, int j, const double *q)
{
    const KinematicJoint &joint = joints[j];
    if (joint.mimicOf < 0)
        return joint.firstCoordinate >= 0 ? q[joint.firstCoordinate] : 0.0;
    const KinematicJoint &source = joints[joint.mimicOf];
    const double sourceValue = source.firstCoordinate >= 0 ? q[source.firstCoordinate] : 0.0;
    return joint.mimicMultiplier * sourceValue + joint.mimicOffset;
}

/** \brief The pose of \a joint's child link in its parent link's frame: \a value (jointValue) for a
    joint of one coordinate or a mimic joint, else its coordinates in \a q. */
RC_HD Pose<double> jointLocalPose(const KinematicJoint &joint, const double *q, const double &value)
{
    const double *values = joint.mimicOf >= 0 || coordinateCount(joint.kind) == 1
                               ? &value
                               : (joint.firstCoordinate >= 0 ? q + joint.firstCoordinate : nullptr);
    return jointPose(joint.kind, joint.origin, joint.axis, values);
}

/** \brief The links' world poses from the joints' local ones (\a local[j], jointLocalPose): link 0
    (the root) at the origin, each joint's child placed from its parent, in the joints' topological
    order. */
RC_HD void placeLinks(const KinematicJoint *joints, int numJoints, const Pose<double> *local, Pose<double> *links)
{
    links[0] = Pose<double>::identity();
    for (int j = 0; j < numJoints; ++j)
        links[joints[j].childLink] = compose(links[joints[j].parentLink], local[j]);
}

/** \brief Forward kinematics of a whole tree: \a links[l] = pose of link l in the world frame for
    configuration \a q; link 0 (the root) sits at the origin; \a jointValues[j] = jointValue(j).
    The CPU backend's; the stages compute the same local poses a thread per (state, joint) and then
    placeLinks a thread per state, so the chain's serial part is its products alone. */
RC_HD void linkPoses(const KinematicJoint *joints, int numJoints, const double *q, double *jointValues,
                     Pose<double> *links)
{
    links[0] = Pose<double>::identity();
    for (int j = 0; j < numJoints; ++j)
    {
        jointValues[j] = jointValue(joints, j, q);  // a mimic's reads its source's coordinate, not this array
        links[joints[j].childLink] = compose(links[joints[j].parentLink], jointLocalPose(joints[j], q, jointValues[j]));
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
