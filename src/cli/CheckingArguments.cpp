#include "Commands.h"

namespace rastercheck::cli
{
void CheckingArguments::addModeAndPadding(CLI::App &command, const std::string &what)
{
    command
        .add_option("--mode", mode,
                    what + ": safe (default, no false negatives), raster, exact, or conservative (proofs only: no "
                           "false negatives, some false alarms)")
        ->check(CLI::IsMember({"safe", "raster", "exact", "conservative"}));
    command.add_option("--padding", padding, "safety margin in scene units")->check(CLI::NonNegativeNumber);
}

void CheckingArguments::addBackendAndThreads(CLI::App &command, const std::string &threadsHelp)
{
    command.add_option("--backend", backend, "auto, cpu or cuda")->check(CLI::IsMember({"auto", "cpu", "cuda"}));
    command.add_option("--device-batch", deviceBatch,
                       "smallest batch of states sent to the GPU; smaller ones run on the CPU (default: 4096 per CPU "
                       "thread, where a device started to beat 16 cores; the planning benchmarks on a GPU use 32)");
    command.add_option("--threads", threads, threadsHelp + " (0 = all cores)")->check(CLI::NonNegativeNumber);
}

CollisionRequest CheckingArguments::request() const
{
    CollisionRequest request;
    request.mode = parseCollisionMode(mode);
    request.padding = padding;
    return request;
}

CheckerOptions CheckingArguments::checker() const
{
    CheckerOptions options;
    options.backend = parseBackendChoice(backend);
    options.threads = threads;
    options.minDeviceBatch = deviceBatch;
    return options;
}
}  // namespace rastercheck::cli
