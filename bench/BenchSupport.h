#pragma once

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <time.h>

#include "rastercheck/io/DataPath.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/RobotModel.h"

namespace rastercheck::bench
{
/** \brief CPU seconds this thread spent in \a work: the build machine is shared, and a loaded core
    stretches wall time far more than the thread's own time. */
template <class Work>
double threadSeconds(Work &&work)
{
    timespec start{}, stop{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
    work();
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &stop);
    return static_cast<double>(stop.tv_sec - start.tv_sec) + 1e-9 * static_cast<double>(stop.tv_nsec - start.tv_nsec);
}

/** \brief The seven MotionBenchMaker scenarios of the shared data. */
inline const std::vector<std::string> &mbmScenarios()
{
    static const std::vector<std::string> names{"bookshelf_small", "bookshelf_tall",  "bookshelf_thin", "box", "cage",
                                                "table_pick",      "table_under_pick"};
    return names;
}

/** \brief "a,b,c" -> {"a", "b", "c"} (empty parts dropped): list arguments of the benches. */
inline std::vector<std::string> splitList(const std::string &text)
{
    std::vector<std::string> parts;
    std::stringstream in(text);
    std::string part;
    while (std::getline(in, part, ','))
        if (!part.empty())
            parts.push_back(part);
    return parts;
}

inline std::string sharedDataOrExit()
{
    const std::string root = dataRoot(RASTERCHECK_DEFAULT_DATA);
    if (root.empty())
    {
        std::fprintf(stderr,
                     "shared data not found: set RASTERCHECK_DATA or place ../shared/data beside the checkout\n");
        std::exit(2);
    }
    return root;
}

/** \brief The MBM robot (URDF + SRDF) of \a robot ("panda", "ur5", "fetch"). */
inline RobotModelConstPtr loadMbmRobot(const std::string &root, const std::string &robot)
{
    RobotModelPtr model = loadUrdf(root + "/mbm/" + robot + "/" + robot + ".urdf");
    applySrdf(*model, loadSrdf(root + "/mbm/" + robot + "/" + robot + ".srdf"));
    return model;
}

inline std::string mbmProblemPath(const std::string &root, const std::string &robot, const std::string &scenario,
                                  int index, const std::string &kind)
{
    char name[32];
    std::snprintf(name, sizeof name, "%s%04d.yaml", kind.c_str(), index);
    return root + "/mbm/" + robot + "/problems/" + scenario + "_" + robot + "/" + name;
}

/** \brief \a n uniform poses of a free-flying body (x y z qx qy qz qw): positions within the
    robot's position bounds, orientations uniform (normalised Gaussian quaternions). */
inline std::vector<double> uniformPoses(const RobotModel &robot, std::size_t n, unsigned seed)
{
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    std::vector<double> q(7 * n);
    for (std::size_t i = 0; i < n; ++i)
    {
        double *s = &q[7 * i];
        for (int k = 0; k < 3; ++k)
            s[k] = std::uniform_real_distribution<double>(robot.lowerBounds[k], robot.upperBounds[k])(rng);
        double norm = 0;
        for (int k = 3; k < 7; ++k)
        {
            s[k] = normal(rng);
            norm += s[k] * s[k];
        }
        for (int k = 3; k < 7; ++k)
            s[k] /= std::sqrt(norm);
    }
    return q;
}

/** \brief \a n states drawn uniformly within the robot's bounds (fixed seed: every run and every
    mode sees the same states). */
inline std::vector<double> uniformStates(const RobotModel &robot, std::size_t n, unsigned seed)
{
    std::mt19937_64 rng(seed);
    std::vector<double> q(n * robot.numCoordinates());
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < robot.numCoordinates(); ++k)
            q[i * robot.numCoordinates() + k] =
                std::uniform_real_distribution<double>(robot.lowerBounds[k], robot.upperBounds[k])(rng);
    return q;
}

/** \brief An OMPL.app .cfg's text for \a robot in \a world (mesh paths as the .cfg names them; no
    start or goal needed for checking: both at the origin, identity), \a volume as min x y z max x
    y z (empty: OMPL.app's default, the world's vertices' box). */
inline std::string checkingCfg(const std::string &name, const std::string &robot, const std::string &world,
                               const std::vector<double> &volume)
{
    std::ostringstream out;
    out << "[problem]\nname = " << name << "\nrobot = " << robot << "\nworld = " << world << '\n';
    for (const char *which : {"start", "goal"})
        out << which << ".x = 0\n"
            << which << ".y = 0\n"
            << which << ".z = 0\n"
            << which << ".theta = 0\n"
            << which << ".axis.x = 1\n"
            << which << ".axis.y = 0\n"
            << which << ".axis.z = 0\n";
    const char *axes[3] = {"x", "y", "z"};
    for (std::size_t k = 0; k < volume.size(); ++k)
        out << "volume." << (k < 3 ? "min." : "max.") << axes[k % 3] << " = " << volume[k] << '\n';
    return out.str();
}

/** \brief Wall-clock seconds of \a work. */
template <class Work>
double seconds(Work &&work)
{
    const auto start = std::chrono::steady_clock::now();
    work();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace rastercheck::bench
