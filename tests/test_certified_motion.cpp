// CertifiedMotionValidator: a thin wall the discrete validator steps over, free edges, and on Panda
// and crane scenes every accepted edge (and every reported valid prefix) re-checked by the exact
// oracle so densely that no point of the robot moves more than 2 mm between checks.
#include <algorithm>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>

#include "TestSupport.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/RigidBody.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/MotionValidator.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;

namespace
{
struct Context
{
    ::ompl::geometric::SimpleSetupPtr setup;
    ob::SpaceInformationPtr si;
    rco::StateValidityCheckerPtr validity;
};

Context makeContext(const rc::Problem &problem, double segmentFraction = 0.01)
{
    rco::SetupOptions options;
    options.longestValidSegmentFraction = segmentFraction;
    Context context;
    context.setup = rco::makeSimpleSetup(problem, options);
    context.si = context.setup->getSpaceInformation();
    context.si->setup();
    context.validity = rco::getStateValidityChecker(*context.setup);
    return context;
}

/** \brief A 10 cm cube that flies in a 4 m room with a 2 mm plate across it at x = 0. */
rc::Problem cubeAndPlate()
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d::Constant(-2);
    bounds.max = Eigen::Vector3d::Constant(2);
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("plate", rc::makeBox(Eigen::Vector3d(0.002, 1.0, 1.0)));
    return {rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d(0.1, 0.1, 0.1)), bounds), scene, nullptr};
}

void setPosition(const Context &context, ob::State *state, double x, double y, double z)
{
    context.validity->getStateMapping().fromConfiguration(std::vector<double>{x, y, z, 0, 0, 0, 1}, state);
}

/** \brief Whether every state from fraction 0 to \a upTo of the edge passes the exact oracle, checked
    at steps over which no point of the robot moves more than \a step (MotionBound). */
/** \brief One way of sizing a certified edge's intervals (CertifiedMotionOptions). */
struct Sizing
{
    const char *name;
    bool byClearance;
    rc::ClearanceMeasure measure;
    rco::CertifiedMotionOptions options() const
    {
        rco::CertifiedMotionOptions options;
        options.sizeByClearance = byClearance;
        options.clearanceMeasure = measure;
        return options;
    }
};
constexpr Sizing kSizings[] = {{"bisection", false, rc::ClearanceMeasure::Exact},
                               {"sized by clearance", true, rc::ClearanceMeasure::Exact},
                               {"sized by the hulls' bound", true, rc::ClearanceMeasure::HullBound}};

bool denselyFree(const Context &context, const rco::CertifiedMotionValidator &certified, const ob::State *from,
                 const ob::State *to, double upTo, double step)
{
    const rco::StateMapping &mapping = context.validity->getStateMapping();
    const std::vector<double> qa = mapping.toConfiguration(from), qb = mapping.toConfiguration(to);
    const double sweep = certified.getMotionBound().sweep(qa.data(), qb.data());
    const std::size_t n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(sweep * upTo / step)));
    const std::size_t dof = mapping.numCoordinates();
    std::vector<double> rows((n + 1) * dof);
    ob::ScopedState<> between(context.si);
    for (std::size_t k = 0; k <= n; ++k)
    {
        context.si->getStateSpace()->interpolate(from, to, upTo * static_cast<double>(k) / static_cast<double>(n),
                                                 between.get());
        mapping.toConfiguration(between.get(), rows.data() + k * dof);
    }
    std::vector<std::uint8_t> valid(n + 1);
    rc::CollisionRequest exact = context.validity->getRequest();
    exact.mode = rc::CollisionMode::Exact;
    context.validity->getChecker().check(rows.data(), n + 1, valid.data(), exact);
    return std::all_of(valid.begin(), valid.end(), [](std::uint8_t v) { return v != 0; });
}

/** \brief Random edges of at most \a range (OMPL's distance) from valid states; each accepted one,
    and each valid prefix, must be densely free. Returns {accepted, rejected, rejected by the
    certified validator but accepted by the discrete one}. */
std::array<int, 3> checkRandomEdges(const Context &context, int edges, double range, unsigned int seed,
                                    const rco::CertifiedMotionOptions &options = {})
{
    const rco::CertifiedMotionValidator certified(context.si, *context.validity, options);
    const rco::MotionValidator discrete(context.si, *context.validity);
    rc::test::seedOmpl(seed);  // before the sampler exists: the same edges on every run
    ob::StateSamplerPtr sampler = context.si->allocStateSampler();
    ob::ScopedState<> from(context.si), to(context.si), target(context.si), last(context.si);
    std::array<int, 3> counts{0, 0, 0};
    for (int e = 0; e < edges; ++e)
    {
        do
            sampler->sampleUniform(from.get());
        while (!context.si->isValid(from.get()));
        sampler->sampleUniform(target.get());
        const double d = context.si->distance(from.get(), target.get());
        context.si->getStateSpace()->interpolate(from.get(), target.get(), std::min(1.0, range / d), to.get());
        if (certified.checkMotion(from.get(), to.get()))
        {
            ++counts[0];
            EXPECT_TRUE(denselyFree(context, certified, from.get(), to.get(), 1.0, 0.002)) << "edge " << e;
            continue;
        }
        ++counts[1];
        counts[2] += discrete.checkMotion(from.get(), to.get()) ? 1 : 0;
        std::pair<ob::State *, double> lastValid(last.get(), -1.0);
        EXPECT_FALSE(certified.checkMotion(from.get(), to.get(), lastValid)) << "edge " << e;
        EXPECT_GE(lastValid.second, 0.0);
        EXPECT_LT(lastValid.second, 1.0);
        if (lastValid.second > 0)
        {
            EXPECT_TRUE(denselyFree(context, certified, from.get(), to.get(), lastValid.second, 0.002)) << "edge " << e;
        }
    }
    return counts;
}
}  // namespace

TEST(CertifiedMotion, AThinWallTheDiscreteValidatorStepsOverIsFound)
{
    // Resolution 20 % of the extent: the discrete validator checks the 2.3 m edge at its middle
    // (x = 0.15) and its end.
    const Context context = makeContext(cubeAndPlate(), 0.2);
    const rco::CertifiedMotionValidator certified(context.si, *context.validity);
    const rco::MotionValidator discrete(context.si, *context.validity);
    ob::ScopedState<> from(context.si), to(context.si), last(context.si);
    setPosition(context, from.get(), -1.0, 0.1, 0.0);
    setPosition(context, to.get(), 1.3, 0.1, 0.0);
    ASSERT_TRUE(context.si->isValid(from.get()));
    ASSERT_TRUE(context.si->isValid(to.get()));
    EXPECT_TRUE(discrete.checkMotion(from.get(), to.get()));  // the plate falls between its samples
    EXPECT_FALSE(certified.checkMotion(from.get(), to.get()));

    std::pair<ob::State *, double> lastValid(last.get(), -1.0);
    EXPECT_FALSE(certified.checkMotion(from.get(), to.get(), lastValid));
    // The cube (x +- 0.05) meets the plate (x +- 0.001) at x = -0.051, t = 0.4126: the valid prefix
    // ends before it, and not far before (the default margin is a tenth of the cube's reach, 8.7 mm:
    // coarse intervals of 1.7 cm of travel).
    const double x = context.validity->getStateMapping().toConfiguration(last.get())[0];
    EXPECT_NEAR(lastValid.second, (x + 1.0) / 2.3, 1e-12);
    EXPECT_LT(x, -0.051);
    EXPECT_GT(x, -0.051 - 0.02);
    EXPECT_TRUE(context.si->isValid(last.get()));

    // Beside the plate, 1 cm clear of its edge (y = 0.5 + 0.05 + 0.01): certified, and it needs
    // refinement only near the plate.
    setPosition(context, from.get(), -1.0, 0.56, 0.0);
    setPosition(context, to.get(), 1.0, 0.56, 0.0);
    EXPECT_TRUE(certified.checkMotion(from.get(), to.get()));
    // 1 mm into its edge: a collision.
    setPosition(context, from.get(), -1.0, 0.549, 0.0);
    setPosition(context, to.get(), 1.0, 0.549, 0.0);
    EXPECT_FALSE(certified.checkMotion(from.get(), to.get()));
}

TEST(CertifiedMotion, AFreeEdgeNeedsOneCheckPerCoarseInterval)
{
    const Context context = makeContext(cubeAndPlate());
    rco::CertifiedMotionOptions options;
    options.margin = 0.1;
    const rco::CertifiedMotionValidator certified(context.si, *context.validity, options);
    ob::ScopedState<> from(context.si), to(context.si);
    setPosition(context, from.get(), -1.5, -1.0, -1.0);
    setPosition(context, to.get(), -1.5, 1.0, -1.0);  // 2 m along y, far from the plate
    EXPECT_TRUE(certified.checkMotion(from.get(), to.get()));
    // Every point moves 2 m: intervals of 0.2 m keep each within 0.1 m of its midpoint.
    EXPECT_EQ(certified.getCheckedStateCount(), 10u);
}

TEST(CertifiedMotion, ASlideCloserThanTheFinestMarginIsRejectedWithinItsBudget)
{
    // The cube slides 0.8 m along the plate's face 1 um away: free, but no margin down to
    // 0.1 m / 2^12 = 24 um can certify it. It is rejected (a documented false alarm) after a
    // bounded number of checks: 4 coarse intervals, at most 16 x 4 + 64 x 12 refined midpoints,
    // each failing one checked once more at the padding (or its clearance measured, exactly or by
    // the hulls' bound, of 1 um).
    const Context context = makeContext(cubeAndPlate());
    for (const Sizing &sizing : kSizings)
    {
        rco::CertifiedMotionOptions options = sizing.options();
        options.margin = 0.1;
        const rco::CertifiedMotionValidator certified(context.si, *context.validity, options);
        ob::ScopedState<> from(context.si), to(context.si), last(context.si);
        const double x = -0.051 - 1e-6;
        setPosition(context, from.get(), x, -0.4, 0.0);
        setPosition(context, to.get(), x, 0.4, 0.0);
        ASSERT_TRUE(denselyFree(context, certified, from.get(), to.get(), 1.0, 0.002));
        EXPECT_FALSE(certified.checkMotion(from.get(), to.get())) << sizing.name;
        const std::uint64_t spent = certified.getCheckedStateCount() + certified.getClearanceCount();
        EXPECT_LE(spent, 2u * (4 + 16 * 4 + 64 * 12)) << sizing.name;
        EXPECT_GT(spent, 100u) << sizing.name;  // it did refine before giving up
        std::pair<ob::State *, double> lastValid(last.get(), -1.0);
        EXPECT_FALSE(certified.checkMotion(from.get(), to.get(), lastValid));
        EXPECT_GE(lastValid.second, 0.0);
        EXPECT_LT(lastValid.second, 1.0);
    }
}

TEST(CertifiedMotion, APassNearAnEdgeSizedByClearanceNeedsFewerChecks)
{
    // The cube flies 2 m along x past the plate's edge (y = 0.5), 5 mm beside it: free. Bisection
    // refines the intervals near x = 0 until their margin is under 5 mm; the midpoints' clearance
    // certifies most of each failing interval at once. Both accept the edge, and it is free.
    const Context context = makeContext(cubeAndPlate());
    ob::ScopedState<> from(context.si), to(context.si);
    setPosition(context, from.get(), -1.0, 0.5 + 0.05 + 0.005, 0.0);
    setPosition(context, to.get(), 1.0, 0.5 + 0.05 + 0.005, 0.0);
    std::uint64_t states[3], clearances[3];
    for (int k = 0; k < 3; ++k)
    {
        rco::CertifiedMotionOptions options = kSizings[k].options();
        options.margin = 0.1;
        const rco::CertifiedMotionValidator certified(context.si, *context.validity, options);
        EXPECT_TRUE(certified.checkMotion(from.get(), to.get())) << kSizings[k].name;
        EXPECT_TRUE(denselyFree(context, certified, from.get(), to.get(), 1.0, 0.002));
        states[k] = certified.getCheckedStateCount();
        clearances[k] = certified.getClearanceCount();
    }
    EXPECT_EQ(clearances[0], 0u);
    for (int k = 1; k < 3; ++k)
    {
        EXPECT_GT(clearances[k], 0u) << kSizings[k].name;
        EXPECT_LT(states[k] + clearances[k], states[0]) << kSizings[k].name;
        std::printf("bisection: %llu states; %s: %llu states and %llu clearances\n",
                    static_cast<unsigned long long>(states[0]), kSizings[k].name,
                    static_cast<unsigned long long>(states[k]), static_cast<unsigned long long>(clearances[k]));
    }
}

TEST(CertifiedMotion, RejectsRasterModeAndBadOptions)
{
    rc::Problem problem = cubeAndPlate();
    rco::SetupOptions options;
    options.request.mode = rc::CollisionMode::Raster;
    options.edges = rco::EdgeChecking::Certified;
    EXPECT_THROW(rco::makeSimpleSetup(problem, options), rc::ConfigurationError);
    const Context context = makeContext(problem);
    rco::CertifiedMotionOptions bad;
    bad.margin = -1;
    EXPECT_THROW(rco::CertifiedMotionValidator(context.si, *context.validity, bad), rc::ConfigurationError);
    bad.margin = 0;
    bad.levels = 41;
    EXPECT_THROW(rco::CertifiedMotionValidator(context.si, *context.validity, bad), rc::ConfigurationError);
    bad.levels = 12;
    bad.deviceRakeWidth = 0;
    EXPECT_THROW(rco::CertifiedMotionValidator(context.si, *context.validity, bad), rc::ConfigurationError);
    EXPECT_EQ(rco::parseEdgeChecking("certified"), rco::EdgeChecking::Certified);
    EXPECT_THROW(rco::parseEdgeChecking("continuous"), rc::ConfigurationError);
}

TEST(CertifiedMotion, EveryAcceptedPandaEdgeIsCollisionFreeAtEveryPoint)
{
    RASTERCHECK_REQUIRE_DATA(root);
    for (const char *scenario : {"cage", "bookshelf_thin"})
    {
        const Context context = makeContext(rc::test::pandaProblem(root, scenario));
        for (const Sizing &sizing : kSizings)
        {
            // RRT-Connect's default range: a fifth of the space's extent.
            const std::array<int, 3> counts =
                checkRandomEdges(context, 60, 0.2 * context.si->getMaximumExtent(), 3, sizing.options());
            EXPECT_GT(counts[0], 5) << scenario;  // both answers occur
            EXPECT_GT(counts[1], 5) << scenario;
            std::printf("%s, %s: %d edges certified, %d not (%d of them accepted by the discrete validator)\n",
                        scenario, sizing.name, counts[0], counts[1], counts[2]);
        }
    }
}

TEST(CertifiedMotion, EveryAcceptedUr5EdgeIsCollisionFreeAtEveryPoint)
{
    // The UR5 among a bookshelf's shelves: its base and upper arm, centimetres apart at the
    // shoulder, are held to the shoulder joints' turns at the base's own distance from their axes
    // (MotionBound's pair sweeps from the nearer side).
    RASTERCHECK_REQUIRE_DATA(root);
    rc::ProblemSource source;
    source.urdfPath = root + "/mbm/ur5/ur5.urdf";
    source.srdfPath = root + "/mbm/ur5/ur5.srdf";
    source.scenePath = root + "/mbm/ur5/problems/bookshelf_small_ur5/scene0001.yaml";
    const Context context = makeContext(rc::loadProblem(source));
    const std::array<int, 3> counts = checkRandomEdges(context, 12, 0.2 * context.si->getMaximumExtent(), 7);
    EXPECT_GT(counts[0], 2);
    EXPECT_GT(counts[1], 2);
    std::printf(
        "UR5 bookshelf_small, bisection: %d edges certified, %d not (%d of them accepted by the discrete "
        "validator)\n",
        counts[0], counts[1], counts[2]);
}

TEST(CertifiedMotion, EveryAcceptedCraneEdgeIsCollisionFreeAtEveryPoint)
{
    const rc::Problem &plant = rc::test::plant();
    const Context context = makeContext(plant);
    // A quarter of the edges under the sanitizers (RASTERCHECK_SAMPLE_SCALE): each edge's dense
    // check is most of the test's time.
    const int edges = rc::test::scaledCount(20, "RASTERCHECK_SAMPLE_SCALE");
    for (const Sizing &sizing : kSizings)
    {
        const std::array<int, 3> counts =
            checkRandomEdges(context, edges, 0.1 * context.si->getMaximumExtent(), 5, sizing.options());
        EXPECT_GT(counts[0], 2);
        std::printf("crane, %s: %d edges certified, %d not (%d of them accepted by the discrete validator)\n",
                    sizing.name, counts[0], counts[1], counts[2]);
    }
}

TEST(CertifiedMotion, WhereTheFirstBatchReachesTheDeviceItIsWiderAndTheEdgesTakeFewerCalls)
{
    // On the stages (here the host executor, which counts the calls a GPU would get) every call
    // costs about a device's latency: an edge's first batch takes deviceRakeWidth midpoints where
    // it reaches the device, and the same verdicts come in fewer calls.
    RASTERCHECK_REQUIRE_DATA(root);
    rco::SetupOptions options;
    options.checker.backend = rc::BackendChoice::HostStages;
    options.checker.threads = 1;
    options.checker.minDeviceBatch = 1;
    const ::ompl::geometric::SimpleSetupPtr setup = rco::makeSimpleSetup(rc::test::pandaProblem(root, "cage"), options);
    const ob::SpaceInformationPtr si = setup->getSpaceInformation();
    si->setup();
    const rco::StateValidityCheckerPtr validity = rco::getStateValidityChecker(*setup);
    const auto *stages = dynamic_cast<const rc::StagedBackend *>(&validity->getChecker().backend());
    ASSERT_NE(stages, nullptr);
    rco::CertifiedMotionOptions narrow;
    narrow.deviceRakeWidth = 1;
    const rco::CertifiedMotionValidator one(si, *validity, narrow), wide(si, *validity);
    EXPECT_EQ(one.firstBatchWidth(1), 1u);
    EXPECT_EQ(wide.firstBatchWidth(1), 8u);
    ob::StateSamplerPtr sampler = si->allocStateSampler();
    ob::ScopedState<> from(si), to(si);
    std::uint64_t calls[2] = {0, 0};
    int accepted = 0;
    for (int e = 0; e < 40; ++e)
    {
        sampler->sampleUniform(from.get());
        sampler->sampleUniform(to.get());
        si->getStateSpace()->interpolate(from.get(), to.get(), 0.3, to.get());
        bool verdicts[2];
        for (int w = 0; w < 2; ++w)
        {
            const std::uint64_t before = stages->executorCounts().calls;
            verdicts[w] = (w == 0 ? one : wide).checkMotion(from.get(), to.get());
            calls[w] += stages->executorCounts().calls - before;
        }
        EXPECT_EQ(verdicts[0], verdicts[1]) << "edge " << e;
        accepted += verdicts[0] ? 1 : 0;
    }
    EXPECT_GT(accepted, 3);  // both verdicts occur
    EXPECT_LT(accepted, 37);
    EXPECT_LT(4 * calls[1], 3 * calls[0]) << calls[1] << " calls wide, " << calls[0] << " one midpoint first";

    // The CPU backend, and batches below the device's smallest: the first batch stays narrow.
    const Context cpu = makeContext(rc::test::pandaProblem(root, "cage"));
    EXPECT_EQ(rco::CertifiedMotionValidator(cpu.si, *cpu.validity).firstBatchWidth(1000), 1u);
    options.checker.minDeviceBatch = 32;
    const ::ompl::geometric::SimpleSetupPtr hybrid =
        rco::makeSimpleSetup(rc::test::pandaProblem(root, "cage"), options);
    hybrid->getSpaceInformation()->setup();
    const rco::CertifiedMotionValidator mixed(hybrid->getSpaceInformation(), *rco::getStateValidityChecker(*hybrid));
    EXPECT_EQ(mixed.firstBatchWidth(3), 1u);  // 24 midpoints: the CPU's
    EXPECT_EQ(mixed.firstBatchWidth(4), 8u);  // 32: the device's
}

TEST(CertifiedMotion, EdgesCheckedTogetherGetTheVerdictsTheyGetAlone)
{
    // checkMotions puts the midpoints of many edges (each with its own sweeps, so its own pair
    // paddings: PairPadding rows) into one batch; verdicts and valid prefixes must be those of
    // checkMotion on each edge alone, for the certified and the batched discrete validator.
    RASTERCHECK_REQUIRE_DATA(root);
    const Context context = makeContext(rc::test::pandaProblem(root, "cage"));
    const rco::CertifiedMotionValidator certified(context.si, *context.validity);
    const rco::MotionValidator discrete(context.si, *context.validity);
    ob::StateSamplerPtr sampler = context.si->allocStateSampler();
    constexpr int kEdges = 40;
    std::vector<ob::ScopedState<>> states;
    std::vector<rco::Edge> edges;
    for (int e = 0; e < 2 * kEdges; ++e)
    {
        states.emplace_back(context.si);
        sampler->sampleUniform(states.back().get());
    }
    for (int e = 0; e < kEdges; ++e)
    {
        // Short and long edges mixed: their sweeps, and so their paddings, differ.
        context.si->getStateSpace()->interpolate(states[2 * e].get(), states[2 * e + 1].get(), e % 2 ? 0.1 : 0.6,
                                                 states[2 * e + 1].get());
        edges.push_back({states[2 * e].get(), states[2 * e + 1].get()});
    }
    for (const rco::BatchMotionValidator *validator : {static_cast<const rco::BatchMotionValidator *>(&certified),
                                                       static_cast<const rco::BatchMotionValidator *>(&discrete)})
    {
        std::vector<std::uint8_t> together(kEdges), firstTogether(kEdges);
        std::vector<double> prefixes(kEdges);
        validator->checkMotions(edges.data(), edges.size(), together.data());
        validator->checkMotions(edges.data(), edges.size(), firstTogether.data(), prefixes.data());
        int accepted = 0;
        for (int e = 0; e < kEdges; ++e)
        {
            const bool alone = validator->checkMotion(edges[e].from, edges[e].to);
            std::pair<ob::State *, double> lastValid(nullptr, 1.0);
            validator->checkMotion(edges[e].from, edges[e].to, lastValid);
            EXPECT_EQ(together[e] != 0, alone) << "edge " << e;
            EXPECT_EQ(firstTogether[e] != 0, alone) << "edge " << e;
            EXPECT_DOUBLE_EQ(prefixes[e], alone ? 1.0 : lastValid.second) << "edge " << e;
            accepted += alone ? 1 : 0;
        }
        EXPECT_GT(accepted, 3);  // both verdicts occur
        EXPECT_LT(accepted, kEdges - 3);
    }
}
