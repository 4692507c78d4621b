#pragma once

#include <cmath>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>

#include "Reference.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rastercheck::bench
{
namespace ob = ::ompl::base;

/** \brief FCL as an OMPL validity checker. FclReference is not thread-safe, so each thread gets its
    own instance, owned by the checker and freed with it (a thread-local cache that outlived its
    checkers kept every problem's FCL models: 50 MB per UR5 problem, and the 700-problem bench ran
    out of memory). The lock costs tens of nanoseconds against FCL's microseconds per state. */
class FclStateValidityChecker : public ob::StateValidityChecker
{
public:
    FclStateValidityChecker(const ob::SpaceInformationPtr &si, rastercheck::ompl::StateMappingConstPtr mapping,
                            rastercheck::ompl::CheckerConstPtr owner)
        : ob::StateValidityChecker(si), mapping_(std::move(mapping)), owner_(std::move(owner))
    {
    }

    bool isValid(const ob::State *state) const override
    {
        if (!si_->satisfiesBounds(state))
            return false;
        test::FclReference *fcl = nullptr;
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            std::unique_ptr<test::FclReference> &mine = references_[std::this_thread::get_id()];
            if (!mine)
                mine = std::make_unique<test::FclReference>(owner_->collisionModel());
            fcl = mine.get();
        }
        thread_local std::vector<double> q;
        q.resize(mapping_->numCoordinates());
        mapping_->toConfiguration(state, q.data());
        for (double v : q)
            if (!std::isfinite(v))
                return false;
        return !fcl->collides(q.data());
    }

private:
    rastercheck::ompl::StateMappingConstPtr mapping_;
    rastercheck::ompl::CheckerConstPtr owner_;  ///< only for its collision model (robot, scene, ACM)
    mutable std::mutex mutex_;
    mutable std::unordered_map<std::thread::id, std::unique_ptr<test::FclReference>> references_;
};
}  // namespace rastercheck::bench
