#pragma once

#include <string>
#include <utility>
#include <vector>

#include <ompl/base/Planner.h>
#include <ompl/base/SpaceInformation.h>

namespace rastercheck::ompl
{
/** \brief The geometric planners known by their OMPL.app names ("rrtconnect", "rrt", "prm",
    "kpiece", "bkpiece", "lbkpiece", "est", "sbl", "stride", "pdst", "trrt", "rrtstar", ...) and
    rastercheck's own ("batchrrtconnect": rastercheck::planners::BatchRRTConnect), sorted. The
    registry lives in the rastercheck::planners library (link rastercheck::planners). */
const std::vector<std::string> &knownPlannerNames();

/** \brief A new planner of OMPL.app name \a name (case-insensitive) on \a si. Throws
    ConfigurationError listing the known names when \a name is not one. */
::ompl::base::PlannerPtr allocatePlanner(const std::string &name, const ::ompl::base::SpaceInformationPtr &si);

/** \brief Applies (parameter, value) pairs, as written after "name." in an OMPL.app [planner]
    section ("range", "5"), through planner->params().setParam. Throws ConfigurationError naming the
    planner and parameter when the planner has no such parameter or rejects the value. */
void setPlannerParameters(::ompl::base::Planner &planner,
                          const std::vector<std::pair<std::string, std::string>> &parameters);
}  // namespace rastercheck::ompl
