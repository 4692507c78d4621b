#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include <ompl/base/StateValidityChecker.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/ompl/StateMapping.h"

namespace rastercheck::ompl
{
/** \brief A Checker shared by the OMPL adapters (they outlive any one planner). */
using CheckerConstPtr = std::shared_ptr<const Checker>;

/** \brief OMPL's state validity checker backed by a rastercheck Checker. A state is valid when it
    satisfies the space's bounds (SpaceInformation::satisfiesBounds), its coordinates are finite and
    Checker::isValid accepts its configuration under the request given here.

    It computes clearance exactly (OMPL's specs say ClearanceComputationType EXACT): clearance() is
    Checker::distance less the request's padding, over the pairs the request checks (environment,
    self), so optimizing planners can maximise it (ompl::base::MaximizeMinClearanceObjective).

    The implementation is thread safe: it holds no mutable scratch (the configuration lives in a
    thread-local buffer) and counts calls and invalid verdicts with atomics, so one instance can serve
    parallel planners (pRRT, pSBL, CForest) and threaded benchmarks. */
class StateValidityChecker : public ::ompl::base::StateValidityChecker
{
public:
    /** \brief \a mapping must describe the state space of \a si; \a checker must check the mapping's
        robot. Throws ConfigurationError otherwise, or when \a request is malformed (validate()). */
    StateValidityChecker(const ::ompl::base::SpaceInformationPtr &si, StateMappingConstPtr mapping,
                         CheckerConstPtr checker, const CollisionRequest &request = {});

    using ::ompl::base::StateValidityChecker::isValid;
    bool isValid(const ::ompl::base::State *state) const override;

    /** \brief Same verdict as isValid(state); \a contact receives why an invalid state is invalid
        (Contact::Kind::OutOfBounds for states outside the space's bounds). */
    bool isValid(const ::ompl::base::State *state, Contact &contact) const;

    /** \brief isValid(state), and \a dist = clearance(state) for a valid state, 0 for an invalid one
        (the distance is then not computed). */
    bool isValid(const ::ompl::base::State *state, double &dist) const override;

    /** \brief The exact distance (metres) from the robot at \a state to the scene and between its
        non-exempt self pairs (those the request checks), less the request's padding: how far the
        robot is from an invalid state in the workspace. 0 for a state outside the bounds, not finite
        or colliding, never negative. CollisionRequest::pairPadding entries are not subtracted (its
        users, the certified edges, ask Checker::distance directly). Thread-safe. */
    double clearance(const ::ompl::base::State *state) const override;

    /** \brief Decides \a n states in one Checker::check call (one batch: one GPU pass where the
        checker has a device): valid[i] = 1 when isValid(states[i]) would return true. Counted as n
        calls. */
    void areValid(const ::ompl::base::State *const *states, std::size_t n, std::uint8_t *valid) const;

    /** \brief Number of isValid() calls since construction or resetCounters(). */
    std::uint64_t getCallCount() const { return calls_.load(std::memory_order_relaxed); }
    /** \brief Number of those calls that returned false. */
    std::uint64_t getInvalidCount() const { return invalid_.load(std::memory_order_relaxed); }
    void resetCounters()
    {
        calls_.store(0, std::memory_order_relaxed);
        invalid_.store(0, std::memory_order_relaxed);
    }

    const StateMapping &getStateMapping() const { return *mapping_; }
    const StateMappingConstPtr &getStateMappingPtr() const { return mapping_; }
    const Checker &getChecker() const { return *checker_; }
    const CheckerConstPtr &getCheckerPtr() const { return checker_; }
    const CollisionRequest &getRequest() const { return request_; }

private:
    bool decide(const ::ompl::base::State *state, Contact *contact) const;

    StateMappingConstPtr mapping_;
    CheckerConstPtr checker_;
    CollisionRequest request_;
    mutable std::atomic<std::uint64_t> calls_{0};
    mutable std::atomic<std::uint64_t> invalid_{0};
};

using StateValidityCheckerPtr = std::shared_ptr<StateValidityChecker>;
}  // namespace rastercheck::ompl
