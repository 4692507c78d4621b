#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/ompl/BatchMotionValidator.h"
#include "rastercheck/ompl/StateMapping.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rastercheck::ompl
{
/** \brief A motion validator that checks the states of an edge in batches through Checker::check.

    Resolution and verdicts are exactly those of ::ompl::base::DiscreteMotionValidator when the
    space information's validity checker is a StateValidityChecker with the same checker and
    request: an edge s1 -> s2 is split into n = space->validSegmentCount(s1, s2) segments, the
    states at t = j / n (j = 1 .. n-1) are made by space->interpolate, the state at j = n is s2
    itself, s1 is assumed valid, and a state is valid when it satisfies the space's bounds and the
    checker accepts it. checkMotion(s1, s2, lastValid) reports the first invalid index j as
    DiscreteMotionValidator does: lastValid.second = (j - 1) / n and lastValid.first =
    interpolate(s1, s2, lastValid.second). (A zero-length edge, n = 0, is checked as n = 1: its end
    state is s2; DiscreteMotionValidator would report the fraction -1/0 there.)

    Only the order differs ("rake", as in VAMP): the first batch holds s2 and states spread over
    the whole edge (breadth-first bisection), later batches fill in between, with doubling sizes,
    so a collision anywhere on the edge is found after few states. Once a collision is found,
    checkMotion(s1, s2) stops; checkMotion(s1, s2, lastValid) checks, in one more batch, only the
    unchecked states before it. checkMotions runs the scans of many edges side by side, each
    round's states of all of them in one batch.

    The implementation is thread safe: scratch buffers are thread-local (bounded between calls:
    detail::kKeptEdges), and the valid / invalid motion counters of the base class are updated with
    atomic operations (OMPL's own getters and the Benchmark's "valid segment fraction" read them). */
class MotionValidator : public BatchMotionValidator
{
public:
    /** \brief \a rakeWidth: states in the first batch (>= 1); later batches double. Throws
        ConfigurationError when the mapping is not \a si's or the checker does not fit it. */
    MotionValidator(const ::ompl::base::SpaceInformationPtr &si, StateMappingConstPtr mapping, CheckerConstPtr checker,
                    const CollisionRequest &request = {}, unsigned int rakeWidth = 8);

    /** \brief The edge checker of an existing StateValidityChecker: same mapping, checker and
        request, hence the same verdicts. */
    MotionValidator(const ::ompl::base::SpaceInformationPtr &si, const StateValidityChecker &validityChecker,
                    unsigned int rakeWidth = 8);

    void checkMotions(const Edge *edges, std::size_t n, std::uint8_t *valid,
                      double *lastValid = nullptr) const override;

    /** \brief States decided (interpolated states and end states) since construction or
        resetStateCounter(). */
    std::uint64_t getCheckedStateCount() const { return states_.load(std::memory_order_relaxed); }
    void resetStateCounter() { states_.store(0, std::memory_order_relaxed); }

    unsigned int getRakeWidth() const { return rakeWidth_; }

private:
    struct EdgeScan;
    /** \brief Fills scan.batch with the next state indices to check; leaves it empty when the scan
        is finished. */
    void nextBatch(EdgeScan &scan, bool wantFirst) const;

    StateMappingConstPtr mapping_;
    CheckerConstPtr checker_;
    CollisionRequest request_;
    unsigned int rakeWidth_;
    ::ompl::base::StateSpace *space_;
    mutable std::atomic<std::uint64_t> states_{0};
};

using MotionValidatorPtr = std::shared_ptr<MotionValidator>;
}  // namespace rastercheck::ompl
