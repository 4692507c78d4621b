#pragma once

// What the proofs can settle about a pair of solids (relateSolids): their whole hulls first, then
// their shells, then, for a large non-convex mesh, its patches. A non-convex solid's hull holds
// most of what comes near it (a robot in a room is inside the room's hull), so the whole-hull test
// settles little there; the patch tree (the top of the solid's one triangle tree, MeshBvh, cut
// where a subtree is a patch of a few dozen flat triangles with a hull of its own) lets the same
// plane and point proofs work on the few patches near the other solid, culled by boxes, with the
// cost growing with what is near rather than with the mesh. Runs on the host (CpuBackend) and on
// the device (BatchPipeline) alike.

#include <cstdint>

#include "rastercheck/device/ConvexClosest.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/Separation.h"
#include "rastercheck/device/Traversal.h"

namespace rastercheck::device
{
/** \brief One of a fixed set of ray directions (k in [0, kRayDirections)) with "irrational"
    components (from sqrt 2, sqrt 3, sqrt 5 and the golden ratio), all non-zero, so that no ray runs
    parallel to the axis-aligned walls and edges real meshes are full of, and no two are related by
    a simple symmetry of a box. The containment tests retry along the next one when a ray grazes. */
constexpr int kRayDirections = 8;

RC_HD Vec3<double> rayDirection(int k)
{
    const double directions[kRayDirections][3] = {
        {0.4142135623730951, 0.6180339887498949, 0.7320508075688772},
        {-0.6180339887498949, 0.7320508075688772, 0.4142135623730951},
        {0.7320508075688772, -0.4142135623730951, 0.6180339887498949},
        {-0.2360679774997897, -0.8660254037844386, 0.4472135954999579},
        {0.8660254037844386, 0.4472135954999579, -0.2360679774997897},
        {-0.4472135954999579, 0.2360679774997897, -0.8660254037844386},
        {0.5411961001461970, -0.3090169943749474, -0.7818314824680298},
        {-0.3826834323650898, -0.5411961001461970, -0.7487781956271592},
    };
    return {directions[k][0], directions[k][1], directions[k][2]};
}

/** \brief Ray origin + t direction, t >= 0, against triangle abc, for parity counting: 1 for a
    crossing of the interior that stays at least \a tolerance from every edge line, 0 for a clear
    miss (the hit point on the plane more than \a tolerance outside an edge line, the plane behind
    the origin, or the ray parallel to and off the plane), -1 when ambiguous: the hit point within
    \a tolerance of the boundary, the ray in the triangle's plane, or the origin within \a tolerance
    of the triangle. Retry along another direction on -1. A zero-area triangle is a miss (its
    neighbours in a closed mesh catch the ray). On 1, \a t receives the ray parameter of the hit. */
RC_HD int rayCrossesTriangle(const Vec3<double> &origin, const Vec3<double> &direction, const Vec3<double> &a,
                             const Vec3<double> &b, const Vec3<double> &c, double tolerance, double &t)
{
    const Vec3<double> n = cross(b - a, c - a);
    const double area2 = std::sqrt(dot(n, n));
    const double length = std::sqrt(dot(direction, direction));
    if (!(area2 > 0.0) || !(length > 0.0))
        return 0;
    const double height = dot(n, a - origin) / area2;              // signed distance from the origin to the plane
    const double approach = dot(n, direction) / (area2 * length);  // cosine of the ray to the normal
    // Near-parallel rays hit the plane far away or not at all; within 1e-12 they are treated as in
    // the plane when the origin is on it (ambiguous) and as missing otherwise.
    if ((approach < 0.0 ? -approach : approach) <= 1e-12)
        return (height < 0.0 ? -height : height) <= tolerance ? -1 : 0;
    const double distanceAlong = height / approach;  // along the ray to the plane
    if (distanceAlong < -tolerance)
        return 0;
    const Vec3<double> hit = origin + (distanceAlong / length) * direction;
    // Signed distances from the hit point to the three edge lines, positive inside.
    const Vec3<double> unitNormal = (1.0 / area2) * n;
    const Vec3<double> corners[3] = {a, b, c};
    bool nearEdge = false;
    for (int i = 0; i < 3; ++i)
    {
        const Vec3<double> edge = corners[(i + 1) % 3] - corners[i];
        const double inside = dot(unitNormal, cross(edge, hit - corners[i])) / std::sqrt(dot(edge, edge));
        if (inside < -tolerance)
            return 0;
        if (inside < tolerance)
            nearEdge = true;
    }
    if (nearEdge || distanceAlong < tolerance)
        return -1;
    t = distanceAlong / length;
    return 1;
}

/** \brief A ray of the containment test: origin + t direction, t >= 0, and the direction's
    componentwise inverse for slab tests (every rayDirection() component is non-zero). */
struct Ray
{
    Vec3<double> origin;
    Vec3<double> direction;
    Vec3<double> inverse;
};

/** \brief Slab test of \a ray against the axis-aligned box [lower, upper] grown by \a margin. */
RC_HD bool rayMeetsBox(const Ray &ray, const double lower[3], const double upper[3], double margin)
{
    const double origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
    const double inverse[3] = {ray.inverse.x, ray.inverse.y, ray.inverse.z};
    double near = 0.0, far = 1e300;
    for (int i = 0; i < 3; ++i)
    {
        const double t1 = (lower[i] - margin - origin[i]) * inverse[i];
        const double t2 = (upper[i] + margin - origin[i]) * inverse[i];
        near = near > (t1 < t2 ? t1 : t2) ? near : (t1 < t2 ? t1 : t2);
        far = far < (t1 > t2 ? t1 : t2) ? far : (t1 > t2 ? t1 : t2);
    }
    return near <= far;
}

/** \brief The point-in-solid test, for every tree of triangles (the exact phase's, MeshBvh; the
    proofs' patch trees): is \a point (the tree's frame) inside the closed solid? Signed crossings
    of a ray with the triangles (+1 leaving through an outward face, -1 entering) rather than
    parity, so that a mesh of several overlapping closed shells (a link of a cylinder and two
    spheres) contains the point when any shell does. A ray that grazes an edge, a vertex or a
    face's plane within \a tolerance (rayCrossesTriangle() says -1) is retried along the next
    rayDirection().
    When every direction grazes (a point within \a tolerance of the surface) or the walk overflows
    its stack, the answer is inside: the safe one, since a solid found inside another is a
    collision, so no doubt here ever makes a colliding state valid.
    \a rayMeetsNode(node, ray) culls a node; \a leafTriangles(leaf, visit) calls
    visit(a, b, c) for each triangle of a leaf (outward order) while visit returns true, and
    returns false when one returned false. */
template <class Node, class RayMeetsNode, class LeafTriangles>
RC_HD bool pointInsideSolid(const Node *nodes, std::uint32_t numNodes, const Vec3<double> &point, double tolerance,
                            RayMeetsNode &&rayMeetsNode, LeafTriangles &&leafTriangles)
{
    for (int k = 0; k < kRayDirections; ++k)
    {
        const Vec3<double> direction = rayDirection(k);
        const Ray ray{point, direction, Vec3<double>{1.0 / direction.x, 1.0 / direction.y, 1.0 / direction.z}};
        int winding = 0;
        const WalkEnd end = walkTree(
            nodes, numNodes, [&](const Node &node) { return rayMeetsNode(node, ray); },
            [&](const Node &leaf)
            {
                return leafTriangles(
                    leaf,
                    [&](const Vec3<double> &a, const Vec3<double> &b, const Vec3<double> &c)
                    {
                        double at = 0.0;
                        const int crossing = rayCrossesTriangle(point, direction, a, b, c, tolerance, at);
                        if (crossing == 1)
                            winding += dot(direction, cross(b - a, c - a)) > 0.0 ? 1 : -1;
                        return crossing >= 0;  // a graze ends this ray
                    });
            });
        if (end == WalkEnd::Finished)
            return winding > 0;
        if (end == WalkEnd::Overflow)
            return true;
    }
    return true;
}

/** \brief Slab test of \a ray against \a node's oriented box grown by \a margin, in double (the
    exact phase's rays), in the box's own frame. */
RC_HD bool rayMeetsTreeNode(const Ray &ray, const TreeNode &node, double margin)
{
    const float *a = node.axes;  // row-major: box axis k is (a[k], a[3 + k], a[6 + k])
    const Vec3<double> offset{ray.origin.x - node.centre[0], ray.origin.y - node.centre[1],
                              ray.origin.z - node.centre[2]};
    double near = 0.0, far = 1e300;
    for (int k = 0; k < 3; ++k)
    {
        const Vec3<double> axis{a[k], a[3 + k], a[6 + k]};
        const double o = dot(axis, offset), d = dot(axis, ray.direction);
        const double extent = node.halfExtents[k] + margin;
        if (d == 0.0)
        {
            if ((o < 0.0 ? -o : o) > extent)
                return false;
            continue;
        }
        const double t1 = (-extent - o) / d, t2 = (extent - o) / d;
        near = near > (t1 < t2 ? t1 : t2) ? near : (t1 < t2 ? t1 : t2);
        far = far < (t1 > t2 ? t1 : t2) ? far : (t1 > t2 ? t1 : t2);
    }
    return near <= far;
}

/** \brief Is \a point (the mesh's frame) inside the closed mesh of \a tree (pointInsideSolid():
    every ray grazing says inside)? \a corners: the tree's triangle corners in slot order, 9
    doubles per slot (MeshBvh::slotCorners); \a margin grows the node boxes past their float
    storage's rounding. */
RC_HD bool pointInsideTree(const TreeView &tree, const double *corners, const Vec3<double> &point, double tolerance,
                           double margin)
{
    return pointInsideSolid(
        tree.nodes, tree.numNodes, point, tolerance,
        [&](const TreeNode &node, const Ray &ray) { return rayMeetsTreeNode(ray, node, margin); },
        [&](const TreeNode &leaf, auto &&visit)
        {
            for (std::uint32_t slot = leaf.firstSlot(); slot < leaf.firstSlot() + leaf.count; ++slot)
            {
                const double *c = corners + 9 * static_cast<std::size_t>(slot);
                if (!visit(Vec3<double>{c[0], c[1], c[2]}, Vec3<double>{c[3], c[4], c[5]},
                           Vec3<double>{c[6], c[7], c[8]}))
                    return false;
            }
            return true;
        });
}

/** \brief Is \a point (the solid's own frame) inside closed solid \a solid, by its patch tree
    (pointInsideSolid(): every ray grazing says inside)? */
RC_HD bool pointInsidePatches(const ConvexArrays &arrays, std::uint32_t solid, const Vec3<double> &point,
                              double tolerance)
{
    const PatchNode *nodes = arrays.patchNodes + arrays.solidPatchNodes[solid];
    const std::uint32_t numNodes = arrays.solidPatchNodes[solid + 1] - arrays.solidPatchNodes[solid];
    return pointInsideSolid(
        nodes, numNodes, point, tolerance,
        [&](const PatchNode &node, const Ray &ray) { return rayMeetsBox(ray, node.min, node.max, tolerance); },
        [&](const PatchNode &leaf, auto &&visit)
        {
            const ConvexPiece &patch = arrays.patchPieces[-(leaf.first + 1)];
            const double *vertices = arrays.vertices + 3 * static_cast<std::size_t>(patch.firstVertex);
            const std::uint32_t *triangles = arrays.patchTriangles + 3 * static_cast<std::size_t>(patch.firstTriangle);
            const auto corner = [&](std::uint32_t v) {
                return Vec3<double>{vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]};
            };
            for (std::uint32_t t = 0; t < patch.numTriangles; ++t)
                if (!visit(corner(triangles[3 * t]), corner(triangles[3 * t + 1]), corner(triangles[3 * t + 2])))
                    return false;
            return true;
        });
}

/** \brief The box of \a piece (placed by \a pose) in the frame of \a frame, from the hull points'
    support along the frame's axes, grown by the piece's hull slack (so every vertex is inside)
    plus \a grow. */
RC_HD void boundsInFrame(const ConvexProxy &piece, const Pose<double> &pose, const Pose<double> &frame, double grow,
                         double lower[3], double upper[3])
{
    const Vec3<double> origin = translationOf(frame);
    for (int k = 0; k < 3; ++k)
    {
        const Vec3<double> axis{frame.m[k], frame.m[4 + k], frame.m[8 + k]};  // the frame's k-th axis, world
        const double offset = dot(axis, origin);
        const Vec3<double> back{-axis.x, -axis.y, -axis.z};
        upper[k] = dot(axis, detail::placedSupport(piece, pose, axis)) - offset + piece.hullSlack + grow;
        lower[k] = dot(axis, detail::placedSupport(piece, pose, back)) - offset - piece.hullSlack - grow;
    }
}

/** \brief Most face planes of a piece that patchesApart tries on the nodes of a patch tree, and the
    most plane x vertex products it spends placing them (a box has 6 x 8). */
constexpr std::uint32_t kMaxCullPlanes = 16;
constexpr std::uint32_t kMaxCullPlaneReads = 1024;

/** \brief True when every patch of \a solid's tree whose box comes within the padding of \a piece
    (placed by \a pose; the box read by boundsInFrame) is proven apart from it by relateHulls, or
    one is proven to overlap it (\a overlapping set). \a onUnknown(patchProxy) gets each patch
    neither settles and returns whether it settled it apart (and may set \a overlapping); the first
    patch it cannot settle ends the walk with false.
    A piece with a few face planes (a box, a primitive of a scene) also culls whole subtrees by
    them: each plane, moved out to the piece's farthest vertex along its normal, bounds a half-space
    that holds the piece, and a node box beyond it by more than the padding holds only patches that
    are farther than that from the piece (a proof like relateHulls' own, without its search). A
    table's box in a link's frame holds most of the link, so the box test above culls little there.
    On the Panda MotionBenchMaker problems, where the open link6 (1308 triangles, in patches) meets
    the scenes' boxes this way, the planes cut the time per certified edge by a fifth (bench/edges,
    one A/B run: 152 -> 120 us; the same verdicts). */
template <class OnUnknown>
RC_HD bool patchesApart(const ConvexArrays &arrays, std::uint32_t solid, const Pose<double> &solidPose,
                        const ConvexProxy &piece, const Pose<double> &pose, double padding, double rounding,
                        bool proveOverlap, bool &overlapping, OnUnknown &&onUnknown)
{
    double lower[3], upper[3];
    boundsInFrame(piece, pose, solidPose, padding + rounding, lower, upper);
    // The piece's planes in the solid's frame: normal and the offset a node's box must clear.
    Vec3<double> cullNormal[kMaxCullPlanes];
    double cullOffset[kMaxCullPlanes];
    std::uint32_t cullPlanes = 0;
    if (piece.numPlanes <= kMaxCullPlanes && piece.numPlanes * piece.numVertices <= kMaxCullPlaneReads)
    {
        const Pose<double> pieceInSolid = relativePose(solidPose, pose);
        const Vec3<double> shift = translationOf(pieceInSolid);
        for (std::uint32_t f = 0; f < piece.numPlanes; ++f)
        {
            const double *plane = piece.planes + 4 * f;
            const Vec3<double> normal{plane[0], plane[1], plane[2]};
            // The farthest vertex, not the face's own offset: a piece close to convex may have a
            // vertex a little in front of a face plane.
            const double reach = supportValue(piece.vertices, piece.numVertices, normal);
            cullNormal[cullPlanes] = rotateVector(pieceInSolid, normal);
            cullOffset[cullPlanes] = reach + dot(cullNormal[cullPlanes], shift) + padding + rounding;
            ++cullPlanes;
        }
    }
    const auto beyondAPlane = [&](const PatchNode &node)
    {
        for (std::uint32_t f = 0; f < cullPlanes; ++f)
        {
            const Vec3<double> &n = cullNormal[f];
            const double nearest = n.x * (n.x > 0.0 ? node.min[0] : node.max[0]) +
                                   n.y * (n.y > 0.0 ? node.min[1] : node.max[1]) +
                                   n.z * (n.z > 0.0 ? node.min[2] : node.max[2]);
            if (nearest > cullOffset[f])
                return true;
        }
        return false;
    };
    const PatchNode *nodes = arrays.patchNodes + arrays.solidPatchNodes[solid];
    const std::uint32_t numNodes = arrays.solidPatchNodes[solid + 1] - arrays.solidPatchNodes[solid];
    const WalkEnd end = walkTree(
        nodes, numNodes,
        [&](const PatchNode &node)
        {
            return !(node.min[0] > upper[0] || node.min[1] > upper[1] || node.min[2] > upper[2] ||
                     node.max[0] < lower[0] || node.max[1] < lower[1] || node.max[2] < lower[2] ||
                     beyondAPlane(node));
        },
        [&](const PatchNode &leaf)
        {
            const ConvexProxy patch = convexProxy(arrays, arrays.patchPieces[-(leaf.first + 1)]);
            const HullRelation relation = relateHulls(piece, pose, patch, solidPose, padding, proveOverlap);
            if (relation == HullRelation::Overlapping)
            {
                overlapping = true;
                return false;
            }
            return relation != HullRelation::Unknown || onUnknown(patch);
        });
    return end == WalkEnd::Finished;  // an overflow proves nothing
}

RC_HD bool hasPatches(const ConvexArrays &arrays, std::uint32_t solid)
{
    return arrays.solidPatchNodes[solid + 1] > arrays.solidPatchNodes[solid];
}

/** \brief A lower bound on the distance between \a piece (placed by \a pose) and the surface of
    solid \a solid (placed by \a solidPose) by the solid's patch tree, when it is below \a reach:
    the least hullDistanceLowerBound() of the piece against the patches whose boxes come within
    that bound of the piece's box (boundsInFrame), the bound shrinking as patches are measured;
    \a reach when none comes nearer. Each patch's triangles lie in its hull and below its nodes'
    boxes, and the piece's solid in its box, so a skipped node holds nothing nearer than the bound
    so far. Where the piece's hull meets a patch's, \a onMeeting(patch, bound) gives that patch's
    bound instead (the piece's own patches against it, or 0). The surfaces only: a solid inside
    the other is the caller's to rule out. 0 when the solid has no patches or the tree is too deep
    for the walk's stack (which proves nothing). */
template <class OnMeeting>
RC_HD double patchesLowerBound(const ConvexArrays &arrays, std::uint32_t solid, const Pose<double> &solidPose,
                               const ConvexProxy &piece, const Pose<double> &pose, double reach, OnMeeting &&onMeeting)
{
    const PatchNode *nodes = arrays.patchNodes + arrays.solidPatchNodes[solid];
    const std::uint32_t numNodes = arrays.solidPatchNodes[solid + 1] - arrays.solidPatchNodes[solid];
    if (numNodes == 0)
        return 0.0;
    const Vec3<double> ts = translationOf(solidPose), tp = translationOf(pose);
    const double rounding = kSeparationSlack * (piece.radius + arrays.pieces[arrays.solidPieces[solid]].radius +
                                                std::sqrt(dot(ts, ts)) + std::sqrt(dot(tp, tp)));
    double lower[3], upper[3];
    boundsInFrame(piece, pose, solidPose, rounding, lower, upper);
    double bound = reach;
    const WalkEnd end = walkTree(
        nodes, numNodes,
        [&](const PatchNode &node)
        {
            double gap = 0.0;  // squared distance between the node's box and the piece's
            for (int k = 0; k < 3; ++k)
            {
                const double g = fmax(0.0, fmax(node.min[k] - upper[k], lower[k] - node.max[k]));
                gap += g * g;
            }
            return gap < bound * bound;
        },
        [&](const PatchNode &leaf)
        {
            const ConvexProxy patch = convexProxy(arrays, arrays.patchPieces[-(leaf.first + 1)]);
            double d = hullDistanceLowerBound(piece, pose, patch, solidPose, bound);
            if (!(d > 0.0))
                d = onMeeting(patch, bound);
            bound = fmin(bound, d);
            return bound > 0.0;
        });
    return end == WalkEnd::Finished ? bound : 0.0;
}

/** \brief A point of \a piece's surface (its first vertex), world frame. */
RC_HD Vec3<double> surfacePoint(const ConvexProxy &piece, const Pose<double> &pose)
{
    return transformPoint(pose, Vec3<double>{piece.vertices[0], piece.vertices[1], piece.vertices[2]});
}

/** \brief Settles a pair by patches once the whole hulls and the shells could not: solid \a b's
    patches near \a a's hull (or, when both have patches, each of those that \a a's hull cannot
    settle against \a a's patches near it). Apart needs every such pair apart and then, for each
    closed solid the other might lie buried in, a ray from a point of the other that says outside
    (the surfaces being apart, one point tells for the whole of it). Overlapping when any pair is
    proven to share a point (\a proveOverlap; a ray that finds one buried in the other too).
    \a b must have patches. */
RC_HD HullRelation relatePatches(const ConvexArrays &arrays, std::uint32_t a, const Pose<double> &poseA,
                                 std::uint32_t b, const Pose<double> &poseB, double padding, bool proveOverlap)
{
    const std::uint32_t a0 = arrays.solidPieces[a], a1 = arrays.solidPieces[a + 1], b0 = arrays.solidPieces[b];
    const ConvexProxy wholeA = convexProxy(arrays, a0);
    const ConvexProxy wholeB = convexProxy(arrays, b0);
    const bool closedA = arrays.pieces[a0].closed != 0;
    const bool closedB = arrays.pieces[b0].closed != 0;
    const Vec3<double> ta = translationOf(poseA), tb = translationOf(poseB);
    // The magnitudes involved: the proofs' rounding slack and the rays' tolerance are fractions of it.
    const double scale = wholeA.radius + wholeB.radius + std::sqrt(dot(ta, ta)) + std::sqrt(dot(tb, tb));
    const double rounding = kSeparationSlack * scale;
    const bool patchesA = hasPatches(arrays, a);
    bool overlapping = false;
    const auto splitA = [&](const ConvexProxy &patchB)
    {
        // B's patch against A's patches near it, or else against each of A's shells.
        if (patchesA)
            return patchesApart(arrays, a, poseA, patchB, poseB, padding, rounding, proveOverlap, overlapping,
                                [](const ConvexProxy &) { return false; });
        for (std::uint32_t i = a0 + 1; i < a1; ++i)
        {
            const HullRelation relation =
                relateHulls(convexProxy(arrays, i), poseA, patchB, poseB, padding, proveOverlap);
            overlapping = relation == HullRelation::Overlapping;
            if (relation != HullRelation::Apart)
                return false;
        }
        return a1 - a0 > 1;
    };
    const bool apart =
        patchesApart(arrays, b, poseB, wholeA, poseA, padding, rounding, proveOverlap, overlapping, splitA);
    if (overlapping)
        return HullRelation::Overlapping;
    if (!apart)
        return HullRelation::Unknown;
    // The surfaces are apart (A's hull, or A's surface, from B's surface), so each solid lies wholly
    // inside or wholly outside the other; one point of its surface tells. B cannot lie inside A's
    // hull unless A was split into patches.
    const double tolerance = 1e-9 * scale;
    const auto buried =
        [&](const ConvexProxy &inner, const Pose<double> &innerPose, std::uint32_t outer, const Pose<double> &outerPose)
    {
        // A solid without a vertex known to be on its surface, like a point whose every ray grazed,
        // counts as inside: the safe answer.
        if (!inner.surfaceVertices)
            return proveOverlap ? HullRelation::Overlapping : HullRelation::Unknown;
        const Vec3<double> x = surfacePoint(inner, innerPose);
        if (!pointInsidePatches(arrays, outer, inverseRotate(outerPose, x - translationOf(outerPose)), tolerance))
            return HullRelation::Apart;
        return proveOverlap ? HullRelation::Overlapping : HullRelation::Unknown;
    };
    if (closedB)
    {
        const HullRelation relation = buried(wholeA, poseA, b, poseB);
        if (relation != HullRelation::Apart)
            return relation;
    }
    if (!closedA)
        return HullRelation::Apart;
    if (patchesA)
        return buried(wholeB, poseB, a, poseA);
    // A was split into shells: B could lie inside one of their hulls only; a point of B's surface
    // beyond a shell's hull along the direction from its centre shows it does not.
    if (a1 - a0 > 1 && !wholeB.surfaceVertices)
        return HullRelation::Unknown;
    const Vec3<double> pointB = surfacePoint(wholeB, poseB);
    for (std::uint32_t i = a0 + 1; i < a1; ++i)
    {
        const ConvexProxy shell = convexProxy(arrays, i);
        const Vec3<double> d = pointB - transformPoint(poseA, shell.centre);
        const double beyond = dot(d, pointB) - dot(d, detail::placedSupport(shell, poseA, d));
        if (!(beyond > (shell.hullSlack + rounding) * std::sqrt(dot(d, d))))
            return HullRelation::Unknown;
    }
    return HullRelation::Apart;
}

/** \brief relateSolids' first test alone: the two solids' whole hulls, without the scans of every
    vertex and edge (relateHulls' scanSurfaces). Its Apart and Overlapping are relateSolids' answers
    too: the scans only add overlap proofs where the simplex's own fail, and the shells and patches
    come after an Unknown. Code small enough to run at a GPU's full occupancy: the stages decide most
    pairs by it and take relateSolids in a kernel of its own for the pairs it leaves. */
RC_HD HullRelation relateWholeHulls(const ConvexArrays &arrays, std::uint32_t a, const Pose<double> &poseA,
                                    std::uint32_t b, const Pose<double> &poseB, double padding, bool proveOverlap)
{
    const std::uint32_t a0 = arrays.solidPieces[a], b0 = arrays.solidPieces[b];
    if (a0 == arrays.solidPieces[a + 1] || b0 == arrays.solidPieces[b + 1])
        return HullRelation::Unknown;
    return relateHulls(convexProxy(arrays, a0), poseA, convexProxy(arrays, b0), poseB, padding, proveOverlap, nullptr,
                       false);
}

/** \brief Are solids \a a and \a b (ConvexArrays numbering, placed by their poses) provably more
    than \a padding apart, or (with \a proveOverlap) provably overlapping? First their whole hulls;
    when those come too close and either solid is made of several shells, every shell of one
    against every shell of the other (a solid with one shell stands for itself): the solid is the
    union of its shells, each inside its own hull, so all those pairs apart means the solids are,
    and any pair of shells proven to share a point means they overlap. Nested parts of a crane
    (the boom foot between the superstructure's plates) are settled so. A large non-convex solid
    is settled by its patches (relatePatches); its whole hull is tried first, and against the
    other's shells, without the scans of every vertex and edge, which its patches do for what is
    near (on OMPL.app's Home those scans of the whole house took 60 % of the time).
    \a patchAgainstPatch: when both solids have patches, walk one's patches against the other's;
    without it such a pair is left Unknown after the hulls and shells. The walk is what keeps
    conservative mode near-exact among non-convex meshes, and the stages' proof (their exact phase
    is on the host); where the exact phase follows on the same core it costs more than it saves
    (OMPL.app's Easy and alpha-1.5, small meshes on both sides: 0.54x -> 1.24x and 0.14x -> 0.77x
    FCL in one A/B run on a loaded machine), so the CPU backend asks for it in conservative mode
    only. */
RC_HD HullRelation relateSolids(const ConvexArrays &arrays, std::uint32_t a, const Pose<double> &poseA, std::uint32_t b,
                                const Pose<double> &poseB, double padding, bool proveOverlap,
                                Vec3<double> *direction = nullptr, bool patchAgainstPatch = true)
{
    const std::uint32_t a0 = arrays.solidPieces[a], a1 = arrays.solidPieces[a + 1];
    const std::uint32_t b0 = arrays.solidPieces[b], b1 = arrays.solidPieces[b + 1];
    if (a0 == a1 || b0 == b1)
        return HullRelation::Unknown;
    const bool patchesA = hasPatches(arrays, a), patchesB = hasPatches(arrays, b);
    const HullRelation whole = relateHulls(convexProxy(arrays, a0), poseA, convexProxy(arrays, b0), poseB, padding,
                                           proveOverlap, direction, !patchesA && !patchesB);
    if (whole != HullRelation::Unknown)
        return whole;
    // Shells only when either solid has several; a pair of shells that cannot be settled ends the
    // search unless an overlap proof may still be found in another pair.
    bool allApart = a1 - a0 > 1 || b1 - b0 > 1;
    bool looking = allApart;
    const std::uint32_t aShells = a1 - a0 > 1 ? a0 + 1 : a0, bShells = b1 - b0 > 1 ? b0 + 1 : b0;
    for (std::uint32_t i = aShells; i < a1 && looking; ++i)
        for (std::uint32_t j = bShells; j < b1 && looking; ++j)
        {
            const HullRelation shells = relateHulls(convexProxy(arrays, i), poseA, convexProxy(arrays, j), poseB,
                                                    padding, proveOverlap, nullptr, !patchesA && !patchesB);
            if (shells == HullRelation::Overlapping)
                return shells;
            if (shells == HullRelation::Unknown)
            {
                allApart = false;
                looking = proveOverlap;
            }
        }
    if (allApart)
        return HullRelation::Apart;
    if (patchesA && patchesB && !patchAgainstPatch)
        return HullRelation::Unknown;
    if (patchesB)
        return relatePatches(arrays, a, poseA, b, poseB, padding, proveOverlap);
    if (patchesA)
        return relatePatches(arrays, b, poseB, a, poseA, padding, proveOverlap);
    return HullRelation::Unknown;
}
}  // namespace rastercheck::device
