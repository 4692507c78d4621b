#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/model/RigidBody.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/core/Text.h"
#include "rastercheck/io/MeshLoader.h"

namespace rastercheck
{
namespace
{
// The .cfg as OMPL.app's boost::program_options sees it: "section.key" = value, in file order.
struct ConfigFile
{
    std::string path;
    std::map<std::string, std::string> values;                      // [problem] and [benchmark], last wins
    std::vector<std::pair<std::string, std::string>> plannerLines;  // [planner], in order

    bool has(const std::string &key) const { return values.count(key) > 0; }

    std::string text(const std::string &key) const
    {
        auto it = values.find(key);
        if (it == values.end() || it->second.empty())
            throw InputError(path, "[" + section(key) + "] " + keyName(key), "missing");
        return it->second;
    }

    double number(const std::string &key) const
    {
        const std::string value = text(key);
        char *end = nullptr;
        errno = 0;
        const double parsed = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(parsed))
            throw InputError(path, "[" + section(key) + "] " + keyName(key), "'" + value + "' is not a finite number");
        return parsed;
    }

    double number(const std::string &key, double fallback) const { return has(key) ? number(key) : fallback; }

    static std::string section(const std::string &key) { return key.substr(0, key.find('.')); }
    static std::string keyName(const std::string &key) { return key.substr(key.find('.') + 1); }
};

ConfigFile parseConfig(const std::string &text, const std::string &path)
{
    std::istringstream in(text);
    ConfigFile config;
    config.path = path;
    std::string line, section;
    int lineNumber = 0;
    while (std::getline(in, line))
    {
        ++lineNumber;
        const std::size_t comment = line.find('#');
        if (comment != std::string::npos)
            line.erase(comment);
        line = trim(line);
        if (line.empty())
            continue;
        if (line.front() == '[')
        {
            if (line.back() != ']' || line.size() < 3)
                throw InputError(path, "line " + std::to_string(lineNumber), "malformed section header '" + line + "'");
            section = trim(line.substr(1, line.size() - 2));
            continue;
        }
        const std::size_t equals = line.find('=');
        if (equals == std::string::npos)
            throw InputError(path, "line " + std::to_string(lineNumber), "expected 'key = value', got '" + line + "'");
        const std::string key = trim(line.substr(0, equals)), value = trim(line.substr(equals + 1));
        if (key.empty())
            throw InputError(path, "line " + std::to_string(lineNumber), "empty key");
        if (section.empty())
            throw InputError(path, "line " + std::to_string(lineNumber), "key '" + key + "' outside a section");
        if (section == "planner")
            config.plannerLines.emplace_back(key, value);
        else
            config.values[section + "." + key] = value;
    }
    return config;
}

// Start or goal: x y z qx qy qz qw from position and axis-angle (3D), x y yaw (2D).
std::vector<double> readPose(const ConfigFile &config, const std::string &prefix, bool planar)
{
    const std::string p = "problem." + prefix + ".";
    if (planar)
        return {config.number(p + "x"), config.number(p + "y"), config.number(p + "theta")};
    const double theta = config.number(p + "theta");
    Eigen::Vector3d axis(config.number(p + "axis.x"), config.number(p + "axis.y"), config.number(p + "axis.z"));
    if (!(axis.norm() > 0.0))
    {
        if (theta != 0.0)
            throw InputError(config.path, "[problem] " + prefix + ".axis", "rotation axis has zero length");
        axis = Eigen::Vector3d::UnitX();
    }
    const Eigen::Quaterniond q(Eigen::AngleAxisd(theta, axis.normalized()));
    return {config.number(p + "x"), config.number(p + "y"), config.number(p + "z"), q.x(), q.y(), q.z(), q.w()};
}

// A mesh loader's InputError, reported against the .cfg key (robot, world) that names the mesh.
template <typename Load>
auto forKey(const ConfigFile &config, const std::string &key, Load load)
{
    try
    {
        return load();
    }
    catch (const InputError &e)
    {
        throw InputError(config.path, "[problem] " + key + " '" + config.text("problem." + key) + "'", e.what());
    }
}

std::vector<MeshNode> loadProblemMesh(const ConfigFile &config, const std::string &key, const std::string &path)
{
    // OMPL.app reads with assimp's defaults, which turn a Z_UP COLLADA file to Y up; the .cfg
    // coordinates refer to the meshes as OMPL.app sees them.
    return forKey(config, key, [&] { return loadMeshNodes(path, ColladaUpAxis::ConvertToYUp); });
}

// The vertices OMPL.app places by: the robot's centre, the world's bounds. Its extra assimp steps
// (face normals, graph optimisation) change the vertices but not the triangles, so the geometry comes
// from loadProblemMesh (one object per node, corners joined) and only these come from OMPL.app's import.
OmplAppVertices loadProblemVertices(const ConfigFile &config, const std::string &key, const std::string &path)
{
    return forKey(config, key, [&] { return loadOmplAppVertices(path); });
}
}  // namespace

OmplAppProblem loadOmplAppProblem(const std::string &cfgPath)
{
    std::ifstream in(cfgPath, std::ios::binary);
    if (!in)
        throw InputError(cfgPath, "", "file not found");
    std::ostringstream text;
    text << in.rdbuf();
    return loadOmplAppProblemString(text.str(), folderOf(cfgPath), cfgPath);
}

OmplAppProblem loadOmplAppProblemString(const std::string &text, const std::string &baseDirectory,
                                        const std::string &cfgPath)
{
    const ConfigFile config = parseConfig(text, cfgPath);
    auto resolve = [&](const std::string &file) { return file.front() == '/' ? file : baseDirectory + "/" + file; };

    OmplAppProblem problem;
    problem.cfgPath = cfgPath;
    problem.name = config.has("problem.name") ? config.text("problem.name") : "";
    problem.planar = config.has("problem.start.theta") && !config.has("problem.start.z") &&
                     !config.has("problem.start.axis.x") && !config.has("problem.start.axis.y") &&
                     !config.has("problem.start.axis.z");
    problem.robotMeshPath = resolve(config.text("problem.robot"));
    problem.start = readPose(config, "start", problem.planar);
    problem.goal = readPose(config, "goal", problem.planar);

    // The world: one object per assimp node, named after the node (made unique).
    problem.scene = std::make_shared<Scene>();
    if (config.has("problem.world"))
    {
        problem.worldMeshPath = resolve(config.text("problem.world"));
        std::set<std::string> used;
        std::size_t k = 0;
        for (MeshNode &node : loadProblemMesh(config, "world", problem.worldMeshPath))
        {
            std::string name = node.name.empty() ? "world" : node.name;
            if (!used.insert(name).second)
            {
                name += "/" + std::to_string(k);
                used.insert(name);
            }
            ++k;
            problem.scene->addObject(name, std::move(node.mesh));
        }
    }

    // Position bounds: volume.*; without them OMPL.app infers the bounds from the world: the box of
    // all its vertices (inferEnvironmentBounds, factor 1 and no margin), lines' and points' included.
    const int dims = problem.planar ? 2 : 3;
    const char *axes[] = {"x", "y", "z"};
    std::vector<double> lower(dims), upper(dims);
    const bool hasVolume = config.has("problem.volume.min.x");
    if (!hasVolume && problem.worldMeshPath.empty())
        throw InputError(cfgPath, "[problem] volume.min.x", "missing, and there is no world to infer bounds from");
    Aabb worldBounds;
    if (!hasVolume)
        for (const Eigen::Vector3d &vertex : loadProblemVertices(config, "world", problem.worldMeshPath).vertices)
            worldBounds.extend(vertex);
    for (int d = 0; d < dims; ++d)
    {
        const std::string min = std::string("problem.volume.min.") + axes[d],
                          max = std::string("problem.volume.max.") + axes[d];
        lower[d] = hasVolume ? config.number(min) : worldBounds.min[d];
        upper[d] = hasVolume ? config.number(max) : worldBounds.max[d];
        if (lower[d] > upper[d])
            throw InputError(cfgPath, std::string("[problem] volume.min.") + axes[d],
                             "min " + std::to_string(lower[d]) + " is above max " + std::to_string(upper[d]));
    }

    // The robot: all nodes merged, shifted so that OMPL.app's centre (the mean of the vertices of its
    // import, not of ours) is the origin.
    Mesh robotMesh;
    for (const MeshNode &node : loadProblemMesh(config, "robot", problem.robotMeshPath))
        robotMesh.append(node.mesh);
    Eigen::Vector3d center = loadProblemVertices(config, "robot", problem.robotMeshPath).center;
    if (problem.planar)
        center.z() = 0.0;
    robotMesh.transform(Eigen::Isometry3d(Eigen::Translation3d(-center)));

    Aabb positionBounds;
    positionBounds.min = Eigen::Vector3d(lower[0], lower[1], problem.planar ? 0.0 : lower[2]);
    positionBounds.max = Eigen::Vector3d(upper[0], upper[1], problem.planar ? 0.0 : upper[2]);
    RobotModelPtr robot;
    try
    {
        robot = makeRigidBodyModel(problem.name.empty() ? "robot" : problem.name, std::move(robotMesh), positionBounds,
                                   problem.planar);
    }
    catch (const ConfigurationError &e)
    {
        throw InputError(cfgPath, "[problem] robot", e.what());
    }
    problem.robot = robot;

    problem.timeLimit = config.number("benchmark.time_limit", 0.0);
    problem.memoryLimit = config.number("benchmark.mem_limit", 0.0);
    const double runs = config.number("benchmark.run_count", 0.0);
    if (runs < 0 || runs != std::floor(runs))
        throw InputError(cfgPath, "[benchmark] run_count", "expected a non-negative whole number");
    problem.runCount = static_cast<int>(runs);
    problem.objective = config.has("problem.objective") ? config.text("problem.objective") : "";
    problem.objectiveThreshold = config.number("problem.objective.threshold", 0.0);

    // "name=" opens a planner entry; "name.param=value" belongs to the latest entry of that name.
    for (const auto &[key, value] : config.plannerLines)
    {
        const std::size_t dot = key.find('.');
        const std::string planner = key.substr(0, dot);
        if (dot == std::string::npos)
        {
            problem.planners.push_back({planner, {}});
            continue;
        }
        auto entry = problem.planners.rbegin();
        while (entry != problem.planners.rend() && entry->first != planner)
            ++entry;
        if (entry == problem.planners.rend())
        {
            problem.planners.push_back({planner, {}});
            entry = problem.planners.rbegin();
        }
        entry->second.emplace_back(key.substr(dot + 1), value);
    }
    return problem;
}
}  // namespace rastercheck
