// `rastercheck plan` end to end: an OMPL.app problem written here and a MotionBenchMaker problem,
// the benchmark log read by ompl_benchmark_statistics, a colliding solution reported loudly, and
// errors.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/geometric/SimpleSetup.h>

#include "TestSupport.h"
#include "rastercheck/io/StatesCsv.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateValidityChecker.h"

using rastercheck::test::makeTempDir;
using rastercheck::test::objBox;
using rastercheck::test::writeFile;

namespace
{
using CliRun = rastercheck::test::CommandRun;
using rastercheck::test::runCli;
using rastercheck::test::runCommand;

bool contains(const std::string &text, const std::string &part)
{
    return text.find(part) != std::string::npos;
}

const char *kStatisticsTool = "/usr/bin/ompl_benchmark_statistics";

std::string cfg(const std::string &planners)
{
    return "[problem]\nname = boxes\nrobot = robot.obj\nworld = world.obj\n"
           "start.x = -1.5\nstart.y = 0\nstart.z = 0\nstart.theta = 0\nstart.axis.x = 1\nstart.axis.y = "
           "0\nstart.axis.z = 0\n"
           "goal.x = 1.5\ngoal.y = 0.2\ngoal.z = 0\ngoal.theta = 1.0\ngoal.axis.x = 0\ngoal.axis.y = 0\ngoal.axis.z = "
           "1\n"
           "volume.min.x = -2\nvolume.min.y = -2\nvolume.min.z = -2\nvolume.max.x = 2\nvolume.max.y = 2\nvolume.max.z "
           "= 2\n"
           "\n[benchmark]\ntime_limit = 2\nmem_limit = 1000\nrun_count = 2\n\n[planner]\n" +
           planners;
}

// Rows of the runs table of an sqlite database, by python3 (which ompl_benchmark_statistics needs
// anyway); -1 when it cannot be read.
int countRows(const std::string &database, const std::string &where)
{
    const CliRun run = runCommand("python3 -c \"import sqlite3; print(sqlite3.connect('" + database +
                                  "').execute('select count(*) from runs " + where + "').fetchone()[0])\"");
    if (run.status != 0)
        return -1;
    return std::atoi(run.output.c_str());
}

/** \brief An OMPL.app problem in \a folder: a 10 cm cube and a 2 cm wall across the whole volume (no
    path exists); returns the .cfg's path. */
std::string wallProblem(const std::string &folder)
{
    writeFile(folder + "/robot.obj", objBox("robot", -0.05, -0.05, -0.05, 0.05, 0.05, 0.05, 0));
    writeFile(folder + "/world.obj", objBox("wall", -0.01, -3, -3, 0.01, 3, 3, 0));
    return writeFile(folder + "/wall.cfg", cfg("rrtconnect=\n"));
}
}  // namespace

TEST(PlanCli, OmplAppProblemLogIsReadByOmplBenchmarkStatistics)
{
    const std::string folder = makeTempDir("plan_cli");
    writeFile(folder + "/robot.obj", objBox("robot", -0.1, -0.1, -0.1, 0.1, 0.1, 0.1, 0));
    // Obstacles beside the straight start-goal line: every planner's simplified path is clear of them
    // by a margin, so the exact re-check passes (paths that graze a corner between two checked states
    // are what the next test is about).
    writeFile(folder + "/world.obj",
              objBox("pillar", -0.3, 0.8, -2, 0.3, 1.4, 2, 0) + objBox("shelf", -0.8, -1.2, -0.5, 0.8, -0.7, 0.5, 8));
    writeFile(folder + "/boxes.cfg", cfg("rrtconnect=\nrrtconnect.range=1.5\nkpiece=\n"));
    const std::string log = folder + "/boxes.log";
    const CliRun run = runCli("plan " + folder + "/boxes.cfg --log " + log + " --seed 3");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "experiment boxes: 2 run(s) per planner, time limit 2 s")) << run.output;
    EXPECT_TRUE(contains(run.output, "rrtconnect         2/2         0")) << run.output;
    EXPECT_TRUE(contains(run.output, "kpiece")) << run.output;
    EXPECT_FALSE(contains(run.output, "COLLIDES")) << run.output;

    if (access(kStatisticsTool, X_OK) != 0)
        GTEST_SKIP() << kStatisticsTool << " is not installed (package ompl-demos)";
    const std::string database = folder + "/boxes.db";
    const CliRun statistics = runCommand(std::string(kStatisticsTool) + " " + log + " -d " + database);
    ASSERT_EQ(statistics.status, 0) << statistics.output;
    EXPECT_EQ(countRows(database, ""), 4);
    EXPECT_EQ(countRows(database, "where exact_recheck_collision_free = 1"), countRows(database, "where solved = 1"));
    EXPECT_GE(countRows(database, "where solved = 1"), 2);
}

TEST(PlanCli, PathOutWritesEveryRunsPathsWhichCheckAndCertifiedEdgesAccept)
{
    const std::string folder = makeTempDir("plan_cli_paths");
    writeFile(folder + "/robot.obj", objBox("robot", -0.1, -0.1, -0.1, 0.1, 0.1, 0.1, 0));
    writeFile(folder + "/world.obj",
              objBox("pillar", -0.3, -0.6, -2, 0.3, 0.6, 2, 0) + objBox("shelf", -0.8, -1.2, -0.5, 0.8, -0.7, 0.5, 8));
    const std::string problem = writeFile(folder + "/boxes.cfg", cfg("batchrrtconnect=\n"));
    const CliRun run = runCli("plan " + problem + " --seed 3 --path-out " + folder + "/paths");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "batchrrtconnect       2/2         0")) << run.output;

    // The index: both runs, raw and simplified, each re-checked collision-free.
    std::ifstream index(folder + "/paths/paths.csv");
    std::string line;
    std::getline(index, line);
    EXPECT_EQ(line, "planner,run,path,file,states,exact_recheck");
    std::vector<std::string> files;
    for (const char *expected : {"BatchRRTConnect,0,raw,BatchRRTConnect_run0_raw.csv,",
                                 "BatchRRTConnect,0,simplified,BatchRRTConnect_run0_simplified.csv,",
                                 "BatchRRTConnect,1,raw,BatchRRTConnect_run1_raw.csv,",
                                 "BatchRRTConnect,1,simplified,BatchRRTConnect_run1_simplified.csv,"})
    {
        ASSERT_TRUE(std::getline(index, line));
        EXPECT_EQ(line.rfind(expected, 0), 0u) << line;
        EXPECT_TRUE(contains(line, ",collision_free")) << line;
        std::istringstream cells(line);
        std::string cell;
        for (int c = 0; c < 4 && std::getline(cells, cell, ','); ++c)
        {
        }
        files.push_back(folder + "/paths/" + cell);
    }

    // Each file as `check --states` reads it: every state valid. Each motion between consecutive
    // states: accepted by certified edges (the default of makeSimpleSetup, as of plan).
    rastercheck::ProblemSource source;
    source.cfgPath = problem;
    const ompl::geometric::SimpleSetupPtr setup = rastercheck::ompl::makeSimpleSetup(rastercheck::loadProblem(source));
    const rastercheck::ompl::StateMapping &mapping = rastercheck::ompl::getStateValidityChecker(*setup)->getStateMapping();
    for (const std::string &file : files)
    {
        const CliRun checked = runCli("check " + problem + " --states " + file);
        EXPECT_EQ(checked.status, 0) << checked.output;
        EXPECT_TRUE(contains(checked.output, " invalid=0 ")) << file << ": " << checked.output;
        const rastercheck::StatesTable states = rastercheck::readStatesCsv(file, mapping.robot().coordinateNames);
        ASSERT_GE(states.rows, 2u) << file;
        ompl::base::ScopedState<> from(setup->getStateSpace()), to(setup->getStateSpace());
        for (std::size_t r = 0; r + 1 < states.rows; ++r)
        {
            mapping.fromConfiguration(states.values.data() + r * states.dof, from.get());
            mapping.fromConfiguration(states.values.data() + (r + 1) * states.dof, to.get());
            EXPECT_TRUE(setup->getSpaceInformation()->checkMotion(from.get(), to.get())) << file << " motion " << r;
        }
    }
}

TEST(PlanCli, CollidingSolutionIsReportedLoudly)
{
    // A thin wall across the whole volume: no path exists, but with coarse edge checks (a 0.69 m
    // resolution against a 2 cm wall) the planner steps through it. The exact re-check at 10x the
    // resolution must catch every such path.
    const std::string folder = makeTempDir("plan_cli_wall");
    const CliRun run = runCli("plan " + wallProblem(folder) + " --edges batched" +
                              " --runs 1 --time-limit 5 --segment-fraction 0.1 --seed 5 --log " + folder + "/wall.log");
    EXPECT_EQ(run.status, 3) << run.output;
    EXPECT_TRUE(contains(run.output, "rastercheck: ERROR: solution path of RRTConnect run 0 COLLIDES")) << run.output;
    EXPECT_TRUE(contains(run.output, "the planner's resolution stepped over it")) << run.output;
    EXPECT_TRUE(contains(run.output, "wall")) << run.output;
    EXPECT_TRUE(contains(run.output, "rrtconnect         0/1         1")) << run.output;
    EXPECT_TRUE(contains(run.output, "1 solution path(s) collide")) << run.output;
    EXPECT_TRUE(contains(run.output, "plan with --edges certified")) << run.output;
}

TEST(PlanCli, CertifiedEdgesDoNotStepThroughAThinWall)
{
    // The wall of the test above with the same coarse resolution: certified edges cannot cross it,
    // so there is no solution, and no colliding one.
    const CliRun run = runCli("plan " + wallProblem(makeTempDir("plan_cli_wall_certified")) +
                              " --runs 1 --time-limit 1 --segment-fraction 0.1 --seed 5 --edges certified");
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "certified edges")) << run.output;
    EXPECT_TRUE(contains(run.output, "rrtconnect         0/1         0")) << run.output;
    EXPECT_FALSE(contains(run.output, "COLLIDES")) << run.output;
    // They are the default; raster mode, which cannot certify, falls back to batched edges.
    const CliRun byDefault = runCli("plan " + wallProblem(makeTempDir("plan_cli_wall_default")) +
                                    " --runs 1 --time-limit 1 --segment-fraction 0.1 --seed 5");
    EXPECT_EQ(byDefault.status, 0) << byDefault.output;
    // The margin and first batch in use are logged: a tenth of the robot's size and one midpoint by
    // default, else --margin's and --rake-width's.
    EXPECT_TRUE(contains(byDefault.output, "certified edges (margin ")) << byDefault.output;
    const CliRun margin =
        runCli("plan " + wallProblem(makeTempDir("plan_cli_wall_margin")) +
               " --runs 1 --time-limit 1 --segment-fraction 0.1 --seed 5 --margin 0.25 --rake-width 8");
    EXPECT_EQ(margin.status, 0) << margin.output;
    EXPECT_TRUE(contains(margin.output, "certified edges (margin 0.25, first batch 8),")) << margin.output;
    EXPECT_TRUE(contains(byDefault.output, ", first batch 1),")) << byDefault.output;
    EXPECT_NE(runCli("plan " + wallProblem(makeTempDir("plan_cli_wall_rake0")) + " --rake-width 0").status, 0);
    const CliRun raster = runCli("plan " + wallProblem(makeTempDir("plan_cli_wall_raster")) +
                                 " --runs 1 --time-limit 1 --segment-fraction 0.1 --seed 5 --mode raster");
    EXPECT_TRUE(contains(raster.output, "batched edges,")) << raster.output;  // no margin: nothing certified
}

TEST(PlanCli, MotionBenchMakerProblem)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string panda = root + "/mbm/panda";
    const std::string problems = panda + "/problems/table_pick_panda";
    // (--time-limit is a limit, not a budget: a run stops when it connects; sanitizer builds are slow.)
    auto plan = [&](const std::string &options)
    {
        return runCli("plan --robot " + panda + "/panda.urdf --srdf " + panda + "/panda.srdf --scene " + problems +
                      "/scene0001.yaml --request " + problems +
                      "/request0001.yaml --planner rrtconnect --runs 2 --time-limit 60 --seed 1 " + options);
    };
    const CliRun run = plan("--mode exact");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "experiment scene0001_request0001")) << run.output;
    EXPECT_TRUE(contains(run.output, "rrtconnect         2/2         0")) << run.output;

    // Certified edges are the default (exact mode above chose them too).
    const CliRun certified = plan("");
    ASSERT_EQ(certified.status, 0) << certified.output;
    EXPECT_TRUE(contains(certified.output, "certified edges")) << certified.output;
    EXPECT_TRUE(contains(certified.output, "rrtconnect         2/2         0")) << certified.output;

    // BatchRRTConnect by name, beside RRT-Connect, with its batched shortcutting.
    const CliRun batch = plan("--planner batchrrtconnect --param batchrrtconnect.shortcut=1");
    ASSERT_EQ(batch.status, 0) << batch.output;
    EXPECT_TRUE(contains(batch.output, "batchrrtconnect       2/2         0")) << batch.output;
}

// OMPL's Benchmark simplifies every run's solution with one PathSimplifier per setup: unless it is
// reseeded per run, a run's simplified path and the states it checks depend on whether the planner
// before it in the same process solved (a sweep's Slurm and local runs then disagreed).
TEST(PlanCli, ARunDoesNotDependOnWhetherThePlannerBeforeItSolved)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string panda = root + "/mbm/panda";
    const std::string problems = panda + "/problems/bookshelf_tall_panda";
    const std::string folder = makeTempDir("plan_cli_reseeded");
    // RRTConnect's properties in an OMPL benchmark log: name -> value.
    auto rrtConnectRun = [](const std::string &log)
    {
        std::ifstream in(log);
        std::string line;
        while (std::getline(in, line) && line != "geometric_RRTConnect")
        {
        }
        while (std::getline(in, line) && line.find("properties for each run") == std::string::npos)
        {
        }
        std::vector<std::string> names;
        for (int k = std::atoi(line.c_str()); k > 0 && std::getline(in, line); --k)
            names.push_back(line);
        std::getline(in, line);  // the run count
        std::getline(in, line);
        std::map<std::string, std::string> run;
        std::istringstream values(line);
        for (const std::string &name : names)
            std::getline(values, run[name], ';');
        return run;
    };
    std::map<std::string, std::string> runs[2];
    const char *first[2] = {"batchrrtconnect.range=0.5", "batchrrtconnect.range=0.00001"};  // solves, cannot
    for (int k = 0; k < 2; ++k)
    {
        const std::string log = folder + "/run" + std::to_string(k) + ".log";
        const CliRun run = runCli("plan --robot " + panda + "/panda.urdf --srdf " + panda + "/panda.srdf --scene " +
                                  problems + "/scene0001.yaml --request " + problems +
                                  "/request0001.yaml --planner batchrrtconnect --planner rrtconnect --param " +
                                  first[k] + " --runs 1 --time-limit 2 --seed 1 --threads 1 --log " + log);
        ASSERT_EQ(run.status, 0) << run.output;
        EXPECT_TRUE(contains(run.output, k == 0 ? "batchrrtconnect       1/1" : "batchrrtconnect       0/1"))
            << run.output;
        runs[k] = rrtConnectRun(log);
    }
    for (const char *property : {"solution length REAL", "simplified solution length REAL", "states checked INTEGER"})
    {
        ASSERT_TRUE(runs[0].count(property)) << property;
        EXPECT_EQ(runs[0][property], runs[1][property]) << property;
    }
}

TEST(PlanCli, BadArgumentsAreErrors)
{
    const std::string folder = makeTempDir("plan_cli_bad");
    writeFile(folder + "/robot.obj", objBox("robot", -0.1, -0.1, -0.1, 0.1, 0.1, 0.1, 0));
    writeFile(folder + "/world.obj", objBox("pillar", -0.3, -0.3, -2, 0.3, 0.3, 2, 0));
    writeFile(folder + "/p.cfg", cfg("rrt=\n"));
    auto expectRefused = [](const std::string &arguments, int status, const std::string &message)
    {
        const CliRun run = runCli(arguments);
        EXPECT_EQ(run.status, status) << arguments << "\n" << run.output;
        EXPECT_TRUE(contains(run.output, message)) << arguments << "\n" << run.output;
    };
    expectRefused("plan " + folder + "/p.cfg --planner warpdrive", 1, "unknown planner 'warpdrive'");
    expectRefused("plan " + folder + "/p.cfg --param rrt.no_such_thing=3", 1, "no parameter 'no_such_thing'");
    expectRefused("plan --robot " + folder + "/none.urdf", 1, "--request");
    expectRefused("plan " + folder + "/p.cfg --edges certified --mode raster", 1, "raster mode can miss thin overlaps");
    // CLI11's own refusal of a value outside the choices.
    expectRefused("plan " + folder + "/p.cfg --edges sometimes", 105, "--edges: sometimes not in");
}
