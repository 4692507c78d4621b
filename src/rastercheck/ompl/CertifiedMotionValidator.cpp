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
namespace
{
/** \brief Per-thread buffers of certify (a validator is shared by planner threads). */
struct Scratch
{
    std::vector<double> qa, qb;
    std::vector<double> componentSweeps, pairSweeps;  ///< MotionBound::sweeps of the edge
    std::vector<unsigned int> order;
    std::vector<std::pair<unsigned int, unsigned int>> intervals;
    std::vector<double> pending;  ///< starts of the intervals of the current size still to certify
    std::vector<double> batch;    ///< starts whose midpoints are checked together
    std::vector<double> failed;   ///< starts whose midpoints missed the margin (refined next)
    std::vector<double> close;    ///< starts whose midpoints missed the margin, checked at the padding
    std::vector<double> rows;
    std::vector<std::uint8_t> verdicts;
};

Scratch &scratch()
{
    thread_local Scratch buffers;
    return buffers;
}

/** \brief The request that certifies intervals of \a length (a fraction of the edge) by their
    midpoints: conservative mode, each pair padded by what it can close in over half the interval
    (on top of any pair padding \a base carries). */
CollisionRequest marginRequest(const CollisionRequest &base, const std::vector<double> &componentSweeps,
                               const std::vector<double> &pairSweeps, double length)
{
    auto extra = std::make_shared<PairPadding>(base.pairPadding ? *base.pairPadding : PairPadding{});
    extra->environment.resize(componentSweeps.size(), 0.0);
    extra->self.resize(pairSweeps.size(), 0.0);
    for (std::size_t c = 0; c < componentSweeps.size(); ++c)
        extra->environment[c] += 0.5 * componentSweeps[c] * length;
    for (std::size_t i = 0; i < pairSweeps.size(); ++i)
        extra->self[i] += 0.5 * pairSweeps[i] * length;
    CollisionRequest margin = base;
    margin.mode = CollisionMode::Conservative;
    margin.pairPadding = std::move(extra);
    return margin;
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
    : ob::MotionValidator(si),
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

void CertifiedMotionValidator::checkMidpoints(const ob::State *s1, const ob::State *s2,
                                              const std::vector<double> &starts, double length,
                                              const CollisionRequest &request) const
{
    Scratch &w = scratch();
    const std::size_t dof = mapping_->numCoordinates();
    ob::State *state = si_->allocState();
    w.rows.resize(starts.size() * dof);
    for (std::size_t i = 0; i < starts.size(); ++i)
    {
        space_->interpolate(s1, s2, starts[i] + 0.5 * length, state);
        mapping_->toConfiguration(state, w.rows.data() + i * dof);
    }
    si_->freeState(state);
    w.verdicts.resize(starts.size());
    checker_->check(w.rows.data(), starts.size(), w.verdicts.data(), request);
    states_.fetch_add(starts.size(), std::memory_order_relaxed);
}

bool CertifiedMotionValidator::certify(const ob::State *s1, const ob::State *s2, bool wantFirst, double &prefix) const
{
    prefix = 0.0;
    // The bounds are a box in the interpolated coordinates (angles and quaternions have none), so
    // every state of an edge whose ends satisfy them does too.
    if (!si_->satisfiesBounds(s1) || !si_->satisfiesBounds(s2))
        return false;
    Scratch &w = scratch();
    const std::size_t dof = mapping_->numCoordinates();
    w.qa.resize(dof);
    w.qb.resize(dof);
    mapping_->toConfiguration(s1, w.qa.data());
    mapping_->toConfiguration(s2, w.qb.data());
    // Over an interval of length h, a component moves at most its sweep x h / 2 from where it is at
    // the midpoint, and two components close in by at most their pair's sweep x h / 2: a midpoint
    // clear by that much more than the padding, pair by pair, certifies the interval.
    const CollisionModel &model = checker_->collisionModel();
    w.componentSweeps.resize(model.numComponents());
    w.pairSweeps.resize(model.selfPairs.size());
    bound_.sweeps(w.qa.data(), w.qb.data(), model.selfPairs, w.componentSweeps.data(), w.pairSweeps.data());
    double fastest = 0.0;
    if (request_.checkEnvironment && !w.componentSweeps.empty())
        fastest = *std::max_element(w.componentSweeps.begin(), w.componentSweeps.end());
    if (request_.checkSelfCollision && !w.pairSweeps.empty())
        fastest = std::max(fastest, *std::max_element(w.pairSweeps.begin(), w.pairSweeps.end()));
    if (!std::isfinite(fastest))
        return false;
    const double coarse = std::clamp(std::ceil(0.5 * fastest / margin_), 1.0, kMaxIntervals);
    double length = 1.0 / coarse;

    w.pending.clear();
    detail::rakeOrder(static_cast<unsigned int>(coarse), w.order, w.intervals);
    for (const unsigned int j : w.order)
        w.pending.push_back(static_cast<double>(j - 1) * length);

    // Start of the earliest interval known not to be certifiable: nothing from there on matters.
    double stop = std::numeric_limits<double>::infinity();
    // An edge sliding along an obstacle nearer than the margins resolve doubles its failing
    // intervals at every level; past this many midpoints it is given up as not certifiable.
    const double budget = kChecksPerInterval * coarse + kChecksPerLevel * levels_;
    double spent = 0.0;
    for (unsigned int level = 0;; ++level)
    {
        const CollisionRequest margin = marginRequest(request_, w.componentSweeps, w.pairSweeps, length);
        w.failed.clear();
        std::size_t next = 0;
        std::size_t width = level == 0 ? rakeWidth_ : w.pending.size();
        while (next < w.pending.size())
        {
            w.batch.clear();
            for (; next < w.pending.size() && w.batch.size() < width; ++next)
                if (w.pending[next] < stop)
                    w.batch.push_back(w.pending[next]);
            width *= 2;
            if (w.batch.empty())
                continue;
            checkMidpoints(s1, s2, w.batch, length, margin);
            w.close.clear();
            for (std::size_t i = 0; i < w.batch.size(); ++i)
                if (!w.verdicts[i])
                    w.close.push_back(w.batch[i]);
            if (w.close.empty())
                continue;
            // Nearer than the margin: a collision at the padding itself ends the search there.
            checkMidpoints(s1, s2, w.close, length, request_);
            for (std::size_t i = 0; i < w.close.size(); ++i)
            {
                if (w.verdicts[i])
                    w.failed.push_back(w.close[i]);
                else if (!wantFirst)
                    return false;
                else
                    stop = std::min(stop, w.close[i]);
            }
        }
        w.pending.clear();
        for (const double start : w.failed)
        {
            if (start >= stop)
                continue;
            if (level == levels_)
            {
                if (!wantFirst)
                    return false;
                stop = std::min(stop, start);
                continue;
            }
            w.pending.push_back(start);
            w.pending.push_back(start + 0.5 * length);
        }
        if (w.pending.empty())
            break;
        spent += static_cast<double>(w.pending.size());
        if (spent > budget)
        {
            if (!wantFirst)
                return false;
            stop = std::min(stop, *std::min_element(w.pending.begin(), w.pending.end()));
            break;
        }
        length *= 0.5;
    }
    prefix = std::min(stop, 1.0);
    return stop > 1.0;
}

bool CertifiedMotionValidator::checkMotion(const ob::State *s1, const ob::State *s2) const
{
    double prefix = 0.0;
    const bool valid = certify(s1, s2, false, prefix);
    detail::countMotion(valid_, invalid_, valid);
    return valid;
}

bool CertifiedMotionValidator::checkMotion(const ob::State *s1, const ob::State *s2,
                                           std::pair<ob::State *, double> &lastValid) const
{
    double prefix = 0.0;
    const bool valid = certify(s1, s2, true, prefix);
    if (!valid)
    {
        lastValid.second = prefix;
        if (lastValid.first != nullptr)
            space_->interpolate(s1, s2, prefix, lastValid.first);
    }
    detail::countMotion(valid_, invalid_, valid);
    return valid;
}
}  // namespace rastercheck::ompl
