#include "rastercheck/collision/CurvedSolids.h"

#include <algorithm>
#include <cmath>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/device/ConvexClosest.h"
#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/Traversal.h"
#include "rastercheck/geometry/EigenDevice.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
using device::ConvexKind;
using device::ConvexShape;
using device::Pose;
using device::Vec3;

bool hasCurved(const std::vector<PrimitiveShape> &shapes)
{
    return std::any_of(shapes.begin(), shapes.end(), [](const PrimitiveShape &s) { return s.curved(); });
}

/** \brief \a shape as a convex shape in its solid's frame. */
ConvexShape localShape(const PrimitiveShape &shape)
{
    ConvexShape convex{};
    convex.pose = toDevicePose(shape.pose);
    switch (shape.kind)
    {
        case PrimitiveShape::Kind::Box:
            convex.kind = ConvexKind::Box;
            for (int i = 0; i < 3; ++i)
                convex.size[i] = 0.5 * shape.size[i];
            break;
        case PrimitiveShape::Kind::Sphere:
            convex.kind = ConvexKind::Sphere;
            convex.size[0] = shape.size.x();
            break;
        case PrimitiveShape::Kind::Cylinder:
        case PrimitiveShape::Kind::Cone:
            convex.kind = shape.kind == PrimitiveShape::Kind::Cone ? ConvexKind::Cone : ConvexKind::Cylinder;
            convex.size[0] = shape.size.x();
            convex.size[1] = 0.5 * shape.size.y();
            break;
    }
    return convex;
}

/** \brief Radius of a ball about the primitive's frame origin that holds it. */
double reachOf(const PrimitiveShape &shape)
{
    switch (shape.kind)
    {
        case PrimitiveShape::Kind::Box:
            return 0.5 * shape.size.norm();
        case PrimitiveShape::Kind::Sphere:
            return shape.size.x();
        case PrimitiveShape::Kind::Cylinder:
        case PrimitiveShape::Kind::Cone:
            return std::hypot(shape.size.x(), 0.5 * shape.size.y());
    }
    return 0.0;
}

/** \brief The nearest pair of solid \a a's and solid \a b's shapes when nearer than result.distance
    (the best so far, initially the caller's bound): result updated, true. */
bool shapesDistance(const device::CurvedArrays &arrays, std::uint32_t a, const Pose<double> &poseA, std::uint32_t b,
                    const Pose<double> &poseB, SurfaceDistance &result)
{
    bool found = false;
    for (std::uint32_t i = arrays.solidShapes[a]; i < arrays.solidShapes[a + 1]; ++i)
    {
        const ConvexShape ca = device::placedShape(arrays.shapes[i], poseA);
        for (std::uint32_t j = arrays.solidShapes[b]; j < arrays.solidShapes[b + 1]; ++j)
        {
            Vec3<double> onA, onB;
            const double d = device::convexClosest(ca, device::placedShape(arrays.shapes[j], poseB), onA, onB);
            if (d < result.distance)
            {
                result.distance = d;
                result.pointA = toEigen(onA);
                result.pointB = toEigen(onB);
                result.triangleA = result.triangleB = -1;
                found = true;
            }
        }
    }
    return found;
}

/** \brief The nearest point pair of solid \a solid's shapes (placed by \a poseShapes) and the solid
    of \a bvh's mesh (placed by \a poseMesh) when nearer than result.distance: result updated
    (pointA on the shapes, triangleB the mesh's), true. The search runs in the mesh's frame; a node
    is skipped when the ball about the primitive's origin that holds it is no nearer to the node's
    box or sphere than the best so far (less the nodes' float rounding). */
bool shapesToMeshDistance(const device::CurvedArrays &arrays, std::uint32_t solid, const Pose<double> &poseShapes,
                          const MeshBvh &bvh, bool closed, const Pose<double> &poseMesh, SurfaceDistance &result)
{
    if (bvh.empty())
        return false;
    const Pose<double> inMesh = device::relativePose(poseMesh, poseShapes);  // shapes' frame -> mesh frame
    const Eigen::Isometry3d meshToWorld = fromDevicePose(poseMesh);
    const MeshBvh::Node *nodes = bvh.nodes();
    bool found = false;
    const device::ExactTree mesh = bvh.exactTree();
    for (std::uint32_t k = arrays.solidShapes[solid]; k < arrays.solidShapes[solid + 1]; ++k)
    {
        const ConvexShape convex = device::placedShape(arrays.shapes[k], inMesh);
        const Eigen::Vector3d centre(convex.pose.m[3], convex.pose.m[7], convex.pose.m[11]);
        const double radius = arrays.reach[k];
        const double slack = 1e-5 * (centre.cwiseAbs().sum() + nodes[0].radius);
        const auto nodeTest = [&](const MeshBvh::Node &node)
        {
            const Eigen::Vector3d offset = centre - nodeCentre(node);
            const double sphereGap = offset.norm() - node.radius;
            // The ball's centre to the box, along the box's axes.
            const Eigen::Vector3d local = nodeAxes(node).transpose() * offset;
            const Eigen::Vector3d outside = (local.cwiseAbs() - nodeExtents(node)).cwiseMax(0.0);
            return std::max(sphereGap, outside.norm()) - radius - slack < result.distance;
        };
        const auto leaf = [&](const MeshBvh::Node &node)
        {
            for (std::uint32_t slot = node.firstSlot(); slot < node.firstSlot() + node.count; ++slot)
            {
                const ConvexShape triangle = device::slotTriangle(mesh, slot);
                Vec3<double> onShape, onTriangle;
                const double d = device::convexClosest(convex, triangle, onShape, onTriangle);
                if (d < result.distance)
                {
                    result.distance = d;
                    result.pointA = meshToWorld * toEigen(onShape);
                    result.pointB = meshToWorld * toEigen(onTriangle);
                    result.triangleA = -1;
                    result.triangleB = static_cast<std::int32_t>(bvh.triangleOrder()[slot]);
                    found = true;
                    if (d <= 0.0)
                        return false;
                }
            }
            return true;
        };
        device::walkTree(nodes, static_cast<std::uint32_t>(bvh.numNodes()), nodeTest, leaf);
        if (result.distance <= 0.0)
            return true;
        // No surface touches the primitive: it is inside the mesh's solid or wholly outside it.
        if (closed && pointInsideClosedMesh(bvh, centre))
        {
            result.distance = 0.0;
            result.pointA = result.pointB = meshToWorld * centre;
            result.triangleA = result.triangleB = -1;
            return true;
        }
    }
    return found;
}
}  // namespace

CurvedSolids::CurvedSolids(const CollisionModel &model)
{
    const RobotModel &robot = *model.robot;
    const std::size_t m = model.numComponents();
    // The solids' shapes, components then objects, as the per-element code reads them.
    solidShapes_.push_back(0);
    const auto addSolid = [&](const std::vector<PrimitiveShape> &shapes)
    {
        for (const PrimitiveShape &shape : shapes)
        {
            shapes_.push_back(localShape(shape));
            reach_.push_back(reachOf(shape));
        }
        solidShapes_.push_back(static_cast<std::uint32_t>(shapes_.size()));
    };
    for (std::size_t c = 0; c < m; ++c)
        addSolid(robot.components[c].shapes);
    for (std::size_t o = 0; o < model.numObjects(); ++o)
        addSolid(model.scene->objects[o].shapes);

    refines_.assign(model.numPairs(), 0);
    bool any = false;
    for (std::uint32_t pair = 0; pair < model.numPairs(); ++pair)
    {
        Contact parties;
        model.nameParties(pair, parties);
        const std::vector<PrimitiveShape> &a = robot.components[static_cast<std::size_t>(parties.component)].shapes;
        const std::vector<PrimitiveShape> &b =
            parties.kind == Contact::Kind::Environment
                ? model.scene->objects[static_cast<std::size_t>(parties.object)].shapes
                : robot.components[static_cast<std::size_t>(parties.otherComponent)].shapes;
        refines_[pair] = hasCurved(a) || hasCurved(b) ? 1 : 0;
        any = any || refines_[pair];
    }
    if (!any || m == 0)
        refines_.clear();
}

namespace
{
/** \brief A pair's two parties: component \a a, and \a b, a scene object (\a environment) or a
    component, with their solid numbers in CurvedArrays (components, then objects). */
struct PairParties
{
    std::size_t a, b;
    bool environment;
    std::uint32_t solidA, solidB;
    const MeshBvh *bvhA, *bvhB;
    bool closedA, closedB;
};

PairParties partiesOf(const CollisionModel &model, std::uint32_t pair)
{
    Contact named;
    model.nameParties(pair, named);
    PairParties parties;
    parties.a = static_cast<std::size_t>(named.component);
    parties.environment = named.kind == Contact::Kind::Environment;
    parties.b = static_cast<std::size_t>(parties.environment ? named.object : named.otherComponent);
    parties.solidA = static_cast<std::uint32_t>(parties.a);
    parties.solidB = static_cast<std::uint32_t>(parties.environment ? model.numComponents() + parties.b : parties.b);
    parties.bvhA = model.componentBvhs[parties.a].get();
    parties.closedA = model.components[parties.a].closed;
    parties.bvhB = parties.environment ? model.objectBvhs[parties.b].get() : model.componentBvhs[parties.b].get();
    parties.closedB = parties.environment ? model.objects[parties.b].closed : model.components[parties.b].closed;
    return parties;
}
}  // namespace

bool CurvedSolids::collide(const CollisionModel &model, std::uint32_t pair, const Pose<double> &poseA,
                           const Pose<double> &poseB, double padding) const
{
    const PairParties p = partiesOf(model, pair);
    return device::curvedPairCollides(arrays(), p.solidA, poseA, p.bvhA->exactTree(), p.closedA, p.solidB, poseB,
                                      p.bvhB->exactTree(), p.closedB, padding);
}

bool CurvedSolids::distance(const CollisionModel &model, std::uint32_t pair, const Pose<double> &poseA,
                            const Pose<double> &poseB, double bound, SurfaceDistance &result) const
{
    const PairParties p = partiesOf(model, pair);
    const device::CurvedArrays shapes = arrays();
    const bool shapesA = shapes.solidShapes[p.solidA + 1] > shapes.solidShapes[p.solidA];
    const bool shapesB = shapes.solidShapes[p.solidB + 1] > shapes.solidShapes[p.solidB];
    SurfaceDistance best;
    best.distance = bound;
    if (shapesA && shapesB)
    {
        if (!shapesDistance(shapes, p.solidA, poseA, p.solidB, poseB, best))
            return false;
    }
    else if (shapesA)
    {
        if (!shapesToMeshDistance(shapes, p.solidA, poseA, *p.bvhB, p.closedB, poseB, best))
            return false;
    }
    else
    {
        // The shapes are B's: measured the other way round, then A and B swapped back.
        if (!shapesToMeshDistance(shapes, p.solidB, poseB, *p.bvhA, p.closedA, poseA, best))
            return false;
        std::swap(best.pointA, best.pointB);
        std::swap(best.triangleA, best.triangleB);
    }
    result = best;
    return true;
}
}  // namespace rastercheck
