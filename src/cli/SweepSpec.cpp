#include "SweepSpec.h"

#include <fcntl.h>
#include <glob.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/util/Console.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/ompl/Planners.h"

extern char **environ;

namespace rastercheck::cli
{
namespace
{
std::string absolute(const std::string &path, const std::string &base)
{
    if (!path.empty() && path[0] == '/')
        return path;
    return base + "/" + path;
}

std::string currentFolder()
{
    std::vector<char> buffer(4096);
    if (!::getcwd(buffer.data(), buffer.size()))
        throw ConfigurationError("cannot read the current folder");
    return buffer.data();
}

/** \brief The files \a pattern (a glob, relative to \a base) matches, sorted; an error naming the
    pattern when it matches none: a sweep over nothing is a mistake, never an empty result. */
std::vector<std::string> expandGlob(const std::string &spec, const std::string &key, const std::string &pattern,
                                    const std::string &base)
{
    glob_t found{};
    const int status = ::glob(absolute(pattern, base).c_str(), 0, nullptr, &found);
    std::vector<std::string> paths;
    if (status == 0)
        for (std::size_t i = 0; i < found.gl_pathc; ++i)
            if (isFile(found.gl_pathv[i]))
                paths.push_back(canonicalPath(found.gl_pathv[i]));
    ::globfree(&found);
    if (paths.empty())
        throw InputError(spec, key, "'" + pattern + "' matches no file (relative to " + base + ")");
    std::sort(paths.begin(), paths.end());
    return paths;
}

std::string requireFile(const std::string &spec, const std::string &key, const std::string &path,
                        const std::string &base)
{
    const std::string full = absolute(path, base);
    if (!isFile(full))
        throw InputError(spec, key, "no such file '" + full + "'");
    return canonicalPath(full);
}

/** \brief Throws naming the first key of \a node that is not in \a known (a typo would otherwise be
    a silently ignored setting). */
void checkKeys(const std::string &spec, const std::string &where, const YAML::Node &node,
               const std::set<std::string> &known)
{
    if (!node.IsMap())
        throw InputError(spec, where, "expected a mapping");
    for (const auto &entry : node)
    {
        const std::string key = entry.first.as<std::string>();
        if (!known.count(key))
        {
            std::string list;
            for (const std::string &name : known)
                list += (list.empty() ? "" : ", ") + name;
            throw InputError(spec, where.empty() ? key : where + "." + key, "unknown key (known: " + list + ")");
        }
    }
}

template <typename T>
T scalar(const std::string &spec, const YAML::Node &node, const std::string &key, const T &fallback)
{
    const YAML::Node value = node[key];
    if (!value)
        return fallback;
    try
    {
        return value.as<T>();
    }
    catch (const YAML::Exception &)
    {
        throw InputError(spec, key, "'" + YAML::Dump(value) + "' is not a valid value");
    }
}

/** \brief The planners' names and parameters, each tried on a throwaway space: an unknown planner or
    parameter, or a value a planner rejects, is an error now rather than in every task. */
void checkPlanners(const std::string &spec,
                   const std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> &planners)
{
    auto space = std::make_shared<::ompl::base::RealVectorStateSpace>(2);
    space->setBounds(0.0, 1.0);
    auto si = std::make_shared<::ompl::base::SpaceInformation>(space);
    // Quiet: OMPL reports every parameter it sets, and the runs will report them again.
    const ::ompl::msg::LogLevel level = ::ompl::msg::getLogLevel();
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_WARN);
    struct RestoreLevel
    {
        ::ompl::msg::LogLevel level;
        ~RestoreLevel() { ::ompl::msg::setLogLevel(level); }
    } restore{level};
    for (const auto &[name, parameters] : planners)
    {
        try
        {
            ::ompl::base::PlannerPtr planner = ompl::allocatePlanner(name, si);
            ompl::setPlannerParameters(*planner, parameters);
        }
        catch (const Error &e)
        {
            throw InputError(spec, "planners", e.what());
        }
    }
}

/** \brief A name that is safe in a file name: what is not a letter, digit, '-', '_' or '.' becomes '-'. */
std::string fileSafe(std::string text)
{
    for (char &c : text)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
            c = '-';
    return text;
}

struct ProblemEntry
{
    std::string robot;  ///< summary group
    std::string name;   ///< FAMILY/REQUEST or the .cfg's stem
    std::vector<std::string> arguments;
};
}  // namespace

std::string canonicalPath(const std::string &path)
{
    char *resolved = ::realpath(path.c_str(), nullptr);
    if (!resolved)
        return path;
    std::string result = resolved;
    std::free(resolved);
    return result;
}

std::string readTextFile(const std::string &path)
{
    std::ifstream in(path);
    if (!in)
        throw InputError(path, "", "cannot read");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

bool pathExists(const std::string &path)
{
    struct stat info;
    return ::stat(path.c_str(), &info) == 0;
}

/** \brief Starts \a arguments[0] (searched on PATH) with stdout and stderr appended to \a outPath
    (inherited when empty) and \a extraEnvironment added; returns its pid. */
pid_t spawnProcess(const std::vector<std::string> &arguments, const std::string &outPath,
            const std::vector<std::string> &extraEnvironment)
{
    std::vector<char *> argv;
    for (const std::string &argument : arguments)
        argv.push_back(const_cast<char *>(argument.c_str()));
    argv.push_back(nullptr);
    std::vector<std::string> environmentText(extraEnvironment);
    for (char **entry = environ; *entry; ++entry)
    {
        const std::string text = *entry;
        bool replaced = false;
        for (const std::string &extra : extraEnvironment)
            replaced = replaced || text.compare(0, extra.find('=') + 1, extra, 0, extra.find('=') + 1) == 0;
        if (!replaced)
            environmentText.push_back(text);
    }
    std::vector<char *> envp;
    for (const std::string &text : environmentText)
        envp.push_back(const_cast<char *>(text.c_str()));
    envp.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!outPath.empty())
    {
        posix_spawn_file_actions_addopen(&actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
        posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    pid_t pid = 0;
    const int status = ::posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (status != 0)
        throw ConfigurationError("cannot start " + arguments[0] + ": " + std::strerror(status));
    return pid;
}

/** \brief Waits for \a pid; its exit status, or 128 + the signal that ended it. */
int waitForProcess(pid_t pid)
{
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
        if (errno != EINTR)
            return 127;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

double SweepPlan::taskTimeLimit(const SweepTask &task) const
{
    const double runsPerUnit = static_cast<double>(planners.size()) * runs;
    return static_cast<double>(task.units.size()) * (2.0 * runsPerUnit * timeLimit + 60.0);
}

std::string unitLogPath(const SweepTask &task, const SweepUnit &unit)
{
    return "logs/" + task.name + "/" + unit.name + ".log";
}

SweepPlan loadSweepSpec(const std::string &path)
{
    YAML::Node root;
    try
    {
        root = YAML::LoadFile(path);
    }
    catch (const YAML::BadFile &)
    {
        throw InputError(path, "", "cannot read the sweep spec");
    }
    catch (const YAML::Exception &e)
    {
        throw InputError(path, "", std::string("not valid YAML: ") + e.what());
    }
    checkKeys(path, "", root,
              {"name", "problems", "planners", "runs", "seeds", "time_limit", "memory_limit", "mode", "edges",
               "backend", "padding", "problems_per_task", "cpus_per_task", "slurm"});
    const std::string specPath = absolute(path, currentFolder());
    const std::string base = folderOf(specPath);

    SweepPlan plan;
    plan.specPath = specPath;
    plan.name = scalar<std::string>(path, root, "name", stemOf(path));
    plan.runs = scalar<int>(path, root, "runs", 1);
    plan.timeLimit = scalar<double>(path, root, "time_limit", 0.0);
    const double memoryLimit = scalar<double>(path, root, "memory_limit", 4096.0);
    const std::string mode = scalar<std::string>(path, root, "mode", "safe");
    const std::string edges = scalar<std::string>(path, root, "edges", "auto");
    // One CPU per task: the CPU backend by default, so that tasks sharing a node do not share its GPU.
    const std::string backend = scalar<std::string>(path, root, "backend", "cpu");
    const double padding = scalar<double>(path, root, "padding", 0.0);
    const int perTask = scalar<int>(path, root, "problems_per_task", 1);
    plan.cpusPerTask = scalar<int>(path, root, "cpus_per_task", 1);

    if (plan.runs < 1)
        throw InputError(path, "runs", "must be at least 1, got " + std::to_string(plan.runs));
    if (!(plan.timeLimit > 0.0) || !std::isfinite(plan.timeLimit))
        throw InputError(path, "time_limit", "needs a positive number of seconds per run");
    if (!(memoryLimit > 0.0))
        throw InputError(path, "memory_limit", "needs a positive number of MB");
    if (!(padding >= 0.0))
        throw InputError(path, "padding", "must not be negative");
    if (perTask < 1)
        throw InputError(path, "problems_per_task", "must be at least 1");
    if (plan.cpusPerTask < 1)
        throw InputError(path, "cpus_per_task", "must be at least 1");
    const std::set<std::string> modes = {"safe", "raster", "exact", "conservative"};
    if (!modes.count(mode))
        throw InputError(path, "mode", "'" + mode + "' is not one of safe, raster, exact, conservative");
    const std::set<std::string> edgeModes = {"auto", "batched", "discrete", "certified"};
    if (!edgeModes.count(edges))
        throw InputError(path, "edges", "'" + edges + "' is not one of auto, batched, discrete, certified");
    if (backend != "cpu" && backend != "cuda" && backend != "auto")
        throw InputError(path, "backend", "'" + backend + "' is not one of cpu, cuda, auto");

    std::vector<long long> seeds;
    if (root["seeds"])
    {
        if (!root["seeds"].IsSequence() || root["seeds"].size() == 0)
            throw InputError(path, "seeds", "expected a non-empty list of seeds");
        for (const YAML::Node &seed : root["seeds"])
        {
            long long value = -1;
            try
            {
                value = seed.as<long long>();
            }
            catch (const YAML::Exception &)
            {
            }
            if (value < 1)  // OMPL takes 0 as "no seed"
                throw InputError(path, "seeds", "'" + YAML::Dump(seed) + "' is not a positive integer");
            seeds.push_back(value);
        }
    }
    else
        seeds.push_back(1);

    // Planners: a name, or {name: NAME, params: {PARAM: VALUE}}.
    std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> planners;
    if (!root["planners"] || !root["planners"].IsSequence() || root["planners"].size() == 0)
        throw InputError(path, "planners", "expected a non-empty list of planners");
    for (const YAML::Node &entry : root["planners"])
    {
        if (entry.IsScalar())
        {
            planners.push_back({entry.as<std::string>(), {}});
            continue;
        }
        checkKeys(path, "planners", entry, {"name", "params"});
        if (!entry["name"])
            throw InputError(path, "planners", "a planner entry needs a name");
        planners.push_back({entry["name"].as<std::string>(), {}});
        if (entry["params"])
        {
            if (!entry["params"].IsMap())
                throw InputError(path, "planners." + planners.back().first + ".params", "expected a mapping");
            for (const auto &parameter : entry["params"])
                planners.back().second.emplace_back(parameter.first.as<std::string>(),
                                                    parameter.second.as<std::string>());
        }
    }
    std::set<std::string> plannerNames;
    for (const auto &planner : planners)
        if (!plannerNames.insert(planner.first).second)
            throw InputError(path, "planners", "'" + planner.first + "' is listed twice (plan runs each name once)");
    checkPlanners(path, planners);

    std::vector<std::string> common;
    for (const auto &[name, parameters] : planners)
    {
        plan.planners.push_back(name);
        common.insert(common.end(), {"--planner", name});
        for (const auto &[key, value] : parameters)
            common.insert(common.end(), {"--param", name + "." + key + "=" + value});
    }
    auto number = [](double value)
    {
        char text[64];
        std::snprintf(text, sizeof text, "%.17g", value);
        return std::string(text);
    };
    common.insert(common.end(), {"--runs", std::to_string(plan.runs), "--time-limit", number(plan.timeLimit),
                                 "--memory-limit", number(memoryLimit), "--mode", mode, "--edges", edges,
                                 "--backend", backend, "--padding", number(padding)});

    // Problems: MoveIt requests (with the robot, and the scene beside each request) or OMPL.app .cfg files.
    std::vector<ProblemEntry> problems;
    if (!root["problems"] || !root["problems"].IsSequence() || root["problems"].size() == 0)
        throw InputError(path, "problems", "expected a non-empty list of problem groups");
    for (const YAML::Node &group : root["problems"])
    {
        checkKeys(path, "problems", group, {"robot", "srdf", "requests", "package_paths", "label", "cfg"});
        if (group["cfg"])
        {
            if (group["robot"] || group["requests"] || group["srdf"])
                throw InputError(path, "problems.cfg",
                                 "an OMPL.app group names .cfg files only (robot, srdf and requests are MoveIt's)");
            const std::string label = scalar<std::string>(path, group, "label", "omplapp");
            for (const std::string &cfg : expandGlob(path, "problems.cfg", group["cfg"].as<std::string>(), base))
                problems.push_back({label, stemOf(cfg), {cfg}});
            continue;
        }
        if (!group["robot"] || !group["requests"])
            throw InputError(path, "problems", "a group needs either cfg: GLOB or robot: URDF with requests: GLOB");
        const std::string robot = requireFile(path, "problems.robot", group["robot"].as<std::string>(), base);
        std::vector<std::string> robotArguments = {"--robot", robot};
        if (group["srdf"])
            robotArguments.insert(robotArguments.end(),
                                  {"--srdf", requireFile(path, "problems.srdf", group["srdf"].as<std::string>(), base)});
        if (group["package_paths"])
            for (const YAML::Node &folder : group["package_paths"])
                robotArguments.insert(robotArguments.end(),
                                      {"--package-path", canonicalPath(absolute(folder.as<std::string>(), base))});
        const std::string label = scalar<std::string>(path, group, "label", stemOf(robot));
        for (const std::string &request :
             expandGlob(path, "problems.requests", group["requests"].as<std::string>(), base))
        {
            // MotionBenchMaker's layout: sceneNNNN.yaml beside requestNNNN.yaml.
            std::string sceneName = nameOf(request);
            const std::size_t at = sceneName.find("request");
            if (at == std::string::npos)
                throw InputError(path, "problems.requests",
                                 "'" + request + "': a request file's name contains 'request' (requestNNNN.yaml), "
                                 "whose scene is sceneNNNN.yaml beside it");
            sceneName.replace(at, 7, "scene");
            const std::string scene = folderOf(request) + "/" + sceneName;
            if (!isFile(scene))
                throw InputError(path, "problems.requests", "'" + request + "' has no scene beside it (" + scene + ")");
            ProblemEntry problem{label, nameOf(folderOf(request)) + "/" + stemOf(request), robotArguments};
            problem.arguments.insert(problem.arguments.end(), {"--scene", scene, "--request", request});
            problems.push_back(std::move(problem));
        }
    }

    std::set<std::string> unitNames;
    for (std::size_t first = 0; first < problems.size(); first += static_cast<std::size_t>(perTask))
    {
        SweepTask task;
        char name[32];
        std::snprintf(name, sizeof name, "task-%04zu", plan.tasks.size());
        task.name = name;
        const std::size_t last = std::min(problems.size(), first + static_cast<std::size_t>(perTask));
        for (std::size_t p = first; p < last; ++p)
            for (long long seed : seeds)
            {
                SweepUnit unit;
                unit.robot = problems[p].robot;
                unit.problem = problems[p].name;
                unit.seed = seed;
                unit.name = fileSafe(unit.robot + "." + unit.problem + ".seed" + std::to_string(seed));
                if (!unitNames.insert(unit.name).second)
                    throw InputError(path, "problems",
                                     "problem '" + unit.problem + "' of " + unit.robot +
                                         " is listed twice (or two groups share a label)");
                unit.planArguments = problems[p].arguments;
                unit.planArguments.insert(unit.planArguments.end(), common.begin(), common.end());
                unit.planArguments.insert(unit.planArguments.end(), {"--seed", std::to_string(seed)});
                task.units.push_back(std::move(unit));
            }
        plan.tasks.push_back(std::move(task));
    }

    if (const YAML::Node slurm = root["slurm"])
    {
        checkKeys(path, "slurm", slurm, {"max_parallel", "options"});
        plan.slurmMaxParallel = scalar<int>(path, slurm, "max_parallel", 0);
        if (plan.slurmMaxParallel < 0)
            throw InputError(path, "slurm.max_parallel", "must not be negative");
        if (slurm["options"])
            for (const YAML::Node &option : slurm["options"])
            {
                const std::string text = option.as<std::string>();
                if (text.rfind("--", 0) != 0 || text.find('\n') != std::string::npos)
                    throw InputError(path, "slurm.options", "'" + text + "' is not one sbatch option (--name=value)");
                plan.slurmOptions.push_back(text);
            }
    }
    return plan;
}

std::string sweepPlanToJson(const SweepPlan &plan)
{
    nlohmann::json json;
    json["name"] = plan.name;
    json["spec"] = plan.specPath;
    json["planners"] = plan.planners;
    json["runs"] = plan.runs;
    json["time_limit"] = plan.timeLimit;
    json["cpus_per_task"] = plan.cpusPerTask;
    json["slurm_max_parallel"] = plan.slurmMaxParallel;
    json["slurm_options"] = plan.slurmOptions;
    json["tasks"] = nlohmann::json::array();
    for (const SweepTask &task : plan.tasks)
    {
        nlohmann::json units = nlohmann::json::array();
        for (const SweepUnit &unit : task.units)
            units.push_back({{"name", unit.name},
                             {"robot", unit.robot},
                             {"problem", unit.problem},
                             {"seed", unit.seed},
                             {"plan", unit.planArguments}});
        json["tasks"].push_back({{"name", task.name}, {"units", units}});
    }
    return json.dump(1) + "\n";
}

SweepPlan loadSweepManifest(const std::string &dir)
{
    const std::string path = dir + "/sweep.json";
    if (!pathExists(path))
        throw InputError(path, "", "no sweep manifest: is " + dir + " the --out folder of `rastercheck sweep run`?");
    return sweepPlanFromJson(readTextFile(path), path);
}

SweepPlan sweepPlanFromJson(const std::string &text, const std::string &path)
{
    try
    {
        const nlohmann::json json = nlohmann::json::parse(text);
        SweepPlan plan;
        plan.name = json.at("name").get<std::string>();
        plan.specPath = json.at("spec").get<std::string>();
        plan.planners = json.at("planners").get<std::vector<std::string>>();
        plan.runs = json.at("runs").get<int>();
        plan.timeLimit = json.at("time_limit").get<double>();
        plan.cpusPerTask = json.at("cpus_per_task").get<int>();
        plan.slurmMaxParallel = json.at("slurm_max_parallel").get<int>();
        plan.slurmOptions = json.at("slurm_options").get<std::vector<std::string>>();
        for (const nlohmann::json &taskJson : json.at("tasks"))
        {
            SweepTask task;
            task.name = taskJson.at("name").get<std::string>();
            for (const nlohmann::json &unitJson : taskJson.at("units"))
            {
                SweepUnit unit;
                unit.name = unitJson.at("name").get<std::string>();
                unit.robot = unitJson.at("robot").get<std::string>();
                unit.problem = unitJson.at("problem").get<std::string>();
                unit.seed = unitJson.at("seed").get<long long>();
                unit.planArguments = unitJson.at("plan").get<std::vector<std::string>>();
                task.units.push_back(std::move(unit));
            }
            plan.tasks.push_back(std::move(task));
        }
        return plan;
    }
    catch (const nlohmann::json::exception &e)
    {
        throw InputError(path, "", std::string("not a sweep manifest: ") + e.what());
    }
}
}  // namespace rastercheck::cli
