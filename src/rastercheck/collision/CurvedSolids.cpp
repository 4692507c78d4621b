#include "rastercheck/collision/CurvedSolids.h"

#include <algorithm>
#include <cmath>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/device/ConvexClosest.h"
#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/Traversal.h"
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

/** \brief \a shape placed by \a placement (its solid's frame -> the frame the test runs in). */
ConvexShape placed(const PrimitiveShape &shape, const Pose<double> &placement)
{
    ConvexShape convex{};
    convex.pose = device::compose(placement, toDevicePose(shape.pose));
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
double reach(const PrimitiveShape &shape)
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

bool shapesWithin(const std::vector<PrimitiveShape> &a, const Pose<double> &poseA, const std::vector<PrimitiveShape> &b,
                  const Pose<double> &poseB, double padding)
{
    for (const PrimitiveShape &sa : a)
    {
        const ConvexShape ca = placed(sa, poseA);
        for (const PrimitiveShape &sb : b)
            if (device::convexWithin(ca, placed(sb, poseB), padding))
                return true;
    }
    return false;
}

/** \brief The triangle in slot \a slot of \a bvh (its frame) as a convex shape. */
ConvexShape slotTriangle(const MeshBvh &bvh, std::uint32_t slot)
{
    ConvexShape triangle{};
    triangle.kind = ConvexKind::Triangle;
    const double *corners = bvh.slotCorners(slot);
    for (int k = 0; k < 3; ++k)
        triangle.corner[k] = {corners[3 * k], corners[3 * k + 1], corners[3 * k + 2]};
    return triangle;
}

/** \brief Do the primitives \a shapes (placed by \a poseShapes) come within \a padding of the
    solid of \a bvh's mesh (placed by \a poseMesh; \a closed: it has an inside)? The test runs in
    the mesh's frame, so its triangles are read as stored; its tree's bounding spheres rule out the
    triangles beyond the primitive's reach. */
bool shapesMeetMesh(const std::vector<PrimitiveShape> &shapes, const Pose<double> &poseShapes, const MeshBvh &bvh,
                    bool closed, const Pose<double> &poseMesh, double padding)
{
    if (bvh.empty())
        return false;
    const Pose<double> inMesh = device::relativePose(poseMesh, poseShapes);  // shapes' frame -> mesh frame
    const MeshBvh::Node *nodes = bvh.nodes();
    for (const PrimitiveShape &shape : shapes)
    {
        const ConvexShape convex = placed(shape, inMesh);
        const Vec3<double> centre{convex.pose.m[3], convex.pose.m[7], convex.pose.m[11]};
        const double radius = reach(shape) + padding;
        // Tree nodes are in float: grow their spheres by a rounding allowance.
        const double slack = 1e-5 * (std::abs(centre.x) + std::abs(centre.y) + std::abs(centre.z) + nodes[0].radius);
        const device::WalkEnd end = device::walkTree(
            nodes, static_cast<std::uint32_t>(bvh.numNodes()),
            [&](const MeshBvh::Node &node)
            {
                const Vec3<double> offset{centre.x - node.centre[0], centre.y - node.centre[1],
                                          centre.z - node.centre[2]};
                const double within = node.radius + radius + slack;
                return device::dot(offset, offset) <= within * within;
            },
            [&](const MeshBvh::Node &leaf)
            {
                for (std::uint32_t slot = leaf.firstSlot(); slot < leaf.firstSlot() + leaf.count; ++slot)
                    if (device::convexWithin(convex, slotTriangle(bvh, slot), padding))
                        return false;  // within padding: stop
                return true;
            });
        if (end != device::WalkEnd::Finished)  // a triangle within padding, or (never built) a tree too deep: colliding
            return true;
        // No surface within reach: the primitive is inside the mesh's solid or wholly outside it.
        if (closed && pointInsideClosedMesh(bvh, Eigen::Vector3d(centre.x, centre.y, centre.z)))
            return true;
    }
    return false;
}

Eigen::Vector3d toEigen(const Vec3<double> &v)
{
    return Eigen::Vector3d(v.x, v.y, v.z);
}

/** \brief The nearest pair of \a a's and \a b's shapes when nearer than result.distance (the best so
    far, initially the caller's bound): result updated, true. */
bool shapesDistance(const std::vector<PrimitiveShape> &a, const Pose<double> &poseA,
                    const std::vector<PrimitiveShape> &b, const Pose<double> &poseB, SurfaceDistance &result)
{
    bool found = false;
    for (const PrimitiveShape &sa : a)
    {
        const ConvexShape ca = placed(sa, poseA);
        for (const PrimitiveShape &sb : b)
        {
            Vec3<double> onA, onB;
            const double d = device::convexClosest(ca, placed(sb, poseB), onA, onB);
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

/** \brief The nearest point pair of \a shapes (placed by \a poseShapes) and the solid of \a bvh's
    mesh (placed by \a poseMesh) when nearer than result.distance: result updated (pointA on the
    shapes, triangleB the mesh's), true. The search runs in the mesh's frame; a node is skipped when
    the ball about the primitive's origin that holds it is no nearer to the node's box or sphere
    than the best so far (less the nodes' float rounding). */
bool shapesToMeshDistance(const std::vector<PrimitiveShape> &shapes, const Pose<double> &poseShapes, const MeshBvh &bvh,
                          bool closed, const Pose<double> &poseMesh, SurfaceDistance &result)
{
    if (bvh.empty())
        return false;
    const Pose<double> inMesh = device::relativePose(poseMesh, poseShapes);  // shapes' frame -> mesh frame
    const Eigen::Isometry3d meshToWorld = fromDevicePose(poseMesh);
    const MeshBvh::Node *nodes = bvh.nodes();
    bool found = false;
    for (const PrimitiveShape &shape : shapes)
    {
        const ConvexShape convex = placed(shape, inMesh);
        const Eigen::Vector3d centre(convex.pose.m[3], convex.pose.m[7], convex.pose.m[11]);
        const double radius = reach(shape);
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
                const ConvexShape triangle = slotTriangle(bvh, slot);
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
    component, with their primitives. */
struct PairParties
{
    std::size_t a, b;
    bool environment;
    const std::vector<PrimitiveShape> *shapesA, *shapesB;
};

PairParties partiesOf(const CollisionModel &model, std::uint32_t pair)
{
    Contact named;
    model.nameParties(pair, named);
    PairParties parties;
    parties.a = static_cast<std::size_t>(named.component);
    parties.environment = named.kind == Contact::Kind::Environment;
    parties.b = static_cast<std::size_t>(parties.environment ? named.object : named.otherComponent);
    parties.shapesA = &model.robot->components[parties.a].shapes;
    parties.shapesB =
        parties.environment ? &model.scene->objects[parties.b].shapes : &model.robot->components[parties.b].shapes;
    return parties;
}
}  // namespace

bool CurvedSolids::collide(const CollisionModel &model, std::uint32_t pair, const Pose<double> &poseA,
                           const Pose<double> &poseB, double padding) const
{
    const PairParties parties = partiesOf(model, pair);
    const std::size_t a = parties.a, b = parties.b;
    const bool environment = parties.environment;
    const std::vector<PrimitiveShape> &shapesA = *parties.shapesA, &shapesB = *parties.shapesB;
    padding = std::max(0.0, padding);
    if (!shapesA.empty() && !shapesB.empty())
        return shapesWithin(shapesA, poseA, shapesB, poseB, padding);
    const MeshBvh &bvhB = environment ? *model.objectBvhs[b] : *model.componentBvhs[b];
    const bool closedB = environment ? model.objects[b].closed : model.components[b].closed;
    if (!shapesA.empty())
        return shapesMeetMesh(shapesA, poseA, bvhB, closedB, poseB, padding);
    return shapesMeetMesh(shapesB, poseB, *model.componentBvhs[a], model.components[a].closed, poseA, padding);
}

bool CurvedSolids::distance(const CollisionModel &model, std::uint32_t pair, const Pose<double> &poseA,
                            const Pose<double> &poseB, double bound, SurfaceDistance &result) const
{
    const PairParties parties = partiesOf(model, pair);
    const std::size_t a = parties.a, b = parties.b;
    const bool environment = parties.environment;
    const std::vector<PrimitiveShape> &shapesA = *parties.shapesA, &shapesB = *parties.shapesB;
    SurfaceDistance best;
    best.distance = bound;
    if (!shapesA.empty() && !shapesB.empty())
    {
        if (!shapesDistance(shapesA, poseA, shapesB, poseB, best))
            return false;
    }
    else if (!shapesA.empty())
    {
        const MeshBvh &bvhB = environment ? *model.objectBvhs[b] : *model.componentBvhs[b];
        const bool closedB = environment ? model.objects[b].closed : model.components[b].closed;
        if (!shapesToMeshDistance(shapesA, poseA, bvhB, closedB, poseB, best))
            return false;
    }
    else
    {
        // The shapes are B's: measured the other way round, then A and B swapped back.
        if (!shapesToMeshDistance(shapesB, poseB, *model.componentBvhs[a], model.components[a].closed, poseA, best))
            return false;
        std::swap(best.pointA, best.pointB);
        std::swap(best.triangleA, best.triangleB);
    }
    result = best;
    return true;
}
}  // namespace rastercheck
