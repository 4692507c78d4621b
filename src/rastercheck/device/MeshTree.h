#pragma once

// Every mesh's triangle hierarchy as flat arrays that the CPU and the GPU read alike: the nodes
// geometry/MeshBvh builds (oriented boxes in the mesh's own frame), and per mesh the order of its
// triangles in the leaves. The batched stages walk them (walkTree below) per surviving pair to pick
// the triangles a pair's image can see, so no stage scans a whole large mesh; the exact phase
// (device/ExactPhase.h) walks them tree against tree, on both backends.

#include <cstdint>

#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Raster.h"
#include "rastercheck/device/Traversal.h"

namespace rastercheck::device
{
/** \brief One node of a mesh's triangle hierarchy: an oriented box with a bounding sphere, in the
    mesh's frame, 72 bytes. Children and triangle slots are numbered within the mesh's own tree. */
struct TreeNode
{
    float axes[9];         ///< row-major 3x3 matrix whose columns are the box's axes (mesh frame)
    float centre[3];       ///< box centre (mesh frame)
    float halfExtents[3];  ///< along the three axes
    float radius;          ///< bounding sphere about the centre
    /** \brief Inner node: index of the first child (the second is first + 1), >= 0.
        Leaf: -(1 + first triangle slot) into the tree's triangle order. */
    std::int32_t first;
    std::uint32_t count;  ///< leaf: number of triangles; inner: 0

    RC_HD bool isLeaf() const { return first < 0; }
    RC_HD std::uint32_t firstSlot() const { return static_cast<std::uint32_t>(-(first + 1)); }
};

/** \brief One mesh's tree in the flat arrays: its nodes, root first, and the triangle numbers
    (within the mesh) in slot order. */
struct TreeView
{
    const TreeNode *nodes;
    const std::uint32_t *triangleOrder;
    std::uint32_t numNodes;
};

/** \brief Where a node's box, placed, lies against a raster image (nodeAgainstImage). */
enum class ImageSide
{
    Outside,  ///< no triangle below it meets the image
    Meets,    ///< some may
    Inside    ///< well inside: every node below it meets the image too
};

/** \brief Whether the node, placed by \a placement, may hold a triangle whose projection along the
    grid's axis meets the image rectangle grown by \a margin (triangleMeetsImage's test): the box's
    extent along the two image axes, grown by a slack that covers the float rounding of the node
    and of the placement (a few 1e-7 of the coordinates in play; 4e-6 of them is kept, which only
    keeps more nodes). Inside: the box's extent lies within the rectangle shrunk by that slack, so
    every triangle below (each node holds its subtree's corners, up to the float storage's rounding)
    meets the image, and so does every node between. */
RC_HD ImageSide nodeAgainstImage(const TreeNode &node, const Pose<float> &placement, const RasterGrid &grid,
                                 float margin)
{
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    const float *m = placement.m;
    const float *a = node.axes;
    const float magnitude = fabsf(node.centre[0]) + fabsf(node.centre[1]) + fabsf(node.centre[2]) + node.radius +
                            fabsf(m[3]) + fabsf(m[7]) + fabsf(m[11]);
    const float slack = 4e-6f * magnitude;
    const float reach = margin + slack;
    const float lower[2] = {grid.origin[0], grid.origin[1]};
    const float upper[2] = {grid.origin[0] + grid.width * grid.pixel, grid.origin[1] + grid.height * grid.pixel};
    const int rows[2] = {u, v};
    bool inside = true;
    for (int k = 0; k < 2; ++k)
    {
        const float *r = m + 4 * rows[k];  // the placement's row for this image axis
        const float centre = r[0] * node.centre[0] + r[1] * node.centre[1] + r[2] * node.centre[2] + r[3];
        float half = 0;
        for (int j = 0; j < 3; ++j)  // |row . axis j| * extent j
            half += fabsf(r[0] * a[j] + r[1] * a[3 + j] + r[2] * a[6 + j]) * node.halfExtents[j];
        if (centre + half < lower[k] - reach || centre - half > upper[k] + reach)
            return ImageSide::Outside;
        inside = inside && centre - half >= lower[k] + slack && centre + half <= upper[k] - slack;
    }
    return inside ? ImageSide::Inside : ImageSide::Meets;
}

/** \brief The slots [\a begin, \a end) of the triangles below \a node: a subtree's leaves hold
    consecutive slots, its first child's first (MeshBvh's builder splits a node's slot range). */
RC_HD void subtreeSlots(const TreeNode *nodes, const TreeNode &node, std::uint32_t &begin, std::uint32_t &end)
{
    const TreeNode *first = &node, *last = &node;
    while (!first->isLeaf())
        first = &nodes[first->first];
    while (!last->isLeaf())
        last = &nodes[last->first + 1];
    begin = first->firstSlot();
    end = last->firstSlot() + last->count;
}

/** \brief Calls \a visit(triangle) for every triangle (number within the mesh) in a leaf whose box
    and ancestors' boxes meet the image (nodeAgainstImage): a superset of the triangles
    triangleMeetsImage() keeps, found without reading the others. Leaves come in tree order. A node
    well inside the image gives its subtree's triangles at once, in the same order, without testing
    the nodes below it (the same triangles: every one of those nodes meets the image): a pair's
    image often holds most of a component, whose whole tree the walk tested node by node (at 1 000
    Panda states, the raster's two walks per open pair were the largest terms of a call's
    critical path; docs/benchmarks.md).

    Part \a partIndex of 2^\a partDepth (treePartStart): the parts in index order give the whole
    walk's triangles in its order, so that a pair's walks may run in as many threads. */
template <class Visit>
RC_HD void forEachTriangleNearImage(const TreeView &tree, const Pose<float> &placement, const RasterGrid &grid,
                                    float margin, Visit &&visit, std::uint32_t partIndex = 0,
                                    std::uint32_t partDepth = 0)
{
    const auto visitSlots = [&](std::uint32_t begin, std::uint32_t end)
    {
        for (std::uint32_t slot = begin; slot < end; ++slot)
            visit(tree.triangleOrder[slot]);
    };
    std::uint32_t start = 0;
    if (partDepth > 0 &&
        !treePartStart(
            tree.nodes, tree.numNodes,
            [&](const TreeNode &node) { return nodeAgainstImage(node, placement, grid, margin) != ImageSide::Outside; },
            partIndex, partDepth, start))
        return;
    walkTree(
        tree.nodes, tree.numNodes,
        [&](const TreeNode &node)
        {
            const ImageSide side = nodeAgainstImage(node, placement, grid, margin);
            if (side != ImageSide::Inside || node.isLeaf())
                return side != ImageSide::Outside;
            std::uint32_t begin = 0, end = 0;
            subtreeSlots(tree.nodes, node, begin, end);
            visitSlots(begin, end);
            return false;  // visited: not walked below
        },
        [&](const TreeNode &leaf)
        {
            visitSlots(leaf.firstSlot(), leaf.firstSlot() + leaf.count);
            return true;
        },
        start);
}
}  // namespace rastercheck::device
