#include "rastercheck/ompl/MotionValidator.h"

#include <algorithm>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/ompl/EdgeChecks.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
namespace
{
/** \brief Per-thread buffers of findInvalid (a validator is shared by planner threads). */
struct Scratch
{
    std::vector<unsigned int> order;
    std::vector<std::pair<unsigned int, unsigned int>> intervals;
    std::vector<unsigned int> batch;
    std::vector<unsigned int> inBounds;  ///< indices of batch whose state satisfies the bounds
    std::vector<double> rows;            ///< inBounds.size() x dof
    std::vector<std::uint8_t> verdicts;
};

Scratch &scratch()
{
    thread_local Scratch buffers;
    return buffers;
}
}  // namespace

MotionValidator::MotionValidator(const ob::SpaceInformationPtr &si, StateMappingConstPtr mapping,
                                 CheckerConstPtr checker, const CollisionRequest &request, unsigned int rakeWidth)
    : ob::MotionValidator(si),
      mapping_(std::move(mapping)),
      checker_(std::move(checker)),
      request_(request),
      rakeWidth_(rakeWidth),
      space_(si->getStateSpace().get())
{
    detail::requireMatchingParts(si, mapping_, checker_, "MotionValidator");
    if (rakeWidth_ == 0)
        throw ConfigurationError("MotionValidator: the rake width must be at least 1");
}

MotionValidator::MotionValidator(const ob::SpaceInformationPtr &si, const StateValidityChecker &validityChecker,
                                 unsigned int rakeWidth)
    : MotionValidator(si, validityChecker.getStateMappingPtr(), validityChecker.getCheckerPtr(),
                      validityChecker.getRequest(), rakeWidth)
{
}

unsigned int MotionValidator::findInvalid(const ob::State *s1, const ob::State *s2, unsigned int nd,
                                          bool wantFirst) const
{
    Scratch &w = scratch();
    detail::rakeOrder(nd, w.order, w.intervals);
    const std::size_t dof = mapping_->numCoordinates();
    ob::State *test = si_->allocState();
    unsigned int found = 0;
    std::size_t next = 0;
    std::size_t width = rakeWidth_;
    while (next < w.order.size())
    {
        w.batch.clear();
        if (found == 0)
        {
            const std::size_t end = std::min(w.order.size(), next + width);
            w.batch.assign(w.order.begin() + static_cast<std::ptrdiff_t>(next),
                           w.order.begin() + static_cast<std::ptrdiff_t>(end));
            next = end;
            width *= 2;
        }
        else
        {
            // Everything before the collision found so far, at once: the first invalid is among them or is it.
            for (; next < w.order.size(); ++next)
                if (w.order[next] < found)
                    w.batch.push_back(w.order[next]);
            if (w.batch.empty())
                break;
        }

        w.inBounds.clear();
        w.rows.resize(w.batch.size() * dof);
        for (unsigned int j : w.batch)
        {
            const ob::State *state = s2;
            if (j != nd)
            {
                space_->interpolate(s1, s2, static_cast<double>(j) / static_cast<double>(nd), test);
                state = test;
            }
            if (!si_->satisfiesBounds(state))
            {
                found = found == 0 ? j : std::min(found, j);
                continue;
            }
            mapping_->toConfiguration(state, w.rows.data() + w.inBounds.size() * dof);
            w.inBounds.push_back(j);
        }
        w.verdicts.resize(w.inBounds.size());
        if (!w.inBounds.empty())
            checker_->check(w.rows.data(), w.inBounds.size(), w.verdicts.data(), request_);
        states_.fetch_add(w.batch.size(), std::memory_order_relaxed);
        for (std::size_t i = 0; i < w.inBounds.size(); ++i)
            if (!w.verdicts[i])
                found = found == 0 ? w.inBounds[i] : std::min(found, w.inBounds[i]);
        if (found != 0 && !wantFirst)
            break;
    }
    si_->freeState(test);
    return found;
}

bool MotionValidator::checkMotion(const ob::State *s1, const ob::State *s2) const
{
    const unsigned int nd = std::max(1u, space_->validSegmentCount(s1, s2));
    const bool valid = findInvalid(s1, s2, nd, false) == 0;
    detail::countMotion(valid_, invalid_, valid);
    return valid;
}

bool MotionValidator::checkMotion(const ob::State *s1, const ob::State *s2,
                                  std::pair<ob::State *, double> &lastValid) const
{
    const unsigned int nd = std::max(1u, space_->validSegmentCount(s1, s2));
    const unsigned int first = findInvalid(s1, s2, nd, true);
    if (first != 0)
    {
        lastValid.second = static_cast<double>(first - 1) / static_cast<double>(nd);
        if (lastValid.first != nullptr)
            space_->interpolate(s1, s2, lastValid.second, lastValid.first);
    }
    detail::countMotion(valid_, invalid_, first == 0);
    return first == 0;
}
}  // namespace rastercheck::ompl
