#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/model/MotionBound.h"
#include "rastercheck/ompl/BatchMotionValidator.h"
#include "rastercheck/ompl/StateMapping.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rastercheck::ompl
{
/** \brief Options of a CertifiedMotionValidator. */
struct CertifiedMotionOptions
{
    /** \brief Clearance margin of the first, coarsest samples of an edge (the model's length unit,
        metres for URDF robots); 0 = a tenth of the robot's size (MotionBound::size; 11.3 cm for
        the Panda). Larger: fewer samples in open space, more refinement near obstacles. */
    double margin = 0.0;
    /** \brief How often a sample's margin may be halved where the robot comes closer than it; the
        finest margin is margin / 2^levels (28 um for the Panda's default). An edge that passes
        nearer than that without touching cannot be certified and is rejected. At most 40. */
    unsigned int levels = 12;
    /** \brief Coarsest samples checked in the first batch of an edge (>= 1); later batches double,
        in the rake order of MotionValidator (every prefix spread over the edge). One: most edges a
        planner rejects collide over a good part of their length, and one midpoint rejects them
        where a first batch of 8 paid 8 (OMPL.app Home, lazy BatchRRTConnect: 1.53 M -> 0.38 M
        states per solve, 2.5x faster; no problem set slower, docs/benchmarks.md "Rake width of
        certified edges"). Wider first batches make fewer, larger checker calls, for a backend whose
        calls cost more than their states. */
    unsigned int rakeWidth = 1;
    /** \brief The first batch's coarsest midpoints per edge (>= 1; at least rakeWidth) where that
        first batch reaches the GPU (checkMotions of n edges: n x deviceRakeWidth states, at least
        Checker::deviceBatch()): a device call costs about its latency whatever its few hundred
        states, so fewer rounds pay for more states there (Panda edges, every call on the stages:
        4.28 -> 2.32 calls an edge for 25.0 states against 23.4; docs/benchmarks.md "Certified
        edges' first batch on the device"). Batches on the CPU keep rakeWidth. */
    unsigned int deviceRakeWidth = 8;
    /** \brief Where a midpoint misses its margin, size what it certifies by its clearance
        (Checker::freeRadius: each pair's exact distance against what it can close in along the
        edge) instead of halving the interval: conservative advancement. It checks fewer states
        (Panda MotionBenchMaker edges, bench/edges: 24.7 -> 19.6 per edge, plus 3 clearances) but
        an exact clearance costs about fifty checks there (6.6x the time per edge; 1.4x with
        clearanceMeasure HullBound, 20.3 states), so it is off by default (docs/benchmarks.md,
        "Edges sized by clearance"). */
    bool sizeByClearance = false;
    /** \brief How sizeByClearance measures a midpoint's clearance (Checker::freeRadius): the exact
        distances, or the hulls' lower bounds (ClearanceMeasure::HullBound), which certify a
        little less of each interval for far less time. */
    ClearanceMeasure clearanceMeasure = ClearanceMeasure::Exact;
};

/** \brief A motion validator whose accepted edges are collision-free at every point, not only at
    sampled states: continuous collision checking for the planner's straight edges.

    For an edge s1 -> s2, MotionBound gives, per component, a bound on how far any of its points travels
    along it, and per self pair, on how much the distance between their points can change (only the
    joints between the two links count). Over an interval of fractions of length h, a component then
    moves at most its sweep x h / 2 from where it is at the interval's midpoint, and a self pair closes
    in by at most its sweep x h / 2: a midpoint whose every pair is clear by that much more than the
    padding p certifies the whole interval. The sweeps are measured about the links' poses halfway
    along the edge (MotionBound::sweeps about a reference: a joint turns a point by its distance
    from the joint's axis there, which the chain's lengths only bound), and for the refinements of
    each coarse interval about its own middle, tighter still. The edge is covered by intervals of
    equal length, the longest for which no pair needs more than the margin. Each midpoint is checked once, in the
    request's own mode, at two paddings (Checker::checkTwoPaddings: the request's, and its interval's
    sweeps on top, per pair): clear by the sweeps certifies the interval; in collision at p ends the
    search (a real collision); valid but nearer than the sweeps halves the interval, each half needing
    half the margin, down to margin / 2^levels. (In safe and exact mode the pairs the proofs leave go to
    the exact narrow phase, which settles them where conservative mode would call every unproven pair a
    false alarm and pay for it with two finer midpoints: Panda MotionBenchMaker edges, bench/edges: 30
    -> 25 states and 1.3x less time per edge.) With CertifiedMotionOptions::sizeByClearance, a near
    midpoint's clearance (Checker::freeRadius) certifies the part of its interval the motion bound keeps
    clear instead, and only the two sides left go on (conservative advancement). Intervals of one level
    are checked together in one batch (many states in one pass), the coarsest in rake order.
    checkMotions runs the searches of many edges side by side: each round's midpoints of all of them go
    to the checker in one batch, each state with its own edge's pair paddings (PairPadding rows), so
    every edge gets the verdict it gets alone. The base of a robot that does not move is held to the
    padding p only, and two links a joint apart only to what that joint can do between them.

    Semantics: checkMotion(s1, s2) returns true only when every state of the edge, s1 and s2
    included, satisfies the bounds and is valid at the request's padding (in Safe or Exact mode,
    whose verdicts are exact; Raster mode is refused). It may return false for an edge that does
    not collide but passes within margin / 2^levels of a collision (or, in conservative mode, where
    the proofs cannot show it clear), or whose L is infinite (a
    non-finite coordinate, a mimic joint following a continuous joint across +-pi).
    checkMotion(s1, s2, lastValid) returns the largest fraction up to which the edge was certified
    (the start of the first interval that could not be), and that state. s1 is not assumed valid:
    it is certified with the rest.

    Thread safe: scratch buffers are thread-local (what a thread keeps between calls is bounded:
    detail::kKeptEdges), the counters atomic. */
class CertifiedMotionValidator : public BatchMotionValidator
{
public:
    /** \brief The edge checker of an existing StateValidityChecker: same mapping, checker and
        request. Throws ConfigurationError for a Raster-mode request, a negative or non-finite
        margin, levels above 40 or a zero rake width. */
    CertifiedMotionValidator(const ::ompl::base::SpaceInformationPtr &si, const StateValidityChecker &validityChecker,
                             const CertifiedMotionOptions &options = {});

    void checkMotions(const Edge *edges, std::size_t n, std::uint8_t *valid,
                      double *lastValid = nullptr) const override;

    /** \brief States decided since construction or resetStateCounter(). */
    std::uint64_t getCheckedStateCount() const { return states_.load(std::memory_order_relaxed); }
    /** \brief Clearances measured (Checker::freeRadius, one per midpoint that missed its margin)
        since construction or resetStateCounter(); not among the checked states. */
    std::uint64_t getClearanceCount() const { return clearances_.load(std::memory_order_relaxed); }
    void resetStateCounter()
    {
        states_.store(0, std::memory_order_relaxed);
        clearances_.store(0, std::memory_order_relaxed);
    }

    /** \brief The coarsest margin in use (options.margin, or its default). */
    double getMargin() const { return margin_; }
    /** \brief Coarsest midpoints in an edge's first batch (options.rakeWidth). */
    unsigned int getRakeWidth() const { return rakeWidth_; }
    /** \brief The same where checkMotions of \a edges edges sends its first batch to the GPU
        (options.deviceRakeWidth), else getRakeWidth(). */
    unsigned int firstBatchWidth(std::size_t edges) const;
    const MotionBound &getMotionBound() const { return bound_; }

private:
    struct EdgeSearch;
    /** \brief Starts \a search on \a edge: bounds, sweeps and the coarsest intervals in rake order,
        \a width of them in the first batch; finished at once when an end is outside the bounds or
        the sweeps are not finite. */
    void start(const Edge &edge, unsigned int width, EdgeSearch &search) const;
    /** \brief Fills search.batch with the next midpoints to check (finishing levels on the way);
        leaves it empty when the search is finished. */
    void nextBatch(EdgeSearch &search) const;
    /** \brief Ends the search's current level: what is left of its intervals whose midpoints missed
        their margin becomes the next level's (or the search finishes). */
    void endLevel(EdgeSearch &search) const;
    /** \brief The sweeps (per unit of the edge) of \a search's edge for the part within \a halfSpan
        of \a fraction: MotionBound::sweeps about the links' poses there. */
    void sweepsAbout(const EdgeSearch &search, double fraction, double halfSpan, double *componentSweeps,
                     double *pairSweeps) const;
    /** \brief The sweeps that pad the refined midpoints within coarse interval \a coarse: those of
        its span of the edge, measured the first time one is asked. */
    void intervalSweeps(EdgeSearch &search, std::uint32_t coarse, const double *&componentSweeps,
                        const double *&pairSweeps) const;

    /** \brief The robot configurations of the midpoints of the batches of \a searches, in order. */
    void midpointRows(const std::vector<EdgeSearch *> &searches, bool closeOnly, std::vector<double> &rows) const;

    StateMappingConstPtr mapping_;
    CheckerConstPtr checker_;
    CollisionRequest request_;
    MotionBound bound_;
    double margin_;
    unsigned int levels_;
    unsigned int rakeWidth_;
    unsigned int deviceRakeWidth_;
    bool sizeByClearance_;
    ClearanceMeasure clearanceMeasure_;
    ::ompl::base::StateSpace *space_;
    mutable std::atomic<std::uint64_t> states_{0};
    mutable std::atomic<std::uint64_t> clearances_{0};
};

using CertifiedMotionValidatorPtr = std::shared_ptr<CertifiedMotionValidator>;
}  // namespace rastercheck::ompl
