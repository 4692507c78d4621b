// The GPU backend's code path on the CPU: the batched stages (device/BatchPipeline.h) through the
// host executor, with the host's per-state reduction (StagedBackend), must decide every state and
// report every first contact exactly as the CPU backend does. The CUDA backend runs the same driver
// and per-element functions; only the loops, scans, compaction and sort differ. The host's scratch
// buffers are poisoned (HostScratch::Poisoned) as uninitialised device memory may be, except in the
// chunked run, which reuses what earlier chunks left as the CUDA runner does.
#include <gtest/gtest.h>

#include <thread>

#include "BackendSuites.h"
#include "BlindSpots.h"
#include "TestSupport.h"
#include "rastercheck/collision/StagedBackend.h"

namespace rc = rastercheck;

namespace
{
const rc::CollisionMode kModes[] = {rc::CollisionMode::Safe, rc::CollisionMode::Raster, rc::CollisionMode::Exact,
                                    rc::CollisionMode::Conservative};

std::string label(const std::string &suite, rc::CollisionMode mode)
{
    return suite + " (" + rc::toString(mode) + ")";
}

/** \brief \a states per suite, a quarter under the sanitizers (scripts/sanitize.sh sets
    RASTERCHECK_NONCONVEX_SCALE), which slow these comparisons 10 to 50 times. */
std::size_t sanitizerScaled(int states)
{
    return static_cast<std::size_t>(rc::test::scaledCount(states, "RASTERCHECK_NONCONVEX_SCALE"));
}

/** \brief The stages on the host with poisoned scratch, as uninitialised device memory may be. */
std::unique_ptr<rc::StageRunner> poisonedStages(const rc::CollisionModelConstPtr &model,
                                                const rc::device::StageBudget &budget = {})
{
    return rc::makeHostStageRunner(model, budget, rc::HostScratch::Poisoned);
}
}  // namespace

TEST(StagedPipeline, SameVerdictsAndFirstContactsAsTheCpuBackendOnTheAccuracySuites)
{
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(200)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend staged(model, poisonedStages(model));
        // The proofs in pair order, as the GPU takes them in large batches (StageBudget).
        rc::device::StageBudget pairOrder;
        pairOrder.orderedProofsFrom = 0;
        const rc::StagedBackend ordered(model, poisonedStages(model, pairOrder));
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(ordered, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " pair order");
            const rc::test::Agreement counts =
                rc::test::expectSameDecisions(staged, cpu, *model, suite.states, request, label(suite.name, mode));
            if (mode == rc::CollisionMode::Exact && suite.name.rfind("panda", 0) == 0)
            {
                EXPECT_GT(counts.valid, 0u) << suite.name;  // the comparison covers both answers
                EXPECT_GT(counts.invalid, 0u) << suite.name;
            }
        }
    }
}

TEST(StagedPipeline, PaddingAndSwitchedOffChecksMatchTheCpuBackend)
{
    const std::vector<rc::test::StateSuite> suites = rc::test::accuracySuites(sanitizerScaled(80));
    for (const rc::test::StateSuite &suite : suites)
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend staged(model, poisonedStages(model));
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.padding = 0.01;
            rc::test::expectSameDecisions(staged, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " padded");
            request.padding = 0;
            request.checkSelfCollision = false;
            rc::test::expectSameDecisions(staged, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " no self");
            request.checkSelfCollision = true;
            request.checkEnvironment = false;
            rc::test::expectSameDecisions(staged, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " self only");
        }
    }
}

TEST(StagedPipeline, BatchesOfEverySizeGiveTheSameVerdicts)
{
    const rc::test::StateSuite suite = rc::test::accuracySuites(1)[0];  // the thin plate
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::CpuBackend cpu(model);
    const rc::StagedBackend staged(model, poisonedStages(model));
    const std::vector<rc::test::BlindSpotSuite> blind = rc::test::blindSpotSuites(1000, 7);
    for (std::size_t n : {1u, 7u, 1000u})
    {
        const std::vector<double> states(blind[0].states.begin(), blind[0].states.begin() + 7 * n);
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(staged, cpu, *model, states, request,
                                          label("batch of " + std::to_string(n), mode));
        }
    }
}

TEST(StagedPipeline, ChunksTooSmallForTheBatchGiveIdenticalVerdicts)
{
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(60)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        rc::device::StageBudget fewStates;
        fewStates.maxStates = 5;
        const rc::StagedBackend chunked(model, rc::makeHostStageRunner(model, fewStates));
        // So small that chunks halve down to single states and some single states overflow: their
        // pairs go to the exact phase, which in safe and exact mode is what the CPU does anyway.
        rc::device::StageBudget tiny = fewStates;
        tiny.maxItems = 4000;
        tiny.maxFragments = 2000;
        const rc::StagedBackend overflowing(model, poisonedStages(model, tiny));
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(chunked, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " chunked");
            if (mode != rc::CollisionMode::Raster)
                rc::test::expectSameDecisions(overflowing, cpu, *model, suite.states, request,
                                              label(suite.name, mode) + " overflowing");
        }
    }
}

TEST(StagedPipeline, AScratchLimitSplitsTheBatchWithoutChangingVerdicts)
{
    // What a device with little free memory (or CheckerOptions::deviceMemoryLimit) does: a buffer
    // that would pass the limit abandons the chunk, which is split until its passes fit. 64 KiB
    // cannot hold one pass over 60 Panda states (their link poses alone take 69 KiB).
    rc::device::StageBudget small;
    small.maxScratchBytes = 64 << 10;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(60))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend limited(model, poisonedStages(model, small));
        for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(limited, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " within 64 KiB");
        }
    }
    // A limit that not even one state's pass fits is an error that says so, never a wrong answer.
    const rc::test::StateSuite suite = rc::test::accuracySuites(2)[0];
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    rc::device::StageBudget tiny;
    tiny.maxScratchBytes = 64;
    const rc::StagedBackend starved(model, poisonedStages(model, tiny));
    std::vector<std::uint8_t> valid(2);
    try
    {
        starved.check(suite.states.data(), 2, valid.data(), nullptr, {}, 1);
        ADD_FAILURE() << "a 64-byte scratch limit was not enforced";
    }
    catch (const std::length_error &e)
    {
        EXPECT_NE(std::string(e.what()).find("within the scratch limit of 64 bytes"), std::string::npos) << e.what();
    }
}

TEST(StagedPipeline, AStateTooLargeForOnePassInRasterModeGetsTheExactAnswer)
{
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(60)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        rc::device::StageBudget none;
        none.maxItems = 0;  // no state fits: every one is decided exactly
        const rc::StagedBackend overflowing(model, poisonedStages(model, none));
        rc::CollisionRequest raster, exact;
        raster.mode = rc::CollisionMode::Raster;
        exact.mode = rc::CollisionMode::Exact;
        const std::size_t n = suite.numStates();
        std::vector<std::uint8_t> fromOverflow(n), fromExact(n);
        overflowing.check(suite.states.data(), n, fromOverflow.data(), nullptr, raster, 0);
        cpu.check(suite.states.data(), n, fromExact.data(), nullptr, exact, 0);
        EXPECT_EQ(fromOverflow, fromExact) << suite.name;
    }
}

TEST(StagedPipeline, BadStatesAreInvalidNotErrors)
{
    const rc::test::StateSuite suite = rc::test::accuracySuites(3)[0];
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    std::vector<double> states = suite.states;
    states[0] = std::numeric_limits<double>::quiet_NaN();
    states[7 + 1] = 1e9;  // beyond the bounds
    std::vector<std::uint8_t> valid(3, 1);
    std::vector<rc::Contact> contacts(3);
    staged.check(states.data(), 3, valid.data(), contacts.data(), {}, 1);
    EXPECT_EQ(valid[0], 0);
    EXPECT_EQ(valid[1], 0);
    EXPECT_EQ(contacts[0].kind, rc::Contact::Kind::OutOfBounds);
    EXPECT_EQ(contacts[1].kind, rc::Contact::Kind::OutOfBounds);
}

TEST(StagedPipeline, TheStagesSettleEveryPairAndNeverContradictTheOracle)
{
    // Safe mode leaves the host nothing to decide: the hull proofs, the raster and the exact phase
    // inside the stages settle every pair past the box culls. Every pair they settle must agree
    // with the exact oracle, the CPU backend's decision of that pair. The hull proofs and the raster
    // settle almost every pair; the exact phase takes the few they leave (the raster's misses near
    // contact). A non-convex mesh obstacle goes to it always (test_nonconvex, test_gpu_backend).
    std::size_t checkedSuites = 0;
    unsigned long long exactPairs = 0;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(300))
    {
        ++checkedSuites;
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend oracle(model);
        const std::unique_ptr<rc::StageRunner> runner = poisonedStages(model);
        runner->countStages(true);
        const rc::CollisionRequest request;  // safe mode, no padding
        const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
        std::vector<std::uint8_t> admissible(n);
        for (std::size_t i = 0; i < n; ++i)
            admissible[i] = model->configurationAdmissible(suite.states.data() + i * dof) ? 1 : 0;
        std::vector<rc::device::PairOutcome> outcomes;
        runner->run(suite.states.data(), admissible.data(), n, rc::stageSettings(*model, request, false), outcomes);
        std::unique_ptr<rc::CpuWorkspace> ws = oracle.makeWorkspace();
        std::size_t open = 0;
        for (const rc::device::PairOutcome &o : outcomes)
        {
            if (o.status == rc::device::PairOpen)
            {
                ++open;
                continue;
            }
            oracle.refitState(suite.states.data() + o.state * dof, *ws);
            rc::Contact contact;
            const bool collides = oracle.decideOpenPair(o.pair, request, *ws, contact);
            // The stages see curved primitives as their meshes, which lie outside the exact shapes:
            // a mesh overlap there is confirmed on the shapes by the host (StagedBackend).
            if (o.status == rc::device::PairOverlaps && model->curved.refines(o.pair))
                continue;
            EXPECT_EQ(collides, o.status == rc::device::PairOverlaps)
                << suite.name << ", state " << o.state << ", pair " << o.pair << ", status " << o.status;
        }
        const rc::device::StageCounts counts = runner->counts();
        std::printf(
            "%s: %zu pairs survive the box culls, %llu rasterized, %llu decided by the exact phase in the "
            "stages, %zu left to the host\n",
            suite.name.c_str(), outcomes.size(), counts.rasterizedPairs, counts.exactPairs, open);
        EXPECT_EQ(open, 0u) << suite.name;
        exactPairs += counts.exactPairs;
    }
    ASSERT_GT(checkedSuites, 0u);
    EXPECT_GT(exactPairs, 0u) << "the exact phase never ran in the stages";
}

TEST(StagedPipeline, PerStatePairPaddingsMatchTheCpuBackend)
{
    // Certified midpoints (CertifiedMotionValidator, BatchRRTConnect) give every (state, pair) its own
    // padding; the stages take them in every cull, proof and raster window, and the host's exact
    // phase takes the open pair's own. Chunks of 5 states check that each chunk reads its own rows.
    const std::size_t states = sanitizerScaled(16);
    std::size_t pandaSuites = 0, pandaValid = 0;  // free Panda states: the comparison covers both answers
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(states))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend staged(model, poisonedStages(model));
        rc::device::StageBudget fewStates;
        fewStates.maxStates = 5;
        const rc::StagedBackend chunked(model, poisonedStages(model, fewStates));
        const std::size_t n = suite.numStates();
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.pairPadding = rc::test::randomPairPaddings(*model, n, 7);
            const rc::test::Agreement perState = rc::test::expectSameDecisions(
                staged, cpu, *model, suite.states, request, label(suite.name, mode) + " padding per state");
            if (mode == rc::CollisionMode::Safe)
                rc::test::expectSameDecisions(chunked, cpu, *model, suite.states, request,
                                              label(suite.name, mode) + " padding per state, chunked");
            request.padding = 0.003;
            request.pairPadding = rc::test::randomPairPaddings(*model, 1, 11);
            rc::test::expectSameDecisions(staged, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " one padding row");
            if (mode == rc::CollisionMode::Exact && suite.name.rfind("panda", 0) == 0)
            {
                ++pandaSuites;
                pandaValid += perState.valid;
            }
        }
    }
    if (pandaSuites > 0)
    {
        EXPECT_GT(pandaValid, 0u) << "every Panda state was invalid with its paddings: nothing free was compared";
    }
}

TEST(StagedPipeline, ABatchCostsAFewWaitsAndNoAllocationAfterTheFirst)
{
    // What a small batch pays whatever its size (the GPU's fixed cost per call): the executor
    // counts its launches, waits and allocations on the host, as the CUDA executor does.
    const rc::test::StateSuite suite = rc::test::accuracySuites(32)[0];
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    std::vector<std::uint8_t> valid(32);
    auto call = [&](const rc::CollisionRequest &request)
    {
        const rc::device::ExecutorCounts before = staged.executorCounts();
        staged.check(suite.states.data(), 32, valid.data(), nullptr, request, 1);
        const rc::device::ExecutorCounts after = staged.executorCounts();
        return rc::device::ExecutorCounts{after.chunks - before.chunks, after.launches - before.launches,
                                          after.synchronizations - before.synchronizations,
                                          after.allocations - before.allocations, after.seconds - before.seconds};
    };
    rc::CollisionRequest safe, exact;
    exact.mode = rc::CollisionMode::Exact;
    const rc::device::ExecutorCounts first = call(safe);
    EXPECT_GT(first.allocations, 0u);
    const rc::device::ExecutorCounts again = call(safe);
    EXPECT_EQ(again.chunks, 1u);
    EXPECT_EQ(again.allocations, 0u) << "buffers are kept between calls";
    // The survivors' count, the two scans' totals (triangles, fragments), the count of the outcomes
    // the reduction reads, the outcomes.
    EXPECT_LE(again.synchronizations, 5u);
    EXPECT_LE(again.launches, 30u);
    EXPECT_GT(again.seconds, 0.0);
    call(exact);
    const rc::device::ExecutorCounts exactAgain = call(exact);
    EXPECT_EQ(exactAgain.allocations, 0u);
    EXPECT_LE(exactAgain.synchronizations, 3u) << "nothing to rasterize: no counts to wait for";
    // Stage counts cost a wait per chunk: only when asked.
    EXPECT_EQ(staged.stageCounts().states, 0u);
    staged.countStages(true);
    call(safe);
    EXPECT_EQ(staged.stageCounts().states, 32u);
}

TEST(StagedPipeline, EightThreadsOnOneBackendGetTheVerdictsOfOne)
{
    // Planners call one checker from several threads: each pass takes an executor of its own (on
    // the GPU, a stream and scratch), none waits for another's.
    const rc::test::StateSuite suite = rc::test::accuracySuites(64)[0];
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    const std::size_t n = suite.numStates();
    rc::CollisionRequest request;
    request.pairPadding = rc::test::randomPairPaddings(*model, n, 3);
    std::vector<std::uint8_t> alone(n);
    staged.check(suite.states.data(), n, alone.data(), nullptr, request, 1);
    std::vector<std::vector<std::uint8_t>> verdicts(8, std::vector<std::uint8_t>(n));
    std::vector<std::thread> threads;
    for (int t = 0; t < 8; ++t)
        threads.emplace_back(
            [&, t]
            {
                for (int round = 0; round < 5; ++round)
                    staged.check(suite.states.data(), n, verdicts[t].data(), nullptr, request, 1);
            });
    for (std::thread &thread : threads)
        thread.join();
    for (int t = 0; t < 8; ++t)
        EXPECT_EQ(verdicts[t], alone) << "thread " << t;
}
