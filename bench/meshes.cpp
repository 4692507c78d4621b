// Collision checking among real, non-convex triangle meshes, FCL in the same run, one thread:
// OMPL.app's rigid-body problems (read from the folder the user gives: their licence forbids
// redistribution), FCL's env.obj / rob.obj, and a generated terrain of 1e4, 1e5 and 1e6 triangles
// (cost growth). Two state sets per scene: uniform states within the problem's bounds, and states
// near contact (each pair of a uniform free and colliding state bisected 12 times by the exact
// oracle along the segment between them, both ends kept). Verdicts are compared with exact mode.
// Rates: best of three rounds in the thread's CPU time (see measure()).
//
// usage: rastercheck_bench_meshes [states=20000] [omplapp_3d_folder (default $RASTERCHECK_OMPLAPP)]
//        [scene names to run, default all]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <time.h>

#include "BenchSupport.h"
#include "Reference.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/io/OmplAppProblem.h"

using namespace rastercheck;

namespace
{
/** \brief A smooth height field over 40 000 x 40 000 units tessellated into about \a triangles
    triangles, written as an OBJ; returns its path. \a solid closes it into the ground below
    (walls down to z = -1500 and a bottom), so that the raster, which needs one closed party, decides
    its pairs. */
std::string writeTerrain(std::size_t triangles, bool solid = false)
{
    const int n = static_cast<int>(std::sqrt(static_cast<double>(triangles) / 2.0));
    const std::string path =
        "/tmp/rastercheck_terrain_" + std::string(solid ? "solid_" : "") + std::to_string(triangles) + ".obj";
    std::ofstream out(path);
    const double size = 40000.0, step = size / n;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
        {
            const double x = i * step - size / 2, y = j * step - size / 2;
            const double z = 600.0 * std::sin(x / 2300.0) * std::cos(y / 3100.0) + 250.0 * std::sin((x + y) / 900.0);
            out << "v " << x << ' ' << y << ' ' << z << '\n';
        }
    const auto at = [n](int i, int j) { return i * (n + 1) + j + 1; };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
        {
            out << "f " << at(i, j) << ' ' << at(i + 1, j) << ' ' << at(i + 1, j + 1) << '\n';
            out << "f " << at(i, j) << ' ' << at(i + 1, j + 1) << ' ' << at(i, j + 1) << '\n';
        }
    if (!solid)
        return path;
    // The boundary counter-clockwise seen from above, a vertex below each, and the bottom's centre.
    std::vector<int> ring;
    for (int i = 0; i < n; ++i)
        ring.push_back(at(i, 0));
    for (int j = 0; j < n; ++j)
        ring.push_back(at(n, j));
    for (int i = n; i > 0; --i)
        ring.push_back(at(i, n));
    for (int j = n; j > 0; --j)
        ring.push_back(at(0, j));
    const int firstBelow = (n + 1) * (n + 1) + 1, centre = firstBelow + static_cast<int>(ring.size());
    const auto below = [&](std::size_t k) { return firstBelow + static_cast<int>(k % ring.size()); };
    for (int top : ring)
    {
        const int i = (top - 1) / (n + 1), j = (top - 1) % (n + 1);
        out << "v " << i * step - size / 2 << ' ' << j * step - size / 2 << " -1500\n";
    }
    out << "v 0 0 -1500\n";
    for (std::size_t k = 0; k < ring.size(); ++k)
    {
        const int next = ring[(k + 1) % ring.size()];
        out << "f " << ring[k] << ' ' << below(k) << ' ' << below(k + 1) << '\n';
        out << "f " << ring[k] << ' ' << below(k + 1) << ' ' << next << '\n';
        out << "f " << centre << ' ' << below(k + 1) << ' ' << below(k) << '\n';
    }
    return path;
}

/** \brief bench::checkingCfg's text for \a robot in \a world, written to a file named by \a name. */
std::string writeCfg(const std::string &name, const std::string &robot, const std::string &world,
                     const std::vector<double> &volume)
{
    const std::string path = "/tmp/rastercheck_" + name + ".cfg";
    std::ofstream(path) << bench::checkingCfg(name, robot, world, volume);
    return path;
}

/** \brief States near contact: pairs of a free and a colliding uniform state, bisected 12 times by
    \a exact (positions linearly, quaternions normalised linearly), both final ends. */
std::vector<double> nearContact(const Checker &checker, const std::vector<double> &uniform,
                                const std::vector<std::uint8_t> &valid, std::size_t n)
{
    std::vector<std::size_t> free, colliding;
    for (std::size_t i = 0; i < valid.size(); ++i)
        (valid[i] ? free : colliding).push_back(i);
    std::vector<double> out;
    if (free.empty() || colliding.empty())
        return out;
    CollisionRequest exact;
    exact.mode = CollisionMode::Exact;
    std::vector<double> a(7), b(7), mid(7);
    for (std::size_t p = 0; 2 * p < n; ++p)
    {
        std::copy_n(&uniform[7 * free[p % free.size()]], 7, a.begin());
        std::copy_n(&uniform[7 * colliding[(p * 7919) % colliding.size()]], 7, b.begin());
        if (a[3] * b[3] + a[4] * b[4] + a[5] * b[5] + a[6] * b[6] < 0)
            for (int k = 3; k < 7; ++k)
                b[k] = -b[k];
        for (int step = 0; step < 12; ++step)
        {
            double norm = 0;
            for (int k = 0; k < 7; ++k)
            {
                mid[k] = 0.5 * (a[k] + b[k]);
                norm += k >= 3 ? mid[k] * mid[k] : 0.0;
            }
            for (int k = 3; k < 7; ++k)
                mid[k] /= std::sqrt(norm);
            (checker.isValid(mid, exact) ? a : b) = mid;
        }
        out.insert(out.end(), a.begin(), a.end());
        out.insert(out.end(), b.begin(), b.end());
    }
    return out;
}

constexpr int kRepeats = 3;

struct Row
{
    std::string scene;
    std::size_t environmentTriangles, robotTriangles;
    double fcl, safe, conservative, exact;  // states/s
    std::size_t free, conservativeFalseAlarms, falseNegatives, fclDisagreements;
};

Row measure(const std::string &scene, const Checker &checker, const std::vector<double> &q)
{
    const std::size_t n = q.size() / 7;
    Row row{scene,
            checker.collisionModel().objectTriangles.size() / 3,
            checker.collisionModel().componentTriangles.size() / 3,
            0,
            0,
            0,
            0,
            0,
            0,
            0,
            0};
    test::FclReference fcl(checker.collisionModel());
    std::vector<std::uint8_t> fclValid(n), exactValid(n), valid(n);
    // Each rate is the best of kRepeats rounds, the checkers taking turns within a round, timed in
    // this thread's CPU time: on a build machine shared with compilers a single wall-clock run
    // moved the near-contact ratios by up to 40 % between runs.
    for (int round = 0; round < kRepeats; ++round)
    {
        row.fcl = std::max(row.fcl, n / bench::threadSeconds(
                                            [&]
                                            {
                                                for (std::size_t i = 0; i < n; ++i)
                                                    fclValid[i] = fcl.collides(&q[7 * i]) ? 0 : 1;
                                            }));
        for (CollisionMode mode : {CollisionMode::Exact, CollisionMode::Safe, CollisionMode::Conservative})
        {
            CollisionRequest request;
            request.mode = mode;
            std::vector<std::uint8_t> &out = mode == CollisionMode::Exact ? exactValid : valid;
            const double rate = n / bench::threadSeconds([&] { checker.check(q.data(), n, out.data(), request); });
            double &best = mode == CollisionMode::Exact  ? row.exact
                           : mode == CollisionMode::Safe ? row.safe
                                                         : row.conservative;
            best = std::max(best, rate);
            for (std::size_t i = 0; round == 0 && mode != CollisionMode::Exact && i < n; ++i)
            {
                row.falseNegatives += valid[i] && !exactValid[i];
                if (mode == CollisionMode::Conservative)
                    row.conservativeFalseAlarms += !valid[i] && exactValid[i];
            }
        }
    }
    for (std::size_t i = 0; i < n; ++i)
    {
        row.free += exactValid[i];
        row.fclDisagreements += fclValid[i] != exactValid[i];
    }
    return row;
}

/** \brief The batched stages (the GPU's code path, here on the host executor), safe mode without
    contacts: the stages rasterize every pair no proof settles, and the host decides what they
    leave open. Counts from device::StageCounts. */
struct StagesRow
{
    std::string scene;
    double rate;     // states/s, one thread
    double cpuRate;  // the CPU backend's, same states and request
    double rasterizedPerState, candidatesPerPair;
    std::size_t meshTriangles;  // robot + environment: what each rasterized pair's items were before the node culls
    std::size_t disagreements;  // verdicts unlike the CPU backend's
};

StagesRow measureStages(const std::string &scene, const Checker &checker, const std::vector<double> &q)
{
    const std::size_t n = q.size() / 7;
    const CollisionModelConstPtr model = checker.collisionModelPtr();
    const StagedBackend staged(model, makeHostStageRunner(model));
    staged.countStages(true);
    std::vector<std::uint8_t> valid(n), cpuValid(n);
    const CollisionRequest request;
    const double rate = n / bench::threadSeconds([&] { staged.check(q.data(), n, valid.data(), nullptr, request, 1); });
    const double cpuRate = n / bench::threadSeconds([&] { checker.check(q.data(), n, cpuValid.data(), request); });
    const device::StageCounts counts = staged.stageCounts();
    StagesRow row{scene,
                  rate,
                  cpuRate,
                  double(counts.rasterizedPairs) / double(n),
                  double(counts.candidateTriangles) / double(std::max(1ull, counts.rasterizedPairs)),
                  (model->componentTriangles.size() + model->objectTriangles.size()) / 3,
                  0};
    for (std::size_t i = 0; i < n; ++i)
        row.disagreements += valid[i] != cpuValid[i];
    return row;
}

void printTable(const char *title, const std::vector<Row> &rows)
{
    std::printf(
        "\n%s\n\n| scene | env tris | robot tris | FCL states/s | safe / FCL | conservative / FCL | "
        "exact / FCL | conservative false alarms (of free) | FN, every mode | FCL differs |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        title);
    double worst = 1e300;
    std::string worstScene;
    for (const Row &r : rows)
    {
        std::printf("| %s | %zu | %zu | %.0f | %.2f | %.2f | %.2f | %zu (%.2f %% of %zu) | %zu | %zu |\n",
                    r.scene.c_str(), r.environmentTriangles, r.robotTriangles, r.fcl, r.safe / r.fcl,
                    r.conservative / r.fcl, r.exact / r.fcl, r.conservativeFalseAlarms,
                    r.free ? 100.0 * r.conservativeFalseAlarms / r.free : 0.0, r.free, r.falseNegatives,
                    r.fclDisagreements);
        if (r.safe / r.fcl < worst)
        {
            worst = r.safe / r.fcl;
            worstScene = r.scene;
        }
    }
    if (!rows.empty())
        std::printf("\nworst safe / FCL: %.2f (%s)\n", worst, worstScene.c_str());
}
}  // namespace

int main(int argc, char **argv)
{
    const std::size_t states = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 20000;
    std::string omplapp =
        argc > 2 ? argv[2] : (std::getenv("RASTERCHECK_OMPLAPP") ? std::getenv("RASTERCHECK_OMPLAPP") : "");
    std::vector<std::string> only(argv + std::min(argc, 3), argv + argc);
    const auto wanted = [&](const std::string &name)
    { return only.empty() || std::find(only.begin(), only.end(), name) != only.end(); };
    const std::string root = bench::sharedDataOrExit();

    std::vector<std::pair<std::string, std::string>> scenes;  // name, .cfg
    if (omplapp.empty())
        std::printf(
            "OMPL.app problems skipped: give their resources/3D folder as the second argument or in "
            "RASTERCHECK_OMPLAPP\n");
    else
        for (const char *name :
             {"Easy", "bugtrap", "Twistycool", "cubicles", "Abstract", "Home", "Apartment", "alpha-1.5"})
            if (std::ifstream(omplapp + "/" + name + ".cfg"))
                scenes.emplace_back(name, omplapp + "/" + name + ".cfg");
    const std::string fcl = root + "/meshes/fcl/";
    scenes.emplace_back("fcl env/rob", writeCfg("fcl_env_rob", fcl + "rob.obj", fcl + "env.obj", {}));
    for (std::size_t size : {10000, 100000, 1000000})
    {
        const std::string name = "terrain " + std::to_string(size);
        if (wanted(name))
            scenes.emplace_back(name, writeCfg("terrain_" + std::to_string(size), fcl + "rob.obj", writeTerrain(size),
                                               {-20000, -20000, -900, 20000, 20000, 1000}));
    }

    // Closed terrains: only the batched stages' table (the raster needs a closed party; rob.obj is
    // open), for their cost growth.
    std::vector<std::pair<std::string, std::string>> stagesOnly;
    for (std::size_t size : {10000, 100000, 1000000})
    {
        const std::string name = "terrain solid " + std::to_string(size);
        if (wanted(name))
            stagesOnly.emplace_back(
                name, writeCfg("terrain_solid_" + std::to_string(size), fcl + "rob.obj", writeTerrain(size, true),
                               {-20000, -20000, -900, 20000, 20000, 1000}));
    }

    std::vector<Row> uniformRows, nearRows;
    std::vector<StagesRow> stagesRows;
    for (const auto &[name, cfg] : scenes)
    {
        if (!wanted(name))
            continue;
        double loadSeconds = 0;
        OmplAppProblem problem;
        loadSeconds = bench::seconds([&] { problem = loadOmplAppProblem(cfg); });
        std::unique_ptr<Checker> checker;
        loadSeconds += bench::seconds(
            [&] {
                checker =
                    std::make_unique<Checker>(problem.robot, problem.scene, CheckerOptions{BackendChoice::Cpu, 1});
            });
        const std::vector<double> uniform = bench::uniformPoses(*problem.robot, states, 17);
        uniformRows.push_back(measure(name, *checker, uniform));
        std::vector<std::uint8_t> valid(states);
        CollisionRequest exact;
        exact.mode = CollisionMode::Exact;
        checker->check(uniform.data(), states, valid.data(), exact);
        const std::vector<double> near = nearContact(*checker, uniform, valid, std::min<std::size_t>(states, 4000));
        if (!near.empty())
            nearRows.push_back(measure(name, *checker, near));
        stagesRows.push_back(measureStages(name, *checker, uniform));
        std::fprintf(stderr, "%s: loaded and built in %.2f s; proof arrays %zu bytes\n", name.c_str(), loadSeconds,
                     checker->collisionModel().convex.bytes());
    }
    for (const auto &[name, cfg] : stagesOnly)
    {
        const OmplAppProblem problem = loadOmplAppProblem(cfg);
        const Checker checker(problem.robot, problem.scene, CheckerOptions{BackendChoice::Cpu, 1});
        stagesRows.push_back(measureStages(name, checker, bench::uniformPoses(*problem.robot, states, 17)));
    }
    std::printf(
        "\nOne thread, CPU backend, best of %d rounds in CPU time; FCL 0.7 BVHModel<OBBRSS> (OMPL.app's "
        "semantics: surfaces only, so it misses a robot buried in a closed obstacle; 'FCL differs' counts its "
        "verdicts against exact mode)\n",
        kRepeats);
    printTable("Uniform states", uniformRows);
    printTable("Near-contact states (free and colliding ends of 12-step bisections)", nearRows);
    std::printf(
        "\nBatched stages (the GPU's code path) on the host, one thread, safe mode, uniform states, one round\n\n"
        "| scene | states/s | CPU backend states/s | rasterized pairs per state | candidate triangles per rasterized "
        "pair | triangles "
        "of both meshes | verdicts unlike the CPU backend's |\n|---|---:|---:|---:|---:|---:|---:|\n");
    for (const StagesRow &r : stagesRows)
        std::printf("| %s | %.0f | %.0f | %.3f | %.1f | %zu | %zu |\n", r.scene.c_str(), r.rate, r.cpuRate,
                    r.rasterizedPerState, r.candidatesPerPair, r.meshTriangles, r.disagreements);
    return 0;
}
