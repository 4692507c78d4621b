#include "rastercheck/ompl/Planners.h"

#include <exception>
#include <functional>
#include <map>
#include <stdexcept>

#include <ompl/geometric/planners/est/BiEST.h>
#include <ompl/geometric/planners/est/EST.h>
#include <ompl/geometric/planners/est/ProjEST.h>
#include <ompl/geometric/planners/fmt/BFMT.h>
#include <ompl/geometric/planners/fmt/FMT.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/kpiece/BKPIECE1.h>
#include <ompl/geometric/planners/kpiece/KPIECE1.h>
#include <ompl/geometric/planners/kpiece/LBKPIECE1.h>
#include <ompl/geometric/planners/pdst/PDST.h>
#include <ompl/geometric/planners/prm/LazyPRM.h>
#include <ompl/geometric/planners/prm/LazyPRMstar.h>
#include <ompl/geometric/planners/prm/PRM.h>
#include <ompl/geometric/planners/prm/PRMstar.h>
#include <ompl/geometric/planners/prm/SPARS.h>
#include <ompl/geometric/planners/prm/SPARStwo.h>
#include <ompl/geometric/planners/rrt/BiTRRT.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/LBTRRT.h>
#include <ompl/geometric/planners/rrt/LazyRRT.h>
#include <ompl/geometric/planners/rrt/RRT.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTsharp.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/geometric/planners/rrt/SORRTstar.h>
#include <ompl/geometric/planners/rrt/TRRT.h>
#include <ompl/geometric/planners/sbl/SBL.h>
#include <ompl/geometric/planners/sst/SST.h>
#include <ompl/geometric/planners/stride/STRIDE.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Text.h"
#include "rastercheck/planners/BatchRRTConnect.h"

namespace og = ::ompl::geometric;
namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
namespace
{
using Allocator = std::function<ob::PlannerPtr(const ob::SpaceInformationPtr &)>;

template <class PlannerType>
Allocator make()
{
    return [](const ob::SpaceInformationPtr &si) { return std::make_shared<PlannerType>(si); };
}

const std::map<std::string, Allocator> &registry()
{
    static const std::map<std::string, Allocator> planners{
        {"batchrrtconnect", make<rastercheck::planners::BatchRRTConnect>()},
        {"bfmt", make<og::BFMT>()},
        {"biest", make<og::BiEST>()},
        {"bitrrt", make<og::BiTRRT>()},
        {"bitstar", make<og::BITstar>()},
        {"bkpiece", make<og::BKPIECE1>()},
        {"est", make<og::EST>()},
        {"fmt", make<og::FMT>()},
        {"informedrrtstar", make<og::InformedRRTstar>()},
        {"kpiece", make<og::KPIECE1>()},
        {"lazyprm", make<og::LazyPRM>()},
        {"lazyprmstar", make<og::LazyPRMstar>()},
        {"lazyrrt", make<og::LazyRRT>()},
        {"lbkpiece", make<og::LBKPIECE1>()},
        {"lbtrrt", make<og::LBTRRT>()},
        {"pdst", make<og::PDST>()},
        {"prm", make<og::PRM>()},
        {"prmstar", make<og::PRMstar>()},
        {"projest", make<og::ProjEST>()},
        {"rrt", make<og::RRT>()},
        {"rrtconnect", make<og::RRTConnect>()},
        {"rrtsharp", make<og::RRTsharp>()},
        {"rrtstar", make<og::RRTstar>()},
        {"sbl", make<og::SBL>()},
        {"sorrtstar", make<og::SORRTstar>()},
        {"spars", make<og::SPARS>()},
        {"spars2", make<og::SPARStwo>()},
        {"sst", make<og::SST>()},
        {"stride", make<og::STRIDE>()},
        {"trrt", make<og::TRRT>()},
    };
    return planners;
}
}  // namespace

const std::vector<std::string> &knownPlannerNames()
{
    static const std::vector<std::string> names = []
    {
        std::vector<std::string> result;
        for (const auto &entry : registry())
            result.push_back(entry.first);
        return result;
    }();
    return names;
}

ob::PlannerPtr allocatePlanner(const std::string &name, const ob::SpaceInformationPtr &si)
{
    const std::string key = lowerCase(name);
    const auto found = registry().find(key);
    if (found == registry().end())
    {
        std::string known;
        for (const std::string &n : knownPlannerNames())
            known += (known.empty() ? "" : ", ") + n;
        throw ConfigurationError("unknown planner '" + name + "' (known: " + known + ")");
    }
    return found->second(si);
}

void setPlannerParameters(ob::Planner &planner, const std::vector<std::pair<std::string, std::string>> &parameters)
{
    for (const auto &[key, value] : parameters)
    {
        if (!planner.params().hasParam(key))
            throw ConfigurationError("planner " + planner.getName() + " has no parameter '" + key + "'");
        // OMPL reads the value with its own conversions: a value that is not a number makes setParam
        // return false or throw (std::runtime_error for a real parameter), and a number too large
        // for the type ("1e999") throws std::out_of_range.
        bool accepted = false;
        try
        {
            accepted = planner.params().setParam(key, value);
        }
        catch (const Error &)
        {
            throw;  // the planner's own refusal, with its reason
        }
        catch (const std::exception &)
        {
        }
        if (!accepted)
            throw ConfigurationError("planner " + planner.getName() + " rejected " + key + "=" + value);
    }
}
}  // namespace rastercheck::ompl
