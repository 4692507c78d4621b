#pragma once

// The one tree walk of the library: a depth-first traversal of a pair of trees (FCL's
// collisionRecurse / distanceRecurse, Coal's the same), written once for every query that walks a
// tree: the exact phase (a tree against a tree), the rays of the point-in-solid test, the image
// culls of the stages and the patch culls of the proofs (a tree against one leaf). A query is a
// visitor with a node test, a leaf visitor and a descent rule; the walk owns the order and the
// stack. The stack is a fixed array (no recursion, no allocation: it runs on the GPU too), and a
// walk that would outgrow it ends with WalkEnd::Overflow for the caller to answer safely, never
// writes past it.

#include <cstdint>

#include "rastercheck/device/HostDevice.h"

namespace rastercheck::device
{
/** \brief Deepest tree the walk's stack allows (the builders check it): a walk that pushes both
    children of a node and pops one holds at most depth + 1 entries per tree. */
constexpr int kMaxTreeDepth = 60;

/** \brief Entries of a pair walk's stack: it pushes two pairs per level descended in either tree and
    pops one, so it never holds more than depthA + depthB + 1. */
constexpr int kPairStackSize = 2 * kMaxTreeDepth + 2;

/** \brief Most parts one walk is split into for as many threads (walkPartStart; the stages' exact
    phase, StageBudget::exactWalkParts): a power of two, a part per path of up to 6 bits. 64, not
    32, since any part's contact ends a pair's walk where no contact is read: what is left of the
    slowest walks is then walks that find nothing, whose heaviest part more parts split again; 128
    gained no more and asked twice the work of small calls (each part tests the pairs on its path;
    docs/benchmarks.md "Any contact decides where none is read"). */
constexpr std::uint32_t kMaxWalkParts = 64;
static_assert((kMaxWalkParts & (kMaxWalkParts - 1)) == 0, "parts are paths of bits");

/** \brief The bits of a part's path for \a perPair parts (a power of two; walkPartStart's depth). */
RC_HD std::uint32_t walkPartDepth(std::uint32_t perPair)
{
    std::uint32_t depth = 0;
    while ((2u << depth) <= perPair)
        ++depth;
    return depth;
}

/** \brief How a walk ended. */
enum class WalkEnd : std::uint8_t
{
    Finished,  ///< every pair the node test kept was visited
    Stopped,   ///< the leaf visitor asked to stop (a contact found, a ray grazed)
    Overflow   ///< a tree deeper than kMaxTreeDepth: the walk is incomplete, the caller must answer safely
};

/** \brief Two node indices, one per tree. */
struct NodePair
{
    std::int32_t a, b;
};

/** \brief Every node the walk reads follows one convention (device::TreeNode, device::PatchNode):
    \a first < 0 for a leaf, else the index of the first child, the second child at first + 1,
    both in the same array as the node. */
template <class Node>
RC_HD bool isLeafNode(const Node &node)
{
    return node.first < 0;
}

/** \brief The two pairs a pair of nodes (not both leaves) splits into, in walk order (\a first is
    walked first): the children of A's node or of B's (the visitor's splitA; never a leaf's),
    swapped when the visitor's secondFirst says so. */
template <class NodeA, class NodeB, class Visitor>
RC_HD void childPairs(const NodeA *nodesA, const NodeB *nodesB, Visitor &visitor, NodePair pair, bool leafA,
                      bool leafB, NodePair &first, NodePair &second)
{
    const bool descendA = leafB || (!leafA && visitor.splitA(pair));
    const std::int32_t child = descendA ? nodesA[pair.a].first : nodesB[pair.b].first;
    first = descendA ? NodePair{child, pair.b} : NodePair{pair.a, child};
    second = descendA ? NodePair{child + 1, pair.b} : NodePair{pair.a, child + 1};
    if (visitor.secondFirst(first, second))
    {
        const NodePair swapped = first;
        first = second;
        second = swapped;
    }
}

/** \brief Depth-first walk of the node pairs of two trees (root index 0 in each; both non-empty),
    from the pair \a start (the roots; a pair below them walks that pair's part of the trees alone).
    \a visitor provides:
    - `bool test(NodePair)`: may the pair hold what the query looks for? Called when a pair is
      popped, so a query whose reach shrinks as it goes (a distance query's best distance so far,
      lowered in its leaf visitor) prunes the pairs still on the stack against the current reach.
    - `bool leaves(NodePair)`: a pair of leaves the test kept; false ends the walk (Stopped).
    - `bool splitA(NodePair)`: with both nodes inner, descend into A's (else B's). A leaf is never
      split.
    - `bool secondFirst(NodePair first, NodePair second)`: visit the pair with the second child
      before the one with the first (the nearer first: a colliding query stops at the first
      contact, a distance query's reach shrinks sooner). */
template <class NodeA, class NodeB, class Visitor>
RC_HD WalkEnd walkPairs(const NodeA *nodesA, const NodeB *nodesB, Visitor &visitor, NodePair start = NodePair{0, 0})
{
    NodePair stack[kPairStackSize];
    int top = 0;
    stack[top++] = start;
    while (top > 0)
    {
        const NodePair pair = stack[--top];
        if (!visitor.test(pair))
            continue;
        const bool leafA = isLeafNode(nodesA[pair.a]), leafB = isLeafNode(nodesB[pair.b]);
        if (leafA && leafB)
        {
            if (!visitor.leaves(pair))
                return WalkEnd::Stopped;
            continue;
        }
        if (top + 2 > kPairStackSize)
            return WalkEnd::Overflow;
        NodePair first, second;
        childPairs(nodesA, nodesB, visitor, pair, leafA, leafB, first, second);
        stack[top++] = second;
        stack[top++] = first;  // popped next
    }
    return WalkEnd::Finished;
}

/** \brief Where part \a index of the walk of walkPairs split into up to 2^\a depth parts starts
    (walkPairs' \a start; false: the part is empty). Part \a index follows a path from the roots'
    pair: at each pair whose two children (in walkPairs' order) both pass the visitor's test, the
    next bit of \a index (highest first) picks the first or the second; a pair with one child kept
    leads to it without a bit, so a pruned walk still spreads over the parts; a pair of leaves
    reached with bits left is taken by the part whose remaining bits are all zero. The parts in
    index order cover the walk's kept pairs in walk order, so walks from each, one after the
    other, visit the same leaf pairs in the same order as one walk from the roots, and the first
    part to stop in index order is the one walk's stop.

    Each part finds its own start, in its own thread: one thread splitting the walk level by level
    ahead of the parts (testing the pairs it kept again at every level) was most of a small
    batch's critical path with mesh pairs (FCL's env/rob, the crane in the plant; docs/benchmarks.md
    "A call's critical path"). Here a part tests two pairs a level of its path. */
template <class NodeA, class NodeB, class Visitor>
RC_HD bool walkPartStart(const NodeA *nodesA, const NodeB *nodesB, Visitor &visitor, std::uint32_t index,
                         std::uint32_t depth, NodePair &start)
{
    NodePair pair{0, 0};
    if (!visitor.test(pair))
        return false;
    while (depth > 0)
    {
        const bool leafA = isLeafNode(nodesA[pair.a]), leafB = isLeafNode(nodesB[pair.b]);
        if (leafA && leafB)
            break;
        NodePair first, second;
        childPairs(nodesA, nodesB, visitor, pair, leafA, leafB, first, second);
        const bool keepFirst = visitor.test(first), keepSecond = visitor.test(second);
        if (keepFirst && keepSecond)
        {
            --depth;
            pair = (index >> depth & 1u) ? second : first;
        }
        else if (keepFirst || keepSecond)
            pair = keepFirst ? first : second;
        else
            return false;
    }
    if (depth > 0 && (index & ((1u << depth) - 1u)) != 0)
        return false;  // a pair of leaves with bits left: the part of the zeros takes it
    start = pair;
    return true;
}

/** \brief The pair walk's interface over one tree, the second tree being one leaf (walkTree). */
template <class Node, class NodeTest, class LeafVisit>
struct OneTreeVisitor
{
    const Node *nodes;
    NodeTest &nodeTest;
    LeafVisit &leafVisit;
    RC_HD bool test(NodePair pair) { return nodeTest(nodes[pair.a]); }
    RC_HD bool leaves(NodePair pair) { return leafVisit(nodes[pair.a]); }
    RC_HD bool splitA(NodePair) { return true; }
    RC_HD bool secondFirst(NodePair, NodePair) { return false; }
};

/** \brief The one leaf a tree is walked against (walkTree). */
struct OneLeaf
{
    std::int32_t first = -1;
};

/** \brief Depth-first walk of one tree (\a numNodes nodes, root first): \a visit(leaf) for every leaf
    whose node and ancestors all pass \a test(node), first children first; stops when \a visit
    returns false. The pair walk against a tree of one leaf, as FCL walks a mesh against a shape.
    From node \a start: the walk of its subtree (a part of the walk, treePartStart). */
template <class Node, class NodeTest, class LeafVisit>
RC_HD WalkEnd walkTree(const Node *nodes, std::uint32_t numNodes, NodeTest &&test, LeafVisit &&visit,
                       std::uint32_t start = 0)
{
    if (numNodes == 0)
        return WalkEnd::Finished;
    const OneLeaf single;
    OneTreeVisitor<Node, NodeTest, LeafVisit> visitor{nodes, test, visit};
    return walkPairs(nodes, &single, visitor, NodePair{static_cast<std::int32_t>(start), 0});
}

/** \brief Where part \a index of walkTree's walk split into up to 2^\a depth parts starts (walkTree's
    \a start; false: the part is empty): walkPartStart on one tree. \a test must have no side
    effect (the parts' paths test the nodes on them, each part its own). */
template <class Node, class NodeTest>
RC_HD bool treePartStart(const Node *nodes, std::uint32_t numNodes, NodeTest &&test, std::uint32_t index,
                         std::uint32_t depth, std::uint32_t &start)
{
    if (numNodes == 0)
        return false;
    const OneLeaf single;
    const auto noVisit = [](const Node &) { return true; };
    OneTreeVisitor<Node, NodeTest, const decltype(noVisit)> visitor{nodes, test, noVisit};
    NodePair pair{0, 0};
    if (!walkPartStart(nodes, &single, visitor, index, depth, pair))
        return false;
    start = static_cast<std::uint32_t>(pair.a);
    return true;
}
}  // namespace rastercheck::device
