#pragma once

#include <map>
#include <string>
#include <vector>

#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck
{
/** \brief Reads a MoveIt PlanningScene YAML (as in MotionBenchMaker's sceneNNNN.yaml):
    `world.collision_objects[]` with `primitives` (box, cylinder, sphere, cone) and
    `primitive_poses`, `meshes` (triangles + vertices) and `mesh_poses`, and the object `pose`
    when present (poses compose: object pose * primitive pose). Quaternions are x, y, z, w and are
    normalised. Each primitive/mesh of an object becomes one SceneObject named
    "<id>" (or "<id>/<k>" when the object has several shapes).
    Throws InputError naming the file and the object on malformed input. */
ScenePtr loadMoveItScene(const std::string &path, double primitiveError = kDefaultPrimitiveError);
ScenePtr loadMoveItSceneString(const std::string &yaml, const std::string &sourceName = "<scene>",
                               double primitiveError = kDefaultPrimitiveError);

/** \brief The parts of a MoveIt MotionPlanRequest YAML that a planner needs. */
struct MotionPlanRequest
{
    std::string groupName;
    /** \brief start_state.joint_state: name -> position. */
    std::map<std::string, double> startJoints;
    /** \brief goal_constraints[0].joint_constraints: joint name -> position (tolerances kept apart). */
    std::map<std::string, double> goalJoints;
    std::map<std::string, double> goalToleranceAbove;
    std::map<std::string, double> goalToleranceBelow;
};

MotionPlanRequest loadMoveItRequest(const std::string &path);
MotionPlanRequest loadMoveItRequestString(const std::string &yaml, const std::string &sourceName = "<request>");
}  // namespace rastercheck
