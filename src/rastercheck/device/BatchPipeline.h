#pragma once

// The batched pipeline: many states decided in one pass, stage by stage, each stage one data-
// parallel loop over its elements (a kernel on the GPU). The driver is a template over an
// executor that provides the loops, scans, compaction, ordering by a small key and segmented
// sort: the CUDA executor runs them as kernels and CUB calls (cuda/), the host executor as plain
// loops (collision/HostStageRunner), so the CPU test suite runs exactly the code the GPU runs,
// apart from those primitives.
//
// Stages per chunk of states:
//   1. forward kinematics (one element per state), component poses, OBBs and AABBs (per state x
//      component), layer boxes and the robot's bounding sphere (per state);
//   2. culls per (state, pair): distance filter, layer AABBs, OBB tests; compaction of survivors;
//   3. per surviving pair (in pair order when there are many): image window, the convex
//      separation proof, the grid, and the candidate triangles (both meshes' trees walked with the
//      node culls, counted, scanned, written); per (pair, candidate triangle): the per-triangle
//      cull and the pre-rasterization fragment count; scan;
//   4. rasterization into the counted slots; segmented sort by (pixel, depth) per pair;
//   5. Sort_Search_Pair per pixel run; per pair the first hit pixel (atomic minimum); outcomes;
//   6. the exact phase (device/ExactPhase.h) on every pair still open, with its first contact;
//      the per-state reduction's compaction: only the outcomes that decide a state come back.
// The host finishes the reduction (the first colliding pair in pair order), confirms curved
// primitives on their exact shapes, and places conservative mode's unproven pairs (StagedBackend).

#include <cstddef>
#include <cstdint>

#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Kinematics.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/Raster.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/Stages.h"

#if defined(__CUDACC__)
#define RC_LAMBDA __host__ __device__
#else
#define RC_LAMBDA
#endif

namespace rastercheck::device
{
/** \brief The model's flat arrays (host or device memory, per executor), with their sizes. */
struct ModelArrays
{
    const KinematicJoint *joints;
    int numJoints;
    int numLinks;
    int numCoordinates;
    const float *componentVertices;
    std::size_t numComponentVertexFloats;
    const std::uint32_t *componentTriangles;
    std::size_t numComponentTriangleIndices;
    const MeshSlice *components;
    const OrientedBox *componentLocalBoxes;
    const int *componentLink;
    const int *componentSubtreeEnd;
    int numComponents;
    const float *objectVertices;
    std::size_t numObjectVertexFloats;
    const std::uint32_t *objectTriangles;
    std::size_t numObjectTriangleIndices;
    const MeshSlice *objects;
    const Box *objectBoxes;
    const OrientedBox *objectOrientedBoxes;
    int numObjects;
    const int *selfPairs;  // numSelfPairs x 2
    int numSelfPairs;
    double origin[3];  // CollisionModel::origin: world-frame floats are relative to it
    // The separation cull's arrays (CollisionModel::convex; solids: components, then objects).
    ConvexArrays convex;
    std::size_t numConvexVertexDoubles;
    std::size_t numConvexHullDoubles;
    std::size_t numConvexPieces;
    std::size_t numConvexPlaneDoubles;
    std::size_t numConvexEdgeIndices;
    std::size_t numConvexHullGroups;
    std::size_t numPatchNodes;
    std::size_t numPatches;
    std::size_t numPatchTriangleIndices;
    // Every mesh's triangle hierarchy (MeshBvh's nodes, stored once): nodes per party concatenated
    // (MeshSlice::firstNode), triangle order per party (MeshSlice::firstTriangle).
    const TreeNode *componentTreeNodes;
    std::size_t numComponentTreeNodes;
    const std::uint32_t *componentTriangleOrder;
    const TreeNode *objectTreeNodes;
    std::size_t numObjectTreeNodes;
    const std::uint32_t *objectTriangleOrder;
    // The exact phase's arrays per party (CollisionModel::TreeArrays), with their sizes.
    ExactArrays componentExact;
    ExactArrays objectExact;
    std::size_t numComponentGridCells, numComponentProbeDoubles, numComponentShellStarts;
    std::size_t numObjectGridCells, numObjectProbeDoubles, numObjectShellStarts;
    /** \brief 1 per pair with curved primitives (CurvedSolids::refines), numCurvedPairFlags of them. */
    const std::uint8_t *curvedPairs;
    std::size_t numCurvedPairFlags;
    /** \brief Places the objects' trees (world frame) in the stages' float frame (relative to
        origin). */
    Pose<float> objectTreePlacement;

    RC_HD std::uint32_t numPairs() const
    {
        return static_cast<std::uint32_t>(numObjects) * static_cast<std::uint32_t>(numComponents) +
               static_cast<std::uint32_t>(numSelfPairs);
    }
};

/** \brief Extra padding per (state, pair) (CollisionRequest::pairPadding): the certified motion
    validators give each pair of each midpoint the distance its solids can close in. Null arrays:
    no extra padding. */
struct PairPaddingRows
{
    const double *environment = nullptr;  // rows x numComponents: component k's pairs with every object
    const double *self = nullptr;         // rows x numSelfPairs
    bool rowPerState = false;             // row s for state s of the batch (else row 0 for every state)

    RC_HD bool any() const { return environment != nullptr; }
    /** \brief The rows of states [first, ...) of the batch. */
    RC_HD PairPaddingRows fromState(std::size_t first, int numComponents, int numSelfPairs) const
    {
        PairPaddingRows rest = *this;
        if (environment && rowPerState)
        {
            rest.environment += first * static_cast<std::size_t>(numComponents);
            rest.self += first * static_cast<std::size_t>(numSelfPairs);
        }
        return rest;
    }
};

/** \brief How the stages treat a batch (from the CollisionRequest). */
struct StageSettings
{
    double padding;  ///< the request's padding (>= 0); pairPadding() gives a pair's
    /** \brief Added to padding per (state, pair); host memory in the settings a runner is
        given, executor memory inside a chunk (runStageChunk uploads the chunk's rows). */
    PairPaddingRows extraPadding;
    float pixel;
    int maxImageSide;
    bool checkEnvironment;
    bool checkSelfCollision;
    /** \brief Rasterize surviving pairs (raster mode, and safe mode when no contacts are asked). */
    bool rasterize;
    /** \brief Settle pairs the hull test proves overlapping as colliding, without a triangle or
        place (safe and exact mode when no contacts are asked). */
    bool proveOverlaps;
    /** \brief A pair the raster does not hit stays open for the exact phase (safe mode); otherwise
        it is settled as apart unless padding asks for distances. */
    bool confirmMisses;
    /** \brief Pairs with a non-convex mesh obstacle (an object split into patches) skip the hull
        proof and stay open (raster or the exact phase), as the CPU backend decides them (every
        mode but raster). */
    bool meshObstaclesUnproven;
    /** \brief A pair no test settles collides, placed by the host (conservative mode, but for mesh
        obstacles): the stages leave those pairs open. Every other open pair is decided by the exact
        phase in the stages (decideOpenPairs). */
    bool unprovenCollides;
    /** \brief An overlap of a pair with curved primitives is confirmed on the exact shapes by the host
        (safe and exact mode): it does not settle its state. */
    bool confirmCurvedOverlaps;
    /** \brief Only the outcomes the per-state reduction reads come back (reduceOutcomes): per state,
        the pairs up to its first settled overlap, none settled apart. */
    bool onlyDecisive;
};

/** \brief The padding of \a pair for state \a s of a chunk: the request's, plus the pair's extra
    (the same sum the CPU backend forms, so both round it to float alike). */
RC_HD double pairPadding(const ModelArrays &model, const StageSettings &settings, std::size_t s, std::uint32_t pair)
{
    const PairPaddingRows &extra = settings.extraPadding;
    const std::size_t m = static_cast<std::size_t>(model.numComponents);
    const std::size_t row = extra.rowPerState ? s : 0;
    return paddingOfPair(settings.padding, extra.any() ? extra.environment + row * m : nullptr,
                         extra.any() ? extra.self + row * static_cast<std::size_t>(model.numSelfPairs) : nullptr, m,
                         static_cast<std::size_t>(model.numObjects) * m, pair);
}

/** \brief The largest padding of state \a s's environment pairs: the distance filter and the layer
    culls stand for many pairs at once (the CPU backend takes the largest per layer; one per state
    is coarser, never wrong: the pair's own test follows). */
RC_HD double environmentReachPadding(const ModelArrays &model, const StageSettings &settings, std::size_t s)
{
    const PairPaddingRows &extra = settings.extraPadding;
    double largest = settings.padding;
    if (extra.any())
    {
        const double *row = extra.environment + (extra.rowPerState ? s : 0) * static_cast<std::size_t>(model.numComponents);
        for (int k = 0; k < model.numComponents; ++k)
            largest = row[k] + settings.padding > largest ? row[k] + settings.padding : largest;
    }
    return largest;
}

/** \brief Where a pair stands after the stages. */
enum PairStatus : std::int32_t
{
    PairApart = 0,     ///< settled: does not collide
    PairOpen = 1,      ///< left to the host (conservative mode's unproven pairs)
    PairOverlaps = 2   ///< a ray found the solids overlapping (triangle and position set), or the hulls did (neither)
};

/** \brief One pair that survived the culls. Outcomes come sorted by (state, pair). */
struct PairOutcome
{
    std::uint32_t state;  // within the chunk
    std::uint32_t pair;
    std::int32_t status;
    std::int32_t triangle;
    double position[3];  ///< world frame
};

/** \brief Limits of one pass; a chunk that would exceed them is split (verdicts do not change). */
struct StageBudget
{
    std::size_t maxStates = 1 << 16;
    std::size_t maxPairElements = std::size_t(1) << 30;  // states x pairs in a chunk
    std::size_t maxItems = std::size_t(1) << 27;         // (pair, triangle) elements in a chunk
    std::size_t maxFragments = std::size_t(1) << 27;
    /** The executor's scratch buffers together (0: no limit but the allocator's). The limits above
        size chunks from counts; this one is enforced when a buffer grows: an executor that would
        pass it, or whose allocator refuses, frees its scratch and throws StageMemoryExhausted,
        and the chunk is split. */
    std::size_t maxScratchBytes = 0;
    /** Chunks with at least this many pairs past the box culls take the proofs in pair order
        (stage 3). Measured on an H200 (2026-11-26, docs/benchmarks.md "GPU"): the order made the
        proof stage 1.8-3.2x faster and a batch of 10^6 Panda states 1.3-1.4x, 10^5 states 1.0-1.2x,
        but batches of 10^3-10^4 states (2 000 to 20 000 pairs, less than one wave of the device)
        a third slower; there the unordered stage stays. */
    std::size_t orderedProofsFrom = std::size_t(1) << 16;
};

/** \brief What the stages did, summed over the chunks of a runner's passes: how much work the
    culls left (benchmarks, tuning). */
struct StageCounts
{
    unsigned long long states = 0;
    unsigned long long survivingPairs = 0;      ///< (state, pair) elements past the box culls
    unsigned long long rasterizedPairs = 0;     ///< of those, pairs neither proof settled that went to the raster
    unsigned long long candidateTriangles = 0;  ///< triangles of rasterized pairs the node culls kept
    unsigned long long fragments = 0;
    unsigned long long exactPairs = 0;  ///< pairs the exact phase decided in the stages

    StageCounts &operator+=(const StageCounts &other)
    {
        states += other.states;
        survivingPairs += other.survivingPairs;
        rasterizedPairs += other.rasterizedPairs;
        candidateTriangles += other.candidateTriangles;
        fragments += other.fragments;
        exactPairs += other.exactPairs;
        return *this;
    }
};

/** \brief The fixed costs of the passes an executor ran: what a small batch pays whatever its
    size. Counted on the host by both executors alike (a CUB call counts as one launch), so the
    host executor's tests see the GPU's figures. */
struct ExecutorCounts
{
    unsigned long long chunks = 0;
    unsigned long long launches = 0;          ///< kernels and CUB calls
    unsigned long long synchronizations = 0;  ///< waits of the host for the executor
    unsigned long long allocations = 0;       ///< scratch buffers grown
    double seconds = 0;                       ///< host clock inside the passes (kernels, copies, waits)

    ExecutorCounts &operator+=(const ExecutorCounts &other)
    {
        chunks += other.chunks;
        launches += other.launches;
        synchronizations += other.synchronizations;
        allocations += other.allocations;
        seconds += other.seconds;
        return *this;
    }
};

/** \brief The executor's scratch buffers, one per stage output; sized per chunk, reused. */
enum StageBuffer : int
{
    BufferStates,
    BufferAdmissible,
    BufferJointValues,
    BufferLinks,
    BufferComponentPose,
    BufferComponentBox,
    BufferComponentBounds,
    BufferLayers,
    BufferRobotSphere,
    BufferReachPadding,
    BufferExtraEnvironment,
    BufferExtraSelf,
    BufferPairFlags,
    BufferCandidates,
    BufferCandidateCount,
    BufferCandidatePairs,
    BufferProofOrder,
    BufferGrids,
    BufferMargins,
    BufferStatus,
    BufferTriangleCount,
    BufferItemStart,
    BufferItemTriangles,
    BufferRasterized,
    BufferRasterizedList,
    BufferFragmentCount,
    BufferFragmentStart,
    BufferKeys,
    BufferValues,
    BufferFragments,
    BufferSegmentStart,
    BufferHit,
    BufferOutcomes,
    BufferExactFlags,
    BufferFirstSettled,
    BufferKeep,
    BufferKept,
    BufferKeptOutcomes,
    kNumStageBuffers
};

/** \brief One solid of a pair as the per-triangle stages see it. */
struct StageSolid
{
    MeshSlice slice;
    const float *vertices;           // slice's vertices, local frame
    const std::uint32_t *triangles;  // slice's triangles
    const Pose<float> *pose;         // null for objects (world frame already)
    Box bounds;
    TreeView tree;
    Pose<float> treePlacement;  // the tree's frame -> the stages' float frame
};

/** \brief Component \a c's and object \a o's triangle trees in the flat arrays. */
RC_HD TreeView componentTreeView(const ModelArrays &model, int c)
{
    const MeshSlice &slice = model.components[c];
    return TreeView{model.componentTreeNodes + slice.firstNode, model.componentTriangleOrder + slice.firstTriangle,
                    slice.numNodes};
}
RC_HD TreeView objectTreeView(const ModelArrays &model, int o)
{
    const MeshSlice &slice = model.objects[o];
    return TreeView{model.objectTreeNodes + slice.firstNode, model.objectTriangleOrder + slice.firstTriangle,
                    slice.numNodes};
}

RC_HD void pairSolids(const ModelArrays &model, std::uint32_t pair, const Pose<float> *poses, const Box *bounds,
                      StageSolid &a, StageSolid &b)
{
    const std::uint32_t environmentPairs =
        static_cast<std::uint32_t>(model.numObjects) * static_cast<std::uint32_t>(model.numComponents);
    auto component = [&](int c) {
        const MeshSlice &slice = model.components[c];
        return StageSolid{slice, model.componentVertices + 3 * slice.firstVertex,
                          model.componentTriangles + 3 * slice.firstTriangle, poses + c, bounds[c],
                          componentTreeView(model, c), poses[c]};
    };
    if (pair < environmentPairs)
    {
        a = component(static_cast<int>(pair % model.numComponents));
        const int o = static_cast<int>(pair / model.numComponents);
        const MeshSlice &slice = model.objects[o];
        b = StageSolid{slice, model.objectVertices + 3 * slice.firstVertex,
                       model.objectTriangles + 3 * slice.firstTriangle, nullptr, model.objectBoxes[o],
                       objectTreeView(model, o), model.objectTreePlacement};
        return;
    }
    const int *self = model.selfPairs + 2 * (pair - environmentPairs);
    a = component(self[0]);
    b = component(self[1]);
}

/** \brief The hull test of a pair (CpuBackend's hullRelation). \a links are the state's link poses
    (double, world frame), as the CPU backend's. */
RC_HD HullRelation pairHullRelation(const ModelArrays &model, std::uint32_t pair, const Pose<double> *links,
                                    double padding, bool proveOverlap)
{
    const std::uint32_t m = static_cast<std::uint32_t>(model.numComponents);
    const std::uint32_t environmentPairs = static_cast<std::uint32_t>(model.numObjects) * m;
    if (pair < environmentPairs)
    {
        const std::uint32_t c = pair % m, o = pair / m;
        return relateSolids(model.convex, c, links[model.componentLink[c]], m + o, Pose<double>::identity(), padding,
                            proveOverlap);
    }
    const int *self = model.selfPairs + 2 * (pair - environmentPairs);
    return relateSolids(model.convex, static_cast<std::uint32_t>(self[0]), links[model.componentLink[self[0]]],
                        static_cast<std::uint32_t>(self[1]), links[model.componentLink[self[1]]], padding,
                        proveOverlap);
}

RC_HD Vec3<float> stageVertex(const StageSolid &solid, std::uint32_t index)
{
    const Vec3<float> local{solid.vertices[3 * index], solid.vertices[3 * index + 1], solid.vertices[3 * index + 2]};
    return solid.pose ? transformPoint(*solid.pose, local) : local;
}

/** \brief Rasterizes triangle t of the pair (A's triangles first, then B's, as on the CPU). */
template <class Emit>
RC_HD int rasterizePairTriangle(const StageSolid &a, const StageSolid &b, std::uint32_t t, const RasterGrid &grid,
                                float margin, Emit &&emit)
{
    const bool partyB = t >= a.slice.numTriangles;
    const StageSolid &solid = partyB ? b : a;
    const std::uint32_t local = partyB ? t - a.slice.numTriangles : t;
    const std::uint32_t *tri = solid.triangles + 3 * local;
    const Vec3<float> p0 = stageVertex(solid, tri[0]), p1 = stageVertex(solid, tri[1]), p2 = stageVertex(solid, tri[2]);
    if (!triangleMeetsImage(p0, p1, p2, grid, margin))
        return 0;
    const std::uint32_t code = partyB ? (local | kPartyB) : local;
    return rasterizeTriangle(grid, p0, p1, p2,
                             [&](int pixel, float depth, bool entering) { emit(pixel, depth, entering ? code | kEntering : code); });
}

/** \brief The two meshes of a pair as the exact phase reads them, with their poses (double,
    world frame) at a state whose link poses are \a links, and whether each is closed. */
RC_HD void exactSolids(const ModelArrays &model, std::uint32_t pair, const Pose<double> *links, ExactTree &a,
                       Pose<double> &poseA, bool &closedA, ExactTree &b, Pose<double> &poseB, bool &closedB)
{
    const std::uint32_t m = static_cast<std::uint32_t>(model.numComponents);
    const std::uint32_t environmentPairs = static_cast<std::uint32_t>(model.numObjects) * m;
    auto component = [&](std::uint32_t c, ExactTree &tree, Pose<double> &pose, bool &closed) {
        const MeshSlice &slice = model.components[c];
        tree = exactTreeOf(model.componentExact, c, componentTreeView(model, static_cast<int>(c)), slice.firstTriangle,
                           slice.numTriangles);
        pose = links[model.componentLink[c]];
        closed = slice.closed;
    };
    if (pair < environmentPairs)
    {
        component(pair % m, a, poseA, closedA);
        const std::uint32_t o = pair / m;
        const MeshSlice &slice = model.objects[o];
        b = exactTreeOf(model.objectExact, o, objectTreeView(model, static_cast<int>(o)), slice.firstTriangle,
                        slice.numTriangles);
        poseB = Pose<double>::identity();
        closedB = slice.closed;
        return;
    }
    const int *self = model.selfPairs + 2 * (pair - environmentPairs);
    component(static_cast<std::uint32_t>(self[0]), a, poseA, closedA);
    component(static_cast<std::uint32_t>(self[1]), b, poseB, closedB);
}

/** \brief The exact phase in the stages: every pair still open after the raster (or without one) is
    decided on the executor by the exact test (solidsOverlap, what the CPU backend decides it by),
    with its first contact: the triangle of B and the place. Not conservative mode's unproven pairs
    other than mesh obstacles, which the host settles as colliding. One element per candidate, in
    \a order when given (pair order: the same trees in a warp). \a exactFlags (numCandidates) gets
    1 per pair decided here. */
template <class Exec>
void decideOpenPairs(Exec &ex, const ModelArrays &md, const StageSettings &st, const Pose<double> *links,
                     std::uint32_t numCandidates, const std::uint32_t *order, PairOutcome *decided,
                     std::uint8_t *exactFlags)
{
    const int numLinks = md.numLinks;
    const std::uint32_t m = static_cast<std::uint32_t>(md.numComponents);
    const std::uint32_t environmentPairs = static_cast<std::uint32_t>(md.numObjects) * m;
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = order ? order[k] : k;
        PairOutcome &out = decided[c];
        exactFlags[c] = 0;
        if (out.status != PairOpen)
            return;
        const bool meshObstacle = out.pair < environmentPairs && hasPatches(md.convex, m + out.pair / m);
        if (st.unprovenCollides && !(st.meshObstaclesUnproven && meshObstacle))
            return;
        ExactTree a, b;
        Pose<double> poseA, poseB;
        bool closedA = false, closedB = false;
        exactSolids(md, out.pair, links + static_cast<std::size_t>(out.state) * numLinks, a, poseA, closedA, b, poseB,
                    closedB);
        ExactContact contact;
        exactFlags[c] = 1;
        if (!solidsOverlap(a, poseA, closedA, b, poseB, closedB, pairPadding(md, st, out.state, out.pair), &contact))
        {
            out.status = PairApart;
            return;
        }
        out.status = PairOverlaps;
        out.triangle = contact.triangleB;
        out.position[0] = contact.position.x;
        out.position[1] = contact.position.y;
        out.position[2] = contact.position.z;
    });
}

/** \brief The per-state reduction's part on the executor (StageSettings::onlyDecisive): of each
    state's outcomes (in pair order) only those the host reads: the first overlap that settles the
    state (a curved pair's does not when the host confirms it on the exact shapes), and the pairs
    before it the host must still decide; no pair settled apart. Every other outcome stays on the
    executor, so a batch's download is about one outcome per colliding state. */
template <class Exec>
void reduceOutcomes(Exec &ex, const ModelArrays &md, const StageSettings &st, std::uint32_t numStates,
                    std::uint32_t numCandidates, const PairOutcome *decided, const PairOutcome *&outcomes,
                    std::uint32_t &numOutcomes)
{
    outcomes = decided;
    numOutcomes = numCandidates;
    if (!st.onlyDecisive)
        return;
    unsigned long long *firstSettled = ex.template buffer<unsigned long long>(BufferFirstSettled, numStates + 1);
    std::uint8_t *keep = ex.template buffer<std::uint8_t>(BufferKeep, numCandidates + 1);
    ex.forEach(numStates, [=] RC_LAMBDA(std::size_t s) { firstSettled[s] = ~0ull; });
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) {
        const PairOutcome &o = decided[c];
        const bool curved = st.confirmCurvedOverlaps && o.pair < md.numCurvedPairFlags && md.curvedPairs[o.pair];
        if (o.status == PairOverlaps && !curved)
            atomicMinimum(&firstSettled[o.state], static_cast<unsigned long long>(c));
    });
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) {
        keep[c] = decided[c].status != PairApart && c <= firstSettled[decided[c].state] ? 1 : 0;
    });
    std::uint32_t *kept = ex.template buffer<std::uint32_t>(BufferKept, numCandidates + 1);
    const std::uint32_t numKept = ex.selectFlagged(keep, numCandidates, kept);
    PairOutcome *compact = ex.template buffer<PairOutcome>(BufferKeptOutcomes, numKept + 1);
    ex.forEach(numKept, [=] RC_LAMBDA(std::size_t k) { compact[k] = decided[kept[k]]; });
    outcomes = compact;
    numOutcomes = numKept;
}

/** \brief A chunk's last stages, with or without a raster before them: the exact phase on the
    pairs still open (decideOpenPairs), the reduction's compaction (reduceOutcomes), and the counts
    every chunk adds. */
template <class Exec>
void finishChunk(Exec &ex, const ModelArrays &md, const StageSettings &st, const Pose<double> *links,
                 std::uint32_t numStates, std::uint32_t numCandidates, const std::uint32_t *order, PairOutcome *decided,
                 const PairOutcome *&outcomes, std::uint32_t &numOutcomes, StageCounts *counts)
{
    std::uint8_t *exactFlags = ex.template buffer<std::uint8_t>(BufferExactFlags, numCandidates + 1);
    decideOpenPairs(ex, md, st, links, numCandidates, order, decided, exactFlags);
    reduceOutcomes(ex, md, st, numStates, numCandidates, decided, outcomes, numOutcomes);
    if (!counts)
        return;
    counts->states += numStates;
    counts->survivingPairs += numCandidates;
    std::uint32_t *list = ex.template buffer<std::uint32_t>(BufferRasterizedList, numCandidates + 1);
    counts->exactPairs += ex.selectFlagged(exactFlags, numCandidates, list);
}

/** \brief Runs the stages for \a numStates states (host arrays: \a hostStates row-major,
    \a hostAdmissible 1 per state that passed the bounds check). On return \a outcomes points at
    the surviving pairs' outcomes in the executor's memory (\a numOutcomes of them, in (state,
    pair) order). Returns false, having decided nothing, when the chunk exceeds \a budget (the
    caller splits it); else adds to \a counts (when not null) what the chunk did. */
template <class Exec>
bool runStageChunk(Exec &ex, const ModelArrays &model, const StageSettings &settings, const StageBudget &budget,
                   const double *hostStates, const std::uint8_t *hostAdmissible, std::uint32_t numStates,
                   const PairOutcome *&outcomes, std::uint32_t &numOutcomes, StageCounts *counts = nullptr)
{
    const int dof = model.numCoordinates, m = model.numComponents, numLinks = model.numLinks;
    const std::uint32_t pairs = model.numPairs();
    const std::uint32_t environmentPairs =
        static_cast<std::uint32_t>(model.numObjects) * static_cast<std::uint32_t>(m);
    if (static_cast<std::size_t>(numStates) * pairs > budget.maxPairElements)
        return false;

    double *states = ex.template buffer<double>(BufferStates, static_cast<std::size_t>(numStates) * dof);
    std::uint8_t *admissible = ex.template buffer<std::uint8_t>(BufferAdmissible, numStates);
    ex.upload(states, hostStates, static_cast<std::size_t>(numStates) * dof);
    ex.upload(admissible, hostAdmissible, numStates);
    StageSettings st = settings;  // with the chunk's pair paddings in executor memory
    if (settings.extraPadding.any())
    {
        const std::size_t rows = settings.extraPadding.rowPerState ? numStates : 1;
        const std::size_t environmentValues = rows * static_cast<std::size_t>(m);
        const std::size_t selfValues = rows * static_cast<std::size_t>(model.numSelfPairs);
        double *environment = ex.template buffer<double>(BufferExtraEnvironment, environmentValues + 1);
        double *self = ex.template buffer<double>(BufferExtraSelf, selfValues + 1);
        ex.upload(environment, settings.extraPadding.environment, environmentValues);
        ex.upload(self, settings.extraPadding.self, selfValues);
        st.extraPadding.environment = environment;
        st.extraPadding.self = self;
    }

    // 1. Forward kinematics and the hybrid hierarchy's boxes.
    double *jointValues = ex.template buffer<double>(BufferJointValues, static_cast<std::size_t>(numStates) * model.numJoints + 1);
    Pose<double> *links = ex.template buffer<Pose<double>>(BufferLinks, static_cast<std::size_t>(numStates) * numLinks);
    const std::size_t componentElements = static_cast<std::size_t>(numStates) * m;
    Pose<float> *poses = ex.template buffer<Pose<float>>(BufferComponentPose, componentElements + 1);
    OrientedBox *boxes = ex.template buffer<OrientedBox>(BufferComponentBox, componentElements + 1);
    Box *bounds = ex.template buffer<Box>(BufferComponentBounds, componentElements + 1);
    Box *layers = ex.template buffer<Box>(BufferLayers, componentElements + 1);
    Sphere *robotSphere = ex.template buffer<Sphere>(BufferRobotSphere, numStates);
    float *reachPadding = ex.template buffer<float>(BufferReachPadding, numStates);
    const ModelArrays md = model;
    ex.forEach(numStates, [=] RC_LAMBDA(std::size_t s) {
        if (admissible[s])
            linkPoses(md.joints, md.numJoints, states + s * dof, jointValues + s * md.numJoints, links + s * numLinks);
    });
    ex.forEach(componentElements, [=] RC_LAMBDA(std::size_t i) {
        const std::size_t s = i / m;
        const int c = static_cast<int>(i % m);
        if (!admissible[s])
            return;
        poses[i] = toFloatPose(links[s * numLinks + md.componentLink[c]], md.origin);
        boxes[i] = transformBox(poses[i], md.componentLocalBoxes[c]);
        bounds[i] = boundsOf(boxes[i]);
    });
    ex.forEach(numStates, [=] RC_LAMBDA(std::size_t s) {
        if (!admissible[s] || m == 0)
            return;
        computeLayerBounds(bounds + s * m, md.componentSubtreeEnd, m, layers + s * m);
        Box all = emptyBox();
        for (int c = 0; c < m; ++c)
            extend(all, bounds[s * m + c]);
        robotSphere[s] = boundingSphere(all);
        reachPadding[s] = floatPadding(environmentReachPadding(md, st, s));
    });

    // 2. Culls per (state, pair), then compaction: the survivors in (state, pair) order.
    const std::size_t pairElements = static_cast<std::size_t>(numStates) * pairs;
    std::uint8_t *flags = ex.template buffer<std::uint8_t>(BufferPairFlags, pairElements + 1);
    ex.forEach(pairElements, [=] RC_LAMBDA(std::size_t i) {
        const std::size_t s = i / pairs;
        const std::uint32_t pair = static_cast<std::uint32_t>(i % pairs);
        bool survives = false;
        if (admissible[s])
        {
            if (pair < environmentPairs)
            {
                const int o = static_cast<int>(pair / m), k = static_cast<int>(pair % m);
                const Box &objectBox = md.objectBoxes[o];
                survives = st.checkEnvironment && objectWithinReach(robotSphere[s], objectBox, reachPadding[s]) &&
                           layersReach(layers + s * m, md.componentSubtreeEnd, k, objectBox, reachPadding[s]) &&
                           solidsMayMeet(bounds[s * m + k], boxes[s * m + k], objectBox, md.objectOrientedBoxes[o],
                                         floatPadding(pairPadding(md, st, s, pair)));
            }
            else
            {
                const int *self = md.selfPairs + 2 * (pair - environmentPairs);
                survives = st.checkSelfCollision &&
                           solidsMayMeet(bounds[s * m + self[0]], boxes[s * m + self[0]], bounds[s * m + self[1]],
                                         boxes[s * m + self[1]], floatPadding(pairPadding(md, st, s, pair)));
            }
        }
        flags[i] = survives ? 1 : 0;
    });
    std::uint32_t *candidates = ex.template buffer<std::uint32_t>(BufferCandidates, pairElements + 1);
    const std::uint32_t numCandidates = ex.selectFlagged(flags, pairElements, candidates);

    // 3. Per surviving pair: the image window, the grid, and how many triangles to rasterize.
    // The survivors are in (state, pair) order, so a warp holds different pairs of a few states,
    // each proof with its own hulls and loop lengths (GJK over up to 128 points per solid and
    // passes over hundreds of vertices): the threads diverge (an H200, 2026-11-26: this stage was
    // 2/3 of a safe-mode batch's kernel time, at 6 % occupancy). Taken in pair order, a warp runs
    // one pair's proof for 32 states: the same hull data and trip counts (budget.orderedProofsFrom
    // says when that pays).
    const bool pairOrdered = numCandidates >= budget.orderedProofsFrom;
    std::uint32_t *proofOrder = nullptr;
    if (pairOrdered)
    {
        std::uint32_t *candidatePairs = ex.template buffer<std::uint32_t>(BufferCandidatePairs, numCandidates + 1);
        proofOrder = ex.template buffer<std::uint32_t>(BufferProofOrder, numCandidates + 1);
        ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) { candidatePairs[c] = candidates[c] % pairs; });
        ex.orderByKey(candidatePairs, numCandidates, pairs, proofOrder);
    }
    RasterGrid *grids = ex.template buffer<RasterGrid>(BufferGrids, numCandidates + 1);
    float *margins = ex.template buffer<float>(BufferMargins, numCandidates + 1);
    std::int32_t *status = ex.template buffer<std::int32_t>(BufferStatus, numCandidates + 1);
    unsigned long long *triangleCount = ex.template buffer<unsigned long long>(BufferTriangleCount, numCandidates + 1);
    std::uint8_t *rasterized = ex.template buffer<std::uint8_t>(BufferRasterized, numCandidates + 1);
    ex.forEach(numCandidates + 1, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = pairOrdered && k < numCandidates ? proofOrder[k] : k;
        triangleCount[c] = 0;
        rasterized[c] = 0;
        if (c == numCandidates)
            return;  // the scan's trailing zero: its output is the total
        const std::size_t s = candidates[c] / pairs;
        const std::uint32_t pair = candidates[c] % pairs;
        StageSolid a, b;
        pairSolids(md, pair, poses + s * m, bounds + s * m, a, b);
        const double padding = pairPadding(md, st, s, pair);
        const Box window = pairWindow(a.bounds, b.bounds, floatPadding(padding));
        // A mesh obstacle's proof walks its patches, serially per thread: on FCL's env.obj (an H200,
        // 2026-11-26) the stages ran at 0.3x the CPU backend on 16 cores, which skips that proof.
        const bool meshObstacle =
            st.meshObstaclesUnproven && pair < environmentPairs && hasPatches(md.convex, m + pair / m);
        const HullRelation relation = isEmpty(window) ? HullRelation::Apart
                                      : meshObstacle  ? HullRelation::Unknown
                                                      : pairHullRelation(md, pair, links + s * numLinks, padding,
                                                                         st.proveOverlaps);
        if (relation != HullRelation::Unknown)
        {
            // An overlap proven by the hulls has no triangle or place (the contact is not asked).
            status[c] = relation == HullRelation::Apart ? PairApart : PairOverlaps;
            return;
        }
        status[c] = PairOpen;
        if (!st.rasterize || !rasterUsable(a.slice.closed, b.slice.closed, window, st.pixel))
            return;  // the exact phase decides
        grids[c] = makeGrid(window, st.pixel, st.maxImageSide);
        margins[c] = pairMargin(window, grids[c], floatPadding(padding));
        rasterized[c] = 1;
        // Candidate triangles from the node culls: the leaves of both trees near the image.
        unsigned long long count = 0;
        forEachTriangleNearImage(a.tree, a.treePlacement, grids[c], margins[c], [&](std::uint32_t) { ++count; });
        forEachTriangleNearImage(b.tree, b.treePlacement, grids[c], margins[c], [&](std::uint32_t) { ++count; });
        triangleCount[c] = count;
    });
    PairOutcome *decided = ex.template buffer<PairOutcome>(BufferOutcomes, numCandidates + 1);
    if (!st.rasterize)
    {
        // Nothing to rasterize (exact and conservative mode, contacts asked): no counts to wait for.
        ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) {
            decided[c] = PairOutcome{static_cast<std::uint32_t>(candidates[c] / pairs), candidates[c] % pairs,
                                     status[c], -1, {0.0, 0.0, 0.0}};
        });
        finishChunk(ex, md, st, links, numStates, numCandidates, proofOrder, decided, outcomes, numOutcomes, counts);
        return true;
    }
    unsigned long long *itemStart = ex.template buffer<unsigned long long>(BufferItemStart, numCandidates + 1);
    const std::size_t numItems = ex.exclusiveSum(triangleCount, itemStart, numCandidates + 1);
    if (numItems > budget.maxItems)
        return false;
    // The candidates themselves, the same walk again: item i of pair c is triangle itemTriangles[i]
    // of the pair (A's numbers first, then B's after A's count, as rasterizePairTriangle reads them).
    std::uint32_t *itemTriangles = ex.template buffer<std::uint32_t>(BufferItemTriangles, numItems + 1);
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) {
        if (triangleCount[c] == 0)
            return;
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        unsigned long long slot = itemStart[c];
        forEachTriangleNearImage(a.tree, a.treePlacement, grids[c], margins[c],
                                 [&](std::uint32_t t) { itemTriangles[slot++] = t; });
        const std::uint32_t partyB = a.slice.numTriangles;
        forEachTriangleNearImage(b.tree, b.treePlacement, grids[c], margins[c],
                                 [&](std::uint32_t t) { itemTriangles[slot++] = partyB + t; });
    });

    // Pre-rasterization count per (pair, triangle): the per-triangle cull, then the pixels covered.
    unsigned long long *fragmentCount = ex.template buffer<unsigned long long>(BufferFragmentCount, numItems + 1);
    ex.forEach(numItems + 1, [=] RC_LAMBDA(std::size_t i) {
        if (i == numItems)
        {
            fragmentCount[i] = 0;
            return;
        }
        const std::uint32_t c = findSegment(itemStart, numCandidates, static_cast<unsigned long long>(i));
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        fragmentCount[i] = static_cast<unsigned long long>(
            rasterizePairTriangle(a, b, itemTriangles[i], grids[c], margins[c], [](int, float, std::uint32_t) {}));
    });
    unsigned long long *fragmentStart = ex.template buffer<unsigned long long>(BufferFragmentStart, numItems + 1);
    const std::size_t numFragments = ex.exclusiveSum(fragmentCount, fragmentStart, numItems + 1);
    if (numFragments > budget.maxFragments)
        return false;

    // 4. Rasterization into the counted slots, keyed by (pixel, depth); sort within each pair.
    unsigned long long *keys = ex.template buffer<unsigned long long>(BufferKeys, numFragments + 1);
    std::uint32_t *values = ex.template buffer<std::uint32_t>(BufferValues, numFragments + 1);
    ex.forEach(numItems, [=] RC_LAMBDA(std::size_t i) {
        const std::uint32_t c = findSegment(itemStart, numCandidates, static_cast<unsigned long long>(i));
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        std::size_t slot = fragmentStart[i];
        rasterizePairTriangle(a, b, itemTriangles[i], grids[c], margins[c],
                              [&](int pixel, float depth, std::uint32_t code) {
                                  keys[slot] = (static_cast<unsigned long long>(pixel) << 32) | depthKey(depth);
                                  values[slot] = code;
                                  ++slot;
                              });
    });
    std::uint32_t *segmentStart = ex.template buffer<std::uint32_t>(BufferSegmentStart, numCandidates + 1);
    ex.forEach(numCandidates + 1, [=] RC_LAMBDA(std::size_t c) {
        segmentStart[c] = static_cast<std::uint32_t>(fragmentStart[itemStart[c]]);
    });
    ex.sortSegments(keys, values, numFragments, segmentStart, numCandidates);

    // 5. Sort_Search_Pair on each pixel's run; the first hit pixel of each pair.
    Fragment *fragments = ex.template buffer<Fragment>(BufferFragments, numFragments + 1);
    unsigned long long *hit = ex.template buffer<unsigned long long>(BufferHit, numCandidates + 1);
    ex.forEach(numFragments, [=] RC_LAMBDA(std::size_t f) {
        fragments[f] = Fragment{depthFromKey(static_cast<std::uint32_t>(keys[f])), values[f]};
    });
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) { hit[c] = ~0ull; });
    ex.forEach(numFragments, [=] RC_LAMBDA(std::size_t f) {
        const std::uint32_t c = findSegment(segmentStart, numCandidates, static_cast<std::uint32_t>(f));
        const unsigned long long pixel = keys[f] >> 32;
        if (f > segmentStart[c] && (keys[f - 1] >> 32) == pixel)
            return;  // not the first fragment of its pixel's run
        std::uint32_t end = static_cast<std::uint32_t>(f) + 1;
        while (end < segmentStart[c + 1] && (keys[end] >> 32) == pixel)
            ++end;
        const int count = static_cast<int>(end - f);
        if (count < 2)
            return;
        // The radix sort ordered by depth; ties take the CPU's order (by code) here.
        sortFragments(fragments + f, count);
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        if (sortSearchPair(fragments + f, count, a.slice.closed, b.slice.closed) >= 0)
            atomicMinimum(&hit[c], (pixel << 32) | static_cast<unsigned long long>(f));
    });

    // Outcomes, in (state, pair) order.
    ex.forEach(numCandidates, [=] RC_LAMBDA(std::size_t c) {
        PairOutcome out{static_cast<std::uint32_t>(candidates[c] / pairs), candidates[c] % pairs, status[c], -1,
                        {0.0, 0.0, 0.0}};
        if (out.status == PairOpen && rasterized[c])
        {
            if (hit[c] != ~0ull)
            {
                const int pixel = static_cast<int>(hit[c] >> 32);
                const std::uint32_t run = static_cast<std::uint32_t>(hit[c] & 0xffffffffull);
                std::uint32_t end = run + 1;
                while (end < segmentStart[c + 1] && (keys[end] >> 32) == (hit[c] >> 32))
                    ++end;
                const std::size_t s = out.state;
                StageSolid a, b;
                pairSolids(md, out.pair, poses + s * m, bounds + s * m, a, b);
                const int at = sortSearchPair(fragments + run, static_cast<int>(end - run), a.slice.closed, b.slice.closed);
                float position[3];  // relative to the model's origin, as the raster works
                hitContact(fragments + run, at, grids[c], pixel, out.triangle, position);
                for (int k = 0; k < 3; ++k)
                    out.position[k] = static_cast<double>(position[k]) + md.origin[k];
                out.status = PairOverlaps;
            }
            else if (!st.confirmMisses && !(pairPadding(md, st, out.state, out.pair) > 0))
                out.status = PairApart;
        }
        decided[c] = out;
    });
    finishChunk(ex, md, st, links, numStates, numCandidates, proofOrder, decided, outcomes, numOutcomes, counts);
    if (counts)
    {
        std::uint32_t *list = ex.template buffer<std::uint32_t>(BufferRasterizedList, numCandidates + 1);
        counts->rasterizedPairs += ex.selectFlagged(rasterized, numCandidates, list);
        counts->candidateTriangles += numItems;
        counts->fragments += numFragments;
    }
    return true;
}
}  // namespace rastercheck::device
