#include "rastercheck/collision/SelfPairTables.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/core/Parallel.h"
#include "rastercheck/device/Kinematics.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/model/MotionBound.h"

namespace rastercheck
{
namespace
{
constexpr int kMaxNodesPerAxis = 64;

/** \brief The coordinates that move components \a a and \a b relative to each other: those of
    the joints MotionBound counts in their pair sweep (so the table's axes and its sweep rest on one
    definition), or false when one of those joints does not qualify (SelfPairTables' class
    comment) or more than two move. \a followed: per coordinate, whether a mimic joint follows it. */
bool pairCoordinates(const RobotModel &robot, const MotionBound &bound, int a, int b, const std::vector<bool> &followed,
                     std::vector<int> &coordinates)
{
    coordinates.clear();
    for (const MotionBound::PairJoint &joint : bound.pairJoints(a, b))
    {
        const bool oneCoordinate = joint.kind == JointKind::Revolute || joint.kind == JointKind::Prismatic;
        const auto c = static_cast<std::size_t>(joint.coordinate);
        if (!oneCoordinate || joint.wraps || joint.mimic || followed[c])
            return false;
        if (!std::isfinite(robot.lowerBounds[c]) || !std::isfinite(robot.upperBounds[c]))
            return false;
        if (robot.upperBounds[c] > robot.lowerBounds[c])
            coordinates.push_back(joint.coordinate);
    }
    return coordinates.size() <= 2;
}
}  // namespace

SelfPairTables::SelfPairTables(const CollisionModel &model)
{
    const RobotModel &robot = *model.robot;
    tableOf_.assign(model.selfPairs.size(), -1);
    if (model.selfPairs.empty())
        return;
    const MotionBound bound(robot);
    const double size = bound.size();
    if (!(size > 0) || !std::isfinite(size))
        return;
    // A configuration for the rest of the robot: zero within the bounds, identity quaternions.
    const std::size_t dof = robot.numCoordinates();
    std::vector<double> canonical(dof);
    for (std::size_t i = 0; i < dof; ++i)
        canonical[i] = std::isfinite(robot.lowerBounds[i]) && std::isfinite(robot.upperBounds[i])
                           ? std::clamp(0.0, robot.lowerBounds[i], robot.upperBounds[i])
                           : 0.0;
    for (int start : model.quaternionStarts)
        canonical[static_cast<std::size_t>(start) + 3] = 1.0;
    // Paddings tried per node: 0, then from size / 1024 (about 1 mm for an arm) up by half each.
    std::vector<double> ladder{0.0};
    for (double p = size / 1024; ladder.size() < 13; p *= 1.5)
        ladder.push_back(p);
    const double target = size / 512;  // the largest sweep to a node, per axis, where nodes allow

    std::vector<double> componentSweeps(model.components.size());
    const device::ConvexArrays arrays = model.convex.arrays();
    std::vector<bool> followed(dof, false);
    for (const Joint &joint : robot.joints)
        if (joint.mimicOf >= 0 && robot.joints[static_cast<std::size_t>(joint.mimicOf)].firstCoordinate >= 0)
            followed[static_cast<std::size_t>(robot.joints[static_cast<std::size_t>(joint.mimicOf)].firstCoordinate)] =
                true;
    std::vector<int> coordinates;
    for (std::size_t p = 0; p < model.selfPairs.size(); ++p)
    {
        const int a = model.selfPairs[p].first, b = model.selfPairs[p].second;  // (a lambda below reads them)
        if (!pairCoordinates(robot, bound, a, b, followed, coordinates))
            continue;
        device::ClearanceTable table;
        table.numAxes = static_cast<int>(coordinates.size());
        std::size_t numNodes = 1;
        bool finiteRates = true;
        for (int k = 0; k < table.numAxes; ++k)
        {
            device::ClearanceAxis &axis = table.axes[k];
            axis.coordinate = coordinates[static_cast<std::size_t>(k)];
            const auto c = static_cast<std::size_t>(axis.coordinate);
            axis.lower = robot.lowerBounds[c];
            const double range = robot.upperBounds[c] - axis.lower;
            // The pair sweep over the whole range, per unit: MotionBound's bound is a sum of each
            // joint's travel times a reach that holds in every configuration, so it is linear.
            std::vector<double> from = canonical, to = canonical;
            from[c] = axis.lower;
            to[c] = robot.upperBounds[c];
            double pairSweep = 0.0;
            bound.sweeps(from.data(), to.data(), {{a, b}}, componentSweeps.data(), &pairSweep);
            axis.rate = pairSweep / range;
            if (!std::isfinite(axis.rate))
            {
                finiteRates = false;
                break;
            }
            axis.nodes = std::clamp(static_cast<int>(std::ceil(pairSweep / (2 * target))) + 1, 2, kMaxNodesPerAxis);
            axis.step = range / (axis.nodes - 1);
            numNodes *= static_cast<std::size_t>(axis.nodes);
        }
        if (!finiteRates)
            continue;
        table.firstClearance = clearance_.size();
        clearance_.resize(clearance_.size() + numNodes);
        // The nodes on OpenMP's threads: each is a few proofs of its own (about 11 ms per table for
        // the Panda's, half a second in all for the UR5's).
        parallelFor(numNodes,
                    [&](std::size_t node)
                    {
                        std::vector<double> q = canonical, jointValues(robot.kinematicJoints.size() + 1);
                        std::vector<device::Pose<double>> links(robot.links.size());
                        std::size_t rest = node;
                        for (int k = table.numAxes; k-- > 0;)
                        {
                            const device::ClearanceAxis &axis = table.axes[k];
                            const auto index = static_cast<int>(rest % static_cast<std::size_t>(axis.nodes));
                            rest /= static_cast<std::size_t>(axis.nodes);
                            q[static_cast<std::size_t>(axis.coordinate)] =
                                axis.lower + index * axis.step;  // as apart() places it
                        }
                        device::linkPoses(robot.kinematicJoints.data(), static_cast<int>(robot.kinematicJoints.size()),
                                          q.data(), jointValues.data(), links.data());
                        const auto provenApart = [&](double padding)
                        {
                            return device::relateSolids(arrays, static_cast<std::uint32_t>(a),
                                                        links[model.componentLink[a]], static_cast<std::uint32_t>(b),
                                                        links[model.componentLink[b]], padding,
                                                        false) == device::HullRelation::Apart;
                        };
                        // The largest padding on the ladder proven (a binary search: the proofs hold
                        // for every smaller padding in practice; any value proven is sound either way).
                        double clearance = -std::numeric_limits<double>::infinity();
                        if (provenApart(0.0))
                        {
                            std::size_t low = 0, high = ladder.size();  // ladder[low] proven; ladder[high] not
                            while (high - low > 1)
                            {
                                const std::size_t middle = (low + high) / 2;
                                (provenApart(ladder[middle]) ? low : high) = middle;
                            }
                            clearance = ladder[low];
                        }
                        float stored = static_cast<float>(clearance);
                        if (static_cast<double>(stored) > clearance)
                            stored = std::nextafter(stored, -std::numeric_limits<float>::infinity());
                        clearance_[table.firstClearance + node] = stored;
                    });
        tableOf_[p] = static_cast<int>(tables_.size());
        tables_.push_back(table);
    }
}

bool SelfPairTables::apart(std::size_t pair, const double *q, double padding) const
{
    return pair < tableOf_.size() && device::selfPairApartByTable(arrays(), pair, q, padding);
}

std::size_t SelfPairTables::memoryBytes() const
{
    return tableOf_.size() * sizeof(int) + tables_.size() * sizeof(device::ClearanceTable) +
           clearance_.size() * sizeof(float);
}
}  // namespace rastercheck
