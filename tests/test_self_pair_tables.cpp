// SelfPairTables: which self pairs get a table, that a table's "apart" is never wrong (the exact
// oracle, solidsOverlap in double, on the pair itself), and that it settles most of the Panda's
// wrist checks (the reason it exists).

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;

namespace
{
/** \brief Index of the self pair of the components on links \a first and \a second, or -1. */
int selfPairOf(const rc::CollisionModel &model, const std::string &first, const std::string &second)
{
    const rc::RobotModel &robot = *model.robot;
    for (std::size_t i = 0; i < model.selfPairs.size(); ++i)
    {
        const std::string a = robot.links[model.componentLink[model.selfPairs[i].first]].name;
        const std::string b = robot.links[model.componentLink[model.selfPairs[i].second]].name;
        if ((a == first && b == second) || (a == second && b == first))
            return static_cast<int>(i);
    }
    return -1;
}
}  // namespace

TEST(SelfPairTables, ThePandaWristPairsGetTablesAndNoProofIsWrong)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "cage");
    const rc::CollisionModel model(problem.robot, problem.scene);
    const rc::RobotModel &robot = *model.robot;
    const int link7 = selfPairOf(model, "panda_link5", "panda_link7");
    const int hand = selfPairOf(model, "panda_link5", "panda_hand");
    ASSERT_GE(link7, 0);
    ASSERT_GE(hand, 0);
    // link5 against link7, the hand and the fingers (fixed joints in this URDF) is moved by joints 6
    // and 7 only: tables. Every other pair is three or more joints apart: none.
    EXPECT_TRUE(model.selfPairTables.hasTable(static_cast<std::size_t>(link7)));
    EXPECT_TRUE(model.selfPairTables.hasTable(static_cast<std::size_t>(hand)));
    EXPECT_TRUE(
        model.selfPairTables.hasTable(static_cast<std::size_t>(selfPairOf(model, "panda_link5", "panda_leftfinger"))));
    EXPECT_FALSE(
        model.selfPairTables.hasTable(static_cast<std::size_t>(selfPairOf(model, "panda_link2", "panda_link5"))));
    EXPECT_EQ(model.selfPairTables.numTables(), 4u);
    std::mt19937_64 rng(17);
    std::vector<double> q(robot.numCoordinates());
    rc::RobotData data(robot);
    int settled[2] = {0, 0}, states = 4000;
    for (int s = 0; s < states; ++s)
    {
        for (std::size_t i = 0; i < q.size(); ++i)
            q[i] = std::uniform_real_distribution<double>(robot.lowerBounds[i], robot.upperBounds[i])(rng);
        rc::forwardKinematics(robot, data, q.data());
        for (int which = 0; which < 2; ++which)
        {
            const std::size_t pair = static_cast<std::size_t>(which == 0 ? link7 : hand);
            const auto [a, b] = model.selfPairs[pair];
            for (double padding : {0.0, 0.005, 0.02})
            {
                if (!model.selfPairTables.apart(pair, q.data(), padding))
                    continue;
                settled[which] += padding == 0.0 ? 1 : 0;
                // The oracle, a little inside the padding (the proof says "more than padding").
                EXPECT_FALSE(rc::solidsOverlap(*model.componentBvhs[a], data.oMl[model.componentLink[a]],
                                               model.components[a].closed, *model.componentBvhs[b],
                                               data.oMl[model.componentLink[b]], model.components[b].closed, padding))
                    << "state " << s << ", pair " << pair << ", padding " << padding;
            }
        }
    }
    // 20 000 uniform states put the hulls more than 10 mm apart in 86 % (link7) and 88 % (hand) of
    // them (docs/benchmarks.md); the tables' nodes are at most about 11 mm of sweep away.
    EXPECT_GT(settled[0], states * 7 / 10);
    EXPECT_GT(settled[1], states * 7 / 10);
    EXPECT_GT(model.selfPairTables.memoryBytes(), 0u);
}

TEST(SelfPairTables, NonFiniteOrOutOfBoundsStatesGetNoProofOrASoundOne)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "cage");
    const rc::CollisionModel model(problem.robot, problem.scene);
    const int link7 = selfPairOf(model, "panda_link5", "panda_link7");
    ASSERT_GE(link7, 0);
    const rc::RobotModel &robot = *model.robot;
    std::vector<double> q = robot.neutralConfiguration();
    q[5] = std::nan("");  // panda_joint6
    EXPECT_FALSE(model.selfPairTables.apart(static_cast<std::size_t>(link7), q.data(), 0.0));
    EXPECT_FALSE(model.selfPairTables.apart(model.selfPairs.size(), q.data(), 0.0));  // no such pair

    // Outside the joint limits the nearest node is read and the distance to it swept: far out, no
    // proof; just out, a proof only where the oracle agrees.
    const auto [a, b] = model.selfPairs[static_cast<std::size_t>(link7)];
    rc::RobotData data(robot);
    int proven = 0;
    for (std::size_t coordinate : {5u, 6u})  // panda_joint6, panda_joint7
        for (double beyond : {-1000.0, -0.3, -0.02, 0.02, 0.3, 1000.0})
        {
            q = robot.neutralConfiguration();
            q[coordinate] = (beyond < 0 ? robot.lowerBounds[coordinate] : robot.upperBounds[coordinate]) + beyond;
            const bool apart = model.selfPairTables.apart(static_cast<std::size_t>(link7), q.data(), 0.0);
            if (std::abs(beyond) > 100)
            {
                EXPECT_FALSE(apart) << "coordinate " << coordinate << " at " << q[coordinate];
                continue;
            }
            proven += apart;
            rc::forwardKinematics(robot, data, q.data());
            EXPECT_FALSE(apart && rc::solidsOverlap(*model.componentBvhs[a], data.oMl[model.componentLink[a]],
                                                    model.components[a].closed, *model.componentBvhs[b],
                                                    data.oMl[model.componentLink[b]], model.components[b].closed, 0.0))
                << "coordinate " << coordinate << " at " << q[coordinate];
        }
    // Just outside a limit the wrist is as far apart as just inside: the table still proves it.
    EXPECT_GT(proven, 0);
}
