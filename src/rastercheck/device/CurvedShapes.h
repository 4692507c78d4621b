#pragma once

#include <cstdint>

#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Traversal.h"

/** \file The exact decision of a pair with curved primitives (CurvedSolids), as per-element code:
    the CPU backend, the distance queries' callers and the batched stages (host executor and GPU)
    run this one implementation. */

namespace rastercheck::device
{
/** \brief The primitive shapes of every solid, in flat arrays: solid s (the components, then the
    scene objects) owns shapes[solidShapes[s] .. solidShapes[s + 1]), each placed in its solid's
    frame (link frame; world frame for objects), and reach[k], the radius of a ball about shape k's
    origin that holds it. A solid not made of primitives only owns none. */
struct CurvedArrays
{
    const ConvexShape *shapes;
    const double *reach;
    const std::uint32_t *solidShapes;
};

/** \brief \a local (in its solid's frame) placed by \a placement (solid frame -> test frame). */
RC_HD ConvexShape placedShape(const ConvexShape &local, const Pose<double> &placement)
{
    ConvexShape shape = local;
    shape.pose = compose(placement, local.pose);
    return shape;
}

/** \brief Do the shapes of solids \a a and \a b (placed by their poses) come within \a padding?
    GJK (convexWithin) on each pair of shapes. */
RC_HD bool shapesWithin(const CurvedArrays &arrays, std::uint32_t a, const Pose<double> &poseA, std::uint32_t b,
                        const Pose<double> &poseB, double padding)
{
    for (std::uint32_t i = arrays.solidShapes[a]; i < arrays.solidShapes[a + 1]; ++i)
    {
        const ConvexShape shapeA = placedShape(arrays.shapes[i], poseA);
        for (std::uint32_t j = arrays.solidShapes[b]; j < arrays.solidShapes[b + 1]; ++j)
            if (convexWithin(shapeA, placedShape(arrays.shapes[j], poseB), padding))
                return true;
    }
    return false;
}

/** \brief The triangle in slot \a slot of \a mesh (its frame) as a convex shape. */
RC_HD ConvexShape slotTriangle(const ExactTree &mesh, std::uint32_t slot)
{
    ConvexShape triangle{};
    triangle.kind = ConvexKind::Triangle;
    const double *corners = mesh.slotCorners(slot);
    for (int k = 0; k < 3; ++k)
        triangle.corner[k] = {corners[3 * k], corners[3 * k + 1], corners[3 * k + 2]};
    return triangle;
}

/** \brief The half sizes of a primitive's box in its own frame, which holds it (a cone lies in its
    cylinder's). */
RC_HD Vec3<double> shapeHalfSizes(const ConvexShape &shape)
{
    switch (shape.kind)
    {
        case ConvexKind::Box:
            return {shape.size[0], shape.size[1], shape.size[2]};
        case ConvexKind::Sphere:
            return {shape.size[0], shape.size[0], shape.size[0]};
        default:  // cylinder, cone: radius, half length along z
            return {shape.size[0], shape.size[0], shape.size[1]};
    }
}

/** \brief Do the shapes of solid \a solid (placed by \a poseShapes) come within \a padding of the
    solid of \a mesh (placed by \a poseMesh; \a closed: it has an inside)? The test runs in the
    mesh's frame, so its triangles are read as stored; its tree's bounding spheres rule out the
    triangles beyond each shape's reach. A shape that no triangle comes near is inside the mesh's
    solid or wholly outside it: one point (its origin) decides. \a hintSlot (a slot of \a mesh's
    tree, or -1): a triangle tested first, the mesh's triangle where the two meshes touched, which
    the exact shape most often meets too; it changes how soon a meeting is found, never the answer. */
RC_HD_CALL bool shapesMeetTree(const CurvedArrays &arrays, std::uint32_t solid, const Pose<double> &poseShapes,
                               const ExactTree &mesh, bool closed, const Pose<double> &poseMesh, double padding,
                               std::int32_t hintSlot = -1)
{
    if (mesh.empty())
        return false;
    const Pose<double> inMesh = relativePose(poseMesh, poseShapes);  // shapes' frame -> mesh frame
    const TreeNode *nodes = mesh.tree.nodes;
    for (std::uint32_t k = arrays.solidShapes[solid]; k < arrays.solidShapes[solid + 1]; ++k)
    {
        const ConvexShape shape = placedShape(arrays.shapes[k], inMesh);
        if (hintSlot >= 0 && static_cast<std::uint32_t>(hintSlot) < mesh.numTriangles &&
            convexWithin(shape, slotTriangle(mesh, static_cast<std::uint32_t>(hintSlot)), padding))
            return true;
        const Vec3<double> centre{shape.pose.m[3], shape.pose.m[7], shape.pose.m[11]};
        const double radius = arrays.reach[k] + padding;
        // Tree nodes are in float: grow their spheres and boxes by a rounding allowance.
        const double slack = 1e-5 * (fabs(centre.x) + fabs(centre.y) + fabs(centre.z) + nodes[0].radius);
        // The primitive's box, placed in the mesh's frame as boxesMayMeet reads a moving node.
        const double *m = shape.pose.m;
        const PlacedNode box{{{m[0], m[4], m[8]}, {m[1], m[5], m[9]}, {m[2], m[6], m[10]}}, centre};
        const Vec3<double> half = shapeHalfSizes(shape);
        const WalkEnd end = walkTree(
            nodes, mesh.tree.numNodes,
            [&](const TreeNode &node)
            {
                const Vec3<double> offset{centre.x - node.centre[0], centre.y - node.centre[1],
                                          centre.z - node.centre[2]};
                const double within = node.radius + radius + slack;
                // The ball about the shape first; then its box, which a long cylinder's ball (or a
                // flat box's) far outgrows: the slowest pairs of a 1 000-state call's exact phase
                // walked most of a Panda link's tree against a shelf's or a pole's ball.
                return dot(offset, offset) <= within * within && boxesMayMeet(node, box, half, offset, padding + slack);
            },
            [&](const TreeNode &leaf)
            {
                for (std::uint32_t slot = leaf.firstSlot(); slot < leaf.firstSlot() + leaf.count; ++slot)
                    if (convexWithin(shape, slotTriangle(mesh, slot), padding))
                        return false;  // within padding: stop
                return true;
            });
        if (end != WalkEnd::Finished)  // a triangle within padding, or (never built) a tree too deep: colliding
            return true;
        if (closed && pointInsideClosedTree(mesh, centre))
            return true;
    }
    return false;
}

/** \brief Do the exact shapes of a pair come within \a padding (>= 0)? Solid \a a is the pair's
    component (its mesh \a meshA, closed or not), \a b the object or other component (solid
    numbers as CurvedArrays'). Both made of primitives: GJK on each pair of shapes; else the
    primitives of the one side against the other's mesh (shapesMeetTree). Only for the pairs
    CurvedSolids refines: one side is made of primitives only. \a meshContact (or null): where the
    two meshes touched, whose triangle on the mesh side is tested first (shapesMeetTree's hint). */
RC_HD_CALL bool curvedPairCollides(const CurvedArrays &arrays, std::uint32_t a, const Pose<double> &poseA,
                                   const ExactTree &meshA, bool closedA, std::uint32_t b, const Pose<double> &poseB,
                                   const ExactTree &meshB, bool closedB, double padding,
                                   const ExactContact *meshContact = nullptr)
{
    padding = padding > 0.0 ? padding : 0.0;
    const bool shapesA = arrays.solidShapes[a + 1] > arrays.solidShapes[a];
    const bool shapesB = arrays.solidShapes[b + 1] > arrays.solidShapes[b];
    if (shapesA && shapesB)
        return shapesWithin(arrays, a, poseA, b, poseB, padding);
    if (shapesA)
        return shapesMeetTree(arrays, a, poseA, meshB, closedB, poseB, padding, meshContact ? meshContact->slotB : -1);
    return shapesMeetTree(arrays, b, poseB, meshA, closedA, poseA, padding, meshContact ? meshContact->slotA : -1);
}
}  // namespace rastercheck::device
