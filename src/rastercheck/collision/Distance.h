#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/collision/CollisionRequest.h"
#include "rastercheck/core/Pool.h"
#include "rastercheck/collision/Penetration.h"

namespace rastercheck
{
/** \brief What a distance query measures (Coal/FCL style). */
struct DistanceRequest
{
    /** \brief Measure the components against the scene's objects. */
    bool checkEnvironment = true;
    /** \brief Measure the self pairs the allowed-collision matrix does not exempt. */
    bool checkSelfCollision = true;
    /** \brief The query stops as soon as it knows the distance is at least this (metres, > 0):
        the answer is then DistanceResult::capped with distance equal to this bound, no pair named.
        For callers that need only a threshold ("is the clearance at least d?"): pairs and node pairs
        whose lower bounds reach it are never measured. Infinity (the default): the exact minimum. */
    double upperBound = std::numeric_limits<double>::infinity();
    /** \brief On a colliding state, also measure how deep the pair named overlaps
        (DistanceResult::penetration; Penetration says what is and is not returned). Off by default:
        a query that does not ask pays nothing. */
    bool penetration = false;
};

/** \brief How DistanceQueries::freeRadius measures each pair's distance. */
enum class ClearanceMeasure
{
    /** \brief The exact distance (the triangle walks, about 200 us per Panda clearance): the
        longest step the motion allows. */
    Exact,
    /** \brief A lower bound from the convex hulls (device::hullDistanceLowerBound: GJK over each
        solid's hull points, less its hull slack); where the whole hulls meet, the least bound over
        the solids' shells or patches (device::patchesLowerBound); 0 where those meet too, so that
        the state gets no step (a certified edge then halves the interval, as bisection does). A
        bound is as sound a proof as the distance (a step it allows is one the distance allows),
        shorter where a hull stands far out of its solid, and takes a few microseconds per pair.
        Pairs with curved primitives keep their exact (GJK) distance. */
    HullBound
};

/** \brief Throws ConfigurationError unless upperBound is > 0 (NaN is not). */
void validate(const DistanceRequest &request);

/** \brief The smallest distance between the robot and the scene, and between the robot's non-exempt
    self pairs, at one state, with the pair and a closest pair of points. */
struct DistanceResult
{
    /** \brief Metres (the scene's units). 0 when the state collides (surfaces crossing or touching,
        or one solid inside another): then the pair and the points are a contact. The upper bound
        when capped; infinity when there was nothing to measure (no object and no self pair). */
    double distance = std::numeric_limits<double>::infinity();
    /** \brief The distance is at least DistanceRequest::upperBound: distance = that bound and no
        pair is named. */
    bool capped = false;
    /** \brief Environment or SelfCollision for the pair measured; OutOfBounds for a state outside
        the bounds or not finite (distance 0, \a coordinate named, nothing measured); None when
        capped or nothing was measured. */
    Contact::Kind kind = Contact::Kind::None;
    int component = -1;       ///< the pair's component
    int object = -1;          ///< Environment: the scene object
    int otherComponent = -1;  ///< SelfCollision: the second component
    /** \brief Triangle of the component's mesh the closest point lies on; -1 when measured on a
        primitive shape (curved primitives are measured on their exact shapes, CurvedSolids) or
        when the state collides by containment (one solid inside the other). */
    int triangle = -1;
    /** \brief The same for the object (or the other component). */
    int otherTriangle = -1;
    /** \brief OutOfBounds: the first coordinate outside its bounds or not finite; -1 otherwise. */
    int coordinate = -1;
    Eigen::Vector3d pointOnComponent = Eigen::Vector3d::Zero();  ///< world frame
    Eigen::Vector3d pointOnOther = Eigen::Vector3d::Zero();      ///< world frame; equal when colliding
    /** \brief DistanceRequest::penetration on a colliding state: how deep the pair named overlaps
        (the first colliding pair the query met: others may overlap too, deeper). NaN otherwise. */
    Penetration penetration;

    bool colliding() const { return kind != Contact::Kind::None && distance <= 0.0; }
};

struct DistanceWorkspace;

/** \brief Exact distance queries over one collision model: the minimum over the pairs of solids
    a validity check decides (components against objects, non-exempt self pairs), each pair measured
    on its meshes' triangle trees (surfaceDistance(): node lower bounds, pruning by the best distance
    so far) or, where a side is made of primitives and one is curved, on the exact shapes (GJK,
    CurvedSolids::distance). Pairs are taken nearest root bound first and the best distance so far
    is every pair's bound, so far pairs cost one box test. A pair whose surfaces are apart but whose
    root boxes overlap is tested for containment (closed meshes), which is a collision: distance 0.
    Solids, not padded: CollisionRequest::padding plays no part. Immutable; every method is
    thread-safe (each call borrows pooled scratch). */
class DistanceQueries
{
public:
    explicit DistanceQueries(CollisionModelConstPtr model);
    ~DistanceQueries();

    /** \brief Measures state \a q (dof values). Never throws for a bad state: one outside the
        bounds or not finite is OutOfBounds. */
    void distance(const double *q, const DistanceRequest &request, DistanceResult &result) const;
    /** \brief \a n states (n x dof, row-major) into \a results (n entries), over \a threads worker
        threads (0 = all cores). */
    void distance(const double *q, std::size_t n, DistanceResult *results, const DistanceRequest &request,
                  int threads) const;

    /** \brief Conservative advancement's step at \a n states \a q (n x dof, row-major): for state i,
        the largest t in [0, caps[i]] such that every pair \a request checks stays farther apart than
        its padding (request.padding plus its pairPadding entry) while it closes in by up to its rate
        times t: the minimum over the pairs of (distance - padding) / rate, less a rounding slack.
        \a rates is laid out as a pairPadding (per component, for its pairs with every object; per
        self pair; one row or one per state) with finite entries >= 0; a pair whose rate is 0 limits
        nothing unless it is within its padding now. 0 for a state within a pair's padding (or
        touching, or one solid inside another) and for a state outside the bounds. Exact as
        distance() is (the same walks, each pair's bound padding + rate x the smallest step so
        far): between meshes to rounding, so a step is never longer than the motion allows; a pair
        with curved primitives is measured by GJK (device::convexClosest), which converges to
        rounding in practice but is not proven near contact (within about a millimetre of it, its
        witnesses' plane proves up to 1e-6 less than the distance it gives). With \a clearance
        HullBound, each mesh pair's distance is a lower bound from the hulls instead (the same walk
        over the pairs, each pair's bound below its reach): a step no longer, often a little
        shorter, for far less time. CertifiedMotionValidator sizes its intervals with it when asked
        (CertifiedMotionOptions::sizeByClearance, clearanceMeasure). */
    void freeRadius(const double *q, std::size_t n, const CollisionRequest &request, const PairPadding &rates,
                    const double *caps, double *radii, int threads,
                    ClearanceMeasure clearance = ClearanceMeasure::Exact) const;

private:
    struct PairMetric;
    void measure(const double *q, const DistanceRequest &request, const PairMetric &metric, DistanceWorkspace &ws,
                 DistanceResult &result) const;
    /** \brief fn(state, workspace) for the \a n states, over \a threads workers, each with a pooled
        workspace. */
    template <class PerState>
    void forEachState(std::size_t n, int threads, const PerState &fn) const;

    CollisionModelConstPtr model_;
    PairPenetration penetration_;
    Pool<DistanceWorkspace> workspaces_;
};
}  // namespace rastercheck
