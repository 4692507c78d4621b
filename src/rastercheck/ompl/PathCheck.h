#pragma once

#include <cstddef>
#include <vector>

#include <ompl/geometric/PathGeometric.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/ompl/StateMapping.h"

namespace rastercheck::ompl
{
/** \brief What checkPathDensely found. */
struct PathCheckResult
{
    bool valid = true;
    std::size_t statesChecked = 0;
    /** \brief For an invalid path: the segment (from state i to state i + 1) holding the first invalid
        state, the time of that state on the segment (0 = state i), its configuration and why. */
    std::size_t segment = 0;
    double time = 0.0;
    std::vector<double> configuration;
    Contact contact;
};

/** \brief Re-checks a solution path densely: every segment is split into \a resolutionFactor times
    as many pieces as the space's validSegmentCount (the planner's resolution), and every state (the
    path's states included) must satisfy the space's bounds and pass \a checker under \a request
    (typically CollisionMode::Exact: the oracle). States are checked in batches. */
PathCheckResult checkPathDensely(const ::ompl::geometric::PathGeometric &path, const StateMapping &mapping,
                                 const Checker &checker, const CollisionRequest &request,
                                 unsigned int resolutionFactor = 10);
}  // namespace rastercheck::ompl
