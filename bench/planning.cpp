// Planning with RRT-Connect on the Panda MotionBenchMaker problems: rastercheck's validity checker and
// batched motion validator against FCL (BVHModel<OBBRSS>, as MoveIt and OMPL.app use it) with OMPL's
// DiscreteMotionValidator. Same state space, edge resolution, planner settings and time limit, in
// one run, problem by problem. Prints per scenario and overall: success rates, median solve times
// and their ratio (rastercheck / FCL; below 1 means rastercheck plans faster). Each run seeds OMPL's
// random numbers the same for every checker, so they grow the same trees and the times differ by
// the checking (and the motion validator's order of work) alone.
//
// usage: rastercheck_bench_planning [problems_per_scenario=3] [time_limit_s=5] [runs_per_problem=1]
//                                   [modes=safe,exact] [threads=1]
// A mode is a collision mode, optionally with the edge checking after a '+': "safe+certified" plans
// with CertifiedMotionValidator (collision-free edges at every point) instead of the batched
// discrete one.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>

#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "BenchSupport.h"
#include "FclValidity.h"
#include "Reference.h"
#include "rastercheck/core/Statistics.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/Setup.h"

using namespace rastercheck;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace
{

struct Outcome
{
    bool solved = false;
    double seconds = 0.0;
    bool recheckValid = true;
    /** \brief For a colliding path: the planning checker calls the first colliding dense state valid
        (a checker miss rather than a resolution miss between the planner's samples). */
    bool checkerMissed = false;
    double length = 0.0;  ///< of the solution path (0 when unsolved): equal lengths mean equal trees
};

/** \brief One planning run. Every RNG OMPL creates from here on (the planner's, its sampler's)
    draws its seed from \a seed, so two checkers given the same seed grow the same tree (their
    verdicts are the same) and the difference in time is the checkers'. */
Outcome solve(og::SimpleSetup &setup, double timeLimit, const rastercheck::ompl::StateValidityChecker &oracle,
              std::uint_fast32_t seed)
{
    // OMPL logs an error when the seed changes after RNGs exist; here, resetting it is the point.
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_NONE);
    ::ompl::RNG::setSeed(seed);
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_WARN);
    setup.clear();
    setup.setPlanner(std::make_shared<og::RRTConnect>(setup.getSpaceInformation()));
    const ob::PlannerStatus status = rastercheck::ompl::solveWithin(setup, timeLimit);
    Outcome outcome;
    outcome.solved = status == ob::PlannerStatus::EXACT_SOLUTION;
    outcome.seconds = setup.getLastPlanComputationTime();
    outcome.length = outcome.solved ? setup.getSolutionPath().length() : 0.0;
    if (outcome.solved)
    {
        CollisionRequest exact;
        exact.mode = CollisionMode::Exact;
        const rastercheck::ompl::PathCheckResult recheck = rastercheck::ompl::checkPathDensely(
            setup.getSolutionPath(), oracle.getStateMapping(), oracle.getChecker(), exact, 10);
        outcome.recheckValid = recheck.valid;
        if (!recheck.valid)
        {
            // Ask the planning checker (rastercheck or FCL) about the colliding state itself.
            ob::ScopedState<> state(setup.getStateSpace());
            oracle.getStateMapping().fromConfiguration(recheck.configuration, state.get());
            outcome.checkerMissed = setup.getSpaceInformation()->isValid(state.get());
        }
    }
    return outcome;
}

struct Tally
{
    int attempts = 0;
    int solved = 0;
    int colliding = 0;
    int checkerMissed = 0;
    std::vector<double> times;  ///< solve times of the solved runs (s)
    std::vector<double> all;    ///< every run's time (s), unsolved at the time limit

    void add(const Outcome &outcome)
    {
        ++attempts;
        all.push_back(outcome.seconds);
        if (!outcome.solved)
            return;
        if (!outcome.recheckValid)
        {
            ++colliding;
            checkerMissed += outcome.checkerMissed ? 1 : 0;
            return;
        }
        ++solved;
        times.push_back(outcome.seconds);
    }
};

/** \brief "solved/attempts", then "(c colliding, m by the checker)" when paths failed the re-check. */
std::string solvedText(const Tally &t)
{
    std::string text = std::to_string(t.solved) + "/" + std::to_string(t.attempts);
    if (t.colliding > 0)
        text +=
            " (" + std::to_string(t.colliding) + " colliding, " + std::to_string(t.checkerMissed) + " by the checker)";
    return text;
}

}  // namespace

int main(int argc, char **argv)
{
    const int problemsPerScenario = argc > 1 ? std::atoi(argv[1]) : 3;
    const double timeLimit = argc > 2 ? std::atof(argv[2]) : 5.0;
    const int runsPerProblem = argc > 3 ? std::atoi(argv[3]) : 1;
    const std::vector<std::string> modes = bench::splitList(argc > 4 ? argv[4] : "safe,exact");
    const int threads = argc > 5 ? std::atoi(argv[5]) : 1;
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_WARN);
    const std::string root = bench::sharedDataOrExit();
    const RobotModelConstPtr robot = bench::loadMbmRobot(root, "panda");

    // tallies[mode][scenario]; mode "fcl" is the reference.
    std::map<std::string, std::map<std::string, Tally>> tallies;
    std::map<std::string, int> sameTree;  // runs whose outcome and path length equal FCL's
    for (const std::string &scenario : bench::mbmScenarios())
        for (int index = 1; index <= problemsPerScenario; ++index)
        {
            Problem problem;
            problem.robot = robot;
            problem.scene = loadMoveItScene(bench::mbmProblemPath(root, "panda", scenario, index, "scene"));
            const MotionPlanRequest request =
                loadMoveItRequest(bench::mbmProblemPath(root, "panda", scenario, index, "request"));

            std::map<std::string, og::SimpleSetupPtr> setups;
            for (const std::string &mode : modes)
            {
                // "safe" or "safe+certified": the mode, then the edge checking (batched by default).
                const std::size_t plus = mode.find('+');
                rastercheck::ompl::SetupOptions options;
                options.request.mode = parseCollisionMode(mode.substr(0, plus));
                if (plus != std::string::npos)
                    options.edges = rastercheck::ompl::parseEdgeChecking(mode.substr(plus + 1));
                options.checker.backend = BackendChoice::Cpu;
                options.checker.threads = threads;
                setups[mode] = rastercheck::ompl::makeSimpleSetup(problem, options);
                rastercheck::ompl::setStartAndGoal(*setups[mode], request);
            }
            // FCL: a setup of its own (same robot, scene, space and resolution), OMPL's default
            // DiscreteMotionValidator, the FCL checker.
            rastercheck::ompl::SetupOptions fclOptions;
            fclOptions.edges = rastercheck::ompl::EdgeChecking::Discrete;
            fclOptions.checker.backend = BackendChoice::Cpu;
            og::SimpleSetupPtr fcl = rastercheck::ompl::makeSimpleSetup(problem, fclOptions);
            rastercheck::ompl::setStartAndGoal(*fcl, request);
            const rastercheck::ompl::StateValidityCheckerPtr oracle = rastercheck::ompl::getStateValidityChecker(*fcl);
            fcl->setStateValidityChecker(std::make_shared<bench::FclStateValidityChecker>(
                fcl->getSpaceInformation(), oracle->getStateMappingPtr(), oracle->getCheckerPtr()));
            // What a setup makes on its first setup() is made before the seeded runs, so that run k
            // of every checker draws the same seeds (bench/planners.cpp).
            for (auto &entry : setups)
                entry.second->setup();
            fcl->setup();

            for (int run = 0; run < runsPerProblem; ++run)
            {
                const std::uint_fast32_t seed = static_cast<std::uint_fast32_t>(1000 * index + run + 1);
                const Outcome reference = solve(*fcl, timeLimit, *oracle, seed);
                tallies["fcl"][scenario].add(reference);
                for (const std::string &mode : modes)
                {
                    const Outcome outcome = solve(*setups[mode], timeLimit,
                                                  *rastercheck::ompl::getStateValidityChecker(*setups[mode]), seed);
                    tallies[mode][scenario].add(outcome);
                    sameTree[mode] += outcome.length == reference.length ? 1 : 0;
                }
            }
            std::fprintf(stderr, "%s %04d done\n", scenario.c_str(), index);
        }

    std::printf(
        "Panda MotionBenchMaker, RRT-Connect: %d problem(s) per scenario x %d run(s), time limit %g s, "
        "longest valid segment fraction 0.01; rastercheck batches on %d thread(s), FCL on 1.\n"
        "Solved = exact solution whose path the exact oracle accepts at 10x the planner's resolution; a\n"
        "colliding path is unsolved ('by the checker': the planning checker itself calls the colliding\n"
        "state valid; otherwise the planner's resolution stepped over the obstacle). Time ratio: median of\n"
        "all runs (unsolved at the limit) over FCL's. Run k of a problem seeds OMPL alike for every checker.\n\n",
        problemsPerScenario, runsPerProblem, timeLimit, threads);
    std::printf("| scenario | FCL solved | FCL median s |");
    for (const std::string &mode : modes)
        std::printf(" %s solved | %s median s | %s / FCL |", mode.c_str(), mode.c_str(), mode.c_str());
    std::printf("\n|---|---:|---:|");
    for (std::size_t m = 0; m < modes.size(); ++m)
        std::printf("---:|---:|---:|");
    std::printf("\n");
    auto row = [&](const std::string &label, const std::map<std::string, Tally> &byMode)
    {
        const Tally &f = byMode.at("fcl");
        std::printf("| %s | %s | %.4f |", label.c_str(), solvedText(f).c_str(), median(f.times));
        for (const std::string &mode : modes)
        {
            const Tally &t = byMode.at(mode);
            // Ratio of medians over every run (unsolved runs count at their time), so a mode that
            // solves less is not flattered by the runs it dropped.
            std::printf(" %s | %.4f | %.2f |", solvedText(t).c_str(), median(t.times), median(t.all) / median(f.all));
        }
        std::printf("\n");
    };
    std::map<std::string, Tally> overall;
    for (const std::string &scenario : bench::mbmScenarios())
    {
        std::map<std::string, Tally> byMode;
        for (auto &[mode, perScenario] : tallies)
        {
            const Tally &t = perScenario[scenario];
            byMode[mode] = t;
            Tally &o = overall[mode];
            o.attempts += t.attempts;
            o.solved += t.solved;
            o.colliding += t.colliding;
            o.times.insert(o.times.end(), t.times.begin(), t.times.end());
            o.all.insert(o.all.end(), t.all.begin(), t.all.end());
        }
        row(scenario, byMode);
    }
    row("**overall**", overall);
    std::printf("\nRuns whose outcome and path length equal FCL's (the same tree, so the times compare checkers):");
    for (const std::string &mode : modes)
        std::printf(" %s %d/%d", mode.c_str(), sameTree[mode], overall[mode].attempts);
    std::printf("\n");
    return 0;
}
