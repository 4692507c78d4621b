#pragma once

#include <string>
#include <utility>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/ompl/StateMapping.h"

/** \file Pieces the two motion validators (MotionValidator, CertifiedMotionValidator) share. */

namespace rastercheck::ompl::detail
{
/** \brief Indices 1 .. n in rake order (VAMP): n first, then the midpoints of a breadth-first
    bisection of [1, n - 1], so that every prefix is spread over the whole range and a collision
    anywhere on an edge is met after few checks. \a intervals is scratch. */
inline void rakeOrder(unsigned int n, std::vector<unsigned int> &order,
                      std::vector<std::pair<unsigned int, unsigned int>> &intervals)
{
    order.clear();
    order.push_back(n);
    if (n < 2)
        return;
    intervals.clear();
    intervals.emplace_back(1u, n - 1);
    for (std::size_t head = 0; head < intervals.size(); ++head)
    {
        const auto [first, last] = intervals[head];
        const unsigned int mid = first + (last - first) / 2;
        order.push_back(mid);
        if (first < mid)
            intervals.emplace_back(first, mid - 1);
        if (last > mid)
            intervals.emplace_back(mid + 1, last);
    }
}

/** \brief What a thread keeps of a validator's scratch between calls: the searches of at most
    kKeptEdges edges and no buffer with room for more than kKeptValues entries. Enough for a
    planner's batches (8 to tens of edges); the memory of a larger batch, or of a very long edge, is
    returned when the call ends instead of staying with the thread for good. (Fresh buffers at every
    call instead cost about 5 % per certified edge in bench/edges.) */
constexpr std::size_t kKeptEdges = 64;
constexpr std::size_t kKeptValues = std::size_t(1) << 14;

/** \brief Frees \a buffer when it has room for more than kKeptValues entries. */
template <class T>
void releaseIfLarge(std::vector<T> &buffer)
{
    if (buffer.capacity() > kKeptValues)
        std::vector<T>().swap(buffer);
}

/** \brief Counts one motion in ompl::base::MotionValidator's counters (\a valid or \a invalid):
    plain integers that OMPL's getters read, updated atomically because planner threads share a
    validator. */
inline void countMotion(unsigned int &validCount, unsigned int &invalidCount, bool valid)
{
    __atomic_fetch_add(valid ? &validCount : &invalidCount, 1u, __ATOMIC_RELAXED);
}

/** \brief Throws ConfigurationError, naming \a who, unless \a mapping and \a checker exist, the
    mapping's space is \a si's and the checker's robot has the mapping's coordinates. */
inline void requireMatchingParts(const ::ompl::base::SpaceInformationPtr &si, const StateMappingConstPtr &mapping,
                                 const CheckerConstPtr &checker, const std::string &who)
{
    if (!mapping || !checker)
        throw ConfigurationError(who + " needs a state mapping and a checker");
    if (si->getStateSpace() != mapping->getStateSpace())
        throw ConfigurationError(who + ": the space information's state space is not the mapping's");
    if (checker->dof() != mapping->numCoordinates())
        throw ConfigurationError(who + ": the checker's robot does not match the mapping's");
}
}  // namespace rastercheck::ompl::detail
