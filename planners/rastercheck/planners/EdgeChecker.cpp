#include "rastercheck/planners/EdgeChecker.h"

#include <algorithm>
#include <cmath>

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

std::size_t EdgeChecker::checkAlong(const std::vector<ompl::Edge> &edges,
                                    const std::vector<std::pair<std::size_t, double>> &points,
                                    std::vector<std::uint8_t> &valid) const
{
    std::vector<ob::State *> inner;
    std::vector<const ob::State *> states;
    states.reserve(points.size());
    for (const auto &[e, fraction] : points)
    {
        if (fraction >= 1.0)
        {
            states.push_back(edges[e].to);
            continue;
        }
        inner.push_back(si_->allocState());
        si_->getStateSpace()->interpolate(edges[e].from, edges[e].to, fraction, inner.back());
        states.push_back(inner.back());
    }
    std::vector<std::uint8_t> stateValid;
    checkStates(states, stateValid);
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!stateValid[i])
            valid[points[i].first] = 0;
    for (ob::State *state : inner)
        si_->freeState(state);
    return states.size();
}

std::size_t EdgeChecker::rake(const std::vector<ompl::Edge> &edges, std::vector<unsigned int> &levels,
                              std::vector<std::uint8_t> &valid,
                              const std::vector<std::vector<std::size_t>> *paths) const
{
    valid.assign(edges.size(), 1);
    const double segment = si_->getStateSpace()->getLongestValidSegmentLength();
    std::vector<double> length(edges.size());
    for (std::size_t e = 0; e < edges.size(); ++e)
        length[e] = si_->distance(edges[e].from, edges[e].to);
    std::vector<std::uint8_t> live;  // the edge lies on a path not rejected yet
    auto findLive = [&]
    {
        if (!paths)
        {
            live = valid;
            return;
        }
        live.assign(edges.size(), 0);
        for (const std::vector<std::size_t> &path : *paths)
            if (std::all_of(path.begin(), path.end(), [&](std::size_t e) { return valid[e] != 0; }))
                for (std::size_t e : path)
                    live[e] = 1;
    };
    std::vector<std::pair<std::size_t, double>> points;
    std::size_t checked = 0;
    // Level L checks the odd multiples of 2^-L of every live edge still longer than 2^-L times the
    // segment length and not yet clean at that level.
    for (unsigned int level = 1;; ++level)
    {
        findLive();
        const double parts = std::ldexp(1.0, static_cast<int>(level));
        points.clear();
        bool deeper = false;  // some edge still needs this level
        for (std::size_t e = 0; e < edges.size(); ++e)
        {
            if (!live[e] || length[e] * 2.0 / parts <= segment)
                continue;
            deeper = true;
            if (level <= levels[e])
                continue;
            for (double j = 1.0; j < parts; j += 2.0)
                points.emplace_back(e, j / parts);
        }
        if (!deeper)
            break;
        checked += checkAlong(edges, points, valid);
        for (std::size_t e = 0; e < edges.size(); ++e)
            if (live[e] && valid[e] && levels[e] + 1 == level)
                levels[e] = level;
    }
    return checked;
}
}  // namespace rastercheck::planners
