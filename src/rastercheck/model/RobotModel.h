#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/device/Kinematics.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/geometry/Aabb.h"
#include "rastercheck/geometry/Mesh.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Obb.h"
#include "rastercheck/geometry/Primitives.h"

namespace rastercheck
{
struct UrdfOptions;

using JointKind = device::JointKind;

/** \brief One joint of the kinematic tree. Frames: \a origin places the joint frame in the parent
    link frame (URDF `<origin>`); the child link frame is the joint frame moved by the joint. */
struct Joint
{
    std::string name;
    JointKind kind = JointKind::Fixed;
    int parentLink = -1;
    int childLink = -1;
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  ///< unit, joint frame
    bool continuous = false;  ///< revolute without limits (URDF "continuous"); bounds are [-pi, pi]

    /** \brief Names and bounds of the coordinates this joint consumes (empty for fixed and mimic
        joints): the joint name for one-coordinate joints; for floating joints x y z qx qy qz qw,
        for planar x y theta, each prefixed "<joint>/" unless the loader chose bare names (a single
        rigid body). Units: rad or m. */
    std::vector<std::string> coordinateNames;
    std::vector<double> lower;
    std::vector<double> upper;

    /** \brief Index of the joint's first coordinate in the configuration vector, -1 for fixed and
        mimic joints (they consume none). */
    int firstCoordinate = -1;

    /** \brief Mimic: value = multiplier * value(mimicked) + offset. -1 when not a mimic joint.
        Always refers to a joint that is not itself a mimic (chains are resolved at load). */
    int mimicOf = -1;
    double mimicMultiplier = 1.0;
    double mimicOffset = 0.0;
};

/** \brief One link. A link with collision geometry owns exactly one component. */
struct Link
{
    std::string name;
    int parentJoint = -1;  ///< -1 for the root link
    int component = -1;    ///< index into RobotModel::components(), -1 without collision geometry
};

/** \brief Party-1 component: the merged collision geometry of one link, in the link frame. */
struct Component
{
    std::string name;  ///< the link name
    int link = -1;
    Mesh mesh;
    MeshTopology topology;
    Obb localObb;    ///< tight box in the link frame
    Aabb localAabb;  ///< bounds in the link frame
    /** \brief The exact shapes of its collision elements (link frame) when every one is a
        primitive; empty otherwise (the mesh is then all there is). */
    std::vector<PrimitiveShape> shapes;
};

/** \brief A component from the meshes of a link's collision elements (link frame): each part is
    cleaned on its own and the parts are kept as separate shells (cleanAndMerge), then the boxes
    are fitted. The result's mesh is empty when no part has a triangle. */
Component makeComponent(const std::string &name, std::vector<Mesh> parts);

/** \brief An immutable description of a robot (or a rigid body): kinematic tree, configuration
    layout, bounds, collision components and the allowed-collision matrix. Build it with the
    loaders (io/UrdfLoader.h, io/OmplAppProblem.h), then share it as RobotModelConstPtr; all
    mutable state lives in RobotData. */
class RobotModel
{
public:
    /** \brief Loads a robot from a URDF file; same as loadUrdf() (io/UrdfLoader.h), which documents
        the options, fallbacks and errors. */
    static std::shared_ptr<RobotModel> fromUrdf(const std::string &path);
    static std::shared_ptr<RobotModel> fromUrdf(const std::string &path, const UrdfOptions &options);

    std::string name;
    /** \brief Links; index 0 is the root. */
    std::vector<Link> links;
    /** \brief Joints in topological order (a joint's parent link is placed by an earlier joint). */
    std::vector<Joint> joints;
    /** \brief Components in depth-first order of their links, so the components of a subtree form a
        contiguous range [k, subtreeEnd[k]) — the layers of the hybrid BVH. */
    std::vector<Component> components;
    std::vector<int> componentSubtreeEnd;

    /** \brief Configuration layout: one entry per coordinate, in the order of active joints. */
    std::vector<std::string> coordinateNames;
    std::vector<double> lowerBounds;
    std::vector<double> upperBounds;

    /** \brief Allowed-collision matrix over components (symmetric, row-major, size n x n):
        true = pair exempt from self-collision checks. */
    std::vector<bool> allowedCollisions;

    /** \brief The joints in device layout, same order (derived by finalize()): what forward
        kinematics runs on, on the CPU and on the GPU. */
    std::vector<device::KinematicJoint> kinematicJoints;

    std::size_t numCoordinates() const { return coordinateNames.size(); }
    std::size_t numComponents() const { return components.size(); }
    bool isCollisionAllowed(int a, int b) const
    {
        return allowedCollisions[static_cast<std::size_t>(a) * components.size() + static_cast<std::size_t>(b)];
    }
    void setCollisionAllowed(int a, int b, bool allowed);

    /** \brief Index of a link / joint / coordinate by name, or -1. */
    int linkIndex(const std::string &linkName) const;
    int jointIndex(const std::string &jointName) const;
    int coordinateIndex(const std::string &coordinateName) const;

    /** \brief Names of joints that consume coordinates, in configuration order. */
    std::vector<std::string> activeJointNames() const;

    /** \brief Total triangles over all components. */
    std::size_t numTriangles() const;

    /** \brief Recomputes the derived fields after the tree or geometry changed: joint order,
        component order and subtree ranges, coordinate layout, and resets the allowed-collision
        matrix to "adjacent links allowed" (components whose links share a joint). Loaders call it
        (then apply SRDF); a user who edits a model calls it too. Throws ConfigurationError on a
        malformed tree (several roots, cycles, dangling indices, mimic of a mimic). */
    void finalize();

    /** \brief Middle of the bounds (for unbounded coordinates: 0; quaternion: identity). */
    std::vector<double> neutralConfiguration() const;
};

/** \brief Every field of \a robot as bytes: two robots hold the same content exactly when their
    strings are equal (a double's bits count, so -0.0 and 0.0 differ). CollisionModel shares what it
    builds from a robot alone (its meshes' trees and hulls, the self-pair tables) between robots whose
    content is equal, loaded once or several times, and builds it anew for a robot changed in any
    field. */
std::string contentBytes(const RobotModel &robot);

using RobotModelPtr = std::shared_ptr<RobotModel>;
using RobotModelConstPtr = std::shared_ptr<const RobotModel>;
}  // namespace rastercheck
