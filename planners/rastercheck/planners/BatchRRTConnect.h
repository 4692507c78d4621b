#pragma once

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

    Parameters: "range" (longest extension; 0 = OMPL's default, a fifth of the space's extent),
    "batch_size" (samples per iteration, >= 1), "shortcut" (0 or 1: shorten the solution with
    BatchShortcutter before returning it). Seeded through OMPL's RNG like every OMPL
    planner: a run with the same seed and verdicts grows the same trees. Honours the termination
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
    /** \brief Samples per iteration; throws ConfigurationError for 0. */
    void setBatchSize(unsigned int samples);
    unsigned int getBatchSize() const { return batchSize_; }
    /** \brief Whether a solution is shortened by BatchShortcutter (its candidate shortcuts decided
        in batches, within the time left) before it is returned. */
    void setShortcut(bool shortcut) { shortcut_ = shortcut; }
    bool getShortcut() const { return shortcut_; }

private:
    struct Motion
    {
        ::ompl::base::State *state = nullptr;
        Motion *parent = nullptr;
    };
    using Tree = std::shared_ptr<::ompl::NearestNeighbors<Motion *>>;

    /** \brief Connect step: each \a fresh state (and its tree) pulls the other tree toward it;
        true, with the solution path added, when a line joins the trees. */
    bool connect(const std::vector<std::pair<Motion *, const Tree *>> &fresh,
                 const ::ompl::base::PlannerTerminationCondition &ptc);
    Motion *addMotion(const Tree &tree, const ::ompl::base::State *state, Motion *parent);
    /** \brief The states from \a a tree's root to \a motion's, root first. */
    static std::vector<const ::ompl::base::State *> branch(const Motion *motion);
    void freeMemory();

    ::ompl::base::StateSamplerPtr sampler_;
    Tree startTree_, goalTree_;
    std::vector<Motion *> motions_;             ///< every motion of both trees, for freeing
    std::shared_ptr<const EdgeChecker> edges_;  ///< made by setup()
    double range_ = 0.0;
    unsigned int batchSize_ = 8;
    bool shortcut_ = false;
    std::pair<const Motion *, const Motion *> connection_{nullptr, nullptr};  ///< (start tree, goal tree)
};
}  // namespace rastercheck::planners
