// OMPL's clearance through our StateValidityChecker: the specs say EXACT, clearance() is the
// checker's distance less the padding, and RRT* maximising the minimum clearance
// (ob::MaximizeMinClearanceObjective) plans with it on a Panda problem and an OMPL.app problem.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/objectives/MaximizeMinClearanceObjective.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>

#include "BackendSuites.h"
#include "TestSupport.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace
{
/** \brief RRT* with MaximizeMinClearanceObjective for \a seconds (\a range, \a goalBias: the
    planner's; 0 = OMPL's defaults); expects an exact solution whose states are all valid with
    positive clearance, the path's cost (the minimum clearance along its motions) positive and no
    larger than its states' smallest clearance. */
void planForClearance(og::SimpleSetup &setup, double seconds, double range = 0.0, double goalBias = 0.0)
{
    const ob::SpaceInformationPtr &si = setup.getSpaceInformation();
    auto objective = std::make_shared<ob::MaximizeMinClearanceObjective>(si);
    setup.setOptimizationObjective(objective);
    auto planner = std::make_shared<og::RRTstar>(si);
    if (range > 0.0)
        planner->setRange(range);
    if (goalBias > 0.0)
        planner->setGoalBias(goalBias);
    setup.setPlanner(planner);
    ob::PlannerStatus status = setup.solve(seconds);
    // A slow machine (the sanitizers' builds run 10-50x slower) may not reach the goal in that time:
    // the same planner goes on, up to a minute, until its first exact solution. RRT* hands a
    // solution to the problem only when it stops, so it is told to stop at the first path it finds
    // (a cost threshold every free path meets); else it would always optimise for the whole minute.
    if (status != ob::PlannerStatus::EXACT_SOLUTION)
    {
        objective->setCostThreshold(ob::Cost(0.0));
        status = setup.solve(ob::timedPlannerTerminationCondition(60.0));
    }
    ASSERT_EQ(status, ob::PlannerStatus::EXACT_SOLUTION);
    og::PathGeometric &path = setup.getSolutionPath();
    const rco::StateValidityChecker &checker = *rco::getStateValidityChecker(setup);
    double smallest = std::numeric_limits<double>::infinity();
    for (const ob::State *state : path.getStates())
    {
        double dist = -1.0;
        EXPECT_TRUE(checker.isValid(state, dist));
        EXPECT_GT(dist, 0.0);
        EXPECT_EQ(dist, checker.clearance(state));
        smallest = std::min(smallest, dist);
    }
    const double cost = path.cost(objective).value();
    EXPECT_GT(cost, 0.0);
    EXPECT_LE(cost, smallest + 1e-12);
}
}  // namespace

TEST(OmplClearance, ExactClearanceIsTheCheckersDistanceLessThePadding)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    rco::SetupOptions options;
    options.request.padding = 0.01;
    const og::SimpleSetupPtr setup = rco::makeSimpleSetup(problem, options);
    const rco::StateValidityChecker &checker = *rco::getStateValidityChecker(*setup);
    EXPECT_EQ(checker.getSpecs().clearanceComputationType, ob::StateValidityCheckerSpecs::EXACT);

    const std::vector<double> q = rc::test::randomStates(*problem.robot, 60, 17);
    ob::ScopedState<> state(setup->getStateSpace());
    int valid = 0;
    for (std::size_t i = 0; i < 60; ++i)
    {
        const double *configuration = q.data() + i * checker.getChecker().dof();
        checker.getStateMapping().fromConfiguration(configuration, state.get());
        rc::DistanceResult distance;
        checker.getChecker().distance(configuration, rc::DistanceRequest{}, &distance);
        const double clearance = checker.clearance(state.get());
        EXPECT_EQ(clearance, std::max(0.0, distance.distance - 0.01)) << "state " << i;
        double dist = -1.0;
        const bool isValid = checker.isValid(state.get(), dist);
        EXPECT_EQ(isValid, checker.isValid(state.get())) << "state " << i;
        // A valid state is farther than the padding from everything, an invalid one reports 0.
        EXPECT_EQ(dist, isValid ? clearance : 0.0) << "state " << i;
        if (isValid)
        {
            ++valid;
            EXPECT_GT(clearance, 0.0) << "state " << i;
        }
    }
    EXPECT_GT(valid, 5);
}

TEST(OmplClearance, StatesOutsideTheBoundsOrNotFiniteHaveNone)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const og::SimpleSetupPtr setup = rco::makeSimpleSetup(rc::test::pandaProblem(root, "box"));
    const rco::StateValidityChecker &checker = *rco::getStateValidityChecker(*setup);
    ob::ScopedState<> state(setup->getStateSpace());
    std::vector<double> q(checker.getChecker().dof(), 0.0);
    q[0] = 100.0;  // far outside the first joint's limits
    checker.getStateMapping().fromConfiguration(q.data(), state.get());
    EXPECT_EQ(checker.clearance(state.get()), 0.0);
    q[0] = std::nan("");
    checker.getStateMapping().fromConfiguration(q.data(), state.get());
    EXPECT_EQ(checker.clearance(state.get()), 0.0);
    double dist = -1.0;
    EXPECT_FALSE(checker.isValid(state.get(), dist));
    EXPECT_EQ(dist, 0.0);
}

TEST(OmplClearance, RrtStarMaximisesClearanceOnAPandaProblem)
{
    RASTERCHECK_REQUIRE_DATA(root);
    rc::test::seedOmpl(3);
    // RRT* weighs every motion it considers by the clearance at each state of OMPL's interpolation
    // of it (about a millisecond a motion on the Panda, whose wrist keeps panda_link5 and
    // panda_link7 about 2.2 cm apart at most states, which then bounds every path's cost): states 5 %
    // of the space's extent apart, a range that reaches table_pick 1's goal in one motion (4.25 rad
    // away, the straight motion valid) and a goal bias of one half keep the test to seconds.
    rco::SetupOptions options;
    options.longestValidSegmentFraction = 0.05;
    const og::SimpleSetupPtr setup = rco::makeSimpleSetup(rc::test::pandaProblem(root, "table_pick"), options);
    rco::setStartAndGoal(*setup, rc::loadMoveItRequest(root + "/mbm/panda/problems/table_pick_panda/request0001.yaml"));
    planForClearance(*setup, 3.0, 5.0, 0.5);
}

TEST(OmplClearance, RrtStarMaximisesClearanceOnAnOmplAppProblem)
{
    // An OMPL.app problem of our own (OMPL.app's resources may not be redistributed): a unit cube
    // flies from one side of a wall with a window to the other.
    rc::test::seedOmpl(4);
    const std::string folder = rc::test::makeTempDir("clearance");
    rc::test::writeFile(folder + "/robot.obj", rc::test::kCubeObj);
    std::string world = rc::test::objBox("below", -1, -6, -6, 1, 6, -1.5, 0);
    world += rc::test::objBox("above", -1, -6, 1.5, 1, 6, 6, 8);
    world += rc::test::objBox("left", -1, -6, -1.5, 1, -1.5, 1.5, 16);
    world += rc::test::objBox("right", -1, 1.5, -1.5, 1, 6, 1.5, 24);
    rc::test::writeFile(folder + "/world.obj", world);
    const std::string cfg = rc::test::writeFile(folder + "/window.cfg", R"([problem]
name = window
robot = robot.obj
world = world.obj
start.x = -4
start.y = 0
start.z = 0
start.theta = 0
start.axis.x = 1
start.axis.y = 0
start.axis.z = 0
goal.x = 4
goal.y = 0
goal.z = 0
goal.theta = 0
goal.axis.x = 1
goal.axis.y = 0
goal.axis.z = 0
volume.min.x = -6
volume.min.y = -6
volume.min.z = -6
volume.max.x = 6
volume.max.y = 6
volume.max.z = 6
)");
    rc::ProblemSource source;
    source.cfgPath = cfg;
    const rc::Problem problem = rc::loadProblem(source);
    const og::SimpleSetupPtr setup = rco::makeSimpleSetup(problem);
    rco::setStartAndGoal(*setup, *problem.omplApp);
    planForClearance(*setup, 2.0);
    // Through the window (3 wide, the cube 1), the clearance is at most 1 - its half diagonal.
    EXPECT_LE(setup->getSolutionPath().cost(setup->getOptimizationObjective()).value(), 1.0);
}
