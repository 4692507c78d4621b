#pragma once

// The exact narrow phase, for both backends: do two meshes' surfaces come within a padding (a
// simultaneous walk of their triangle trees, device::walkPairs, with the exact triangle tests at the
// leaves), and does one closed solid hold the other (its inside grid, else rays over its tree)? The
// CPU backend calls it through geometry/MeshBvh (with a cache of placed nodes and leaf hints in its
// workspace), the batched stages per open pair (without them: one thread per pair on the GPU).

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/Traversal.h"
#include "rastercheck/device/TriangleTests.h"

namespace rastercheck::device
{
/** \brief What the float storage of the nodes may be off by, as a fraction of the coordinates'
    magnitude: their axes depart from orthonormal by a few float ulps (about 1e-7), so a corner may
    sit that fraction of the node's size outside its stored box. Ten times that is the slack every
    node test adds; it only keeps more pairs. */
constexpr double kNodeRounding = 1e-6;

/** \brief A closed mesh's grid of inside/outside facts (MeshBvh builds it): a regular grid over its
    bounds, one byte per cell, x fastest (0 near the surface, 1 outside, 2 inside). */
struct InsideGrid
{
    double lower[3];
    double inverseCell[3];
    std::int32_t size[3];  // 0 x 0 x 0: no grid (a built grid has at least one cell a side)
};

/** \brief One mesh as the exact phase reads it (mesh frame): its tree, its triangles' corners in
    slot order (9 doubles each), its inside grid, and per connected shell a few probe points
    (containment tests: when two surfaces do not meet, any point of a shell is inside the other
    solid exactly when the whole shell is). */
struct ExactTree
{
    TreeView tree;
    std::uint32_t numTriangles;
    const double *corners;
    InsideGrid grid;
    const std::uint8_t *gridCells;         // null without a grid
    const double *probePoints;             // 3 doubles per probe
    const std::uint32_t *shellProbeStart;  // numShells + 1: shell s's probes are [start[s], start[s + 1])
    std::uint32_t numShells;

    RC_HD bool empty() const { return tree.numNodes == 0; }
    RC_HD const double *slotCorners(std::uint32_t slot) const { return corners + 9 * static_cast<std::size_t>(slot); }
    RC_HD Vec3<double> probe(std::uint32_t k) const
    {
        return {probePoints[3 * k], probePoints[3 * k + 1], probePoints[3 * k + 2]};
    }
};

/** \brief One mesh's place in its party's flat exact-phase arrays (ExactArrays): the batched
    stages form its ExactTree from them in any memory (exactTreeOf). */
struct ExactMeshInfo
{
    InsideGrid grid;
    std::uint64_t firstGridCell;
    std::uint32_t firstProbe;  // probe number (3 doubles each) of its first probe
    std::uint32_t firstShell;  // its numShells + 1 shell starts (its own probe numbers) begin here
    std::uint32_t numShells;
};

/** \brief The exact-phase arrays of one party (components or objects), every mesh's concatenated:
    corners per MeshSlice::firstTriangle, the rest per ExactMeshInfo. */
struct ExactArrays
{
    const double *corners;
    const std::uint8_t *gridCells;
    const double *probePoints;
    const std::uint32_t *shellProbeStart;
    const ExactMeshInfo *meshes;
};

/** \brief Mesh \a mesh of a party, its tree's nodes and triangle order at \a tree. */
RC_HD ExactTree exactTreeOf(const ExactArrays &arrays, std::uint32_t mesh, const TreeView &tree,
                            std::uint32_t firstTriangle, std::uint32_t numTriangles)
{
    const ExactMeshInfo &info = arrays.meshes[mesh];
    ExactTree t;
    t.tree = tree;
    t.numTriangles = numTriangles;
    t.corners = arrays.corners + 9 * static_cast<std::size_t>(firstTriangle);
    t.grid = info.grid;
    t.gridCells = info.grid.size[0] > 0 ? arrays.gridCells + info.firstGridCell : nullptr;
    t.probePoints = arrays.probePoints + 3 * static_cast<std::size_t>(info.firstProbe);
    t.shellProbeStart = arrays.shellProbeStart + info.firstShell;
    t.numShells = info.numShells;
    return t;
}

/** \brief A node's centre, and axis j (a column of its row-major axes), in double. */
RC_HD Vec3<double> nodeCentreOf(const TreeNode &node)
{
    return {node.centre[0], node.centre[1], node.centre[2]};
}
RC_HD Vec3<double> nodeAxisOf(const TreeNode &node, int j)
{
    return {node.axes[j], node.axes[3 + j], node.axes[6 + j]};
}

/** \brief Is \a p (the tree's frame) in the node's box grown by \a margin? */
RC_HD bool nodeHolds(const TreeNode &node, const Vec3<double> &p, double margin)
{
    const Vec3<double> offset = p - nodeCentreOf(node);
    for (int j = 0; j < 3; ++j)
        if (std::fabs(dot(nodeAxisOf(node, j), offset)) > node.halfExtents[j] + margin)
            return false;
    return true;
}

/** \brief A magnitude of a tree's coordinates: its root's radius plus its distance from the origin. */
RC_HD double treeScale(const ExactTree &t)
{
    const Vec3<double> centre = nodeCentreOf(t.tree.nodes[0]);
    return t.tree.nodes[0].radius + std::sqrt(dot(centre, centre));
}

/** \brief What the inside grid knows of \a point (mesh frame): 1 outside, 2 inside, 0 not known
    (its cell is near the surface, or there is no grid). */
RC_HD int insideGridAnswer(const ExactTree &t, const Vec3<double> &point)
{
    if (!t.gridCells)
        return 0;
    int cell[3];
    for (int k = 0; k < 3; ++k)
    {
        const double at = (point[k] - t.grid.lower[k]) * t.grid.inverseCell[k];
        // Beyond the grid (grown past every vertex) is outside; NaN is too, as the ray would say.
        if (!(at >= 0.0 && at < t.grid.size[k]))
            return 1;
        cell[k] = static_cast<int>(at);
    }
    return t.gridCells[(static_cast<std::size_t>(cell[2]) * t.grid.size[1] + cell[1]) * t.grid.size[0] + cell[0]];
}

/** \brief Is \a point (mesh frame) strictly inside the closed mesh? The inside grid answers when it
    knows the point's cell; otherwise pointInsideTree(): a ray's signed crossings, retried along
    another direction whenever it grazes (within 1e-9 of the mesh's size of an edge or vertex, or
    in a face's plane); every direction grazing (a point that close to the surface) says inside,
    the safe answer. */
RC_HD_CALL bool pointInsideClosedTree(const ExactTree &t, const Vec3<double> &point)
{
    const int known = insideGridAnswer(t, point);
    if (known != 0)
        return known == 2;
    if (t.empty())
        return false;
    const TreeNode &root = t.tree.nodes[0];
    const Vec3<double> fromCentre = point - nodeCentreOf(root);
    // Large against the rounding of the ray/triangle arithmetic (1e-16 of these magnitudes), small
    // against any feature a mesh is meant to resolve.
    const double tolerance = 1e-9 * (2.0 * root.radius + std::sqrt(dot(fromCentre, fromCentre)));
    const double margin = tolerance + kNodeRounding * (treeScale(t) + std::sqrt(dot(point, point)));
    if (!nodeHolds(root, point, margin))
        return false;
    return pointInsideTree(t.tree, t.corners, point, tolerance, margin);
}

/** \brief A node of the moving tree placed in the fixed tree's frame: its axes and centre. */
struct PlacedNode
{
    Vec3<double> axis[3];
    Vec3<double> centre;
};

/** \brief For the last queries of a pair of trees: the leaf pair (triangle slots) where the last
    query found its contact or, when it found none, the leaf pair whose bounding spheres came
    nearest (keyed by the trees' node arrays). */
struct LeafHint
{
    const void *fixed = nullptr;
    const void *moving = nullptr;
    std::uint32_t slotFixed = 0, slotMoving = 0;
};

/** \brief What a caller may lend the exact phase to go faster (the CPU backend's workspace; the
    GPU's threads lend nothing). \a placed / \a stamps (capacity entries): the moving tree's nodes
    placed once per query, stamped by query so nothing is cleared between queries (a tree with more
    nodes than that is placed per visit). \a hints (numHints): leaf hints by pair of trees; a query
    that asks no contact first tests its pair's hinted leaf pair (nearby states often touch there
    again). Neither changes an answer. */
struct ExactScratch
{
    PlacedNode *placed = nullptr;
    std::uint32_t *stamps = nullptr;
    std::size_t capacity = 0;
    std::uint32_t *query = nullptr;  // the stamp of the current query, kept by the lender
    LeafHint *hints = nullptr;
    std::size_t numHints = 0;
};

/** \brief Starts a query that places a moving tree of \a numNodes nodes: true when \a scratch caches
    them, its stamp then advanced (stamps that wrapped are cleared). */
RC_HD bool beginPlacing(ExactScratch *scratch, std::uint32_t numNodes)
{
    if (!scratch || !scratch->placed || numNodes > scratch->capacity)
        return false;
    if (++*scratch->query == 0)  // the stamps wrapped: forget them all
    {
        for (std::size_t k = 0; k < scratch->capacity; ++k)
            scratch->stamps[k] = 0;
        *scratch->query = 1;
    }
    return true;
}

/** \brief Node \a index of \a nodes placed by \a place: from the scratch's cache when \a cached
    (placed there on first use in this query), else into \a visit. */
RC_HD const PlacedNode &placedNode(const TreeNode *nodes, std::int32_t index, const Pose<double> &place,
                                   ExactScratch *scratch, bool cached, PlacedNode &visit)
{
    PlacedNode &slot = cached ? scratch->placed[index] : visit;
    if (!cached || scratch->stamps[index] != *scratch->query)
    {
        const TreeNode &node = nodes[index];
        for (int j = 0; j < 3; ++j)
            slot.axis[j] = rotateVector(place, nodeAxisOf(node, j));
        slot.centre = transformPoint(place, nodeCentreOf(node));
        if (cached)
            scratch->stamps[index] = *scratch->query;
    }
    return slot;
}

/** \brief Separating-axis test (Gottschalk's 15 axes) of a fixed-tree node's box against a box
    placed in the fixed frame (\a pm: its axes and centre, at \a between from the fixed box's centre;
    \a extentsB: its half extents along those axes), a moving-tree node's or a primitive's: false
    when some axis shows a gap wider than \a reach. Lazy: the fixed box's face
    axes first, one row of the relative rotation at a time (on FCL's env/rob, 73 % of the rejections
    come from those three axes), and a moving box whose centre lies in the fixed box meets it
    without further test. The cross-product axes are not normalised; their length is at most 1, so
    comparing their projected gap against the full reach only keeps more pairs. */
RC_HD_CALL bool boxesMayMeet(const TreeNode &nf, const PlacedNode &pm, const Vec3<double> &extentsB,
                             const Vec3<double> &between, double reach)
{
    const float *f = nf.axes;  // row-major: the fixed box's axis i is (f[i], f[3 + i], f[6 + i])
    const double ea[3] = {nf.halfExtents[0], nf.halfExtents[1], nf.halfExtents[2]};
    const double eb[3] = {extentsB.x, extentsB.y, extentsB.z};
    double d[3];
    for (int i = 0; i < 3; ++i)
        d[i] = f[i] * between.x + f[3 + i] * between.y + f[6 + i] * between.z;
    if (std::fabs(d[0]) <= ea[0] && std::fabs(d[1]) <= ea[1] && std::fabs(d[2]) <= ea[2])
        return true;
    double R[3][3], Q[3][3];  // R(i, j) = axis i of the fixed box . axis j of the moving box; Q = |R|
    for (int i = 0; i < 3; ++i)
    {
        const double a0 = f[i], a1 = f[3 + i], a2 = f[6 + i];
        for (int j = 0; j < 3; ++j)
        {
            R[i][j] = a0 * pm.axis[j].x + a1 * pm.axis[j].y + a2 * pm.axis[j].z;
            Q[i][j] = std::fabs(R[i][j]);
        }
        if (std::fabs(d[i]) > ea[i] + Q[i][0] * eb[0] + Q[i][1] * eb[1] + Q[i][2] * eb[2] + reach)
            return false;
    }
    for (int j = 0; j < 3; ++j)
        if (std::fabs(d[0] * R[0][j] + d[1] * R[1][j] + d[2] * R[2][j]) >
            ea[0] * Q[0][j] + ea[1] * Q[1][j] + ea[2] * Q[2][j] + eb[j] + reach)
            return false;
    for (int i = 0; i < 3; ++i)
    {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j)
        {
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const double gap = std::fabs(d[i2] * R[i1][j] - d[i1] * R[i2][j]);
            const double radii = ea[i1] * Q[i2][j] + ea[i2] * Q[i1][j] + eb[j1] * Q[i][j2] + eb[j2] * Q[i][j1];
            if (gap > radii + reach)
                return false;
        }
    }
    return true;
}

/** \brief Nothing found yet: the value the lowest index that found a contact or an overlap starts
    from (WalkPart::earliestFound, the stages' per-state first overlap). */
constexpr unsigned long long kNoneFound = ~0ull;

/** \brief Whether what others found stops \a own (a walk's part, a state's pair): \a found, the
    lowest index (walk or pair order) that found a contact or an overlap, stops it when earlier, so
    the first in order is still found; with \a anyFound (the caller reads no contact, any decides)
    when it is any other. */
RC_HD bool stoppedByFound(unsigned long long found, unsigned long long own, bool anyFound)
{
    return anyFound ? found != kNoneFound && found != own : found < own;
}

/** \brief One part of a walk split among threads (walkPartStart): its index of 2^depth parts, in
    walk order, and where the parts lower the index of the earliest part that found a contact
    (atomicMinimum; null: the part runs to its end). The whole walk by default. */
struct WalkPart
{
    std::uint32_t index = 0;
    std::uint32_t depth = 0;
    const unsigned long long *earliestFound = nullptr;
    /** \brief Stop once any part, or any other pair of the state, has found a contact, not only an
        earlier one (stoppedByFound): for a caller that reads whether a state collides and not
        where (StageSettings::firstContacts false). The first contact is then in no part's hands,
        but the parts and pairs, which a device runs at once, end with the first contact found
        anywhere instead of waiting for the earlier ones' walks (docs/benchmarks.md "Any contact
        decides where none is read"). */
    bool anyContact = false;
    /** \brief Where the stages note the lowest pair element of the walk's state that overlaps
        (noteOverlap; null: not read), and the walk's own: the walk stops once an earlier pair of
        the state overlaps (any other, with anyContact), as the CPU backend stops at a state's first
        colliding pair. */
    const unsigned long long *stateFirstOverlap = nullptr;
    unsigned long long pairElement = 0;
};

/** \brief The surface query for walkPairs, with the fixed tree's frame as the working frame and the
    moving tree placed there by \a place: bounding spheres, then boxesMayMeet(), both grown by
    \a reach; leaf pairs by the triangle tests, in the caller's order (a, b) (\a movingIsA says which
    tree is A). Stops at the first contact. */
struct SurfaceQuery
{
    const ExactTree &fixed, &moving;
    Pose<double> place;  // moving frame -> fixed frame
    bool movingIsA;
    double padding, reach;
    ExactScratch *scratch;  // null or without a cache: nodes placed per visit
    bool cached;
    LeafHint *hint;
    Vec3<double> *point;  // receives the contact's point (working frame)
    PlacedNode visit{};
    Vec3<double> between{0.0, 0.0, 0.0};  // of the pair last tested: the moving node's centre less the fixed one's
    double nearestGap = HUGE_VAL;
    std::uint32_t slotFixed = 0, slotMoving = 0;
    WalkPart part{};  // the walk's part (whose start surfacesWithin finds: walkPartStart)

    RC_HD const PlacedNode &placed(std::int32_t index)
    {
        return placedNode(moving.tree.nodes, index, place, scratch, cached, visit);
    }

    RC_HD Vec3<double> corner(const double *c, int k) const { return {c[3 * k], c[3 * k + 1], c[3 * k + 2]}; }

    // The moving tree's triangle in slot sm, placed in the working frame.
    RC_HD void placeTriangle(std::uint32_t sm, Vec3<double> placedTriangle[3]) const
    {
        const double *cm = moving.slotCorners(sm);
        for (int k = 0; k < 3; ++k)
            placedTriangle[k] = transformPoint(place, corner(cm, k));
    }

    RC_HD bool triangles(std::uint32_t sf, const Vec3<double> placedTriangle[3]) const
    {
        const double *cf = fixed.slotCorners(sf);
        const Vec3<double> fixedTriangle[3] = {corner(cf, 0), corner(cf, 1), corner(cf, 2)};
        const Vec3<double> *ta = movingIsA ? placedTriangle : fixedTriangle;
        const Vec3<double> *tb = movingIsA ? fixedTriangle : placedTriangle;
        return padding > 0.0 ? trianglesWithin(ta[0], ta[1], ta[2], tb[0], tb[1], tb[2], padding, point)
                             : trianglesIntersect(ta[0], ta[1], ta[2], tb[0], tb[1], tb[2], point);
    }

    RC_HD void remember(std::uint32_t sf, std::uint32_t sm)
    {
        if (!hint)
            return;
        hint->fixed = fixed.tree.nodes;
        hint->moving = moving.tree.nodes;
        hint->slotFixed = sf;
        hint->slotMoving = sm;
    }

    RC_HD bool test(NodePair pair)
    {
        // A part stops once an earlier part has found a contact: the walk's first contact is not
        // in this one; or once an earlier pair of its state overlaps: the pair is not read (any
        // other part or pair, with anyContact). Its pairs still on the stack are dropped unread.
        if (part.earliestFound && stoppedByFound(atomicLoad(part.earliestFound), part.index, part.anyContact))
            return false;
        if (part.stateFirstOverlap &&
            stoppedByFound(atomicLoad(part.stateFirstOverlap), part.pairElement, part.anyContact))
            return false;
        const TreeNode &nf = fixed.tree.nodes[pair.a], &nm = moving.tree.nodes[pair.b];
        const PlacedNode &pm = placed(pair.b);
        // Bounding spheres first: they settle most pairs that are far apart for one dot product.
        between = pm.centre - nodeCentreOf(nf);
        const double spheres = static_cast<double>(nf.radius) + nm.radius + reach;
        if (dot(between, between) > spheres * spheres)
            return false;
        return boxesMayMeet(nf, pm, {nm.halfExtents[0], nm.halfExtents[1], nm.halfExtents[2]}, between, reach);
    }

    RC_HD bool leaves(NodePair pair)
    {
        const TreeNode &nf = fixed.tree.nodes[pair.a], &nm = moving.tree.nodes[pair.b];
        Vec3<double> placedTriangle[3];
        for (std::uint32_t sm = nm.firstSlot(); sm < nm.firstSlot() + nm.count; ++sm)
        {
            placeTriangle(sm, placedTriangle);
            for (std::uint32_t sf = nf.firstSlot(); sf < nf.firstSlot() + nf.count; ++sf)
                if (triangles(sf, placedTriangle))
                {
                    remember(sf, sm);
                    slotFixed = sf;
                    slotMoving = sm;
                    return false;
                }
        }
        const double gap = std::sqrt(dot(between, between)) - (static_cast<double>(nf.radius) + nm.radius);
        if (gap < nearestGap)
        {
            nearestGap = gap;
            remember(nf.firstSlot(), nm.firstSlot());
        }
        return true;
    }

    // Descend into the bigger node, so both trees shrink at a similar pace.
    RC_HD bool splitA(NodePair pair) const
    {
        return fixed.tree.nodes[pair.a].radius >= moving.tree.nodes[pair.b].radius;
    }

    // The child nearer the other node first: in a colliding state the contact is more likely
    // there, and the walk stops at the first one.
    RC_HD bool secondFirst(NodePair first, NodePair second)
    {
        if (first.a != second.a)
        {
            const Vec3<double> centre = placed(first.b).centre;
            const Vec3<double> toSecond = nodeCentreOf(fixed.tree.nodes[second.a]) - centre;
            const Vec3<double> toFirst = nodeCentreOf(fixed.tree.nodes[first.a]) - centre;
            return dot(toSecond, toSecond) < dot(toFirst, toFirst);
        }
        // One at a time: placed() may hand back the same scratch node for both.
        const Vec3<double> fixedCentre = nodeCentreOf(fixed.tree.nodes[first.a]);
        const Vec3<double> second2 = placed(second.b).centre - fixedCentre;
        const double toSecond = dot(second2, second2);
        const Vec3<double> first2 = placed(first.b).centre - fixedCentre;
        return toSecond < dot(first2, first2);
    }
};

/** \brief Where two meshes touch: a point (world frame) and the triangle of each mesh (-1 when found
    by containment, with no surface crossing, or when a walk outgrew its stack), as its number in
    the mesh and its slot in the mesh's tree (ExactTree::slotCorners). */
struct ExactContact
{
    Vec3<double> position{0.0, 0.0, 0.0};
    std::int32_t triangleA = -1;
    std::int32_t triangleB = -1;
    std::int32_t slotA = -1;
    std::int32_t slotB = -1;
};

/** \brief The surface query of A (placed by \a poseA) and B (placed by \a poseB) within \a padding
    (negative counts as 0): the tree with fewer nodes is the one moved (its nodes placed once per
    query); the other's frame is the working frame, where the moved tree's triangles are placed by
    one transform before the exact tests. \a point receives a contact's point (working frame). */
RC_HD SurfaceQuery surfaceQuery(const ExactTree &a, const Pose<double> &poseA, const ExactTree &b,
                                const Pose<double> &poseB, double padding, ExactScratch *scratch, Vec3<double> *point)
{
    padding = padding > 0.0 ? padding : 0.0;
    const bool movingIsA = a.tree.numNodes <= b.tree.numNodes;
    const ExactTree &fixed = movingIsA ? b : a, &moving = movingIsA ? a : b;
    const Pose<double> place = relativePose(movingIsA ? poseB : poseA, movingIsA ? poseA : poseB);
    const Vec3<double> shift{place.m[3], place.m[7], place.m[11]};
    // The node tests must never drop a pair the triangle test would accept: the slack covers the
    // nodes' float storage (kNodeRounding) and the rounding of the transform and the projections.
    const double reach = padding + kNodeRounding * (std::sqrt(dot(shift, shift)) + treeScale(a) + treeScale(b));
    const bool cached = beginPlacing(scratch, moving.tree.numNodes);
    LeafHint *hint = nullptr;
    if (scratch && scratch->hints && scratch->numHints > 0)
    {
        const auto key = reinterpret_cast<unsigned long long>(fixed.tree.nodes) * 0x9E3779B97F4A7C15ull ^
                         reinterpret_cast<unsigned long long>(moving.tree.nodes) * 0xC2B2AE3D27D4EB4Full;
        hint = scratch->hints + (key >> 32) % scratch->numHints;
    }
    return SurfaceQuery{fixed, moving, place, movingIsA, padding, reach, scratch, cached, hint, point};
}

/** \brief Do the surfaces of A (placed by \a poseA) and B (placed by \a poseB) come within
    \a padding (metres; 0 = intersect or touch; negative counts as 0)? Simultaneous traversal of
    both trees, descending the larger node first; node pairs are culled by their bounding spheres,
    then by boxesMayMeet(), both grown by \a padding plus a rounding slack (kNodeRounding of the
    coordinates' magnitude), and leaf pairs decided by trianglesIntersect() (padding 0) or
    trianglesWithin() (padding > 0) with the smaller tree's triangles placed in the other's frame.
    So the answer is exact for the coordinates after that one rigid transform. Stops at the first
    contact found, which \a contact (when not null) receives: for padding > 0 the midpoint of a
    close-enough pair. With a leaf hint in \a scratch and without \a contact the query first tests
    the leaf pair where the last query of the same two trees touched or came nearest; that may
    change which contact is found first, never the answer, so a query with \a contact skips it and
    its first contact does not depend on earlier queries. A tree too deep for the walk's stack
    (which MeshBvh's builder rules out) answers true, with no triangles named. \a part: walk only
    its part (walkPartStart, in the query's numbering), and stop with false once an earlier part has
    found a contact; the whole walk by default. The parts of a walk, one after the other, decide
    as the whole walk does, and the first in order that finds a contact finds its first contact. */
RC_HD_CALL bool surfacesWithin(const ExactTree &a, const Pose<double> &poseA, const ExactTree &b,
                               const Pose<double> &poseB, double padding, ExactContact *contact = nullptr,
                               ExactScratch *scratch = nullptr, WalkPart part = WalkPart{})
{
    if (a.empty() || b.empty())
        return false;
    Vec3<double> point{0.0, 0.0, 0.0};
    SurfaceQuery query = surfaceQuery(a, poseA, b, poseB, padding, scratch, &point);
    query.part = part;
    const ExactTree &fixed = query.fixed, &moving = query.moving;
    const bool movingIsA = query.movingIsA;
    LeafHint *hint = query.hint;
    // A caller that asks for the contact gets the walk's own first one, independent of what this
    // scratch saw before (the backends promise the same first contacts); the others may start
    // from the remembered leaf pair.
    if (!contact && hint && hint->fixed == fixed.tree.nodes && hint->moving == moving.tree.nodes &&
        hint->slotFixed < fixed.numTriangles && hint->slotMoving < moving.numTriangles)
    {
        Vec3<double> placedTriangle[3];
        query.placeTriangle(hint->slotMoving, placedTriangle);
        if (query.triangles(hint->slotFixed, placedTriangle))
            return true;
    }
    NodePair start{0, 0};
    if (part.depth > 0 && !walkPartStart(fixed.tree.nodes, moving.tree.nodes, query, part.index, part.depth, start))
        return false;
    const WalkEnd end = walkPairs(fixed.tree.nodes, moving.tree.nodes, query, start);
    if (end == WalkEnd::Finished)
        return false;
    const Pose<double> &fixedPose = movingIsA ? poseB : poseA;
    if (contact && end == WalkEnd::Overflow)  // the safe answer, with no triangle to name
    {
        contact->position = transformPoint(fixedPose, nodeCentreOf(fixed.tree.nodes[0]));
        contact->triangleA = contact->triangleB = contact->slotA = contact->slotB = -1;
    }
    else if (contact)
    {
        contact->position = transformPoint(fixedPose, point);
        const auto triangleFixed = static_cast<std::int32_t>(fixed.tree.triangleOrder[query.slotFixed]);
        const auto triangleMoving = static_cast<std::int32_t>(moving.tree.triangleOrder[query.slotMoving]);
        contact->triangleA = movingIsA ? triangleMoving : triangleFixed;
        contact->triangleB = movingIsA ? triangleFixed : triangleMoving;
        const auto slotFixed = static_cast<std::int32_t>(query.slotFixed);
        const auto slotMoving = static_cast<std::int32_t>(query.slotMoving);
        contact->slotA = movingIsA ? slotMoving : slotFixed;
        contact->slotB = movingIsA ? slotFixed : slotMoving;
    }
    return true;
}

/** \brief Is some shell of \a inner (placed by \a innerPose) inside the closed solid \a outer (placed
    by \a outerPose), given that their surfaces do not meet? Each shell lies wholly inside or wholly
    outside, so any one of its points tells: the first probe the outer mesh's inside grid knows
    answers, and a ray is cast only when it knows none (near-contact states of OMPL.app's Home: 80 %
    of the free states needed a ray from the first vertex alone, 9 % with the probes). */
RC_HD_CALL bool shellInside(const ExactTree &inner, const Pose<double> &innerPose, const ExactTree &outer,
                            const Pose<double> &outerPose, ExactContact *contact)
{
    const Pose<double> innerToOuter = relativePose(outerPose, innerPose);
    for (std::uint32_t shell = 0; shell < inner.numShells; ++shell)
    {
        int known = 0;
        Vec3<double> probe{0.0, 0.0, 0.0};
        for (std::uint32_t k = inner.shellProbeStart[shell]; k < inner.shellProbeStart[shell + 1]; ++k)
        {
            probe = inner.probe(k);
            known = insideGridAnswer(outer, transformPoint(innerToOuter, probe));
            if (known != 0)
                break;
        }
        if (known == 0)
            probe = inner.probe(inner.shellProbeStart[shell]);
        if (known == 0 ? !pointInsideClosedTree(outer, transformPoint(innerToOuter, probe)) : known == 1)
            continue;
        if (contact)
        {
            contact->position = transformPoint(innerPose, probe);
            contact->triangleA = contact->triangleB = contact->slotA = contact->slotB = -1;
        }
        return true;
    }
    return false;
}

/** \brief The containment half of solidsOverlap, for solids whose surfaces do not meet: does a shell
    of one lie inside the other (tested for closed meshes only: \a closedA / \a closedB)? On
    containment \a contact gets the inner shell's probe (world frame) and triangles -1. */
RC_HD bool solidsContain(const ExactTree &a, const Pose<double> &poseA, bool closedA, const ExactTree &b,
                         const Pose<double> &poseB, bool closedB, ExactContact *contact)
{
    if (a.empty() || b.empty())
        return false;
    return (closedB && shellInside(a, poseA, b, poseB, contact)) ||
           (closedA && shellInside(b, poseB, a, poseA, contact));
}

/** \brief The exact oracle for two solids: true when their surfaces come within \a padding or one
    contains the other (tested for closed meshes only: \a closedA / \a closedB). On containment
    \a contact gets the inner shell's probe (world frame) and triangles -1. */
RC_HD bool solidsOverlap(const ExactTree &a, const Pose<double> &poseA, bool closedA, const ExactTree &b,
                         const Pose<double> &poseB, bool closedB, double padding, ExactContact *contact = nullptr,
                         ExactScratch *scratch = nullptr)
{
    return surfacesWithin(a, poseA, b, poseB, padding, contact, scratch) ||
           solidsContain(a, poseA, closedA, b, poseB, closedB, contact);
}
}  // namespace rastercheck::device
