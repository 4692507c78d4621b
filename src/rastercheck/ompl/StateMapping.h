#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <ompl/base/State.h>
#include <ompl/base/StateSpace.h>

#include "rastercheck/model/Bounds.h"
#include "rastercheck/model/RobotModel.h"

namespace rastercheck::ompl
{
/** \brief Options of a StateMapping. */
struct StateMappingOptions
{
    /** \brief Coordinates (by name, RobotModel::coordinateNames) that are not planned: they keep the
        given value (rad or m) in every configuration the mapping produces. A floating joint's
        quaternion (qx qy qz qw) is held entirely or not at all. Example: a crane whose mobile-base
        coordinates are held while the superstructure is planned. */
    std::map<std::string, double> heldCoordinates;
    /** \brief How far outside a joint limit (rad or m) a given start or goal may lie and still be
        moved onto it (setStartAndGoal, fitToBounds); >= 0. */
    double boundsTolerance = kDefaultBoundsTolerance;
};

/** \brief The OMPL state space of a robot and the conversion between its states and the robot's
    configuration vectors (RobotModel::coordinateNames order, rad or m).

    The planned coordinates are grouped, in active-joint (configuration) order, into these blocks:
    - consecutive bounded coordinates (revolute, prismatic, and the parts of a floating / planar
      joint that are not an orientation) share one RealVectorStateSpace, bounded by the model bounds,
      dimension names = coordinate names;
    - a continuous revolute joint is an SO2StateSpace;
    - a planar joint (x y theta) is an SE2StateSpace; a floating joint (x y z qx qy qz qw) an
      SE3StateSpace whose position is bounded by the joint bounds;
    - when some coordinates of a floating joint are held, its planned position coordinates are real
      coordinates and a planned quaternion is an SO3StateSpace; likewise a planar joint with held
      coordinates contributes real x / y and an SO2 theta.
    One block is the state space itself; several form a CompoundStateSpace (weights 1) with the blocks
    as subspaces in that order, and a default projection (the largest subspace's) so that
    projection-based planners (KPIECE, SBL, ...) run on it.

    Quaternions read from a configuration are normalised (OMPL asserts unit length). Immutable after
    construction; conversions are thread-safe. */
class StateMapping
{
public:
    /** \brief Throws ConfigurationError on an unknown held coordinate, a partly held quaternion,
        nothing left to plan, or a planned real coordinate without finite bounds. */
    explicit StateMapping(RobotModelConstPtr robot, const StateMappingOptions &options = {});

    /** \brief The state space (bounds set; not yet set up). */
    const ::ompl::base::StateSpacePtr &getStateSpace() const { return space_; }

    const RobotModel &robot() const { return *robot_; }
    const RobotModelConstPtr &robotPtr() const { return robot_; }

    /** \brief Length of a configuration vector (the robot's coordinate count). */
    std::size_t numCoordinates() const { return robot_->numCoordinates(); }

    /** \brief Indices of the planned coordinates, in the order the state space stores them. */
    const std::vector<int> &plannedCoordinates() const { return planned_; }

    /** \brief Whether coordinate \a index is held (not planned). */
    bool isHeld(int index) const { return held_[static_cast<std::size_t>(index)]; }

    /** \brief StateMappingOptions::boundsTolerance. */
    double boundsTolerance() const { return boundsTolerance_; }

    /** \brief The configuration every conversion starts from: the robot's neutral configuration with
        the held values written in. */
    const std::vector<double> &baseConfiguration() const { return base_; }

    /** \brief Writes the robot configuration of \a state into \a q (numCoordinates() values); held
        coordinates receive their held values. */
    void toConfiguration(const ::ompl::base::State *state, double *q) const;
    std::vector<double> toConfiguration(const ::ompl::base::State *state) const;

    /** \brief Sets \a state from configuration \a q (numCoordinates() values; held coordinates are
        ignored). Angles of SO2 blocks are wrapped to [-pi, pi); quaternions are normalised (a zero
        or non-finite quaternion becomes the identity). */
    void fromConfiguration(const double *q, ::ompl::base::State *state) const;
    void fromConfiguration(const std::vector<double> &q, ::ompl::base::State *state) const;

private:
    enum class BlockKind
    {
        RealVector,
        SO2,
        SO3,
        SE2,
        SE3
    };
    /** \brief One subspace and the configuration indices it stores, in its own order (SE3: x y z
        qx qy qz qw, SE2: x y theta, SO3: qx qy qz qw). */
    struct Block
    {
        BlockKind kind;
        std::vector<int> coordinates;
    };

    const ::ompl::base::State *blockState(const ::ompl::base::State *state, std::size_t block) const;
    ::ompl::base::State *blockState(::ompl::base::State *state, std::size_t block) const;

    RobotModelConstPtr robot_;
    std::vector<Block> blocks_;
    std::vector<int> planned_;
    std::vector<bool> held_;
    std::vector<double> base_;
    double boundsTolerance_;
    ::ompl::base::StateSpacePtr space_;
    bool compound_ = false;
};

using StateMappingPtr = std::shared_ptr<StateMapping>;
using StateMappingConstPtr = std::shared_ptr<const StateMapping>;
}  // namespace rastercheck::ompl
