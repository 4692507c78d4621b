#include "rastercheck/ompl/Setup.h"

#include <cmath>
#include <sstream>

#include <ompl/base/ScopedState.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/ompl/MotionValidator.h"

namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace rastercheck::ompl
{
namespace
{
void setStartAndGoalInBounds(og::SimpleSetup &setup, const std::vector<double> &start, const std::vector<double> &goal)
{
    const StateMapping &mapping = getStateValidityChecker(setup)->getStateMapping();
    ob::ScopedState<> startState(setup.getStateSpace()), goalState(setup.getStateSpace());
    mapping.fromConfiguration(start, startState.get());
    mapping.fromConfiguration(goal, goalState.get());
    setup.setStartAndGoalStates(startState, goalState);
}
}  // namespace

og::SimpleSetupPtr makeSimpleSetup(const Problem &problem, const SetupOptions &options)
{
    if (!problem.robot)
        throw ConfigurationError("makeSimpleSetup: the problem has no robot");
    if (!(options.longestValidSegmentFraction > 0.0 && options.longestValidSegmentFraction <= 1.0))
        throw ConfigurationError("longest valid segment fraction must be in (0, 1]");
    StateMappingOptions mappingOptions;
    mappingOptions.heldCoordinates = options.heldCoordinates;
    mappingOptions.boundsTolerance = options.boundsTolerance;
    auto mapping = std::make_shared<const StateMapping>(problem.robot, mappingOptions);
    if (options.existingChecker && &options.existingChecker->robot() != problem.robot.get())
        throw ConfigurationError("makeSimpleSetup: the existing checker checks another robot than the problem's");
    CheckerConstPtr checker = options.existingChecker
                                  ? options.existingChecker
                                  : std::make_shared<const Checker>(problem.robot, problem.scene, options.checker);

    const ob::StateSpacePtr &space = mapping->getStateSpace();
    space->setLongestValidSegmentFraction(options.longestValidSegmentFraction);
    auto setup = std::make_shared<og::SimpleSetup>(space);
    const ob::SpaceInformationPtr &si = setup->getSpaceInformation();
    auto validityChecker = std::make_shared<StateValidityChecker>(si, mapping, checker, options.request);
    setup->setStateValidityChecker(validityChecker);
    switch (resolveEdgeChecking(options.edges, options.request.mode))
    {
        case EdgeChecking::Auto:  // resolved: never returned
        case EdgeChecking::Batched:
            si->setMotionValidator(std::make_shared<MotionValidator>(si, *validityChecker, options.rakeWidth));
            break;
        case EdgeChecking::Certified:
            si->setMotionValidator(std::make_shared<CertifiedMotionValidator>(si, *validityChecker, options.certified));
            break;
        case EdgeChecking::Discrete:
            break;  // SpaceInformation's default
    }
    return setup;
}

EdgeChecking resolveEdgeChecking(EdgeChecking edges, CollisionMode mode)
{
    if (edges != EdgeChecking::Auto)
        return edges;
    return mode == CollisionMode::Raster ? EdgeChecking::Batched : EdgeChecking::Certified;
}

EdgeChecking parseEdgeChecking(const std::string &text)
{
    if (text == "auto")
        return EdgeChecking::Auto;
    if (text == "batched")
        return EdgeChecking::Batched;
    if (text == "discrete")
        return EdgeChecking::Discrete;
    if (text == "certified")
        return EdgeChecking::Certified;
    throw ConfigurationError("unknown edge checking '" + text + "' (expected auto, batched, discrete or certified)");
}

StateValidityCheckerPtr getStateValidityChecker(const og::SimpleSetup &setup)
{
    auto checker = std::dynamic_pointer_cast<StateValidityChecker>(setup.getStateValidityChecker());
    if (!checker)
        throw ConfigurationError("this SimpleSetup was not made by rastercheck::ompl::makeSimpleSetup");
    return checker;
}

std::uint64_t checkedStates(const og::SimpleSetup &setup)
{
    const ob::MotionValidatorPtr &edges = setup.getSpaceInformation()->getMotionValidator();
    const auto validity = std::dynamic_pointer_cast<StateValidityChecker>(setup.getStateValidityChecker());
    std::uint64_t states = validity ? validity->getCallCount() : 0;
    if (auto batched = std::dynamic_pointer_cast<MotionValidator>(edges))
        states += batched->getCheckedStateCount();
    else if (auto certified = std::dynamic_pointer_cast<CertifiedMotionValidator>(edges))
        states += certified->getCheckedStateCount();
    return states;
}

void resetCheckedStates(const og::SimpleSetup &setup)
{
    const ob::MotionValidatorPtr &edges = setup.getSpaceInformation()->getMotionValidator();
    if (auto validity = std::dynamic_pointer_cast<StateValidityChecker>(setup.getStateValidityChecker()))
        validity->resetCounters();
    if (auto batched = std::dynamic_pointer_cast<MotionValidator>(edges))
        batched->resetStateCounter();
    else if (auto certified = std::dynamic_pointer_cast<CertifiedMotionValidator>(edges))
        certified->resetStateCounter();
}

std::vector<double> configurationFromJoints(const StateMapping &mapping, const std::map<std::string, double> &joints,
                                            const std::string &what, UnknownJoints unknown)
{
    const RobotModel &robot = mapping.robot();
    std::vector<double> q = mapping.baseConfiguration();
    std::string skipped;
    for (const auto &[name, value] : joints)
    {
        const int index = robot.jointIndex(name);
        if (index < 0 && unknown == UnknownJoints::Skip)
        {
            skipped += (skipped.empty() ? "'" : ", '") + name + "'";
            continue;
        }
        if (index < 0)
            throw ConfigurationError(what + " names joint '" + name + "', which robot '" + robot.name + "' lacks");
        const Joint &joint = robot.joints[index];
        if (joint.firstCoordinate < 0)
            continue;  // fixed or mimic: nothing to plan
        if (joint.coordinateNames.size() != 1)
            throw ConfigurationError(what + " sets joint '" + name + "' by one position, but it has " +
                                     std::to_string(joint.coordinateNames.size()) + " coordinates");
        if (!std::isfinite(value))
            throw ConfigurationError(what + " gives joint '" + name + "' a non-finite position");
        const int c = joint.firstCoordinate;
        if (mapping.isHeld(c))
        {
            if (std::abs(value - q[c]) > 1e-9)
                logWarning(what + " sets held coordinate '" + name + "' to " + std::to_string(value) +
                           "; it stays at its held value " + std::to_string(q[c]));
            continue;
        }
        q[c] = value;
    }
    if (!skipped.empty())
        logWarning(what + " names joint(s) " + skipped + ", which robot '" + robot.name + "' lacks; ignored");
    return q;
}

std::vector<double> ontoBounds(const StateMapping &mapping, std::vector<double> q, const std::string &what,
                               const std::vector<double> &slackDown, const std::vector<double> &slackUp)
{
    if (q.size() != mapping.numCoordinates())
        throw ConfigurationError(what + " has " + std::to_string(q.size()) + " coordinates, robot '" +
                                 mapping.robot().name + "' has " + std::to_string(mapping.numCoordinates()));
    const BoundsFit fit = fitToBounds(mapping.robot(), q.data(), mapping.boundsTolerance(), slackDown, slackUp);
    if (fit.outside.coordinate >= 0)
    {
        std::ostringstream tolerance;
        tolerance << mapping.boundsTolerance();
        throw ConfigurationError(what + ": " + describeExcess(mapping.robot(), fit.outside) +
                                 ", farther than the bounds tolerance (" + tolerance.str() + ")");
    }
    for (const BoundsExcess &moved : fit.moved)
        logWarning(what + ": " + describeExcess(mapping.robot(), moved) + "; moved onto the bound");
    return q;
}

void setStartAndGoal(og::SimpleSetup &setup, const std::vector<double> &start, const std::vector<double> &goal)
{
    const StateValidityCheckerPtr checker = getStateValidityChecker(setup);
    const StateMapping &mapping = checker->getStateMapping();
    setStartAndGoalInBounds(setup, ontoBounds(mapping, start, "start"), ontoBounds(mapping, goal, "goal"));
}

void setStartAndGoal(og::SimpleSetup &setup, const OmplAppProblem &problem)
{
    setStartAndGoal(setup, problem.start, problem.goal);
}

void setObjective(og::SimpleSetup &setup, const OmplAppProblem &problem)
{
    if (problem.objective == "length")
    {
        auto objective = std::make_shared<ob::PathLengthOptimizationObjective>(setup.getSpaceInformation());
        if (problem.objectiveThreshold > 0)
            objective->setCostThreshold(ob::Cost(problem.objectiveThreshold));
        setup.setOptimizationObjective(objective);
    }
    else if (!problem.objective.empty())
        throw ConfigurationError("objective '" + problem.objective + "' is not supported (only 'length')");
}

std::pair<std::vector<double>, std::vector<double>> startAndGoal(const StateMapping &mapping,
                                                                 const MotionPlanRequest &request)
{
    return {configurationFromJoints(mapping, request.startJoints, "start", UnknownJoints::Skip),
            configurationFromJoints(mapping, request.goalJoints, "goal")};
}

void setStartAndGoal(og::SimpleSetup &setup, const MotionPlanRequest &request)
{
    const StateMapping &mapping = getStateValidityChecker(setup)->getStateMapping();
    // A goal joint constraint is met anywhere in [position - tolerance_below, position +
    // tolerance_above], so a goal past a limit by less than that may move onto the limit.
    std::vector<double> slackDown(mapping.numCoordinates(), 0.0), slackUp(mapping.numCoordinates(), 0.0);
    auto slack = [&](const std::map<std::string, double> &tolerances, std::vector<double> &out)
    {
        for (const auto &[name, tolerance] : tolerances)
        {
            const int c = mapping.robot().coordinateIndex(name);
            if (c >= 0 && std::isfinite(tolerance) && tolerance > 0)
                out[static_cast<std::size_t>(c)] = tolerance;
        }
    };
    slack(request.goalToleranceBelow, slackDown);
    slack(request.goalToleranceAbove, slackUp);
    auto [start, goal] = startAndGoal(mapping, request);
    setStartAndGoalInBounds(setup, ontoBounds(mapping, std::move(start), "start"),
                            ontoBounds(mapping, std::move(goal), "goal", slackDown, slackUp));
}

::ompl::base::PlannerStatus solveWithin(::ompl::geometric::SimpleSetup &setup, double seconds)
{
    return setup.solve(::ompl::base::timedPlannerTerminationCondition(seconds));
}
}  // namespace rastercheck::ompl
