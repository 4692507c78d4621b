#include "rastercheck/ompl/StateValidityChecker.h"

#include <algorithm>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"

namespace rastercheck::ompl
{
StateValidityChecker::StateValidityChecker(const ::ompl::base::SpaceInformationPtr &si, StateMappingConstPtr mapping,
                                           CheckerConstPtr checker, const CollisionRequest &request)
    : ::ompl::base::StateValidityChecker(si),
      mapping_(std::move(mapping)),
      checker_(std::move(checker)),
      request_(request)
{
    if (!mapping_ || !checker_)
        throw ConfigurationError("StateValidityChecker needs a state mapping and a checker");
    if (si->getStateSpace() != mapping_->getStateSpace())
        throw ConfigurationError("StateValidityChecker: the space information's state space is not the mapping's");
    if (checker_->dof() != mapping_->numCoordinates())
        throw ConfigurationError("StateValidityChecker: the checker's robot has " + std::to_string(checker_->dof()) +
                                 " coordinates, the mapping's " + std::to_string(mapping_->numCoordinates()));
    validate(request_);  // here, not first inside a planner's isValid()
    specs_.clearanceComputationType = ::ompl::base::StateValidityCheckerSpecs::EXACT;
}

bool StateValidityChecker::decide(const ::ompl::base::State *state, Contact *contact) const
{
    calls_.fetch_add(1, std::memory_order_relaxed);
    bool valid = si_->satisfiesBounds(state);
    if (!valid && contact != nullptr)
    {
        *contact = Contact{};
        contact->kind = Contact::Kind::OutOfBounds;
    }
    if (valid)
    {
        // One buffer per thread, reused across calls: no allocation and no sharing on the hot path.
        thread_local std::vector<double> q;
        q.resize(mapping_->numCoordinates());
        mapping_->toConfiguration(state, q.data());
        valid = checker_->isValid(q.data(), request_, contact);  // also rejects non-finite values
    }
    if (!valid)
        invalid_.fetch_add(1, std::memory_order_relaxed);
    return valid;
}

void StateValidityChecker::areValid(const ::ompl::base::State *const *states, std::size_t n, std::uint8_t *valid) const
{
    calls_.fetch_add(n, std::memory_order_relaxed);
    // Every state goes to the checker, so that its warnings count states as the caller does; one
    // outside the bounds (rare: samplers draw inside them) is then overruled.
    thread_local std::vector<double> q;
    const std::size_t dof = mapping_->numCoordinates();
    q.resize(n * dof);
    for (std::size_t i = 0; i < n; ++i)
        mapping_->toConfiguration(states[i], q.data() + i * dof);
    checker_->check(q.data(), n, valid, request_);
    std::uint64_t rejected = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
        valid[i] = valid[i] && si_->satisfiesBounds(states[i]) ? 1 : 0;
        rejected += valid[i] ? 0 : 1;
    }
    invalid_.fetch_add(rejected, std::memory_order_relaxed);
}

bool StateValidityChecker::isValid(const ::ompl::base::State *state) const
{
    return decide(state, nullptr);
}

bool StateValidityChecker::isValid(const ::ompl::base::State *state, Contact &contact) const
{
    return decide(state, &contact);
}

bool StateValidityChecker::isValid(const ::ompl::base::State *state, double &dist) const
{
    const bool valid = decide(state, nullptr);
    dist = valid ? clearance(state) : 0.0;
    return valid;
}

double StateValidityChecker::clearance(const ::ompl::base::State *state) const
{
    if (!si_->satisfiesBounds(state))
        return 0.0;
    thread_local std::vector<double> q;
    q.resize(mapping_->numCoordinates());
    mapping_->toConfiguration(state, q.data());
    DistanceRequest request;
    request.checkEnvironment = request_.checkEnvironment;
    request.checkSelfCollision = request_.checkSelfCollision;
    DistanceResult result;
    checker_->distance(q.data(), request, &result);  // a state not finite is OutOfBounds: distance 0
    // Nothing to measure (no object, no self pair): nothing can make the state invalid.
    return std::max(0.0, result.distance - request_.padding);
}
}  // namespace rastercheck::ompl
