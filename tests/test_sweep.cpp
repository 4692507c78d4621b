// `rastercheck sweep`: specs rejected before anything runs, a local sweep that resumes and names what
// is missing or failed, and (test_sweep_slurm.cpp) the same sweep under a real one-node Slurm.
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "SweepTestSupport.h"
#include "TestSupport.h"

using rastercheck::test::makeTempDir;
using rastercheck::test::runCli;
using rastercheck::test::writeFile;
using namespace rastercheck::test::sweep;

namespace
{
/** \brief A spec over the OMPL.app box problems of \a folder (writeBoxProblems), RRT-Connect, 1 run
    of at most 2 s, the given seeds; \a extra appended as written. */
std::string boxSpec(const std::string &folder, const std::string &seeds, const std::string &extra = "")
{
    return writeFile(folder + "/spec.yaml", "name: boxes\nproblems:\n  - cfg: problems/*.cfg\nplanners:\n  - rrtconnect\n"
                                            "runs: 1\nseeds: " +
                                                seeds + "\ntime_limit: 2\n" + extra);
}

/** \brief Runs `sweep run` on a spec of \a text (in a folder with the box problems) and expects it to
    fail with \a message before writing anything. */
void expectRejected(const std::string &text, const std::string &message)
{
    const std::string folder = makeTempDir("sweep_bad");
    writeBoxProblems(folder + "/problems", 1);
    writeFile(folder + "/spec.yaml", text);
    const auto run = runCli("sweep run " + folder + "/spec.yaml --out " + folder + "/out --local 1");
    EXPECT_EQ(run.status, 1) << text << "\n" << run.output;
    EXPECT_NE(run.output.find(message), std::string::npos) << "expected '" << message << "' in:\n" << run.output;
    EXPECT_NE(access((folder + "/out").c_str(), F_OK), 0) << "a rejected spec must not create its --out folder";
}
}  // namespace

TEST(SweepCli, BadSpecsAreRejectedBeforeAnythingRuns)
{
    const std::string good = "problems:\n  - cfg: problems/*.cfg\nplanners: [rrtconnect]\ntime_limit: 1\n";
    expectRejected("problems:\n  - cfg: nothing/*.cfg\nplanners: [rrtconnect]\ntime_limit: 1\n",
                   "'nothing/*.cfg' matches no file");
    expectRejected("problems:\n  - cfg: problems/*.cfg\nplanners: [rrtconect]\ntime_limit: 1\n", "rrtconect");
    expectRejected("problems:\n  - cfg: problems/*.cfg\nplanners:\n  - name: rrtconnect\n    params: {rnage: 1}\n"
                   "time_limit: 1\n",
                   "rnage");
    expectRejected("problems:\n  - cfg: problems/*.cfg\nplanners: [rrtconnect]\ntime_limit: -1\n",
                   "time_limit: needs a positive number");
    expectRejected(good + "seeds: [1, -2]\n", "is not a positive integer");
    expectRejected(good + "time_limt: 3\n", "time_limt: unknown key");
    expectRejected(good + "runs: 0\n", "runs: must be at least 1");
    // More workers than cores would make the runs wait for each other (and skew every time).
    const std::string folder = makeTempDir("sweep_cores");
    writeBoxProblems(folder + "/problems", 1);
    writeFile(folder + "/spec.yaml", good);
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    const auto run =
        runCli("sweep run " + folder + "/spec.yaml --out " + folder + "/out --local " + std::to_string(cores + 1));
    EXPECT_EQ(run.status, 1) << run.output;
    EXPECT_NE(run.output.find("cores; this machine has " + std::to_string(cores)), std::string::npos) << run.output;
}

TEST(SweepCli, LocalSweepMergesResumesAndNamesMissingAndFailedRuns)
{
    const std::string folder = makeTempDir("sweep_local");
    writeBoxProblems(folder + "/problems", 2);
    // A third problem whose robot mesh does not exist: it passes the spec check (files are not parsed
    // there) and fails in its task, which the merge must report.
    writeFile(folder + "/problems/c_broken.cfg",
              readFile(folder + "/problems/a_boxes.cfg").replace(0, 0, "") + "");
    {
        std::string text = readFile(folder + "/problems/c_broken.cfg");
        text.replace(text.find("robot = robot.obj"), 17, "robot = missing.obj");
        writeFile(folder + "/problems/c_broken.cfg", text);
    }
    const std::string spec = boxSpec(folder, "[1, 2]");
    const std::string out = folder + "/out";
    auto run = runCli("sweep run " + spec + " --out " + out + " --local 2");
    EXPECT_EQ(run.status, 2) << run.output;  // the broken problem's two units failed
    EXPECT_NE(run.output.find("3 task(s), 6 run(s)"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("4/6 unit(s) logged, 2 failed, 0 missing; 4/6 run(s) in the database"),
              std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("FAILED task-0002 omplapp.c_broken.seed1: exit status 1"), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("FAILED task-0002 omplapp.c_broken.seed2: exit status 1"), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("| omplapp | RRTConnect | 4 | 4 | 0 |"), std::string::npos) << run.output;
    EXPECT_EQ(countRuns(out + "/sweep.db", ""), 4);
    EXPECT_EQ(countRuns(out + "/sweep.db", "where solved = 1 and states_checked > 0"), 4);
    EXPECT_TRUE(isPng(out + "/summary.png"));

    // Resume: a lost log is named by the merge, and the next run repeats only its task (and the
    // failed one), not the complete one.
    const std::string lost = out + "/logs/task-0001/omplapp.b_boxes.seed2.log";
    ASSERT_EQ(std::remove(lost.c_str()), 0);
    std::remove((lost + ".status").c_str());
    run = runCli("sweep merge " + out);
    EXPECT_EQ(run.status, 2) << run.output;
    EXPECT_NE(run.output.find("MISSING task-0001 omplapp.b_boxes.seed2: no log"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("3/6 unit(s) logged, 2 failed, 1 missing"), std::string::npos) << run.output;
    const std::string kept = readFile(out + "/logs/task-0000/omplapp.a_boxes.seed1.log");

    // A task inside a Slurm job takes the CPUs of its allocation, whatever the spec says.
    run = rastercheck::test::runCommand("SLURM_CPUS_PER_TASK=2 " + std::string(RASTERCHECK_CLI) + " sweep task " +
                                        out + " --index 1");
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("'--threads' '2'"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("2/2 unit(s) logged, 2 CPU(s)"), std::string::npos) << run.output;
    ASSERT_EQ(std::remove(lost.c_str()), 0);
    std::remove((lost + ".status").c_str());

    run = runCli("sweep run " + spec + " --out " + out + " --local 2");
    EXPECT_EQ(run.status, 2) << run.output;
    EXPECT_NE(run.output.find("2 task(s) to run, 1 complete"), std::string::npos) << run.output;
    EXPECT_EQ(access(lost.c_str(), F_OK), 0);
    EXPECT_EQ(readFile(out + "/logs/task-0000/omplapp.a_boxes.seed1.log"), kept) << "a complete task ran again";
    EXPECT_NE(readFile(out + "/out/task-0001.out").find("omplapp.b_boxes.seed1: log present, skipped"),
              std::string::npos);

    // A changed spec is not mixed into the old sweep's folder.
    boxSpec(folder, "[1, 3]");
    run = runCli("sweep run " + spec + " --out " + out + " --local 1");
    EXPECT_EQ(run.status, 1) << run.output;
    EXPECT_NE(run.output.find("holds another sweep"), std::string::npos) << run.output;
}

TEST(SweepCli, SlurmScriptsAskForOneCpuPerTaskAndDependOnTheArray)
{
    const std::string folder = makeTempDir("sweep_scripts");
    writeBoxProblems(folder + "/problems", 3);
    const std::string spec = boxSpec(folder, "[4]", "slurm:\n  max_parallel: 2\n  options: [\"--partition=short\"]\n");
    const auto run = runCli("sweep run " + spec + " --out " + folder + "/out --slurm");
    ASSERT_EQ(run.status, 0) << run.output;
    const std::string array = readFile(folder + "/out/slurm/array.sbatch");
    EXPECT_NE(array.find("#SBATCH --array=0-2%2\n"), std::string::npos) << array;
    EXPECT_NE(array.find("#SBATCH --cpus-per-task=1\n"), std::string::npos) << array;
    // 3 tasks of 1 unit: 2 x 1 run x 2 s + 60 s, rounded up to minutes.
    EXPECT_NE(array.find("#SBATCH --time=2\n"), std::string::npos) << array;
    EXPECT_NE(array.find("#SBATCH --partition=short\n"), std::string::npos) << array;
    EXPECT_NE(array.find("export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}"), std::string::npos) << array;
    EXPECT_NE(array.find("sweep task"), std::string::npos) << array;
    EXPECT_NE(readFile(folder + "/out/slurm/merge.sbatch").find("sweep merge"), std::string::npos);
    EXPECT_NE(run.output.find("--dependency=afterany:"), std::string::npos) << run.output;
}
