// SRDF: disabled pairs and group states of the shared Panda, and applying them to the model
// (malformed files and unknown links: test_bad_input.cpp).
#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rc = rastercheck;

namespace
{
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
