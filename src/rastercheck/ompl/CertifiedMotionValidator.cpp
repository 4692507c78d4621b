#include "rastercheck/ompl/CertifiedMotionValidator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/EdgeChecks.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
/** \brief One edge's certification in progress (see the class comment): the intervals of the
    current size still to certify, the ones whose midpoints missed the margin, the batch in flight. */
struct CertifiedMotionValidator::EdgeSearch
{
    /** \brief The fractions [start, start + length) of the edge. */
    struct Interval
    {
        double start;
        double length;
        std::uint32_t coarse = 0;  ///< the coarse interval it lies in
        double middle() const { return start + 0.5 * length; }
    };
    Edge edge;
    ::ompl::base::State *state = nullptr;             ///< scratch of the space, owned by checkMotions
    std::vector<double> componentSweeps, pairSweeps;  ///< MotionBound::sweeps of the edge
    /** \brief The coarse intervals in at most kSweepSpans spans of perSpan each, and per span the
        sweeps within it (MotionBound::sweeps about its middle; rows of components and of self
        pairs), measured when the first refinement in it is checked. */
    std::uint32_t perSpan = 1;
    double coarseLength = 1.0;
    std::vector<double> spanComponentSweeps, spanPairSweeps;
    std::vector<std::uint8_t> spanMeasured;
    double finest = 0.0;  ///< intervals this short are not split: past them the edge is not certifiable
    unsigned int level = 0;  ///< 0: the coarse intervals, in rake order; then one round per refinement
    std::vector<Interval> pending;  ///< the current level's intervals still to certify
    std::size_t next = 0;           ///< next pending interval to batch
    std::size_t width = 0;          ///< size of the next batch of this level
    std::vector<Interval> refined;  ///< what is left of intervals whose midpoints missed the margin (next level)
    std::vector<Interval> batch;    ///< intervals whose midpoints are checked in this round
    std::vector<Interval> close;    ///< intervals of batch whose midpoints missed the margin
    double stop = std::numeric_limits<double>::infinity();  ///< earliest start known not certifiable
    double budget = 0.0;                                    ///< refined midpoints the edge may use
    double spent = 0.0;
    bool finished = false;
    bool accepted = false;
    double prefix = 0.0;  ///< fraction certified from the edge's start, once finished

    void finish(bool certified)
    {
        finished = true;
        accepted = certified;
        prefix = certified ? 1.0 : std::min(stop, 1.0);
        batch.clear();
    }
    /** \brief \a interval cannot be certified: the search ends, or, when the first uncertifiable
        fraction is wanted, goes on before it. */
    void reject(const Interval &interval, bool wantFirst)
    {
        stop = std::min(stop, interval.start);
        if (!wantFirst && !finished)
            finish(false);
    }
    /** \brief \a interval is clear at its midpoint but not by its margin: its parts outside
        [middle - radius, middle + radius], which the midpoint's clearance certifies, are checked at
        the next level; an interval already at the finest length cannot be split. */
    void refine(const Interval &interval, double radius, bool wantFirst)
    {
        if (interval.length <= finest)
            return reject(interval, wantFirst);
        const double side = 0.5 * interval.length - radius;
        if (side <= 0.0)
            return;
        refined.push_back({interval.start, side, interval.coarse});
        refined.push_back({interval.start + interval.length - side, side, interval.coarse});
    }
};

namespace
{
/** \brief Per-thread buffers of checkMotions (a validator is shared by planner threads). */
struct CertifiedScratch
{
    std::vector<double> qa, qb, qm;
    std::unique_ptr<RobotData> reference;  ///< the links' poses where sweeps are measured
    std::vector<unsigned int> order;
    std::vector<std::pair<unsigned int, unsigned int>> intervals;
    std::vector<double> rows;
    std::vector<std::uint8_t> verdicts;
    std::vector<double> caps, radii;
    PairPadding sweepPadding;  ///< per midpoint, what each pair can close in over half its interval
};

CertifiedScratch &certifiedScratch()
{
    thread_local CertifiedScratch buffers;
    return buffers;
}

/** \brief The most coarse intervals one edge is split into (an edge longer than margin x this gets
    intervals needing more than the margin). */
constexpr double kMaxIntervals = 1 << 20;
/** \brief Refined midpoints an edge may use: this many per coarse interval plus this many per level
    (a pass near a corner fails about two to four midpoints per level; a slide does far more). */
constexpr double kChecksPerInterval = 16;
constexpr double kChecksPerLevel = 64;
/** \brief The most parts of an edge whose sweeps are measured on their own for their refinements
    (each a forward kinematics): the coarse intervals, or groups of them on a long edge. Measuring
    them for the coarse midpoints too costs more than it saves (Panda: 16.2 instead of 17.0 states
    per edge, 47.5 instead of 36.5 us; at most 4 spans for them, 16.4 states and 38.5 us). */
constexpr double kSweepSpans = 64;
}  // namespace

CertifiedMotionValidator::CertifiedMotionValidator(const ob::SpaceInformationPtr &si,
                                                   const StateValidityChecker &validityChecker,
                                                   const CertifiedMotionOptions &options)
    : BatchMotionValidator(si),
      mapping_(validityChecker.getStateMappingPtr()),
      checker_(validityChecker.getCheckerPtr()),
      request_(validityChecker.getRequest()),
      bound_(mapping_->robot()),
      margin_(options.margin > 0.0 ? options.margin : 0.1 * bound_.size()),
      levels_(options.levels),
      rakeWidth_(options.rakeWidth),
      deviceRakeWidth_(std::max(options.rakeWidth, options.deviceRakeWidth)),
      sizeByClearance_(options.sizeByClearance),
      clearanceMeasure_(options.clearanceMeasure),
      space_(si->getStateSpace().get())
{
    detail::requireMatchingParts(si, mapping_, checker_, "CertifiedMotionValidator");
    if (request_.mode == CollisionMode::Raster)
        throw ConfigurationError(
            "CertifiedMotionValidator: raster mode can miss thin overlaps, so it cannot certify "
            "an edge; use safe, exact or conservative mode");
    if (!(std::isfinite(options.margin) && options.margin >= 0.0))
        throw ConfigurationError("CertifiedMotionValidator: the margin must be finite and >= 0 (0 = automatic)");
    if (levels_ > 40)
        throw ConfigurationError(
            "CertifiedMotionValidator: at most 40 levels (the finest margin is margin / 2^levels)");
    if (rakeWidth_ == 0 || options.deviceRakeWidth == 0)
        throw ConfigurationError("CertifiedMotionValidator: the rake widths must be at least 1");
    if (!(margin_ > 0.0))
        margin_ = 1.0;  // a robot without geometry: nothing moves, every edge needs one check at any margin
}

unsigned int CertifiedMotionValidator::firstBatchWidth(std::size_t edges) const
{
    return checker_->reachesDevice(edges * deviceRakeWidth_) ? deviceRakeWidth_ : rakeWidth_;
}

void CertifiedMotionValidator::start(const Edge &edge, unsigned int width, EdgeSearch &w) const
{
    w.edge = edge;
    w.level = 0;
    w.pending.clear();
    w.refined.clear();
    w.batch.clear();
    w.close.clear();
    w.next = 0;
    w.width = width;
    w.stop = std::numeric_limits<double>::infinity();
    w.spent = 0.0;
    w.finished = false;
    w.prefix = 0.0;
    // The bounds are a box in the interpolated coordinates (angles and quaternions have none), so
    // every state of an edge whose ends satisfy them does too.
    if (!si_->satisfiesBounds(edge.from) || !si_->satisfiesBounds(edge.to))
    {
        w.stop = 0.0;
        w.finish(false);
        return;
    }
    CertifiedScratch &scratchBuffers = certifiedScratch();
    const std::size_t dof = mapping_->numCoordinates();
    scratchBuffers.qa.resize(dof);
    scratchBuffers.qb.resize(dof);
    mapping_->toConfiguration(edge.from, scratchBuffers.qa.data());
    mapping_->toConfiguration(edge.to, scratchBuffers.qb.data());
    // Over an interval of length h, a component moves at most its sweep x h / 2 from where it is at
    // the midpoint, and two components close in by at most their pair's sweep x h / 2: a midpoint
    // clear by that much more than the padding, pair by pair, certifies the interval. The sweeps
    // of the whole edge (about its middle) size and pad the coarse intervals; each coarse
    // interval's own, tighter, pad its refinements (intervalSweeps).
    const CollisionModel &model = checker_->collisionModel();
    w.componentSweeps.resize(model.numComponents());
    w.pairSweeps.resize(model.selfPairs.size());
    if (bound_.tightensAboutReferences())
        sweepsAbout(w, 0.5, 0.5, w.componentSweeps.data(), w.pairSweeps.data());
    else
        bound_.sweeps(scratchBuffers.qa.data(), scratchBuffers.qb.data(), model.selfPairs, w.componentSweeps.data(),
                      w.pairSweeps.data());
    double fastest = 0.0;
    if (request_.checkEnvironment && !w.componentSweeps.empty())
        fastest = *std::max_element(w.componentSweeps.begin(), w.componentSweeps.end());
    if (request_.checkSelfCollision && !w.pairSweeps.empty())
        fastest = std::max(fastest, *std::max_element(w.pairSweeps.begin(), w.pairSweeps.end()));
    if (!std::isfinite(fastest))
    {
        w.stop = 0.0;
        w.finish(false);
        return;
    }
    const double coarse = std::clamp(std::ceil(0.5 * fastest / margin_), 1.0, kMaxIntervals);
    const double length = 1.0 / coarse;
    w.finest = std::ldexp(length, -static_cast<int>(levels_));
    detail::rakeOrder(static_cast<unsigned int>(coarse), scratchBuffers.order, scratchBuffers.intervals);
    for (const unsigned int j : scratchBuffers.order)
        w.pending.push_back({static_cast<double>(j - 1) * length, length, j - 1});
    w.coarseLength = length;
    // A robot whose sweeps no reference tightens (a lone rigid body) keeps the edge's: one span.
    w.perSpan = static_cast<std::uint32_t>(bound_.tightensAboutReferences() ? std::ceil(coarse / kSweepSpans) : coarse);
    const std::size_t spans = static_cast<std::size_t>(std::ceil(coarse / w.perSpan));
    w.spanMeasured.assign(spans, 0);
    w.spanComponentSweeps.resize(spans * w.componentSweeps.size());
    w.spanPairSweeps.resize(spans * w.pairSweeps.size());
    if (spans == 1)  // the span is the edge, measured above
    {
        w.spanMeasured[0] = 1;
        std::copy(w.componentSweeps.begin(), w.componentSweeps.end(), w.spanComponentSweeps.begin());
        std::copy(w.pairSweeps.begin(), w.pairSweeps.end(), w.spanPairSweeps.begin());
    }
    // An edge sliding along an obstacle nearer than the margins resolve doubles its failing
    // intervals at every level; past this many midpoints it is given up as not certifiable.
    w.budget = kChecksPerInterval * coarse + kChecksPerLevel * levels_;
}

void CertifiedMotionValidator::sweepsAbout(const EdgeSearch &w, double fraction, double halfSpan,
                                           double *componentSweeps, double *pairSweeps) const
{
    CertifiedScratch &buffers = certifiedScratch();
    const RobotModel &robot = mapping_->robot();
    space_->interpolate(w.edge.from, w.edge.to, fraction, w.state);
    buffers.qm.resize(mapping_->numCoordinates());
    mapping_->toConfiguration(w.state, buffers.qm.data());
    std::unique_ptr<RobotData> &poses = buffers.reference;  // per thread, for any robot of its sizes
    if (!poses || poses->oMl.size() != robot.links.size() || poses->jointValues.size() != robot.joints.size())
        poses = std::make_unique<RobotData>(robot);
    forwardKinematics(robot, *poses, buffers.qm.data());
    bound_.sweeps(buffers.qa.data(), buffers.qb.data(), *poses, halfSpan, checker_->collisionModel().selfPairs,
                  componentSweeps, pairSweeps);
}

void CertifiedMotionValidator::intervalSweeps(EdgeSearch &w, std::uint32_t coarse, const double *&componentSweeps,
                                              const double *&pairSweeps) const
{
    const std::size_t span = coarse / w.perSpan;
    const std::size_t components = w.componentSweeps.size(), pairs = w.pairSweeps.size();
    double *spanComponents = w.spanComponentSweeps.data() + span * components;
    double *spanPairs = w.spanPairSweeps.data() + span * pairs;
    componentSweeps = spanComponents;
    pairSweeps = spanPairs;
    if (w.spanMeasured[span])
        return;
    w.spanMeasured[span] = 1;
    CertifiedScratch &buffers = certifiedScratch();
    mapping_->toConfiguration(w.edge.from, buffers.qa.data());
    mapping_->toConfiguration(w.edge.to, buffers.qb.data());
    const double begin = static_cast<double>(span * w.perSpan) * w.coarseLength;
    const double end = std::min(1.0, static_cast<double>((span + 1) * w.perSpan) * w.coarseLength);
    sweepsAbout(w, 0.5 * (begin + end), 0.5 * (end - begin), spanComponents, spanPairs);
    // The edge's own bounds hold there too: keep the smaller of each.
    for (std::size_t c = 0; c < components; ++c)
        spanComponents[c] = std::min(spanComponents[c], w.componentSweeps[c]);
    for (std::size_t p = 0; p < pairs; ++p)
        spanPairs[p] = std::min(spanPairs[p], w.pairSweeps[p]);
}

void CertifiedMotionValidator::endLevel(EdgeSearch &w) const
{
    w.pending.clear();
    for (const EdgeSearch::Interval &interval : w.refined)
        if (interval.start < w.stop)
            w.pending.push_back(interval);
    w.refined.clear();
    if (w.pending.empty())
        return w.finish(w.stop > 1.0);
    w.spent += static_cast<double>(w.pending.size());
    if (w.spent > w.budget)
    {
        for (const EdgeSearch::Interval &interval : w.pending)
            w.stop = std::min(w.stop, interval.start);
        return w.finish(false);
    }
    ++w.level;
    w.next = 0;
    w.width = w.pending.size();  // the refined intervals of a level go in one batch
}

void CertifiedMotionValidator::nextBatch(EdgeSearch &w) const
{
    w.batch.clear();
    while (!w.finished && w.batch.empty())
    {
        if (w.next >= w.pending.size())
        {
            endLevel(w);
            continue;
        }
        for (; w.next < w.pending.size() && w.batch.size() < w.width; ++w.next)
            if (w.pending[w.next].start < w.stop)
                w.batch.push_back(w.pending[w.next]);
        if (w.level == 0)
            w.width *= 2;  // the rake: a collision anywhere on the edge is met after few checks
    }
}

void CertifiedMotionValidator::midpointRows(const std::vector<EdgeSearch *> &searches, bool closeOnly,
                                            std::vector<double> &rows) const
{
    const std::size_t dof = mapping_->numCoordinates();
    ob::State *state = si_->allocState();
    rows.clear();
    for (const EdgeSearch *w : searches)
        for (const EdgeSearch::Interval &interval : closeOnly ? w->close : w->batch)
        {
            space_->interpolate(w->edge.from, w->edge.to, interval.middle(), state);
            rows.resize(rows.size() + dof);
            mapping_->toConfiguration(state, rows.data() + rows.size() - dof);
        }
    si_->freeState(state);
}

void CertifiedMotionValidator::checkMotions(const Edge *edges, std::size_t n, std::uint8_t *valid,
                                            double *lastValid) const
{
    const bool wantFirst = lastValid != nullptr;
    // Searches are reused per thread: their vectors keep their capacity between calls.
    thread_local std::vector<std::unique_ptr<EdgeSearch>> pool;
    while (pool.size() < n)
        pool.push_back(std::make_unique<EdgeSearch>());
    // One scratch state for all searches (the pool is the thread's, shared by validators of
    // different spaces), where sweeps are measured about states on the edges.
    auto freeState = [this](ob::State *s) { si_->freeState(s); };
    std::unique_ptr<ob::State, decltype(freeState)> scratchState(
        bound_.tightensAboutReferences() ? si_->allocState() : nullptr, freeState);
    const unsigned int width = firstBatchWidth(n);
    for (std::size_t i = 0; i < n; ++i)
    {
        pool[i]->state = scratchState.get();
        start(edges[i], width, *pool[i]);
    }

    CertifiedScratch &w = certifiedScratch();
    const CollisionModel &model = checker_->collisionModel();
    const std::size_t components = model.numComponents();
    const std::size_t selfPairs = model.selfPairs.size();
    std::vector<EdgeSearch *> open;
    for (;;)
    {
        open.clear();
        for (std::size_t i = 0; i < n; ++i)
        {
            nextBatch(*pool[i]);
            if (!pool[i]->batch.empty())
                open.push_back(pool[i].get());
        }
        if (open.empty())
            break;

        // Every edge's midpoints in one batch, in the request's own mode, each with its own edge's
        // pair paddings: what each pair can close in over half its interval, on top of the
        // request's paddings. One pass says per midpoint whether it is clear by that much, or
        // else whether it is valid at all (a collision ends the search).
        std::size_t count = 0;
        for (const EdgeSearch *search : open)
            count += search->batch.size();
        PairPadding &sweep = w.sweepPadding;
        sweep.rows = count;
        sweep.environment.resize(count * components);
        sweep.self.resize(count * selfPairs);
        std::size_t row = 0;
        for (EdgeSearch *search : open)
            for (const EdgeSearch::Interval &interval : search->batch)
            {
                // A coarse midpoint is padded by the edge's sweeps; its refinements, by those of its
                // coarse interval (a forward kinematics each, which the coarse checks do not pay).
                const double *componentSweeps = search->componentSweeps.data();
                const double *pairSweeps = search->pairSweeps.data();
                if (search->level > 0)
                    intervalSweeps(*search, interval.coarse, componentSweeps, pairSweeps);
                for (std::size_t c = 0; c < components; ++c)
                    sweep.environment[row * components + c] = 0.5 * componentSweeps[c] * interval.length;
                for (std::size_t p = 0; p < selfPairs; ++p)
                    sweep.self[row * selfPairs + p] = 0.5 * pairSweeps[p] * interval.length;
                ++row;
            }
        midpointRows(open, false, w.rows);
        w.verdicts.resize(count);
        checker_->checkTwoPaddings(w.rows.data(), count, w.verdicts.data(), request_, sweep);
        states_.fetch_add(count, std::memory_order_relaxed);

        std::size_t closeCount = 0;
        row = 0;
        for (EdgeSearch *search : open)
        {
            search->close.clear();
            double firstCollision = std::numeric_limits<double>::infinity();
            for (const EdgeSearch::Interval &interval : search->batch)
                switch (static_cast<PaddedVerdict>(w.verdicts[row++]))
                {
                    case PaddedVerdict::Clear:
                        break;
                    case PaddedVerdict::Near:
                        search->close.push_back(interval);
                        break;
                    case PaddedVerdict::Collides:
                        firstCollision = std::min(firstCollision, interval.start);
                        break;
                }
            // After the loop: rejecting may finish the search, which empties its batch. The earliest
            // colliding interval says all that rejecting each would.
            if (firstCollision < std::numeric_limits<double>::infinity())
                search->reject({firstCollision, 0.0}, wantFirst);
            if (search->finished)
                search->close.clear();
            closeCount += search->close.size();
        }
        if (closeCount == 0)
            continue;

        // Nearer than the margin but valid: the midpoint's clearance, measured against what each
        // pair can close in per unit of the edge, certifies the middle of the interval
        // (conservative advancement) and leaves two shorter sides; without it, or where it is 0,
        // the interval is halved.
        w.radii.assign(closeCount, 0.0);
        if (sizeByClearance_)
        {
            midpointRows(open, true, w.rows);
            auto rates = std::make_shared<PairPadding>();
            rates->rows = closeCount;
            rates->environment.resize(closeCount * components);
            rates->self.resize(closeCount * selfPairs);
            w.caps.resize(closeCount);
            row = 0;
            for (EdgeSearch *search : open)
                for (const EdgeSearch::Interval &interval : search->close)
                {
                    const double *componentSweeps, *pairSweeps;
                    intervalSweeps(*search, interval.coarse, componentSweeps, pairSweeps);
                    std::copy(componentSweeps, componentSweeps + components,
                              rates->environment.begin() + static_cast<std::ptrdiff_t>(row * components));
                    std::copy(pairSweeps, pairSweeps + selfPairs,
                              rates->self.begin() + static_cast<std::ptrdiff_t>(row * selfPairs));
                    w.caps[row++] = 0.5 * interval.length;
                }
            checker_->freeRadius(w.rows.data(), closeCount, request_, *rates, w.caps.data(), w.radii.data(),
                                 clearanceMeasure_);
            clearances_.fetch_add(closeCount, std::memory_order_relaxed);
        }
        row = 0;
        for (EdgeSearch *search : open)
            for (const EdgeSearch::Interval &interval : search->close)
                search->refine(interval, w.radii[row++], wantFirst);  // a radius of 0 halves it
    }
    for (std::size_t i = 0; i < n; ++i)
    {
        valid[i] = pool[i]->accepted ? 1 : 0;
        if (lastValid)
            lastValid[i] = pool[i]->prefix;
        detail::countMotion(valid_, invalid_, pool[i]->accepted);
    }
    // Keep what a planner's next batch needs, not what the largest batch ever needed.
    if (pool.size() > detail::kKeptEdges)
        pool.resize(detail::kKeptEdges);
    for (const auto &search : pool)
    {
        for (std::vector<double> *buffer : {&search->componentSweeps, &search->pairSweeps})
            detail::releaseIfLarge(*buffer);
        for (std::vector<EdgeSearch::Interval> *buffer :
             {&search->pending, &search->refined, &search->batch, &search->close})
            detail::releaseIfLarge(*buffer);
    }
    for (std::vector<double> *buffer :
         {&w.qa, &w.qb, &w.rows, &w.caps, &w.radii, &w.sweepPadding.environment, &w.sweepPadding.self})
        detail::releaseIfLarge(*buffer);
    detail::releaseIfLarge(w.order);
    detail::releaseIfLarge(w.intervals);
    detail::releaseIfLarge(w.verdicts);
}
}  // namespace rastercheck::ompl
