#include "rastercheck/model/MotionBound.h"

#include <algorithm>
#include <cmath>
#include <limits>


namespace rastercheck
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

/** \brief sqrt(x^2 + y^2 + z^2), infinite when one is (libstdc++'s three-argument std::hypot
    returns NaN for infinite arguments). */
double length(double x, double y, double z) { return std::sqrt(x * x + y * y + z * z); }

/** \brief How far joint \a joint's coordinates can move its child frame's origin from the joint
    frame's (0 for joints that only turn it): by the bounds, infinite where one is infinite (an
    unbounded floating base, say; it matters only if a joint above it turns on an edge). */
double frameShift(const RobotModel &robot, const Joint &joint)
{
    auto largest = [&](std::size_t i) { return std::max(std::abs(joint.lower[i]), std::abs(joint.upper[i])); };
    switch (joint.kind)
    {
        case JointKind::Prismatic:
        {
            if (joint.mimicOf < 0)
                return largest(0);
            const Joint &source = robot.joints[static_cast<std::size_t>(joint.mimicOf)];
            const double a = joint.mimicMultiplier * source.lower[0] + joint.mimicOffset;
            const double b = joint.mimicMultiplier * source.upper[0] + joint.mimicOffset;
            return std::max(std::abs(a), std::abs(b));
        }
        case JointKind::Floating:
            return length(largest(0), largest(1), largest(2));
        case JointKind::Planar:
            return std::hypot(largest(0), largest(1));
        default:
            return 0.0;
    }
}

/** \brief The angle, in [0, pi], between the rotations of two quaternions (x y z w, any length; zero
    or non-finite = identity, as StateMapping reads them), by the formula that keeps small angles
    accurate: 4 atan2(|a - b|, |a + b|) for unit quaternions on the same hemisphere. */
double rotationAngle(const double *a, const double *b)
{
    double ua[4], ub[4];
    for (auto [in, out] : {std::pair<const double *, double *>{a, ua}, {b, ub}})
    {
        const double norm = std::sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2] + in[3] * in[3]);
        const bool usable = std::isfinite(norm) && norm > 0.0;
        for (int k = 0; k < 4; ++k)
            out[k] = usable ? in[k] / norm : (k == 3 ? 1.0 : 0.0);
    }
    const double sign = ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2] + ua[3] * ub[3] < 0.0 ? -1.0 : 1.0;
    double difference = 0.0, sum = 0.0;
    for (int k = 0; k < 4; ++k)
    {
        difference += (ua[k] - sign * ub[k]) * (ua[k] - sign * ub[k]);
        sum += (ua[k] + sign * ub[k]) * (ua[k] + sign * ub[k]);
    }
    return 4.0 * std::atan2(std::sqrt(difference), std::sqrt(sum));
}
}  // namespace

MotionBound::MotionBound(const RobotModel &robot) : reach_(robot.joints.size(), 0.0)
{
    // Bottom-up over the tree (joints are in topological order): how far the geometry of each
    // link's subtree can lie from that link's origin, and whether there is any.
    std::vector<double> subtreeReach(robot.links.size(), 0.0);
    std::vector<bool> carries(robot.links.size(), false);
    for (std::size_t l = 0; l < robot.links.size(); ++l)
    {
        const int c = robot.links[l].component;
        if (c < 0)
            continue;
        for (const Eigen::Vector3d &v : robot.components[static_cast<std::size_t>(c)].mesh.vertices)
            subtreeReach[l] = std::max(subtreeReach[l], v.norm());
        carries[l] = !robot.components[static_cast<std::size_t>(c)].mesh.triangles.empty();
    }
    for (std::size_t j = robot.joints.size(); j-- > 0;)
    {
        const Joint &joint = robot.joints[j];
        const auto child = static_cast<std::size_t>(joint.childLink);
        const auto parent = static_cast<std::size_t>(joint.parentLink);
        if (!carries[child])
            continue;
        reach_[j] = subtreeReach[child];
        carries[parent] = true;
        subtreeReach[parent] = std::max(subtreeReach[parent],
                                        joint.origin.translation().norm() + frameShift(robot, joint) + subtreeReach[child]);
    }
    for (const double r : reach_)
        if (std::isfinite(r))
            size_ = std::max(size_, r);

    for (std::size_t j = 0; j < robot.joints.size(); ++j)
    {
        const Joint &joint = robot.joints[j];
        if (joint.kind == JointKind::Fixed || !carries[static_cast<std::size_t>(joint.childLink)])
            continue;
        const Joint &driver = joint.mimicOf >= 0 ? robot.joints[static_cast<std::size_t>(joint.mimicOf)] : joint;
        if (driver.firstCoordinate < 0)
            continue;  // held by nothing: cannot move
        moving_.push_back({joint.kind, driver.firstCoordinate, driver.continuous,
                           joint.mimicOf >= 0, joint.mimicOf >= 0 ? joint.mimicMultiplier : 1.0, reach_[j]});
    }
}

double MotionBound::sweep(const double *qa, const double *qb) const
{
    // A joint that does not turn adds nothing, even with an infinite reach (a held floating base).
    auto turn = [](double angle, double reach) { return angle == 0.0 ? 0.0 : angle * reach; };
    const double infinity = std::numeric_limits<double>::infinity();
    double bound = 0.0;
    for (const MovingJoint &joint : moving_)
    {
        const double *a = qa + joint.firstCoordinate;
        const double *b = qb + joint.firstCoordinate;
        switch (joint.kind)
        {
            case JointKind::Revolute:
            case JointKind::Prismatic:
            {
                const double change = b[0] - a[0];
                double travel = std::abs(change);
                if (joint.wraps && travel > kPi)
                {
                    if (joint.mimic)
                        return infinity;  // the source jumps from pi to -pi; its follower jumps too
                    travel = std::abs(std::remainder(change, 2.0 * kPi));
                }
                travel *= std::abs(joint.multiplier);
                bound += joint.kind == JointKind::Revolute ? turn(travel, joint.reach) : travel;
                break;
            }
            case JointKind::Planar:
                bound += std::hypot(b[0] - a[0], b[1] - a[1]) +
                         turn(std::abs(std::remainder(b[2] - a[2], 2.0 * kPi)), joint.reach);
                break;
            case JointKind::Floating:
                bound += length(b[0] - a[0], b[1] - a[1], b[2] - a[2]) + turn(rotationAngle(a + 3, b + 3), joint.reach);
                break;
            default:
                break;
        }
    }
    return std::isnan(bound) ? infinity : bound;
}
}  // namespace rastercheck
