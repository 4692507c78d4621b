// rastercheck sweep: benchmark sweeps over many problems, planners and seeds, as local processes or a
// Slurm job array, every run a `rastercheck plan` run writing one OMPL benchmark log; `sweep merge`
// (SweepMerge.cpp) makes one database of them.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "SweepSpec.h"
#include "rastercheck/core/Error.h"

namespace rastercheck::cli
{
namespace
{
void makeFolder(const std::string &path)
{
    if (::mkdir(path.c_str(), 0755) != 0 && errno != EEXIST)
        throw InputError(path, "", "cannot create the folder");
}

void writeText(const std::string &path, const std::string &text)
{
    // Written beside and renamed: a reader (a task, the merge, a second `sweep run`) never sees half a file.
    const std::string partial = path + ".partial";
    {
        std::ofstream out(partial);
        out << text;
        if (!out.flush())
            throw InputError(partial, "", "cannot write");
    }
    if (std::rename(partial.c_str(), path.c_str()) != 0)
        throw InputError(path, "", "cannot write");
}

std::string absoluteFolder(const std::string &path)
{
    if (!pathExists(path))
        throw InputError(path, "", "no such folder");
    return canonicalPath(path);
}

/** \brief This program's own path, for the job scripts. */
std::string selfPath()
{
    std::vector<char> buffer(4096);
    const ssize_t length = ::readlink("/proc/self/exe", buffer.data(), buffer.size() - 1);
    if (length <= 0)
        throw ConfigurationError("cannot find the rastercheck program's own path (/proc/self/exe)");
    return std::string(buffer.data(), static_cast<std::size_t>(length));
}

/** \brief The CPUs this task may use: Slurm's SLURM_CPUS_PER_TASK when set (the allocation), else the
    spec's cpus_per_task; never the node's core count, which other tasks share. */
int taskCpus(const SweepPlan &plan)
{
    if (const char *slurm = std::getenv("SLURM_CPUS_PER_TASK"))
    {
        const int cpus = std::atoi(slurm);
        if (cpus > 0)
            return cpus;
    }
    return plan.cpusPerTask;
}

bool taskComplete(const std::string &dir, const SweepTask &task)
{
    for (const SweepUnit &unit : task.units)
        if (!pathExists(dir + "/" + unitLogPath(task, unit)))
            return false;
    return true;
}

/** \brief "0-3,5,7-9": Slurm's --array list of \a indices (sorted). */
std::string arrayList(const std::vector<std::size_t> &indices)
{
    std::string list;
    for (std::size_t i = 0; i < indices.size();)
    {
        std::size_t j = i;
        while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1)
            ++j;
        list += (list.empty() ? "" : ",") + std::to_string(indices[i]);
        if (j > i)
            list += "-" + std::to_string(indices[j]);
        i = j + 1;
    }
    return list;
}

std::string shellQuote(const std::string &text)
{
    std::string quoted = "'";
    for (char c : text)
        quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

/** \brief Runs `command` and returns its stdout (the job id of `sbatch --parsable`); throws on failure. */
std::string captureOutput(const std::vector<std::string> &arguments)
{
    std::string command;
    for (const std::string &argument : arguments)
        command += (command.empty() ? "" : " ") + shellQuote(argument);
    FILE *pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (!pipe)
        throw ConfigurationError("cannot run " + command);
    std::string output;
    char buffer[512];
    while (std::fgets(buffer, sizeof buffer, pipe))
        output += buffer;
    const int status = ::pclose(pipe);
    while (!output.empty() && (output.back() == '\n' || output.back() == ' '))
        output.pop_back();
    if (status != 0)
        throw ConfigurationError(command + " failed: " + output);
    return output;
}

// ---- sweep task ----------------------------------------------------------------------------------

/** \brief One unit in a child process (fork, then the plan command in it): OMPL seeds its random
    numbers once per process, so every (problem, seed) run gets a process of its own and the same seed
    gives the same run wherever the task runs. The log is written beside and renamed when the run
    finished, so a log that exists is a complete one. */
int runUnit(const std::string &dir, const SweepTask &task, const SweepUnit &unit, int cpus)
{
    const std::string log = dir + "/" + unitLogPath(task, unit);
    const std::string partial = log + ".partial";
    std::remove(partial.c_str());
    std::vector<std::string> arguments = unit.planArguments;
    arguments.insert(arguments.end(), {"--log", partial, "--threads", std::to_string(cpus)});
    std::cout << "sweep task: " << unit.name << ": rastercheck plan";
    for (const std::string &argument : arguments)
        std::cout << ' ' << shellQuote(argument);
    std::cout << std::endl;

    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid < 0)
        throw ConfigurationError(std::string("fork failed: ") + std::strerror(errno));
    if (pid == 0)
    {
        int status = 1;
        try
        {
            status = runPlanCommand(arguments);
        }
        catch (const std::exception &e)
        {
            std::cerr << "rastercheck: error: " << e.what() << '\n';
        }
        std::cout.flush();
        std::cerr.flush();
        std::_Exit(status);
    }
    const int status = waitForProcess(pid);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // 3: solution paths that collide (counted by the merge); the log is complete.
    const bool logged = (status == 0 || status == 3) && pathExists(partial);
    if (logged && std::rename(partial.c_str(), log.c_str()) != 0)
        throw InputError(log, "", "cannot write");
    std::ostringstream record;
    record << "status " << status << "\nwall_s " << wall << "\n";
    writeText(log + ".status", record.str());
    std::cout << "sweep task: " << unit.name << ": " << (logged ? "done" : "FAILED") << " (exit status " << status
              << ", " << wall << " s)" << std::endl;
    return logged ? 0 : 1;
}

int runTask(const std::string &dir, std::size_t index)
{
    const SweepPlan plan = loadSweepManifest(dir);
    if (index >= plan.tasks.size())
        throw ConfigurationError("task index " + std::to_string(index) + " is out of range: the sweep has " +
                                 std::to_string(plan.tasks.size()) + " task(s)");
    const SweepTask &task = plan.tasks[index];
    const int cpus = taskCpus(plan);
    makeFolder(dir + "/logs");
    makeFolder(dir + "/logs/" + task.name);
    int failed = 0;
    for (const SweepUnit &unit : task.units)
    {
        if (pathExists(dir + "/" + unitLogPath(task, unit)))
        {
            std::cout << "sweep task: " << unit.name << ": log present, skipped" << std::endl;
            continue;
        }
        failed += runUnit(dir, task, unit, cpus);
    }
    std::cout << "sweep task: " << task.name << ": " << task.units.size() - failed << "/" << task.units.size()
              << " unit(s) logged, " << cpus << " CPU(s)" << std::endl;
    return failed == 0 ? 0 : 1;
}

// ---- sweep run -----------------------------------------------------------------------------------

struct RunOptions
{
    std::string spec;
    std::string out;
    int local = 0;
    bool slurm = false;
    bool submit = false;
};

/** \brief The job scripts: an array with one element per pending task, and a merge that runs after
    the array whatever became of it (afterany), so missing tasks are named rather than waited for. */
void writeSlurmScripts(const std::string &dir, const SweepPlan &plan, const std::vector<std::size_t> &pending)
{
    makeFolder(dir + "/slurm");
    double limit = 0.0;
    std::size_t units = 0;
    for (std::size_t index : pending)
        limit = std::max(limit, plan.taskTimeLimit(plan.tasks[index]));
    for (const SweepTask &task : plan.tasks)
        units += task.units.size();
    const std::string self = selfPath();
    std::ostringstream array;
    array << "#!/bin/bash\n"
          << "# rastercheck sweep " << plan.name << ": one array element per task (" << pending.size() << " of "
          << plan.tasks.size() << " pending), written by `rastercheck sweep run --slurm`.\n"
          << "#SBATCH --job-name=" << plan.name << "\n"
          << "#SBATCH --array=" << arrayList(pending)
          << (plan.slurmMaxParallel > 0 ? "%" + std::to_string(plan.slurmMaxParallel) : "") << "\n"
          << "#SBATCH --ntasks=1\n"
          << "#SBATCH --cpus-per-task=" << plan.cpusPerTask << "\n"
          << "#SBATCH --time=" << static_cast<long>(std::ceil(limit / 60.0)) << "\n"
          << "#SBATCH --output=" << dir << "/out/task-%4a.out\n"
          << "#SBATCH --open-mode=append\n";  // a resumed task's output follows its first attempt's
    for (const std::string &option : plan.slurmOptions)
        array << "#SBATCH " << option << "\n";
    array << "# The checker's threads: the CPUs Slurm gave this task, not the node's cores.\n"
          << "export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-" << plan.cpusPerTask << "}\n"
          << "exec " << shellQuote(self) << " sweep task " << shellQuote(dir) << " --index \"$SLURM_ARRAY_TASK_ID\"\n";
    writeText(dir + "/slurm/array.sbatch", array.str());

    std::ostringstream merge;
    merge << "#!/bin/bash\n"
          << "# rastercheck sweep " << plan.name << ": the merge, after the array (submitted with "
          << "--dependency=afterany:ARRAY_JOB_ID).\n"
          << "#SBATCH --job-name=" << plan.name << "-merge\n"
          << "#SBATCH --ntasks=1\n"
          << "#SBATCH --cpus-per-task=1\n"
          << "#SBATCH --time=" << 10 + units / 600 << "\n"
          << "#SBATCH --output=" << dir << "/out/merge.out\n";
    for (const std::string &option : plan.slurmOptions)
        merge << "#SBATCH " << option << "\n";
    merge << "exec " << shellQuote(self) << " sweep merge " << shellQuote(dir) << "\n";
    writeText(dir + "/slurm/merge.sbatch", merge.str());
}

int runLocal(const std::string &dir, const SweepPlan &plan, const std::vector<std::size_t> &pending, int workers)
{
    const long cores = ::sysconf(_SC_NPROCESSORS_ONLN);
    if (static_cast<long>(workers) * plan.cpusPerTask > cores)
        throw ConfigurationError("--local " + std::to_string(workers) + " with " + std::to_string(plan.cpusPerTask) +
                                 " CPU(s) per task needs " + std::to_string(workers * plan.cpusPerTask) +
                                 " cores; this machine has " + std::to_string(cores) +
                                 " (more would only make the runs wait for each other)");
    // This very program, even when its file was rebuilt (replaced) during the sweep: every task of
    // one run uses the same code.
    const std::string self = "/proc/self/exe";
    const std::vector<std::string> environment = {"OMP_NUM_THREADS=" + std::to_string(plan.cpusPerTask)};
    std::map<pid_t, std::size_t> running;
    std::size_t next = 0;
    int failedTasks = 0;
    const auto start = std::chrono::steady_clock::now();
    while (next < pending.size() || !running.empty())
    {
        while (next < pending.size() && static_cast<int>(running.size()) < workers)
        {
            const std::size_t index = pending[next++];
            try
            {
                const pid_t pid = spawnProcess({self, "sweep", "task", dir, "--index", std::to_string(index)},
                                               dir + "/out/" + plan.tasks[index].name + ".out", environment);
                running[pid] = index;
            }
            catch (const Error &e)
            {
                // Named by the merge as missing; the tasks already running still finish.
                ++failedTasks;
                std::cerr << "rastercheck: error: " << plan.tasks[index].name << ": " << e.what() << '\n';
            }
        }
        if (running.empty())
            continue;
        int status = 0;
        const pid_t done = ::wait(&status);
        if (done < 0)
        {
            if (errno == EINTR)
                continue;
            throw ConfigurationError(std::string("wait failed: ") + std::strerror(errno));
        }
        const auto found = running.find(done);
        if (found == running.end())
            continue;
        const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        failedTasks += ok ? 0 : 1;
        std::cout << "sweep: " << plan.tasks[found->second].name << (ok ? " done" : " FAILED (see out/")
                  << (ok ? "" : plan.tasks[found->second].name + ".out)") << std::endl;
        running.erase(found);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "sweep: " << pending.size() - failedTasks << "/" << pending.size() << " task(s) completed in "
              << wall << " s with " << workers << " worker(s)" << std::endl;
    return mergeSweep(dir);
}

int runSweep(const RunOptions &options)
{
    if ((options.local > 0) == options.slurm)
        throw ConfigurationError("sweep run needs exactly one of --local N and --slurm");
    if (options.submit && !options.slurm)
        throw ConfigurationError("--submit goes with --slurm");
    // The spec is checked completely before anything is written or submitted.
    const SweepPlan plan = loadSweepSpec(options.spec);
    makeFolder(options.out);
    const std::string dir = absoluteFolder(options.out);
    makeFolder(dir + "/logs");
    makeFolder(dir + "/out");
    const std::string manifest = dir + "/sweep.json";
    const std::string json = sweepPlanToJson(plan);
    if (pathExists(manifest))
    {
        if (readTextFile(manifest) != json)
            throw ConfigurationError(dir + " holds another sweep (its sweep.json differs from what " + options.spec +
                                     " gives now): choose a new --out, or remove " + dir +
                                     " to start over; an unchanged spec resumes");
    }
    else
        writeText(manifest, json);

    std::vector<std::size_t> pending;
    std::size_t units = 0;
    for (std::size_t i = 0; i < plan.tasks.size(); ++i)
    {
        units += plan.tasks[i].units.size();
        if (!taskComplete(dir, plan.tasks[i]))
            pending.push_back(i);
    }
    std::cout << "sweep " << plan.name << ": " << plan.tasks.size() << " task(s), " << units
              << " run(s) of `rastercheck plan` (problem x seed), " << plan.planners.size() << " planner(s) x "
              << plan.runs << " run(s) each; " << pending.size() << " task(s) to run, "
              << plan.tasks.size() - pending.size() << " complete" << std::endl;

    if (options.local > 0)
        return runLocal(dir, plan, pending, options.local);

    if (pending.empty())
    {
        std::cout << "sweep: every task is complete; merge with: rastercheck sweep merge " << dir << std::endl;
        return 0;
    }
    writeSlurmScripts(dir, plan, pending);
    if (plan.tasks.size() > 1001)
        std::cerr << "rastercheck: warning: " << plan.tasks.size() << " tasks: array indices above 1000 exceed "
                  << "Slurm's default MaxArraySize (raise problems_per_task, or ask for a larger MaxArraySize)\n";
    if (!options.submit)
    {
        std::cout << "sweep: wrote " << dir << "/slurm/array.sbatch and merge.sbatch; submit with:\n"
                  << "  job=$(sbatch --parsable " << dir << "/slurm/array.sbatch)\n"
                  << "  sbatch --dependency=afterany:${job%%;*} " << dir << "/slurm/merge.sbatch\n";
        return 0;
    }
    std::string arrayJob = captureOutput({"sbatch", "--parsable", dir + "/slurm/array.sbatch"});
    arrayJob = arrayJob.substr(0, arrayJob.find(';'));  // "ID;cluster" on a multi-cluster setup
    std::string mergeJob = captureOutput(
        {"sbatch", "--parsable", "--dependency=afterany:" + arrayJob, dir + "/slurm/merge.sbatch"});
    mergeJob = mergeJob.substr(0, mergeJob.find(';'));
    writeText(dir + "/slurm/jobs", "array " + arrayJob + "\nmerge " + mergeJob + "\n");
    std::cout << "sweep: submitted array job " << arrayJob << " (" << pending.size() << " task(s)) and merge job "
              << mergeJob << " (after it); the merge writes " << dir << "/summary.md" << std::endl;
    return 0;
}
}  // namespace

void addSweepCommand(CLI::App &app)
{
    CLI::App *sweep = app.add_subcommand(
        "sweep", "Benchmark sweeps: many problems, planners and seeds as local processes or a Slurm job array, "
                 "merged into one OMPL benchmark database");
    sweep->require_subcommand(1);

    auto run = std::make_shared<RunOptions>();
    CLI::App *runCommand =
        sweep->add_subcommand("run", "Run a sweep spec (or write and submit its Slurm job array); resumes: only "
                                     "tasks whose logs are missing or incomplete run again");
    runCommand->add_option("spec", run->spec, "sweep spec (YAML; see examples/sweeps/)")->required();
    runCommand->add_option("--out", run->out, "sweep folder: manifest, logs, outputs, database, summary")->required();
    runCommand->add_option("--local", run->local, "run the tasks here, N at a time (then merge)")
        ->check(CLI::PositiveNumber);
    runCommand->add_flag("--slurm", run->slurm, "write a Slurm job array and a merge job (DIR/slurm/)");
    runCommand->add_flag("--submit", run->submit, "with --slurm: submit both with sbatch");
    runCommand->callback([run]() { throw CommandResult{runSweep(*run)}; });

    auto taskDir = std::make_shared<std::string>();
    auto taskIndex = std::make_shared<std::size_t>(0);
    CLI::App *taskCommand = sweep->add_subcommand(
        "task", "Run one task of a sweep (what the Slurm array and the local workers call)");
    taskCommand->add_option("dir", *taskDir, "sweep folder (sweep run --out)")->required();
    taskCommand->add_option("--index", *taskIndex, "task index (the Slurm array index)")->required();
    taskCommand->callback([taskDir, taskIndex]() { throw CommandResult{runTask(*taskDir, *taskIndex)}; });

    auto mergeDir = std::make_shared<std::string>();
    CLI::App *mergeCommand = sweep->add_subcommand(
        "merge", "Merge a sweep's logs into one database (ompl_benchmark_statistics), a Markdown summary and a "
                 "PNG; names every missing or failed run; exit status 2 when any is");
    mergeCommand->add_option("dir", *mergeDir, "sweep folder (sweep run --out)")->required();
    mergeCommand->callback([mergeDir]() { throw CommandResult{mergeSweep(absoluteFolder(*mergeDir))}; });
}
}  // namespace rastercheck::cli
