// Distance queries against FCL 0.7's fcl::distance in the same run, one thread: Checker::distance
// (exact, witnesses) per state against FCL over the same pairs (components against objects, the
// SRDF's non-exempt self pairs), one fcl::DistanceResult shared by a state's pairs so that FCL
// prunes each pair against its running minimum. FCL twice: with the scenes' single primitives as
// FCL shapes (as MoveIt loads them) and with every solid a BVHModel<OBBRSS> mesh; the ratio is
// taken against the faster of the two. Agreement: |ours - FCL| over the scene's extent (its
// bounds' diagonal) on states both call apart, against FCL's meshes where the pair's solids are
// meshes and its shapes where we measure curved primitives exactly. OMPL.app's rigid-body problems
// (resources/3D, when given): the robot at uniform positions in the problem's bounds and uniform
// rotations.
//
// Usage: rastercheck_bench_distance [states per scene (default 2000)] [OMPL.app resources/3D folder or ""]
//        [scenes, comma-separated (default all)]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "BenchSupport.h"
#include "Reference.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/Problem.h"

using namespace rastercheck;

namespace
{
struct Row
{
    std::string scene;
    std::size_t states = 0, apart = 0;
    double ours = 0, fclShapes = 0, fclMeshes = 0;  // microseconds per query
    double worstDifference = 0;                     // over the extent, states both call apart
    double meanDistance = 0;                        // of the states apart
};

// Best of three rounds, in this thread's CPU time (the build machine is shared).
template <class Query>
double microsecondsPerQuery(std::size_t n, Query &&query)
{
    double best = 1e300;
    for (int round = 0; round < 3; ++round)
        best = std::min(best, bench::threadSeconds(
                                  [&]
                                  {
                                      for (std::size_t i = 0; i < n; ++i)
                                          query(i);
                                  }));
    return 1e6 * best / static_cast<double>(n);
}

Row measure(const std::string &name, const RobotModelConstPtr &robot, const SceneConstPtr &scene,
            const std::vector<double> &q)
{
    const Checker checker(robot, scene, CheckerOptions{BackendChoice::Cpu, 1});
    const CollisionModel &model = checker.collisionModel();
    const std::size_t dof = checker.dof(), n = q.size() / dof;
    test::FclDistance fclShapes(model, true), fclMeshes(model, false);
    Row row;
    row.scene = name;
    row.states = n;
    std::vector<DistanceResult> ours(n);
    std::vector<double> shapes(n), meshes(n);
    row.ours = microsecondsPerQuery(n, [&](std::size_t i) { checker.distance(&q[i * dof], {}, &ours[i]); });
    row.fclShapes = microsecondsPerQuery(n, [&](std::size_t i) { shapes[i] = fclShapes.distance(&q[i * dof]); });
    row.fclMeshes = microsecondsPerQuery(n, [&](std::size_t i) { meshes[i] = fclMeshes.distance(&q[i * dof]); });
    const Aabb bounds = scene->bounds();
    const double extent = (bounds.max - bounds.min).norm();
    for (std::size_t i = 0; i < n; ++i)
    {
        if (!(ours[i].distance > 0.0))
            continue;
        // Where we measured a curved primitive exactly, FCL's shapes are the reference; elsewhere
        // its meshes (FCL's mesh distance is exact, its GJK on shapes is not).
        bool curved = false;
        if (ours[i].kind == Contact::Kind::Environment)
            curved = model.curved.refines(
                device::environmentPair(ours[i].object, ours[i].component, static_cast<int>(model.numComponents())));
        else if (ours[i].kind == Contact::Kind::SelfCollision)
            for (std::size_t p = 0; p < model.selfPairs.size(); ++p)
                if (model.selfPairs[p] == std::make_pair(ours[i].component, ours[i].otherComponent))
                    curved =
                        model.curved.refines(device::selfPair(static_cast<int>(p), static_cast<int>(model.numObjects()),
                                                              static_cast<int>(model.numComponents())));
        const double theirs = curved ? shapes[i] : meshes[i];
        if (!(theirs > 0.0))
            continue;
        ++row.apart;
        row.meanDistance += ours[i].distance;
        const double difference = std::abs(ours[i].distance - theirs) / extent;
        if (difference > row.worstDifference)
            row.worstDifference = difference;
        if (difference > 1e-6)
            std::fprintf(stderr, "%s state %zu: ours %.9g, FCL %.9g (%s): %s\n", name.c_str(), i, ours[i].distance,
                         theirs, curved ? "shapes" : "meshes", checker.describe(ours[i]).c_str());
    }
    if (row.apart > 0)
        row.meanDistance /= static_cast<double>(row.apart);
    std::fprintf(stderr, "%s: %.1f us ours, %.1f / %.1f us FCL shapes / meshes\n", name.c_str(), row.ours,
                 row.fclShapes, row.fclMeshes);
    return row;
}
}  // namespace

int main(int argc, char **argv)
{
    const std::size_t states = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 2000;
    const std::string omplapp =
        argc > 2 ? argv[2] : (std::getenv("RASTERCHECK_OMPLAPP") ? std::getenv("RASTERCHECK_OMPLAPP") : "");
    const std::vector<std::string> only = bench::splitList(argc > 3 ? argv[3] : "");
    const auto wanted = [&](const std::string &name)
    { return only.empty() || std::find(only.begin(), only.end(), name) != only.end(); };
    const std::string root = bench::sharedDataOrExit();
    std::vector<Row> rows;
    const RobotModelConstPtr panda = bench::loadMbmRobot(root, "panda");
    const std::vector<double> pandaStates = bench::uniformStates(*panda, states, 17);
    for (const std::string &scenario : bench::mbmScenarios())
        if (wanted("Panda " + scenario))
            rows.push_back(measure("Panda " + scenario, panda,
                                   loadMoveItScene(bench::mbmProblemPath(root, "panda", scenario, 1, "scene")),
                                   pandaStates));
    if (wanted("crane in the plant"))
    {
        ProblemSource source;
        source.urdfPath = std::string(RASTERCHECK_ROBOTS_DIR) + "/crane/crane.urdf";
        source.srdfPath = std::string(RASTERCHECK_ROBOTS_DIR) + "/crane/crane.srdf";
        source.scenePath = std::string(RASTERCHECK_ROBOTS_DIR) + "/sites/plant.yaml";
        const Problem crane = loadProblem(source);
        rows.push_back(
            measure("crane in the plant", crane.robot, crane.scene, bench::uniformStates(*crane.robot, states, 17)));
    }
    std::vector<std::pair<std::string, std::string>> meshScenes;  // name, .cfg
    const std::string fclCfg = "/tmp/rastercheck_distance_fcl_env_rob.cfg";
    std::ofstream(fclCfg) << bench::checkingCfg("fcl_env_rob", root + "/meshes/fcl/rob.obj",
                                                root + "/meshes/fcl/env.obj", {});
    meshScenes.emplace_back("fcl env/rob", fclCfg);
    if (omplapp.empty())
        std::printf(
            "OMPL.app problems skipped: give their resources/3D folder as the second argument or in "
            "RASTERCHECK_OMPLAPP\n");
    else
        for (const char *name : {"Easy", "cubicles", "Twistycool", "Twistycooler", "Home", "Apartment", "Abstract",
                                 "bugtrap", "spirelli", "escape", "alpha-1.5"})
            if (std::ifstream(omplapp + "/" + name + ".cfg"))
                meshScenes.emplace_back(name, omplapp + "/" + name + ".cfg");
    for (const auto &[name, cfg] : meshScenes)
    {
        if (!wanted(name))
            continue;
        OmplAppProblem problem;
        try
        {
            problem = loadOmplAppProblem(cfg);
        }
        catch (const std::exception &error)  // a mesh missing from a partial copy of the resources
        {
            std::printf("%s skipped: %s\n", name.c_str(), error.what());
            continue;
        }
        rows.push_back(measure(name, problem.robot, problem.scene, bench::uniformPoses(*problem.robot, states, 17)));
    }

    std::printf(
        "\nDistance queries, one thread, %zu uniform states per scene, best of 3 rounds in CPU time; FCL 0.7 "
        "fcl::distance over the same pairs, one DistanceResult per state (pruned by its running minimum)\n\n",
        states);
    std::printf(
        "| scene | states apart | mean distance | ours us/query | FCL shapes us | FCL meshes us | FCL (faster) "
        "/ ours | worst abs(ours - FCL) / extent |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
    double worstRatio = 1e300;
    std::string worstScene;
    for (const Row &r : rows)
    {
        const double ratio = std::min(r.fclShapes, r.fclMeshes) / r.ours;
        if (ratio < worstRatio)
        {
            worstRatio = ratio;
            worstScene = r.scene;
        }
        std::printf("| %s | %zu / %zu | %.3f | %.1f | %.1f | %.1f | %.2f | %.1e |\n", r.scene.c_str(), r.apart,
                    r.states, r.meanDistance, r.ours, r.fclShapes, r.fclMeshes, ratio, r.worstDifference);
    }
    if (!rows.empty())
        std::printf("\nworst FCL / ours: %.2f (%s)\n", worstRatio, worstScene.c_str());
    return 0;
}
