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
};
}  // namespace rastercheck
