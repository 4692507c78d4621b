#include "rastercheck/ompl/StateValidityChecker.h"

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

bool StateValidityChecker::isValid(const ::ompl::base::State *state) const
{
    return decide(state, nullptr);
}

bool StateValidityChecker::isValid(const ::ompl::base::State *state, Contact &contact) const
{
    return decide(state, &contact);
}
}  // namespace rastercheck::ompl
