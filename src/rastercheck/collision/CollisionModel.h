#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "rastercheck/collision/CollisionRequest.h"
#include "rastercheck/collision/CurvedSolids.h"
#include "rastercheck/collision/SelfPairTables.h"
#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/Stages.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck
{
/** \brief Directions the hull points of a convex piece are extreme along. Every vertex lies within
    the piece's hull slack of their hull; the proof reads every vertex only when the hull points'
    gap does not clear it. The support search reads only the few hull points of a direction's cell
    (device::supportCell), so more points cost little there and shrink the slack: 256 instead of
    128 took a fifth of the instructions off the Panda's certified edges and a quarter off its free
    states, 1024 instead of 256 a fifth off the UR5's free states (its links have thousands of
    vertices), at 0.37 s more per UR5 model (docs/benchmarks.md, "The support search by direction
    cells", "1024 hull directions"). Meshes of up to this many vertices have no slack. At most
    65536: the cells number hull points in 16 bits. */
constexpr std::size_t kConvexHullDirections = 1024;

/** \brief Most shells a solid is split into for the separation cull: shell pairs grow as the
    product, and a solid of more shells (a scene mesh of loose parts) is tried whole only. */
constexpr std::size_t kMaxConvexShells = 8;

/** \brief Most triangles in a patch (device::PatchNode) that is not a leaf of the triangle tree:
    small enough that a patch of a wall or a curved surface is close to flat (its hull hugs it),
    large enough that the patch tree stays shallow and each patch's hull test amortises the box
    tests above it. */
constexpr std::size_t kPatchTriangles = 32;

/** \brief A patch of more than one triangle is split further while its triangles are thicker,
    along their mean normal, than this fraction of the robot's scale (the median diagonal of the
    components' boxes; a component's own diagonal for its patches): a patch that wraps a corner of
    a non-convex solid has a hull that fills the corner, and hides gaps about as wide as it is
    thick from the proofs. */
constexpr double kPatchFlatness = 0.02;

/** \brief A solid gets patches when it has more triangles than this and neither its whole mesh nor
    every one of its shells is close to convex (ConvexPiece::numPlanes): where its hull stands
    for it poorly. */
constexpr std::size_t kMinPatchedTriangles = 4;

/** \brief The hull test's arrays (device::ConvexArrays), in double, each solid in its own frame:
    its whole mesh as one piece, then each of its shells when it has 2 to kMaxConvexShells of them.
    A closed shell close to convex keeps its face planes, so that overlaps can be proven too; a
    piece whose vertices are all on its surface says so (ConvexPiece::surfaceVertices). */
class ConvexSolids
{
public:
    /** \brief Appends the mesh of \a tree (its triangle tree, MeshBvh) as the next solid; \a closed:
        its topology is closed (MeshTopology, outward-oriented), without which its pieces keep no
        face planes (an open mesh has no inside; its vertices can still prove an overlap with a
        closed solid). A solid that is not close to convex gets patches no thicker than
        \a patchThickness (kPatchFlatness), cut from \a tree (addPatches). The tree is read during
        the call only. */
    void add(const MeshBvh &tree, bool closed, double patchThickness = kOwnScale);
    /** \brief add()'s default patch thickness: kPatchFlatness of the mesh's own box diagonal. */
    static constexpr double kOwnScale = -1.0;
    std::size_t numSolids() const { return solidPieces_.size() - 1; }
    /** \brief Pieces of solid \a s: its whole mesh, then its shells (none when it has one). */
    std::size_t numPieces(std::size_t s) const { return solidPieces_[s + 1] - solidPieces_[s]; }
    device::ConvexArrays arrays() const
    {
        return device::ConvexArrays{
            vertices_.data(),   hullPoints_.data(),      pieces_.data(),           solidPieces_.data(),
            planes_.data(),     edges_.data(),           supportCellStart_.data(), supportCandidates_.data(),
            patchNodes_.data(), solidPatchNodes_.data(), patchPieces_.data(),      patchTriangles_.data()};
    }
    std::size_t numVertexDoubles() const { return vertices_.size(); }
    std::size_t numHullPointDoubles() const { return hullPoints_.size(); }
    std::size_t numAllPieces() const { return pieces_.size(); }
    std::size_t numPlaneDoubles() const { return planes_.size(); }
    std::size_t numEdgeIndices() const { return edges_.size(); }
    std::size_t numSupportCellOffsets() const { return supportCellStart_.size(); }
    std::size_t numSupportCandidates() const { return supportCandidates_.size(); }
    std::size_t numPatchNodes() const { return patchNodes_.size(); }
    std::size_t numPatches() const { return patchPieces_.size(); }
    std::size_t numPatchTriangleIndices() const { return patchTriangles_.size(); }
    /** \brief Patches of solid \a s (0 when it has none: small, or close to convex). */
    std::size_t numPatchesOf(std::size_t s) const { return solidPatches_[s + 1] - solidPatches_[s]; }
    /** \brief Bytes of every array, for the memory report. */
    std::size_t bytes() const;

private:
    /** \brief \a closedShell: the piece is one closed, outward-oriented shell (it may keep planes). */
    device::ConvexPiece makePiece(const Mesh &mesh, bool closedShell);
    /** \brief The patch tree of \a tree's mesh (device::PatchNode): a cut of the triangle tree
        itself. From the root down, a node becomes a patch when it is a leaf, or holds at most
        kPatchTriangles triangles that are no thicker than \a patchThickness; else its two
        children are visited. So every patch is the subtree of one triangle-tree node
        (PatchNode::treeNode), every triangle lies in exactly one patch, and the patch tree is
        as deep as the triangle tree at most (MeshBvh::kMaxDepth). */
    void addPatches(const MeshBvh &tree, double patchThickness);

    std::vector<double> vertices_;    // n_piece_vertices x 3
    std::vector<double> hullPoints_;  // n_hull_points x 3
    std::vector<device::ConvexPiece> pieces_;
    std::vector<std::uint32_t> solidPieces_{0};      // n_solids + 1
    std::vector<double> planes_;                     // n_planes x 4
    std::vector<std::uint32_t> edges_;               // n_edges x 2
    std::vector<std::uint32_t> supportCellStart_;    // per piece with cells, kSupportCells + 1
    std::vector<device::HullPointNumber> supportCandidates_;  // hull point numbers within their piece
    std::vector<device::PatchNode> patchNodes_;      // per solid, root first
    std::vector<std::uint32_t> solidPatchNodes_{0};  // n_solids + 1
    std::vector<device::ConvexPiece> patchPieces_;   // n_patches
    std::vector<std::uint32_t> solidPatches_{0};     // n_solids + 1
    std::vector<std::uint32_t> patchTriangles_;      // n_patch_triangles x 3, vertex numbers within the patch
};

/** \brief Flat, immutable arrays of one robot and one scene, laid out for the pipeline stages (and
    uploaded unchanged to a GPU), plus the oracle's BVHs. Built once per checker.

    What depends on the robot alone (its meshes' trees, hulls and patches, the self pairs and their
    tables: 95 % of a model's build, about 70 ms for the Panda and 1.3 s for the UR5 on one core,
    docs/benchmarks.md "Building a checker") is built once per
    robot content (contentBytes) and shared: a model of a robot whose content equals an earlier
    one's, loaded once or again, copies those arrays and shares the trees, so a benchmark or a
    viewer that builds a checker per scene builds the robot's part once. The parts of the
    kKeptRobotParts robots used last stay built while no model holds them; a robot changed in any
    field gets parts of its own.

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

    std::vector<float> componentVertices;                  // n_component_vertices x 3, link frame
    std::vector<std::uint32_t> componentTriangles;         // n_component_triangles x 3
    std::vector<MeshSlice> components;                     // n_components
    std::vector<device::OrientedBox> componentLocalBoxes;  // n_components, link frame
    std::vector<int> componentLink;                        // n_components
    std::vector<int> componentSubtreeEnd;                  // n_components: layer k spans [k, end)

    std::vector<float> objectVertices;                     // n_object_vertices x 3, world frame - origin
    std::vector<std::uint32_t> objectTriangles;            // n_object_triangles x 3
    std::vector<MeshSlice> objects;                        // n_objects
    std::vector<device::Box> objectBoxes;                  // n_objects, world frame - origin
    std::vector<device::OrientedBox> objectOrientedBoxes;  // n_objects, world frame - origin
    std::vector<device::Sphere> objectSpheres;             // n_objects: device::boundingSphere of the box

    /** \brief Component pairs (a < b) checked for self-collision: those the ACM does not allow. */
    std::vector<std::pair<int, int>> selfPairs;

    /** \brief The oracle's trees, reading componentTrees' and objectTrees' arrays; the components'
        trees are shared by every model of a robot of the same content. */
    std::vector<std::shared_ptr<const MeshBvh>> componentBvhs;  // n_components, link frame
    std::vector<std::shared_ptr<const MeshBvh>> objectBvhs;     // n_objects, world frame

    /** \brief One party's trees and the exact phase's arrays, stored here once (each MeshBvh
        reads its slice) as flat arrays that the batched stages and the GPU read too. */
    struct TreeArrays
    {
        std::vector<device::TreeNode> nodes;         // per mesh at MeshSlice::firstNode
        std::vector<std::uint32_t> triangleOrder;    // n_triangles; per mesh at MeshSlice::firstTriangle
        std::vector<double> corners;                 // n_triangles x 9, slot order (MeshBvh::slotCorners)
        std::vector<std::uint8_t> gridCells;         // inside grids (MeshBvh::insideGridAnswer)
        std::vector<double> probePoints;             // every mesh's shell probes, 3 doubles each
        std::vector<std::uint32_t> shellProbeStart;  // per mesh its n_shells + 1 starts (its own probe numbers)
        std::vector<device::ExactMeshInfo> meshes;   // n_meshes: where each mesh's part lies
        /** \brief The arrays as the exact phase reads them. */
        device::ExactArrays exactArrays() const
        {
            return device::ExactArrays{corners.data(), gridCells.data(), probePoints.data(), shellProbeStart.data(),
                                       meshes.data()};
        }
    };
    TreeArrays componentTrees;  // link frame
    TreeArrays objectTrees;     // world frame
    /** \brief The objects' trees are in the world frame, the stages' floats relative to origin. */
    device::Pose<float> objectTreePlacement = device::Pose<float>::identity();

    /** \brief The convex separation cull's view of every solid: components first, then objects. */
    ConvexSolids convex;

    /** \brief Raster pixel side used when a request gives none: 1/32 of the median diagonal of the
        components' boxes (about a centimetre for an arm), so a typical link's box spans about 32
        pixels along its diagonal. */
    double defaultPixelSize = 0.0;

    /** \brief Per coordinate: 1 when bounds apply (continuous joints wrap and have none). */
    std::vector<std::uint8_t> boundedCoordinates;
    /** \brief First coordinate of every floating joint's quaternion (qx). */
    std::vector<int> quaternionStarts;

    /** \brief Joint-space clearance tables of the self pairs one or two coordinates move apart (a
        wrist's links), which prove those pairs apart without a hull test where they are far enough
        from touching (SelfPairTables). */
    SelfPairTables selfPairTables;
    /** \brief The exact shapes of the pairs with curved primitives (CurvedSolids): what safe and
        exact mode decide those pairs by once the meshes call them colliding. */
    CurvedSolids curved;

    /** \brief True when every coordinate is finite, bounded coordinates lie within their bounds
        (OMPL's tolerance: one double epsilon), and no quaternion is zero. */
    bool configurationAdmissible(const double *q) const { return firstInadmissibleCoordinate(q) < 0; }
    /** \brief The first coordinate that makes \a q inadmissible (a quaternion's qx when it is zero),
        -1 when there is none: what a Contact::Kind::OutOfBounds contact names. */
    int firstInadmissibleCoordinate(const double *q) const;

    std::size_t numComponents() const { return components.size(); }
    std::size_t numObjects() const { return objects.size(); }
    /** \brief Size of the pair numbering (device::environmentPair, then the self pairs). */
    std::size_t numPairs() const { return numObjects() * numComponents() + selfPairs.size(); }
    /** \brief Sets contact.kind, component and object or otherComponent from a pair's number. */
    void nameParties(std::uint32_t pair, Contact &contact) const;

    /** \brief How many robots' parts stay built while no model holds them: a benchmark that builds
        a checker per problem, and frees it before the next, reuses its robot's parts. */
    static constexpr std::size_t kKeptRobotParts = 2;

private:
    struct RobotPartOnly
    {
    };
    /** \brief The part of a model that depends on \a robot alone, built (no scene; no origin, no
        curved pairs). */
    CollisionModel(RobotModelConstPtr robot, RobotPartOnly);
    /** \brief The robot part for \a robot's content: shared when built before and still held or
        kept, else built (for a copy of \a robot, so that a change to the caller's robot later
        cannot reach it). Thread-safe. */
    static std::shared_ptr<const CollisionModel> sharedRobotPart(const RobotModel &robot);
    /** \brief Builds the robot's fields (components, their trees and hulls, self pairs, coordinate
        flags, self-pair tables). */
    void buildRobotPart();
    /** \brief Copies \a part's robot fields; the trees are shared, and keep \a part alive. */
    void copyRobotPart(const std::shared_ptr<const CollisionModel> &part);
};

using CollisionModelConstPtr = std::shared_ptr<const CollisionModel>;

/** \brief The padding of every pair at one state, the one lookup the backends read it through:
    CollisionRequest::padding plus, when the request has a pairPadding, the pair's entry in row
    \a row (0 for a request with one row). A view: the request must outlive it. */
class PairPaddings
{
public:
    PairPaddings(const CollisionModel &model, const CollisionRequest &request, std::size_t row)
        : PairPaddings(model, request.padding, request.pairPadding.get(), row)
    {
    }
    /** \brief \a base plus, when \a extra is not null, its row \a row (0 for one row) per pair,
        plus, when \a wider is not null, its row \a row too (Checker::checkTwoPaddings' wider
        paddings). */
    PairPaddings(const CollisionModel &model, double base, const PairPadding *extra, std::size_t row,
                 const PairPadding *wider = nullptr)
        : base_(base),
          numComponents_(model.numComponents()),
          numEnvironmentPairs_(model.numObjects() * model.numComponents())
    {
        if (extra)
            own_ = Terms(model, *extra, row);
        if (wider)
            (extra ? added_ : own_) = Terms(model, *wider, row);
    }
    /** \brief No entry per pair: every pair has the request's padding. */
    bool uniform() const { return own_.environment == nullptr; }
    /** \brief Component \a k against any scene object. */
    double component(std::size_t k) const
    {
        return base_ + (own_.environment ? own_.environment[k] : 0.0) +
               (added_.environment ? added_.environment[k] : 0.0);
    }
    /** \brief Self pair \a i (CollisionModel::selfPairs order). */
    double self(std::size_t i) const
    {
        return base_ + (own_.self ? own_.self[i] : 0.0) + (added_.self ? added_.self[i] : 0.0);
    }
    /** \brief Pair \a pair in CollisionModel's numbering (environment pairs, then self pairs). */
    double pair(std::uint32_t pair) const
    {
        return device::paddingOfPair(base_, own_.environment, own_.self, numComponents_, numEnvironmentPairs_, pair) +
               (added_.environment ? device::paddingOfPair(0.0, added_.environment, added_.self, numComponents_,
                                                           numEnvironmentPairs_, pair)
                                   : 0.0);
    }

private:
    /** \brief One row of a PairPadding (row 0 when it has one row). */
    struct Terms
    {
        Terms() = default;
        Terms(const CollisionModel &model, const PairPadding &rows, std::size_t row)
            : environment(rows.environment.data() + (rows.rows == 1 ? 0 : row) * model.numComponents()),
              self(rows.self.data() + (rows.rows == 1 ? 0 : row) * model.selfPairs.size())
        {
        }
        const double *environment = nullptr;  // numComponents entries, or null
        const double *self = nullptr;         // selfPairs.size() entries, or null
    };
    double base_;
    std::size_t numComponents_;
    std::size_t numEnvironmentPairs_;
    Terms own_, added_;  // the first and second row given (added_ only when both are)
};

/** \brief Appends \a rows rows to \a out (its rows counted up): row r is \a own's row r plus, when
    \a wider is not null, \a wider's row r, per component and self pair (a PairPadding of one row
    gives row 0 to every r; a null \a own adds nothing). CollisionRequest::padding is not in them:
    the rows are a request's pairPadding. */
void appendPaddingRows(const CollisionModel &model, const PairPadding *own, const PairPadding *wider, std::size_t rows,
                       PairPadding &out);

}  // namespace rastercheck
