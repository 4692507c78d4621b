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
    tessellated), adjacent links allowed to collide. Visual elements are ignored unless
    UrdfOptions::visualWhenNoCollision. The model is finalized (see RobotModel::finalize()).

    Joints and coordinates:
    - revolute, prismatic: one coordinate named after the joint, bounds from `<limit>` (rad or m).
      Equal limits are allowed (a joint that cannot move). Inverted limits (lower > upper, as in
      the public crane) are swapped with a warning naming the joint (documented fallback).
    - continuous: a revolute joint with Joint::continuous set and bounds [-pi, pi].
    - floating: coordinates "<joint>/x" "<joint>/y" "<joint>/z" "<joint>/qx" .. "<joint>/qw";
      URDF gives floating joints no limits, so the position bounds are -inf / +inf (the OMPL layer
      must be given finite bounds before sampling) and the quaternion bounds [-1, 1].
    - planar: coordinates "<joint>/x" "<joint>/y" "<joint>/theta", position bounds -inf / +inf,
      theta [-pi, pi]; only axis 0 0 1 (motion in the joint frame's xy plane) is supported, any
      other axis is an InputError.
    - mimic: chains (a mimics b mimics c) are resolved to the joint that moves on its own, with the
      multipliers and offsets composed; a cycle, an unknown joint, or a source that is not
      revolute/prismatic/continuous is an InputError. A `<mimic>` on a fixed joint is ignored (the
      joint cannot move; the MotionBenchMaker Panda has one).

    Collision geometry: every `<collision>` of a link is placed by its `<origin>` and merged into the
    link's one component, then cleaned (cleanMesh); an open result is reported with logInfo.
    Mesh URIs: `package://NAME/rest` (see UrdfOptions::packagePaths), `file://` absolute paths,
    and plain paths relative to the URDF's folder.

    Throws InputError naming the file and element on malformed XML, an unknown joint type, a
    joint naming a missing link, a number that does not parse or is not finite, a missing or empty
    collision mesh, a primitive with a non-positive size, or a mimic cycle. */
RobotModelPtr loadUrdf(const std::string &path, const UrdfOptions &options = {});

/** \brief As loadUrdf, from XML text; relative mesh paths resolve against \a baseDirectory and
    \a sourceName names the input in errors. */
RobotModelPtr loadUrdfString(const std::string &xml, const std::string &baseDirectory, const UrdfOptions &options = {},
                             const std::string &sourceName = "<urdf>");
}  // namespace rastercheck
