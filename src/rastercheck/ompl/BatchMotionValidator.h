#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/SpaceInformation.h>

namespace rastercheck::ompl
{
/** \brief A straight motion from one state to another, as OMPL's checkMotion takes it. */
struct Edge
{
    const ::ompl::base::State *from = nullptr;
    const ::ompl::base::State *to = nullptr;
};

/** \brief A motion validator that decides many edges together: the checks of all of them go to the
    Checker in shared batches (one Checker::check per round of the edges' searches), so a planner
    that grows many edges at once (rastercheck::planners::BatchRRTConnect) hands the checker
    hundreds of states per call instead of a few per edge.

    checkMotions(edges) gives every edge the verdict checkMotion(from, to) gives it alone: batching
    changes how the work is grouped, never a verdict. Thread safe like the validators deriving
    from it. */
class BatchMotionValidator : public ::ompl::base::MotionValidator
{
public:
    using ::ompl::base::MotionValidator::MotionValidator;

    /** \brief Decides the \a n edges: valid[i] = 1 when edge i is accepted. When \a lastValid is
        given, lastValid[i] receives the fraction of edge i known valid (as checkMotion(s1, s2,
        lastValid) gives for a rejected edge; 1 for an accepted one); without it the search of an
        edge stops at its first sign of rejection. Counts every edge in the valid/invalid motion
        counters. */
    virtual void checkMotions(const Edge *edges, std::size_t n, std::uint8_t *valid,
                              double *lastValid = nullptr) const = 0;

    /** \brief One edge: checkMotions of it alone. */
    bool checkMotion(const ::ompl::base::State *s1, const ::ompl::base::State *s2) const override
    {
        const Edge edge{s1, s2};
        std::uint8_t valid = 0;
        checkMotions(&edge, 1, &valid);
        return valid != 0;
    }

    /** \brief One edge; for a rejected one, lastValid.second = the fraction known valid and
        lastValid.first (when given) the state there. */
    bool checkMotion(const ::ompl::base::State *s1, const ::ompl::base::State *s2,
                     std::pair<::ompl::base::State *, double> &lastValid) const override
    {
        const Edge edge{s1, s2};
        std::uint8_t valid = 0;
        double prefix = 0.0;
        checkMotions(&edge, 1, &valid, &prefix);
        if (!valid)
        {
            lastValid.second = prefix;
            if (lastValid.first != nullptr)
                si_->getStateSpace()->interpolate(s1, s2, prefix, lastValid.first);
        }
        return valid != 0;
    }
};
}  // namespace rastercheck::ompl
