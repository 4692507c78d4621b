#include "rastercheck/ompl/MotionValidator.h"

#include <algorithm>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/ompl/EdgeChecks.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
/** \brief One edge's scan in progress: its states j = 1 .. nd in rake order, the batch in flight
    and the smallest invalid index found so far (0: none). */
struct MotionValidator::EdgeScan
{
    Edge edge;
    unsigned int nd = 1;
    std::vector<unsigned int> order;
    std::size_t next = 0;   ///< next index of order to batch
    std::size_t width = 0;  ///< size of the next batch
    unsigned int found = 0;
    std::vector<unsigned int> batch;
};

namespace
{
/** \brief Per-thread buffers of checkMotions (a validator is shared by planner threads). */
struct BatchScratch
{
    std::vector<std::pair<unsigned int, unsigned int>> intervals;
    std::vector<std::pair<std::size_t, unsigned int>> inBounds;  ///< (scan, index) of each checked row
    std::vector<double> rows;                                    ///< inBounds.size() x dof
    std::vector<std::uint8_t> verdicts;
};

BatchScratch &batchScratch()
{
    thread_local BatchScratch buffers;
    return buffers;
}
}  // namespace

MotionValidator::MotionValidator(const ob::SpaceInformationPtr &si, StateMappingConstPtr mapping,
                                 CheckerConstPtr checker, const CollisionRequest &request, unsigned int rakeWidth)
    : BatchMotionValidator(si),
      mapping_(std::move(mapping)),
      checker_(std::move(checker)),
      request_(request),
      rakeWidth_(rakeWidth),
      space_(si->getStateSpace().get())
{
    detail::requireMatchingParts(si, mapping_, checker_, "MotionValidator");
    if (rakeWidth_ == 0)
        throw ConfigurationError("MotionValidator: the rake width must be at least 1");
}

MotionValidator::MotionValidator(const ob::SpaceInformationPtr &si, const StateValidityChecker &validityChecker,
                                 unsigned int rakeWidth)
    : MotionValidator(si, validityChecker.getStateMappingPtr(), validityChecker.getCheckerPtr(),
                      validityChecker.getRequest(), rakeWidth)
{
}

void MotionValidator::nextBatch(EdgeScan &scan, bool wantFirst) const
{
    scan.batch.clear();
    if (scan.found == 0)
    {
        const std::size_t end = std::min(scan.order.size(), scan.next + scan.width);
        scan.batch.assign(scan.order.begin() + static_cast<std::ptrdiff_t>(scan.next),
                          scan.order.begin() + static_cast<std::ptrdiff_t>(end));
        scan.next = end;
        scan.width *= 2;
    }
    else if (wantFirst)
    {
        // Everything before the collision found so far, at once: the first invalid is among them or is it.
        for (; scan.next < scan.order.size(); ++scan.next)
            if (scan.order[scan.next] < scan.found)
                scan.batch.push_back(scan.order[scan.next]);
    }
}

void MotionValidator::checkMotions(const Edge *edges, std::size_t n, std::uint8_t *valid, double *lastValid) const
{
    const bool wantFirst = lastValid != nullptr;
    BatchScratch &w = batchScratch();
    // Scans are reused per thread: their vectors keep their capacity between calls.
    thread_local std::vector<std::unique_ptr<EdgeScan>> pool;
    while (pool.size() < n)
        pool.push_back(std::make_unique<EdgeScan>());
    for (std::size_t i = 0; i < n; ++i)
    {
        EdgeScan &scan = *pool[i];
        scan.edge = edges[i];
        scan.nd = std::max(1u, space_->validSegmentCount(edges[i].from, edges[i].to));
        detail::rakeOrder(scan.nd, scan.order, w.intervals);
        scan.next = 0;
        scan.width = rakeWidth_;
        scan.found = 0;
    }

    const std::size_t dof = mapping_->numCoordinates();
    ob::State *test = si_->allocState();
    for (;;)
    {
        w.inBounds.clear();
        w.rows.clear();
        std::size_t batched = 0;
        for (std::size_t i = 0; i < n; ++i)
        {
            EdgeScan &scan = *pool[i];
            nextBatch(scan, wantFirst);
            batched += scan.batch.size();
            for (const unsigned int j : scan.batch)
            {
                const ob::State *state = scan.edge.to;
                if (j != scan.nd)
                {
                    space_->interpolate(scan.edge.from, scan.edge.to,
                                        static_cast<double>(j) / static_cast<double>(scan.nd), test);
                    state = test;
                }
                if (!si_->satisfiesBounds(state))
                {
                    scan.found = scan.found == 0 ? j : std::min(scan.found, j);
                    continue;
                }
                w.rows.resize(w.rows.size() + dof);
                mapping_->toConfiguration(state, w.rows.data() + w.rows.size() - dof);
                w.inBounds.emplace_back(i, j);
            }
        }
        if (batched == 0)
            break;
        w.verdicts.resize(w.inBounds.size());
        if (!w.inBounds.empty())
            checker_->check(w.rows.data(), w.inBounds.size(), w.verdicts.data(), request_);
        states_.fetch_add(batched, std::memory_order_relaxed);
        for (std::size_t k = 0; k < w.inBounds.size(); ++k)
            if (!w.verdicts[k])
            {
                EdgeScan &scan = *pool[w.inBounds[k].first];
                const unsigned int j = w.inBounds[k].second;
                scan.found = scan.found == 0 ? j : std::min(scan.found, j);
            }
    }
    si_->freeState(test);

    for (std::size_t i = 0; i < n; ++i)
    {
        const EdgeScan &scan = *pool[i];
        valid[i] = scan.found == 0 ? 1 : 0;
        if (lastValid)
            lastValid[i] = scan.found == 0 ? 1.0 : static_cast<double>(scan.found - 1) / static_cast<double>(scan.nd);
        detail::countMotion(valid_, invalid_, scan.found == 0);
    }
    // Keep what a planner's next batch needs, not what the largest batch ever needed.
    if (pool.size() > detail::kKeptEdges)
        pool.resize(detail::kKeptEdges);
    for (const auto &scan : pool)
    {
        detail::releaseIfLarge(scan->order);
        detail::releaseIfLarge(scan->batch);
    }
    detail::releaseIfLarge(w.intervals);
    detail::releaseIfLarge(w.inBounds);
    detail::releaseIfLarge(w.rows);
    detail::releaseIfLarge(w.verdicts);
}
}  // namespace rastercheck::ompl
