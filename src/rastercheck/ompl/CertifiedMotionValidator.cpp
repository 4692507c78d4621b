#include "rastercheck/ompl/CertifiedMotionValidator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/ompl/EdgeChecks.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
/** \brief One edge's certification in progress (see the class comment): the intervals of the
    current size still to certify, the ones whose midpoints missed the margin, the batch in flight. */
struct CertifiedMotionValidator::EdgeSearch
{
    Edge edge;
    std::vector<double> componentSweeps, pairSweeps;  ///< MotionBound::sweeps of the edge
    double length = 1.0;                              ///< of the current level's intervals
    unsigned int level = 0;
    std::vector<double> pending;  ///< starts of the intervals of the current size still to certify
    std::size_t next = 0;         ///< next pending interval to batch
    std::size_t width = 0;        ///< size of the next batch of this level
    std::vector<double> failed;   ///< starts whose midpoints missed the margin (refined next level)
    std::vector<double> batch;    ///< starts whose midpoints are checked in this round
    std::vector<double> close;    ///< starts of batch whose midpoints missed the margin
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
};

namespace
{
/** \brief Per-thread buffers of checkMotions (a validator is shared by planner threads). */
struct Scratch
{
    std::vector<double> qa, qb;
    std::vector<unsigned int> order;
    std::vector<std::pair<unsigned int, unsigned int>> intervals;
    std::vector<double> rows;
    std::vector<std::uint8_t> verdicts;
};

Scratch &scratch()
{
    thread_local Scratch buffers;
    return buffers;
}

/** \brief The most coarse intervals one edge is split into (an edge longer than margin x this gets
    intervals needing more than the margin). */
constexpr double kMaxIntervals = 1 << 20;
/** \brief Refined midpoints an edge may use: this many per coarse interval plus this many per level
    (a pass near a corner fails about two to four midpoints per level; a slide does far more). */
constexpr double kChecksPerInterval = 16;
constexpr double kChecksPerLevel = 64;
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
    if (rakeWidth_ == 0)
        throw ConfigurationError("CertifiedMotionValidator: the rake width must be at least 1");
    if (!(margin_ > 0.0))
        margin_ = 1.0;  // a robot without geometry: nothing moves, every edge needs one check at any margin
}

void CertifiedMotionValidator::start(const Edge &edge, EdgeSearch &w) const
{
    w.edge = edge;
    w.level = 0;
    w.pending.clear();
    w.failed.clear();
    w.batch.clear();
    w.close.clear();
    w.next = 0;
    w.width = rakeWidth_;
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
    Scratch &scratchBuffers = scratch();
    const std::size_t dof = mapping_->numCoordinates();
    scratchBuffers.qa.resize(dof);
    scratchBuffers.qb.resize(dof);
    mapping_->toConfiguration(edge.from, scratchBuffers.qa.data());
    mapping_->toConfiguration(edge.to, scratchBuffers.qb.data());
    // Over an interval of length h, a component moves at most its sweep x h / 2 from where it is at
    // the midpoint, and two components close in by at most their pair's sweep x h / 2: a midpoint
    // clear by that much more than the padding, pair by pair, certifies the interval.
    const CollisionModel &model = checker_->collisionModel();
    w.componentSweeps.resize(model.numComponents());
    w.pairSweeps.resize(model.selfPairs.size());
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
    w.length = 1.0 / coarse;
    detail::rakeOrder(static_cast<unsigned int>(coarse), scratchBuffers.order, scratchBuffers.intervals);
    for (const unsigned int j : scratchBuffers.order)
        w.pending.push_back(static_cast<double>(j - 1) * w.length);
    // An edge sliding along an obstacle nearer than the margins resolve doubles its failing
    // intervals at every level; past this many midpoints it is given up as not certifiable.
    w.budget = kChecksPerInterval * coarse + kChecksPerLevel * levels_;
}

void CertifiedMotionValidator::endLevel(EdgeSearch &w, bool wantFirst) const
{
    w.pending.clear();
    for (const double start : w.failed)
    {
        if (start >= w.stop)
            continue;
        if (w.level == levels_)
        {
            if (!wantFirst)
                return w.finish(false);
            w.stop = std::min(w.stop, start);
            continue;
        }
        w.pending.push_back(start);
        w.pending.push_back(start + 0.5 * w.length);
    }
    w.failed.clear();
    if (w.pending.empty())
        return w.finish(w.stop > 1.0);
    w.spent += static_cast<double>(w.pending.size());
    if (w.spent > w.budget)
    {
        w.stop = std::min(w.stop, *std::min_element(w.pending.begin(), w.pending.end()));
        return w.finish(false);
    }
    w.length *= 0.5;
    ++w.level;
    w.next = 0;
    w.width = w.pending.size();  // the refined intervals of a level go in one batch
}

void CertifiedMotionValidator::nextBatch(EdgeSearch &w, bool wantFirst) const
{
    w.batch.clear();
    while (!w.finished && w.batch.empty())
    {
        if (w.next >= w.pending.size())
        {
            endLevel(w, wantFirst);
            continue;
        }
        for (; w.next < w.pending.size() && w.batch.size() < w.width; ++w.next)
            if (w.pending[w.next] < w.stop)
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
        for (const double start : closeOnly ? w->close : w->batch)
        {
            space_->interpolate(w->edge.from, w->edge.to, start + 0.5 * w->length, state);
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
    for (std::size_t i = 0; i < n; ++i)
        start(edges[i], *pool[i]);

    Scratch &w = scratch();
    const CollisionModel &model = checker_->collisionModel();
    const std::size_t components = model.numComponents();
    const std::size_t selfPairs = model.selfPairs.size();
    const PairPadding *base = request_.pairPadding.get();
    std::vector<EdgeSearch *> open;
    for (;;)
    {
        open.clear();
        for (std::size_t i = 0; i < n; ++i)
        {
            nextBatch(*pool[i], wantFirst);
            if (!pool[i]->batch.empty())
                open.push_back(pool[i].get());
        }
        if (open.empty())
            break;

        // Every edge's midpoints in one batch, in the request's own mode, each with its own edge's
        // pair paddings: what each pair can close in over half its interval (on top of any pair
        // padding the request carries).
        std::size_t count = 0;
        for (const EdgeSearch *search : open)
            count += search->batch.size();
        auto extra = std::make_shared<PairPadding>();
        extra->rows = count;
        extra->environment.resize(count * components);
        extra->self.resize(count * selfPairs);
        std::size_t row = 0;
        for (const EdgeSearch *search : open)
            for (std::size_t k = 0; k < search->batch.size(); ++k, ++row)
            {
                for (std::size_t c = 0; c < components; ++c)
                    extra->environment[row * components + c] =
                        (base ? base->environment[c] : 0.0) + 0.5 * search->componentSweeps[c] * search->length;
                for (std::size_t p = 0; p < selfPairs; ++p)
                    extra->self[row * selfPairs + p] =
                        (base ? base->self[p] : 0.0) + 0.5 * search->pairSweeps[p] * search->length;
            }
        CollisionRequest margin = request_;
        margin.pairPadding = std::move(extra);
        midpointRows(open, false, w.rows);
        w.verdicts.resize(count);
        checker_->check(w.rows.data(), count, w.verdicts.data(), margin);
        states_.fetch_add(count, std::memory_order_relaxed);

        // Nearer than the margin: checked at the padding itself, where a collision ends the search.
        std::size_t closeCount = 0;
        row = 0;
        for (EdgeSearch *search : open)
        {
            search->close.clear();
            for (const double start : search->batch)
                if (!w.verdicts[row++])
                    search->close.push_back(start);
            closeCount += search->close.size();
        }
        if (closeCount == 0)
            continue;
        midpointRows(open, true, w.rows);
        w.verdicts.resize(closeCount);
        checker_->check(w.rows.data(), closeCount, w.verdicts.data(), request_);
        states_.fetch_add(closeCount, std::memory_order_relaxed);
        row = 0;
        for (EdgeSearch *search : open)
            for (const double start : search->close)
            {
                if (w.verdicts[row++])
                    search->failed.push_back(start);
                else if (!search->finished)
                {
                    search->stop = std::min(search->stop, start);
                    if (!wantFirst)
                        search->finish(false);
                }
            }
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
        for (std::vector<double> *buffer : {&search->componentSweeps, &search->pairSweeps, &search->pending,
                                            &search->failed, &search->batch, &search->close})
            detail::releaseIfLarge(*buffer);
    for (std::vector<double> *buffer : {&w.qa, &w.qb, &w.rows})
        detail::releaseIfLarge(*buffer);
    detail::releaseIfLarge(w.order);
    detail::releaseIfLarge(w.intervals);
    detail::releaseIfLarge(w.verdicts);
}
}  // namespace rastercheck::ompl
