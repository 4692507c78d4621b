#pragma once

#include <utility>
#include <vector>

#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
struct RobotData;

/** \brief Bounds how far a robot's collision geometry can travel along a straight edge in
    configuration space: the basis of certified (continuous) edge checking.

    The edge from configuration qa to qb is the path the planner's state space interpolates
    (ompl::StateMapping's space): each coordinate linearly, except a continuous revolute joint's
    angle and a planar joint's angle, which turn the shorter way round (SO2), and a floating
    joint's quaternion, which turns along the shorter great arc (slerp). Every joint then moves at
    a constant rate, so a point x of a component has speed at most

        sum over joints j of  (translation rate of j) + (turn rate of j) * reach(j),

    where reach(j) bounds the distance from the centre joint j turns about (its child frame's
    origin) to the point, in every configuration within the bounds: the point's component radius,
    and for each joint between them the length of its origin offset plus the farthest its own
    coordinates can shift the next frame (prismatic and floating / planar translations, by their
    bounds). Each component gets its own reach per joint above it, so a link near the base is not
    held to the hand's speed. Hence for the positions x(s), x(t) of the same material point at
    fractions s, t of the edge

        |x(t) - x(s)| <= |t - s| * sweep(qa, qb),

    in the model's length unit. The bound is conservative, never tight on purpose: it ignores the
    directions of the axes. About a configuration whose link poses are known, reach(j) can be
    measured instead of bounded by the chain (the second sweeps(): distance from the axis at that
    configuration, plus what the joints below j move the point within a span of the edge around
    it): the certified validator pads refined intervals that way. Immutable; thread-safe. */
class MotionBound
{
public:
    /** \brief Never throws. A coordinate without finite bounds that shifts a frame (an unbounded
        floating or planar base) makes the reach of the joints above it infinite: edges that turn
        those joints get an infinite sweep. */
    explicit MotionBound(const RobotModel &robot);

    /** \brief The largest distance, in the model's length unit, that any point of any component travels
        from \a qa to \a qb (numCoordinates() values each; quaternions need not be normalised, a zero
        one counts as the identity). Infinite when the edge has a non-finite coordinate, turns a
        joint of infinite reach, or moves a continuous joint the short way across +-pi while a mimic
        joint follows it (the follower's value jumps there). */
    double sweep(const double *qa, const double *qb) const;

    /** \brief Finer bounds for the same edge. \a componentSweeps (numComponents() values): the
        farthest any point of each component travels (only the joints above it count).
        \a pairSweeps (one per entry of \a pairs, component indices): how much the distance between
        a point of the first component and a point of the second can change, which only the joints
        between them in the tree can do (the joints above both move them rigidly together: the
        distance is the same in their common ancestor's frame). Infinite where sweep() would be.
        Each such joint counts from either side, the nearer: a turn w about a centre c changes the
        distance between points a and b at the rate (b - a) / |b - a| . (w x (b - c)), which is
        also (b - a) / |b - a| . (w x (a - c)) since w x (b - a) is normal to b - a; so where the
        chain's bounds make the other component the nearer to the joint, the turn counts at the
        smaller of the carried component's reach and the other's distance from the joint (a UR5's
        base lies within 0.1 m of its shoulder-pan axis, which turns the upper arm at up to half a
        metre). */
    void sweeps(const double *qa, const double *qb, const std::vector<std::pair<int, int>> &pairs,
                double *componentSweeps, double *pairSweeps) const;

    /** \brief The same bounds (per unit of the edge) for the part of the edge within \a halfSpan
        (a fraction of it) of a configuration on it, tightened by where the links are there
        (\a reference: forwardKinematics at that configuration, as the state space interpolates the
        edge). A revolute joint moves a point by its turn times the point's distance from the
        joint's axis (not its centre); that distance is measured at the reference, for a sphere
        and a capsule holding the component (the nearer bound), and within the span it changes by
        at most what the joints between that joint and the component move the point there. Each
        reach is the smaller of that and the chain's bound, so these sweeps never exceed
        sweeps()'s. An arm's hand is turned by its base joint at its distance from the base's axis,
        not at the arm's full length; the shorter the span, the tighter. */
    void sweeps(const double *qa, const double *qb, const RobotData &reference, double halfSpan,
                const std::vector<std::pair<int, int>> &pairs, double *componentSweeps, double *pairSweeps) const;

    /** \brief Whether sweeps about a reference can be smaller than sweeps(): some component is turned
        by a revolute joint, or by a joint with other moving joints between it and the component. A
        lone floating or planar body never is (its points' distance from the joint's centre is the
        chain's bound already), so callers can skip the forward kinematics. */
    bool tightensAboutReferences() const { return tightens_; }

    /** \brief A joint that moves two components relative to each other (pairJoints()). */
    struct PairJoint
    {
        JointKind kind;
        int coordinate;  ///< the joint's first coordinate, or that of the joint it mimics
        bool wraps;      ///< a continuous revolute joint
        bool mimic;
    };
    /** \brief The moving joints above exactly one of components \a a and \b b: those whose travel
        pairSweeps counts for the pair, the only ones that change its points' distances. */
    std::vector<PairJoint> pairJoints(int a, int b) const;

    /** \brief reach(j) for every joint (model order): the bound on the distance from the centre joint
        j turns about to any point of the components below it. 0 for a joint that carries no
        geometry. */
    const std::vector<double> &jointReach() const { return reach_; }

    /** \brief The largest finite reach of any joint: the robot's size as its joints see it (used to
        scale default margins; 0 when no joint carries geometry). */
    double size() const { return size_; }

private:
    /** \brief What sweep() needs of a joint that carries geometry. */
    struct MovingJoint
    {
        JointKind kind;
        int childLink;
        Eigen::Vector3d axis;  ///< unit, in the child link's frame (revolute and prismatic joints)
        int firstCoordinate;  ///< of the joint itself, or of the joint it mimics
        bool wraps;           ///< a continuous revolute joint (its angle turns the shorter way round)
        bool mimic;
        double multiplier;  ///< mimic multiplier (1 otherwise)
    };
    /** \brief How far a moving joint's centre slides (m) and how far it turns (rad) along an edge. */
    struct Travel
    {
        double slide = 0.0;
        double turn = 0.0;
    };
    /** \brief A moving joint above a component, and the farthest the component's points can lie from
        its centre. */
    struct Carrier
    {
        int joint;  ///< index into moving_
        double distance;
    };

    void travels(const double *qa, const double *qb, std::vector<Travel> &travel) const;
    /** \brief Both sweeps() overloads: \a reference null for the chain's bounds alone. */
    void sweepsAlong(const double *qa, const double *qb, const RobotData *reference, double halfSpan,
                     const std::vector<std::pair<int, int>> &pairs, double *componentSweeps, double *pairSweeps) const;
    /** \brief Calls \a f(c, i) for each Carrier above_[c][i] above exactly one of components \a a
        and \a b. */
    template <class F>
    void forEachPairCarrier(int a, int b, F &&f) const;

    std::vector<MovingJoint> moving_;
    std::vector<std::vector<Carrier>> above_;  ///< per component, by ascending joint
    std::vector<std::size_t> firstCarrier_;    ///< per component: where its carriers start in a flat array
    std::vector<int> componentLink_;
    /** \brief Per moving joint, then per component (row-major): the farthest
        the component's points can lie from the joint's centre in any configuration (its radius
        plus the joints' offsets and shifts along the tree path between them). */
    std::vector<double> centreDistance_;
    /** \brief Per component (link frame), a sphere and a capsule (a segment along its box's longest
        axis, widened by the other two half extents) that hold its vertices: what sweeps() about a
        reference measures, the nearer of the two. */
    std::vector<Eigen::Vector3d> sphereCentre_;
    std::vector<double> sphereRadius_;
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> capsuleEnds_;
    std::vector<double> capsuleRadius_;
    bool tightens_ = false;
    std::vector<double> reach_;
    double size_ = 0.0;
};
}  // namespace rastercheck
