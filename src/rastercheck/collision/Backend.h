#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/collision/CollisionRequest.h"

namespace rastercheck
{
/** \brief Runs the pipeline for a batch of states. Implementations must be thread-safe: check()
    may be called from several threads at once (each call keeps its own scratch). */
class Backend
{
public:
    virtual ~Backend() = default;
    /** \brief "cpu" or "cuda (<device name>)". */
    virtual std::string name() const = 0;
    /** \brief Decides \a n states. \a q: n x numCoordinates, row-major. \a valid: n entries, 1 = valid.
        \a contacts: null, or n entries receiving the first contact of each invalid state.
        \a threads: worker threads for this call (CPU backend; 0 = all cores). Never throws for
        bad states: those are invalid (Contact::Kind::OutOfBounds). */
    virtual void check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts,
                       const CollisionRequest &request, int threads) const = 0;
    /** \brief Decides \a n states at two paddings in one pass: the request's, and the request's
        plus row i of \a wider (PairPadding: 1 row or n, entries >= 0) for state i; \a verdicts: n
        PaddedVerdict values. Returns false, deciding nothing, where the backend has no such pass
        (Checker::checkTwoPaddings then runs two). */
    virtual bool checkTwoPaddings(const double * /*q*/, std::size_t /*n*/, std::uint8_t * /*verdicts*/,
                                  const CollisionRequest & /*request*/, const PairPadding & /*wider*/,
                                  int /*threads*/) const
    {
        return false;
    }
};
}  // namespace rastercheck
