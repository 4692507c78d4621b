// The OMPL validity checker on bad states, and the batched motion validator against OMPL's
// DiscreteMotionValidator (both overloads: verdict, last valid fraction and state) on a synthetic
// SE(3) scene and on a Panda MotionBenchMaker scene. Both under many threads: test_concurrency.cpp.
#include <random>

#include <gtest/gtest.h>

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/util/RandomNumbers.h>

#include "TestSupport.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/RigidBody.h"
#include "rastercheck/ompl/MotionValidator.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;

namespace
{
// OMPL's seed can only be set before its first random number: at static initialisation.
const bool kSeeded = (::ompl::RNG::setSeed(42), true);

struct Context
{
    rco::StateMappingConstPtr mapping;
    rco::CheckerConstPtr checker;
    ob::SpaceInformationPtr si;
    std::shared_ptr<rco::StateValidityChecker> validity;
};

Context makeContext(const rc::RobotModelConstPtr &robot, const rc::SceneConstPtr &scene, double segmentFraction)
{
    Context context;
    context.mapping = std::make_shared<const rco::StateMapping>(robot);
    context.checker = std::make_shared<const rc::Checker>(robot, scene);
    context.mapping->getStateSpace()->setLongestValidSegmentFraction(segmentFraction);
    context.si = std::make_shared<ob::SpaceInformation>(context.mapping->getStateSpace());
    context.validity = std::make_shared<rco::StateValidityChecker>(context.si, context.mapping, context.checker);
    context.si->setStateValidityChecker(context.validity);
    context.si->setup();
    return context;
}

// A 0.3 m cube flying among 24 boxes in a 4 m room.
Context cubeAmongBoxes()
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d::Constant(-2);
    bounds.max = Eigen::Vector3d::Constant(2);
    auto robot = rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d(0.3, 0.2, 0.1)), bounds);
    auto scene = std::make_shared<rc::Scene>();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> position(-1.8, 1.8), size(0.1, 0.6);
    for (int i = 0; i < 24; ++i)
    {
        rc::Mesh box = rc::makeBox(Eigen::Vector3d(size(rng), size(rng), size(rng)));
        box.transform(Eigen::Isometry3d(Eigen::Translation3d(position(rng), position(rng), position(rng))));
        scene->addObject("box_" + std::to_string(i), std::move(box));
    }
    return makeContext(robot, scene, 0.01);
}

Context pandaScene(const std::string &root, const std::string &scenario)
{
    const rc::Problem problem = rc::test::pandaProblem(root, scenario);
    return makeContext(problem.robot, problem.scene, 0.01);
}

// Compares the two validators on \a edges random edges from valid states; returns the number of
// invalid edges seen (so a caller can require a mix).
int compareWithDiscreteMotionValidator(const Context &context, int edges, double reach)
{
    const ob::StateSpacePtr &space = context.si->getStateSpace();
    ob::DiscreteMotionValidator discrete(context.si);
    rco::MotionValidator batched(context.si, *context.validity, 4);
    ob::StateSamplerPtr sampler = space->allocDefaultStateSampler();
    ob::ScopedState<> s1(space), target(space), s2(space), lastDiscrete(space), lastBatched(space);
    int invalid = 0;
    for (int e = 0; e < edges; ++e)
    {
        do
            sampler->sampleUniform(s1.get());
        while (!context.si->isValid(s1.get()));
        sampler->sampleUniform(target.get());
        space->interpolate(s1.get(), target.get(), reach, s2.get());

        const bool d2 = discrete.checkMotion(s1.get(), s2.get());
        const bool b2 = batched.checkMotion(s1.get(), s2.get());
        EXPECT_EQ(d2, b2) << "edge " << e;

        std::pair<ob::State *, double> dLast(lastDiscrete.get(), -1.0), bLast(lastBatched.get(), -1.0);
        const bool d3 = discrete.checkMotion(s1.get(), s2.get(), dLast);
        const bool b3 = batched.checkMotion(s1.get(), s2.get(), bLast);
        EXPECT_EQ(d3, b3) << "edge " << e;
        EXPECT_EQ(d3, d2);
        EXPECT_EQ(dLast.second, bLast.second) << "edge " << e;  // exactly: same (j - 1) / n
        if (!d3)
        {
            ++invalid;
            EXPECT_TRUE(space->equalStates(lastDiscrete.get(), lastBatched.get())) << "edge " << e;
            EXPECT_TRUE(context.si->isValid(lastBatched.get())) << "edge " << e;
        }
        // Without a state to fill, only the fraction.
        std::pair<ob::State *, double> bare(nullptr, -1.0);
        EXPECT_EQ(batched.checkMotion(s1.get(), s2.get(), bare), d3);
        EXPECT_EQ(bare.second, d3 ? -1.0 : dLast.second);
    }
    EXPECT_EQ(discrete.getValidMotionCount(), batched.getValidMotionCount() * 2 / 3);
    EXPECT_EQ(batched.getCheckedMotionCount(), 3u * static_cast<unsigned int>(edges));
    return invalid;
}
}  // namespace

TEST(OmplValidity, OutOfBoundsAndNonFiniteStatesAreInvalid)
{
    const Context context = cubeAmongBoxes();
    ob::ScopedState<> state(context.si->getStateSpace());
    context.mapping->fromConfiguration(std::vector<double>{0, 0, 2.5, 0, 0, 0, 1}, state.get());
    rc::Contact contact;
    EXPECT_FALSE(context.validity->isValid(state.get(), contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);
    context.mapping->fromConfiguration(std::vector<double>{0, std::nan(""), 0, 0, 0, 0, 1}, state.get());
    EXPECT_FALSE(context.validity->isValid(state.get()));
}

TEST(OmplValidity, AreValidGivesIsValidsVerdictsInOneBatch)
{
    // 400 uniform states (a mix of free and colliding among the boxes), one outside the bounds and
    // one with a NaN: areValid's verdicts are isValid's, and it counts every state as a call.
    const Context context = cubeAmongBoxes();
    ob::StateSamplerPtr sampler = context.si->allocStateSampler();
    std::vector<ob::State *> owned(402);
    for (ob::State *&state : owned)
    {
        state = context.si->allocState();
        sampler->sampleUniform(state);
    }
    context.mapping->fromConfiguration(std::vector<double>{0, 0, 2.5, 0, 0, 0, 1}, owned[7]);
    context.mapping->fromConfiguration(std::vector<double>{0, std::nan(""), 0, 0, 0, 0, 1}, owned[300]);
    const std::vector<const ob::State *> states(owned.begin(), owned.end());
    context.validity->resetCounters();
    std::vector<std::uint8_t> valid(states.size(), 2);
    context.validity->areValid(states.data(), states.size(), valid.data());
    EXPECT_EQ(context.validity->getCallCount(), states.size());
    const std::uint64_t invalid = context.validity->getInvalidCount();
    std::size_t free = 0;
    for (std::size_t i = 0; i < states.size(); ++i)
    {
        EXPECT_EQ(valid[i] != 0, context.validity->isValid(states[i])) << i;
        free += valid[i];
    }
    EXPECT_EQ(valid[7], 0);
    EXPECT_EQ(valid[300], 0);
    EXPECT_EQ(invalid, states.size() - free);
    EXPECT_GT(free, 40u);
    EXPECT_GT(invalid, 20u);
    for (ob::State *state : owned)
        context.si->freeState(state);
}

TEST(OmplValidity, MotionValidatorMatchesDiscreteOnSyntheticScene)
{
    const Context context = cubeAmongBoxes();
    const int invalid = compareWithDiscreteMotionValidator(context, 250, 0.3);
    EXPECT_GT(invalid, 25);
    EXPECT_LT(invalid, 225);
}

TEST(OmplValidity, MotionValidatorMatchesDiscreteOnPandaScene)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const Context context = pandaScene(root, "bookshelf_small");
    // The default (safe) mode decides a Panda state in about a millisecond here: few edges.
    ASSERT_TRUE(kSeeded);
    const int invalid = compareWithDiscreteMotionValidator(context, 40, 0.5);
    EXPECT_GE(invalid, 5);
    EXPECT_LE(invalid, 35);
}
