// The crawler crane (robots/crane) behaves as a crane, and the plant lift (robots/sites) is a sound
// planning problem: its start and goal are valid, the straight line between them is not, and a short
// planned lift is collision-free by the exact oracle with the hook hanging plumb throughout.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <ompl/base/ScopedState.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>

#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/StateMapping.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;

namespace
{
constexpr double kTight = 1e-9;

using rastercheck::test::plant;

const rc::RobotModel &crane()
{
    return *plant().robot;
}

/** \brief A configuration from joint values by name (the rest neutral). */
std::vector<double> configuration(const std::map<std::string, double> &values)
{
    std::vector<double> q = crane().neutralConfiguration();
    for (const auto &[name, value] : values)
    {
        const int index = crane().coordinateIndex(name);
        EXPECT_GE(index, 0) << name;
        q[static_cast<std::size_t>(index)] = value;
    }
    return q;
}

/** \brief Pose of \a link (world frame) at \a q. */
Eigen::Isometry3d pose(const std::vector<double> &q, const std::string &link)
{
    rc::RobotData data(crane());
    rc::forwardKinematics(crane(), data, q);
    const int index = crane().linkIndex(link);
    EXPECT_GE(index, 0) << link;
    return data.oMl[static_cast<std::size_t>(index)];
}

/** \brief The rope point: where the hoist rope leaves the sheave head (origin of hoist_frame). */
Eigen::Vector3d ropePoint(const std::vector<double> &q)
{
    return pose(q, "hoist_frame").translation();
}

double radius(const Eigen::Vector3d &p)
{
    return p.head<2>().norm();
}

std::vector<double> requestState(const std::map<std::string, double> &joints)
{
    std::vector<double> q(crane().numCoordinates());
    for (std::size_t i = 0; i < q.size(); ++i)
        q[i] = joints.at(crane().coordinateNames[i]);
    return q;
}

const rc::MotionPlanRequest &lift()
{
    static const rc::MotionPlanRequest request =
        rc::loadMoveItRequest(rc::test::sourcePath("robots/sites/plant_lift.yaml"));
    return request;
}
}  // namespace

TEST(Crane, CoordinatesAreTheSevenActiveJoints)
{
    EXPECT_EQ(crane().coordinateNames,
              (std::vector<std::string>{"base_x", "base_y", "base_yaw", "slew", "luff", "telescope_1", "hoist"}));
}

TEST(Crane, SlewTurnsTheBoomTipAboutTheVerticalSlewAxis)
{
    for (double luff : {0.2, 0.8, 1.3})
        for (double telescope : {0.0, 4.0, 9.3})
        {
            const Eigen::Vector3d reference = ropePoint(configuration({{"luff", luff}, {"telescope_1", telescope}}));
            for (double slew = -M_PI; slew <= M_PI; slew += M_PI / 7)
            {
                const Eigen::Vector3d tip =
                    ropePoint(configuration({{"slew", slew}, {"luff", luff}, {"telescope_1", telescope}}));
                EXPECT_NEAR(radius(tip), radius(reference), kTight);
                EXPECT_NEAR(tip.z(), reference.z(), kTight);
                // At slew = 0 the boom points along +x, so the tip's bearing is the slew angle.
                EXPECT_NEAR(std::remainder(std::atan2(tip.y(), tip.x()) - slew, 2 * M_PI), 0.0, kTight)
                    << "slew " << slew;
            }
        }
}

TEST(Crane, LuffRaisesTheTipAndBringsItIn)
{
    for (double telescope : {0.0, 9.3})
    {
        const double boom = 12.0 + 3.0 * telescope;
        double lastHeight = -1e9, lastRadius = 1e9;
        for (int k = 0; k <= 80; ++k)
        {
            const double luff = 1.396263 * k / 80;
            const Eigen::Vector3d tip = ropePoint(configuration({{"luff", luff}, {"telescope_1", telescope}}));
            EXPECT_GT(tip.z(), lastHeight) << "luff " << luff;
            // The reach formulas of robots/crane/README.md: luff pivot 1.8 m behind the slew axis and
            // 3.3 m up, rope point 0.9 m below the boom axis.
            EXPECT_NEAR(radius(tip), -1.8 + boom * std::cos(luff) + 0.9 * std::sin(luff), kTight);
            EXPECT_NEAR(tip.z(), 3.3 + boom * std::sin(luff) - 0.9 * std::cos(luff), kTight);
            // The 0.9 m drop moves the tip out for the first few degrees (d radius / d luff = 0 at
            // tan(luff) = 0.9 / boom, under 4.3 degrees); beyond that, luffing up brings it in.
            if (luff > 0.08)
            {
                EXPECT_LT(radius(tip), lastRadius) << "luff " << luff;
            }
            lastHeight = tip.z();
            lastRadius = radius(tip);
        }
    }
}

TEST(Crane, TelescopeExtendsTheBoomByThreeStrokesAlongItsAxis)
{
    for (double luff : {0.0, 0.7, 1.396263})
        for (double slew : {-2.0, 0.5})
        {
            const std::vector<double> retracted = configuration({{"slew", slew}, {"luff", luff}, {"telescope_1", 0.0}});
            const Eigen::Isometry3d base = pose(retracted, "boom_base");
            const Eigen::Vector3d boomAxis = base.linear().col(0);
            for (double telescope : {1.0, 4.65, 9.3})
            {
                const std::vector<double> q =
                    configuration({{"slew", slew}, {"luff", luff}, {"telescope_1", telescope}});
                const Eigen::Vector3d shift =
                    pose(q, "sheave_head").translation() - pose(retracted, "sheave_head").translation();
                EXPECT_NEAR((shift - 3.0 * telescope * boomAxis).norm(), 0.0, kTight);
                // telescope_2 and telescope_3 mimic telescope_1: every section is out by the same stroke.
                const char *sections[] = {"boom_base", "boom_section_1", "boom_section_2", "boom_section_3"};
                for (int s = 1; s < 4; ++s)
                {
                    const Eigen::Vector3d step =
                        pose(q, sections[s]).translation() - pose(q, sections[s - 1]).translation();
                    EXPECT_NEAR((step - ((s == 1 ? 0.0 : 0.3) + telescope) * boomAxis).norm(), 0.0, kTight)
                        << sections[s];
                }
                // The boom, luff pivot to rope point along its axis: 12.0 + 3 * telescope_1.
                const Eigen::Vector3d rope = base.inverse() * ropePoint(q);
                EXPECT_NEAR(rope.x(), 12.0 + 3.0 * telescope, kTight);
            }
        }
}

TEST(Crane, HoistLowersTheHookByTheHoistDelta)
{
    const std::vector<double> up = configuration({{"slew", 0.4}, {"luff", 0.9}, {"telescope_1", 3.0}, {"hoist", 2.0}});
    const Eigen::Vector3d hookUp = pose(up, "hook_block").translation();
    const Eigen::Vector3d loadUp = pose(up, "load").translation();
    for (double hoist : {2.5, 10.0, 35.0})
    {
        const std::vector<double> q =
            configuration({{"slew", 0.4}, {"luff", 0.9}, {"telescope_1", 3.0}, {"hoist", hoist}});
        const Eigen::Vector3d hook = pose(q, "hook_block").translation();
        EXPECT_NEAR((hook - (hookUp - (hoist - 2.0) * Eigen::Vector3d::UnitZ())).norm(), 0.0, kTight);
        EXPECT_NEAR((pose(q, "load").translation() - (loadUp - (hoist - 2.0) * Eigen::Vector3d::UnitZ())).norm(), 0.0,
                    kTight);
        // The rope (rope point to hook block) is plumb and as long as the hoist coordinate.
        EXPECT_NEAR((ropePoint(q) - hook - hoist * Eigen::Vector3d::UnitZ()).norm(), 0.0, kTight);
    }
}

TEST(Crane, HookBlockStaysVertical)
{
    std::mt19937 random(6);
    const rc::RobotModel &robot = crane();
    for (int trial = 0; trial < 500; ++trial)
    {
        std::vector<double> q(robot.numCoordinates());
        for (std::size_t i = 0; i < q.size(); ++i)
            q[i] = std::uniform_real_distribution<double>(robot.lowerBounds[i], robot.upperBounds[i])(random);
        const Eigen::Isometry3d hook = pose(q, "hook_block");
        EXPECT_NEAR((hook.linear().col(2) - Eigen::Vector3d::UnitZ()).norm(), 0.0, kTight);
        // The load turns with the superstructure only: its long axis is radial.
        const double heading = q[2] + q[3];  // base_yaw + slew
        EXPECT_NEAR((hook.linear().col(0) - Eigen::Vector3d(std::cos(heading), std::sin(heading), 0)).norm(), 0.0,
                    kTight);
    }
}

TEST(Crane, NoPointMovesMoreThan45MetresPerUnitOfTheStateMetric)
{
    // examples/crane_lift.cpp paces its exact re-check in metres of crane motion from this bound
    // (its edges are certified, which needs no resolution): one unit of OMPL's distance (radians of
    // slew + euclidean over luff, telescope, hoist) moves no vertex of the crane more than 45 m.
    rc::ompl::StateMappingOptions options;
    options.heldCoordinates = {{"base_x", 0.0}, {"base_y", 0.0}, {"base_yaw", 0.0}};
    const rc::ompl::StateMapping mapping(plant().robot, options);
    const ::ompl::base::StateSpacePtr &space = mapping.getStateSpace();
    ::ompl::base::ScopedState<> a(space), b(space);
    const rc::RobotModel &robot = crane();
    rc::RobotData dataA(robot), dataB(robot);
    // Largest vertex displacement from qa to qb over their distance in the state space.
    auto metresPerUnit = [&](const std::vector<double> &qa, const std::vector<double> &qb)
    {
        mapping.fromConfiguration(qa, a.get());
        mapping.fromConfiguration(qb, b.get());
        rc::forwardKinematics(robot, dataA, qa);
        rc::forwardKinematics(robot, dataB, qb);
        double moved = 0.0;
        for (const rc::Component &component : robot.components)
            for (const Eigen::Vector3d &v : component.mesh.vertices)
            {
                const auto l = static_cast<std::size_t>(component.link);
                moved = std::max(moved, (dataA.oMl[l] * v - dataB.oMl[l] * v).norm());
            }
        return moved / space->distance(a.get(), b.get());
    };
    // The worst cases: the longest boom, horizontal, slewing or luffing (the tip is 38 to 40 m out).
    const std::vector<double> reach =
        configuration({{"slew", 0.3}, {"luff", 0.0}, {"telescope_1", 9.3}, {"hoist", 1.0}});
    std::vector<double> slewed = reach, luffed = reach;
    slewed[3] += 1e-4;
    luffed[4] += 1e-4;
    EXPECT_GT(metresPerUnit(reach, slewed), 38.0);
    EXPECT_LT(metresPerUnit(reach, slewed), 45.0);
    EXPECT_GT(metresPerUnit(reach, luffed), 38.0);
    EXPECT_LT(metresPerUnit(reach, luffed), 45.0);

    std::mt19937 random(45);
    for (int trial = 0; trial < 300; ++trial)
    {
        std::vector<double> qa = mapping.baseConfiguration();
        for (int c : mapping.plannedCoordinates())
        {
            const auto i = static_cast<std::size_t>(c);
            qa[i] = std::uniform_real_distribution<double>(robot.lowerBounds[i], robot.upperBounds[i])(random);
        }
        // A short step in a random direction, kept inside the bounds.
        std::vector<double> qb = qa;
        for (int c : mapping.plannedCoordinates())
        {
            const auto i = static_cast<std::size_t>(c);
            qb[i] = std::clamp(qa[i] + std::uniform_real_distribution<double>(-1e-3, 1e-3)(random),
                               robot.lowerBounds[i], robot.upperBounds[i]);
        }
        if (qa != qb)
        {
            EXPECT_LT(metresPerUnit(qa, qb), 45.0);
        }
    }
}

TEST(CraneLift, StartAndGoalAreValidWithTheLiftClearance)
{
    const rc::Checker checker(plant().robot, plant().scene);
    for (const auto *joints : {&lift().startJoints, &lift().goalJoints})
    {
        const std::vector<double> q = requestState(*joints);
        rc::Contact contact;
        for (double padding : {0.0, 0.25})
        {
            rc::CollisionRequest request;
            request.padding = padding;
            EXPECT_TRUE(checker.isValid(q, request, &contact)) << checker.describe(contact);
            request.mode = rc::CollisionMode::Exact;
            EXPECT_TRUE(checker.isValid(q, request, &contact)) << checker.describe(contact);
            EXPECT_FALSE(rc::test::bruteForceCollides(checker.collisionModel(), q.data(), padding));
        }
        // The skid hangs 0.3 m above its support (robots/sites/README.md): half a metre of padding
        // is more than the state has.
        rc::CollisionRequest wide;
        wide.padding = 0.5;
        EXPECT_FALSE(checker.isValid(q, wide, &contact));
        EXPECT_TRUE(rc::test::bruteForceCollides(checker.collisionModel(), q.data(), 0.5));
    }
}

TEST(CraneLift, StraightLineSwingsTheLoadIntoTank1)
{
    const rc::Checker checker(plant().robot, plant().scene);
    const std::vector<double> start = requestState(lift().startJoints), goal = requestState(lift().goalJoints);
    rc::CollisionRequest request;
    request.mode = rc::CollisionMode::Exact;
    for (int k = 0; k <= 100; ++k)
    {
        const double t = k / 100.0;
        std::vector<double> q(start.size());
        for (std::size_t i = 0; i < q.size(); ++i)
            q[i] = (1 - t) * start[i] + t * goal[i];
        rc::Contact contact;
        if (checker.isValid(q, request, &contact))
            continue;
        ASSERT_EQ(contact.kind, rc::Contact::Kind::Environment);
        EXPECT_EQ(checker.robot().components[static_cast<std::size_t>(contact.component)].name, "load");
        EXPECT_EQ(checker.scene().objects[static_cast<std::size_t>(contact.object)].name, "tank_1");
        EXPECT_GT(t, 0.2);
        EXPECT_LT(t, 0.35);
        return;
    }
    FAIL() << "the straight line from pick to set-down is expected to hit tank_1";
}

TEST(CraneLift, ShortPlannedLiftIsFreeByTheOracleAndKeepsTheHookVertical)
{
    rc::test::seedOmpl(6);
    rc::ompl::SetupOptions options;
    options.request.padding = 0.25;
    options.heldCoordinates = {{"base_x", 0.0}, {"base_y", 0.0}, {"base_yaw", 0.0}};
    const ::ompl::geometric::SimpleSetupPtr setup = rc::ompl::makeSimpleSetup(plant(), options);
    setup->setPlanner(std::make_shared<::ompl::geometric::RRTConnect>(setup->getSpaceInformation()));
    // Lift the skid off the trailer and swing it 20 degrees west of south.
    std::vector<double> start = requestState(lift().startJoints), goal = start;
    goal[3] -= 0.35;  // slew
    goal[6] = 9.0;    // hoist: skid bottom from 1.4 m to 8.2 m
    rc::ompl::setStartAndGoal(*setup, start, goal);
    ASSERT_TRUE(setup->solve(60.0));  // a limit, not a budget: it stops when it connects (slow under sanitizers)
    ASSERT_TRUE(setup->haveExactSolutionPath());
    setup->simplifySolution(1.0);
    ::ompl::geometric::PathGeometric &path = setup->getSolutionPath();

    const auto validity = rc::ompl::getStateValidityChecker(*setup);
    rc::CollisionRequest exact;
    exact.mode = rc::CollisionMode::Exact;
    exact.padding = 0.0;
    const rc::ompl::PathCheckResult result =
        rc::ompl::checkPathDensely(path, validity->getStateMapping(), validity->getChecker(), exact, 10);
    EXPECT_TRUE(result.valid) << "segment " << result.segment << " t " << result.time << ": "
                              << validity->getChecker().describe(result.contact);
    EXPECT_GT(result.statesChecked, path.getStateCount());

    path.interpolate(200);
    const rc::CollisionModel &model = validity->getChecker().collisionModel();
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
    {
        const std::vector<double> q = validity->getStateMapping().toConfiguration(path.getState(i));
        EXPECT_FALSE(rc::test::bruteForceCollides(model, q.data(), 0.0)) << "state " << i;
        EXPECT_NEAR((pose(q, "hook_block").linear().col(2) - Eigen::Vector3d::UnitZ()).norm(), 0.0, kTight);
        EXPECT_EQ(q[0], 0.0);  // the held base does not move
        EXPECT_EQ(q[2], 0.0);
    }
}
