// The GPU backend's code path on the CPU: the batched stages (device/BatchPipeline.h) through the
// host executor, with the host's per-state reduction (StagedBackend), must decide every state and
// report every first contact exactly as the CPU backend does. The CUDA backend runs the same driver
// and per-element functions; only the loops, scans, compaction and sort differ. The host's scratch
// buffers are poisoned (HostScratch::Poisoned) as uninitialised device memory may be, except in the
// chunked run, which reuses what earlier chunks left as the CUDA runner does.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>

#include "BackendSuites.h"
#include "BlindSpots.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/PassRecorder.h"
#include "rastercheck/collision/StageChunks.h"
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
    RASTERCHECK_SAMPLE_SCALE), which slow these comparisons 10 to 50 times. */
std::size_t sanitizerScaled(int states)
{
    return static_cast<std::size_t>(rc::test::scaledCount(states, "RASTERCHECK_SAMPLE_SCALE"));
}

/** \brief The stages on the host with poisoned scratch, as uninitialised device memory may be. */
std::unique_ptr<rc::StageRunner> poisonedStages(const rc::CollisionModelConstPtr &model,
                                                const rc::device::StageBudget &budget = {},
                                                rc::HostLoop loop = rc::HostLoop::Parallel)
{
    return rc::makeHostStageRunner(model, budget, rc::HostScratch::Poisoned, loop);
}

/** \brief 1 per state of \a suite within \a model's bounds (what StagedBackend hands the stages). */
std::vector<std::uint8_t> admissibleStates(const rc::CollisionModel &model, const rc::test::StateSuite &suite)
{
    const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
    std::vector<std::uint8_t> admissible(n);
    for (std::size_t i = 0; i < n; ++i)
        admissible[i] = model.configurationAdmissible(suite.states.data() + i * dof) ? 1 : 0;
    return admissible;
}
}  // namespace

TEST(StagedPipeline, SameVerdictsAndFirstContactsAsTheCpuBackendOnTheAccuracySuites)
{
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(200)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend staged(model, poisonedStages(model));
        // Every chunk waits for each count, as large batches do, and takes the proofs in pair order,
        // as the GPU does in large batches (StageBudget).
        rc::device::StageBudget pairOrder;
        pairOrder.waitForCountsFrom = 0;
        pairOrder.orderedProofsFrom = 0;
        const rc::StagedBackend ordered(model, poisonedStages(model, pairOrder));
        // Small chunks whose split walks get fewer parts per pair (walkPartsPerPair), down to one,
        // with the proofs in pair order (past the survivors' count, the order's slots sort last).
        rc::device::StageBudget fewWalkThreads;
        fewWalkThreads.exactWalkThreads = 64;
        fewWalkThreads.orderedProofsFrom = 0;
        const rc::StagedBackend fewParts(model, poisonedStages(model, fewWalkThreads));
        // Each kernel's elements run from the last to the first, as a device may: later parts and
        // pairs find their contacts first, and where no contact is read they stop the earlier ones.
        const rc::StagedBackend backwards(model, poisonedStages(model, {}, rc::HostLoop::Reversed));
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(ordered, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " pair order");
            if (mode == rc::CollisionMode::Safe)  // the default mode: one thread's pass is slow
                rc::test::expectSameDecisions(backwards, cpu, *model, suite.states, request,
                                              label(suite.name, mode) + " backwards");
            rc::test::expectSameDecisions(fewParts, cpu, *model, suite.states, request,
                                          label(suite.name, mode) + " few walk parts");
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

TEST(StagedPipeline, HostCodeNeverReadsTheExecutorsMemory)
{
    // On a GPU the executor's buffers and the model's arrays are the device's: host code that reads
    // them faults, and a download is junk until its wait. HostScratch::Guarded makes the host's
    // memory behave so (pages open only while an operation runs): every mode, the small chunks'
    // path (one wait, guessed bounds, replayed passes) and the large one's (a wait per count), with
    // and without pair paddings per state, with the CPU backend's verdicts and first contacts. A
    // host read of executor memory crashes this test.
    const std::size_t states = sanitizerScaled(12);
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(states))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        rc::device::StageBudget waitForEachCount;
        waitForEachCount.waitForCountsFrom = 0;
        for (const rc::device::StageBudget &budget : {rc::device::StageBudget{}, waitForEachCount})
        {
            const rc::StagedBackend guarded(model, rc::makeHostStageRunner(model, budget, rc::HostScratch::Guarded));
            for (rc::CollisionMode mode : kModes)
            {
                rc::CollisionRequest request;
                request.mode = mode;
                const std::string what =
                    label(suite.name, mode) + (budget.waitForCountsFrom == 0 ? ", a wait per count" : ", one wait");
                for (int call = 0; call < 3; ++call)  // the third replays a small chunk's pass
                    rc::test::expectSameDecisions(guarded, cpu, *model, suite.states, request, what);
                request.pairPadding = rc::test::randomPairPaddings(*model, suite.numStates(), 3);
                rc::test::expectSameDecisions(guarded, cpu, *model, suite.states, request, what + ", pair paddings");
            }
        }
    }
}

TEST(StagedPipeline, SplitWalksKeepTheirThreadsWithinTheBudget)
{
    // Each open pair's walk gets as many parts as keep the pairs past the culls within the threads
    // (StageBudget::exactWalkThreads): a chunk with pairs enough to fill the device splits none.
    using rc::device::walkPartsPerPair;
    EXPECT_EQ(walkPartsPerPair(0, 32, 65536), 32u);
    EXPECT_EQ(walkPartsPerPair(100, 32, 65536), 32u);
    EXPECT_EQ(walkPartsPerPair(2048, 32, 65536), 32u);
    EXPECT_EQ(walkPartsPerPair(10000, 32, 65536), 4u);  // a power of two: parts are paths of bits
    EXPECT_EQ(walkPartsPerPair(40000, 32, 65536), 1u);
    EXPECT_EQ(walkPartsPerPair(100000, 32, 65536), 1u);
    EXPECT_EQ(walkPartsPerPair(10, 1, 65536), 1u);
    EXPECT_EQ(walkPartsPerPair(10, 3, 65536), 2u);
}

TEST(StagedPipeline, TimingEachElementKeepsTheVerdictsAndMeasuresACriticalPath)
{
    // rastercheck_bench_critical_path's runner: each kernel's elements one by one, each timed (a
    // slow one twice). The verdicts and contacts stay the CPU backend's, and the slowest elements'
    // times add up to a critical path within the passes' own time; an untimed runner counts none.
    const std::vector<rc::test::StateSuite> suites = rc::test::accuracySuites(sanitizerScaled(100));
    const rc::test::StateSuite &suite = suites.front();
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::CpuBackend cpu(model);
    const rc::StagedBackend timed(model,
                                  rc::makeHostStageRunner(model, {}, rc::HostScratch::Poisoned, rc::HostLoop::Timed));
    const rc::StagedBackend untimed(model, poisonedStages(model));
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        rc::test::expectSameDecisions(timed, cpu, *model, suite.states, request, label(suite.name, mode) + " timed");
    }
    const rc::device::ExecutorCounts timedCounts = timed.executorCounts();
    EXPECT_GT(timedCounts.criticalPathSeconds, 0.0);
    EXPECT_LT(timedCounts.criticalPathSeconds, timedCounts.seconds);
    // The same states untimed (the accuracy-suite test compares those verdicts): no critical path.
    std::vector<std::uint8_t> valid(suite.numStates());
    untimed.check(suite.states.data(), suite.numStates(), valid.data(), nullptr, rc::CollisionRequest{}, 0);
    EXPECT_GT(untimed.executorCounts().launches, 0u);
    EXPECT_EQ(untimed.executorCounts().criticalPathSeconds, 0.0);
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
        const std::vector<std::uint8_t> admissible = admissibleStates(*model, suite);
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

TEST(StagedPipeline, TheTwoProofKernelsSettleWhatOneFullProofPerPairSettles)
{
    // The stages prove pairs apart or overlapping in two kernels: the whole hulls first, then the
    // full proof (scans, shells, patches) for the pairs the first leaves. In exact mode every pair
    // they leave goes to the exact phase, so that phase must take exactly the pairs past the box
    // culls that one relateSolids per pair leaves Unknown: a second kernel skipped or cut short
    // sends it more.
    std::size_t suites = 0;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(100)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::device::ModelArrays arrays = rc::hostModelArrays(*model);
        const std::unique_ptr<rc::StageRunner> runner = poisonedStages(model);
        runner->countStages(true);
        rc::CollisionRequest request;
        request.mode = rc::CollisionMode::Exact;
        const rc::device::StageSettings settings = rc::stageSettings(*model, request, false);
        ASSERT_FALSE(settings.onlyDecisive) << "every pair past the culls must come back";
        const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
        const std::vector<std::uint8_t> admissible = admissibleStates(*model, suite);
        std::vector<rc::device::PairOutcome> outcomes;
        runner->run(suite.states.data(), admissible.data(), n, settings, outcomes);
        const std::uint32_t m = static_cast<std::uint32_t>(arrays.numComponents);
        const std::uint32_t environmentPairs = static_cast<std::uint32_t>(arrays.numObjects) * m;
        std::vector<double> jointValues(static_cast<std::size_t>(arrays.numJoints) + 1);
        std::vector<rc::device::Pose<double>> links(static_cast<std::size_t>(arrays.numLinks));
        unsigned long long exactPairs = 0;  // what one full proof per pair leaves to the exact phase
        for (const rc::device::PairOutcome &o : outcomes)
        {
            const bool meshObstacle = settings.meshObstaclesUnproven && o.pair < environmentPairs &&
                                      rc::device::hasPatches(arrays.convex, m + o.pair / m);
            rc::device::linkPoses(arrays.joints, arrays.numJoints, suite.states.data() + o.state * dof,
                                  jointValues.data(), links.data());
            const rc::device::HullRelation relation =
                meshObstacle ? rc::device::HullRelation::Unknown
                             : rc::device::pairHullRelation(arrays, o.pair, links.data(), settings.padding,
                                                            settings.proveOverlaps, rc::device::FullProof{});
            // An overlap of curved primitives' meshes is decided again on the exact shapes.
            const bool curved = settings.confirmCurvedOverlaps && o.pair < arrays.numCurvedPairFlags &&
                                arrays.curvedPairs[o.pair];
            if (relation == rc::device::HullRelation::Unknown ||
                (curved && relation == rc::device::HullRelation::Overlapping))
                ++exactPairs;
        }
        ++suites;
        EXPECT_EQ(runner->counts().exactPairs, exactPairs) << suite.name << ": " << outcomes.size() << " pairs past the culls";
    }
    EXPECT_GT(suites, 0u);
}

TEST(StagedPipeline, ThePairCullDropsTheSelfPairsTheClearanceTablesProveApart)
{
    // Safe and exact mode: a self pair that its joint-space clearance table proves apart skips the
    // proofs in the stages, as it does in the CPU backend's self-pair loop (SelfPairTables). Exact
    // mode returns every pair past the culls: with the tables, none of those the tables prove apart
    // (at the request's padding); without, exactly those more.
    std::size_t provenApart = 0;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(100)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        if (model->selfPairTables.numTables() == 0)
            continue;
        rc::CollisionRequest request;
        request.mode = rc::CollisionMode::Exact;
        request.padding = 0.002;
        rc::device::StageSettings settings = rc::stageSettings(*model, request, false);
        ASSERT_TRUE(settings.clearanceTables) << "exact mode reads the tables";
        const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
        const std::vector<std::uint8_t> admissible = admissibleStates(*model, suite);
        const std::uint32_t environmentPairs = static_cast<std::uint32_t>(model->numObjects() * model->numComponents());
        // The (state, pair) outcomes of self pairs the tables prove apart, and all outcomes.
        const auto run = [&](bool tables, std::size_t &tableApart)
        {
            settings.clearanceTables = tables;
            std::vector<rc::device::PairOutcome> outcomes;
            poisonedStages(model)->run(suite.states.data(), admissible.data(), n, settings, outcomes);
            tableApart = 0;
            for (const rc::device::PairOutcome &o : outcomes)
                if (o.pair >= environmentPairs &&
                    model->selfPairTables.apart(o.pair - environmentPairs, suite.states.data() + o.state * dof,
                                                request.padding))
                    ++tableApart;
            return outcomes.size();
        };
        std::size_t withTables = 0, withoutTables = 0;
        const std::size_t pastWith = run(true, withTables), pastWithout = run(false, withoutTables);
        EXPECT_EQ(withTables, 0u) << suite.name << ": pairs the tables prove apart went past the cull";
        EXPECT_EQ(pastWithout - pastWith, withoutTables) << suite.name;
        std::printf("%s: %zu pairs past the box culls, %zu of them self pairs the tables prove apart\n",
                    suite.name.c_str(), pastWithout, withoutTables);
        provenApart += withoutTables;
    }
    EXPECT_GT(provenApart, 0u) << "no suite has a self pair past the box culls that its table proves apart";
}

TEST(StagedPipeline, ThePairCullKeepsExactlyThePairsWhoseOwnBoxesMeet)
{
    // The cull takes an object's pairs with the robot in one thread, behind one test of the robot's
    // bounds at the largest of their paddings: it must keep exactly the pairs whose own boxes meet
    // at their own padding (and, for self pairs, that no clearance table proves apart), every
    // suite, paddings per (state, pair) among them. Exact mode returns every pair past the cull.
    std::size_t suites = 0, outOfReach = 0;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(100)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::device::ModelArrays md = rc::hostModelArrays(*model);
        const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
        rc::CollisionRequest request;
        request.mode = rc::CollisionMode::Exact;
        request.padding = 0.001;
        request.pairPadding = rc::test::randomPairPaddings(*model, n, 5);
        const rc::device::StageSettings settings = rc::stageSettings(*model, request, false);
        const std::vector<std::uint8_t> admissible = admissibleStates(*model, suite);
        std::vector<rc::device::PairOutcome> outcomes;
        poisonedStages(model)->run(suite.states.data(), admissible.data(), n, settings, outcomes);

        const std::uint32_t m = static_cast<std::uint32_t>(md.numComponents);
        const std::uint32_t environmentPairs = static_cast<std::uint32_t>(md.numObjects) * m;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> expected;  // (state, pair), in that order
        std::vector<double> jointValues(static_cast<std::size_t>(md.numJoints) + 1);
        std::vector<rc::device::Pose<double>> links(static_cast<std::size_t>(md.numLinks));
        std::vector<rc::device::OrientedBox> boxes(m);
        std::vector<rc::device::Box> bounds(m);
        for (std::uint32_t s = 0; s < n; ++s)
        {
            if (!admissible[s])
                continue;
            const double *q = suite.states.data() + static_cast<std::size_t>(s) * dof;
            rc::device::linkPoses(md.joints, md.numJoints, q, jointValues.data(), links.data());
            for (std::uint32_t c = 0; c < m; ++c)
            {
                boxes[c] = rc::device::transformBox(rc::device::toFloatPose(links[md.componentLink[c]], md.origin),
                                                    md.componentLocalBoxes[c]);
                bounds[c] = rc::device::boundsOf(boxes[c]);
            }
            for (std::uint32_t pair = 0; pair < md.numPairs(); ++pair)
            {
                const float padding = rc::device::floatPadding(rc::device::pairPadding(md, settings, s, pair));
                bool meet;
                if (pair < environmentPairs)
                {
                    const std::uint32_t o = pair / m, k = pair % m;
                    meet = rc::device::solidsMayMeet(bounds[k], boxes[k], md.objectBoxes[o], md.objectOrientedBoxes[o],
                                                     padding);
                }
                else
                {
                    const std::uint32_t p = pair - environmentPairs;
                    const int a = md.selfPairs[2 * p], b = md.selfPairs[2 * p + 1];
                    meet = rc::device::solidsMayMeet(bounds[a], boxes[a], bounds[b], boxes[b], padding) &&
                           !model->selfPairTables.apart(p, q, rc::device::pairPadding(md, settings, s, pair));
                }
                if (meet)
                    expected.emplace_back(s, pair);
            }
            // Objects whose pairs all fail: what the robot's reach lets the cull skip at once.
            for (std::uint32_t o = 0; o < static_cast<std::uint32_t>(md.numObjects); ++o)
            {
                bool any = false;
                for (std::uint32_t k = 0; k < m && !any; ++k)
                    any = rc::device::boxesOverlap(bounds[k], md.objectBoxes[o], 0.06f);
                outOfReach += any ? 0 : 1;
            }
        }
        std::vector<std::pair<std::uint32_t, std::uint32_t>> kept;
        for (const rc::device::PairOutcome &o : outcomes)
            kept.emplace_back(o.state, o.pair);
        EXPECT_EQ(kept, expected) << suite.name;
        ++suites;
    }
    EXPECT_GT(suites, 0u);
    EXPECT_GT(outOfReach, 0u) << "no object was out of every component's reach: the robot's test skipped nothing";
}

TEST(StagedPipeline, OnlyAStatesPairsUpToItsFirstOverlapAreDecided)
{
    // The reduction reads each state's pairs up to its first overlap (StageSettings::onlyDecisive),
    // and the stages skip the pairs behind an overlap they have found (pastFirstOverlap): the
    // outcomes must be exactly those of deciding every pair, cut at each state's first overlap
    // (none settled apart), with the same statuses and first contacts, and the exact phase must
    // decide fewer pairs (the crane in the plant: a state's pairs with the plant often reach it
    // together).
    // The same with each kernel's elements run from the last to the first (HostLoop::Reversed): a
    // device keeps no order among its threads. Where no contact is read (StageSettings::
    // firstContacts false) any overlap settles a state: a colliding state's one outcome is an
    // overlap of one of its pairs that overlap, the others' outcomes are the same, and, run
    // backwards, the exact phase decides fewer pairs (a later pair's overlap stops the earlier
    // ones, as on a device where they run at once).
    unsigned long long exactAll = 0, exactDecisive = 0, exactReversed = 0, exactAnyContact = 0;
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(sanitizerScaled(100)))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const std::size_t n = suite.numStates();
        const std::vector<std::uint8_t> admissible = admissibleStates(*model, suite);
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::device::StageSettings settings = rc::stageSettings(*model, request, true);
            const auto run = [&](bool onlyDecisive, unsigned long long &exactPairs, bool firstContacts = true,
                                 rc::HostLoop loop = rc::HostLoop::Parallel)
            {
                settings.onlyDecisive = onlyDecisive;
                settings.firstContacts = firstContacts;
                const std::unique_ptr<rc::StageRunner> runner = poisonedStages(model, {}, loop);
                runner->countStages(true);
                std::vector<rc::device::PairOutcome> outcomes;
                runner->run(suite.states.data(), admissible.data(), n, settings, outcomes);
                exactPairs += runner->counts().exactPairs;
                return outcomes;
            };
            const std::vector<rc::device::PairOutcome> all = run(false, exactAll);
            const std::vector<rc::device::PairOutcome> decisive = run(true, exactDecisive);
            std::vector<rc::device::PairOutcome> expected;
            std::uint32_t settledState = ~0u;  // the last state whose first overlap was passed
            for (const rc::device::PairOutcome &o : all)
            {
                if (o.state == settledState || o.status == rc::device::PairApart)
                    continue;
                expected.push_back(o);
                if (o.status == rc::device::PairOverlaps)
                    settledState = o.state;
            }
            const std::vector<rc::device::PairOutcome> reversed =
                run(true, exactReversed, true, rc::HostLoop::Reversed);
            for (const std::vector<rc::device::PairOutcome> *outcomes : {&decisive, &reversed})
            {
                const std::string how = outcomes == &decisive ? "" : ", reversed";
                ASSERT_EQ(outcomes->size(), expected.size()) << label(suite.name, mode) << how;
                for (std::size_t i = 0; i < expected.size(); ++i)
                {
                    const rc::device::PairOutcome &a = (*outcomes)[i], &b = expected[i];
                    EXPECT_TRUE(a.state == b.state && a.pair == b.pair && a.status == b.status &&
                                a.triangle == b.triangle && a.position[0] == b.position[0] &&
                                a.position[1] == b.position[1] && a.position[2] == b.position[2])
                        << label(suite.name, mode) << how << ": outcome " << i << ", state " << b.state << ", pair "
                        << b.pair;
                }
            }

            const std::vector<rc::device::PairOutcome> anyContact =
                run(true, exactAnyContact, false, rc::HostLoop::Reversed);
            std::map<std::uint32_t, std::set<std::uint32_t>> overlapping;  // per state, of every pair decided
            for (const rc::device::PairOutcome &o : all)
                if (o.status == rc::device::PairOverlaps)
                    overlapping[o.state].insert(o.pair);
            // The expected outcomes in order, but for a colliding state one overlap of any of its
            // overlapping pairs in place of its pairs up to the first.
            std::size_t next = 0;
            for (const rc::device::PairOutcome &o : expected)
            {
                const auto found = overlapping.find(o.state);
                const bool colliding = found != overlapping.end();
                if (colliding && o.status != rc::device::PairOverlaps)
                    continue;  // a pair before the state's first overlap: need not come back
                ASSERT_LT(next, anyContact.size()) << label(suite.name, mode) << ": state " << o.state;
                const rc::device::PairOutcome &a = anyContact[next++];
                EXPECT_EQ(a.state, o.state) << label(suite.name, mode);
                EXPECT_EQ(a.status, o.status) << label(suite.name, mode) << ": state " << o.state;
                if (colliding)
                    EXPECT_EQ(found->second.count(a.pair), 1u)
                        << label(suite.name, mode) << ": state " << o.state << ", pair " << a.pair;
                else
                    EXPECT_EQ(a.pair, o.pair) << label(suite.name, mode) << ": state " << o.state;
            }
            EXPECT_EQ(next, anyContact.size()) << label(suite.name, mode);
        }
    }
    std::printf(
        "the exact phase decided %llu pairs, %llu with only the pairs up to a state's first overlap (%llu "
        "run backwards, %llu where any overlap decides)\n",
        exactAll, exactDecisive, exactReversed, exactAnyContact);
    EXPECT_LT(exactDecisive, exactAll);
    EXPECT_LT(exactAnyContact, exactReversed);
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

TEST(StagedPipeline, TwoPaddingsInOnePassGiveTheCpuBackendsVerdicts)
{
    // Certified midpoints' check at two paddings (Checker::checkTwoPaddings): the stages decide each
    // state at the wider paddings and again at the request's in one pass of twice the states, with
    // the verdicts of the CPU backend's one pass, every mode, with and without the request's own
    // pair paddings per state; a batch above kTwoPaddingsInOnePassMost is left to the Checker.
    const std::size_t states = sanitizerScaled(24);
    std::size_t kinds[3] = {0, 0, 0};
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(states))
    {
        const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
        const rc::CpuBackend cpu(model);
        const rc::StagedBackend staged(model, poisonedStages(model));
        const std::size_t n = suite.numStates();
        const std::shared_ptr<rc::PairPadding> wider = rc::test::randomPairPaddings(*model, n, 5);
        for (rc::CollisionMode mode : kModes)
            for (const bool ownPairPaddings : {false, true})
            {
                rc::CollisionRequest request;
                request.mode = mode;
                request.padding = 0.002;
                if (ownPairPaddings)
                    request.pairPadding = rc::test::randomPairPaddings(*model, n, 9);
                std::vector<std::uint8_t> onStages(n), expected(n);
                if (!cpu.checkTwoPaddings(suite.states.data(), n, expected.data(), request, *wider, 1))
                {
                    // Raster mode on the CPU: what the Checker's two checks say.
                    const rc::Checker checker(suite.robot, suite.scene, rc::CheckerOptions{rc::BackendChoice::Cpu, 1});
                    checker.checkTwoPaddings(suite.states.data(), n, expected.data(), request, *wider);
                }
                const rc::device::ExecutorCounts before = staged.executorCounts();
                ASSERT_TRUE(staged.checkTwoPaddings(suite.states.data(), n, onStages.data(), request, *wider, 1));
                EXPECT_EQ(staged.executorCounts().since(before).calls, 1u) << label(suite.name, mode);
                for (std::size_t i = 0; i < n; ++i)
                {
                    EXPECT_EQ(onStages[i], expected[i])
                        << label(suite.name, mode) << (ownPairPaddings ? ", own pair paddings" : "") << ", state " << i;
                    ++kinds[onStages[i] < 3 ? onStages[i] : 0];
                }
            }
    }
    // Every verdict occurs, or the comparison above proves little.
    EXPECT_GT(kinds[0], 50u);
    EXPECT_GT(kinds[1], 50u);
    EXPECT_GT(kinds[2], 50u);

    const rc::test::StateSuite suite = rc::test::accuracySuites(1).front();
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    const std::size_t n = rc::StagedBackend::kTwoPaddingsInOnePassMost + 1;
    const std::vector<double> q(n * suite.robot->numCoordinates(), 0.0);
    std::vector<std::uint8_t> verdicts(n);
    rc::PairPadding wider;
    wider.environment.assign(model->numComponents(), 0.01);
    wider.self.assign(model->selfPairs.size(), 0.01);
    EXPECT_FALSE(staged.checkTwoPaddings(q.data(), n, verdicts.data(), {}, wider, 1));
}

namespace
{
/** \brief The suite called \a name, with \a states states. */
rc::test::StateSuite suiteNamed(const std::string &name, std::size_t states)
{
    for (rc::test::StateSuite &suite : rc::test::accuracySuites(states))
        if (suite.name == name)
            return suite;
    throw std::runtime_error("no accuracy suite " + name);
}

/** \brief What one call of \a backend cost its executor. */
rc::device::ExecutorCounts oneCall(const rc::StagedBackend &backend, const rc::test::StateSuite &suite,
                                   const rc::CollisionRequest &request, std::vector<std::uint8_t> &valid)
{
    const std::size_t n = suite.numStates();
    valid.resize(n);
    const rc::device::ExecutorCounts before = backend.executorCounts();
    backend.check(suite.states.data(), n, valid.data(), nullptr, request, 1);
    return backend.executorCounts().since(before);
}

/** \brief The CPU backend's verdicts on \a suite. */
std::vector<std::uint8_t> cpuVerdicts(const rc::CollisionModelConstPtr &model, const rc::test::StateSuite &suite,
                                      const rc::CollisionRequest &request)
{
    std::vector<std::uint8_t> valid(suite.numStates());
    rc::CpuBackend(model).check(suite.states.data(), valid.size(), valid.data(), nullptr, request, 1);
    return valid;
}
}  // namespace

TEST(StagedPipeline, ASmallBatchWaitsOnceAndAllocatesNothingAfterTheFirst)
{
    // What a planner's batch pays whatever its size (the GPU's fixed cost per call): the executor
    // counts launches, waits and allocations on the host where the CUDA executor makes them. A
    // small batch keeps its counts on the executor and sizes its buffers by bounds and by what the
    // executor's earlier batches needed, so that after the first call one like it allocates
    // nothing and waits once, for its outcomes (StageBudget::waitForCountsFrom).
    const rc::test::StateSuite suite = suiteNamed("thin plate at 1e6 m", 32);  // rasterizes in safe mode
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    std::vector<std::uint8_t> valid;
    rc::CollisionRequest safe, exact;
    exact.mode = rc::CollisionMode::Exact;

    const rc::device::ExecutorCounts first = oneCall(staged, suite, safe, valid);
    EXPECT_GT(first.allocations, 0u);
    EXPECT_EQ(first.reruns, 0u);
    // The first rasterizing call waits for its candidate triangles and fragments, to size them from
    // then on, and for its outcomes.
    EXPECT_EQ(first.synchronizations, 3u);
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));
    for (int call = 0; call < 3; ++call)
    {
        const rc::device::ExecutorCounts again = oneCall(staged, suite, safe, valid);
        EXPECT_EQ(again.calls, 1u);
        EXPECT_EQ(again.chunks, 1u);
        EXPECT_EQ(again.allocations, 0u) << "call " << call << ": buffers are kept between calls";
        EXPECT_EQ(again.synchronizations, 1u) << "call " << call << ": the counts stay on the executor";
        EXPECT_EQ(again.reruns, 0u);
        EXPECT_EQ(again.launches, first.launches) << "the same kernels as the first call";
        EXPECT_LE(again.launches, 30u);
        EXPECT_GT(again.seconds, 0.0);
        EXPECT_EQ(valid, cpuVerdicts(model, suite, safe)) << "call " << call;
    }

    // Exact mode rasterizes nothing: one wait from its first call on, in the buffers safe mode grew.
    for (int call = 0; call < 2; ++call)
    {
        const rc::device::ExecutorCounts counts = oneCall(staged, suite, exact, valid);
        EXPECT_EQ(counts.allocations, 0u);
        EXPECT_EQ(counts.synchronizations, 1u);
        EXPECT_EQ(valid, cpuVerdicts(model, suite, exact));
    }

    // Stage counts ride with the outcomes (two more compactions, no wait), only when asked.
    EXPECT_EQ(staged.stageCounts().states, 0u);
    staged.countStages(true);
    oneCall(staged, suite, safe, valid);
    const rc::device::ExecutorCounts counted = oneCall(staged, suite, safe, valid);
    EXPECT_EQ(counted.synchronizations, 1u);
    EXPECT_EQ(counted.allocations, 0u);
    EXPECT_EQ(counted.launches, first.launches + 2);
    const rc::device::StageCounts stages = staged.stageCounts();
    EXPECT_EQ(stages.states, 64u);
    EXPECT_GT(stages.candidateTriangles, 0u) << "the batch must rasterize for this test to measure the raster's counts";
    EXPECT_GT(stages.fragments, 0u);
}

TEST(StageChunks, CopyInParallelCopiesEveryByteAtEverySize)
{
    // Below, at and past the size where the copy is split over threads, an odd size whose last piece
    // is short, and inside another parallel region (where it runs on one thread).
    constexpr std::size_t kSplitFrom = std::size_t(1) << 20;
    for (const std::size_t bytes :
         {std::size_t(0), std::size_t(1), kSplitFrom - 1, kSplitFrom, kSplitFrom + 1, std::size_t(3670019)})
        for (const bool nested : {false, true})
        {
            std::vector<unsigned char> from(bytes), to(bytes + 1, 0xAB);
            for (std::size_t i = 0; i < bytes; ++i)
                from[i] = static_cast<unsigned char>((i * 2654435761u) >> 13);
            if (nested)
            {
#pragma omp parallel num_threads(2)
                {
#pragma omp single
                    rc::copyInParallel(to.data(), from.data(), bytes);
                }
            }
            else
                rc::copyInParallel(to.data(), from.data(), bytes);
            EXPECT_TRUE(std::equal(from.begin(), from.end(), to.begin())) << bytes << " bytes, nested " << nested;
            EXPECT_EQ(to[bytes], 0xAB) << "wrote past the end: " << bytes << " bytes";
        }
}

TEST(PassRecorder, IssuesInOrderRemembersSixteenPassesAndComparesValuesNotPadding)
{
    struct Compiled
    {
        int pass;
    };
    using Recorder = rc::PassRecorder<Compiled>;
    using Issued = Recorder::Issued;
    Recorder recorder;
    std::vector<int> ran;
    const auto pass = [&](int tag)
    {
        recorder.begin();
        const std::size_t before = ran.size();
        for (int k = 0; k < 3; ++k)
            recorder.issue([&ran, tag, k] { ran.push_back(10 * tag + k); }, tag, k);
        EXPECT_EQ(ran.size(), before) << "recorded operations wait for finish()";
        return recorder.finish(
            [&](std::vector<Recorder::Operation> &operations)
            {
                Recorder::issueAll(operations);
                return Compiled{tag};
            },
            [&](Compiled &compiled, std::vector<Recorder::Operation> &) { ran.push_back(-compiled.pass); });
    };
    EXPECT_EQ(pass(1), Issued::AsRecorded);
    EXPECT_EQ(ran, (std::vector<int>{10, 11, 12}));
    ran.clear();
    EXPECT_EQ(pass(1), Issued::CompiledNow);
    EXPECT_EQ(ran, (std::vector<int>{10, 11, 12}));
    ran.clear();
    EXPECT_EQ(pass(1), Issued::Replayed);
    EXPECT_EQ(ran, (std::vector<int>{-1})) << "a replay issues the compiled pass, not the operations";
    ran.clear();

    // Sixteen others push the least recently used one out.
    for (int tag = 2; tag <= 17; ++tag)
        EXPECT_EQ(pass(tag), Issued::AsRecorded);
    ran.clear();
    EXPECT_EQ(pass(1), Issued::AsRecorded) << "forgotten";
    EXPECT_EQ(pass(17), Issued::CompiledNow) << "kept";

    // An interrupted recording issues what it holds, in order, and then everything at once.
    ran.clear();
    recorder.begin();
    recorder.issue([&ran] { ran.push_back(1); }, 1);
    recorder.issue([&ran] { ran.push_back(2); }, 2);
    recorder.interrupt();
    EXPECT_EQ(ran, (std::vector<int>{1, 2}));
    recorder.issue([&ran] { ran.push_back(3); }, 3);
    EXPECT_EQ(ran, (std::vector<int>{1, 2, 3}));
    EXPECT_FALSE(recorder.recording());
    // A discarded one issues nothing.
    recorder.begin();
    recorder.issue([&ran] { ran.push_back(4); }, 4);
    recorder.discard();
    EXPECT_EQ(ran.size(), 3u);

#if defined(__has_builtin)
#if __has_builtin(__builtin_clear_padding)
    // Values that differ only in their padding have one signature.
    struct Padded
    {
        char c;
        double d;
    };
    Padded a, b;
    std::memset(static_cast<void *>(&a), 0x11, sizeof a);
    std::memset(static_cast<void *>(&b), 0x22, sizeof b);
    a.c = b.c = 'x';
    a.d = b.d = 2.5;
    const auto padded = [&](const Padded &value)
    {
        recorder.begin();
        recorder.issue([] {}, value);
        return recorder.finish([](std::vector<Recorder::Operation> &) { return Compiled{0}; },
                               [](Compiled &, std::vector<Recorder::Operation> &) {});
    };
    EXPECT_EQ(padded(a), Issued::AsRecorded);
    EXPECT_EQ(padded(b), Issued::CompiledNow);
    b.d = 3.5;
    EXPECT_EQ(padded(b), Issued::AsRecorded) << "a value that differs is another pass";
#endif
#endif
}

TEST(StagedPipeline, ABatchSeenTwiceIsReplayedFromItsThirdCallWithTheNewStatesVerdicts)
{
    // A small chunk with its counts guessed issues everything before its one wait without reading
    // anything back, so the executor records it (PassRecorder): a pass that issues exactly what an
    // earlier one did is compiled the second time (on a GPU captured as a CUDA graph) and replayed
    // from the third on (one graph launch). The states and paddings are data the pass uploads, not
    // what it issues: new states of the same count replay, with their own verdicts.
    const rc::test::StateSuite suite = suiteNamed("thin plate at 1e6 m", 32);  // rasterizes in safe mode
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::StagedBackend staged(model, poisonedStages(model));
    std::vector<std::uint8_t> valid;
    const rc::CollisionRequest safe;

    const rc::device::ExecutorCounts first = oneCall(staged, suite, safe, valid);
    EXPECT_EQ(first.compiledPasses + first.replayedPasses, 0u) << "the first call measures its counts";
    const rc::device::ExecutorCounts second = oneCall(staged, suite, safe, valid);
    EXPECT_EQ(second.compiledPasses + second.replayedPasses, 0u) << "seen for the first time";
    const rc::device::ExecutorCounts third = oneCall(staged, suite, safe, valid);
    EXPECT_EQ(third.compiledPasses, 1u);
    EXPECT_EQ(third.replayedPasses, 0u);
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));

    // The same count of other states: the suite's rows reversed.
    rc::test::StateSuite reversed = suite;
    const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
    for (std::size_t i = 0; i < n; ++i)
        std::copy_n(suite.states.begin() + static_cast<std::ptrdiff_t>((n - 1 - i) * dof), dof,
                    reversed.states.begin() + static_cast<std::ptrdiff_t>(i * dof));
    const std::vector<std::uint8_t> expected = cpuVerdicts(model, reversed, safe);
    ASSERT_NE(expected, cpuVerdicts(model, suite, safe)) << "the reversed states must have other verdicts";
    for (int call = 0; call < 2; ++call)
    {
        const rc::device::ExecutorCounts again = oneCall(staged, call == 0 ? reversed : suite, safe, valid);
        EXPECT_EQ(again.replayedPasses, 1u) << "call " << call;
        EXPECT_EQ(again.compiledPasses, 0u);
        EXPECT_EQ(again.synchronizations, 1u);
        EXPECT_EQ(again.launches, third.launches) << "a replay issues what the pass issued";
        EXPECT_EQ(valid, call == 0 ? expected : cpuVerdicts(model, suite, safe)) << "call " << call;
    }

    // Another count is another pass: recorded, not replayed; the first one's is kept.
    const rc::test::StateSuite fewer = suiteNamed("thin plate at 1e6 m", 31);
    const rc::device::ExecutorCounts other = oneCall(staged, fewer, safe, valid);
    EXPECT_EQ(other.compiledPasses + other.replayedPasses, 0u);
    EXPECT_EQ(valid, cpuVerdicts(model, fewer, safe));
    EXPECT_EQ(oneCall(staged, suite, safe, valid).replayedPasses, 1u);
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));

    // Another request (a padding) issues other kernel arguments: a pass of its own.
    rc::CollisionRequest padded;
    padded.padding = 0.01;
    for (int call = 0; call < 3; ++call)
    {
        const rc::device::ExecutorCounts counts = oneCall(staged, suite, padded, valid);
        EXPECT_EQ(counts.replayedPasses, call == 2 ? 1u : 0u) << "call " << call;
        EXPECT_EQ(valid, cpuVerdicts(model, suite, padded)) << "call " << call;
    }
}

namespace
{
/** \brief \a count of \a suite's states, those from \a first on in the order of what each needs
    of a stage count (\a what: StageCounts::survivingPairs, candidateTriangles, ...), checked one by
    one in \a request's mode; \a total is what the batch's states needed together. */
rc::test::StateSuite statesByStageCount(const rc::CollisionModelConstPtr &model, const rc::test::StateSuite &suite,
                                        const rc::CollisionRequest &request,
                                        unsigned long long rc::device::StageCounts::*what, std::size_t first,
                                        std::size_t count, unsigned long long &total)
{
    const std::size_t n = suite.numStates(), dof = suite.robot->numCoordinates();
    std::vector<std::pair<unsigned long long, std::size_t>> needs;  // (count, state)
    const rc::StagedBackend counting(model, poisonedStages(model));
    counting.countStages(true);
    std::uint8_t valid = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
        const unsigned long long before = counting.stageCounts().*what;
        counting.check(suite.states.data() + i * dof, 1, &valid, nullptr, request, 1);
        needs.emplace_back(counting.stageCounts().*what - before, i);
    }
    std::sort(needs.begin(), needs.end());
    rc::test::StateSuite batch = suite;
    batch.states.clear();
    total = 0;
    for (std::size_t k = first; k < first + count; ++k)
    {
        total += needs[k].first;
        const auto row = suite.states.begin() + static_cast<std::ptrdiff_t>(needs[k].second * dof);
        batch.states.insert(batch.states.end(), row, row + static_cast<std::ptrdiff_t>(dof));
    }
    return batch;
}

/** \brief A call of \a suite that the executor's earlier calls sized: one wait, nothing run again or
    allocated, the CPU backend's verdicts. */
void expectOneWaitAndTheCpuVerdicts(const rc::StagedBackend &staged, const rc::CollisionModelConstPtr &model,
                                    const rc::test::StateSuite &suite, const rc::CollisionRequest &request)
{
    std::vector<std::uint8_t> valid;
    const rc::device::ExecutorCounts counts = oneCall(staged, suite, request, valid);
    EXPECT_EQ(counts.reruns, 0u);
    EXPECT_EQ(counts.synchronizations, 1u);
    EXPECT_EQ(counts.allocations, 0u);
    EXPECT_EQ(valid, cpuVerdicts(model, suite, request));
}

/** \brief \a few, then \a many, which needs more than \a few did: \a many runs again once, with
    \a grownWaits waits and the CPU backend's verdicts, then waits once and allocates nothing, and
    \a few fits what \a many needed. */
void expectTheLargerNeedRunsAgainOnce(const rc::StagedBackend &staged, const rc::CollisionModelConstPtr &model,
                                      const rc::test::StateSuite &few, const rc::test::StateSuite &many,
                                      const rc::CollisionRequest &request, unsigned long long grownWaits)
{
    std::vector<std::uint8_t> valid;
    EXPECT_EQ(oneCall(staged, few, request, valid).reruns, 0u) << "the first chunk waits for what it needs";
    EXPECT_EQ(valid, cpuVerdicts(model, few, request));
    const rc::device::ExecutorCounts grown = oneCall(staged, many, request, valid);
    EXPECT_EQ(grown.reruns, 1u);
    EXPECT_EQ(grown.synchronizations, grownWaits);
    EXPECT_EQ(valid, cpuVerdicts(model, many, request));
    expectOneWaitAndTheCpuVerdicts(staged, model, many, request);
    expectOneWaitAndTheCpuVerdicts(staged, model, few, request);
}
}  // namespace

TEST(StagedPipeline, GuessedBoundsRoundUpByAtMostAQuarterToFiveValuesPerPowerOfTwo)
{
    // A guess that creeps up from batch to batch must change a small chunk's bounds (its buffers,
    // its pass's signature) only now and then: bounds round up by at most a quarter, to multiples
    // of a quarter of their power of two (five values from 2^k to 2^(k+1)), and never pass their
    // limit.
    for (int k = 3; k < 20; ++k)
    {
        std::set<std::size_t> values;
        for (std::size_t n = std::size_t(1) << k; n < std::size_t(2) << k; ++n)
        {
            const std::size_t bound = rc::device::coarseBound(static_cast<double>(n), std::size_t(1) << 30);
            ASSERT_GE(bound, n);
            ASSERT_LE(4 * bound, 5 * n) << n;
            values.insert(bound);
        }
        EXPECT_LE(values.size(), 5u) << "between 2^" << k << " and 2^" << k + 1 << " (2^" << k + 1 << " included)";
    }
    for (std::size_t n = 0; n < 8; ++n)
        EXPECT_EQ(rc::device::coarseBound(static_cast<double>(n), 100), n);
    EXPECT_EQ(rc::device::coarseBound(7.2, 100), 8u);
    EXPECT_EQ(rc::device::coarseBound(1000.0, 900), 900u);
    EXPECT_EQ(rc::device::coarseBound(std::nan(""), 900), 900u);
}

TEST(StagedPipeline, ABatchThatRasterizesMorePerStateRunsAgainOnceThenWaitsOnce)
{
    // A small chunk sizes its candidate triangles and fragments by the most an earlier chunk needed
    // or as many per state as the most per state one needed, half again (CountGuess): a batch
    // whose states rasterize more outgrows them; nothing runs past them, and the chunk runs again,
    // waiting for those counts. The verdicts never change.
    const rc::test::StateSuite suite = suiteNamed("thin plate at 1e6 m", 96);
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const rc::CollisionRequest safe;
    const auto triangles = &rc::device::StageCounts::candidateTriangles;
    unsigned long long fewTriangles = 0, manyTriangles = 0;
    const rc::test::StateSuite few = statesByStageCount(model, suite, safe, triangles, 0, 16, fewTriangles);
    const rc::test::StateSuite many = statesByStageCount(model, suite, safe, triangles, 80, 16, manyTriangles);
    ASSERT_GT(manyTriangles, 2 * fewTriangles + 16) << "the second batch must need more than the guess";

    const rc::StagedBackend staged(model, poisonedStages(model));
    // The outgrown pass's wait, then the triangles', fragments' and outcomes'.
    expectTheLargerNeedRunsAgainOnce(staged, model, few, many, safe, 4);
    // A batch of both fits: as many per state.
    std::vector<std::uint8_t> valid;
    rc::test::StateSuite both = many;
    both.states.insert(both.states.end(), few.states.begin(), few.states.end());
    both.states.insert(both.states.end(), many.states.begin(), many.states.end());
    const rc::device::ExecutorCounts larger = oneCall(staged, both, safe, valid);
    EXPECT_EQ(larger.reruns, 0u) << "48 states that need at most twice what 16 of them needed per state";
    EXPECT_EQ(larger.synchronizations, 1u);
    EXPECT_EQ(valid, cpuVerdicts(model, both, safe));
}

TEST(StagedPipeline, ABatchWithMorePairsPastTheCullsPerStateRunsAgainOnceThenWaitsOnce)
{
    // A small chunk sizes its launches past the culls by the pairs per state its executor's
    // earlier small chunks needed, half again (CountGuesses::survivorsPerState; the first chunk by
    // every pair): a batch with more of them runs nothing past the bound and runs again, sized by
    // what it needed. Exact mode, so that no raster count is guessed. The crane's states, split by
    // the pairs past their culls: few, then many.
    const rc::test::StateSuite suite = suiteNamed("crane in the plant", 96);
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    rc::CollisionRequest exact;
    exact.mode = rc::CollisionMode::Exact;
    const auto pairs = &rc::device::StageCounts::survivingPairs;
    unsigned long long fewPairs = 0, manyPairs = 0;
    const rc::test::StateSuite few = statesByStageCount(model, suite, exact, pairs, 0, 16, fewPairs);
    const rc::test::StateSuite many = statesByStageCount(model, suite, exact, pairs, 80, 16, manyPairs);
    ASSERT_GT(manyPairs, 2 * fewPairs + 16) << "the second batch must need more pairs per state than the guess";

    rc::device::StageBudget budget;
    budget.minSurvivorBound = 1;  // the bound is the guess alone
    const rc::StagedBackend staged(model, poisonedStages(model, budget));
    // The first chunk is sized by every pair; the outgrown pass's wait, then the pass's again.
    expectTheLargerNeedRunsAgainOnce(staged, model, few, many, exact, 2);
}

TEST(StagedPipeline, ALargeChunkWaitsForEachCount)
{
    // Past StageBudget::waitForCountsFrom a chunk's buffers and launches take the counts' sizes:
    // it waits for the pairs past the culls, the candidate triangles, the fragments and the
    // outcomes, then for their download.
    const rc::test::StateSuite suite = suiteNamed("thin plate at 1e6 m", 32);
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    rc::device::StageBudget large;
    large.waitForCountsFrom = 0;
    const rc::StagedBackend staged(model, poisonedStages(model, large));
    std::vector<std::uint8_t> valid;
    rc::CollisionRequest safe, exact;
    exact.mode = rc::CollisionMode::Exact;
    oneCall(staged, suite, safe, valid);
    const rc::device::ExecutorCounts again = oneCall(staged, suite, safe, valid);
    EXPECT_EQ(again.synchronizations, 5u);
    EXPECT_EQ(again.allocations, 0u);
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));
    EXPECT_EQ(oneCall(staged, suite, exact, valid).synchronizations, 3u) << "no raster: no triangles or fragments";
    EXPECT_EQ(valid, cpuVerdicts(model, suite, exact));
}

TEST(StagedPipeline, ABatchOfManyPairsWaitsOnceOnceItsPairsPastTheCullsWereCounted)
{
    // Whether a chunk waits once is decided by the bound of its pairs past the culls: every (state,
    // pair) element before its executor has counted them, then what the executor's chunks needed
    // per state (StageBudget::waitForCountsFrom). A batch of more elements than that waits for each
    // count the first time only.
    const rc::test::StateSuite suite = suiteNamed("crane in the plant", 32);  // 935 pairs a state
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    rc::device::StageBudget budget;
    budget.waitForCountsFrom = suite.numStates() * model->numPairs();
    budget.minSurvivorBound = 1;
    const rc::StagedBackend staged(model, poisonedStages(model, budget));
    staged.countStages(true);
    std::vector<std::uint8_t> valid;
    const rc::CollisionRequest safe;
    EXPECT_EQ(oneCall(staged, suite, safe, valid).synchronizations, 5u) << "every count, as a large chunk";
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));
    ASSERT_LT(2 * staged.stageCounts().survivingPairs, budget.waitForCountsFrom)
        << "the pairs past the culls, half again, must be fewer than the batch's elements";
    EXPECT_EQ(oneCall(staged, suite, safe, valid).synchronizations, 3u)
        << "the raster's counts, measured by small chunks only, and the outcomes";
    EXPECT_EQ(valid, cpuVerdicts(model, suite, safe));
    expectOneWaitAndTheCpuVerdicts(staged, model, suite, safe);
}

TEST(StagedPipeline, ConcurrentCallsEachTakeAnExecutorOfTheirOwn)
{
    // The pool behind a runner: calls that run at the same time never share an executor (on the
    // GPU: a stream, its buffers and host mirrors), and later calls reuse the executors made.
    struct Executor
    {
        rc::device::ExecutorCounts counts_;
        std::atomic<int> users{0};
        rc::device::ExecutorCounts &counts() { return counts_; }
    };
    std::atomic<int> made{0};
    rc::ExecutorPool<Executor> pool(
        [&]
        {
            ++made;
            return std::make_unique<Executor>();
        });
    constexpr int kThreads = 8;
    std::mutex mutex;
    std::condition_variable allInside;
    for (int round = 0; round < 3; ++round)
    {
        int inside = 0;
        std::vector<std::thread> threads;
        std::vector<const Executor *> used(kThreads);
        for (int t = 0; t < kThreads; ++t)
            threads.emplace_back(
                [&, t]
                {
                    pool.run(
                        [&](Executor &ex)
                        {
                            EXPECT_EQ(ex.users++, 0) << "an executor taken by two calls at once";
                            used[t] = &ex;
                            std::unique_lock<std::mutex> lock(mutex);
                            ++inside;
                            allInside.notify_all();
                            allInside.wait(lock, [&] { return inside == kThreads; });  // all eight at once
                            --ex.users;
                        });
                });
        for (std::thread &thread : threads)
            thread.join();
        std::sort(used.begin(), used.end());
        EXPECT_EQ(std::unique(used.begin(), used.end()), used.end()) << "round " << round;
        EXPECT_EQ(made.load(), kThreads) << "round " << round << ": the executors are made once";
        EXPECT_EQ(pool.size(), static_cast<std::size_t>(kThreads));
    }
}

TEST(StagedPipeline, EightThreadsOnOneBackendGetTheCpuBackendsVerdicts)
{
    // Planners call one checker from several threads: each pass takes an executor of its own (on
    // the GPU, a stream and buffers), none waits for another's. Every executor's first call
    // allocates its buffers and measures its raster's counts; every later call allocates nothing
    // and waits once.
    const rc::test::StateSuite suite = suiteNamed("thin plate at 1e6 m", 64);
    const auto model = std::make_shared<const rc::CollisionModel>(suite.robot, suite.scene);
    const std::size_t n = suite.numStates();
    rc::CollisionRequest request;
    request.pairPadding = rc::test::randomPairPaddings(*model, n, 3);
    const std::vector<std::uint8_t> expected = cpuVerdicts(model, suite, request);

    // One executor's first call, to know what a first call costs.
    const rc::StagedBackend alone(model, poisonedStages(model));
    std::vector<std::uint8_t> valid;
    const rc::device::ExecutorCounts firstCall = oneCall(alone, suite, request, valid);
    EXPECT_EQ(valid, expected);

    const rc::StagedBackend staged(model, poisonedStages(model));
    constexpr int kThreads = 8, kRounds = 5;
    std::vector<std::vector<std::vector<std::uint8_t>>> verdicts(
        kThreads, std::vector<std::vector<std::uint8_t>>(kRounds, std::vector<std::uint8_t>(n)));
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back(
            [&, t]
            {
                for (int round = 0; round < kRounds; ++round)
                    staged.check(suite.states.data(), n, verdicts[t][round].data(), nullptr, request, 1);
            });
    for (std::thread &thread : threads)
        thread.join();
    for (int t = 0; t < kThreads; ++t)
        for (int round = 0; round < kRounds; ++round)
            EXPECT_EQ(verdicts[t][round], expected) << "thread " << t << ", round " << round;

    const unsigned long long executors = staged.executors();
    EXPECT_GE(executors, 1u);
    EXPECT_LE(executors, static_cast<unsigned long long>(kThreads)) << "an executor per concurrent call, no more";
    const rc::device::ExecutorCounts all = staged.executorCounts();
    const unsigned long long calls = kThreads * kRounds;
    EXPECT_EQ(all.calls, calls);
    EXPECT_EQ(all.chunks, calls);
    EXPECT_EQ(all.reruns, 0u);
    EXPECT_EQ(all.allocations, executors * firstCall.allocations) << "only each executor's first call allocates";
    EXPECT_EQ(all.synchronizations, executors * firstCall.synchronizations + (calls - executors))
        << "one wait per call but each executor's first";
}
