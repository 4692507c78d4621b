// States on the bounds: a request's start or goal within a tolerance of a joint limit is moved onto
// it (as MoveIt does), farther is an error naming the joint; `check` says why a state is invalid.
#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include <ompl/base/goals/GoalState.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/Bounds.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;
using rc::test::LogCapture;
using rc::test::urdfJoint;
using rc::test::urdfLink;
using rc::test::urdfRobot;
using rc::test::writeFile;

namespace
{
constexpr double kPi = 3.14159265358979323846;

std::string box(const std::string &size, const std::string &xyz = "0 0 0")
{
    return "<collision><origin xyz=\"" + xyz + "\"/><geometry><box size=\"" + size + "\"/></geometry></collision>";
}

// The Fetch's roll joints as this URDF limits them (+-3.14159, where the original model has
// continuous joints): base -roll-> middle -j2-> tip; the tip's box lies 0.6 m out, so folding j2 by
// pi lands it on the base (a self collision: the pair is not adjacent).
std::string rollArm()
{
    const std::string roll = "<limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"1\" velocity=\"1\"/>";
    return urdfRobot(
        urdfLink("world") + urdfLink("base", box("0.1 0.1 0.1")) + urdfLink("middle", box("0.05 0.05 0.05")) +
        urdfLink("tip", box("0.1 0.1 0.1", "0.6 0 0")) + urdfJoint("mount", "fixed", "world", "base") +
        urdfJoint("roll", "revolute", "base", "middle", "<origin xyz=\"0.3 0 0\"/><axis xyz=\"0 0 1\"/>" + roll) +
        urdfJoint("j2", "revolute", "middle", "tip", "<origin xyz=\"0.3 0 0\"/><axis xyz=\"0 0 1\"/>" + roll));
}

rc::Problem rollProblem()
{
    rc::Problem problem;
    problem.robot = rc::loadUrdfString(rollArm(), ".", {}, "roll.urdf");
    return problem;
}

rc::MotionPlanRequest request(double startRoll, double goalRoll)
{
    rc::MotionPlanRequest r;
    r.startJoints = {{"roll", startRoll}, {"j2", 0.0}};
    r.goalJoints = {{"roll", goalRoll}, {"j2", 0.0}};
    return r;
}

void expectRefused(og::SimpleSetup &setup, const rc::MotionPlanRequest &r, const std::string &what)
{
    try
    {
        rco::setStartAndGoal(setup, r);
        ADD_FAILURE() << what << " accepted";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_NE(std::string(e.what()).find(what + ": joint 'roll' at"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("bound 3.14159"), std::string::npos) << e.what();
    }
}
}  // namespace

TEST(Bounds, FitMovesWithinTheToleranceAndReportsTheFirstBeyond)
{
    const rc::RobotModelPtr robot = rc::loadUrdfString(rollArm(), ".", {}, "roll.urdf");
    std::vector<double> q{kPi, -3.1416};
    rc::BoundsFit fit = rc::fitToBounds(*robot, q.data(), 1e-4);
    EXPECT_EQ(q, (std::vector<double>{3.14159, -3.14159}));
    ASSERT_EQ(fit.moved.size(), 2u);
    EXPECT_EQ(fit.moved[0].coordinate, 0);
    EXPECT_EQ(fit.moved[0].value, kPi);
    EXPECT_EQ(fit.outside.coordinate, -1);
    EXPECT_EQ(rc::describeExcess(*robot, fit.moved[0]),
              "joint 'roll' at 3.141592654 is 2.65e-06 above its upper bound 3.14159");

    q = {0.0, -3.14159 - 1e-3};
    fit = rc::fitToBounds(*robot, q.data(), 1e-4);
    EXPECT_TRUE(fit.moved.empty());
    EXPECT_EQ(fit.outside.coordinate, 1);
    EXPECT_EQ(q[1], -3.14159 - 1e-3);  // left as it is
    // A slack (a goal constraint's tolerance) in the direction of the move counts; the other not.
    fit = rc::fitToBounds(*robot, q.data(), 1e-4, {0.0, 0.0}, {0.0, 2e-3});
    EXPECT_EQ(fit.outside.coordinate, -1);
    EXPECT_EQ(q[1], -3.14159);
    q[1] = -3.14159 - 1e-3;
    EXPECT_EQ(rc::fitToBounds(*robot, q.data(), 1e-4, {0.0, 2e-3}, {}).outside.coordinate, 1);
    EXPECT_THROW(rc::fitToBounds(*robot, q.data(), -1.0), rc::ConfigurationError);
}

TEST(Bounds, GoalAtPiOnALimitOfPlus314159Plans)
{
    rc::test::seedOmpl(36);
    og::SimpleSetupPtr setup = rco::makeSimpleSetup(rollProblem());
    LogCapture log;
    rco::setStartAndGoal(*setup, request(-kPi, kPi));
    ASSERT_EQ(log.warnings.size(), 2u);
    EXPECT_TRUE(
        log.warned("start: joint 'roll' at -3.141592654 is 2.65e-06 below its lower bound -3.14159; "
                   "moved onto the bound"));
    EXPECT_TRUE(
        log.warned("goal: joint 'roll' at 3.141592654 is 2.65e-06 above its upper bound 3.14159; "
                   "moved onto the bound"));
    const ob::State *goal = setup->getGoal()->as<ob::GoalState>()->getState();
    const rco::StateValidityCheckerPtr checker = rco::getStateValidityChecker(*setup);
    EXPECT_EQ(checker->getStateMapping().toConfiguration(goal)[0], 3.14159);
    EXPECT_TRUE(checker->isValid(goal));
    setup->setPlanner(std::make_shared<og::RRTConnect>(setup->getSpaceInformation()));
    EXPECT_EQ(setup->solve(5.0), ob::PlannerStatus::EXACT_SOLUTION);
}

TEST(Bounds, BeyondTheToleranceIsRefusedNamingTheJoint)
{
    og::SimpleSetupPtr setup = rco::makeSimpleSetup(rollProblem());
    expectRefused(*setup, request(0.0, 3.14159 + 1e-3), "goal");
    expectRefused(*setup, request(3.14159 + 1e-3, 0.0), "start");
    // The option moves the line.
    rco::SetupOptions wide;
    wide.boundsTolerance = 2e-3;
    og::SimpleSetupPtr wideSetup = rco::makeSimpleSetup(rollProblem(), wide);
    EXPECT_NO_THROW(rco::setStartAndGoal(*wideSetup, request(0.0, 3.14159 + 1e-3)));
    wide.boundsTolerance = std::nan("");
    EXPECT_THROW(rco::makeSimpleSetup(rollProblem(), wide), rc::ConfigurationError);
}

TEST(Bounds, GoalJointConstraintToleranceIsHonoured)
{
    og::SimpleSetupPtr setup = rco::makeSimpleSetup(rollProblem());
    rc::MotionPlanRequest r = request(0.0, 3.14159 + 1e-3);
    r.goalToleranceAbove["roll"] = 0.01;  // the wrong side: the goal must move down
    expectRefused(*setup, r, "goal");
    r.goalToleranceBelow["roll"] = 0.01;
    LogCapture log;
    EXPECT_NO_THROW(rco::setStartAndGoal(*setup, r));
    EXPECT_TRUE(log.warned("goal: joint 'roll' at 3.14259 is 0.001 above its upper bound 3.14159"))
        << log.warnings.size();
}

TEST(Bounds, CheckWritesWhyAStateIsInvalid)
{
    const std::string folder = rc::test::makeTempDir("bounds");
    const std::string urdf = writeFile(folder + "/roll.urdf", rollArm());
    // A crate where the stretched arm's tip is (x = 1.2).
    const std::string scene =
        writeFile(folder + "/scene.yaml",
                  "world:\n  collision_objects:\n    - id: crate\n"
                  "      primitives: [{type: box, dimensions: [0.2, 0.2, 0.2]}]\n"
                  "      primitive_poses: [{position: [1.2, 0, 0], orientation: [0, 0, 0, 1]}]\n");
    // free, self (tip folded onto the base), environment (stretched), 2.65e-6 past a limit (moved:
    // free), 1e-3 past it (bounds).
    const std::string states =
        writeFile(folder + "/states.csv", "roll,j2\n0,1.5\n0,3.14159\n0,0\n3.141592653589793,1.5\n0,-3.14259\n");
    const rc::test::CommandRun run = rc::test::runCli("check --robot " + urdf + " --scene " + scene + " --states " +
                                                      states + " --out " + folder + "/out.csv --mode exact");
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("states=5 invalid=3 bounds=1 environment=1 self=1 "), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("1 state(s) within the bounds tolerance of a limit moved onto it; the first: joint "
                              "'roll' at 3.141592654 is 2.65e-06 above its upper bound 3.14159"),
              std::string::npos)
        << run.output;
    std::ifstream out(folder + "/out.csv");
    std::vector<std::string> rows;
    for (std::string line; std::getline(out, line);)
        rows.push_back(line.substr(0, line.find(',')) + "|" + line.substr(line.rfind(',') + 1));
    EXPECT_EQ(rows, (std::vector<std::string>{"valid|reason", "1|", "0|self", "0|environment", "1|", "0|bounds:j2"}));

    // --bounds-tolerance 0: the state at pi is out of bounds too.
    const rc::test::CommandRun strict = rc::test::runCli("check --robot " + urdf + " --scene " + scene + " --states " +
                                                         states + " --bounds-tolerance 0");
    EXPECT_NE(strict.output.find("states=5 invalid=4 bounds=2 environment=1 self=1 "), std::string::npos)
        << strict.output;
}
