#pragma once

#include <string>
#include <utility>
#include <vector>

#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck
{
/** \brief An OMPL.app rigid-body problem (`.cfg`, see shared/data/README.md section 1). */
struct OmplAppProblem
{
    std::string name;
    std::string cfgPath;
    std::string robotMeshPath;  ///< absolute (resolved against the .cfg's folder)
    std::string worldMeshPath;
    bool planar = false;  ///< 2D problem: SE(2) state (x, y, yaw)

    /** \brief Start and goal as configurations of \a robot: x y z qx qy qz qw (3D) or x y yaw (2D). */
    std::vector<double> start;
    std::vector<double> goal;

    /** \brief The robot as a one-link model on a floating (3D) or planar (2D) joint whose
        coordinates are named x y z qx qy qz qw (x y yaw), bounded by `volume.*`; its mesh is
        shifted so the mean of its vertices is the origin, as OMPL.app does (z shift 0 in 2D): the
        mean of the vertices of OMPL.app's import (loadOmplAppVertices), which has a corner once per
        face normal around it where the file has no normals. */
    RobotModelPtr robot;
    /** \brief The world mesh, one object per assimp node. */
    ScenePtr scene;

    double timeLimit = 0.0;  ///< [benchmark] time_limit (s), 0 when absent
    double memoryLimit = 0.0;
    int runCount = 0;
    /** \brief [planner] entries in order: name and its parameters (name.param=value). */
    std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> planners;
    std::string objective;  ///< [problem] objective, "" when absent
    double objectiveThreshold = 0.0;
};

/** \brief Loads a .cfg and the meshes it names, as OMPL.app does: meshes are read with assimp's
    default COLLADA handling (a Z_UP file is turned Y up, ColladaUpAxis::ConvertToYUp), the 3D start
    and goal axis is normalised (a zero axis is allowed only with theta 0), `world` is optional (no
    world: an empty scene) and without `volume.*` the position bounds are the box of the world's
    vertices as OMPL.app reads them (loadOmplAppVertices).
    Throws InputError naming the file and key on a missing key, a number that does not parse or is
    not finite, a missing or empty mesh, or min > max in `volume`. */
OmplAppProblem loadOmplAppProblem(const std::string &cfgPath);

/** \brief As loadOmplAppProblem, from the .cfg's text: mesh paths resolve against \a baseDirectory
    and \a cfgPath names the input in errors (it becomes OmplAppProblem::cfgPath). */
OmplAppProblem loadOmplAppProblemString(const std::string &text, const std::string &baseDirectory,
                                        const std::string &cfgPath = "<cfg>");
}  // namespace rastercheck
