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
    "<id>" (or "<id>/<k>" when the object has several shapes, primitives first, then meshes).
    Primitive dimensions follow shape_msgs: box [x y z], sphere [radius], cylinder and cone
    [height radius]; the type may be a name or the message constant (1 box .. 4 cone).
    `header.frame_id` is not interpreted: poses are taken as given in the planning frame (the robot's
    root, as in MotionBenchMaker). The scene's allowed-collision matrix and robot state are not read.
    An object whose `operation` is REMOVE or MOVE is an InputError (it describes no geometry), and
    so is an id used twice (MoveIt would replace the first object: an obstacle silently lost).
    A scene without collision objects loads with a warning (only self-collision is checked).
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
    /** \brief goal_constraints[0].joint_constraints: joint name -> position (tolerances kept apart;
        a tolerance absent from the file is absent from its map). */
    std::map<std::string, double> goalJoints;
    std::map<std::string, double> goalToleranceAbove;
    std::map<std::string, double> goalToleranceBelow;
};

/** \brief Reads a MotionPlanRequest YAML; missing sections leave their fields empty. Throws
    InputError naming the file and element on malformed YAML, a non-number position, name and
    position lists of different lengths, or a joint named twice (start) or constrained twice (goal). */
MotionPlanRequest loadMoveItRequest(const std::string &path);
MotionPlanRequest loadMoveItRequestString(const std::string &yaml, const std::string &sourceName = "<request>");
}  // namespace rastercheck
