#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief Bounding-volume hierarchy over a mesh's triangles, in the mesh's own frame: a flat array
    of nodes (oriented boxes with a bounding sphere) linked by index, one triangle per leaf by
    default. Immutable after build; share it between threads freely. This is the exact narrow
    phase's acceleration structure (and the oracle's), and the batched stages pick a pair's triangles
    through it (device::forEachTriangleNearImage).

    Each node's box is fitted to its triangles' corners along the frame of least surface area among
    the principal axes of their covariance (FCL's OBB fit) and the frames about a few normals (those
    axes, the mesh's axes, a few of the node's triangles' normals), each turned about its normal to
    the least rectangle about the corners (see fitAxes). Boxes along the principal axes alone made
    distance queries 17-44 % slower and collision queries near contact 1.2x-1.9x slower
    (docs/benchmarks.md); boxes along the mesh axes alone, 3x to 5x more node pairs on OMPL.app's
    alpha-1.5 and Apartment. Built top-down: for the first 24 levels each node is split where the
    surface area heuristic says (its three axes, 15 cuts each; 2.6x fewer node pairs than the
    median of the longest axis on FCL's env/rob), below that at the median along its longest axis,
    so the depth stays bounded (at most 24 + log2(triangles)), which lets every query traverse it
    with a small fixed stack instead of allocating.

    Nodes are stored in float (72 bytes each, two per triangle; with the triangle order and the
    corners in double, 220 bytes per triangle) and read into double: the axes are
    rounded first and the extents, centre and radius then computed about the rounded values and
    rounded outwards, so every corner lies in the stored box up to the axes' departure from
    orthonormality (a few 1e-8 of the node's size), which the queries' slack covers. */
class MeshBvh
{
public:
    /** \brief The nodes are device::TreeNode, so the batched stages (and the GPU) read the very
        arrays the exact phase walks (CollisionModel's flat tree arrays). */
    using Node = device::TreeNode;

    /** \brief Deepest tree the walk's fixed stack allows (device::walkPairs); a balanced build of
        any mesh that fits in memory stays far below it (the constructor checks). */
    static constexpr int kMaxDepth = device::kMaxTreeDepth;
    /** \brief Smallest subtree a large mesh's build gives an OpenMP thread of its own: a mesh of more
        than twice as many triangles is built on every thread (the same tree as on one). */
    static constexpr std::size_t kMinJobTriangles = 4096;

    /** \brief Builds over \a mesh, which must outlive this object and not change. Empty meshes give
        an empty tree. Throws rastercheck::Error if a triangle names a vertex that does not exist.
        With \a insideGrid (meant for closed meshes, which containment is asked of), also builds
        the grid of inside/outside facts that lets pointInsideClosedMesh() answer most points
        without casting a ray. */
    explicit MeshBvh(const Mesh &mesh, unsigned maxLeafTriangles = 1, bool insideGrid = false);
    // The node and order pointers may point into the own arrays: a move keeps them, a copy would not.
    MeshBvh(const MeshBvh &) = delete;
    MeshBvh &operator=(const MeshBvh &) = delete;
    MeshBvh(MeshBvh &&) = default;
    MeshBvh &operator=(MeshBvh &&) = default;

    const Mesh &mesh() const { return *mesh_; }
    /** \brief The nodes, root first (numNodes() of them). */
    const Node *nodes() const { return nodes_; }
    std::size_t numNodes() const { return numNodes_; }
    /** \brief Triangle numbers of the mesh in slot order (one per triangle of the mesh). */
    const std::uint32_t *triangleOrder() const { return triangleOrder_; }
    /** \brief The tree as the device code reads it. */
    device::TreeView view() const
    {
        return device::TreeView{nodes_, triangleOrder_, static_cast<std::uint32_t>(numNodes_)};
    }
    /** \brief Where a tree's arrays may be held: the nodes, the triangle order, the corners
        (slotCorners) and the inside grid's cells (null without a grid). */
    struct Arrays
    {
        const Node *nodes;
        const std::uint32_t *triangleOrder;
        const double *corners;
        const std::uint8_t *gridCells;
    };
    /** \brief Points this tree at a copy of its arrays held elsewhere (the model's flat arrays,
        which the batched stages and the GPU read) and frees its own, so each is stored once. The
        copy must equal arrays() and outlive the tree. */
    void useSharedArrays(const Arrays &arrays);
    Arrays arrays() const { return Arrays{nodes_, triangleOrder_, corners_, gridCells_}; }
    /** \brief Cells of the inside grid (0 without one). */
    std::size_t numGridCells() const { return numGridCells_; }
    /** \brief Corners of the triangle in slot \a slot of triangleOrder (mesh frame): 9 doubles,
        x y z of each corner, stored in traversal order so that leaves read contiguous memory. */
    const double *slotCorners(std::uint32_t slot) const { return corners_ + 9 * static_cast<std::size_t>(slot); }
    /** \brief The triangles under a node: slots [begin, end) of triangleOrder (every node's
        triangles are contiguous there, since a split partitions its parent's range). */
    struct SlotRange
    {
        std::uint32_t begin, end;
    };
    /** \brief Every node's SlotRange, indexed like nodes(): computed on demand (inner nodes store
        no range), for walks that need how many triangles a subtree holds (the patch cut,
        ConvexSolids::add). */
    std::vector<SlotRange> nodeSlotRanges() const;
    /** \brief Levels below the root (0 for a single leaf, -1 when empty). */
    int depth() const { return depth_; }
    bool empty() const { return numNodes_ == 0; }

    /** \brief Bytes held by the nodes, the triangle order, the stored corners and the inside grid. */
    std::size_t bytes() const;

    /** \brief What the inside grid knows of \a point (mesh frame): 1 outside, 2 inside, 0 not known
        (its cell is near the surface, or there is no grid). Every point of a cell that no triangle
        comes near (the triangles' bounds grown by a margin far above rounding) lies in one region
        of space the surface does not cross, whose answer one ray cast at build time gave. */
    int insideGridAnswer(const Eigen::Vector3d &point) const;
    bool hasInsideGrid() const { return numGridCells_ > 0; }

    /** \brief Per connected shell of the mesh, a few of its vertices (its first vertex, then its
        extreme vertices along the axes; mesh frame, 3 doubles each), for containment tests: when
        two surfaces do not meet, any vertex of a shell is inside the other solid exactly when the
        whole shell is. Shell s's probes are [shellProbeStart()[s], shellProbeStart()[s + 1]). */
    std::size_t numShells() const { return shellProbeStart_.size() - 1; }
    const std::vector<double> &shellProbePoints() const { return shellProbePoints_; }
    const std::vector<std::uint32_t> &shellProbeStart() const { return shellProbeStart_; }

    /** \brief The tree, corners, inside grid and probes as the exact phase reads them
        (device/ExactPhase.h). A view: valid while this tree and its arrays live. */
    device::ExactTree exactTree() const;

private:
    struct BuildScratch;
    /** \brief The axes (columns) of the box over slots begin..end: of \a principal and the frames
        about a few normals, the one whose box has the least surface area. */
    Eigen::Matrix3d fitAxes(std::uint32_t begin, std::uint32_t end, const Eigen::Matrix3d &principal,
                            BuildScratch &scratch) const;
    /** \brief A subtree left to a thread of its own: slots begin..end at depth \a level, its root
        standing for node \a node of the upper tree. */
    struct BuildJob
    {
        std::uint32_t begin, end;
        std::int32_t node;
        int level;
    };
    /** \brief Builds node \a node of \a nodes over slots begin..end and its subtree (each split
        appends the two children to \a nodes), and returns its height; with \a jobs, a node over at
        most \a jobTriangles triangles is left to a job instead (height 0 here). */
    int build(std::uint32_t begin, std::uint32_t end, std::vector<Node> &nodes, std::int32_t node, int level,
              BuildScratch &scratch, unsigned maxLeafTriangles, std::uint32_t jobTriangles = 0,
              std::vector<BuildJob> *jobs = nullptr);
    /** \brief ownNodes_ and depth_ from \a upper, whose nodes named by \a jobs stand for the roots
        of \a subtrees: the nodes in the order one build() alone appends them. */
    void layOutDepthFirst(const std::vector<Node> &upper, const std::vector<BuildJob> &jobs,
                          const std::vector<std::vector<Node>> &subtrees);
    /** \brief The surface area heuristic's split of slots begin..end: false when every centroid
        projects alike on every axis of \a axes, else the cut (centroids below \a cut along
        \a direction go left; both sides non-empty). */
    bool sahSplit(std::uint32_t begin, std::uint32_t end, const Eigen::Matrix3d &axes,
                  const std::vector<Eigen::Vector3d> &centroids, Eigen::Vector3d &direction, double &cut) const;
    void buildInsideGrid();

    const Mesh *mesh_;
    // Built into the own arrays; read through the pointers (the own arrays, or shared copies).
    std::vector<Node> ownNodes_;
    std::vector<std::uint32_t> ownTriangleOrder_;
    const Node *nodes_ = nullptr;
    std::size_t numNodes_ = 0;
    const std::uint32_t *triangleOrder_ = nullptr;
    std::vector<double> ownCorners_;  // n_triangles x 9, slot order
    const double *corners_ = nullptr;
    std::vector<double> shellProbePoints_;           // n_probes x 3
    std::vector<std::uint32_t> shellProbeStart_{0};  // n_shells + 1
    int depth_ = -1;
    // Inside grid: a regular grid over the mesh's bounding box (mesh frame), one byte per cell
    // (0 near the surface, 1 outside, 2 inside), x fastest.
    Eigen::Vector3d gridLower_ = Eigen::Vector3d::Zero();
    Eigen::Vector3d gridInverseCell_ = Eigen::Vector3d::Zero();
    int gridSize_[3] = {0, 0, 0};
    std::vector<std::uint8_t> ownGridCells_;
    const std::uint8_t *gridCells_ = nullptr;
    std::size_t numGridCells_ = 0;
};

/** \brief Scratch of the exact phase for one thread at a time (Pinocchio's Data): whoever runs the
    queries (a backend's workspace, a test) owns it, so nothing is kept per thread behind the
    caller's back. Sized on first use; a query without one places nodes per visit and starts no
    walk from a remembered leaf pair. */
struct ExactWorkspace
{
    /** \brief A node of the moving tree placed in the fixed tree's frame: done once per node and
        query, where a node pair's test would otherwise redo it for every node of the other tree it
        meets. Stamped by query, so that nothing is cleared between queries; trees above
        kMaxPlacedNodes are placed per visit instead (100 bytes per node). */
    using PlacedNode = device::PlacedNode;
    static constexpr std::size_t kMaxPlacedNodes = std::size_t(1) << 17;
    std::vector<PlacedNode> placed;
    std::vector<std::uint32_t> stamps;
    std::uint32_t query = 0;

    /** \brief For the last queries of a few pairs of trees: the leaf pair (triangle slots) where
        the last query found its contact or, when it found none, the leaf pair whose bounding
        spheres came nearest. The next query of the pair tests that triangle pair before walking:
        nearby states (the next state along a motion, the other end of a bisection step) often touch
        there first (OMPL.app near-contact states, A/B in one build: safe / FCL Easy 2.7 -> 3.2,
        Twistycool 2.0-2.9 -> 3.2-3.4, alpha-1.5 2.6-3.3 -> 3.0-3.5; uniform states unchanged
        within the noise). It only reorders work: a hit is a real contact of those two triangles, a
        miss goes on to the walk, so no verdict depends on it. Keyed by the trees' addresses; a
        stale entry (a tree freed and another built at its address) names slots that are checked
        against the tree's size. */
    using LeafHint = device::LeafHint;
    static constexpr std::size_t kLeafHints = 64;
    std::array<LeafHint, kLeafHints> hints{};

    /** \brief This workspace lent to the exact phase or the distance walk (device::ExactScratch) for
        a query that moves a tree of \a movingNodes nodes: its placed-node cache grown to hold them
        (up to kMaxPlacedNodes), and the leaf hints. */
    device::ExactScratch lend(std::size_t movingNodes);
};

/** \brief Where two meshes touch: a point (world frame) and the triangle of each mesh. */
struct MeshContact
{
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    std::int32_t triangleA = -1;  ///< -1 when found by containment (no surface crossing)
    std::int32_t triangleB = -1;
};

/** \brief Do the surfaces of A (placed by poseA) and B (placed by poseB) come within \a padding
    (metres; 0 = intersect or touch; negative counts as 0)? Simultaneous traversal of both trees,
    descending the larger node first; node pairs are culled by their bounding spheres, then by a
    15-axis separating-axis test of their oriented boxes, both grown by \a padding plus a rounding
    slack (1e-6 of the coordinates' magnitude), and leaf pairs decided by trianglesIntersect() (padding 0) or
    trianglesWithin() (padding > 0) with the smaller tree's triangles expressed in the other's
    frame. So the answer is exact for the coordinates after that one rigid transform. Stops at the
    first contact found, which \a contact (when not null) receives: for padding > 0 the midpoint of
    a close-enough pair. With a \a workspace and without \a contact the query first tests the leaf
    pair where the workspace's last query of the same two trees touched or came nearest (nearby
    states often touch there again); that may change which contact is found first, never the
    answer, so a query with \a contact skips it and its first contact does not depend on earlier
    queries. This is device::surfacesWithin on exactTree(), the code the batched stages run per pair. The smaller tree's
   nodes are placed in the other's frame once per query, in the workspace (up to 13 MB for a tree of 2^17 nodes; larger
   trees, and queries without a workspace, place them per visit). Thread-safe given one workspace per thread. The walk
   is device::walkPairs; a tree too deep for its stack (which the constructor rules out) would answer true, with no
   triangles named. */
bool surfacesWithin(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                    double padding, MeshContact *contact = nullptr, ExactWorkspace *workspace = nullptr);

/** \brief A node's axes (columns), centre and half extents, in double. */
Eigen::Matrix3d nodeAxes(const MeshBvh::Node &node);
Eigen::Vector3d nodeCentre(const MeshBvh::Node &node);
Eigen::Vector3d nodeExtents(const MeshBvh::Node &node);
/** \brief Is \a p (mesh frame) in the node's box grown by \a margin? */
bool nodeContains(const MeshBvh::Node &node, const Eigen::Vector3d &p, double margin = 0.0);

/** \brief Is \a point (frame of the mesh) strictly inside the closed mesh of \a bvh? The tree's
    inside grid answers when it knows the point's cell; otherwise device::pointInsideSolid() over
    the tree: a ray's signed crossings, retried along another of a fixed set of directions whenever
    the ray comes within a small tolerance (1e-9 of the mesh's size) of an edge or vertex or lies
    in a face's plane. If every direction grazes (a point within that tolerance of the surface) the
    answer is inside, the safe one. Meaningful only for closed meshes. No allocation;
    thread-safe. */
bool pointInsideClosedMesh(const MeshBvh &bvh, const Eigen::Vector3d &point);

/** \brief The exact oracle for two solids: true when their surfaces come within \a padding or one
    contains the other (tested for closed meshes only: \a closedA / \a closedB). Containment is
    decided by one vertex of the inner mesh, which suffices once the surfaces are known not to
    cross. On containment \a contact gets that vertex (world frame) and triangles -1. */
bool solidsOverlap(const MeshBvh &a, const Eigen::Isometry3d &poseA, bool closedA, const MeshBvh &b,
                   const Eigen::Isometry3d &poseB, bool closedB, double padding, MeshContact *contact = nullptr,
                   ExactWorkspace *workspace = nullptr);
}  // namespace rastercheck
