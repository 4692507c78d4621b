// planners/ against OMPL's RRT-Connect on the MotionBenchMaker problems (Panda, UR5, Fetch; all 7
// scenarios): BatchRRTConnect and OMPL's RRTConnect on the same rastercheck checker with certified
// edges, and RRTConnect with FCL (BVHModel<OBBRSS>) and OMPL's DiscreteMotionValidator, in one run,
// problem by problem, one core. Every path (raw and simplified) is re-checked by the exact oracle at
// 10x the planner's resolution; a colliding path is unsolved. Simplification: BatchShortcutter for
// BatchRRTConnect, OMPL's PathSimplifier (SimpleSetup::simplifySolution) for the others, 1 s each.
// Prints per robot: solved, colliding, median and p95 solve time (unsolved runs count at the
// limit), the same with simplification, median path length raw and simplified, states checked,
// how many runs have a start or goal that the exact checker puts in collision (MotionBenchMaker
// made its problems with other collision models; no exact planner can solve those), and on the
// staged backends (cuda, host-stages) the checker's calls per solve on them (median, p95, max) and
// over all runs its calls, chunks, chunks run again, waits and launches.
//
// usage: rastercheck_bench_planners [robots=panda,ur5,fetch] [problems_per_scenario=5]
//                                   [time_limit_s=2] [batch_size=8] [first_problem=1]
//                                   [planners=fcl,rrtconnect,batch,eager] [lazy_samples=2]
//                                   [range_fraction=0] [lazy_limit=300] [backend=cpu] [threads=1]
//                                   [edge_sizing=bisection|clearance|hullbound] [margin=0]
//                                   [device_batch=32] [decide_together=-1]
// (backend and threads: the rastercheck checker's, CheckerOptions; threads 0 = every core; FCL
// always runs on one core)
// (margin: CertifiedMotionOptions::margin, scene units; 0: its default, a tenth of the robot's size)
// (batch_size 0: BatchRRTConnect's default, by the backend; device_batch: CheckerOptions::minDeviceBatch
// with backend cuda or host-stages, 32 = every batch the device can take, 0 = the library's automatic
// threshold)
// (decide_together: BatchRRTConnect's, -1 by the backend, 0 one candidate at a time, 1 a round's together)
// (range_fraction > 0: every planner's range is that fraction of the space's maximum extent;
// 0: each planner's default, OMPL's fifth of the extent)
// (a subset of planners: for profiling one of them; the others' rows stay empty; "eager" is
// BatchRRTConnect with lazy 0, every new edge certified when it is grown)
// The robot "crane" plans robots/'s crane lift over the plant (examples/crane_lift's problem),
// problems_per_scenario runs with different seeds. A robot "omplapp:NAME" plans OMPL.app's NAME.cfg
// (from $RASTERCHECK_OMPLAPP, a resources/3D folder; never bundled), as many runs.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <sstream>

#include <ompl/base/goals/GoalState.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "BenchSupport.h"
#include "FclValidity.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/core/Statistics.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/planners/BatchRRTConnect.h"
#include "rastercheck/planners/BatchShortcutter.h"

using namespace rastercheck;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace
{
struct Tally
{
    int attempts = 0, solved = 0, colliding = 0, simplifiedColliding = 0;
    int solvedWithinOneSecond = 0;
    std::vector<double> times;            ///< every run's solve time (s), unsolved at the limit
    std::vector<double> simplifiedTimes;  ///< solve + simplification (s), unsolved at the limit
    std::vector<double> lengths, simplifiedLengths;
    std::vector<double> states;  ///< states the rastercheck checker decided per run
    /// per run, the checker's calls on the staged backend (cuda, host-stages) during the solve: each
    /// at least a device's fixed cost of a call, and the calls of a solve follow one another
    std::vector<double> stagedCalls;
};

bool collisionFree(const og::PathGeometric &path, const rastercheck::ompl::StateValidityChecker &oracle)
{
    CollisionRequest exact;
    exact.mode = CollisionMode::Exact;
    return rastercheck::ompl::checkPathDensely(path, oracle.getStateMapping(), oracle.getChecker(), exact, 10).valid;
}

void seed(std::uint_fast32_t value)
{
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_NONE);  // OMPL warns when the seed changes after RNGs exist
    ::ompl::RNG::setSeed(value);
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_ERROR);
}

/** \brief One planning run of \a planner on \a setup, then its simplification; tallied. */
void run(og::SimpleSetup &setup, const ob::PlannerPtr &planner, bool batchShortcut, double timeLimit,
         const rastercheck::ompl::StateValidityChecker &oracle, std::uint_fast32_t runSeed, const std::string &label,
         Tally &tally)
{
    seed(runSeed);
    setup.clear();
    rastercheck::ompl::resetCheckedStates(setup);
    setup.setPlanner(planner);
    const auto *staged = dynamic_cast<const StagedBackend *>(&oracle.getCheckerPtr()->backend());
    const std::uint64_t callsBefore = staged ? staged->executorCounts().calls : 0;
    const auto begin = std::chrono::steady_clock::now();
    const ob::PlannerStatus status = rastercheck::ompl::solveWithin(setup, timeLimit);
    const bool solved = status == ob::PlannerStatus::EXACT_SOLUTION;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    if (staged && setup.getStateValidityChecker().get() == &oracle)  // the planner ran on the oracle's checker
        tally.stagedCalls.push_back(static_cast<double>(staged->executorCounts().calls - callsBefore));
    ++tally.attempts;
    tally.states.push_back(static_cast<double>(rastercheck::ompl::checkedStates(setup)));
    if (!solved || !collisionFree(setup.getSolutionPath(), oracle))
    {
        // Named on stderr, before the problem's "done" line: which problems a planner misses.
        std::fprintf(stderr, "  %s: %s\n", label.c_str(), solved ? "colliding path" : status.asString().c_str());
        tally.colliding += solved ? 1 : 0;
        tally.times.push_back(timeLimit);
        tally.simplifiedTimes.push_back(timeLimit + 1.0);
        return;
    }
    ++tally.solved;
    if (const auto *batch = dynamic_cast<const planners::BatchRRTConnect *>(planner.get()))
        std::fprintf(stderr, "  %s: %.4f s, %.0f states, %u candidates (%u rejected)\n", label.c_str(), seconds,
                     tally.states.back(), batch->getCandidateCount(), batch->getRejectedCandidateCount());
    else
        std::fprintf(stderr, "  %s: %.4f s, %.0f states\n", label.c_str(), seconds, tally.states.back());
    tally.solvedWithinOneSecond += seconds <= 1.0 ? 1 : 0;
    tally.times.push_back(seconds);
    og::PathGeometric &path = setup.getSolutionPath();
    tally.lengths.push_back(path.length());
    const auto simplifyBegin = std::chrono::steady_clock::now();
    if (batchShortcut)
        planners::BatchShortcutter(setup.getSpaceInformation())
            .shortcut(path, ob::timedPlannerTerminationCondition(1.0));
    else
        setup.simplifySolution(1.0);
    const double simplifySeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - simplifyBegin).count();
    tally.simplifiedTimes.push_back(seconds + simplifySeconds);
    tally.simplifiedLengths.push_back(path.length());
    tally.simplifiedColliding += collisionFree(path, oracle) ? 0 : 1;
}

}  // namespace

int main(int argc, char **argv)
{
    const std::vector<std::string> robots = bench::splitList(argc > 1 ? argv[1] : "panda,ur5,fetch");
    const int problemsPerScenario = argc > 2 ? std::atoi(argv[2]) : 5;
    const double timeLimit = argc > 3 ? std::atof(argv[3]) : 2.0;
    const unsigned int batchSize = argc > 4 ? static_cast<unsigned int>(std::atoi(argv[4])) : 8u;
    const int firstProblem = argc > 5 ? std::atoi(argv[5]) : 1;
    const std::vector<std::string> chosen = bench::splitList(argc > 6 ? argv[6] : "fcl,rrtconnect,batch,eager");
    const unsigned int lazySamples = argc > 7 ? static_cast<unsigned int>(std::atoi(argv[7])) : 2u;
    const double rangeFraction = argc > 8 ? std::atof(argv[8]) : 0.0;
    const unsigned int lazyLimit = argc > 9 ? static_cast<unsigned int>(std::atoi(argv[9])) : 300u;
    const BackendChoice backend = parseBackendChoice(argc > 10 ? argv[10] : "cpu");
    // Certified edges' intervals: "bisection" (the library's default), "clearance" (exact
    // clearances) or "hullbound" (the hulls' lower bounds, ClearanceMeasure::HullBound).
    const std::string sizing = argc > 12 ? argv[12] : "bisection";
    if (sizing != "clearance" && sizing != "hullbound" && sizing != "bisection")
    {
        std::fprintf(stderr, "edge sizing must be clearance, hullbound or bisection, got '%s'\n", sizing.c_str());
        return 2;
    }
    const int checkerThreads = argc > 11 ? std::atoi(argv[11]) : 1;
    const double margin = argc > 13 ? std::atof(argv[13]) : 0.0;
    const std::size_t deviceBatch = argc > 14 ? static_cast<std::size_t>(std::atol(argv[14])) : 32u;
    const int decideTogether = argc > 15 ? std::atoi(argv[15]) : -1;
    auto runs = [&](const std::string &name) { return std::find(chosen.begin(), chosen.end(), name) != chosen.end(); };
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_ERROR);
    const std::string root = bench::sharedDataOrExit();
    const std::vector<std::string> labels{"FCL RRTConnect (discrete edges)", "RRTConnect (rastercheck, certified)",
                                          "BatchRRTConnect (rastercheck, certified, lazy)",
                                          "BatchRRTConnect (rastercheck, certified, eager)"};

    std::printf(
        "Problems %d..%d of each of the 7 MotionBenchMaker scenarios (OMPL.app problems: that many "
        "seeded runs), time limit %g s; rastercheck's checker: backend %s, threads %d (0: every core), FCL one core; "
        "BatchRRTConnect batch_size %u, lazy_samples %u, lazy_limit %u; certified edges sized by %s, margin %s; range "
        "%s.\n",
        firstProblem, firstProblem + problemsPerScenario - 1, timeLimit, argc > 10 ? argv[10] : "cpu", checkerThreads,
        batchSize, lazySamples, lazyLimit, sizing.c_str(),
        margin > 0.0 ? std::to_string(margin).c_str() : "the default (a tenth of the robot's size)",
        rangeFraction > 0.0 ? (std::to_string(rangeFraction) + " of the maximum extent, every planner").c_str()
                            : "each planner's default");
    std::printf(
        "Solved = exact solution whose path the exact oracle accepts at 10x the planner's resolution. "
        "Times: median and p95 over all runs, unsolved ones at the limit (+1 s with simplification).\n\n");
    for (const std::string &robotName : robots)
    {
        std::map<std::string, Tally> tallies;
        int problemsRun = 0, invalidEnds = 0;  // runs, and those whose start or goal collides
        std::vector<double> setupSeconds;      // building each problem's setup (its checker)
        rastercheck::device::ExecutorCounts stagePasses;  // the staged backend's (cuda, host-stages), all runs
        // One problem: both setups, the three planners with one seed.
        auto benchProblem = [&](const Problem &problem, const std::function<void(og::SimpleSetup &)> &setStartAndGoal,
                                std::uint_fast32_t runSeed)
        {
            rastercheck::ompl::SetupOptions options;  // certified edges: the default
            options.checker.backend = backend;
            options.checker.threads = checkerThreads;
            options.certified.margin = margin;
            options.certified.sizeByClearance = sizing != "bisection";
            options.certified.clearanceMeasure =
                sizing == "hullbound" ? ClearanceMeasure::HullBound : ClearanceMeasure::Exact;
            if (backend == BackendChoice::Cuda || backend == BackendChoice::HostStages)
                options.checker.minDeviceBatch = deviceBatch;
            og::SimpleSetupPtr ours;
            setupSeconds.push_back(
                bench::seconds([&] { ours = rastercheck::ompl::makeSimpleSetup(problem, options); }));
            setStartAndGoal(*ours);
            const rastercheck::ompl::StateValidityCheckerPtr oracle = rastercheck::ompl::getStateValidityChecker(*ours);
            // MotionBenchMaker's problems were made with other collision models: a start or goal
            // that the meshes put in collision is unsolvable for every planner on an exact checker.
            ++problemsRun;
            const ob::ProblemDefinitionPtr &pdef = ours->getProblemDefinition();
            const auto *goalState = dynamic_cast<const ob::GoalState *>(pdef->getGoal().get());
            if (!oracle->isValid(pdef->getStartState(0)) || (goalState && !oracle->isValid(goalState->getState())))
            {
                ++invalidEnds;
                std::fprintf(stderr, "  start or goal in collision (exact check): no planner can solve it\n");
            }

            rastercheck::ompl::SetupOptions fclOptions = options;
            fclOptions.edges = rastercheck::ompl::EdgeChecking::Discrete;
            og::SimpleSetupPtr fcl = rastercheck::ompl::makeSimpleSetup(problem, fclOptions);
            setStartAndGoal(*fcl);
            fcl->setStateValidityChecker(std::make_shared<bench::FclStateValidityChecker>(
                fcl->getSpaceInformation(), oracle->getStateMappingPtr(), oracle->getCheckerPtr()));
            // What the setups make on their first setup() (the space information's parts, the
            // simplifier) is made here, before the seeded runs: else the first run of a setup draws
            // seeds for them, and a planner's seeds would depend on which planners ran before it.
            ours->setup();
            fcl->setup();

            // Range 0 leaves a planner its default.
            const double range = rangeFraction * ours->getStateSpace()->getMaximumExtent();
            auto rrtConnect = [&](const og::SimpleSetupPtr &setup)
            {
                auto planner = std::make_shared<og::RRTConnect>(setup->getSpaceInformation());
                planner->setRange(range);
                return planner;
            };
            auto batchRrtConnect = [&](bool lazy)
            {
                auto planner = std::make_shared<planners::BatchRRTConnect>(ours->getSpaceInformation());
                planner->setBatchSize(batchSize);
                planner->setLazy(lazy);
                planner->setLazySamples(lazySamples);
                planner->setLazyLimit(lazyLimit);
                planner->setDecideTogether(decideTogether);
                planner->setRange(range);
                return planner;
            };
            if (runs("fcl"))
                run(*fcl, rrtConnect(fcl), false, timeLimit, *oracle, runSeed, labels[0], tallies[labels[0]]);
            if (runs("rrtconnect"))
                run(*ours, rrtConnect(ours), false, timeLimit, *oracle, runSeed, labels[1], tallies[labels[1]]);
            if (runs("batch"))
                run(*ours, batchRrtConnect(true), true, timeLimit, *oracle, runSeed, labels[2], tallies[labels[2]]);
            if (runs("eager"))
                run(*ours, batchRrtConnect(false), true, timeLimit, *oracle, runSeed, labels[3], tallies[labels[3]]);
            if (const auto *staged = dynamic_cast<const StagedBackend *>(&oracle->getCheckerPtr()->backend()))
                stagePasses += staged->executorCounts();
        };

        if (robotName == "crane")
        {
            // The crane lifting a load over the plant (robots/, examples/crane_lift's problem).
            const std::string robots = RASTERCHECK_ROBOTS_DIR;
            ProblemSource source;
            source.urdfPath = robots + "/crane/crane.urdf";
            source.srdfPath = robots + "/crane/crane.srdf";
            source.scenePath = robots + "/sites/plant.yaml";
            const Problem problem = loadProblem(source);
            const MotionPlanRequest lift = loadMoveItRequest(robots + "/sites/plant_lift.yaml");
            for (int index = firstProblem; index < firstProblem + problemsPerScenario; ++index)
            {
                benchProblem(
                    problem, [&](og::SimpleSetup &setup) { rastercheck::ompl::setStartAndGoal(setup, lift); },
                    static_cast<std::uint_fast32_t>(1000 * index + 1));
                std::fprintf(stderr, "crane run %d done\n", index);
            }
        }
        else if (robotName.rfind("omplapp:", 0) == 0)
        {
            const char *folder = std::getenv("RASTERCHECK_OMPLAPP");
            if (!folder)
            {
                std::printf("### %s: skipped (set RASTERCHECK_OMPLAPP to OMPL.app's resources/3D)\n\n",
                            robotName.c_str());
                continue;
            }
            ProblemSource source;
            source.cfgPath = std::string(folder) + "/" + robotName.substr(8) + ".cfg";
            const Problem problem = loadProblem(source);
            for (int index = firstProblem; index < firstProblem + problemsPerScenario; ++index)
            {
                benchProblem(
                    problem,
                    [&](og::SimpleSetup &setup) { rastercheck::ompl::setStartAndGoal(setup, *problem.omplApp); },
                    static_cast<std::uint_fast32_t>(1000 * index + 1));
                std::fprintf(stderr, "%s run %d done\n", robotName.c_str(), index);
            }
        }
        else
        {
            const RobotModelConstPtr robot = bench::loadMbmRobot(root, robotName);
            for (const std::string &scenario : bench::mbmScenarios())
                for (int index = firstProblem; index < firstProblem + problemsPerScenario; ++index)
                {
                    Problem problem;
                    problem.robot = robot;
                    problem.scene = loadMoveItScene(bench::mbmProblemPath(root, robotName, scenario, index, "scene"));
                    const MotionPlanRequest request =
                        loadMoveItRequest(bench::mbmProblemPath(root, robotName, scenario, index, "request"));
                    benchProblem(
                        problem, [&](og::SimpleSetup &setup) { rastercheck::ompl::setStartAndGoal(setup, request); },
                        static_cast<std::uint_fast32_t>(1000 * index + 1));
                    std::fprintf(stderr, "%s %s %04d done\n", robotName.c_str(), scenario.c_str(), index);
                }
        }

        std::printf("### %s (%zu runs)\n\n", robotName.c_str(),
                    tallies[labels[runs("fcl")          ? 0
                                   : runs("rrtconnect") ? 1
                                   : runs("batch")      ? 2
                                                        : 3]]
                        .times.size());
        std::printf(
            "| planner | solved | within 1 s | colliding | median s | p95 s | median s, simplified | p95 s, simplified "
            "| "
            "median length raw -> simplified | median states checked |\n");
        std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for (const std::string &label : labels)
        {
            const Tally &t = tallies[label];
            std::printf(
                "| %s | %d/%d | %.1f %% | %d (+%d simplified) | %.4f | %.4f | %.4f | %.4f | %.2f -> %.2f | %.0f |\n",
                label.c_str(), t.solved, t.attempts, t.attempts ? 100.0 * t.solvedWithinOneSecond / t.attempts : 0.0,
                t.colliding, t.simplifiedColliding, quantile(t.times, 0.5), quantile(t.times, 0.95),
                quantile(t.simplifiedTimes, 0.5), quantile(t.simplifiedTimes, 0.95), quantile(t.lengths, 0.5),
                quantile(t.simplifiedLengths, 0.5), label == labels[0] ? 0.0 : quantile(t.states, 0.5));
        }
        std::printf(
            "\nStart or goal state in collision for the exact checker (unsolvable for every planner that "
            "checks the meshes exactly): %d of %d runs.\n",
            invalidEnds, problemsRun);
        const double rrt = quantile(tallies[labels[1]].times, 0.5),
                     batchMedian = quantile(tallies[labels[2]].times, 0.5);
        std::printf(
            "\nMedian solve time: BatchRRTConnect (lazy) %.2fx faster than RRTConnect on the same checker, "
            "%.2fx faster than FCL RRTConnect, %.2fx faster than BatchRRTConnect eager.\n\n",
            rrt / batchMedian, quantile(tallies[labels[0]].times, 0.5) / batchMedian,
            quantile(tallies[labels[3]].times, 0.5) / batchMedian);
        // Checkers of one robot share its part (CollisionModel): the first build pays for it.
        if (!setupSeconds.empty())
        {
            const std::vector<double> later(setupSeconds.begin() + 1, setupSeconds.end());
            std::printf(
                "Setups built (the checker with them): %zu; the first %.1f ms, the others median %.1f ms, "
                "max %.1f ms.\n\n",
                setupSeconds.size(), 1e3 * setupSeconds.front(), later.empty() ? 0.0 : 1e3 * quantile(later, 0.5),
                later.empty() ? 0.0 : 1e3 * *std::max_element(later.begin(), later.end()));
        }
        // A solve's calls on the stages come one after another: on a device each costs at least a
        // call's fixed latency, whatever its size.
        for (const std::string &label : labels)
        {
            const std::vector<double> &calls = tallies[label].stagedCalls;
            if (!calls.empty())
                std::printf("%s: calls on the staged backend per solve: median %.0f, p95 %.0f, max %.0f.\n\n",
                            label.c_str(), quantile(calls, 0.5), quantile(calls, 0.95),
                            *std::max_element(calls.begin(), calls.end()));
        }
        // What the batches cost a device in fixed costs: a chunk run again (a count outgrew what
        // the executor's earlier chunks needed) is a second pass and more waits.
        if (stagePasses.calls > 0)
            std::printf(
                "Staged backend, every run's checker: %llu calls, %llu chunks, %llu run again, %.2f waits and %.1f "
                "launches a call.\n\n",
                stagePasses.calls, stagePasses.chunks, stagePasses.reruns,
                static_cast<double>(stagePasses.synchronizations) / static_cast<double>(stagePasses.calls),
                static_cast<double>(stagePasses.launches) / static_cast<double>(stagePasses.calls));
    }
    return 0;
}
