// rastercheck plan: OMPL planners on a problem, through ompl::tools::Benchmark (so the log is what
// ompl_benchmark_statistics reads), with every solution path re-checked densely by the exact oracle.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numeric>
#include <sstream>

#include <CLI/CLI.hpp>

#include <ompl/base/goals/GoalState.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/tools/benchmark/Benchmark.h>
#include <ompl/util/RandomNumbers.h>

#include "Commands.h"
#include "PlannedPaths.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/core/Statistics.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/Planners.h"
#include "rastercheck/ompl/Setup.h"

namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;
namespace ot = ::ompl::tools;

namespace rastercheck::cli
{
namespace
{
// Run properties this command adds to the log (OMPL's convention: the last word is the SQL type).
const char *const kRecheckValid = "exact recheck collision free BOOLEAN";
const char *const kRecheckStates = "exact recheck states INTEGER";
// States the checker decided in the run (single states and edge states; not the re-check's).
const char *const kStatesChecked = "states checked INTEGER";

/** \brief OMPL's Benchmark simplifies every run's solution with the setup's one PathSimplifier, whose
    random numbers would go on from the runs before it: a run's simplified path and the states it
    checks would depend on whether the planner before it (in this process) solved in time. Reseeded
    before each run, they depend on the seed alone, so a sweep's runs agree wherever they ran. */
class ReseededPathSimplifier : public og::PathSimplifier
{
public:
    using og::PathSimplifier::PathSimplifier;
    void reseed(std::uint_fast32_t seed) { rng_.setLocalSeed(seed); }
};

struct PlanOptions
{
    ProblemArguments problem;
    std::string requestPath;
    std::vector<std::string> planners;
    std::vector<std::string> parameters;  ///< name.param=value
    std::vector<std::string> held;        ///< coordinate=value
    int runs = 0;
    double timeLimit = 0.0;
    double memoryLimit = 0.0;
    CheckingArguments checking;
    double boundsTolerance = kDefaultBoundsTolerance;
    double segmentFraction = 0.01;
    std::string edges = "auto";
    double margin = 0.0;
    unsigned int rakeWidth = ompl::CertifiedMotionOptions{}.rakeWidth;
    unsigned int recheckFactor = 10;
    std::string logPath;
    std::string pathOut;
    long long seed = -1;
    bool noSimplify = false;
};

std::pair<std::string, std::string> splitAssignment(const std::string &text, const std::string &option)
{
    const std::size_t equals = text.find('=');
    if (equals == std::string::npos || equals == 0)
        throw ConfigurationError(option + " expects NAME=VALUE, got '" + text + "'");
    return {text.substr(0, equals), text.substr(equals + 1)};
}

double parseNumber(const std::string &text, const std::string &what)
{
    std::istringstream in(text);
    double value = 0.0;
    in >> value;
    if (!in || !in.eof() || !std::isfinite(value))
        throw ConfigurationError(what + ": '" + text + "' is not a finite number");
    return value;
}

double mean(const std::vector<double> &values)
{
    return values.empty() ? std::nan("") : std::accumulate(values.begin(), values.end(), 0.0) / values.size();
}

double property(const ot::Benchmark::RunProperties &run, const std::string &key)
{
    const auto found = run.find(key);
    if (found == run.end())
        return std::nan("");
    try
    {
        return std::stod(found->second);
    }
    catch (const std::exception &)
    {
        return std::nan("");
    }
}

bool flag(const ot::Benchmark::RunProperties &run, const std::string &key)
{
    const auto found = run.find(key);
    return found != run.end() && (found->second == "1" || found->second == "true");
}

/** \brief Checks the start and goal once before benchmarking: a planner cannot fix an invalid one. */
void reportInvalidEndpoints(og::SimpleSetup &setup, const ompl::StateValidityChecker &checker)
{
    auto describe = [&](const char *what, const ob::State *state)
    {
        Contact contact;
        if (!checker.isValid(state, contact))
            std::cerr << "rastercheck: warning: the " << what << " state is invalid: "
                      << (contact.kind == Contact::Kind::OutOfBounds ? std::string("outside the bounds")
                                                                     : checker.getChecker().describe(contact))
                      << '\n';
    };
    describe("start", setup.getProblemDefinition()->getStartState(0));
    if (auto goal = std::dynamic_pointer_cast<ob::GoalState>(setup.getGoal()))
        describe("goal", goal->getState());
}

int runPlan(const PlanOptions &options)
{
    if (options.seed >= 0)
        ::ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(options.seed));
    if (!options.problem.cfgPath.empty() && !options.requestPath.empty())
        throw ConfigurationError(
            "--request applies to --robot/--scene problems; an OMPL.app .cfg has its own start and goal");
    if (options.problem.cfgPath.empty() && options.requestPath.empty())
        throw ConfigurationError("a --robot/--scene problem needs --request request.yaml (start and goal)");
    const Problem problem = loadProblem(options.problem.source());

    ompl::SetupOptions setupOptions;
    setupOptions.checker = options.checking.checker();
    setupOptions.request = options.checking.request();
    setupOptions.boundsTolerance = options.boundsTolerance;
    setupOptions.longestValidSegmentFraction = options.segmentFraction;
    setupOptions.edges = ompl::parseEdgeChecking(options.edges);
    // What "auto" resolves to (certified edges unless raster mode cannot certify), for the log and messages.
    const std::string edges = options.edges != "auto"    ? options.edges
                              : options.checking.mode == "raster" ? "batched"
                                                         : "certified";
    setupOptions.certified.margin = options.margin;
    setupOptions.certified.rakeWidth = options.rakeWidth;
    for (const std::string &text : options.held)
    {
        const auto [name, value] = splitAssignment(text, "--hold");
        setupOptions.heldCoordinates[name] = parseNumber(value, "--hold " + name);
    }
    og::SimpleSetupPtr setup = ompl::makeSimpleSetup(problem, setupOptions);
    const ompl::StateValidityCheckerPtr checker = ompl::getStateValidityChecker(*setup);
    std::string experiment;
    if (problem.omplApp)
    {
        ompl::setStartAndGoal(*setup, *problem.omplApp);
        experiment = problem.omplApp->name.empty() ? stemOf(options.problem.cfgPath) : problem.omplApp->name;
        ompl::setObjective(*setup, *problem.omplApp);
    }
    else
    {
        ompl::setStartAndGoal(*setup, loadMoveItRequest(options.requestPath));
        experiment = stemOf(options.problem.scenePath) + "_" + stemOf(options.requestPath);
    }
    reportInvalidEndpoints(*setup, *checker);

    // Planners: --planner, else the .cfg's [planner] section, else RRT-Connect.
    std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> planners;
    for (const std::string &name : options.planners)
        planners.push_back({name, {}});
    if (planners.empty() && problem.omplApp)
        planners = problem.omplApp->planners;
    if (planners.empty())
        planners.push_back({"rrtconnect", {}});
    for (const std::string &text : options.parameters)
    {
        const auto [key, value] = splitAssignment(text, "--param");
        const std::size_t dot = key.find('.');
        if (dot == std::string::npos)
            throw ConfigurationError("--param expects PLANNER.PARAM=VALUE, got '" + text + "'");
        bool applied = false;
        for (auto &planner : planners)
            if (planner.first == key.substr(0, dot))
            {
                planner.second.emplace_back(key.substr(dot + 1), value);
                applied = true;
            }
        if (!applied)
            throw ConfigurationError("--param " + text + ": no planner '" + key.substr(0, dot) + "' is run");
    }

    const int runs = options.runs > 0
                         ? options.runs
                         : (problem.omplApp && problem.omplApp->runCount > 0 ? problem.omplApp->runCount : 10);
    const double timeLimit =
        options.timeLimit > 0 ? options.timeLimit
                              : (problem.omplApp && problem.omplApp->timeLimit > 0 ? problem.omplApp->timeLimit : 10.0);
    const double memoryLimit =
        options.memoryLimit > 0
            ? options.memoryLimit
            : (problem.omplApp && problem.omplApp->memoryLimit > 0 ? problem.omplApp->memoryLimit : 4096.0);

    ot::Benchmark benchmark(*setup, experiment);
    std::vector<std::string> labels;
    for (const auto &[name, parameters] : planners)
    {
        ob::PlannerPtr planner = ompl::allocatePlanner(name, setup->getSpaceInformation());
        ompl::setPlannerParameters(*planner, parameters);
        if (!options.pathOut.empty())
            planner = std::make_shared<RawPathRecorder>(planner);
        benchmark.addPlanner(planner);
        labels.push_back(name);
    }
    benchmark.addExperimentParameter("collision_mode", "ENUM", options.checking.mode);
    benchmark.addExperimentParameter("recheck_factor", "INTEGER", std::to_string(options.recheckFactor));
    benchmark.addExperimentParameter("edge_checking", "ENUM", edges);

    CollisionRequest exact = setupOptions.request;
    exact.mode = CollisionMode::Exact;
    std::unique_ptr<PathFolder> pathFolder;
    if (!options.pathOut.empty())
        pathFolder = std::make_unique<PathFolder>(options.pathOut, checker->getStateMapping(), checker->getChecker(),
                                                  exact, options.recheckFactor);
    int collidingPaths = 0;
    int runIndex = 0;
    ob::PlannerPtr previous;
    std::shared_ptr<ReseededPathSimplifier> simplifier;
    benchmark.setPreRunEvent(
        [&](const ob::PlannerPtr &)
        {
            ompl::resetCheckedStates(*setup);
            // After the benchmark's setup, which makes the setup's own simplifier.
            if (!simplifier)
            {
                const ob::ProblemDefinitionPtr &problemDefinition = setup->getProblemDefinition();
                simplifier =
                    std::make_shared<ReseededPathSimplifier>(setup->getSpaceInformation(), problemDefinition->getGoal(),
                                                             problemDefinition->getOptimizationObjective());
                setup->getPathSimplifier() = simplifier;
            }
            simplifier->reseed(static_cast<std::uint_fast32_t>(options.seed >= 0 ? options.seed : 0));
        });
    benchmark.setPostRunEvent(
        [&](const ob::PlannerPtr &planner, ot::Benchmark::RunProperties &run)
        {
            if (planner != previous)
            {
                previous = planner;
                runIndex = 0;
            }
            const int thisRun = runIndex++;
            run[kStatesChecked] = std::to_string(ompl::checkedStates(*setup));
            const ob::ProblemDefinitionPtr &pdef = planner->getProblemDefinition();
            if (!pdef->hasSolution())
                return;
            auto path = std::dynamic_pointer_cast<og::PathGeometric>(pdef->getSolutionPath());
            if (!path)
                return;
            const ompl::PathCheckResult result = ompl::checkPathDensely(
                *path, checker->getStateMapping(), checker->getChecker(), exact, options.recheckFactor);
            run[kRecheckValid] = result.valid ? "1" : "0";
            run[kRecheckStates] = std::to_string(result.statesChecked);
            if (pathFolder)
                pathFolder->addRun(*planner, thisRun, *path, result, !options.noSimplify);
            if (!result.valid)
            {
                ++collidingPaths;
                std::cerr << "rastercheck: ERROR: solution path of " << planner->getName() << " run " << thisRun
                          << " COLLIDES (exact oracle, " << options.recheckFactor
                          << "x the planner's resolution): segment " << result.segment << " at t = " << result.time
                          << ": "
                          << (result.contact.kind == Contact::Kind::OutOfBounds
                                  ? std::string("outside the bounds")
                                  : checker->getChecker().describe(result.contact))
                          << (checker->getChecker().isValid(result.configuration, setupOptions.request)
                                  ? " [the planning checker calls this state valid: a checker false negative]"
                                  : " [the planning checker agrees: the planner's resolution stepped over it]")
                          << std::endl;
            }
        });

    ot::Benchmark::Request request(timeLimit, memoryLimit, static_cast<unsigned int>(runs), 0.05, false, false,
                                   !options.noSimplify);
    // The margin in use (--margin or its default, a tenth of the robot's size) and the first batch:
    // they set how finely certified edges are sampled, and with it much of a solve's time.
    std::ostringstream margin;
    if (const auto *certified = dynamic_cast<const ompl::CertifiedMotionValidator *>(
            setup->getSpaceInformation()->getMotionValidator().get()))
        margin << " (margin " << certified->getMargin() << ", first batch " << certified->getRakeWidth() << ")";
    std::cerr << "rastercheck: backend " << checker->getChecker().backendName() << ", mode " << options.checking.mode
              << ", " << edges << " edges" << margin.str() << ", " << runs << " run(s) of " << timeLimit
              << " s per planner\n";
    benchmark.benchmark(request);
    if (!options.logPath.empty() && !benchmark.saveResultsToFile(options.logPath.c_str()))
        throw InputError(options.logPath, "", "cannot write the benchmark log");

    const ot::Benchmark::CompleteExperiment &data = benchmark.getRecordedExperimentData();
    std::cout << "experiment " << experiment << ": " << runs << " run(s) per planner, time limit " << timeLimit
              << " s\n";
    int nameWidth = 14;  // a longer planner name widens the column
    for (const std::string &label : labels)
        nameWidth = std::max(nameWidth, static_cast<int>(label.size()) + 2);
    std::cout << std::left << std::setw(nameWidth) << "planner" << std::right << std::setw(8) << "solved"
              << std::setw(10) << "colliding" << std::setw(14) << "median_time_s" << std::setw(13) << "mean_time_s"
              << std::setw(14) << "median_length" << '\n';
    for (std::size_t i = 0; i < data.planners.size(); ++i)
    {
        std::vector<double> times, lengths;
        int colliding = 0;
        for (const ot::Benchmark::RunProperties &run : data.planners[i].runs)
        {
            if (!flag(run, "solved BOOLEAN"))
                continue;
            if (run.count(kRecheckValid) && !flag(run, kRecheckValid))
            {
                ++colliding;  // a colliding path is not a solution
                continue;
            }
            times.push_back(property(run, "time REAL"));
            lengths.push_back(property(run, "solution length REAL"));
        }
        std::cout << std::left << std::setw(nameWidth) << (i < labels.size() ? labels[i] : data.planners[i].name)
                  << std::right << std::setw(8)
                  << (std::to_string(times.size()) + "/" + std::to_string(data.planners[i].runs.size()))
                  << std::setw(10) << colliding << std::setw(14) << std::setprecision(4) << median(times)
                  << std::setw(13) << mean(times) << std::setw(14) << median(lengths) << '\n';
    }
    std::cout.flush();
    if (collidingPaths > 0)
    {
        std::cerr << "rastercheck: ERROR: " << collidingPaths
                  << " solution path(s) collide according to the exact oracle (counted as unsolved above)\n";
        if (edges != "certified")
            std::cerr << "rastercheck: plan with --edges certified to accept only edges that are collision-free "
                         "at every point\n";
        return 3;
    }
    return 0;
}
}  // namespace

void addPlanCommand(CLI::App &app)
{
    auto options = std::make_shared<PlanOptions>();
    CLI::App *command = app.add_subcommand(
        "plan", "Benchmark OMPL planners on a problem; every solution path is re-checked by the exact oracle");
    options->problem.addTo(*command);
    command->add_option("--request", options->requestPath,
                        "MoveIt MotionPlanRequest YAML (start and goal) for --robot problems");
    command
        ->add_option("--planner", options->planners,
                     "planner by OMPL.app name (rrtconnect, rrt, prm, kpiece, bkpiece, lbkpiece, est, sbl, stride, "
                     "pdst, trrt, rrtstar, ...; repeatable); default: the .cfg's [planner] list, else rrtconnect")
        ->allow_extra_args(false);
    command->add_option("--param", options->parameters, "planner parameter PLANNER.PARAM=VALUE (repeatable)")
        ->allow_extra_args(false);
    command->add_option("--hold", options->held, "hold coordinate NAME=VALUE fixed, not planned (repeatable)")
        ->allow_extra_args(false);
    command->add_option("--runs", options->runs, "runs per planner (default: the .cfg's run_count, else 10)")
        ->check(CLI::PositiveNumber);
    command->add_option("--time-limit", options->timeLimit, "seconds per run (default: the .cfg's time_limit, else 10)")
        ->check(CLI::PositiveNumber);
    command->add_option("--memory-limit", options->memoryLimit, "MB per run (default: the .cfg's mem_limit, else 4096)")
        ->check(CLI::PositiveNumber);
    options->checking.addBackendAndThreads(*command, "worker threads of batch checks");
    options->checking.addModeAndPadding(*command, "collision mode while planning");
    command
        ->add_option("--bounds-tolerance", options->boundsTolerance,
                     "a start or goal this far outside a joint limit (rad or m) is moved onto it with a warning; "
                     "farther is an error (default 1e-4; a goal joint constraint's tolerance counts where larger)")
        ->check(CLI::NonNegativeNumber);
    command
        ->add_option("--segment-fraction", options->segmentFraction,
                     "longest valid segment, as a fraction of the space's extent (OMPL default 0.01)")
        ->check(CLI::Range(1e-6, 1.0));
    command
        ->add_option("--edges", options->edges,
                     "edge checking: auto (default: certified, in raster mode batched), certified (collision-free "
                     "at every point of an edge; not in raster mode), batched (DiscreteMotionValidator's states, in "
                     "batches) or discrete (OMPL's own)")
        ->check(CLI::IsMember({"auto", "batched", "discrete", "certified"}));
    command
        ->add_option("--margin", options->margin,
                     "certified edges: clearance margin of the coarsest samples, scene units (default a tenth "
                     "of the robot's size)")
        ->check(CLI::NonNegativeNumber);
    command
        ->add_option("--rake-width", options->rakeWidth,
                     "certified edges: coarsest midpoints in an edge's first check, later ones doubling (default 1, "
                     "and at least 8 where the check reaches a GPU; wider makes fewer, larger batches, for a "
                     "backend whose calls cost more than their states)")
        ->check(CLI::PositiveNumber);
    command
        ->add_option("--recheck-factor", options->recheckFactor,
                     "solution paths are re-checked at this many times the planner's resolution (default 10)")
        ->check(CLI::PositiveNumber);
    command->add_option("--log", options->logPath, "OMPL benchmark log (for ompl_benchmark_statistics)");
    command->add_option("--path-out", options->pathOut,
                        "folder for every solved run's path as a states CSV, raw and simplified "
                        "(PLANNER_runN_raw.csv, ..._simplified.csv; paths.csv lists them with the exact re-check's "
                        "verdict): what render --states and view --path read");
    command->add_option("--seed", options->seed, "OMPL random seed")->check(CLI::NonNegativeNumber);
    command->add_flag("--no-simplify", options->noSimplify,
                      "do not simplify solutions (the re-check sees the raw path)");
    command->callback([options]() { throw CommandResult{runPlan(*options)}; });
}

int runPlanCommand(const std::vector<std::string> &arguments)
{
    CLI::App app;
    addPlanCommand(app);
    // CLI11 takes a vector of arguments last first.
    std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());
    reversed.push_back("plan");
    try
    {
        app.parse(reversed);
    }
    catch (const CommandResult &result)
    {
        return result.status;
    }
    return 0;
}
}  // namespace rastercheck::cli
