#pragma once
// rastercheck sweep: the sweep spec (YAML) and what it expands to, the tasks of a sweep. A task is what
// one Slurm array task or one local worker runs: a shard of the problems, each with every seed, each
// (problem, seed) pair one `rastercheck plan` run (a unit) writing one OMPL benchmark log.

#include <sys/types.h>

#include <string>
#include <vector>

namespace rastercheck::cli
{
/** \brief One (problem, seed) pair of a task: one `rastercheck plan` run and its log. */
struct SweepUnit
{
    std::string name;                       ///< unique in the sweep; the log is logs/TASK/NAME.log
    std::string robot;                      ///< the summary's group: the URDF's stem, or "omplapp"
    std::string problem;                    ///< the problem's name (FAMILY/REQUEST, or the .cfg's stem)
    long long seed = 0;                     ///< OMPL's random seed of this run
    std::vector<std::string> planArguments; ///< what follows `rastercheck plan` (without --log, --threads)
};

/** \brief One task of the sweep: one Slurm array index, or one local worker's job. */
struct SweepTask
{
    std::string name;  ///< task-NNNN, NNNN its index (the Slurm array index)
    std::vector<SweepUnit> units;
};

/** \brief A sweep spec, checked and expanded: everything a task or the merge needs, so that neither
    reads the spec again (the manifest DIR/sweep.json holds it). */
struct SweepPlan
{
    std::string name;
    std::string specPath;                 ///< absolute
    std::vector<std::string> planners;    ///< labels, in the spec's order
    int runs = 1;                         ///< runs per planner, problem and seed
    double timeLimit = 0.0;               ///< seconds per run
    int cpusPerTask = 1;                  ///< CPUs one task is given (and its checker uses)
    int slurmMaxParallel = 0;             ///< the %M of --array (0: no limit)
    std::vector<std::string> slurmOptions;  ///< extra #SBATCH lines (--partition=..., --account=...)
    std::vector<SweepTask> tasks;

    /** \brief Wall-clock limit of one task in seconds: every run at its time limit, twice over (path
        simplification and the exact re-check come on top of planning), and a minute per unit for
        process start and problem load. */
    double taskTimeLimit(const SweepTask &task) const;
};

/** \brief Reads and checks a sweep spec: every key known, every glob matching, every file present,
    every planner and parameter known, every number in range. Throws ConfigurationError (or InputError
    naming the file) before anything runs. Relative paths are relative to the spec's folder. */
SweepPlan loadSweepSpec(const std::string &path);

/** \brief The plan as JSON text (the manifest DIR/sweep.json), and back. */
std::string sweepPlanToJson(const SweepPlan &plan);
SweepPlan sweepPlanFromJson(const std::string &text, const std::string &path);

/** \brief The manifest DIR/sweep.json that `sweep run` wrote; an error naming \a dir when there is none. */
SweepPlan loadSweepManifest(const std::string &dir);

/** \brief `rastercheck sweep merge DIR` (SweepMerge.cpp): the logs into DIR/sweep.db through OMPL's
    ompl_benchmark_statistics, DIR/summary.md and DIR/summary.png; every missing or failed run named
    and counted. Returns 0 when every run has its log, 2 when some have none. */
int mergeSweep(const std::string &dir);

/** \brief \a path without "." and ".." steps or links (\a path itself when it does not exist): the
    runs' commands stay readable, and the mesh loader resolves package:// paths from a URDF's folder,
    which ".." steps confuse (a Panda URDF reached through ".." fails to read its OBJ meshes). */
std::string canonicalPath(const std::string &path);

/** \brief The whole of a text file; InputError naming it when it cannot be read. */
std::string readTextFile(const std::string &path);

/** \brief Whether \a path exists (a file or a folder). */
bool pathExists(const std::string &path);

/** \brief Starts \a arguments[0] (searched on PATH) with stdout and stderr appended to \a outPath
    (inherited when empty) and \a extraEnvironment (NAME=VALUE) added; returns its pid. Throws
    ConfigurationError when it cannot start. */
pid_t spawnProcess(const std::vector<std::string> &arguments, const std::string &outPath,
                   const std::vector<std::string> &extraEnvironment = {});

/** \brief Waits for \a pid; its exit status, or 128 + the signal that ended it. */
int waitForProcess(pid_t pid);

/** \brief Where unit \a unit of task \a task writes its log, relative to the sweep folder. */
std::string unitLogPath(const SweepTask &task, const SweepUnit &unit);
}  // namespace rastercheck::cli
