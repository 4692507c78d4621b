#pragma once
// Helpers of the sweep tests (test_sweep.cpp, test_sweep_slurm.cpp).

#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "TestSupport.h"

namespace rastercheck::test::sweep
{
inline std::string readFile(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/** \brief \a count OMPL.app problems in \a folder (a_boxes.cfg, b_boxes.cfg, ...): a 20 cm cube
    moving 3 m past a pillar, solved by RRT-Connect in milliseconds. */
inline void writeBoxProblems(const std::string &folder, int count)
{
    ::mkdir(folder.c_str(), 0755);
    writeFile(folder + "/robot.obj", objBox("robot", -0.1, -0.1, -0.1, 0.1, 0.1, 0.1, 0));
    writeFile(folder + "/world.obj", objBox("pillar", -0.3, 0.8, -2, 0.3, 1.4, 2, 0));
    for (int i = 0; i < count; ++i)
    {
        const std::string name = std::string(1, static_cast<char>('a' + i)) + "_boxes";
        writeFile(folder + "/" + name + ".cfg",
                  "[problem]\nname = " + name +
                      "\nrobot = robot.obj\nworld = world.obj\n"
                      "start.x = -1.5\nstart.y = 0.5\nstart.z = 0\nstart.theta = 0\n"
                      "start.axis.x = 0\nstart.axis.y = 0\nstart.axis.z = 1\n"
                      "goal.x = 1.5\ngoal.y = 0.5\ngoal.z = 0\ngoal.theta = 0.5\n"
                      "goal.axis.x = 0\ngoal.axis.y = 0\ngoal.axis.z = 1\n"
                      "volume.min.x = -2\nvolume.min.y = -2\nvolume.min.z = -2\n"
                      "volume.max.x = 2\nvolume.max.y = 2\nvolume.max.z = 2\n");
    }
}

/** \brief Rows of the runs table of the sweep database \a database matching \a where (python3's
    sqlite3, which ompl_benchmark_statistics needs anyway); -1 when it cannot be read. */
inline int countRuns(const std::string &database, const std::string &where)
{
    const CommandRun run = runCommand("/usr/bin/python3 -c \"import sqlite3; print(sqlite3.connect('" + database +
                                      "').execute('select count(*) from runs " + where + "').fetchone()[0])\"");
    return run.status == 0 ? std::atoi(run.output.c_str()) : -1;
}

/** \brief True when \a path starts with the PNG signature. */
inline bool isPng(const std::string &path)
{
    return readFile(path).compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}
}  // namespace rastercheck::test::sweep
