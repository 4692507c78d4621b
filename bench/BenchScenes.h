#pragma once

// The scenes the backend benches share: three Panda MotionBenchMaker scenes, the crane in the plant
// and FCL's env.obj / rob.obj (a free-flying non-convex mesh among non-convex meshes, both open).

#include <string>
#include <vector>

#include "BenchSupport.h"
#include "TestSupport.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"

namespace rastercheck::bench
{
struct SceneCase
{
    std::string name;
    RobotModelConstPtr robot;
    SceneConstPtr scene;
};

/** \brief The backend benches' scenes, from the shared data at \a root. */
inline std::vector<SceneCase> backendScenes(const std::string &root)
{
    const RobotModelConstPtr panda = loadMbmRobot(root, "panda");
    std::vector<SceneCase> cases;
    for (const char *scenario : {"table_pick", "bookshelf_tall", "cage"})
        cases.push_back({std::string("panda ") + scenario, panda,
                         loadMoveItScene(mbmProblemPath(root, "panda", scenario, 1, "scene"))});
    const Problem &crane = test::plant();
    cases.push_back({"crane in the plant", crane.robot, crane.scene});
    const OmplAppProblem meshes = loadOmplAppProblemString(checkingCfg("fcl_env_rob", "rob.obj", "env.obj", {}),
                                                           root + "/meshes/fcl", "fcl env/rob");
    cases.push_back({"fcl env/rob", meshes.robot, meshes.scene});
    return cases;
}
}  // namespace rastercheck::bench
