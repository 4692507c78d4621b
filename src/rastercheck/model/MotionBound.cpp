#include "rastercheck/model/MotionBound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rastercheck/geometry/Obb.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

/** \brief sqrt(x^2 + y^2 + z^2), infinite when one is (libstdc++'s three-argument std::hypot
    returns NaN for infinite arguments). */
double length(double x, double y, double z)
{
    return std::sqrt(x * x + y * y + z * z);
}

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
    std::vector<double> radius(robot.components.size(), 0.0);  // of each component, from its link's origin
    for (std::size_t c = 0; c < robot.components.size(); ++c)
        for (const Eigen::Vector3d &v : robot.components[c].mesh.vertices)
            radius[c] = std::max(radius[c], v.norm());
    std::vector<double> subtreeReach(robot.links.size(), 0.0);
    std::vector<bool> carries(robot.links.size(), false);
    for (std::size_t l = 0; l < robot.links.size(); ++l)
    {
        const int c = robot.links[l].component;
        if (c < 0)
            continue;
        subtreeReach[l] = radius[static_cast<std::size_t>(c)];
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
        subtreeReach[parent] = std::max(
            subtreeReach[parent], joint.origin.translation().norm() + frameShift(robot, joint) + subtreeReach[child]);
    }
    for (const double r : reach_)
        if (std::isfinite(r))
            size_ = std::max(size_, r);

    // Between any two links' frames, the tree path's offsets and shifts bound their origins'
    // distance in every configuration: from each moving joint's centre (its child frame's origin)
    // to every component's points (centreDistance_, filled below once moving_ is known), whether
    // the joint carries the component or not.
    auto pathLengthsFrom = [&](int startLink)
    {
        std::vector<double> lengths(robot.links.size(), std::numeric_limits<double>::infinity());
        std::vector<bool> reached(robot.links.size(), false);
        lengths[static_cast<std::size_t>(startLink)] = 0.0;
        reached[static_cast<std::size_t>(startLink)] = true;
        std::vector<int> stack{startLink};
        while (!stack.empty())
        {
            const int link = stack.back();
            stack.pop_back();
            auto visit = [&](int next, const Joint &joint)
            {
                if (reached[static_cast<std::size_t>(next)])
                    return;
                reached[static_cast<std::size_t>(next)] = true;
                // Infinite past an unbounded shift (a free-floating base): that side is never the nearer.
                lengths[static_cast<std::size_t>(next)] = lengths[static_cast<std::size_t>(link)] +
                                                          joint.origin.translation().norm() + frameShift(robot, joint);
                stack.push_back(next);
            };
            for (const Joint &joint : robot.joints)
            {
                if (joint.parentLink == link)
                    visit(joint.childLink, joint);
                else if (joint.childLink == link)
                    visit(joint.parentLink, joint);
            }
        }
        return lengths;
    };

    std::vector<int> movingIndex(robot.joints.size(), -1);
    for (std::size_t j = 0; j < robot.joints.size(); ++j)
    {
        const Joint &joint = robot.joints[j];
        if (joint.kind == JointKind::Fixed || !carries[static_cast<std::size_t>(joint.childLink)])
            continue;
        const Joint &driver = joint.mimicOf >= 0 ? robot.joints[static_cast<std::size_t>(joint.mimicOf)] : joint;
        if (driver.firstCoordinate < 0)
            continue;  // held by nothing: cannot move
        movingIndex[j] = static_cast<int>(moving_.size());
        moving_.push_back({joint.kind, joint.childLink, joint.axis.normalized(), driver.firstCoordinate,
                           driver.continuous, joint.mimicOf >= 0, joint.mimicOf >= 0 ? joint.mimicMultiplier : 1.0});
    }
    for (const MovingJoint &joint : moving_)
    {
        const std::vector<double> lengths = pathLengthsFrom(joint.childLink);
        for (std::size_t c = 0; c < robot.components.size(); ++c)
            centreDistance_.push_back(lengths[static_cast<std::size_t>(robot.components[c].link)] + radius[c]);
    }
    // Per component, up its chain: the moving joints that carry it, each with how far its points
    // can lie from the joint's centre (centreDistance_). A joint near the base turns a link near
    // the base through a small radius, whatever the hand below does.
    for (std::size_t c = 0; c < robot.components.size(); ++c)
    {
        const Component &component = robot.components[c];
        std::vector<Carrier> above;
        for (int link = component.link; link >= 0;)
        {
            const int j = robot.links[static_cast<std::size_t>(link)].parentJoint;
            if (j < 0)
                break;
            const int k = movingIndex[static_cast<std::size_t>(j)];
            if (k >= 0)
                above.push_back({k, centreDistance_[static_cast<std::size_t>(k) * robot.components.size() + c]});
            link = robot.joints[static_cast<std::size_t>(j)].parentLink;
        }
        std::sort(above.begin(), above.end(), [](const Carrier &a, const Carrier &b) { return a.joint < b.joint; });
        firstCarrier_.push_back(c == 0 ? 0 : firstCarrier_.back() + above_.back().size());
        above_.push_back(std::move(above));
        // A sphere about the vertices' box centre: what sweeps() about a reference measures.
        const Aabb &box = component.localAabb;
        const Eigen::Vector3d centre = box.empty() ? Eigen::Vector3d::Zero() : box.center();
        double sphere = 0.0;
        for (const Eigen::Vector3d &v : component.mesh.vertices)
            sphere = std::max(sphere, (v - centre).norm());
        for (const Carrier &carrier : above_.back())
            tightens_ = tightens_ || above_.back().size() > 1 ||
                        moving_[static_cast<std::size_t>(carrier.joint)].kind == JointKind::Revolute;
        componentLink_.push_back(component.link);
        sphereCentre_.push_back(centre);
        sphereRadius_.push_back(sphere);
        const Obb &obb = component.localObb;
        Eigen::Index longest = 0;
        obb.halfExtents.maxCoeff(&longest);
        const Eigen::Vector3d half = obb.halfExtents(longest) * obb.axes.col(longest);
        capsuleEnds_.emplace_back(obb.center - half, obb.center + half);
        capsuleRadius_.push_back(
            std::sqrt(obb.halfExtents.squaredNorm() - obb.halfExtents(longest) * obb.halfExtents(longest)));
    }
}

void MotionBound::travels(const double *qa, const double *qb, std::vector<Travel> &travel) const
{
    const double infinity = std::numeric_limits<double>::infinity();
    travel.assign(moving_.size(), Travel{});
    for (std::size_t k = 0; k < moving_.size(); ++k)
    {
        const MovingJoint &joint = moving_[k];
        const double *a = qa + joint.firstCoordinate;
        const double *b = qb + joint.firstCoordinate;
        Travel &out = travel[k];
        switch (joint.kind)
        {
            case JointKind::Revolute:
            case JointKind::Prismatic:
            {
                const double change = b[0] - a[0];
                double value = std::abs(change);
                if (joint.wraps && value > kPi)
                {
                    if (joint.mimic)
                    {
                        out.slide = infinity;  // the source jumps from pi to -pi; its follower jumps too
                        break;
                    }
                    value = std::abs(std::remainder(change, 2.0 * kPi));
                }
                value *= std::abs(joint.multiplier);
                (joint.kind == JointKind::Revolute ? out.turn : out.slide) = value;
                break;
            }
            case JointKind::Planar:
                out.slide = std::hypot(b[0] - a[0], b[1] - a[1]);
                out.turn = std::abs(std::remainder(b[2] - a[2], 2.0 * kPi));
                break;
            case JointKind::Floating:
                out.slide = length(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
                out.turn = rotationAngle(a + 3, b + 3);
                break;
            default:
                break;
        }
        if (std::isnan(out.slide) || std::isnan(out.turn))
            out = {infinity, 0.0};  // a non-finite coordinate (no NaN may reach the sums)
    }
}

template <class F>
void MotionBound::forEachPairCarrier(int first, int second, F &&f) const
{
    // The joints above exactly one of the two: both lists ascend, so merge them.
    const std::vector<Carrier> &a = above_[static_cast<std::size_t>(first)];
    const std::vector<Carrier> &b = above_[static_cast<std::size_t>(second)];
    std::size_t x = 0, y = 0;
    while (x < a.size() || y < b.size())
    {
        if (y == b.size() || (x < a.size() && a[x].joint < b[y].joint))
            f(first, x++);
        else if (x == a.size() || b[y].joint < a[x].joint)
            f(second, y++);
        else
            ++x, ++y;  // above both
    }
}

double MotionBound::sweep(const double *qa, const double *qb) const
{
    std::vector<double> componentSweeps(above_.size());
    sweeps(qa, qb, {}, componentSweeps.data(), nullptr);
    double largest = 0.0;
    for (const double s : componentSweeps)
        largest = std::max(largest, s);
    return largest;
}

void MotionBound::sweeps(const double *qa, const double *qb, const std::vector<std::pair<int, int>> &pairs,
                         double *componentSweeps, double *pairSweeps) const
{
    sweepsAlong(qa, qb, nullptr, 0.0, pairs, componentSweeps, pairSweeps);
}

void MotionBound::sweeps(const double *qa, const double *qb, const RobotData &reference, double halfSpan,
                         const std::vector<std::pair<int, int>> &pairs, double *componentSweeps,
                         double *pairSweeps) const
{
    sweepsAlong(qa, qb, &reference, halfSpan, pairs, componentSweeps, pairSweeps);
}

void MotionBound::sweepsAlong(const double *qa, const double *qb, const RobotData *reference, double halfSpan,
                              const std::vector<std::pair<int, int>> &pairs, double *componentSweeps,
                              double *pairSweeps) const
{
    // Per thread, kept between calls: a certified edge asks for these once per part of the edge.
    thread_local std::vector<Travel> travel;
    thread_local std::vector<double> moved;
    thread_local std::vector<Eigen::Vector3d> axes;  // each turning joint's axis at the reference
    thread_local std::vector<Eigen::Vector3d> holders;  // per component at the reference: sphere centre, capsule ends
    thread_local std::vector<double> fromAxis;          // distanceAtReference per (joint, component), once each
    travels(qa, qb, travel);
    if (reference)
    {
        axes.resize(moving_.size());
        for (std::size_t k = 0; k < moving_.size(); ++k)
            axes[k] = reference->oMl[static_cast<std::size_t>(moving_[k].childLink)].linear() * moving_[k].axis;
        holders.resize(3 * above_.size());
        for (std::size_t c = 0; c < above_.size(); ++c)
        {
            const Eigen::Isometry3d &pose = reference->oMl[static_cast<std::size_t>(componentLink_[c])];
            holders[3 * c] = pose * sphereCentre_[c];
            holders[3 * c + 1] = pose * capsuleEnds_[c].first;
            holders[3 * c + 2] = pose * capsuleEnds_[c].second;
        }
        fromAxis.assign(moving_.size() * above_.size(), -1.0);
    }
    // At the reference, the farthest point of component c's sphere or capsule (whose ends are its
    // farthest from a line or a point) from the line joint k turns about (a planar or floating
    // joint: its centre), the nearer of the two bounds.
    auto distanceAtReference = [&](std::size_t k, std::size_t c)
    {
        double &known = fromAxis[k * above_.size() + c];
        if (known >= 0.0)
            return known;
        const MovingJoint &joint = moving_[k];
        const Eigen::Vector3d &pivot = reference->oMl[static_cast<std::size_t>(joint.childLink)].translation();
        const bool aboutAxis = joint.kind == JointKind::Revolute;
        auto distance = [&](const Eigen::Vector3d &point)
        {
            const Eigen::Vector3d offset = point - pivot;
            return aboutAxis ? (offset - offset.dot(axes[k]) * axes[k]).norm() : offset.norm();
        };
        known = std::min(distance(holders[3 * c]) + sphereRadius_[c],
                         std::max(distance(holders[3 * c + 1]), distance(holders[3 * c + 2])) + capsuleRadius_[c]);
        return known;
    };
    // How far each carrier's joint moves its component's points, per component from the joint
    // nearest to it up to the base: a joint that does not turn adds only its slide, even at an
    // infinite distance (a held floating base).
    moved.resize(above_.empty() ? 0 : firstCarrier_.back() + above_.back().size());
    for (std::size_t c = 0; c < above_.size(); ++c)
    {
        const std::vector<Carrier> &above = above_[c];
        double inner = 0.0;  // what the joints between the carrier and the component move its points
        for (std::size_t i = above.size(); i-- > 0;)
        {
            const auto k = static_cast<std::size_t>(above[i].joint);
            const Travel &t = travel[k];
            double reach = above[i].distance;
            if (reference && t.turn != 0.0)
            {
                // Turning about its axis keeps a point's distance from it; only the joints between
                // them change it, by at most their travel over the half span on either side.
                const double tightened = distanceAtReference(k, c) + halfSpan * inner;
                if (tightened < reach)  // false for NaN: the chain's bound stands
                    reach = tightened;
            }
            const double m = t.slide + (t.turn == 0.0 ? 0.0 : t.turn * reach);
            moved[firstCarrier_[c] + i] = m;
            inner += m;
        }
        componentSweeps[c] = inner;
    }
    // A pair's joints, each counted from the nearer side (see sweeps()): the carried component's
    // reach, as above, or the other component's distance from the joint's centre in any
    // configuration, or at the reference its distance from the joint's axis plus what the pair's
    // joints between them (all of the other's own, and the carried side's above this one) move it
    // within the span. In ascending (topological) order each side's joints above the current one
    // are a running sum.
    const std::size_t components = above_.size();
    for (std::size_t i = 0; i < pairs.size(); ++i)
    {
        const int first = pairs[i].first, second = pairs[i].second;
        // Each side's own joints, what they move it: all of its carriers' moves but those of the
        // joints above both (the common ancestors, first in both ascending lists).
        double own[2] = {componentSweeps[first], componentSweeps[second]};
        const std::vector<Carrier> &a = above_[static_cast<std::size_t>(first)];
        const std::vector<Carrier> &b = above_[static_cast<std::size_t>(second)];
        for (std::size_t x = 0; x < a.size() && x < b.size() && a[x].joint == b[x].joint; ++x)
        {
            own[0] -= moved[firstCarrier_[static_cast<std::size_t>(first)] + x];
            own[1] -= moved[firstCarrier_[static_cast<std::size_t>(second)] + x];
        }
        double above[2] = {0.0, 0.0};  // each side's joints so far: what they move the other side
        double sum = 0.0;
        forEachPairCarrier(first, second,
                           [&](int c, std::size_t carrier)
                           {
                               const int side = c == first ? 0 : 1;
                               const auto other = static_cast<std::size_t>(side == 0 ? second : first);
                               const auto k =
                                   static_cast<std::size_t>(above_[static_cast<std::size_t>(c)][carrier].joint);
                               const Travel &t = travel[k];
                               double m = moved[firstCarrier_[static_cast<std::size_t>(c)] + carrier];
                               const double fromCentre = centreDistance_[k * components + other];
                               // Only where the other side is the nearer by the chain's bounds (the UR5's base
                               // about its shoulder joints): elsewhere measuring it costs more than it saves.
                               if (t.turn != 0.0 && fromCentre < above_[static_cast<std::size_t>(c)][carrier].distance)
                               {
                                   double reach = fromCentre;
                                   const double moves = halfSpan * (own[1 - side] + above[side]);
                                   // Measured only where it can beat the carried side (it is at least the moves).
                                   if (reference && t.slide + t.turn * moves < m)
                                   {
                                       const double tightened = distanceAtReference(k, other) + moves;
                                       if (tightened < reach)  // false for NaN
                                           reach = tightened;
                                   }
                                   const double fromOther = t.slide + t.turn * reach;
                                   if (fromOther < m)  // false for NaN
                                       m = fromOther;
                               }
                               above[side] += t.slide + (t.turn == 0.0 ? 0.0 : t.turn * fromCentre);
                               sum += m;
                           });
        pairSweeps[i] = sum;
    }
}

std::vector<MotionBound::PairJoint> MotionBound::pairJoints(int a, int b) const
{
    std::vector<PairJoint> joints;
    forEachPairCarrier(a, b,
                       [&](int c, std::size_t i)
                       {
                           const Carrier &carrier = above_[static_cast<std::size_t>(c)][i];
                           const MovingJoint &joint = moving_[static_cast<std::size_t>(carrier.joint)];
                           joints.push_back({joint.kind, joint.firstCoordinate, joint.wraps, joint.mimic});
                       });
    return joints;
}
}  // namespace rastercheck
