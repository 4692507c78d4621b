#include "rastercheck/planners/BatchShortcutter.h"

#include <algorithm>
#include <vector>

namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace rastercheck::planners
{
namespace
{
/** \brief A point on a path: edge \a edge (from vertex edge to edge + 1) at \a fraction, and its
    arc length from the path's start. */
struct PathPoint
{
    std::size_t edge = 0;
    double fraction = 0.0;
    double arc = 0.0;
};

struct Candidate
{
    PathPoint from, to;
    ob::State *a = nullptr, *b = nullptr;
    double saving = 0.0;
};
}  // namespace

BatchShortcutter::BatchShortcutter(const ob::SpaceInformationPtr &si)
    : BatchShortcutter(si, std::make_shared<const EdgeChecker>(si))
{
}

BatchShortcutter::BatchShortcutter(const ob::SpaceInformationPtr &si, std::shared_ptr<const EdgeChecker> edges)
    : si_(si), edges_(std::move(edges))
{
}

bool BatchShortcutter::shortcut(og::PathGeometric &path, const ob::PlannerTerminationCondition &ptc)
{
    bool changed = false;
    std::vector<Candidate> candidatesOfRound;
    std::vector<ompl::Edge> lines;
    std::vector<std::uint8_t> valid;
    std::vector<unsigned int> levels;
    std::vector<double> arcs;
    unsigned int idle = 0;
    while (idle < idleRounds && !ptc && path.getStateCount() > 2)
    {
        std::vector<ob::State *> &states = path.getStates();
        const std::size_t n = states.size();
        arcs.assign(1, 0.0);
        for (std::size_t i = 0; i + 1 < n; ++i)
            arcs.push_back(arcs.back() + si_->distance(states[i], states[i + 1]));
        const double length = arcs.back();
        if (!(length > 0.0))
            break;
        auto pointAt = [&](double arc)
        {
            PathPoint p;
            p.edge = static_cast<std::size_t>(std::upper_bound(arcs.begin(), arcs.end(), arc) - arcs.begin());
            p.edge = std::min(p.edge == 0 ? 0 : p.edge - 1, n - 2);
            const double span = arcs[p.edge + 1] - arcs[p.edge];
            p.fraction = span > 0.0 ? std::clamp((arc - arcs[p.edge]) / span, 0.0, 1.0) : 0.0;
            p.arc = arcs[p.edge] + p.fraction * span;
            return p;
        };
        auto vertexAt = [&](std::size_t i)
        {
            PathPoint p;
            p.edge = std::min(i, n - 2);
            p.fraction = i == n - 1 ? 1.0 : 0.0;
            p.arc = arcs[i];
            return p;
        };

        // Candidates: pairs of points (every fourth a pair of vertices) whose line is shorter than
        // the path between them; points on one edge save nothing and are dropped.
        candidatesOfRound.clear();
        for (unsigned int c = 0; c < candidates; ++c)
        {
            PathPoint p, q;
            if (c % 4 == 0)
            {
                p = vertexAt(static_cast<std::size_t>(rng_.uniformInt(0, static_cast<int>(n) - 1)));
                q = vertexAt(static_cast<std::size_t>(rng_.uniformInt(0, static_cast<int>(n) - 1)));
            }
            else
            {
                p = pointAt(rng_.uniformReal(0.0, length));
                q = pointAt(rng_.uniformReal(0.0, length));
            }
            if (q.arc < p.arc)
                std::swap(p, q);
            Candidate candidate;
            candidate.from = p;
            candidate.to = q;
            candidate.a = si_->allocState();
            candidate.b = si_->allocState();
            si_->getStateSpace()->interpolate(states[p.edge], states[p.edge + 1], p.fraction, candidate.a);
            si_->getStateSpace()->interpolate(states[q.edge], states[q.edge + 1], q.fraction, candidate.b);
            candidate.saving = (q.arc - p.arc) - si_->distance(candidate.a, candidate.b);
            if (candidate.saving > 1e-9 * length)
                candidatesOfRound.push_back(candidate);
            else
            {
                si_->freeState(candidate.a);
                si_->freeState(candidate.b);
            }
        }
        lines.clear();
        for (const Candidate &candidate : candidatesOfRound)
            lines.push_back({candidate.a, candidate.b});
        // Certified lines cost about 20 checks each at two paddings, and most candidates cross an
        // obstacle: a rake (free states at rising density) rejects those first, and only the
        // shortcuts chosen among the rest are certified.
        if (edges_->certifies())
        {
            levels.assign(lines.size(), 0);
            edges_->rake(lines, levels, valid, nullptr);
        }
        else
            edges_->check(lines, valid);

        // The valid ones, largest saving first, where they do not overlap a shortcut already taken.
        // With a rake, "valid" is "not refused yet": the chosen lines are certified, and while
        // certification refuses one, the choice is made again without it. With exact verdicts (safe
        // and exact mode) the rake never refuses a line certification accepts, so the shortcuts
        // taken are those a certification of every candidate would give.
        std::vector<std::uint8_t> certified(candidatesOfRound.size(), edges_->certifies() ? 0 : 1);
        std::vector<std::size_t> taken;
        for (bool refused = true; refused;)
        {
            std::vector<std::size_t> order;
            for (std::size_t k = 0; k < candidatesOfRound.size(); ++k)
                if (valid[k])
                    order.push_back(k);
            std::sort(order.begin(), order.end(),
                      [&](std::size_t x, std::size_t y)
                      { return candidatesOfRound[x].saving > candidatesOfRound[y].saving; });
            taken.clear();
            for (const std::size_t k : order)
            {
                const Candidate &c = candidatesOfRound[k];
                bool overlaps = false;
                for (const std::size_t t : taken)
                    overlaps = overlaps || !(c.to.arc <= candidatesOfRound[t].from.arc ||
                                             c.from.arc >= candidatesOfRound[t].to.arc);
                if (!overlaps)
                    taken.push_back(k);
            }
            std::vector<std::size_t> unknown;
            lines.clear();
            for (const std::size_t k : taken)
                if (!certified[k])
                {
                    unknown.push_back(k);
                    lines.push_back({candidatesOfRound[k].a, candidatesOfRound[k].b});
                }
            std::vector<std::uint8_t> accepted;
            edges_->check(lines, accepted);
            refused = false;
            for (std::size_t i = 0; i < unknown.size(); ++i)
            {
                certified[unknown[i]] = accepted[i];
                valid[unknown[i]] = accepted[i];
                refused = refused || !accepted[i];
            }
        }
        double saved = 0.0;
        for (const std::size_t k : taken)
            saved += candidatesOfRound[k].saving;
        std::sort(taken.begin(), taken.end(),
                  [&](std::size_t x, std::size_t y)
                  { return candidatesOfRound[x].from.arc < candidatesOfRound[y].from.arc; });

        // Rebuild: vertices before each shortcut, its two ends, then on after it.
        if (!taken.empty())
        {
            std::vector<ob::State *> rebuilt;
            std::size_t next = 0;  // first vertex not yet copied or dropped
            for (const std::size_t k : taken)
            {
                Candidate &c = candidatesOfRound[k];
                bool atStartVertex = false;  // a is the vertex just copied
                for (; next <= c.from.edge; ++next)
                {
                    rebuilt.push_back(si_->cloneState(states[next]));
                    atStartVertex = next == c.from.edge && c.from.fraction == 0.0;
                }
                // (a may also be where the shortcut before this one ended: no zero-length edge then.)
                if (!atStartVertex && !(!rebuilt.empty() && si_->distance(rebuilt.back(), c.a) == 0.0))
                    rebuilt.push_back(si_->cloneState(c.a));
                rebuilt.push_back(si_->cloneState(c.b));
                next = c.to.edge + 1;  // vertices up to the shortcut's end point are cut
                if (c.to.fraction == 1.0)
                    ++next;  // b is that vertex itself
            }
            for (; next < n; ++next)
                rebuilt.push_back(si_->cloneState(states[next]));
            for (ob::State *state : states)
                si_->freeState(state);
            states = std::move(rebuilt);
            changed = true;
        }
        for (Candidate &c : candidatesOfRound)
        {
            si_->freeState(c.a);
            si_->freeState(c.b);
        }
        idle = saved > 1e-3 * length ? 0 : idle + 1;
    }
    return changed;
}
}  // namespace rastercheck::planners
