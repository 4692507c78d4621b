// The CUDA backend against the CPU backend, state for state, on a real GPU. Every test skips when
// this build has no CUDA backend or no usable device (ctest label "gpu"), and fails instead when
// RASTERCHECK_REQUIRE_GPU is set (scripts/gpu-check.sh sets it: on the GPU machine a skip would
// hide a device the backend could not use). The same driver and per-element code are checked on
// every machine through the host executor (test_staged_pipeline).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <gtest/gtest.h>

#include "BackendSuites.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/io/OmplAppProblem.h"

namespace rc = rastercheck;

namespace
{
/** \brief A checker on the CUDA backend for every batch size, or null (the test then skips). */
std::unique_ptr<rc::Checker> gpuChecker(const rc::test::StateSuite &suite, std::size_t deviceMemoryLimit = 0)
{
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cuda;
    options.minDeviceBatch = 1;
    options.deviceMemoryLimit = deviceMemoryLimit;
    auto checker = std::make_unique<rc::Checker>(suite.robot, suite.scene, options);
    if (checker->backendName().rfind("cuda", 0) != 0)
        return nullptr;
    return checker;
}

#define REQUIRE_GPU(checker)                                                                                     \
    if (!(checker))                                                                                              \
    {                                                                                                            \
        if (std::getenv("RASTERCHECK_REQUIRE_GPU"))                                                              \
            FAIL() << "RASTERCHECK_REQUIRE_GPU is set, but the checker runs on the CPU (its warning says why)";  \
        GTEST_SKIP() << "no CUDA backend in this build or no usable CUDA device (the staged pipeline is tested " \
                        "on the CPU by test_staged_pipeline)";                                                   \
    }

/** \brief The checker's model for a CPU backend beside it (the checker outlives the backend). */
rc::CollisionModelConstPtr sameModel(const rc::Checker &checker)
{
    return rc::CollisionModelConstPtr(std::shared_ptr<void>(), &checker.collisionModel());
}

const rc::CollisionMode kModes[] = {rc::CollisionMode::Safe, rc::CollisionMode::Raster, rc::CollisionMode::Exact};
}  // namespace

TEST(GpuBackend, SameVerdictsAndFirstContactsAsTheCpuOnTheAccuracySuites)
{
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(1000))
    {
        const std::unique_ptr<rc::Checker> gpu = gpuChecker(suite);
        REQUIRE_GPU(gpu);
        const rc::CpuBackend cpu(sameModel(*gpu));
        for (rc::CollisionMode mode : kModes)
            for (double padding : {0.0, 0.01})
            {
                rc::CollisionRequest request;
                request.mode = mode;
                request.padding = padding;
                rc::test::expectSameDecisions(
                    gpu->backend(), cpu, gpu->collisionModel(), suite.states, request,
                    suite.name + " (" + rc::toString(mode) + ", padding " + std::to_string(padding) + ")");
            }
    }
}

TEST(GpuBackend, AMeshObstacleIsDecidedExactlyOnTheDevice)
{
    // FCL's env/rob: a non-convex, open mesh obstacle whose pairs no hull proof settles, so the
    // exact phase inside the stages decides them (device/ExactPhase.h, one thread per pair): the
    // same verdicts and first contacts as the CPU backend in every mode, with and without padding.
    const std::string root = rc::test::sharedData();
    if (root.empty())
        GTEST_SKIP() << "shared data not found (set RASTERCHECK_DATA): FCL's env/rob meshes are needed";
    std::string cfg = "[problem]\nname = fcl_env_rob\nrobot = " + root + "/meshes/fcl/rob.obj\nworld = " + root +
                      "/meshes/fcl/env.obj\n";
    for (const char *end : {"start", "goal"})
        for (const char *key :
             {".x = 0", ".y = 0", ".z = 0", ".theta = 0", ".axis.x = 1", ".axis.y = 0", ".axis.z = 0"})
            cfg += std::string(end) + key + "\n";
    const rc::OmplAppProblem problem =
        rc::loadOmplAppProblem(rc::test::writeFile(rc::test::makeTempDir("gpu_env_rob") + "/fcl_env_rob.cfg", cfg));
    const rc::test::StateSuite suite{"fcl env/rob", problem.robot, problem.scene,
                                     rc::test::randomStates(*problem.robot, 2000, 7)};
    const std::unique_ptr<rc::Checker> gpu = gpuChecker(suite);
    REQUIRE_GPU(gpu);
    const rc::CpuBackend cpu(sameModel(*gpu));
    const rc::Mesh &rob = problem.robot->components[0].mesh;
    const double onePercent = 0.01 * (rob.bounds().max - rob.bounds().min).norm();
    for (rc::CollisionMode mode : kModes)
        for (double padding : {0.0, onePercent})
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.padding = padding;
            const rc::test::Agreement agreement = rc::test::expectSameDecisions(
                gpu->backend(), cpu, gpu->collisionModel(), suite.states, request,
                suite.name + " (" + rc::toString(mode) + ", padding " + std::to_string(padding) + ")");
            EXPECT_GT(agreement.valid, 0u);
            EXPECT_GT(agreement.invalid, 0u);
        }
}

TEST(GpuBackend, ADeviceMemoryLimitSplitsBatchesWithoutChangingVerdicts)
{
    // 1 MiB of scratch holds one pass over a few dozen Panda states: 300 take several passes, and
    // the crane's or a thin plate's fragments overflow a pass and are halved again.
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(300))
    {
        const std::unique_ptr<rc::Checker> gpu = gpuChecker(suite, 1 << 20);
        REQUIRE_GPU(gpu);
        const rc::CpuBackend cpu(sameModel(*gpu));
        for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(gpu->backend(), cpu, gpu->collisionModel(), suite.states, request,
                                          suite.name + " (" + rc::toString(mode) + ", 1 MiB)");
        }
    }
}

/** \brief The Panda on the table_pick scene with a GPU checker and a CPU backend on one model. */
class PandaOnTheGpu : public ::testing::Test
{
protected:
    void SetUp() override
    {
        suites_ = rc::test::accuracySuites(1);
        for (const rc::test::StateSuite &suite : suites_)
            if (suite.name == "panda table_pick")
                panda_ = &suite;
        if (!panda_)
            GTEST_SKIP() << "shared data not found: set RASTERCHECK_DATA";
        gpu_ = gpuChecker(*panda_);
        REQUIRE_GPU(gpu_);
        cpu_ = std::make_unique<rc::CpuBackend>(sameModel(*gpu_));
    }

    std::vector<rc::test::StateSuite> suites_;
    const rc::test::StateSuite *panda_ = nullptr;
    std::unique_ptr<rc::Checker> gpu_;
    std::unique_ptr<rc::CpuBackend> cpu_;
};

TEST_F(PandaOnTheGpu, RandomBatchesOf1To1000StatesMatchTheCpu)
{
    for (std::size_t n : {1u, 7u, 1000u})
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            rc::test::expectSameDecisions(gpu_->backend(), *cpu_, gpu_->collisionModel(),
                                          rc::test::randomStates(*panda_->robot, n, 5), request,
                                          "batch of " + std::to_string(n) + " (" + rc::toString(mode) + ")");
        }
}

TEST_F(PandaOnTheGpu, PerStatePairPaddingsMatchTheCpu)
{
    // Certified midpoints: every (state, pair) with its own padding, in one pass on the device.
    const std::vector<double> states = rc::test::randomStates(*panda_->robot, 1000, 9);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact, rc::CollisionMode::Conservative})
    {
        rc::CollisionRequest request;
        request.mode = mode;
        request.pairPadding = rc::test::randomPairPaddings(gpu_->collisionModel(), 1000, 13);
        rc::test::expectSameDecisions(gpu_->backend(), *cpu_, gpu_->collisionModel(), states, request,
                                      "padding per state (" + rc::toString(mode) + ")");
    }
}

TEST_F(PandaOnTheGpu, TwoPaddingsMatchTheCpu)
{
    // Certified edges' one check per midpoint (Checker::checkTwoPaddings): on the device the two
    // checks it stands for (wider paddings, then the request's for the states that missed them),
    // against the CPU backend's one pass.
    const std::size_t n = 1000;
    const std::vector<double> states = rc::test::randomStates(*panda_->robot, n, 9);
    const std::shared_ptr<rc::PairPadding> wider = rc::test::randomPairPaddings(gpu_->collisionModel(), n, 13);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact, rc::CollisionMode::Conservative})
    {
        rc::CollisionRequest request;
        request.mode = mode;
        request.padding = 0.002;
        std::vector<std::uint8_t> onDevice(n), onCpu(n);
        gpu_->checkTwoPaddings(states.data(), n, onDevice.data(), request, *wider);
        ASSERT_TRUE(cpu_->checkTwoPaddings(states.data(), n, onCpu.data(), request, *wider, 0));
        EXPECT_EQ(onDevice, onCpu) << rc::toString(mode);
        EXPECT_NE(std::count(onCpu.begin(), onCpu.end(), static_cast<std::uint8_t>(rc::PaddedVerdict::Near)), 0)
            << rc::toString(mode);
    }
}

TEST_F(PandaOnTheGpu, ABatchOf32StatesWaitsOnceAndAllocatesNothingAfterTheFirst)
{
    // The CUDA executor counts its launches, waits and allocations (device buffers and page-locked
    // host mirrors) where it makes them; test_staged_pipeline checks the same figures on the host.
    // Prints what a call costs on the host clock (the latency the benches report).
    const auto *staged = dynamic_cast<const rc::StagedBackend *>(&gpu_->backend());
    ASSERT_NE(staged, nullptr);
    for (std::size_t n : {32u, 1000u})
    {
        const std::vector<double> states = rc::test::randomStates(*panda_->robot, n, 21);
        std::vector<std::uint8_t> valid(n), expected(n);
        cpu_->check(states.data(), n, expected.data(), nullptr, {}, 0);
        gpu_->check(states.data(), n, valid.data());  // sizes the buffers and measures the raster's counts
        EXPECT_EQ(valid, expected);
        std::vector<double> microseconds;
        for (int call = 0; call < 20; ++call)
        {
            const rc::device::ExecutorCounts before = staged->executorCounts();
            const auto start = std::chrono::steady_clock::now();
            gpu_->check(states.data(), n, valid.data());
            microseconds.push_back(
                std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
            const rc::device::ExecutorCounts counts = staged->executorCounts().since(before);
            EXPECT_EQ(counts.synchronizations, 1u) << n << " states, call " << call;
            EXPECT_EQ(counts.allocations, 0u) << n << " states, call " << call;
            EXPECT_EQ(counts.reruns, 0u) << n << " states, call " << call;
            // Recorded, then compiled (captured as a CUDA graph), then replayed (PassRecorder).
            EXPECT_EQ(counts.replayedPasses, call >= 2 ? 1u : 0u) << n << " states, call " << call;
            EXPECT_EQ(valid, expected) << n << " states, call " << call;
            if (call == 0 || call == 2)
                std::printf("%zu states: %llu launches, %llu wait, %llu allocations, %llu graph replays per call\n", n,
                            counts.launches, counts.synchronizations, counts.allocations, counts.replayedPasses);
        }
        std::sort(microseconds.begin(), microseconds.end());
        std::printf("%zu states: %.0f us per call (median of 20, host clock), fastest %.0f us\n", n,
                    microseconds[microseconds.size() / 2], microseconds.front());

        // Other states, as many: the same graph, their own verdicts.
        const std::vector<double> others = rc::test::randomStates(*panda_->robot, n, 22);
        cpu_->check(others.data(), n, expected.data(), nullptr, {}, 0);
        const rc::device::ExecutorCounts before = staged->executorCounts();
        gpu_->check(others.data(), n, valid.data());
        EXPECT_EQ(staged->executorCounts().since(before).replayedPasses, 1u) << n << " states";
        EXPECT_EQ(valid, expected) << n << " other states";
    }
}

TEST_F(PandaOnTheGpu, EightThreadsOnOneCheckerGetTheVerdictsOfOne)
{
    // Each thread's pass takes its own executor: stream, device buffers and host mirrors.
    const std::vector<double> states = rc::test::randomStates(*panda_->robot, 2000, 17);
    std::vector<std::uint8_t> alone(2000), expected(2000);
    gpu_->check(states.data(), 2000, alone.data());
    cpu_->check(states.data(), 2000, expected.data(), nullptr, {}, 0);
    EXPECT_EQ(alone, expected);
    std::vector<std::vector<std::uint8_t>> verdicts(8, std::vector<std::uint8_t>(2000));
    std::vector<std::thread> threads;
    for (int t = 0; t < 8; ++t)
        threads.emplace_back(
            [&, t]
            {
                for (int round = 0; round < 10; ++round)
                    gpu_->check(states.data(), 2000, verdicts[t].data());
            });
    for (std::thread &thread : threads)
        thread.join();
    for (int t = 0; t < 8; ++t)
        EXPECT_EQ(verdicts[t], alone) << "thread " << t;
    const auto *staged = dynamic_cast<const rc::StagedBackend *>(&gpu_->backend());
    ASSERT_NE(staged, nullptr);
    EXPECT_LE(staged->executors(), 8u) << "an executor per concurrent call, no more";
    EXPECT_EQ(staged->executorCounts().reruns, 0u);
}

// Verdicts only (the contacts path runs the exact phase on every pair); a separate test so that
// compute-sanitizer can run the others in minutes.
TEST_F(PandaOnTheGpu, AMillionRandomStatesMatchTheCpu)
{
    const std::size_t n = 1000000;
    const std::vector<double> states = rc::test::randomStates(*panda_->robot, n, 6);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Raster})
    {
        rc::CollisionRequest request;
        request.mode = mode;
        std::vector<std::uint8_t> fromGpu(n), fromCpu(n);
        gpu_->backend().check(states.data(), n, fromGpu.data(), nullptr, request, 0);
        cpu_->check(states.data(), n, fromCpu.data(), nullptr, request, 0);
        std::size_t differ = 0, invalid = 0;
        for (std::size_t i = 0; i < n; ++i)
        {
            differ += fromGpu[i] != fromCpu[i];
            invalid += fromCpu[i] == 0;
        }
        EXPECT_EQ(differ, 0u) << rc::toString(mode);
        EXPECT_GT(invalid, 0u);
        EXPECT_LT(invalid, n);
    }
}

TEST(GpuBackend, TheCheckerSaysWhichDeviceItUses)
{
    const rc::test::StateSuite suite = rc::test::accuracySuites(1)[0];
    const std::unique_ptr<rc::Checker> gpu = gpuChecker(suite);
    REQUIRE_GPU(gpu);
    EXPECT_NE(gpu->backendName().find("cuda ("), std::string::npos) << gpu->backendName();
    rc::CheckerOptions automatic;
    const rc::Checker chosen(suite.robot, suite.scene, automatic);
    EXPECT_EQ(chosen.backendName(), gpu->backendName());  // auto picks the device
}

TEST(GpuBackend, TheLightKernelsBlockSizeIsSetByTheEnvironmentAndABadOneIsNamed)
{
    // RASTERCHECK_CUDA_BLOCK_THREADS sets the threads per block of the light kernels (64 unless
    // set): another size gives the same verdicts, 1024 too (a kernel whose registers cannot fill
    // such a block takes as many threads as they allow); a malformed size is a warning that names
    // the variable, and the checker runs on the CPU.
    const rc::test::StateSuite suite = rc::test::accuracySuites(200)[0];
    const std::unique_ptr<rc::Checker> gpu = gpuChecker(suite);
    REQUIRE_GPU(gpu);
    struct Restore
    {
        ~Restore() { unsetenv("RASTERCHECK_CUDA_BLOCK_THREADS"); }
    } restore;
    setenv("RASTERCHECK_CUDA_BLOCK_THREADS", "256", 1);
    const std::unique_ptr<rc::Checker> wide = gpuChecker(suite);
    ASSERT_TRUE(wide) << "256 threads a block should run on the device";
    const rc::CpuBackend cpu(sameModel(*wide));
    rc::test::expectSameDecisions(wide->backend(), cpu, wide->collisionModel(), suite.states, {},
                                  suite.name + " (256 threads a block)");
    setenv("RASTERCHECK_CUDA_BLOCK_THREADS", "1024", 1);
    const std::unique_ptr<rc::Checker> widest = gpuChecker(suite);
    ASSERT_TRUE(widest) << "1024 threads a block should run on the device";
    rc::test::expectSameDecisions(widest->backend(), cpu, widest->collisionModel(), suite.states, {},
                                  suite.name + " (1024 threads a block, fewer where registers say so)");
    for (const char *bad : {"100", "2048", "0", "64x"})
    {
        setenv("RASTERCHECK_CUDA_BLOCK_THREADS", bad, 1);
        rc::test::LogCapture log;
        EXPECT_FALSE(gpuChecker(suite)) << bad;
        EXPECT_TRUE(log.warned(std::string("RASTERCHECK_CUDA_BLOCK_THREADS=") + bad +
                               ": expected a multiple of 32 from 32 to 1024 (threads per block); using the CPU "
                               "backend"))
            << bad;
    }
}
