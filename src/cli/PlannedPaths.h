#pragma once
// `rastercheck plan --path-out DIR`: every solved run's path as a states CSV (what `check --states`,
// `render --states` and `view --path` read), as the planner returned it and simplified, with an
// index that gives the exact re-check's verdict of each.

#include <fstream>
#include <memory>
#include <string>

#include <ompl/base/Planner.h>
#include <ompl/geometric/PathGeometric.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/StateMapping.h"

namespace rastercheck::cli
{
/** \brief Runs \a inner and keeps a copy of the path it returned: ompl::tools::Benchmark simplifies
    the solution in place before the post-run event sees it. Name, parameters, specs, progress
    properties and planner data are the inner planner's, so the benchmark log does not change. */
class RawPathRecorder : public ::ompl::base::Planner
{
public:
    explicit RawPathRecorder(::ompl::base::PlannerPtr inner);
    ::ompl::base::PlannerStatus solve(const ::ompl::base::PlannerTerminationCondition &ptc) override;
    void clear() override;
    void setup() override;
    void setProblemDefinition(const ::ompl::base::ProblemDefinitionPtr &pdef) override;
    void getPlannerData(::ompl::base::PlannerData &data) const override;
    /** \brief The last solve's path as the planner returned it; null when it found none. */
    std::shared_ptr<const ::ompl::geometric::PathGeometric> rawPath() const { return raw_; }

private:
    ::ompl::base::PlannerPtr inner_;
    std::shared_ptr<::ompl::geometric::PathGeometric> raw_;
};

/** \brief The folder of `--path-out`: PLANNER_runN_raw.csv and PLANNER_runN_simplified.csv per solved
    run (N from 0, as the plan command's messages count runs), and paths.csv, the index: planner,
    run, path (raw or simplified), file, states, exact_recheck (collision_free or colliding, the
    dense re-check by the exact oracle). */
class PathFolder
{
public:
    /** \brief Creates \a folder and the index; the raw paths are re-checked with \a checker under
        \a exact at \a recheckFactor times the planner's resolution (the final ones are re-checked by
        the caller). Throws InputError when the folder or the index cannot be written. */
    PathFolder(const std::string &folder, const ompl::StateMapping &mapping, const Checker &checker,
               CollisionRequest exact, unsigned int recheckFactor);

    /** \brief Writes run \a run of \a planner: its raw path (a RawPathRecorder's) and, when
        \a simplified, \a final (the simplified path, whose re-check is \a finalCheck). */
    void addRun(const ::ompl::base::Planner &planner, int run, const ::ompl::geometric::PathGeometric &final,
                const ompl::PathCheckResult &finalCheck, bool simplified);

private:
    void write(const std::string &planner, int run, const std::string &kind, const ::ompl::geometric::PathGeometric &path,
               bool collisionFree);

    std::string folder_;
    const ompl::StateMapping &mapping_;
    const Checker &checker_;
    CollisionRequest exact_;
    unsigned int recheckFactor_;
    std::ofstream index_;
};
}  // namespace rastercheck::cli
