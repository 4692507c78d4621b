#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <ompl/geometric/SimpleSetup.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rastercheck::ompl
{
/** \brief Which motion validator checks the planner's edges. */
enum class EdgeChecking
{
    /** \brief Certified, except in raster mode (which cannot certify an edge): Batched there
        (default). */
    Auto,
    /** \brief rastercheck::ompl::MotionValidator: DiscreteMotionValidator's states and verdicts, checked
        in batches. Collision-free at the sampled states only. */
    Batched,
    /** \brief OMPL's own DiscreteMotionValidator, one state at a time (the reference for Batched). */
    Discrete,
    /** \brief CertifiedMotionValidator: collision-free at every point of an accepted edge. Needs safe,
        exact or conservative mode. */
    Certified
};

/** \brief \a edges with Auto resolved for \a mode: Certified, or Batched in raster mode (which
    cannot certify an edge). */
EdgeChecking resolveEdgeChecking(EdgeChecking edges, CollisionMode mode);

/** \brief "auto", "batched", "discrete" or "certified"; throws ConfigurationError otherwise. */
EdgeChecking parseEdgeChecking(const std::string &text);

/** \brief How makeSimpleSetup builds a planning context. */
struct SetupOptions
{
    /** \brief Backend and threads of the Checker (threads are used by batch calls: the motion
        validator's batches). */
    CheckerOptions checker;
    /** \brief A Checker of the problem's robot to use instead of building one from \a checker
        (which is then ignored): the Python module's Checker plans and checks edges over the
        collision model it already built. Null: a new Checker. */
    CheckerConstPtr existingChecker;
    /** \brief Mode, padding, ... of every state check. */
    CollisionRequest request;
    /** \brief Coordinates held fixed (StateMappingOptions::heldCoordinates). */
    std::map<std::string, double> heldCoordinates;
    /** \brief How far outside a joint limit (rad or m) a start or goal given to setStartAndGoal may
        lie and still be moved onto it, with a warning (StateMappingOptions::boundsTolerance); a goal
        joint constraint's own tolerance counts where larger. Farther outside is an error. */
    double boundsTolerance = kDefaultBoundsTolerance;
    /** \brief StateSpace::setLongestValidSegmentFraction: edge resolution as a fraction of the space's
        maximum extent (OMPL's default is 0.01). Certified edges do not use it. */
    double longestValidSegmentFraction = 0.01;
    /** \brief How edges are checked (EdgeChecking). Certified by default: among the Panda
        MotionBenchMaker problems it solves 209/210 where batched edges solve 170 and return 40
        colliding paths, and among meshes batched edges return colliding paths (docs/benchmarks.md). */
    EdgeChecking edges = EdgeChecking::Auto;
    /** \brief First batch size of the batched motion validator. */
    unsigned int rakeWidth = 8;
    /** \brief Margin, levels and rake width of the certified motion validator. */
    CertifiedMotionOptions certified;
};

/** \brief A SimpleSetup for \a problem: the StateMapping's space (bounds = the model bounds; for an
    OMPL.app problem those are its volume bounds), a StateValidityChecker over a new Checker of the
    problem's robot and scene, and the motion validator chosen in \a options. Start and goal are
    not set (see setStartAndGoal). Throws ConfigurationError on bad options, and when
    options.existingChecker does not check the problem's robot. */
::ompl::geometric::SimpleSetupPtr makeSimpleSetup(const Problem &problem, const SetupOptions &options = {});

/** \brief The rastercheck validity checker of \a setup (its mapping, checker and request). Throws
    ConfigurationError when \a setup's checker is not one. */
StateValidityCheckerPtr getStateValidityChecker(const ::ompl::geometric::SimpleSetup &setup);

/** \brief States the rastercheck checker of \a setup decided since the last resetCheckedStates() (0
    for another validity checker and edge checker): single states
    (isValid, areValid) and the states of edges (MotionValidator, CertifiedMotionValidator; OMPL's own
    edge checker calls isValid). Not counted: the exact re-check of paths, which checks on its own. */
std::uint64_t checkedStates(const ::ompl::geometric::SimpleSetup &setup);
void resetCheckedStates(const ::ompl::geometric::SimpleSetup &setup);

/** \brief What configurationFromJoints does with a joint the robot lacks. */
enum class UnknownJoints
{
    Error,  ///< ConfigurationError naming the joint (a goal that cannot be met)
    /** \brief One warning listing them, then ignored: a MoveIt start state lists the whole robot's
        joints, also those a reduced model leaves out (MotionBenchMaker's Fetch requests name its
        wheels, which VAMP's fetch.urdf lacks). */
    Skip
};

/** \brief \a base with the joints of \a joints (name -> position, rad or m) written in. Joints that
    consume no coordinate (fixed, mimic) are skipped; held coordinates keep their value in \a base
    (a warning when the request disagrees by more than 1e-9). Throws ConfigurationError naming the
    joint for a joint with several coordinates, and for a joint the robot lacks unless \a unknown
    is Skip. \a what names the configuration in messages ("start", "goal"). */
std::vector<double> configurationFromJoints(const StateMapping &mapping, const std::map<std::string, double> &joints,
                                            const std::string &what, UnknownJoints unknown = UnknownJoints::Error);

/** \brief Start (start_state.joint_state) and goal (goal_constraints[0] joint positions) of a MoveIt
    request as configurations in robot coordinate order: coordinates the request does not name keep
    their neutral (or held) values; start joints the robot lacks are skipped with a warning
    (UnknownJoints::Skip); goal joints it lacks are a ConfigurationError. What `rastercheck view` and
    `render` show for a request; setStartAndGoal moves them onto the bounds first. */
std::pair<std::vector<double>, std::vector<double>> startAndGoal(const StateMapping &mapping,
                                                                 const MotionPlanRequest &request);

/** \brief \a q with every coordinate within the mapping's boundsTolerance() (or, where larger, the
    per-coordinate \a slackDown / \a slackUp of fitToBounds) outside a joint limit moved onto it, with
    one warning per coordinate naming the joint, its value and the bound. Throws ConfigurationError
    naming the same for a coordinate farther outside. \a what names the configuration ("start",
    "goal"). */
std::vector<double> ontoBounds(const StateMapping &mapping, std::vector<double> q, const std::string &what,
                               const std::vector<double> &slackDown = {}, const std::vector<double> &slackUp = {});

/** \brief Start and goal of an OMPL.app problem (its start / goal configurations). */
void setStartAndGoal(::ompl::geometric::SimpleSetup &setup, const OmplAppProblem &problem);

/** \brief The optimization objective of an OMPL.app problem ([problem] objective): path length, with
    its threshold, for "length"; nothing when absent. Throws ConfigurationError for another. */
void setObjective(::ompl::geometric::SimpleSetup &setup, const OmplAppProblem &problem);

/** \brief Start and goal of a MoveIt request (startAndGoal), both moved
    onto the bounds within the tolerance (ontoBounds), the goal also within its joint constraints'
    tolerance_below / tolerance_above (MoveIt accepts a goal anywhere in that band). Start joints
    the robot lacks are skipped with a warning (UnknownJoints::Skip); goal joints it lacks are a
    ConfigurationError. */
void setStartAndGoal(::ompl::geometric::SimpleSetup &setup, const MotionPlanRequest &request);

/** \brief Start and goal from two configurations (robot coordinate order), moved onto the bounds
    within the tolerance (ontoBounds). */
void setStartAndGoal(::ompl::geometric::SimpleSetup &setup, const std::vector<double> &start,
                     const std::vector<double> &goal);

/** \brief setup.solve for at most \a seconds, without OMPL's timing thread. OMPL's solve(double)
    hands a limit of 1 s or more to a thread that tests the clock every millisecond and is joined
    when the solve returns, so every such solve lasts up to a millisecond longer than its planner
    (measured: the shortest Panda MotionBenchMaker solves took 1.2 ms that way, 0.73 ms this way).
    This one tests the clock in the planner's own thread each time the planner asks. */
::ompl::base::PlannerStatus solveWithin(::ompl::geometric::SimpleSetup &setup, double seconds);
}  // namespace rastercheck::ompl
