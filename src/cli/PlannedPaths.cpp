#include "PlannedPaths.h"

#include <cctype>
#include <filesystem>

#include "rastercheck/core/Error.h"
#include "rastercheck/io/StatesCsv.h"

namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace rastercheck::cli
{
RawPathRecorder::RawPathRecorder(ob::PlannerPtr inner)
  : ob::Planner(inner->getSpaceInformation(), inner->getName()), inner_(std::move(inner))
{
    specs_ = inner_->getSpecs();
    // The parameters' setters and getters are the inner planner's: the log records its values.
    params_ = inner_->params();
    plannerProgressProperties_ = inner_->getPlannerProgressProperties();
}

ob::PlannerStatus RawPathRecorder::solve(const ob::PlannerTerminationCondition &ptc)
{
    raw_.reset();
    const ob::PlannerStatus status = inner_->solve(ptc);
    if (pdef_ && pdef_->hasSolution())
        if (auto path = std::dynamic_pointer_cast<og::PathGeometric>(pdef_->getSolutionPath()))
            raw_ = std::make_shared<og::PathGeometric>(*path);
    return status;
}

void RawPathRecorder::clear()
{
    ob::Planner::clear();
    inner_->clear();
    raw_.reset();
}

void RawPathRecorder::setup()
{
    ob::Planner::setup();
    inner_->setup();
}

void RawPathRecorder::setProblemDefinition(const ob::ProblemDefinitionPtr &pdef)
{
    ob::Planner::setProblemDefinition(pdef);
    inner_->setProblemDefinition(pdef);
}

void RawPathRecorder::getPlannerData(ob::PlannerData &data) const
{
    inner_->getPlannerData(data);
}

PathFolder::PathFolder(const std::string &folder, const ompl::StateMapping &mapping, const Checker &checker,
                       CollisionRequest exact, unsigned int recheckFactor)
  : folder_(folder), mapping_(mapping), checker_(checker), exact_(std::move(exact)), recheckFactor_(recheckFactor)
{
    std::error_code error;
    std::filesystem::create_directories(folder_, error);
    const std::string index = (std::filesystem::path(folder_) / "paths.csv").string();
    index_.open(index);
    if (!index_)
        throw InputError(index, "", "cannot write the index of --path-out");
    index_ << "planner,run,path,file,states,exact_recheck\n" << std::flush;
}

void PathFolder::addRun(const ob::Planner &planner, int run, const og::PathGeometric &final,
                        const ompl::PathCheckResult &finalCheck, bool simplified)
{
    const auto *recorder = dynamic_cast<const RawPathRecorder *>(&planner);
    const std::shared_ptr<const og::PathGeometric> raw = recorder ? recorder->rawPath() : nullptr;
    if (raw && simplified)
        write(planner.getName(), run, "raw", *raw,
              ompl::checkPathDensely(*raw, mapping_, checker_, exact_, recheckFactor_).valid);
    write(planner.getName(), run, simplified ? "simplified" : "raw", final, finalCheck.valid);
}

void PathFolder::write(const std::string &planner, int run, const std::string &kind, const og::PathGeometric &path,
                       bool collisionFree)
{
    // A file name from the planner's name ("geometric_RRTConnect", "BatchRRTConnect").
    std::string name;
    for (const char c : planner)
        name += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
    const std::string file = name + "_run" + std::to_string(run) + "_" + kind + ".csv";
    std::vector<double> values;
    values.reserve(path.getStateCount() * mapping_.numCoordinates());
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
    {
        const std::vector<double> q = mapping_.toConfiguration(path.getState(static_cast<unsigned int>(i)));
        values.insert(values.end(), q.begin(), q.end());
    }
    writeStatesCsv((std::filesystem::path(folder_) / file).string(), mapping_.robot().coordinateNames, values);
    index_ << planner << ',' << run << ',' << kind << ',' << file << ',' << path.getStateCount() << ','
           << (collisionFree ? "collision_free" : "colliding") << '\n'
           << std::flush;
}
}  // namespace rastercheck::cli
