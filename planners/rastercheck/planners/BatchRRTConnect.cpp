#include "rastercheck/planners/BatchRRTConnect.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>

#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/tools/config/SelfConfig.h>
#include "rastercheck/core/Error.h"
#include "rastercheck/planners/BatchShortcutter.h"
#include "rastercheck/planners/Log.h"

namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace rastercheck::planners
{
BatchRRTConnect::BatchRRTConnect(const ob::SpaceInformationPtr &si) : ob::Planner(si, "BatchRRTConnect")
{
    specs_.recognizedGoal = ob::GOAL_SAMPLEABLE_REGION;
    specs_.directed = true;
    declareParam<double>("range", this, &BatchRRTConnect::setRange, &BatchRRTConnect::getRange, "0.:1.:10000.");
    declareParam<unsigned int>("batch_size", this, &BatchRRTConnect::setBatchSize, &BatchRRTConnect::getBatchSize,
                               "0:1:4096");
    declareParam<bool>("shortcut", this, &BatchRRTConnect::setShortcut, &BatchRRTConnect::getShortcut, "0,1");
    declareParam<bool>("lazy", this, &BatchRRTConnect::setLazy, &BatchRRTConnect::getLazy, "0,1");
    declareParam<unsigned int>("lazy_limit", this, &BatchRRTConnect::setLazyLimit, &BatchRRTConnect::getLazyLimit,
                               "1:1:1000000");
    declareParam<unsigned int>("lazy_samples", this, &BatchRRTConnect::setLazySamples, &BatchRRTConnect::getLazySamples,
                               "1:1:64");
    declareParam<int>("decide_together", this, &BatchRRTConnect::setDecideTogether, &BatchRRTConnect::getDecideTogether,
                      "-1:1:1");
}

void BatchRRTConnect::setDecideTogether(int choice)
{
    if (choice < -1 || choice > 1)
        throw ConfigurationError(getName() + ": decide_together must be -1 (by the backend), 0 or 1, got " +
                                 std::to_string(choice));
    decideTogether_ = choice;
}

void BatchRRTConnect::setLazySamples(unsigned int samples)
{
    if (samples == 0)
        throw ConfigurationError(getName() + ": lazy_samples must be at least 1");
    lazySamples_ = samples;
}

unsigned int BatchRRTConnect::samplesPerBatch() const
{
    if (batchSize_ > 0)
        return batchSize_;
    const std::size_t deviceBatch = edges_ ? edges_->deviceBatch() : 0;
    if (deviceBatch == 0)
        return kCpuSamplesPerBatch;
    const std::size_t statesPerSample = lazy_ ? lazySamples_ : 1;
    const std::size_t samples = (deviceBatch + statesPerSample - 1) / statesPerSample;
    // Iterations that cannot reach the device (the automatic threshold on many CPU threads) run on
    // the CPU: they take the CPU's size, since thousands of samples there would buy nothing.
    if (samples > kDeviceSamplesPerBatch[1])
        return kCpuSamplesPerBatch;
    return static_cast<unsigned int>(std::max<std::size_t>(samples, kDeviceSamplesPerBatch[0]));
}

BatchRRTConnect::~BatchRRTConnect()
{
    freeMemory();
}

void BatchRRTConnect::setup()
{
    ob::Planner::setup();
    ::ompl::tools::SelfConfig config(si_, getName());
    config.configurePlannerRange(range_);
    for (Tree *tree : {&startTree_, &goalTree_})
    {
        if (!*tree)
            tree->reset(::ompl::tools::SelfConfig::getDefaultNearestNeighbors<Motion *>(this));
        (*tree)->setDistanceFunction([this](const Motion *a, const Motion *b)
                                     { return si_->distance(a->state, b->state); });
    }

    edges_ = std::make_shared<const EdgeChecker>(si_);
    OMPL_LOG(DEBUG, "%s: edges %s", getName().c_str(), edges_->description().c_str());
}

void BatchRRTConnect::freeMemory()
{
    for (Motion *motion : motions_)
    {
        si_->freeState(motion->state);
        delete motion;
    }
    motions_.clear();
}

void BatchRRTConnect::clear()
{
    ob::Planner::clear();
    sampler_.reset();
    freeMemory();
    if (startTree_)
        startTree_->clear();
    if (goalTree_)
        goalTree_->clear();
    connection_ = {nullptr, nullptr};
    ghosts_[0] = ghosts_[1] = 0;
}

BatchRRTConnect::Motion *BatchRRTConnect::addMotion(const Tree &tree, const ob::State *state, Motion *parent,
                                                    bool edgeDecided)
{
    auto *motion = new Motion;
    motion->state = si_->cloneState(state);
    motion->parent = parent;
    motion->tree = &tree;
    motion->edgeDecided = edgeDecided;
    motion->rakedLevels = edgeDecided ? 0 : lazyRakedLevels();
    if (parent)
        parent->children.push_back(motion);
    motions_.push_back(motion);
    tree->add(motion);
    return motion;
}

void BatchRRTConnect::checkNewEdges(const std::vector<ompl::Edge> &edges, std::vector<std::uint8_t> &valid,
                                    const std::vector<std::uint8_t> *endInTree)
{
    if (!lazyNow_)
    {
        edges_->check(edges, valid);
        return;
    }
    // States at fractions 1/k, 2/k, ..., 1 of every edge (the start is a tree's state already, and
    // so is the end of a step that joins the trees).
    const unsigned int k = lazySamples_;
    std::vector<std::pair<std::size_t, double>> points;
    points.reserve(edges.size() * k);
    for (std::size_t e = 0; e < edges.size(); ++e)
        for (unsigned int j = 1; j <= k; ++j)
            if (j < k || !endInTree || !(*endInTree)[e])
                points.emplace_back(e, j == k ? 1.0 : static_cast<double>(j) / k);
    valid.assign(edges.size(), 1);
    lazyStates_ += edges_->checkAlong(edges, points, valid);
}

unsigned int BatchRRTConnect::lazyRakedLevels() const
{
    // A lazy edge's states at j / k include the rake's level L (the odd multiples of 2^-L) wherever
    // 2^L divides k: with the default k = 2 the rake's first level, the midpoint, is checked.
    unsigned int levels = 0;
    for (unsigned int k = lazySamples_; k % 2 == 0; k /= 2)
        ++levels;
    return levels;
}

void BatchRRTConnect::cutSubtree(Motion *motion)
{
    if (motion->parent)
    {
        std::vector<Motion *> &siblings = motion->parent->children;
        siblings.erase(std::find(siblings.begin(), siblings.end(), motion));
    }
    // Cut motions stay in the nearest-neighbour structure as ghosts: OMPL's GNAT rebuilds itself
    // whenever a removed element is one of its pivots, which took 80 % of a lazy run on OMPL.app's
    // Home. nearest() skips ghosts, and the structure is rebuilt once they are a fifth of it.
    std::vector<Motion *> stack{motion};
    while (!stack.empty())
    {
        Motion *m = stack.back();
        stack.pop_back();
        m->cut = true;
        ++ghosts(*m->tree);
        ++cutMotions_;
        stack.insert(stack.end(), m->children.begin(), m->children.end());
    }
    const Tree &tree = *motion->tree;
    if (4 * ghosts(tree) > liveSize(tree))
    {
        std::vector<Motion *> all, live;
        tree->list(all);
        std::copy_if(all.begin(), all.end(), std::back_inserter(live), [](const Motion *m) { return !m->cut; });
        tree->clear();
        tree->add(live);
        ghosts(tree) = 0;
    }
}

void BatchRRTConnect::abandonLaziness()
{
    // Where candidates keep failing, the lazy trees grow through obstacles faster than candidates
    // cut them back (OMPL.app's Home: 13 880 candidates rejected in 15 s, trees three times the
    // size of an eager run's that solves in 2.4 s). Keep only what was decided, and go on eagerly.
    OMPL_LOG(INFO, "%s: %u candidates rejected; the rest of this solve decides every new edge", getName().c_str(),
             rejectedCandidates_);
    lazyNow_ = false;
    for (const Tree *tree : {&startTree_, &goalTree_})
    {
        std::vector<Motion *> motions;
        (*tree)->list(motions);
        for (Motion *motion : motions)
            if (!motion->cut && !motion->edgeDecided)
                cutSubtree(motion);
    }
}

std::size_t &BatchRRTConnect::ghosts(const Tree &tree)
{
    return ghosts_[&tree == &startTree_ ? 0 : 1];
}

std::size_t BatchRRTConnect::liveSize(const Tree &tree) const
{
    return tree->size() - ghosts_[&tree == &startTree_ ? 0 : 1];
}

double BatchRRTConnect::stepRange() const
{
    // Where lazy candidates keep failing, edges of the full range mostly fail too: half as long,
    // more of them pass (problems 1-10 of every MotionBenchMaker scenario: Panda p95 0.29-0.34 ->
    // 0.09 s, Fetch 45 -> 56 of 70 solved; OMPL.app Home median 1.07 -> 0.87 s; docs/benchmarks.md
    // "Tuning: why the defaults").
    return lazy_ && !lazyNow_ ? 0.5 * range_ : range_;
}

BatchRRTConnect::Motion *BatchRRTConnect::nearest(const Tree &tree, const Motion *probe) const
{
    Motion *motion = tree->nearest(const_cast<Motion *>(probe));
    // Roots are never cut, so some k finds a live motion.
    std::vector<Motion *> near;
    for (std::size_t k = 4; motion->cut; k *= 2)
    {
        tree->nearestK(const_cast<Motion *>(probe), k, near);
        const auto live = std::find_if(near.begin(), near.end(), [](const Motion *m) { return !m->cut; });
        if (live != near.end())
            motion = *live;
    }
    return motion;
}

bool BatchRRTConnect::decidesCandidatesTogether() const
{
    if (decideTogether_ >= 0)
        return decideTogether_ == 1;
    return edges_ && edges_->reachesDevice(samplesPerBatch() * std::size_t{lazy_ ? lazySamples_ : 1u});
}

std::size_t BatchRRTConnect::decideCandidates(const std::vector<Candidate> &candidates)
{
    // The undecided edges of every candidate's branches (parent to child, as they were grown; each
    // once, as candidates share their trees' edges) and the bridges: paths[c] lists candidate c's.
    std::vector<ompl::Edge> edges;
    std::vector<Motion *> below;  ///< the motion under each tree edge; null for a bridge
    std::vector<std::vector<std::size_t>> paths(candidates.size());
    std::map<const Motion *, std::size_t> edgeOf;
    for (std::size_t c = 0; c < candidates.size(); ++c)
    {
        const Candidate &candidate = candidates[c];
        for (Motion *end : {candidate.startEnd, candidate.goalEnd})
            for (Motion *m = end; m->parent; m = m->parent)
                if (!m->edgeDecided)
                {
                    const auto [at, added] = edgeOf.emplace(m, edges.size());
                    if (added)
                    {
                        edges.push_back({m->parent->state, m->state});
                        below.push_back(m);
                    }
                    paths[c].push_back(at->second);
                }
        if (!candidate.bridgeDecided)
        {
            paths[c].push_back(edges.size());
            edges.push_back(candidate.bridge);
            below.push_back(nullptr);
        }
        if (paths[c].empty())
            return c;  // eager mode: every edge was decided when it was grown
    }

    // Most candidates cross an obstacle that the few states of their edges missed: states at
    // rising density find that for a fraction of a certification's cost. Only a candidate that
    // passes them at the space's resolution is certified.
    std::vector<std::uint8_t> valid;
    std::vector<unsigned int> levels;
    for (const Motion *m : below)
        levels.push_back(m ? m->rakedLevels : lazyRakedLevels());  // a bridge was a lazy step
    rakedStates_ += edges_->rake(edges, levels, valid, &paths);
    for (std::size_t e = 0; e < edges.size(); ++e)
        if (below[e])
            below[e]->rakedLevels = levels[e];
    // The survivors in order, each certified (its edges not certified yet) until one is accepted.
    auto accepted = [&](std::size_t c)
    { return std::all_of(paths[c].begin(), paths[c].end(), [&](std::size_t e) { return valid[e] != 0; }); };
    std::vector<std::uint8_t> certified(edges.size(), 0);
    std::size_t found = candidates.size();
    for (std::size_t c = 0; c < candidates.size() && found == candidates.size(); ++c)
    {
        if (!accepted(c))
            continue;
        std::vector<std::size_t> open;
        std::vector<ompl::Edge> openEdges;
        for (std::size_t e : paths[c])
            if (!certified[e])
            {
                open.push_back(e);
                openEdges.push_back(edges[e]);
            }
        std::vector<std::uint8_t> openValid;
        edges_->check(openEdges, openValid);
        for (std::size_t k = 0; k < open.size(); ++k)
        {
            const std::size_t e = open[k];
            valid[e] = openValid[k];
            certified[e] = openValid[k];
            // An edge the rake did not reject is still undecided: only the EdgeChecker decides.
            if (below[e] && openValid[k])
                below[e]->edgeDecided = true;
        }
        if (accepted(c))
            found = c;
    }
    // Cut after deciding: a rejected edge's subtree may hold another rejected edge of a branch.
    for (std::size_t e = 0; e < edges.size(); ++e)
        if (below[e] && !valid[e] && !below[e]->cut)
            cutSubtree(below[e]);
    // Candidates and rejections count as deciding them one at a time would count them (lazy_limit's
    // measure): a candidate on an edge rejected on an earlier counted one is not counted, since
    // one at a time that edge's cut would have ended its line first.
    std::vector<std::uint8_t> counted(edges.size(), 0);
    for (std::size_t c = 0; c < candidates.size(); ++c)
    {
        const std::vector<std::size_t> &path = paths[c];
        if (accepted(c) || std::any_of(path.begin(), path.end(), [&](std::size_t e) { return counted[e] != 0; }))
            continue;
        ++candidates_;
        ++rejectedCandidates_;
        for (std::size_t e : path)
            counted[e] = !valid[e];
    }
    candidates_ += found < candidates.size() ? 1 : 0;
    if (found == candidates.size() && lazyNow_ && rejectedCandidates_ >= lazyLimit_)
        abandonLaziness();
    return found;
}

std::vector<const ob::State *> BatchRRTConnect::branch(const Motion *motion)
{
    std::vector<const ob::State *> states;
    for (; motion; motion = motion->parent)
        states.push_back(motion->state);
    std::reverse(states.begin(), states.end());
    return states;
}

bool BatchRRTConnect::connect(const std::vector<std::pair<Motion *, const Tree *>> &fresh,
                              const ob::PlannerTerminationCondition &ptc)
{
    // A line from the other tree's nearest state to a fresh state; the other tree grows along it
    // in steps of range (RRT-Connect's connect), each step an edge of its own.
    struct Line
    {
        Motion *target = nullptr;
        const Tree *other = nullptr;
        const ob::State *origin = nullptr;
        Motion *last = nullptr;  ///< the other tree's state furthest along the line
        double step = 1.0;       ///< range as a fraction of the line
        unsigned int grown = 0;  ///< steps grown so far
        bool alive = true;
    };
    std::vector<Line> lines;
    for (const auto &[motion, tree] : fresh)
    {
        Line line;
        line.target = motion;
        line.other = tree == &startTree_ ? &goalTree_ : &startTree_;
        line.last = nearest(*line.other, motion);
        line.origin = line.last->state;
        const double d = si_->distance(line.origin, motion->state);
        const double step = stepRange();
        line.step = d > step ? step / d : 1.0;
        lines.push_back(line);
    }
    // Rounds: the next step of every live line, all decided in one call. One step per line and
    // round on the CPU: a step past a blocked one would be wasted work (a batch costs the sum of its
    // checks there).
    std::vector<ompl::Edge> edges;
    std::vector<std::size_t> owner;
    std::vector<ob::State *> points;        ///< ends of the steps of this round (not the targets)
    std::vector<std::uint8_t> endIsTarget;  ///< the step ends at its line's target, a tree state
    std::vector<std::uint8_t> valid;
    bool joined = false;
    auto addSolution = [&](const Candidate &candidate)
    {
        connection_ = {candidate.startEnd, candidate.goalEnd};
        std::vector<const ob::State *> states = branch(connection_.first);
        const std::vector<const ob::State *> back = branch(connection_.second);
        states.insert(states.end(), back.rbegin(), back.rend());
        auto path = std::make_shared<og::PathGeometric>(si_);
        for (const ob::State *state : states)
            path->append(state);
        if (shortcut_)
            BatchShortcutter(si_, edges_).shortcut(*path, ptc);
        pdef_->addSolutionPath(path, false, 0.0, getName());
        joined = true;
    };
    // The lines that reached their targets this round; on the CPU each is decided at once, in turn.
    const bool together = decidesCandidatesTogether();
    std::vector<Candidate> joins;
    std::vector<std::size_t> joinLines;
    for (bool live = !lines.empty(); live && !ptc && !joined;)
    {
        edges.clear();
        owner.clear();
        endIsTarget.clear();
        joins.clear();
        joinLines.clear();
        for (std::size_t l = 0; l < lines.size(); ++l)
        {
            Line &line = lines[l];
            line.alive = line.alive && !line.last->cut && !line.target->cut;
            if (!line.alive)
                continue;
            // Together (on a device), every step left to the target in this one round: a call costs
            // its latency there, and the steps past a blocked one little.
            const ob::State *from = line.last->state;
            for (unsigned int k = 1; k == 1 || together; ++k)
            {
                const double f = (line.grown + k) * line.step;
                const ob::State *to = line.target->state;
                if (f < 1.0)
                {
                    points.push_back(si_->allocState());
                    si_->getStateSpace()->interpolate(line.origin, line.target->state, f, points.back());
                    to = points.back();
                }
                edges.push_back({from, to});
                owner.push_back(l);
                endIsTarget.push_back(to == line.target->state ? 1 : 0);
                if (to == line.target->state)
                    break;
                from = to;
            }
        }
        const bool lazyRound = lazyNow_;  // a rejected candidate below may end laziness mid-round
        checkNewEdges(edges, valid, &endIsTarget);
        live = false;
        for (std::size_t e = 0; e < edges.size(); ++e)
        {
            Line &line = lines[owner[e]];
            if (!line.alive)
                continue;  // an earlier step of this line, this round, was blocked
            // A lazy candidate rejected earlier in this round may have cut either end of the line.
            if (!valid[e] || line.last->cut || line.target->cut)
            {
                line.alive = false;
                continue;
            }
            if (edges[e].to != line.target->state)
            {
                line.last = addMotion(*line.other, edges[e].to, line.last, !lazyRound);
                ++line.grown;
                live = true;
                continue;
            }
            // Joined: root of the start tree ... last state of one tree, first of the other ... goal.
            const bool fromStart = line.other == &goalTree_;
            joins.push_back({fromStart ? line.target : line.last, fromStart ? line.last : line.target,
                             ompl::Edge{line.last->state, edges[e].to}, !lazyRound});
            joinLines.push_back(owner[e]);
            if (together)
                continue;
            if (decideCandidates(joins) == 0)
            {
                addSolution(joins[0]);
                break;
            }
            line.alive = false;
            joins.clear();
            joinLines.clear();
        }
        if (together && !joins.empty())
        {
            const std::size_t c = decideCandidates(joins);
            if (c < joins.size())
                addSolution(joins[c]);
            else
                for (std::size_t l : joinLines)
                    lines[l].alive = false;
        }
        for (ob::State *point : points)
            si_->freeState(point);
        points.clear();
    }
    return joined;
}

ob::PlannerStatus BatchRRTConnect::solve(const ob::PlannerTerminationCondition &ptc)
{
    checkValidity();
    auto *goal = dynamic_cast<ob::GoalSampleableRegion *>(pdef_->getGoal().get());
    if (!goal)
    {
        OMPL_LOG(ERROR, "%s: the goal is not a sampleable region", getName().c_str());
        return ob::PlannerStatus::UNRECOGNIZED_GOAL_TYPE;
    }
    while (const ob::State *start = pis_.nextStart())
        addMotion(startTree_, start, nullptr, true);
    if (startTree_->size() == 0)
    {
        OMPL_LOG(ERROR, "%s: no valid start state", getName().c_str());
        return ob::PlannerStatus::INVALID_START;
    }
    if (!goal->couldSample())
    {
        OMPL_LOG(ERROR, "%s: the goal region cannot be sampled", getName().c_str());
        return ob::PlannerStatus::INVALID_GOAL;
    }
    if (!sampler_)
        sampler_ = si_->allocStateSampler();
    candidates_ = rejectedCandidates_ = cutMotions_ = 0;
    lazyNow_ = lazy_;
    lazyStates_ = rakedStates_ = 0;
    const unsigned int batchSize = samplesPerBatch();
    OMPL_LOG(INFO, "%s: starting with %u states, %u samples per batch", getName().c_str(),
             static_cast<unsigned int>(startTree_->size() + goalTree_->size()), batchSize);

    std::vector<ob::State *> samples(batchSize);
    si_->allocStates(samples);
    Motion probe;
    // States added since the last connection round, and the tree each belongs to.
    std::vector<std::pair<Motion *, const Tree *>> fresh;
    std::vector<Motion *> parents;  ///< the tree state each new edge starts from
    std::vector<const Tree *> grown;
    std::vector<ompl::Edge> edges;
    std::vector<std::uint8_t> valid;
    std::uint64_t extensions = 0;  // the trees take turns, sample by sample
    bool solved = false;
    while (!solved && !ptc)
    {
        // Goal states: the first one waits for the goal region (up to ptc); more while it offers
        // new ones, as RRT-Connect. A new goal state tries to connect to the start tree (the
        // first one: the straight line from start to goal).
        if (goalTree_->size() == 0 || pis_.getSampledGoalsCount() < liveSize(goalTree_) / 2)
        {
            if (const ob::State *state = goalTree_->size() == 0 ? pis_.nextGoal(ptc) : pis_.nextGoal())
                fresh.emplace_back(addMotion(goalTree_, state, nullptr, true), &goalTree_);
            if (goalTree_->size() == 0)
            {
                OMPL_LOG(ERROR, "%s: no valid goal state could be sampled", getName().c_str());
                break;
            }
        }

        solved = connect(fresh, ptc);
        fresh.clear();
        if (solved || ptc)
            break;

        // Extend: batch_size samples, alternately for each tree; each tree steps from its nearest
        // state toward the sample by at most range; all edges decided in one call.
        edges.clear();
        parents.clear();
        grown.clear();
        for (unsigned int i = 0; i < batchSize; ++i)
        {
            const Tree &tree = extensions++ % 2 == 0 ? startTree_ : goalTree_;
            sampler_->sampleUniform(samples[i]);
            probe.state = samples[i];
            Motion *from = nearest(tree, &probe);
            const double d = si_->distance(from->state, samples[i]);
            if (!(d > 0.0))
                continue;
            const double step = stepRange();
            if (d > step)
                si_->getStateSpace()->interpolate(from->state, samples[i], step / d, samples[i]);
            parents.push_back(from);
            grown.push_back(&tree);
            edges.push_back({from->state, samples[i]});
        }
        checkNewEdges(edges, valid);
        for (std::size_t k = 0; k < edges.size(); ++k)
            if (valid[k])
                fresh.emplace_back(addMotion(*grown[k], edges[k].to, parents[k], !lazyNow_), grown[k]);
    }
    si_->freeStates(samples);
    OMPL_LOG(INFO, "%s: %u states in the trees (%u start, %u goal)", getName().c_str(),
             static_cast<unsigned int>(liveSize(startTree_) + liveSize(goalTree_)),
             static_cast<unsigned int>(liveSize(startTree_)), static_cast<unsigned int>(liveSize(goalTree_)));
    if (lazy_)
        OMPL_LOG(INFO,
                 "%s: %u candidate solutions, %u rejected, %u states cut; %llu states checked on new edges, %llu along "
                 "candidates",
                 getName().c_str(), candidates_, rejectedCandidates_, cutMotions_,
                 static_cast<unsigned long long>(lazyStates_), static_cast<unsigned long long>(rakedStates_));
    return solved ? ob::PlannerStatus::EXACT_SOLUTION : ob::PlannerStatus::TIMEOUT;
}

void BatchRRTConnect::getPlannerData(ob::PlannerData &data) const
{
    ob::Planner::getPlannerData(data);
    for (const auto &[tree, tag] : {std::make_pair(&startTree_, 1), std::make_pair(&goalTree_, 2)})
    {
        std::vector<Motion *> motions;
        if (*tree)
            (*tree)->list(motions);
        for (const Motion *motion : motions)
        {
            if (motion->cut)
                continue;
            const ob::PlannerDataVertex vertex(motion->state, tag);
            if (!motion->parent)
                tag == 1 ? data.addStartVertex(vertex) : data.addGoalVertex(vertex);
            else if (tag == 1)
                data.addEdge(ob::PlannerDataVertex(motion->parent->state, tag), vertex);
            else
                data.addEdge(vertex, ob::PlannerDataVertex(motion->parent->state, tag));
        }
    }
    if (connection_.first && connection_.second)
        data.addEdge(data.vertexIndex(connection_.first->state), data.vertexIndex(connection_.second->state));
}
}  // namespace rastercheck::planners
