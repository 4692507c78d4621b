// Where a planner's time goes, without the planner: the certified edges and the free states that
// BatchRRTConnect asks about, replayed on the MotionBenchMaker problems. Per problem, a fixed set
// of edges the way RRT-Connect grows them (from a valid state toward a uniform sample, at most the
// planner's default range long), decided by CertifiedMotionValidator::checkMotions in batches of
// batch_size, and the valid start states decided one by one by Checker::check (safe mode, no
// padding: what a free state costs). One core, the CPU backend, seeded: every build sees the same
// edges and states, and the verdict digest must not change when only speed does.
// Prints per scenario and in all: edges accepted, states the checker decided, time per edge, per
// certified state and per free state (the thread's CPU time, the fastest of the repeats: the
// machine may be shared), and a digest of every verdict and state count per sizing. The edges are
// decided three times, side by side in one run: with intervals sized by the midpoints' exact
// clearance (CertifiedMotionOptions::sizeByClearance), by its lower bound from the hulls
// (clearanceMeasure = HullBound), and by bisection alone (the default); "clearances per edge"
// counts the Checker::freeRadius queries, which are not among the states. A second digest, of the
// verdicts alone, must be the same for every sizing.
//
// usage: rastercheck_bench_edges [robot=panda] [problems_per_scenario=3] [edges_per_problem=400]
//                                [batch_size=8] [repeats=3]
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <map>
#include <memory>
#include <random>

#include <ompl/base/StateSampler.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "BenchSupport.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/ompl/Setup.h"

using namespace rastercheck;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace
{
struct Totals
{
    std::size_t edges = 0, accepted = 0, freeStates = 0;
    std::uint64_t states = 0, clearances = 0;
    double edgeSeconds = 0.0, freeSeconds = 0.0;
};

/** \brief How a mode's certified edges size their intervals. */
struct Sizing
{
    const char *name;
    bool byClearance;
    ClearanceMeasure measure;
};
constexpr Sizing kSizings[] = {{"clearance", true, ClearanceMeasure::Exact},
                               {"hull bound", true, ClearanceMeasure::HullBound},
                               {"bisection", false, ClearanceMeasure::Exact}};
constexpr int kNumSizings = 3;

std::uint64_t mix(std::uint64_t digest, std::uint64_t value)
{
    return (digest ^ value) * 1099511628211ull;  // FNV-1a step
}
}  // namespace

int main(int argc, char **argv)
{
    const std::string robotName = argc > 1 ? argv[1] : "panda";
    const int problemsPerScenario = argc > 2 ? std::atoi(argv[2]) : 3;
    const std::size_t edgesPerProblem = argc > 3 ? static_cast<std::size_t>(std::atoi(argv[3])) : 400;
    const std::size_t batchSize = argc > 4 ? static_cast<std::size_t>(std::atoi(argv[4])) : 8;
    const int repeats = argc > 5 ? std::atoi(argv[5]) : 3;
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_ERROR);
    const std::string root = bench::sharedDataOrExit();
    const RobotModelConstPtr robot = bench::loadMbmRobot(root, robotName);

    std::map<std::string, Totals> perScenario[kNumSizings];
    Totals all[kNumSizings];
    std::uint64_t digest[kNumSizings], verdictDigest[kNumSizings];
    std::fill_n(digest, kNumSizings, 1469598103934665603ull);
    std::fill_n(verdictDigest, kNumSizings, 1469598103934665603ull);
    for (const std::string &scenario : bench::mbmScenarios())
        for (int index = 1; index <= problemsPerScenario; ++index)
        {
            Problem problem;
            problem.robot = robot;
            problem.scene = loadMoveItScene(bench::mbmProblemPath(root, robotName, scenario, index, "scene"));
            rastercheck::ompl::SetupOptions options;  // certified edges: the default
            options.checker.backend = BackendChoice::Cpu;
            options.checker.threads = 1;
            og::SimpleSetupPtr setup = rastercheck::ompl::makeSimpleSetup(problem, options);
            setup->getSpaceInformation()->setup();
            const ob::SpaceInformationPtr &si = setup->getSpaceInformation();
            const auto validity = rastercheck::ompl::getStateValidityChecker(*setup);
            if (!std::dynamic_pointer_cast<rastercheck::ompl::CertifiedMotionValidator>(si->getMotionValidator()))
            {
                std::fprintf(stderr, "the setup's motion validator is not certified\n");
                return 1;
            }
            std::shared_ptr<rastercheck::ompl::CertifiedMotionValidator> validators[kNumSizings];
            for (int m = 0; m < kNumSizings; ++m)
            {
                rastercheck::ompl::CertifiedMotionOptions sizing;
                sizing.sizeByClearance = kSizings[m].byClearance;
                sizing.clearanceMeasure = kSizings[m].measure;
                validators[m] = std::make_shared<rastercheck::ompl::CertifiedMotionValidator>(si, *validity, sizing);
            }
            const Checker &checker = validity->getChecker();
            const rastercheck::ompl::StateMapping &mapping = validity->getStateMapping();
            const std::size_t dof = mapping.numCoordinates();

            // The edges: valid starts (their configurations kept for the free-state timing), ends a
            // range (OMPL's default: a fifth of the space's extent) toward uniform samples.
            ::ompl::msg::setLogLevel(::ompl::msg::LOG_NONE);  // OMPL warns when the seed changes after RNGs exist
            ::ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(7919 * index + scenario.size()));
            ::ompl::msg::setLogLevel(::ompl::msg::LOG_ERROR);
            ob::StateSamplerPtr sampler = si->allocStateSampler();
            const double range = 0.2 * si->getMaximumExtent();
            std::vector<ob::State *> from, to;
            std::vector<double> starts;
            std::vector<double> q(dof);
            while (from.size() < edgesPerProblem)
            {
                ob::State *a = si->allocState();
                sampler->sampleUniform(a);
                mapping.toConfiguration(a, q.data());
                if (!checker.isValid(q.data(), validity->getRequest()))
                {
                    si->freeState(a);
                    continue;
                }
                ob::State *b = si->allocState();
                sampler->sampleUniform(b);
                const double d = si->distance(a, b);
                if (d > range)
                    si->getStateSpace()->interpolate(a, b, range / d, b);
                from.push_back(a);
                to.push_back(b);
                starts.insert(starts.end(), q.begin(), q.end());
            }
            std::vector<rastercheck::ompl::Edge> batch(edgesPerProblem);
            for (std::size_t i = 0; i < edgesPerProblem; ++i)
                batch[i] = {from[i], to[i]};

            std::vector<std::uint8_t> free(edgesPerProblem);
            for (int m = 0; m < kNumSizings; ++m)
            {
                rastercheck::ompl::CertifiedMotionValidator &edges = *validators[m];
                Totals &t = perScenario[m][scenario];
                std::vector<std::uint8_t> verdicts(edgesPerProblem);
                // The fastest of the repeats: the least disturbed by whatever else the machine runs.
                double edgeSeconds = 0.0, freeSeconds = 0.0;
                for (int repeat = 0; repeat < repeats; ++repeat)
                {
                    edges.resetStateCounter();
                    const double edgeTime = bench::threadSeconds(
                        [&]
                        {
                            for (std::size_t i = 0; i < edgesPerProblem; i += batchSize)
                                edges.checkMotions(batch.data() + i, std::min(batchSize, edgesPerProblem - i),
                                                   verdicts.data() + i);
                        });
                    const double freeTime = bench::threadSeconds(
                        [&]
                        {
                            for (std::size_t i = 0; i < edgesPerProblem; ++i)
                                checker.check(starts.data() + i * dof, 1, free.data() + i, validity->getRequest());
                        });
                    edgeSeconds = repeat == 0 ? edgeTime : std::min(edgeSeconds, edgeTime);
                    freeSeconds = repeat == 0 ? freeTime : std::min(freeSeconds, freeTime);
                }
                for (Totals *sum : {&t, &all[m]})
                {
                    sum->edges += edgesPerProblem;
                    sum->accepted += static_cast<std::size_t>(std::count(verdicts.begin(), verdicts.end(), 1));
                    sum->states += edges.getCheckedStateCount();
                    sum->clearances += edges.getClearanceCount();
                    sum->edgeSeconds += edgeSeconds;
                    sum->freeStates += edgesPerProblem;
                    sum->freeSeconds += freeSeconds;
                }
                for (std::size_t i = 0; i < edgesPerProblem; ++i)
                {
                    digest[m] = mix(digest[m], static_cast<std::uint64_t>(verdicts[i]) * 2 + free[i]);
                    verdictDigest[m] = mix(verdictDigest[m], static_cast<std::uint64_t>(verdicts[i]) * 2 + free[i]);
                }
                digest[m] = mix(digest[m], edges.getCheckedStateCount());
            }
            for (std::size_t i = 0; i < edgesPerProblem; ++i)
            {
                si->freeState(from[i]);
                si->freeState(to[i]);
            }
        }

    std::printf("%s, %d problems per scenario, %zu edges each (batches of %zu), %d repeats, one core\n\n",
                robotName.c_str(), problemsPerScenario, edgesPerProblem, batchSize, repeats);
    std::printf("| scenario | sizing | edges accepted | states per edge | clearances per edge | us per edge | us per "
                "certified state | us per free state |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|\n");
    auto row = [](const std::string &name, const char *sizing, const Totals &t)
    {
        std::printf("| %s | %s | %.1f %% | %.1f | %.2f | %.1f | %.2f | %.2f |\n", name.c_str(), sizing,
                    100.0 * static_cast<double>(t.accepted) / static_cast<double>(t.edges),
                    static_cast<double>(t.states) / static_cast<double>(t.edges),
                    static_cast<double>(t.clearances) / static_cast<double>(t.edges), 1e6 * t.edgeSeconds / t.edges,
                    1e6 * t.edgeSeconds / static_cast<double>(t.states), 1e6 * t.freeSeconds / t.freeStates);
    };
    for (const std::string &scenario : bench::mbmScenarios())
        for (int m = 0; m < kNumSizings; ++m)
            row(scenario, kSizings[m].name, perScenario[m][scenario]);
    for (int m = 0; m < kNumSizings; ++m)
        row("all", kSizings[m].name, all[m]);
    for (int m = 0; m < kNumSizings; ++m)
        std::printf("\nverdict digest (%s) %016llx, verdicts alone %016llx", kSizings[m].name,
                    static_cast<unsigned long long>(digest[m]), static_cast<unsigned long long>(verdictDigest[m]));
    std::printf("\n");
    return 0;
}
