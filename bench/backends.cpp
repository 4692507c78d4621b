// Backends side by side: states/s against batch size and scene size for FCL (one core), the CPU
// backend (all cores) and the CUDA backend (when a device is usable), and the motion validator's
// per-edge latency, all in one run on the same states. Prints Markdown tables (docs/benchmarks.md).
// Scenes: three Panda MotionBenchMaker scenes, the crane in the plant, and FCL's env.obj / rob.obj
// (a free-flying non-convex mesh among non-convex meshes, both open: the real-mesh case).
//
// usage: rastercheck_bench_backends [max_batch=1000000] [mode=safe] [staged=cuda]
//   CPU and FCL are timed on batches up to 10^4 states (their rate no longer depends on the batch
//   size there); the GPU on every batch size up to max_batch. staged host-stages runs the GPU's
//   columns on the host executor (the device's code path and its launches and waits, on any
//   machine: its times say how much work a batch is, not how fast a device does it).
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "BenchScenes.h"
#include "BenchSupport.h"
#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/Setup.h"

using namespace rastercheck;

namespace
{
/** \brief Best of \a repeats timings of deciding \a n states, in states per second. */
double statesPerSecond(const Backend &backend, const std::vector<double> &q, std::size_t n,
                       const CollisionRequest &request, int repeats, double *allRepeats = nullptr)
{
    std::vector<std::uint8_t> valid(n);
    double best = 1e30, total = 0;
    for (int r = 0; r < repeats; ++r)
    {
        const double seconds = bench::seconds([&] { backend.check(q.data(), n, valid.data(), nullptr, request, 0); });
        best = std::min(best, seconds);
        total += seconds;
    }
    if (allRepeats)
        *allRepeats = total;
    return static_cast<double>(n) / best;
}

/** \brief How the stages settle the pairs of \a n states that survive the box culls (the host
    executor's outcomes and counts, which the GPU's equal): apart, colliding, how many of those the
    exact phase decided inside the stages, and what is left to the host (conservative mode's
    unproven pairs), with the time one core takes to decide those. That time bounds the GPU
    backend's rate from above, whatever the device: states/s <= host cores x the per-core rate. */
void printHostShare(const std::string &name, const CollisionModelConstPtr &model, const std::vector<double> &q,
                    std::size_t n, const CollisionRequest &request)
{
    const std::size_t dof = model->robot->numCoordinates();
    std::vector<std::uint8_t> admissible(n);
    for (std::size_t i = 0; i < n; ++i)
        admissible[i] = model->configurationAdmissible(q.data() + i * dof) ? 1 : 0;
    std::vector<device::PairOutcome> outcomes;
    const std::unique_ptr<StageRunner> runner = makeHostStageRunner(model);
    runner->countStages(true);
    runner->run(q.data(), admissible.data(), n, stageSettings(*model, request, false), outcomes);
    std::size_t apart = 0, hits = 0, open = 0;
    for (const device::PairOutcome &o : outcomes)
        (o.status == device::PairApart ? apart : o.status == device::PairOverlaps ? hits : open) += 1;
    const CpuBackend exact(model);
    std::unique_ptr<CpuWorkspace> ws = exact.makeWorkspace();
    const double seconds = bench::seconds(
        [&]
        {
            std::uint32_t refitted = ~0u;
            for (const device::PairOutcome &o : outcomes)
            {
                if (o.status != device::PairOpen)
                    continue;
                if (o.state != refitted)
                    exact.refitState(q.data() + o.state * dof, *ws);
                refitted = o.state;
                Contact contact;
                exact.decideOpenPair(o.pair, request, *ws, contact);
            }
        });
    const double perState = 1.0 / static_cast<double>(n);
    std::printf("| %s | %zu | %.2f | %.2f | %.3f | %.3f | %.3f | %s |\n", name.c_str(), n, outcomes.size() * perState,
                apart * perState, hits * perState, runner->counts().exactPairs * perState, open * perState,
                open > 0 ? (std::to_string(static_cast<long>(n / seconds / 1e3)) + "k").c_str() : "unbounded");
}

std::string rate(double statesPerSecond)
{
    char text[32];
    if (statesPerSecond >= 1e6)
        std::snprintf(text, sizeof text, "%.2fM", statesPerSecond / 1e6);
    else
        std::snprintf(text, sizeof text, "%.1fk", statesPerSecond / 1e3);
    return text;
}
}  // namespace

int main(int argc, char **argv)
{
    const std::size_t maxBatch = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 1000000;
    const CollisionMode mode = argc > 2 ? parseCollisionMode(argv[2]) : CollisionMode::Safe;
    const std::string stagedName = argc > 3 ? argv[3] : "cuda";
    const BackendChoice stagedChoice = parseBackendChoice(stagedName);
    if (stagedChoice != BackendChoice::Cuda && stagedChoice != BackendChoice::HostStages)
    {
        std::fprintf(stderr, "rastercheck_bench_backends: staged must be cuda or host-stages\n");
        return 2;
    }
    const std::string root = bench::sharedDataOrExit();
    const std::vector<bench::SceneCase> cases = bench::backendScenes(root);

    CollisionRequest request;
    request.mode = mode;
    std::printf("mode %s, %u CPU threads, staged backend %s\n\n", toString(mode).c_str(),
                std::thread::hardware_concurrency(), stagedName.c_str());

    // States/s against batch size and scene size.
    std::printf("| scene | triangles (robot / scene) | batch | FCL 1 core | CPU backend | GPU backend | GPU / FCL | "
                "GPU / CPU | GPU per call |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const bench::SceneCase &c : cases)
    {
        CheckerOptions gpuOptions;
        gpuOptions.backend = stagedChoice;
        gpuOptions.minDeviceBatch = 1;
        const Checker gpu(c.robot, c.scene, gpuOptions);
        const bool haveGpu = gpu.backendName() != "cpu";
        const CollisionModelConstPtr model(std::shared_ptr<void>(), &gpu.collisionModel());
        const CpuBackend cpu(model);
        test::FclReference fcl(*model);
        const std::size_t dof = c.robot->numCoordinates();
        const std::vector<double> q = bench::uniformStates(*c.robot, std::max<std::size_t>(maxBatch, 10000), 42);
        std::size_t sceneTriangles = 0;
        for (const SceneObject &object : c.scene->objects)
            sceneTriangles += object.mesh.numTriangles();

        const std::size_t fclStates = 10000;
        const double fclRate = fclStates / bench::seconds(
                                               [&]
                                               {
                                                   for (std::size_t i = 0; i < fclStates; ++i)
                                                       fcl.collides(q.data() + i * dof);
                                               });
        // 32 states: a motion validator's edge; 1 000: a planner's round of samples.
        std::vector<std::size_t> batches{1, 32, 1000};
        for (std::size_t batch = 10000; batch <= maxBatch; batch *= 10)
            batches.push_back(batch);
        for (std::size_t batch : batches)
        {
            if (batch > maxBatch)
                continue;
            const int repeats = batch <= 1000 ? 20 : 2;
            const double cpuRate = batch <= 100000 ? statesPerSecond(cpu, q, batch, request, repeats) : 0;
            const auto *staged = dynamic_cast<const StagedBackend *>(&gpu.backend());
            if (haveGpu)  // the first call of a size allocates and measures: the columns give later calls'
                statesPerSecond(gpu.backend(), q, batch, request, 1);
            const device::ExecutorCounts before = staged ? staged->executorCounts() : device::ExecutorCounts{};
            double gpuSeconds = 0;
            const double gpuRate = haveGpu ? statesPerSecond(gpu.backend(), q, batch, request, repeats, &gpuSeconds) : 0;
            // The share of the calls spent in the stages' passes (kernels, copies, waits); the rest is
            // the host's: the bounds check, the per-state reduction and the open pairs' exact phase.
            // And what a call costs its executor: waits for the device, launches, allocations, after
            // the call above (a small batch then waits once and allocates nothing).
            const device::ExecutorCounts used =
                staged ? staged->executorCounts().since(before) : device::ExecutorCounts{};
            const double passShare = used.seconds / std::max(1e-12, gpuSeconds);
            const double perCall = 1.0 / std::max<unsigned long long>(1, used.calls);
            char costs[128];
            std::snprintf(costs, sizeof costs,
                          ", %.2f waits, %.1f launches, %.2f allocations, %.2f graph replays per call",
                          used.synchronizations * perCall, used.launches * perCall, used.allocations * perCall,
                          used.replayedPasses * perCall);
            std::printf("| %s | %zu / %zu | %zu | %s | %s | %s | %s | %s | %s |\n", c.name.c_str(),
                        c.robot->numTriangles(), sceneTriangles, batch, rate(fclRate).c_str(),
                        cpuRate > 0 ? rate(cpuRate).c_str() : "-", haveGpu ? rate(gpuRate).c_str() : "no device",
                        haveGpu ? (std::to_string(gpuRate / fclRate).substr(0, 6) + "x").c_str() : "-",
                        haveGpu && cpuRate > 0 ? (std::to_string(gpuRate / cpuRate).substr(0, 5) + "x").c_str() : "-",
                        haveGpu ? (std::to_string(static_cast<long>(1e6 * batch / gpuRate)) + " us, " +
                                   std::to_string(static_cast<int>(100 * passShare)) + " % in the passes" + costs)
                                      .c_str()
                                : "-");
        }
    }

    // What the stages leave to the host in this mode.
    std::printf(
        "\n| scene | states | pairs past the box culls / state | settled apart by the stages | settled colliding by "
        "the stages | of those, decided by the exact phase in the stages | left to the host | host ceiling, states/s "
        "per core |\n|---|---|---|---|---|---|---|---|\n");
    for (const bench::SceneCase &c : cases)
    {
        const auto model = std::make_shared<const CollisionModel>(c.robot, c.scene);
        printHostShare(c.name, model, bench::uniformStates(*c.robot, 10000, 42), 10000, request);
    }

    // Motion validator: per-edge latency on random edges (OMPL's default resolution, 1 %). FCL
    // checks the same interpolated states one by one from the start, as DiscreteMotionValidator.
    // The staged backend takes every call (minDeviceBatch 1: an edge's few states would otherwise
    // stay on the CPU), and its calls per edge are what a device's latency multiplies.
    std::printf(
        "\n| scene | checker | edges | mean latency per edge | states per edge | calls per edge |\n"
        "|---|---|---|---|---|---|\n");
    for (const bench::SceneCase &c : cases)
        for (int choice = 0; choice < 5; ++choice)
        {
            // 0: FCL, 1: CPU backend, 2: GPU backend, 3: CPU backend with certified edges (collision-free
            // at every point, not only at the states a resolution apart: more states per edge), 4: GPU
            // backend with certified edges (their midpoints' pair paddings ride with the batch).
            rastercheck::ompl::SetupOptions options;
            const bool onStages = choice == 2 || choice == 4;
            options.checker.backend = onStages ? stagedChoice : BackendChoice::Cpu;
            options.checker.minDeviceBatch = onStages ? 1 : 0;
            options.request = request;
            if (choice >= 3)
            {
                if (request.mode == CollisionMode::Raster)
                    continue;  // raster mode cannot certify
                options.edges = rastercheck::ompl::EdgeChecking::Certified;
            }
            const Problem problem{c.robot, c.scene, nullptr};
            ::ompl::geometric::SimpleSetupPtr setup = rastercheck::ompl::makeSimpleSetup(problem, options);
            const rastercheck::ompl::StateValidityCheckerPtr checker =
                rastercheck::ompl::getStateValidityChecker(*setup);
            if (onStages && checker->getChecker().backendName() == "cpu")
                continue;
            const auto *staged = dynamic_cast<const StagedBackend *>(&checker->getChecker().backend());
            const std::uint64_t callsBefore = staged ? staged->executorCounts().calls : 0;
            const ::ompl::base::SpaceInformationPtr &si = setup->getSpaceInformation();
            si->setup();
            auto sampler = si->allocStateSampler();
            const int edges = 2000;
            std::vector<::ompl::base::State *> from(edges), to(edges);
            for (int e = 0; e < edges; ++e)
            {
                from[e] = si->allocState();
                to[e] = si->allocState();
                sampler->sampleUniform(from[e]);
                sampler->sampleUniform(to[e]);
            }
            const auto validator = si->getMotionValidator();
            test::FclReference fcl(checker->getChecker().collisionModel());
            std::vector<double> q(c.robot->numCoordinates());
            ::ompl::base::State *between = si->allocState();
            const double elapsed = bench::seconds(
                [&]
                {
                    for (int e = 0; e < edges; ++e)
                    {
                        if (choice != 0)
                        {
                            validator->checkMotion(from[e], to[e]);
                            continue;
                        }
                        const unsigned steps = si->getStateSpace()->validSegmentCount(from[e], to[e]);
                        for (unsigned k = 1; k <= steps; ++k)
                        {
                            si->getStateSpace()->interpolate(from[e], to[e], static_cast<double>(k) / steps, between);
                            checker->getStateMapping().toConfiguration(between, q.data());
                            if (fcl.collides(q.data()))
                                break;
                        }
                    }
                });
            si->freeState(between);
            std::uint64_t states = 0;
            if (const auto certified =
                    std::dynamic_pointer_cast<rastercheck::ompl::CertifiedMotionValidator>(validator))
                states = certified->getCheckedStateCount();
            else
                for (int e = 0; e < edges; ++e)
                    states += si->getStateSpace()->validSegmentCount(from[e], to[e]);
            const std::string name = choice == 0 ? "FCL, 1 core"
                                     : checker->getChecker().backendName() + " backend" +
                                           (choice >= 3 ? ", certified edges" : "");
            char calls[32] = "-";
            if (staged)
                std::snprintf(calls, sizeof calls, "%.2f",
                              static_cast<double>(staged->executorCounts().calls - callsBefore) / edges);
            std::printf("| %s | %s | %d | %.1f us | %.1f | %s |\n", c.name.c_str(), name.c_str(), edges,
                        1e6 * elapsed / edges, static_cast<double>(states) / edges, calls);
            for (int e = 0; e < edges; ++e)
            {
                si->freeState(from[e]);
                si->freeState(to[e]);
            }
        }
    return 0;
}
