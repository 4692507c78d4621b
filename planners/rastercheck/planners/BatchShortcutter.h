#pragma once

#include <memory>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/util/RandomNumbers.h>

#include "rastercheck/planners/EdgeChecker.h"

namespace rastercheck::planners
{
/** \brief Path shortcutting whose candidate shortcuts are decided in batches (OMPL's PathSimplifier
    checks them one by one).

    Each round draws candidates: pairs of points on the path (a point is a vertex or anywhere on
    an edge; a quarter of the pairs are vertex pairs) whose straight line is shorter than the path
    between them. All candidate lines are raked together (EdgeChecker::rake: states at rising
    density, which reject most lines that cross an obstacle for a few checks); of the lines left,
    non-overlapping shortcuts are chosen greedily by the length they save, the chosen ones are
    decided together (EdgeChecker: certified edges unless the setup chose otherwise; batched edges
    decide every candidate at once instead of a rake), and the path is rebuilt with those accepted.
    Rounds go on until \a idleRounds in a row save less than a thousandth of the length, or the
    termination condition says stop.

    A shortcut never makes a path collide: every line it adds is decided by the edge checker, and
    the rest of the path is pieces of its own edges (with certified edges, collision-free at every
    point). Randomness comes from OMPL's RNG (seeded runs are reproducible). Not thread safe (one
    per thread); the edge checker it uses is. */
class BatchShortcutter
{
public:
    explicit BatchShortcutter(const ::ompl::base::SpaceInformationPtr &si);
    /** \brief With an edge checker shared with a planner. */
    BatchShortcutter(const ::ompl::base::SpaceInformationPtr &si, std::shared_ptr<const EdgeChecker> edges);

    /** \brief Shortens \a path in place; true when it changed. */
    bool shortcut(::ompl::geometric::PathGeometric &path, const ::ompl::base::PlannerTerminationCondition &ptc);

    /** \brief Candidate shortcuts per round (>= 1). */
    unsigned int candidates = 16;
    /** \brief Rounds in a row without a real gain before stopping. */
    unsigned int idleRounds = 2;

    const EdgeChecker &edgeChecker() const { return *edges_; }

private:
    ::ompl::base::SpaceInformationPtr si_;
    std::shared_ptr<const EdgeChecker> edges_;
    ::ompl::RNG rng_;
};
}  // namespace rastercheck::planners
