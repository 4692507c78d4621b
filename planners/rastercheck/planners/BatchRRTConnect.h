#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <ompl/base/Planner.h>
#include <ompl/base/StateSampler.h>
#include <ompl/datastructures/NearestNeighbors.h>

#include "rastercheck/planners/EdgeChecker.h"

namespace rastercheck::planners
{
/** \brief RRT-Connect that grows many edges at once and decides them in shared batches.

    Each iteration draws batch_size samples (half for each tree), extends each tree from the
    state nearest to each of its samples by at most range, and decides all those edges together
    (BatchMotionValidator::checkMotions: one Checker::check per round of the edges' searches).
    Then every state just added pulls the other tree toward it, as RRT-Connect's connect step
    does: along the straight line from the other tree's nearest state, in steps of range, each
    step an edge; the steps of all lines are decided together in rounds (the next step of each
    live line per round), the other tree grows by every valid step, a line ends at its first
    blocked step, and a line that reaches its state joins the trees. The first goal state pulls
    the start tree the same way (the straight line from start to goal first).

    Edges are decided by an EdgeChecker: the setup's batched or certified validator, else
    certified edges of the planner's own over rastercheck's validity checker (collision-free at
    every point), else (a foreign checker) one edge at a time.

    Lazy mode ("lazy", on by default): a new edge is decided at lazy_samples states spread evenly
    along it (its end included; all new edges' states in one batch) instead of by the EdgeChecker,
    and only when a connection joins the trees are the edges of that candidate solution decided:
    first by states at rising density down to the space's resolution (most failing candidates end
    there, cheaply), then by the EdgeChecker, in one batch. An edge either rejects is cut with the
    subtree below it and the search goes on; an edge the EdgeChecker accepts is never decided
    again. The returned path is therefore decided edge by edge exactly as in eager mode (certified
    edges: collision-free at every point), but the edges that never lie on a candidate solution,
    most of both trees, cost a few state checks instead of a certification (LazyRRT's idea, on
    both trees of RRT-Connect). Where candidates keep failing (narrow passages: lazy trees grow
    through walls faster than candidates cut them back), a solve gives laziness up after
    lazy_limit rejected candidates: it cuts what it has not decided and goes on eagerly, with
    extensions and connection steps of half the range (long edges fail where candidates did).

    Parameters: "range" (longest extension; 0 = OMPL's default, a fifth of the space's maximum
    extent; arms among clutter do better with a tenth, which cut the Panda's MotionBenchMaker p95
    from 0.29 to 0.03 s, open spaces with a fifth: docs/benchmarks.md "Tuning: why the defaults"),
    "batch_size" (samples per iteration; 0, the default: by the checker's backend, see
    samplesPerBatch()), "shortcut" (0 or 1: shorten the solution with
    BatchShortcutter before returning it), "lazy" (0 or 1), "lazy_samples" (states per new edge
    in lazy mode, >= 1), "lazy_limit" (rejected candidates before a solve turns eager) and
    "decide_together" (-1, 0 or 1: setDecideTogether()). Seeded
    through OMPL's RNG like every OMPL planner: a run with the same seed and verdicts grows the
    same trees. Honours the termination
    condition between batches; goal regions must be sampleable (GoalSampleableRegion). */
class BatchRRTConnect : public ::ompl::base::Planner
{
public:
    explicit BatchRRTConnect(const ::ompl::base::SpaceInformationPtr &si);
    ~BatchRRTConnect() override;

    ::ompl::base::PlannerStatus solve(const ::ompl::base::PlannerTerminationCondition &ptc) override;
    void clear() override;
    void setup() override;
    void getPlannerData(::ompl::base::PlannerData &data) const override;

    void setRange(double distance) { range_ = distance; }
    double getRange() const { return range_; }
    /** \brief Samples per iteration; 0 (the default): by the checker's backend (samplesPerBatch()). */
    void setBatchSize(unsigned int samples) { batchSize_ = samples; }
    unsigned int getBatchSize() const { return batchSize_; }
    /** \brief The samples per iteration a solve uses (after setup()): batch_size, or where it is 0,
        kCpuSamplesPerBatch when the checker decides batches on the CPU, and on a GPU enough samples
        that an iteration's new states reach the device's smallest batch (Checker::deviceBatch(),
        lazy_samples states per sample in lazy mode, one in eager mode, whose certified edges start
        with a midpoint each), at least kDeviceSamplesPerBatch[0]; where that takes more than
        kDeviceSamplesPerBatch[1] (the automatic threshold on many CPU threads: 4 096 states per
        thread), the iterations run on the CPU and take kCpuSamplesPerBatch. */
    unsigned int samplesPerBatch() const;
    /** \brief Whether a connection round's candidate solutions are decided together, one rake for
        all of them (each level of it one call), and each line's steps in one round, or one at a
        time, the first accepted ending the round, and a step a round: decide_together 1 or 0; -1 (the default) by the
       backend: together where an iteration's states reach the GPU (samplesPerBatch() samples, lazy_samples states each
       in lazy mode, at least Checker::deviceBatch()), whose calls cost far more than their states. Together, a solve
       makes fewer, larger calls and checks more states (Panda MotionBenchMaker problems: 2.4x fewer calls, 2.2x the
       states; docs/benchmarks.md "A connection round's candidates decided together"). (After setup().) */
    bool decidesCandidatesTogether() const;
    /** \brief 1: decide a round's candidates together; 0: one at a time; -1 (the default): by the
        backend (decidesCandidatesTogether()). Throws ConfigurationError for another value. */
    void setDecideTogether(int choice);
    int getDecideTogether() const { return decideTogether_; }
    /** \brief Samples per iteration by default on the CPU (2, 4 and 8 were even on the Panda's
        MotionBenchMaker problems: docs/benchmarks.md "Tuning: why the defaults"). */
    static constexpr unsigned int kCpuSamplesPerBatch = 8;
    /** \brief The fewest and most samples per iteration by default on a GPU: a device call costs
        about the same from a thousand states to ten thousand (docs/benchmarks.md "GPU"), so an
        iteration there takes hundreds of samples (256 solved 69 of the Panda's 70 problems where
        8 solved 61, on an H100), and at most a few thousand (more grows trees far past what a
        solve needs). */
    static constexpr unsigned int kDeviceSamplesPerBatch[2] = {256, 4096};
    /** \brief Whether a solution is shortened by BatchShortcutter (its candidate shortcuts decided
        in batches, within the time left) before it is returned. */
    void setShortcut(bool shortcut) { shortcut_ = shortcut; }
    bool getShortcut() const { return shortcut_; }
    /** \brief Lazy mode (see the class comment): new edges checked at a few states, a candidate
        solution's edges decided by the EdgeChecker only when the trees join. */
    void setLazy(bool lazy) { lazy_ = lazy; }
    bool getLazy() const { return lazy_; }
    /** \brief Rejected candidates after which a solve stops being lazy: the edges not yet decided
        are cut and every new edge is decided when it is grown (eager mode) for the rest of the
        solve. */
    void setLazyLimit(unsigned int candidates) { lazyLimit_ = std::max(1u, candidates); }
    unsigned int getLazyLimit() const { return lazyLimit_; }
    /** \brief States checked per new edge in lazy mode; throws ConfigurationError for 0. */
    void setLazySamples(unsigned int samples);
    unsigned int getLazySamples() const { return lazySamples_; }
    /** \brief Lazy mode, the last solve: candidate solutions decided, how many were rejected, and
        the states cut from the trees with the rejected edges above them. */
    unsigned int getCandidateCount() const { return candidates_; }
    unsigned int getRejectedCandidateCount() const { return rejectedCandidates_; }
    unsigned int getCutStateCount() const { return cutMotions_; }

private:
    struct Motion;
    using Tree = std::shared_ptr<::ompl::NearestNeighbors<Motion *>>;
    struct Motion
    {
        ::ompl::base::State *state = nullptr;
        Motion *parent = nullptr;
        const Tree *tree = nullptr;
        std::vector<Motion *> children;  ///< kept for cutting subtrees in lazy mode
        bool edgeDecided = true;         ///< the edge from parent was decided by the EdgeChecker
        unsigned int rakedLevels = 0;    ///< levels of EdgeChecker::rake the undecided edge from parent passed
        bool cut = false;                ///< removed from its tree with a rejected edge above it
    };

    /** \brief Connect step: each \a fresh state (and its tree) pulls the other tree toward it;
        true, with the solution path added, when a line joins the trees. */
    bool connect(const std::vector<std::pair<Motion *, const Tree *>> &fresh,
                 const ::ompl::base::PlannerTerminationCondition &ptc);
    /** \brief Decides the new \a edges: by the EdgeChecker, or in lazy mode at lazy_samples states each
        (the end left out where \a endInTree says it is a tree's state, checked when it was added). */
    void checkNewEdges(const std::vector<ompl::Edge> &edges, std::vector<std::uint8_t> &valid,
                       const std::vector<std::uint8_t> *endInTree = nullptr);
    /** \brief A candidate solution: a connection step (\a bridge) joined the start tree's \a startEnd
        and the goal tree's \a goalEnd; \a bridgeDecided when the step was decided as it was grown
        (eager mode). */
    struct Candidate
    {
        Motion *startEnd = nullptr;
        Motion *goalEnd = nullptr;
        ompl::Edge bridge;
        bool bridgeDecided = false;
    };
    /** \brief Decides \a candidates together: the edges from both trees' roots to their ends that
        are not decided yet, and their bridges, each edge once, first by a rake of all of them (which
        rejects most failing candidates for less), then the survivors' edges by the EdgeChecker, the
        first survivor's first; cuts the subtree below each rejected tree edge. Returns the first
        candidate (in order) whose every edge is accepted (at once when none needed deciding), else
        candidates.size(). */
    std::size_t decideCandidates(const std::vector<Candidate> &candidates);
    /** \brief The levels of EdgeChecker::rake that a lazy edge's own states (checkNewEdges) have
        checked already: as many as 2 divides lazy_samples. */
    unsigned int lazyRakedLevels() const;
    /** \brief Removes \a motion and every motion below it from their tree. */
    void cutSubtree(Motion *motion);
    /** \brief Cuts every edge not yet decided; the rest of the solve is eager. */
    void abandonLaziness();
    /** \brief The longest extension or connection step now: range, halved once this solve has
        given laziness up. */
    double stepRange() const;
    /** \brief The live motion of \a tree nearest to \a probe (cut motions are skipped). */
    Motion *nearest(const Tree &tree, const Motion *probe) const;
    /** \brief Cut motions still held by \a tree's structure; its motions that are not cut. */
    std::size_t &ghosts(const Tree &tree);
    std::size_t liveSize(const Tree &tree) const;
    Motion *addMotion(const Tree &tree, const ::ompl::base::State *state, Motion *parent, bool edgeDecided);
    /** \brief The states from \a a tree's root to \a motion's, root first. */
    static std::vector<const ::ompl::base::State *> branch(const Motion *motion);
    void freeMemory();

    ::ompl::base::StateSamplerPtr sampler_;
    Tree startTree_, goalTree_;
    std::vector<Motion *> motions_;             ///< every motion of both trees, for freeing
    std::shared_ptr<const EdgeChecker> edges_;  ///< made by setup()
    double range_ = 0.0;
    unsigned int batchSize_ = 0;
    bool shortcut_ = false;
    bool lazy_ = true;
    bool lazyNow_ = true;  ///< lazy_, until this solve abandons laziness
    unsigned int lazyLimit_ = 300;
    unsigned int lazySamples_ = 2;
    int decideTogether_ = -1;
    std::pair<const Motion *, const Motion *> connection_{nullptr, nullptr};  ///< (start tree, goal tree)
    unsigned int candidates_ = 0, rejectedCandidates_ = 0, cutMotions_ = 0;   ///< lazy mode, this solve
    std::uint64_t lazyStates_ = 0, rakedStates_ = 0;                          ///< lazy mode, this solve
    std::size_t ghosts_[2] = {0, 0};  ///< cut motions still in the start and goal trees' structures
};
}  // namespace rastercheck::planners
