// A call's critical path on the host executor: per kernel of the stages the slowest element's time,
// summed over the call (ExecutorCounts::criticalPathSeconds). A device running a thread per element
// waits for that chain, at its own thread speed, besides the call's launches: this measures the
// part of a small call's latency that more launches in a graph cannot hide, without a device.
// Each batch is checked three times and the least kept (a timer interrupt inside one element
// would otherwise count whole); 20 batches first to warm up. Safe mode, uniform random states.
// Prints a Markdown table (docs/benchmarks.md, "A call's critical path").
//
// usage: rastercheck_bench_critical_path [batches=80] [sizes=32,1000]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "BenchScenes.h"
#include "BenchSupport.h"
#include "rastercheck/collision/StagedBackend.h"

using namespace rastercheck;

namespace
{
double quantile(std::vector<double> values, double q)
{
    std::sort(values.begin(), values.end());
    return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1))];
}
}  // namespace

int main(int argc, char **argv)
{
    const int batches = argc > 1 ? std::atoi(argv[1]) : 80;
    std::vector<std::size_t> sizes;
    for (const std::string &item : bench::splitList(argc > 2 ? argv[2] : "32,1000"))
        sizes.push_back(static_cast<std::size_t>(std::atol(item.c_str())));
    if (batches < 1 || sizes.empty() || std::find(sizes.begin(), sizes.end(), 0u) != sizes.end())
    {
        std::fprintf(stderr, "usage: rastercheck_bench_critical_path [batches=80] [sizes=32,1000]\n");
        return 2;
    }
    const std::vector<bench::SceneCase> cases = bench::backendScenes(bench::sharedDataOrExit());

    constexpr int kWarmUp = 20, kRepeats = 3;
    std::printf("safe mode, %d batches per size after %d, each the least of %d runs\n\n", batches, kWarmUp, kRepeats);
    std::printf("| scene | states | critical path p50 / p90 / max, us | launches per call |\n");
    std::printf("|---|---:|---:|---:|\n");
    CollisionRequest request;
    for (const bench::SceneCase &c : cases)
    {
        const auto model = std::make_shared<const CollisionModel>(c.robot, c.scene);
        const StagedBackend staged(model, makeHostStageRunner(model, {}, HostScratch::Reused, HostLoop::Timed));
        const std::size_t dof = c.robot->numCoordinates();
        for (std::size_t n : sizes)
        {
            const std::vector<double> q =
                bench::uniformStates(*c.robot, n * static_cast<std::size_t>(kWarmUp + batches), 42);
            std::vector<std::uint8_t> valid(n);
            std::vector<double> paths;
            double launches = 0;
            for (int b = 0; b < kWarmUp + batches; ++b)
            {
                double least = 0;
                for (int r = 0; r < kRepeats; ++r)
                {
                    const device::ExecutorCounts before = staged.executorCounts();
                    staged.check(q.data() + static_cast<std::size_t>(b) * n * dof, n, valid.data(), nullptr, request,
                                 0);
                    const device::ExecutorCounts call = staged.executorCounts().since(before);
                    least = r == 0 ? call.criticalPathSeconds : std::min(least, call.criticalPathSeconds);
                    launches = static_cast<double>(call.launches);
                }
                if (b >= kWarmUp)
                    paths.push_back(least * 1e6);
            }
            std::printf("| %s | %zu | %.1f / %.1f / %.1f | %.0f |\n", c.name.c_str(), n, quantile(paths, 0.5),
                        quantile(paths, 0.9), quantile(paths, 1.0), launches);
            std::fflush(stdout);
        }
    }
    return 0;
}
