#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
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
    own instance (keyed by a per-checker id, not by address, so that a new checker never reuses an
    old one's). */
class FclStateValidityChecker : public ob::StateValidityChecker
{
public:
    FclStateValidityChecker(const ob::SpaceInformationPtr &si, rastercheck::ompl::StateMappingConstPtr mapping,
                            rastercheck::ompl::CheckerConstPtr owner)
        : ob::StateValidityChecker(si), mapping_(std::move(mapping)), owner_(std::move(owner)), id_(nextId_++)
    {
    }

    bool isValid(const ob::State *state) const override
    {
        if (!si_->satisfiesBounds(state))
            return false;
        thread_local std::unordered_map<std::uint64_t, std::unique_ptr<test::FclReference>> references;
        thread_local std::vector<double> q;
        std::unique_ptr<test::FclReference> &fcl = references[id_];
        if (!fcl)
            fcl = std::make_unique<test::FclReference>(owner_->collisionModel());
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
    std::uint64_t id_;
    static inline std::atomic<std::uint64_t> nextId_{0};
};
}  // namespace rastercheck::bench
