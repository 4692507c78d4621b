#include "rastercheck/planners/EdgeChecker.h"

#include "rastercheck/planners/Log.h"

#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/MotionValidator.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace ob = ::ompl::base;

namespace rastercheck::planners
{
EdgeChecker::EdgeChecker(const ob::SpaceInformationPtr &si) : si_(si)
{
    states_ = dynamic_cast<const ompl::StateValidityChecker *>(si_->getStateValidityChecker().get());
    const ob::MotionValidatorPtr &validator = si_->getMotionValidator();
    batch_ = dynamic_cast<const ompl::BatchMotionValidator *>(validator.get());
    if (batch_)
    {
        description_ = dynamic_cast<const ompl::CertifiedMotionValidator *>(batch_) ? "certified" : "batched";
        return;
    }
    if (!states_)
    {
        description_ = "one at a time";
        return;
    }
    // Only raster mode falls back (it cannot certify an edge); any other setup error is the caller's.
    if (ompl::resolveEdgeChecking(ompl::EdgeChecking::Auto, states_->getRequest().mode) == ompl::EdgeChecking::Batched)
    {
        OMPL_LOG(WARN, "raster mode cannot certify an edge; edges are checked at the space's resolution instead");
        owned_ = std::make_shared<ompl::MotionValidator>(si_, *states_);
        description_ = "batched";
    }
    else
    {
        owned_ = std::make_shared<ompl::CertifiedMotionValidator>(si_, *states_);
        description_ = "certified";
    }
    batch_ = owned_.get();
}

void EdgeChecker::check(const std::vector<ompl::Edge> &edges, std::vector<std::uint8_t> &valid) const
{
    valid.assign(edges.size(), 0);
    if (edges.empty())
        return;
    if (batch_)
    {
        batch_->checkMotions(edges.data(), edges.size(), valid.data());
        return;
    }
    for (std::size_t i = 0; i < edges.size(); ++i)
        valid[i] = si_->checkMotion(edges[i].from, edges[i].to) ? 1 : 0;
}

void EdgeChecker::checkStates(const std::vector<const ob::State *> &states, std::vector<std::uint8_t> &valid) const
{
    valid.assign(states.size(), 0);
    if (states.empty())
        return;
    if (states_)
    {
        states_->areValid(states.data(), states.size(), valid.data());
        return;
    }
    for (std::size_t i = 0; i < states.size(); ++i)
        valid[i] = si_->isValid(states[i]) ? 1 : 0;
}
}  // namespace rastercheck::planners
