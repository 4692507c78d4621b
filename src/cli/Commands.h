#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/io/Problem.h"

namespace rastercheck::cli
{
/** \brief Thrown by a subcommand's callback to end the program with this exit status. */
struct CommandResult
{
    int status;
};

/** \brief The PROBLEM arguments every subcommand shares: an OMPL.app .cfg (positional), or
    --robot URDF [--srdf F] [--scene F] [--package-path P]... [--visual-fallback]. */
struct ProblemArguments
{
    std::string cfgPath;
    std::string urdfPath;
    std::string srdfPath;
    std::string scenePath;
    std::vector<std::string> packagePaths;
    bool visualFallback = false;

    void addTo(CLI::App &command);
    ProblemSource source() const;
};

/** \brief The checking options several subcommands share, each declared here once: --mode and
    --padding (check, plan, render, view), --backend and --threads (check, plan). */
struct CheckingArguments
{
    std::string mode = "safe";
    double padding = 0.0;
    std::string backend = "auto";
    int threads = 0;
    std::size_t deviceBatch = 0;  ///< CheckerOptions::minDeviceBatch (0: automatic)

    /** \brief Declares --mode (\a what: what the mode decides in this command) and --padding. */
    void addModeAndPadding(CLI::App &command, const std::string &what);
    /** \brief Declares --backend, --device-batch and --threads (\a threads: what the threads run). */
    void addBackendAndThreads(CLI::App &command, const std::string &threads);
    /** \brief A request of this mode and padding. */
    CollisionRequest request() const;
    /** \brief Checker options of this backend, device batch and thread count. */
    CheckerOptions checker() const;
};

/** \brief `rastercheck info <urdf | problem.cfg | scene.yaml | request.yaml>`: what the loaders
    make of a file (robot, joints, coordinates, components, allowed pairs; scene objects). */
void addInfoCommand(CLI::App &app);
/** \brief `rastercheck check PROBLEM --states IN.csv ...`: one verdict per state. */
void addCheckCommand(CLI::App &app);
/** \brief `rastercheck plan PROBLEM [--request R] [--planner NAME]... [--runs N] [--time-limit S] [--log F]
    ...`: OMPL planners through ompl::tools::Benchmark; solution paths re-checked by the exact oracle. */
void addPlanCommand(CLI::App &app);
/** \brief Runs `rastercheck plan` with \a arguments (what follows "plan" on its command line) and
    returns its exit status: the sweep's runs go through the very code and checks of the command. Throws
    what the command throws (CLI::ParseError for bad arguments). */
int runPlanCommand(const std::vector<std::string> &arguments);
/** \brief `rastercheck render PROBLEM (--states IN.csv | --request R.yaml) --out-dir DIR`: top and side
    views of the scene and the path, and the raster image of the first colliding state. */
void addRenderCommand(CLI::App &app);
/** \brief `rastercheck view PROBLEM [--path STATES.csv | --request R.yaml] [--port N] [--host H]`: a
    local HTTP server with a live 3D viewer of the problem (src/view). */
void addViewCommand(CLI::App &app);
/** \brief `rastercheck sweep run SPEC --out DIR (--local N | --slurm [--submit])`, `sweep task DIR
    --index I` and `sweep merge DIR`: benchmark sweeps as local processes or a Slurm job array. */
void addSweepCommand(CLI::App &app);
}  // namespace rastercheck::cli
