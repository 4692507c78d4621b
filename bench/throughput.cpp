// Throughput of each collision mode against FCL (BVHModel<OBBRSS> + dynamic AABB tree, as MoveIt and
// OMPL.app use it) on the Panda MotionBenchMaker scenes: the same robot, meshes and states for all,
// in one run. Prints states/s and the ratio to FCL, one thread and all threads.
//
// usage: rastercheck_bench_throughput [scenes_per_scenario=3] [states_per_scene=2000]
#include <cstdio>
#include <cstdlib>
#include <map>
#include <thread>

#include "BenchSupport.h"
#include "Reference.h"
#include "rastercheck/collision/Checker.h"

using namespace rastercheck;

int main(int argc, char **argv)
{
    const int scenesPerScenario = argc > 1 ? std::atoi(argv[1]) : 3;
    const std::size_t statesPerScene = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 2000;
    const std::string root = bench::sharedDataOrExit();
    const RobotModelConstPtr robot = bench::loadMbmRobot(root, "panda");
    const int cores = static_cast<int>(std::thread::hardware_concurrency());

    struct Run
    {
        std::string name;
        CollisionMode mode;
        int threads;
    };
    const std::vector<Run> runs{{"exact, 1 thread", CollisionMode::Exact, 1},
                                {"raster, 1 thread", CollisionMode::Raster, 1},
                                {"safe, 1 thread", CollisionMode::Safe, 1},
                                {"safe, all threads", CollisionMode::Safe, 0}};
    std::map<std::string, double> time;
    std::map<std::string, std::size_t> disagreements;
    double fclTime = 0;
    std::size_t total = 0, colliding = 0;

    for (const std::string &scenario : bench::mbmScenarios())
        for (int index = 1; index <= scenesPerScenario; ++index)
        {
            const SceneConstPtr scene = loadMoveItScene(bench::mbmProblemPath(root, "panda", scenario, index, "scene"));
            const std::vector<double> q = bench::uniformStates(*robot, statesPerScene, 1000u * index + scenario.size());
            const std::size_t dof = robot->numCoordinates();

            const Checker oneThread(robot, scene, CheckerOptions{BackendChoice::Cpu, 1});
            const Checker allThreads(robot, scene, CheckerOptions{BackendChoice::Cpu, 0});
            test::FclReference fcl(oneThread.collisionModel());
            std::vector<std::uint8_t> fclValid(statesPerScene);
            fclTime += bench::seconds(
                [&]
                {
                    for (std::size_t i = 0; i < statesPerScene; ++i)
                        fclValid[i] = fcl.collides(q.data() + i * dof) ? 0 : 1;
                });
            std::vector<std::uint8_t> exactValid;
            for (const Run &run : runs)
            {
                const Checker &checker = run.threads == 1 ? oneThread : allThreads;
                std::vector<std::uint8_t> valid(statesPerScene);
                CollisionRequest request;
                request.mode = run.mode;
                time[run.name] +=
                    bench::seconds([&] { checker.check(q.data(), statesPerScene, valid.data(), request); });
                if (run.mode == CollisionMode::Exact)
                    exactValid = valid;
                for (std::size_t i = 0; i < statesPerScene; ++i)
                    disagreements[run.name] += valid[i] != exactValid[i];
            }
            for (std::size_t i = 0; i < statesPerScene; ++i)
            {
                disagreements["fcl"] += fclValid[i] != exactValid[i];
                colliding += exactValid[i] == 0;
            }
            total += statesPerScene;
        }

    std::printf(
        "Panda, MotionBenchMaker scenes: %d per scenario x 7 scenarios, %zu uniform states each "
        "(%zu states, %.1f %% colliding); %d cores\n\n",
        scenesPerScenario, statesPerScene, total, 100.0 * colliding / total, cores);
    std::printf("| checker | states/s | ratio to FCL (1 thread) | verdicts differing from exact |\n");
    std::printf("|---|---:|---:|---:|\n");
    std::printf("| FCL 0.7 OBBRSS, 1 thread | %.0f | 1.00 | %zu |\n", total / fclTime, disagreements["fcl"]);
    for (const Run &run : runs)
        std::printf("| rastercheck %s | %.0f | %.2f | %zu |\n", run.name.c_str(), total / time[run.name],
                    fclTime / time[run.name], disagreements[run.name]);
    return 0;
}
