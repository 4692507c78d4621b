#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "rastercheck/collision/CollisionRequest.h"
#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/Separation.h"
#include "rastercheck/device/Stages.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck
{
/** \brief Flat, immutable arrays of one robot and one scene, laid out for the pipeline stages (and
    uploaded unchanged to a GPU), plus the oracle's BVHs. Built once per checker.

    Shapes are written next to each buffer; "local" means link frame for components and world frame
    for objects. Triangle indices are local to their mesh's vertex block.

    Float arrays in the world frame (object vertices and boxes, and the component poses a backend
    computes per state with device::toFloatPose) are relative to \a origin: a float resolves about 1e-7 of
    a coordinate, so a plant modelled 1e6 m from its origin (site coordinates) would lose
    centimetres, and the culls would drop real contacts. Re-centred, floats resolve 1e-7 of the
    distance from the scene's centre. The oracle's BVHs stay in double, in the world frame. */
class CollisionModel
{
public:
    CollisionModel(RobotModelConstPtr robot, SceneConstPtr scene);

    using MeshSlice = device::MeshSlice;

    RobotModelConstPtr robot;
    SceneConstPtr scene;

    /** \brief World point the float world-frame arrays are measured from: the centre of the scene's
        bounds; without objects, the mean of the component links' positions at the neutral
        configuration (self-collision only). */
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();

    std::vector<float> componentVertices;           // n_component_vertices x 3, link frame
    std::vector<std::uint32_t> componentTriangles;  // n_component_triangles x 3
    std::vector<MeshSlice> components;              // n_components
    std::vector<device::OrientedBox> componentLocalBoxes;  // n_components, link frame
    std::vector<int> componentLink;                 // n_components
    std::vector<int> componentSubtreeEnd;           // n_components: layer k spans [k, end)

    std::vector<float> objectVertices;           // n_object_vertices x 3, world frame - origin
    std::vector<std::uint32_t> objectTriangles;  // n_object_triangles x 3
    std::vector<MeshSlice> objects;              // n_objects
    std::vector<device::Box> objectBoxes;        // n_objects, world frame - origin

    /** \brief Component pairs (a < b) checked for self-collision: those the ACM does not allow. */
    std::vector<std::pair<int, int>> selfPairs;

    std::vector<std::unique_ptr<MeshBvh>> componentBvhs;  // n_components, link frame
    std::vector<std::unique_ptr<MeshBvh>> objectBvhs;     // n_objects, world frame

    /** \brief The convex separation cull's view of each solid (device::provablySeparated), in
        double in its own frame (components: link frame; objects: world frame, not re-centred):
        every vertex of its mesh, and its extreme vertices along 128 directions (the hull points
        GJK searches). convexSolids holds the components first, then the objects. */
    std::vector<double> convexVertices;                 // n_convex_vertices x 3
    std::vector<double> convexHullPoints;               // n_hull_points x 3
    std::vector<device::ConvexSolid> convexSolids;      // n_components + n_objects
    /** \brief Solid \a index of convexSolids as the separation test reads it. */
    device::ConvexProxy convexProxy(std::size_t index) const
    {
        return device::convexProxy(convexVertices.data(), convexHullPoints.data(), convexSolids[index]);
    }

    /** \brief Raster pixel side used when a request gives none: 1/128 of the median diagonal of the
        components' boxes (a few millimetres for an arm), so a typical link spans about a hundred
        pixels. */
    double defaultPixelSize = 0.0;

    /** \brief Per coordinate: 1 when bounds apply (continuous joints wrap and have none). */
    std::vector<std::uint8_t> boundedCoordinates;
    /** \brief First coordinate of every floating joint's quaternion (qx). */
    std::vector<int> quaternionStarts;

    /** \brief True when every coordinate is finite, bounded coordinates lie within their bounds
        (OMPL's tolerance: one double epsilon), and no quaternion is zero. */
    bool configurationAdmissible(const double *q) const;

    std::size_t numComponents() const { return components.size(); }
    std::size_t numObjects() const { return objects.size(); }
    /** \brief Size of the pair numbering (device::environmentPair, then the self pairs). */
    std::size_t numPairs() const { return numObjects() * numComponents() + selfPairs.size(); }
    /** \brief Sets contact.kind, component and object or otherComponent from a pair's number. */
    void nameParties(std::uint32_t pair, Contact &contact) const;
};

using CollisionModelConstPtr = std::shared_ptr<const CollisionModel>;

/** \brief Directions the hull points of a solid are extreme along: enough that the hull they span
    comes within a few percent of the mesh's size (so GJK's direction is good), few enough that
    its support searches stay short. The proof itself always reads every vertex. */
constexpr std::size_t kConvexHullDirections = 128;

/** \brief Appends \a mesh's vertices and hull points (its own frame, double) to the separation
    cull's arrays and returns where they went (CollisionModel::convexSolids). */
device::ConvexSolid appendConvexSolid(const Mesh &mesh, std::vector<double> &vertices, std::vector<double> &hullPoints);
}  // namespace rastercheck
