#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck
{
/** \brief Where a checking or planning problem comes from: an OMPL.app .cfg, or a robot
    (URDF + optional SRDF) and a scene file. This is what the command line's PROBLEM means. */
struct ProblemSource
{
    std::string cfgPath;   ///< OMPL.app problem; excludes the fields below
    std::string urdfPath;
    std::string srdfPath;  ///< optional
    std::string scenePath;  ///< MoveIt scene YAML (.yaml/.yml) or a mesh file; optional (empty scene)
    UrdfOptions urdfOptions;
};

/** \brief A loaded problem. */
struct Problem
{
    RobotModelConstPtr robot;
    SceneConstPtr scene;
    /** \brief Set for OMPL.app problems (start, goal, bounds, planners). */
    std::shared_ptr<const OmplAppProblem> omplApp;
};

/** \brief Loads \a source. Throws InputError / ConfigurationError with file and element. */
Problem loadProblem(const ProblemSource &source);

/** \brief A scene from a MoveIt scene YAML (by extension .yaml / .yml) or any mesh file assimp reads
    (one object per node, named after it; a repeated or empty node name gets a "/k" suffix or the
    name "object"). */
ScenePtr loadSceneFile(const std::string &path);
}  // namespace rastercheck
