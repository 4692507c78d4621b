// SRDF: disabled pairs and group states of the shared Panda, applying them to the model, and the
// errors of malformed files.
#include <functional>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rc = rastercheck;

namespace
{
using rastercheck::test::expectInputError;

std::size_t allowedPairs(const rc::RobotModel &model)
{
    std::size_t count = 0;
    for (std::size_t a = 0; a < model.numComponents(); ++a)
        for (std::size_t b = a + 1; b < model.numComponents(); ++b)
            count += model.isCollisionAllowed(static_cast<int>(a), static_cast<int>(b)) ? 1 : 0;
    return count;
}
}  // namespace

TEST(Srdf, PandaPairsAndGroupState)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Srdf srdf = rc::loadSrdf(root + "/robots/panda/panda.srdf");
    EXPECT_EQ(srdf.robotName, "panda");
    EXPECT_EQ(srdf.disabledCollisions.size(), 35u);
    EXPECT_EQ(srdf.disabledCollisions[0], (std::pair<std::string, std::string>{"panda_hand", "panda_leftfinger"}));
    ASSERT_EQ(srdf.groupStates.count("default"), 1u);
    const std::map<std::string, double> &state = srdf.groupStates.at("default");
    EXPECT_EQ(state.size(), 8u);
    EXPECT_DOUBLE_EQ(state.at("panda_joint4"), -2.35619);
    EXPECT_DOUBLE_EQ(state.at("panda_finger_joint1"), 0.001);

    rc::RobotModelPtr panda = rc::loadUrdf(root + "/robots/panda/panda.urdf");
    EXPECT_EQ(allowedPairs(*panda), 9u);  // adjacent links with geometry (link7-hand via the fixed link8 is not)
    const int hand = panda->links[panda->linkIndex("panda_hand")].component;
    const int link3 = panda->links[panda->linkIndex("panda_link3")].component;
    EXPECT_FALSE(panda->isCollisionAllowed(hand, link3));
    rc::applySrdf(*panda, srdf);
    EXPECT_TRUE(panda->isCollisionAllowed(hand, link3));
    EXPECT_TRUE(panda->isCollisionAllowed(link3, hand));
    EXPECT_EQ(allowedPairs(*panda), 35u);  // every SRDF pair is a distinct pair of components
}

TEST(Srdf, UnknownLinksAreSkippedWithAWarning)
{
    RASTERCHECK_REQUIRE_DATA(root);
    rc::RobotModelPtr panda = rc::loadUrdf(root + "/robots/panda/panda.urdf");
    const rc::Srdf srdf = rc::loadSrdfString(
        "<robot name=\"panda\"><disable_collisions link1=\"panda_link0\" link2=\"ghost\" reason=\"x\"/>"
        "<disable_collisions link1=\"panda_link0\" link2=\"panda_link7\"/></robot>",
        "test.srdf");
    std::vector<std::string> warnings;
    rc::setLogHandler([&](rc::LogLevel, const std::string &message) { warnings.push_back(message); });
    rc::applySrdf(*panda, srdf);
    rc::setLogHandler(nullptr);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("'ghost'"), std::string::npos);
    EXPECT_TRUE(panda->isCollisionAllowed(panda->links[panda->linkIndex("panda_link0")].component,
                                          panda->links[panda->linkIndex("panda_link7")].component));
}

TEST(Srdf, BadInputNamesTheFileAndElement)
{
    expectInputError([] { rc::loadSrdfString("<robot name=\"r\"><disable_collisions link1=\"a\"", "bad.srdf"); },
                     "bad.srdf", "line", "malformed XML");
    expectInputError([] { rc::loadSrdfString("<notrobot/>", "root.srdf"); }, "root.srdf", "", "no <robot>");
    expectInputError(
        []
        {
            rc::loadSrdfString(
                "<robot name=\"r\"><disable_collisions link1=\"a\" link2=\"b\"/>"
                "<disable_collisions link1=\"a\"/></robot>",
                "pair.srdf");
        },
        "pair.srdf", "disable_collisions #1", "missing attribute 'link2'");
    expectInputError(
        []
        {
            rc::loadSrdfString(
                "<robot name=\"r\"><group_state name=\"home\" group=\"arm\">"
                "<joint name=\"j1\" value=\"nan\"/></group_state></robot>",
                "value.srdf");
        },
        "value.srdf", "group_state 'home' joint 'j1'", "not a finite number");
    const std::string missing = rc::test::makeTempDir("srdf") + "/none.srdf";
    expectInputError([&] { rc::loadSrdf(missing); }, missing, "", "file not found");
}
