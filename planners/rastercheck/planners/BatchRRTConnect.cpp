#include "rastercheck/planners/BatchRRTConnect.h"

#include <algorithm>
#include <cmath>

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
                               "1:1:1024");
    declareParam<bool>("shortcut", this, &BatchRRTConnect::setShortcut, &BatchRRTConnect::getShortcut, "0,1");
}

void BatchRRTConnect::setBatchSize(unsigned int samples)
{
    if (samples == 0)
        throw ConfigurationError(getName() + ": batch_size must be at least 1");
    batchSize_ = samples;
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
}

BatchRRTConnect::Motion *BatchRRTConnect::addMotion(const Tree &tree, const ob::State *state, Motion *parent)
{
    auto *motion = new Motion;
    motion->state = si_->cloneState(state);
    motion->parent = parent;
    motions_.push_back(motion);
    tree->add(motion);
    return motion;
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
        line.last = (*line.other)->nearest(motion);
        line.origin = line.last->state;
        const double d = si_->distance(line.origin, motion->state);
        line.step = d > range_ ? range_ / d : 1.0;
        lines.push_back(line);
    }
    // Rounds: the next step of every live line, all decided in one call. One step per line and
    // round: a step past a blocked one would be wasted work (on the CPU a batch costs the sum of its
    // checks).
    std::vector<ompl::Edge> edges;
    std::vector<std::size_t> owner;
    std::vector<ob::State *> points;  ///< ends of the steps of this round (not the targets)
    std::vector<std::uint8_t> valid;
    bool joined = false;
    for (bool live = !lines.empty(); live && !ptc && !joined;)
    {
        edges.clear();
        owner.clear();
        for (std::size_t l = 0; l < lines.size(); ++l)
        {
            Line &line = lines[l];
            if (!line.alive)
                continue;
            const double f = (line.grown + 1) * line.step;
            const ob::State *to = line.target->state;
            if (f < 1.0)
            {
                points.push_back(si_->allocState());
                si_->getStateSpace()->interpolate(line.origin, line.target->state, f, points.back());
                to = points.back();
            }
            edges.push_back({line.last->state, to});
            owner.push_back(l);
        }
        edges_->check(edges, valid);
        live = false;
        for (std::size_t e = 0; e < edges.size(); ++e)
        {
            Line &line = lines[owner[e]];
            if (!valid[e])
            {
                line.alive = false;
                continue;
            }
            if (edges[e].to != line.target->state)
            {
                line.last = addMotion(*line.other, edges[e].to, line.last);
                ++line.grown;
                live = true;
                continue;
            }
            // Joined: root of the start tree ... last state of one tree, first of the other ... goal.
            const bool fromStart = line.other == &goalTree_;
            connection_ = fromStart ? std::pair<const Motion *, const Motion *>(line.target, line.last)
                                    : std::pair<const Motion *, const Motion *>(line.last, line.target);
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
            break;
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
        addMotion(startTree_, start, nullptr);
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
    OMPL_LOG(INFO, "%s: starting with %u states, %u samples per batch", getName().c_str(),
             static_cast<unsigned int>(startTree_->size() + goalTree_->size()), batchSize_);

    std::vector<ob::State *> samples(batchSize_);
    si_->allocStates(samples);
    Motion probe;
    // States added since the last connection round, and the tree each belongs to.
    std::vector<std::pair<Motion *, const Tree *>> fresh;
    std::vector<Motion *> nearest;
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
        if (goalTree_->size() == 0 || pis_.getSampledGoalsCount() < goalTree_->size() / 2)
        {
            if (const ob::State *state = goalTree_->size() == 0 ? pis_.nextGoal(ptc) : pis_.nextGoal())
                fresh.emplace_back(addMotion(goalTree_, state, nullptr), &goalTree_);
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
        nearest.clear();
        grown.clear();
        for (unsigned int i = 0; i < batchSize_; ++i)
        {
            const Tree &tree = extensions++ % 2 == 0 ? startTree_ : goalTree_;
            sampler_->sampleUniform(samples[i]);
            probe.state = samples[i];
            Motion *from = tree->nearest(&probe);
            const double d = si_->distance(from->state, samples[i]);
            if (!(d > 0.0))
                continue;
            if (d > range_)
                si_->getStateSpace()->interpolate(from->state, samples[i], range_ / d, samples[i]);
            nearest.push_back(from);
            grown.push_back(&tree);
            edges.push_back({from->state, samples[i]});
        }
        edges_->check(edges, valid);
        for (std::size_t k = 0; k < edges.size(); ++k)
            if (valid[k])
                fresh.emplace_back(addMotion(*grown[k], edges[k].to, nearest[k]), grown[k]);
    }
    si_->freeStates(samples);
    OMPL_LOG(INFO, "%s: %u states in the trees (%u start, %u goal)", getName().c_str(),
             static_cast<unsigned int>(motions_.size()), static_cast<unsigned int>(startTree_->size()),
             static_cast<unsigned int>(goalTree_->size()));
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
