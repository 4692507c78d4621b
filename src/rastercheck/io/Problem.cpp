#include "rastercheck/io/Problem.h"

#include "rastercheck/core/Error.h"
#include "rastercheck/io/MeshLoader.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/SrdfLoader.h"

namespace rastercheck
{
namespace
{
bool endsWith(const std::string &text, const std::string &suffix)
{
    return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

ScenePtr loadSceneFile(const std::string &path)
{
    if (endsWith(path, ".yaml") || endsWith(path, ".yml"))
        return loadMoveItScene(path);
    // Node names are labels, not ids: exporters repeat them or leave them empty. Make them unique.
    auto scene = std::make_shared<Scene>();
    std::vector<MeshNode> nodes = loadMeshNodes(path);
    for (std::size_t k = 0; k < nodes.size(); ++k)
    {
        std::string name = nodes[k].name.empty() ? "object" : nodes[k].name;
        while (scene->objectIndex(name) >= 0)
            name += "/" + std::to_string(k);
        scene->addObject(name, std::move(nodes[k].mesh));
    }
    return scene;
}

Problem loadProblem(const ProblemSource &source)
{
    Problem problem;
    if (!source.cfgPath.empty())
    {
        if (!source.urdfPath.empty() || !source.scenePath.empty())
            throw ConfigurationError("give either an OMPL.app .cfg problem or --robot/--scene, not both");
        auto omplApp = std::make_shared<OmplAppProblem>(loadOmplAppProblem(source.cfgPath));
        problem.robot = omplApp->robot;
        problem.scene = omplApp->scene;
        problem.omplApp = omplApp;
        return problem;
    }
    if (source.urdfPath.empty())
        throw ConfigurationError("no problem given: pass an OMPL.app .cfg, or --robot URDF [--srdf F] [--scene F]");
    RobotModelPtr robot = loadUrdf(source.urdfPath, source.urdfOptions);
    if (!source.srdfPath.empty())
        applySrdf(*robot, loadSrdf(source.srdfPath));
    problem.robot = robot;
    problem.scene = source.scenePath.empty() ? std::make_shared<Scene>() : loadSceneFile(source.scenePath);
    return problem;
}
}  // namespace rastercheck
