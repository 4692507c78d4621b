// Many threads on one checker. 8 std::threads deciding states through the OMPL validity checker
// and, at the same time, edges through the batched motion validator get exactly the verdicts of one
// thread, and the same inputs get the same verdicts and first contacts (kind, component, object,
// triangle, position) across runs, thread interleavings and OpenMP thread counts. On the Panda in a
// MotionBenchMaker bookshelf (shared data) and on the crane in the plant (robots/).
//
// Size: RASTERCHECK_CONCURRENCY_STATES states decided by the 8 threads in all (default 100000, half
// per problem, half of that as single states and half as edge states). The sanitizers slow the
// checker 10 to 50 times, so scripts/sanitize.sh sets a tenth of that.
//
// ctest label: concurrency (scripts/sanitize.sh runs these under ThreadSanitizer).
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <functional>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>

#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/MotionValidator.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;

namespace
{
constexpr int kThreads = 8;

std::size_t totalStates()
{
    const char *text = std::getenv("RASTERCHECK_CONCURRENCY_STATES");
    if (!text)
        return 100000;
    const long value = std::strtol(text, nullptr, 10);
    if (value < 400)
        throw std::runtime_error("RASTERCHECK_CONCURRENCY_STATES must be a number >= 400");
    return static_cast<std::size_t>(value);
}

/** \brief Calls body(i) for i in [0, n) on kThreads std::threads that take small chunks of indices
    from a shared counter, so that which thread decides which item, and after which others (what
    its pooled scratch last held), changes from run to run. */
void onThreads(std::size_t n, const std::function<void(std::size_t)> &body)
{
    constexpr std::size_t kChunk = 7;
    std::atomic<std::size_t> next{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back(
            [&]
            {
                for (std::size_t begin = next.fetch_add(kChunk); begin < n; begin = next.fetch_add(kChunk))
                    for (std::size_t i = begin; i < std::min(n, begin + kChunk); ++i)
                        body(i);
            });
    for (std::thread &thread : threads)
        thread.join();
}

/** \brief What the checker said about one state. */
struct Verdict
{
    bool valid = false;
    rc::Contact contact;
};

bool operator==(const Verdict &a, const Verdict &b)
{
    const rc::Contact &x = a.contact, &y = b.contact;
    return a.valid == b.valid && x.kind == y.kind && x.component == y.component && x.object == y.object &&
           x.otherComponent == y.otherComponent && x.triangle == y.triangle && x.position == y.position;
}

/** \brief What the motion validator said about one edge (both overloads). */
struct EdgeVerdict
{
    bool valid = false;              // checkMotion(s1, s2)
    bool validWithLast = false;      // checkMotion(s1, s2, lastValid)
    double lastValidFraction = -1;   // lastValid.second (-1: untouched, the edge is valid)
    std::vector<double> lastValidQ;  // lastValid.first as a configuration
};

bool operator==(const EdgeVerdict &a, const EdgeVerdict &b)
{
    return a.valid == b.valid && a.validWithLast == b.validWithLast && a.lastValidFraction == b.lastValidFraction &&
           a.lastValidQ == b.lastValidQ;
}

std::string describe(const rc::Checker &checker, const Verdict &verdict)
{
    return (verdict.valid ? "valid" : "invalid") + std::string(" (") + checker.describe(verdict.contact) + ")";
}

std::string describe(const rc::Checker &, const EdgeVerdict &verdict)
{
    std::ostringstream text;
    text << (verdict.valid ? "valid" : "invalid") << " / " << (verdict.validWithLast ? "valid" : "invalid")
         << ", last valid fraction " << verdict.lastValidFraction;
    return text.str();
}

/** \brief Expects \a actual to equal \a expected element by element; on failure reports how many
    differ and the first of them (not one line per difference: there may be thousands). */
template <typename T>
void expectSame(const rc::Checker &checker, const std::vector<T> &expected, const std::vector<T> &actual,
                const std::string &what)
{
    ASSERT_EQ(actual.size(), expected.size()) << what;
    std::size_t differences = 0, first = 0;
    for (std::size_t i = expected.size(); i-- > 0;)
        if (!(actual[i] == expected[i]))
        {
            ++differences;
            first = i;
        }
    EXPECT_EQ(differences, 0u) << what << ": " << differences << " of " << expected.size() << " differ; the first, #"
                               << first << ", expected " << describe(checker, expected[first]) << ", got "
                               << describe(checker, actual[first]);
}

template <typename T>
std::size_t countValid(const std::vector<T> &verdicts)
{
    return static_cast<std::size_t>(
        std::count_if(verdicts.begin(), verdicts.end(), [](const T &v) { return v.valid; }));
}

/** \brief Expects a real mix of valid and invalid outcomes, more than 1 / \a parts of each: with one
    kind only, a checker that answers a constant would pass. */
template <typename T>
void expectMix(const std::vector<T> &verdicts, const std::string &what, std::size_t parts = 10)
{
    const std::size_t valid = countValid(verdicts), n = verdicts.size();
    EXPECT_GT(valid, n / parts) << what << ": " << valid << " of " << n << " valid";
    EXPECT_LT(valid, n - n / parts) << what << ": " << valid << " of " << n << " valid";
}

/** \brief One planning problem as makeSimpleSetup builds it, random states and edges in it, and the
    checks; a fixture per problem loads it. */
class Concurrency : public ::testing::Test
{
protected:
    void start(rc::Problem problem, const rco::SetupOptions &options)
    {
        problem_ = std::move(problem);
        options_ = options;
        perProblem_ = totalStates() / 2;
        // Batches (the motion validator's) on every core: an OpenMP team inside each std::thread, as
        // under a parallel planner.
        options_.checker.backend = rc::BackendChoice::Cpu;
        options_.checker.threads = 0;
        options_.edges = rco::EdgeChecking::Batched;  // the states-and-edges test shares its validator
        setup_ = rco::makeSimpleSetup(problem_, options_);
        setup_->getSpaceInformation()->setup();
        sampleStates(perProblem_ / 4);
    }

    void TearDown() override
    {
        if (!setup_)
            return;
        const ob::SpaceInformationPtr &si = setup_->getSpaceInformation();
        for (ob::State *state : states_)
            si->freeState(state);
        for (auto &[from, to] : edges_)
        {
            si->freeState(from);
            si->freeState(to);
        }
    }

    void eightThreadsOnOneCheckerDecideStatesAndEdgesAsOneThread()
    {
        // perProblem_ / 4 states and edges of about perProblem_ / 4 states, each decided by both
        // overloads: about perProblem_ states for the 8 threads.
        sampleEdges(perProblem_ / 4);
        rco::StateValidityChecker &validity = validityOf(*setup_);
        const rco::MotionValidator &motion = motionOf(*setup_);
        const std::size_t n = states_.size(), m = edges_.size();

        // The reference: this thread alone, edges by a validator whose checker runs its batches on
        // one thread.
        const rco::MotionValidator oneThreadMotion(
            setup_->getSpaceInformation(), validity.getStateMappingPtr(),
            std::make_shared<const rc::Checker>(problem_.robot, problem_.scene,
                                                rc::CheckerOptions{rc::BackendChoice::Cpu, 1}),
            validity.getRequest());
        const std::vector<Verdict> serialStates = decideStatesInOrder();
        std::vector<EdgeVerdict> serialEdges(m);
        for (std::size_t j = 0; j < m; ++j)
            serialEdges[j] = decideEdge(oneThreadMotion, j);
        expectMix(serialStates, "states");
        expectMix(serialEdges, "edges");

        // The 8 threads, on the one checker of the setup: states and edges shuffled together, as
        // a parallel planner asks for both at once.
        validity.resetCounters();
        std::vector<std::size_t> order(n + m);
        std::iota(order.begin(), order.end(), 0);
        std::shuffle(order.begin(), order.end(), std::mt19937_64(3));
        std::vector<Verdict> states(n);
        std::vector<EdgeVerdict> edges(m);
        std::atomic<std::size_t> overloadsDisagree{0};
        onThreads(n + m,
                  [&](std::size_t k)
                  {
                      const std::size_t item = order[k];
                      if (item >= n)
                          edges[item - n] = decideEdge(motion, item - n);
                      else if (!decideState(item, states[item]))
                          ++overloadsDisagree;
                  });
        EXPECT_EQ(overloadsDisagree.load(), 0u);
        expectSame(validity.getChecker(), serialStates, states, "states, 8 threads vs 1");
        expectSame(validity.getChecker(), serialEdges, edges, "edges, 8 threads vs 1");
        // The counters are atomic: no call, motion or state is lost.
        EXPECT_EQ(validity.getCallCount(), 2 * n);
        EXPECT_EQ(validity.getInvalidCount(), 2 * (n - countValid(serialStates)));
        EXPECT_EQ(motion.getValidMotionCount(), 2 * countValid(serialEdges));
        EXPECT_EQ(motion.getCheckedMotionCount(), 2 * m);
        EXPECT_EQ(motion.getCheckedStateCount(), oneThreadMotion.getCheckedStateCount());
    }

    void certifiedEdgesOnEightThreadsAsOnOne()
    {
        sampleEdges(perProblem_ / 4);
        const ob::SpaceInformationPtr &si = setup_->getSpaceInformation();
        rco::StateValidityChecker &validity = validityOf(*setup_);
        const rco::CertifiedMotionValidator shared(si, validity);
        const rco::StateValidityChecker oneThreadValidity(
            si, validity.getStateMappingPtr(),
            std::make_shared<const rc::Checker>(problem_.robot, problem_.scene,
                                                rc::CheckerOptions{rc::BackendChoice::Cpu, 1}),
            validity.getRequest());
        const rco::CertifiedMotionValidator oneThread(si, oneThreadValidity);
        const std::size_t m = edges_.size();
        std::vector<EdgeVerdict> serial(m), parallel(m);
        for (std::size_t j = 0; j < m; ++j)
            serial[j] = decideEdge(oneThread, j);
        expectMix(serial, "certified edges", 20);  // most of these edges are free: ask for 5 % of each
        onThreads(m, [&](std::size_t j) { parallel[j] = decideEdge(shared, j); });
        expectSame(validity.getChecker(), serial, parallel, "certified edges, 8 threads vs 1");
        EXPECT_EQ(shared.getValidMotionCount(), 2 * countValid(serial));
        EXPECT_EQ(shared.getCheckedMotionCount(), 2 * m);
        EXPECT_EQ(shared.getCheckedStateCount(), oneThread.getCheckedStateCount());
    }

    void sameVerdictsAndFirstContactsAcrossRunsAndOpenMpThreadCounts()
    {
        // One state at a time on this thread, in order: the reference.
        const std::vector<Verdict> reference = decideStatesInOrder();
        expectMix(reference, "states");
        const std::vector<double> q = configurations();
        const std::size_t n = states_.size();
        const rc::Checker &shared = validityOf(*setup_).getChecker();
        // Batches on a fresh checker per OpenMP thread count: nothing pooled from earlier runs, and
        // each worker's scratch sees another sequence of states.
        for (int threads : {1, 2, kThreads})
        {
            const rc::Checker checker(problem_.robot, problem_.scene,
                                      rc::CheckerOptions{rc::BackendChoice::Cpu, threads});
            std::vector<std::uint8_t> valid(n);
            std::vector<rc::Contact> contacts(n);
            checker.check(q.data(), n, valid.data(), options_.request, contacts.data());
            std::vector<Verdict> batch(n);
            for (std::size_t i = 0; i < n; ++i)
                batch[i] = {valid[i] != 0, contacts[i]};
            expectSame(shared, reference, batch, "batch on " + std::to_string(threads) + " OpenMP threads");
        }
        // The shared checker again, after everything above, in reverse order.
        std::vector<Verdict> reversed(n);
        for (std::size_t i = n; i-- > 0;)
            reversed[i].valid = shared.isValid(q.data() + i * shared.dof(), options_.request, &reversed[i].contact);
        expectSame(shared, reference, reversed, "reverse order");
    }

    static rco::StateValidityChecker &validityOf(const ::ompl::geometric::SimpleSetup &setup)
    {
        return *rco::getStateValidityChecker(setup);
    }

    static const rco::MotionValidator &motionOf(const ::ompl::geometric::SimpleSetup &setup)
    {
        auto motion =
            std::dynamic_pointer_cast<rco::MotionValidator>(setup.getSpaceInformation()->getMotionValidator());
        if (!motion)
            throw std::runtime_error("makeSimpleSetup did not install the batched motion validator");
        return *motion;
    }

    /** \brief \a n states uniformly in the planned coordinates' bounds (held ones at their values). */
    void sampleStates(std::size_t n)
    {
        const rco::StateMapping &mapping = validityOf(*setup_).getStateMapping();
        const rc::RobotModel &robot = mapping.robot();
        std::mt19937_64 random(20240607);
        std::vector<double> q = mapping.baseConfiguration();
        for (std::size_t i = 0; i < n; ++i)
        {
            for (int c : mapping.plannedCoordinates())
                q[c] = std::uniform_real_distribution<double>(robot.lowerBounds[c], robot.upperBounds[c])(random);
            states_.push_back(setup_->getSpaceInformation()->allocState());
            mapping.fromConfiguration(q, states_.back());
        }
    }

    /** \brief Edges from valid states towards random states, a fraction of the way, until their
        states (segments) number about \a budget. */
    void sampleEdges(std::size_t budget)
    {
        const ob::SpaceInformationPtr &si = setup_->getSpaceInformation();
        const ob::StateSpacePtr &space = si->getStateSpace();
        rco::StateValidityChecker &validity = validityOf(*setup_);
        std::mt19937_64 random(7);
        std::uniform_int_distribution<std::size_t> pick(0, states_.size() - 1);
        std::uniform_real_distribution<double> reach(0.1, 1.0);
        std::size_t invalidInARow = 0;
        for (std::size_t segments = 0; segments < budget;)
        {
            const ob::State *from = states_[pick(random)];
            if (!validity.isValid(from))
            {
                if (++invalidInARow == 1000)
                    throw std::runtime_error("no valid start state for the edges");
                continue;
            }
            invalidInARow = 0;
            ob::State *start = si->cloneState(from), *end = si->allocState();
            space->interpolate(start, states_[pick(random)], reach(random), end);
            edges_.emplace_back(start, end);
            segments += std::max(1u, space->validSegmentCount(start, end));
        }
    }

    /** \brief State \a i's verdict and first contact through the shared validity checker; false when
        the plain overload disagrees. */
    bool decideState(std::size_t i, Verdict &verdict) const
    {
        const rco::StateValidityChecker &validity = validityOf(*setup_);
        verdict.valid = validity.isValid(states_[i], verdict.contact);
        return validity.isValid(states_[i]) == verdict.valid;
    }

    std::vector<Verdict> decideStatesInOrder() const
    {
        std::vector<Verdict> verdicts(states_.size());
        std::size_t overloadsDisagree = 0;
        for (std::size_t i = 0; i < states_.size(); ++i)
            overloadsDisagree += decideState(i, verdicts[i]) ? 0 : 1;
        EXPECT_EQ(overloadsDisagree, 0u);
        return verdicts;
    }

    /** \brief Both checkMotion overloads on edge \a j through \a motion. */
    EdgeVerdict decideEdge(const ob::MotionValidator &motion, std::size_t j) const
    {
        const ob::SpaceInformationPtr &si = setup_->getSpaceInformation();
        const auto &[from, to] = edges_[j];
        EdgeVerdict verdict;
        verdict.valid = motion.checkMotion(from, to);
        ob::State *last = si->allocState();
        std::pair<ob::State *, double> lastValid(last, -1.0);
        verdict.validWithLast = motion.checkMotion(from, to, lastValid);
        verdict.lastValidFraction = lastValid.second;
        if (!verdict.validWithLast)
            verdict.lastValidQ = validityOf(*setup_).getStateMapping().toConfiguration(last);
        si->freeState(last);
        return verdict;
    }

    /** \brief The configurations of the states, as the validity checker hands them to the Checker. */
    std::vector<double> configurations() const
    {
        const rco::StateMapping &mapping = validityOf(*setup_).getStateMapping();
        std::vector<double> q(states_.size() * mapping.numCoordinates());
        for (std::size_t i = 0; i < states_.size(); ++i)
            mapping.toConfiguration(states_[i], q.data() + i * mapping.numCoordinates());
        return q;
    }

    rc::Problem problem_;
    rco::SetupOptions options_;
    std::size_t perProblem_ = 0;  // states the 8 threads decide on this problem
    ::ompl::geometric::SimpleSetupPtr setup_;
    std::vector<ob::State *> states_;
    std::vector<std::pair<ob::State *, ob::State *>> edges_;
};

class PandaBookshelf : public Concurrency
{
protected:
    void SetUp() override
    {
        RASTERCHECK_REQUIRE_DATA(root);
        start(rc::test::pandaProblem(root, "bookshelf_small"), {});
    }
};

class CraneInPlant : public Concurrency
{
protected:
    void SetUp() override
    {
        // As examples/crane_lift.cpp plans the lift: the base held, 0.25 m clearance.
        rco::SetupOptions options;
        options.heldCoordinates = {{"base_x", 0.0}, {"base_y", 0.0}, {"base_yaw", 0.0}};
        options.request.padding = 0.25;
        start(rc::test::plant(), options);
    }
};
}  // namespace

TEST_F(PandaBookshelf, EightThreadsOnOneCheckerDecideStatesAndEdgesAsOneThread)
{
    eightThreadsOnOneCheckerDecideStatesAndEdgesAsOneThread();
}

TEST_F(PandaBookshelf, SameVerdictsAndFirstContactsAcrossRunsAndOpenMpThreadCounts)
{
    sameVerdictsAndFirstContactsAcrossRunsAndOpenMpThreadCounts();
}

TEST_F(PandaBookshelf, EightThreadsCertifyEdgesAsOneThread)
{
    certifiedEdgesOnEightThreadsAsOnOne();
}

TEST_F(CraneInPlant, EightThreadsCertifyEdgesAsOneThread)
{
    certifiedEdgesOnEightThreadsAsOnOne();
}

TEST_F(CraneInPlant, EightThreadsOnOneCheckerDecideStatesAndEdgesAsOneThread)
{
    eightThreadsOnOneCheckerDecideStatesAndEdgesAsOneThread();
}

TEST_F(CraneInPlant, SameVerdictsAndFirstContactsAcrossRunsAndOpenMpThreadCounts)
{
    sameVerdictsAndFirstContactsAcrossRunsAndOpenMpThreadCounts();
}

TEST(RobotParts, EightThreadsBuildingCheckersOfEqualRobotsShareOnePartAndAgree)
{
    // Each thread builds a checker of its own copy of the crane at once: the robot parts are built
    // at most once per thread that found none, and every model ends up with the one kept.
    const rc::Problem &plant = rc::test::plant();
    const std::vector<double> boomInRack = {0, 0, 0, 1.570796326795, 0.3, 5, 1};
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cpu;
    std::vector<std::unique_ptr<rc::Checker>> checkers(kThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back(
            [&, t] {
                checkers[t] =
                    std::make_unique<rc::Checker>(std::make_shared<rc::RobotModel>(*plant.robot), plant.scene, options);
            });
    for (std::thread &thread : threads)
        thread.join();
    for (const std::unique_ptr<rc::Checker> &checker : checkers)
    {
        EXPECT_EQ(checker->collisionModel().componentBvhs[0].get(),
                  checkers[0]->collisionModel().componentBvhs[0].get());
        EXPECT_FALSE(checker->isValid(boomInRack));
    }
}
