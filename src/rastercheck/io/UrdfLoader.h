#pragma once

#include <string>
#include <vector>

#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
/** \brief How URDF files are turned into a RobotModel. */
struct UrdfOptions
{
    /** \brief Folders searched for `package://NAME/rest`: NAME is looked up as a subfolder of each
        (ROS convention), then `rest` directly under it. The environment variable
        RASTERCHECK_PACKAGE_PATH (colon-separated) adds folders; the URDF's own folder and its
        parents are tried last. */
    std::vector<std::string> packagePaths;
    /** \brief Tessellation error of box/cylinder/sphere collision elements (metres). */
    double primitiveError = kDefaultPrimitiveError;
    /** \brief Use a link's visual geometry when it has no collision element (some public URDFs, such
        as the crane in the shared data, have only visuals). A warning names each such link. */
    bool visualWhenNoCollision = false;
};

/** \brief Loads a robot from a URDF file: links, joints (revolute, continuous, prismatic, fixed,
    floating, planar; mimic), limits, collision geometry (meshes via assimp with `scale`, primitives
    tessellated), adjacent links allowed to collide. Visual elements are ignored.
    Throws InputError naming the file and element on malformed XML, an unknown joint type, a
    missing or empty collision mesh, or limits that are not numbers. Inverted limits
    (lower > upper) are swapped with a warning naming the joint (documented fallback). */
RobotModelPtr loadUrdf(const std::string &path, const UrdfOptions &options = {});

/** \brief As loadUrdf, from XML text; relative mesh paths resolve against \a baseDirectory and
    \a sourceName names the input in errors. */
RobotModelPtr loadUrdfString(const std::string &xml, const std::string &baseDirectory,
                             const UrdfOptions &options = {}, const std::string &sourceName = "<urdf>");
}  // namespace rastercheck
