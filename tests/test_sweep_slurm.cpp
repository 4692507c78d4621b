// `rastercheck sweep` under a real Slurm: tests/slurm/local-cluster.sh starts munged, slurmctld and
// slurmd on localhost (one node, files in a temporary folder); the Panda sweep of seven
// MotionBenchMaker problems, two planners and two seeds is submitted as a job array with a merge job
// after it, and every run is compared with the same sweep run locally. Skips only where the daemons
// cannot start (not root, Slurm not installed) or the shared data is absent. Label "slurm":
// scripts/sanitize.sh leaves it out (daemons and many processes, nothing of the library's own to check).
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "SweepTestSupport.h"
#include "TestSupport.h"

using rastercheck::test::makeTempDir;
using rastercheck::test::runCli;
using rastercheck::test::runCommand;
using rastercheck::test::sourcePath;
using rastercheck::test::writeFile;
using namespace rastercheck::test::sweep;

namespace
{
class LocalSlurm : public ::testing::Test
{
protected:
    void SetUp() override
    {
        cluster_ = makeTempDir("slurm_cluster");
        const auto started = runCommand(sourcePath("tests/slurm/local-cluster.sh") + " start " + cluster_);
        if (started.status == 77)
            GTEST_SKIP() << started.output;
        ASSERT_EQ(started.status, 0) << started.output;
        running_ = true;
        setenv("SLURM_CONF", (cluster_ + "/slurm.conf").c_str(), 1);
    }

    void TearDown() override
    {
        if (!running_)
            return;
        const auto stopped = runCommand(sourcePath("tests/slurm/local-cluster.sh") + " stop " + cluster_);
        EXPECT_EQ(stopped.status, 0) << stopped.output;
        unsetenv("SLURM_CONF");
    }

    std::string cluster_;
    bool running_ = false;
};

/** \brief Every run of a sweep database, keyed by (experiment, planner, run number): "solved length
    states time" (python3's sqlite3). */
std::map<std::string, std::string> runsOf(const std::string &database)
{
    const auto dump = runCommand(
        "/usr/bin/python3 -c \"import sqlite3\n"
        "c = sqlite3.connect('" +
        database +
        "')\n"
        "for e, p, n, s, l, k, t in c.execute('select r.experimentid, p.name, (select count(*) from runs q where "
        "q.experimentid = r.experimentid and q.plannerid = r.plannerid and q.id < r.id), r.solved, "
        "r.solution_length, r.states_checked, r.time from runs r join plannerConfigs p on p.id = r.plannerid'):\n"
        "    print(e, p, n, s, repr(l), k, t)\"");
    std::map<std::string, std::string> runs;
    std::istringstream lines(dump.output);
    std::string experiment, planner, number, rest;
    while (lines >> experiment >> planner >> number && std::getline(lines, rest))
        runs[experiment + " " + planner + " " + number] = rest;
    return runs;
}
}  // namespace

TEST_F(LocalSlurm, PandaSweepUnderSlurmMatchesLocalMode)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string folder = makeTempDir("sweep_slurm");
    const std::string panda = root + "/mbm/panda";
    const double timeLimit = 0.5;
    const std::string spec =
        writeFile(folder + "/spec.yaml", "name: panda-slurm-test\nproblems:\n  - robot: " + panda +
                                             "/panda.urdf\n    srdf: " + panda + "/panda.srdf\n    requests: " +
                                             panda +
                                             "/problems/*/request0001.yaml\n"
                                             "planners: [batchrrtconnect, rrtconnect]\nruns: 1\nseeds: [1, 2]\n"
                                             "time_limit: 0.5\nproblems_per_task: 2\n");

    // Slurm: the array (4 tasks of up to 2 problems x 2 seeds) and the merge after it.
    const auto submitted = runCli("sweep run " + spec + " --out " + folder + "/slurm --slurm --submit");
    ASSERT_EQ(submitted.status, 0) << submitted.output;
    EXPECT_NE(submitted.output.find("4 task(s), 14 run(s)"), std::string::npos) << submitted.output;
    EXPECT_NE(readFile(folder + "/slurm/slurm/array.sbatch").find("#SBATCH --array=0-3\n"), std::string::npos);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(240);
    while (access((folder + "/slurm/summary.md").c_str(), F_OK) != 0 && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ASSERT_EQ(access((folder + "/slurm/summary.md").c_str(), F_OK), 0)
        << "no merge after 240 s; squeue:\n"
        << runCommand("squeue").output << "\nmerge job:\n"
        << readFile(folder + "/slurm/out/merge.out") << "\ntask 0:\n"
        << readFile(folder + "/slurm/out/task-0000.out");
    const std::string summary = readFile(folder + "/slurm/summary.md");
    EXPECT_NE(summary.find("14/14 unit(s) logged, 0 failed, 0 missing; 28/28 run(s) in the database"),
              std::string::npos)
        << summary;
    // Each task used the one CPU Slurm gave it (SLURM_CPUS_PER_TASK), not the node's cores.
    EXPECT_NE(readFile(folder + "/slurm/out/task-0000.out").find("1 CPU(s)"), std::string::npos);
    EXPECT_NE(readFile(folder + "/slurm/out/task-0000.out").find("'--threads' '1'"), std::string::npos);

    // The same sweep locally, then run by run.
    const auto local = runCli("sweep run " + spec + " --out " + folder + "/local --local 2");
    ASSERT_EQ(local.status, 0) << local.output;
    const auto slurmRuns = runsOf(folder + "/slurm/sweep.db");
    const auto localRuns = runsOf(folder + "/local/sweep.db");
    ASSERT_EQ(slurmRuns.size(), 28u);
    ASSERT_EQ(localRuns.size(), 28u);
    int compared = 0;
    for (const auto &[key, slurmRun] : slurmRuns)
    {
        ASSERT_TRUE(localRuns.count(key)) << key;
        std::istringstream a(slurmRun), b(localRuns.at(key));
        std::string solvedA, lengthA, statesA, solvedB, lengthB, statesB;
        double timeA = 0, timeB = 0;
        a >> solvedA >> lengthA >> statesA >> timeA;
        b >> solvedB >> lengthB >> statesB >> timeB;
        // A run near its limit may stop one iteration earlier or later on a busier machine.
        if (timeA > 0.5 * timeLimit || timeB > 0.5 * timeLimit)
            continue;
        ++compared;
        EXPECT_EQ(solvedA, solvedB) << key;
        EXPECT_EQ(lengthA, lengthB) << key;
        EXPECT_EQ(statesA, statesB) << key;
    }
    EXPECT_GE(compared, 14) << "too few runs finished well inside the limit to compare";
}
