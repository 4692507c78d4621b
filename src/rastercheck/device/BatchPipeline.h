#pragma once

// The batched pipeline: many states decided in one pass, stage by stage, each stage one data-
// parallel loop over its elements (a kernel on the GPU). The driver is a template over an
// executor that provides the loops, scans, compaction, ordering by a small key and a stable
// sort: the CUDA executor runs them as kernels and CUB calls (cuda/), the host executor as plain
// loops (collision/HostStageRunner), so the CPU test suite runs exactly the code the GPU runs,
// apart from those primitives.
//
// Stages per chunk of states:
//   1. forward kinematics (each joint's local pose per (state, joint), the chain per state), component
//      poses, OBBs and AABBs (per state x component);
//   2. the robot's reach per state (its components' bounds); culls per (state, object): the robot's
//      reach, then each component's AABB and OBB tests (which imply the CPU backend's distance
//      filter and layer tests), and per (state, self pair): the boxes, the clearance tables;
//      compaction of the survivors;
//   3. per surviving pair (in pair order when there are many): image window, the convex
//      separation proof, the grid, and the candidate triangles (both meshes' trees walked with the
//      node culls, counted, scanned, written); per (pair, candidate triangle): the per-triangle
//      cull and the pre-rasterization fragment count; scan;
//   4. rasterization into the counted slots; one stable sort by (pair, pixel);
//   5. each pixel run sorted by depth, Sort_Search_Pair on it; per pair the first hit pixel
//      (atomic minimum); outcomes;
//   6. the exact phase (device/ExactPhase.h) on every pair still open, with its first contact;
//      the per-state reduction's compaction: only the outcomes that decide a state come back.
// Each stage notes the overlaps it settles per state (noteOverlap); with only the deciding
// outcomes asked for, the later stages skip a state's pairs behind its first overlap, and its
// walks stop (pastFirstOverlap), as the CPU backend stops at a state's first colliding pair.
// The host finishes the reduction (the first colliding pair in pair order), confirms curved
// primitives on their exact shapes, and places conservative mode's unproven pairs (StagedBackend).
//
// A chunk's stages run in order on one executor (on the GPU one stream), and the host waits for it
// once in a small chunk: the counts that size later stages (survivors, candidate triangles,
// fragments, outcomes) stay on the executor as tallies, and the host sizes buffers and launches by
// bounds (Extent, CountGuesses, StageBudget::waitForCountsFrom).

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/ClearanceTables.h"
#include "rastercheck/device/CurvedShapes.h"
#include "rastercheck/device/ExactPhase.h"
#include "rastercheck/device/HostDevice.h"
#include "rastercheck/device/Kinematics.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/Raster.h"
#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/Stages.h"

// A stage's per-element function. Under nvcc a device lambda: the CUDA executor only launches it,
// and its closure is a plain struct of the captured values, which a pass's signature compares
// (PassRecorder); nvcc wraps a __host__ __device__ one in a type with its own copy constructor.
#if defined(__CUDACC__)
#define RC_LAMBDA __device__
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
    std::size_t numConvexSupportCellOffsets;
    std::size_t numConvexSupportCandidates;
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
    /** \brief Every solid's primitive shapes (CurvedSolids::arrays): what such a pair is decided by
        once its meshes overlap. */
    CurvedArrays curvedShapes;
    std::size_t numCurvedShapes;
    /** \brief Places the objects' trees (world frame) in the stages' float frame (relative to
        origin). */
    Pose<float> objectTreePlacement;
    /** \brief The self pairs' clearance tables (SelfPairTables): numSelfPairs entries of tableOf,
        numClearanceTables tables, numClearanceNodes clearances. */
    ClearanceTableArrays clearanceTables;
    std::size_t numClearanceTables;
    std::size_t numClearanceNodes;

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
    /** \brief An overlap of a pair with curved primitives is decided again on the exact shapes
        (safe and exact mode), in the exact phase (decideOpenPairs). */
    bool confirmCurvedOverlaps;
    /** \brief The clearance tables may prove a self pair apart in the pair cull (safe and exact
        mode, ModeRules::clearanceTables), as the CPU backend's self-pair loop does. */
    bool clearanceTables;
    /** \brief Only the outcomes the per-state reduction reads come back (reduceOutcomes): per state,
        the pairs up to its first settled overlap, none settled apart. */
    bool onlyDecisive;
    /** \brief The caller reads each colliding state's first contact (the CPU backend's): a pair's
        split walk ends at its first contact in walk order, a state's pairs at its first overlap in
        pair order. Else any contact decides: a pair's parts stop at the first any of them finds,
        a state's pairs at the first overlap any of them finds, and only that overlap comes back
        (stoppedByFound, WalkPart::anyContact, pastFirstOverlap, reduceOutcomes). */
    bool firstContacts;
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

/** \brief Where a pair stands after the stages. */
enum PairStatus : std::int32_t
{
    PairApart = 0,     ///< settled: does not collide
    PairOpen = 1,      ///< left to the host (conservative mode's unproven pairs)
    PairOverlaps = 2   ///< a ray found the solids overlapping (triangle and position set), or the hulls did (neither)
};

/** \brief A hull proof's answer as a pair's status; \a unknown where the proof settled nothing. */
RC_HD std::int32_t pairStatusOf(HullRelation relation, std::int32_t unknown)
{
    return relation == HullRelation::Apart ? PairApart : relation == HullRelation::Overlapping ? PairOverlaps : unknown;
}

/** \brief One pair that survived the culls. Outcomes come sorted by (state, pair). */
struct PairOutcome
{
    std::uint32_t state;  // within the chunk
    std::uint32_t pair;
    std::int32_t status;
    std::int32_t triangle;
    double position[3];  ///< world frame
};

/** \brief In a small chunk, each tree's image walk for a rasterized pair's candidate triangles runs in
    2^kImageWalkDepth parts, a thread each (forEachTriangleNearImage's parts): there the slowest
    pair's walks are the call's latency. Larger chunks walk each tree in one thread. */
constexpr std::uint32_t kImageWalkDepth = 2;

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
    /** Chunks with at least this many pairs past the box culls (their bound, survivorBound) take the
        proofs in pair order (stage 3). Measured on an H200 (2026-11-26, docs/benchmarks.md "GPU"):
        the order made the proof stage 1.8-3.2x faster and a batch of 10^6 Panda states 1.3-1.4x,
        10^5 states 1.0-1.2x, but batches of 10^3-10^4 states (2 000 to 20 000 pairs, less than one
        wave of the device) a third slower; there the unordered stage stays. */
    std::size_t orderedProofsFrom = std::size_t(1) << 16;
    /** Chunks whose pairs past the culls are bounded below this (survivorBound: every (state, pair)
        element until the executor has counted a chunk's survivors, then as many per state as its
        chunks needed) make one wait, for their outcomes: the counts only the executor knows (pairs
        past the culls, candidate triangles, fragments, outcomes) stay there (Extent), and the host
        sizes their buffers and launches by those bounds and by what the executor's earlier small
        chunks needed of the raster (CountGuesses: its first rasterizing chunk waits for them); a
        chunk that needs more runs again. Other chunks wait for each count (five waits), so that
        their buffers and launches have the counts' sizes: an executor's first batch of more (state,
        pair) elements than this, and chunks bounded past it. At 2^16, as orderedProofsFrom, the
        chunks that fill a device (25 000 Panda states and more at 1.7 pairs a state past the culls,
        half again) size their sorts and launches by the counts and take the proofs in pair order,
        and smaller ones, once counted (1 000 to 10^4 Panda states, 1 000 of the crane's with its
        935 pairs a state), wait once; before, every chunk under 2^18 (state, pair) elements waited
        once (1 000 Panda states from the first call on), and no larger one. */
    std::size_t waitForCountsFrom = std::size_t(1) << 16;
    /** The least bound of a small chunk's pairs past the culls, whatever CountGuesses says per
        state: a few hundred threads cost a device no more than a few, and the fewer states a batch
        has, the more its pairs per state vary (a planner's edge among obstacles against the random
        samples before it). */
    std::size_t minSurvivorBound = 256;
    /** Threads that share each open pair's exact walk in a chunk below waitForCountsFrom (at most
        kMaxWalkParts; decideOpenPairs): there the slowest pair's walk is the call's latency, and a
        few hundred pairs leave most of a device idle. Larger chunks walk each pair in one thread:
        they have pairs enough to fill it. */
    std::uint32_t exactWalkParts = kMaxWalkParts;
    /** Threads the split walks of a chunk below waitForCountsFrom may take together: each open pair
        gets as many parts as keep the pairs past the culls within them (walkPartsPerPair), so a
        chunk with pairs enough to fill the device walks each pair in one thread. There, parts only
        add work: a part walks its subtree to the end unless another has found a contact already
        (an earlier one, where the first contact is read). Measured on an H100 (2026-11-27,
        docs/benchmarks.md "GPU"): splitting every pair of FCL's env/rob at 10^5 states made the
        batch half as fast. 2^16: a heavy kernel's resident threads on an H100 (132 SMs, 25 %
        occupancy). */
    std::size_t exactWalkThreads = std::size_t(1) << 16;
};

/** \brief Parts each open pair's walk is split into (decideOpenPairs): a power of two (walkPartStart),
    the largest of up to \a parts that keeps \a pairs pairs (past the culls) within \a walkThreads
    threads, at least one. */
RC_HD std::uint32_t walkPartsPerPair(std::size_t pairs, std::uint32_t parts, std::size_t walkThreads)
{
    const std::size_t fit = pairs > 0 ? walkThreads / pairs : parts;
    std::uint32_t perPair = 1;
    while (2 * perPair <= parts && 2 * perPair <= fit)
        perPair *= 2;
    return perPair;
}

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
    host executor's tests see the GPU's launches and waits; allocations differ only in that the GPU
    also grows page-locked host mirrors of the buffers it copies. */
struct ExecutorCounts
{
    unsigned long long calls = 0;             ///< runs of the stages (StageRunner::run)
    unsigned long long chunks = 0;
    unsigned long long reruns = 0;            ///< chunk passes run again: a count outgrew CountGuesses
    unsigned long long launches = 0;          ///< kernels and CUB calls
    unsigned long long synchronizations = 0;  ///< waits of the host for the executor
    unsigned long long allocations = 0;       ///< scratch buffers (and on the GPU host mirrors) grown
    /** Passes recorded after beginReplayable() whose signature was seen once before: compiled
        (on the GPU captured as a CUDA graph), and seen compiled: replayed (one graph launch). */
    unsigned long long compiledPasses = 0;
    unsigned long long replayedPasses = 0;
    double seconds = 0;                       ///< host clock inside the passes (kernels, copies, waits)
    /** The host executor timing its elements (makeHostStageRunner): per kernel the slowest
        element's time, summed. A device running a thread per element waits for that chain (at
        its own thread speed) besides its launches; 0 from any other executor. */
    double criticalPathSeconds = 0;

    ExecutorCounts &operator+=(const ExecutorCounts &other)
    {
        calls += other.calls;
        chunks += other.chunks;
        reruns += other.reruns;
        launches += other.launches;
        synchronizations += other.synchronizations;
        allocations += other.allocations;
        compiledPasses += other.compiledPasses;
        replayedPasses += other.replayedPasses;
        seconds += other.seconds;
        criticalPathSeconds += other.criticalPathSeconds;
        return *this;
    }
    /** \brief What happened between \a earlier and these counts (both of one runner). */
    ExecutorCounts since(const ExecutorCounts &earlier) const
    {
        return ExecutorCounts{calls - earlier.calls,
                              chunks - earlier.chunks,
                              reruns - earlier.reruns,
                              launches - earlier.launches,
                              synchronizations - earlier.synchronizations,
                              allocations - earlier.allocations,
                              compiledPasses - earlier.compiledPasses,
                              replayedPasses - earlier.replayedPasses,
                              seconds - earlier.seconds,
                              criticalPathSeconds - earlier.criticalPathSeconds};
    }
};

/** \brief Counts the stages leave in executor memory (BufferTallies), each written by the stage
    that makes it and read by later stages there; the host reads them after the chunk's wait. */
enum Tally : int
{
    TallyCandidates,  ///< (state, pair) elements past the box culls
    TallyItems,       ///< (pair, candidate triangle) elements
    TallyFragments,
    TallyOutcomes,    ///< outcomes that come back (reduceOutcomes)
    TallyRasterized,  ///< StageCounts::rasterizedPairs (when counting)
    TallyExact,       ///< StageCounts::exactPairs (when counting)
    kNumTallies
};

/** \brief The elements of a stage when the host has not waited for their count: buffers and
    launches are sized by \a bound, and the executor runs the first *count (a tally, written by an
    earlier stage of the chunk). A count past its bound (a chunk that needed more than CountGuesses
    said) runs nothing: the host sees the count after the chunk's wait and runs the chunk again
    with room for it. */
struct Extent
{
    std::size_t bound;
    const unsigned long long *count;  ///< executor memory: a GPU's on the CUDA executor

    // Device code alone may read the count (RC_DEVICE: the host reads a tally from the chunk's
    // download); executor memory is the host's on the host executor, a GPU's on the CUDA one.
    RC_DEVICE bool fits() const { return *count <= bound; }
    RC_DEVICE std::size_t size() const { return fits() ? static_cast<std::size_t>(*count) : 0; }
};

/** \brief \a n rounded up to a step of a quarter of its power of two (at most a quarter more), at
    most \a limit. A guess that creeps up from batch to batch changes a bound, and with it the
    buffers (an allocation) and a pass's signature (a CUDA graph captured again), only past a step. */
inline std::size_t coarseBound(double n, std::size_t limit)
{
    if (!(n < static_cast<double>(limit)))
        return limit;
    const std::size_t value = n > 0.0 ? static_cast<std::size_t>(std::ceil(n)) : 0;
    std::size_t step = 1;
    while (step * 8 <= value)
        step *= 2;
    const std::size_t rounded = (value + step - 1) / step * step;
    return rounded < limit ? rounded : limit;
}

/** \brief \a rate (per state) grown to hold \a needed for \a numStates states, half again. */
inline double grownRate(double rate, std::size_t needed, std::uint32_t numStates)
{
    const double roomy = 1.5 * static_cast<double>(needed) / static_cast<double>(numStates > 0 ? numStates : 1);
    return rate > roomy ? rate : roomy;
}

/** \brief What an executor's earlier chunks needed of one count: the most, and the most per state,
    each half again. A small chunk's bound is the larger of the two for its states, so that a
    batch like an earlier one fits what that one needed, and a larger batch of the same kind what
    its states need. */
struct CountGuess
{
    std::size_t most = 0;
    double perState = 0.0;

    std::size_t bound(std::uint32_t numStates, std::size_t limit) const
    {
        const double byStates = perState * static_cast<double>(numStates);
        return coarseBound(byStates > static_cast<double>(most) ? byStates : static_cast<double>(most), limit);
    }

    /** \brief Grown to hold \a needed for \a numStates states, within \a limit. */
    void grow(std::size_t needed, std::uint32_t numStates, std::size_t limit)
    {
        const std::size_t roomy = needed + needed / 2 < limit ? needed + needed / 2 : limit;
        most = most > roomy ? most : roomy;
        perState = grownRate(perState, needed, numStates);
    }
};

/** \brief What an executor's earlier chunks needed of the counts the host does not wait for in
    small chunks (StageBudget::waitForCountsFrom): the next small chunk sizes their buffers and
    launches by these, so that a batch like the last allocates nothing and waits once. */
struct CountGuesses
{
    /** Pairs past the culls per state that the executor's chunks needed, half again (negative
        before one was counted): a small chunk's survivors, and so every buffer and launch per
        survivor, are sized by it (survivorBound). Sized by every pair, a chunk of 1 000 Panda
        states launched 153 000 threads per survivor kernel for the 800 to 1 700 pairs past its
        culls. Per state only (CountGuess also keeps the most): each state's pairs are culled on
        their own, so the rate varies little between batches (StageBudget::minSurvivorBound covers
        the smallest), and a bound kept from a larger chunk would size small ones by it. */
    double survivorsPerState = -1.0;
    /** Whether items and fragments hold what a chunk needed: a rasterizing small chunk waits for
        those counts until they do, and after a chunk that needed more (run again). */
    bool measured = false;
    CountGuess items;
    CountGuess fragments;
    /** Outcomes per state downloaded with the tallies in the chunk's wait (more take a second). */
    std::size_t outcomesPerState = 1;
    /** The executor ran out of scratch memory (StageMemoryExhausted): from then on its chunks wait
        for every count and size their buffers by it, the least memory a chunk can take. */
    bool outOfMemory = false;
};

/** \brief The executor's scratch buffers, one per stage output; sized per chunk, reused. */
enum StageBuffer : int
{
    BufferStates,
    BufferAdmissible,
    BufferJointPoses,
    BufferLinks,
    BufferComponentPose,
    BufferComponentBox,
    BufferComponentBounds,
    BufferRobotReach,
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
    BufferRasterFragments,
    BufferHit,
    BufferOutcomes,
    BufferExactFlags,
    BufferFirstPart,
    BufferPartContacts,
    BufferFirstOverlap,
    BufferKeep,
    BufferKept,
    BufferKeptOutcomes,
    BufferTallies,
    kNumStageBuffers
};

/** \brief A state's robot as the pair cull sees it first: the union of its components' bounds, and
    the largest padding of its pairs with an object. */
struct RobotReach
{
    Box bounds;
    float padding;
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

/** \brief Pair \a pair's two solids in the numbering of ConvexArrays and CurvedArrays (the
    components, then the objects): A a component; B a component (a self pair) or, for an
    environment pair, the number of components plus the object's. */
RC_HD void pairSolidNumbers(const ModelArrays &model, std::uint32_t pair, std::uint32_t &a, std::uint32_t &b)
{
    const std::uint32_t m = static_cast<std::uint32_t>(model.numComponents);
    const std::uint32_t environmentPairs = static_cast<std::uint32_t>(model.numObjects) * m;
    if (pair < environmentPairs)
    {
        a = pair % m;
        b = m + pair / m;
        return;
    }
    const int *self = model.selfPairs + 2 * (pair - environmentPairs);
    a = static_cast<std::uint32_t>(self[0]);
    b = static_cast<std::uint32_t>(self[1]);
}

/** \brief \a relate (WholeHullsProof or FullProof) on the
    two solids of a pair (CpuBackend's hullRelation). \a links are the state's link poses (double,
    world frame), as the CPU backend's. */
/** \brief The light proof (relateWholeHulls) and the full one (relateSolids), as pairHullRelation
    takes them. */
struct WholeHullsProof
{
    RC_HD HullRelation operator()(const ConvexArrays &arrays, std::uint32_t a, const Pose<double> &poseA,
                                  std::uint32_t b, const Pose<double> &poseB, double padding, bool proveOverlap) const
    {
        return relateWholeHulls(arrays, a, poseA, b, poseB, padding, proveOverlap);
    }
};
struct FullProof
{
    RC_HD HullRelation operator()(const ConvexArrays &arrays, std::uint32_t a, const Pose<double> &poseA,
                                  std::uint32_t b, const Pose<double> &poseB, double padding, bool proveOverlap) const
    {
        return relateSolids(arrays, a, poseA, b, poseB, padding, proveOverlap);
    }
};

template <class Relate>
RC_HD HullRelation pairHullRelation(const ModelArrays &model, std::uint32_t pair, const Pose<double> *links,
                                    double padding, bool proveOverlap, Relate &&relate)
{
    // One call of the proof for both kinds of pair: on the device a call site is an inlined copy,
    // and two copies cost the light proof 11 registers a thread (sm_90).
    std::uint32_t a, b;
    pairSolidNumbers(model, pair, a, b);
    const bool objectB = b >= static_cast<std::uint32_t>(model.numComponents);
    return relate(model.convex, a, links[model.componentLink[a]], b,
                  objectB ? Pose<double>::identity() : links[model.componentLink[b]], padding, proveOverlap);
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

/** \brief Waits for the executor and reads one tally. */
template <class Exec>
std::size_t waitFor(Exec &ex, const unsigned long long *tally)
{
    const unsigned long long *host = ex.template download<unsigned long long>(BufferTallies, tally, 1);
    ex.wait();
    return static_cast<std::size_t>(*host);
}

/** \brief Whether an overlap of \a pair is decided again on its curved primitives' exact shapes
    (StageSettings::confirmCurvedOverlaps, and the pair has such a primitive). */
RC_HD bool curvedOverlapDecidedAgain(const ModelArrays &md, const StageSettings &st, std::uint32_t pair)
{
    return st.confirmCurvedOverlaps && pair < md.numCurvedPairFlags && md.curvedPairs[pair];
}

/** \brief Notes that surviving-pair element \a c of state \a s overlaps for good: \a firstOverlap
    holds per state the lowest such element (in (state, pair) order, so in pair order within the
    state), which the later stages (pastFirstOverlap) and the reduction read. */
RC_HD void noteOverlap(unsigned long long *firstOverlap, std::size_t s, std::size_t c)
{
    atomicMinimum(firstOverlap + s, static_cast<unsigned long long>(c));
}

/** \brief Notes an overlap a proof, the raster or a walk found for element \a c (pair \a pair) of
    state \a s: final, unless the pair has curved primitives, whose overlap the exact phase's end
    decides again on their exact shapes (and notes there). */
RC_HD void noteFoundOverlap(const ModelArrays &md, const StageSettings &st, unsigned long long *firstOverlap,
                            std::size_t s, std::size_t c, std::uint32_t pair)
{
    if (!curvedOverlapDecidedAgain(md, st, pair))
        noteOverlap(firstOverlap, s, c);
}

/** \brief Whether element \a c of state \a s need not be decided: only the outcomes the reduction
    reads come back (StageSettings::onlyDecisive), which end at the state's first overlap, and an
    earlier pair of the state already overlaps (any other, where no contact is read:
    StageSettings::firstContacts). The CPU backend stops at a state's first colliding pair; the
    stages decide a state's pairs side by side, and skip those behind an overlap found in an
    earlier kernel, or while they run (their walks stop). Such a pair is left as it stands, and
    never read. */
RC_HD bool pastFirstOverlap(const StageSettings &st, const unsigned long long *firstOverlap, std::size_t s,
                            std::size_t c)
{
    return st.onlyDecisive &&
           stoppedByFound(atomicLoad(firstOverlap + s), static_cast<unsigned long long>(c), !st.firstContacts);
}

/** \brief The exact phase in the stages: every pair still open after the raster (or without one) is
    decided on the executor by the exact test (solidsOverlap, what the CPU backend decides it by),
    with its first contact: the triangle of B and the place. Not conservative mode's unproven pairs
    other than mesh obstacles, which the host settles as colliding. One element per candidate, in
    \a order when given (pair order: the same trees in a warp; only with the survivors' count
    known, so that order holds exactly the survivors). \a exactFlags (survivors.bound) gets 1 per
    pair decided here, 0 elsewhere. Nothing is decided when the raster's \a items or \a fragments
    outgrew their bounds: that pass runs again.

    A pair's walk of both trees is serial, and in a small batch the slowest pair's walk is the
    call's latency, so each pair's walk is split into up to \a walkParts parts (walkPartStart: each
    part finds its start in its own thread), one thread each, as many as keep the pairs past the
    culls within \a walkThreads threads (walkPartsPerPair); the first part in walk order that finds
    a contact gives the pair's first contact, the one the whole walk finds, and the parts after it
    stop (all parts, where no contact is read: StageSettings::firstContacts). Then one thread per
    pair ends it: the contact, or the containment test (solidsContain), and curved shapes. Three
    kernels; with \a walkParts 1, the pair's whole walk in one thread, as a large batch takes it. */
template <class Exec>
void decideOpenPairs(Exec &ex, const ModelArrays &md, const StageSettings &st, const Pose<double> *links,
                     Extent survivors, Extent items, Extent fragments, const std::uint32_t *order,
                     std::uint32_t walkParts, std::size_t walkThreads, PairOutcome *decided,
                     unsigned long long *firstOverlap, std::uint8_t *exactFlags)
{
    const int numLinks = md.numLinks;
    const std::uint32_t m = static_cast<std::uint32_t>(md.numComponents);
    const std::uint32_t environmentPairs = static_cast<std::uint32_t>(md.numObjects) * m;
    const std::size_t bound = survivors.bound;
    const std::uint32_t parts = walkParts < 1 ? 1 : (walkParts > kMaxWalkParts ? kMaxWalkParts : walkParts);
    // The parts of all pairs: survivors x parts per pair, which walkPartsPerPair keeps within
    // walkThreads (or the survivors, one part each) and which is at most bound x parts.
    const std::size_t splitThreads = bound * parts < walkThreads ? bound * parts : walkThreads;
    const std::size_t partThreads = parts > 1 && splitThreads > bound ? splitThreads : bound;
    unsigned long long *firstPart = ex.template buffer<unsigned long long>(BufferFirstPart, bound + 1);
    ExactContact *partContacts = ex.template buffer<ExactContact>(BufferPartContacts, partThreads + 1);
    // 1. Which pairs the exact phase decides.
    ex.forEach(bound, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = order ? order[k] : k;
        exactFlags[c] = 0;
        firstPart[c] = kNoneFound;  // no part found a contact
        if (c >= survivors.size() || !items.fits() || !fragments.fits())
            return;
        const PairOutcome &out = decided[c];
        // The stages see curved primitives as their meshes, which lie outside the exact shapes: an
        // overlap of such a pair, however found, is decided again here, as the CPU backend decides it.
        const bool curved = curvedOverlapDecidedAgain(md, st, out.pair);
        if (out.status != PairOpen && !(curved && out.status == PairOverlaps))
            return;
        const bool meshObstacle = out.pair < environmentPairs && hasPatches(md.convex, m + out.pair / m);
        if (out.status == PairOpen && st.unprovenCollides && !(st.meshObstaclesUnproven && meshObstacle))
            return;
        if (pastFirstOverlap(st, firstOverlap, out.state, c))
            return;
        exactFlags[c] = 1;
    });
    // 2. The parts' walks, a thread each; the first contact in walk order wins.
    ex.forEachHeavy(partThreads, [=] RC_LAMBDA(std::size_t t) {
        const std::uint32_t perPair = walkPartsPerPair(survivors.size(), parts, walkThreads);
        const std::size_t k = t / perPair;
        if (k >= survivors.size())
            return;
        const std::size_t c = order ? order[k] : k;
        if (!exactFlags[c])
            return;
        const std::uint32_t j = static_cast<std::uint32_t>(t % perPair);
        const PairOutcome &out = decided[c];
        if (pastFirstOverlap(st, firstOverlap, out.state, c))
            return;
        ExactTree a, b;
        Pose<double> poseA, poseB;
        bool closedA = false, closedB = false;
        exactSolids(md, out.pair, links + static_cast<std::size_t>(out.state) * numLinks, a, poseA, closedA, b, poseB,
                    closedB);
        // The walk stops once an earlier part of the pair, or an earlier pair of the state, has
        // found a contact (the latter only where pastFirstOverlap would skip the pair); any other,
        // where no contact is read.
        const WalkPart part{j,
                            walkPartDepth(perPair),
                            &firstPart[c],
                            !st.firstContacts,
                            st.onlyDecisive ? firstOverlap + out.state : nullptr,
                            c};
        if (surfacesWithin(a, poseA, b, poseB, pairPadding(md, st, out.state, out.pair),
                           &partContacts[c * perPair + j], nullptr, part))
        {
            atomicMinimum(&firstPart[c], j);
            noteFoundOverlap(md, st, firstOverlap, out.state, c, out.pair);  // surfaces within the padding
        }
    });
    // 3. Each pair's end: the surfaces' first contact, or containment; curved shapes.
    ex.forEachHeavy(bound, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = order ? order[k] : k;
        if (c >= survivors.size() || !exactFlags[c])
            return;
        PairOutcome &out = decided[c];
        if (pastFirstOverlap(st, firstOverlap, out.state, c))
        {
            exactFlags[c] = 0;  // not decided here after all
            return;
        }
        const bool curved = curvedOverlapDecidedAgain(md, st, out.pair);
        ExactTree a, b;
        Pose<double> poseA, poseB;
        bool closedA = false, closedB = false;
        exactSolids(md, out.pair, links + static_cast<std::size_t>(out.state) * numLinks, a, poseA, closedA, b, poseB,
                    closedB);
        ExactContact contact;
        const bool surfacesMeet = firstPart[c] != kNoneFound;
        if (surfacesMeet)
            contact = partContacts[c * walkPartsPerPair(survivors.size(), parts, walkThreads) + firstPart[c]];
        if (!surfacesMeet && !solidsContain(a, poseA, closedA, b, poseB, closedB, &contact))
        {
            out.status = PairApart;
            return;
        }
        const double padding = pairPadding(md, st, out.state, out.pair);
        if (curved)
        {
            std::uint32_t solidA, solidB;
            pairSolidNumbers(md, out.pair, solidA, solidB);
            if (!curvedPairCollides(md.curvedShapes, solidA, poseA, a, closedA, solidB, poseB, b, closedB, padding,
                                    &contact))
            {
                out.status = PairApart;
                return;
            }
        }
        out.status = PairOverlaps;
        noteOverlap(firstOverlap, out.state, c);
        out.triangle = contact.triangleB;
        out.position[0] = contact.position.x;
        out.position[1] = contact.position.y;
        out.position[2] = contact.position.z;
    });
}

/** \brief The outcomes that come back, compacted in (state, pair) order, their number in
    \a numKept (a tally). With StageSettings::onlyDecisive, the per-state reduction's part: of each
    state's outcomes (in pair order) only those the host reads: the first overlap, which settles the
    state, and, where the first contact is read (StageSettings::firstContacts), the pairs before it
    the host must still decide; no pair settled apart. Every other outcome stays on the executor,
    so a batch's download is about one outcome per colliding state. \a firstOverlap: each state's
    first overlap, which the stages noted as they found it (noteOverlap). \a download: the
    outcomes to download. A \a small chunk downloads as many as it guessed before it knows the
    count, so those slots are written whatever the count (zeros past it); a large one waits for the
    count, which sizes the buffer and the download. */
template <class Exec>
const PairOutcome *reduceOutcomes(Exec &ex, const StageSettings &st, bool small, Extent survivors,
                                  const PairOutcome *decided, const unsigned long long *firstOverlap,
                                  std::size_t &download, unsigned long long *numKept)
{
    const std::size_t bound = survivors.bound;
    const bool onlyDecisive = st.onlyDecisive, firstContacts = st.firstContacts;
    std::uint8_t *keep = ex.template buffer<std::uint8_t>(BufferKeep, bound + 1);
    ex.forEach(bound,
               [=] RC_LAMBDA(std::size_t c)
               {
                   keep[c] = 0;
                   if (c >= survivors.size())
                       return;
                   // Past the first overlap nothing is read; before it, only where the first contact
                   // is (a colliding state's other pairs may be undecided: pastFirstOverlap).
                   const unsigned long long first = firstOverlap[decided[c].state];
                   const bool read = first == kNoneFound || c == first || (firstContacts && c < first);
                   keep[c] = !onlyDecisive || (decided[c].status != PairApart && read) ? 1 : 0;
               });
    std::uint32_t *kept = ex.template buffer<std::uint32_t>(BufferKept, bound + 1);
    ex.selectFlagged(keep, bound, kept, numKept);
    if (!small)
        download = waitFor(ex, numKept);
    const std::size_t room = small ? bound : download;
    const std::size_t prefix = download;
    PairOutcome *compact = ex.template buffer<PairOutcome>(BufferKeptOutcomes, room + 1);
    ex.forEach(room, [=] RC_LAMBDA(std::size_t k) {
        if (k < *numKept)
            compact[k] = decided[kept[k]];
        else if (k < prefix)
            compact[k] = PairOutcome{};
    });
    return compact;
}

/** \brief How a pass over a chunk ended. */
enum class ChunkPass
{
    Done,        ///< outcomes in host memory
    OverBudget,  ///< the chunk needs more than StageBudget allows: split it
    Rerun        ///< a count outgrew its guess: run the chunk again, measuring it (CountGuesses)
};

/** \brief The bound of a small chunk's pairs past the culls: what CountGuesses says for
    \a numStates states, at least StageBudget::minSurvivorBound, at most every pair of every state
    (\a pairElements; also before any chunk was counted). */
inline std::size_t survivorBound(const CountGuesses &guesses, const StageBudget &budget, std::uint32_t numStates,
                                 std::size_t pairElements)
{
    if (guesses.survivorsPerState < 0.0)
        return pairElements;
    const double guess = guesses.survivorsPerState * static_cast<double>(numStates);
    const double least = static_cast<double>(budget.minSurvivorBound);
    return coarseBound(guess > least ? guess : least, pairElements);
}

/** \brief The bound of a raster count (candidate triangles, fragments) whose \a tally a stage just
    wrote: a large chunk waits for it; a small one takes \a guess for its \a numStates states,
    having waited for the count to grow the guess first while it is not measured (CountGuesses).
    Past \a limit: over budget. */
template <class Exec>
std::size_t countBound(Exec &ex, std::size_t limit, bool small, CountGuess &guess, std::uint32_t numStates,
                       const unsigned long long *tally)
{
    if (small && ex.guesses().measured)
        return guess.bound(numStates, limit);
    const std::size_t count = waitFor(ex, tally);
    if (!small || count > limit)
        return count;
    guess.grow(count, numStates, limit);
    return guess.bound(numStates, limit);
}

/** \brief A chunk's last stages, with or without a raster before them (\a items and \a fragments
    its counts; without one, tallies that stay zero): the exact phase on the pairs still open
    (decideOpenPairs), the reduction's compaction (reduceOutcomes), the counts when asked, and the
    chunk's wait: the tallies and the outcomes come back together. Then the host checks what a
    \a small chunk needed against the bounds it had. */
template <class Exec>
ChunkPass finishPass(Exec &ex, const ModelArrays &md, const StageSettings &st, const StageBudget &budget,
                     const Pose<double> *links, std::uint32_t numStates, bool small, Extent survivors, Extent items,
                     Extent fragments, const std::uint32_t *order, PairOutcome *decided,
                     unsigned long long *firstOverlap, unsigned long long *tallies, const std::uint8_t *rasterized,
                     const PairOutcome *&outcomes, std::uint32_t &numOutcomes, StageCounts *counts)
{
    const std::size_t bound = survivors.bound;
    std::uint8_t *exactFlags = ex.template buffer<std::uint8_t>(BufferExactFlags, bound + 1);
    decideOpenPairs(ex, md, st, links, survivors, items, fragments, order, small ? budget.exactWalkParts : 1,
                    budget.exactWalkThreads, decided, firstOverlap, exactFlags);
    CountGuesses &guesses = ex.guesses();
    std::size_t prefix = bound < numStates * guesses.outcomesPerState ? bound : numStates * guesses.outcomesPerState;
    const PairOutcome *kept =
        reduceOutcomes(ex, st, small, survivors, decided, firstOverlap, prefix, tallies + TallyOutcomes);
    if (counts)
    {
        std::uint32_t *list = ex.template buffer<std::uint32_t>(BufferRasterizedList, bound + 1);
        if (st.rasterize)
            ex.selectFlagged(rasterized, bound, list, tallies + TallyRasterized);
        ex.selectFlagged(exactFlags, bound, list, tallies + TallyExact);
    }

    // The chunk's wait (the only one of a small chunk): the tallies and the outcomes (as many as
    // the guess says in a small chunk).
    const unsigned long long *tally = ex.template download<unsigned long long>(BufferTallies, tallies, kNumTallies);
    const PairOutcome *host = ex.template download<PairOutcome>(BufferKeptOutcomes, kept, prefix);
    ex.wait();
    guesses.survivorsPerState =
        grownRate(guesses.survivorsPerState, static_cast<std::size_t>(tally[TallyCandidates]), numStates);
    if (tally[TallyCandidates] > survivors.bound)
        return ChunkPass::Rerun;  // nothing ran past the culls; the raster's counts are not measured
    if (st.rasterize)
    {
        if (tally[TallyItems] > budget.maxItems || tally[TallyFragments] > budget.maxFragments)
            return ChunkPass::OverBudget;
        if (tally[TallyItems] > items.bound || tally[TallyFragments] > fragments.bound)
        {
            guesses.measured = false;  // the pass again, waiting for both counts
            return ChunkPass::Rerun;
        }
        guesses.measured = guesses.measured || small;
    }
    const std::size_t numKept = static_cast<std::size_t>(tally[TallyOutcomes]);
    if (numKept > prefix)
    {
        host = ex.template download<PairOutcome>(BufferKeptOutcomes, kept, numKept);
        ex.wait();
        guesses.outcomesPerState = (numKept + numStates - 1) / numStates;
    }
    if (counts)
    {
        counts->states += numStates;
        counts->survivingPairs += tally[TallyCandidates];
        counts->exactPairs += tally[TallyExact];
        if (st.rasterize)
        {
            counts->rasterizedPairs += tally[TallyRasterized];
            counts->candidateTriangles += tally[TallyItems];
            counts->fragments += tally[TallyFragments];
        }
    }
    outcomes = host;
    numOutcomes = static_cast<std::uint32_t>(numKept);
    return ChunkPass::Done;
}

/** \brief One pass of the stages over a chunk (runStageChunk). */
template <class Exec>
ChunkPass runStagePass(Exec &ex, const ModelArrays &model, const StageSettings &settings, const StageBudget &budget,
                       const double *hostStates, const std::uint8_t *hostAdmissible, std::uint32_t numStates,
                       const PairOutcome *&outcomes, std::uint32_t &numOutcomes, StageCounts *counts)
{
    const int dof = model.numCoordinates, m = model.numComponents, numLinks = model.numLinks;
    const std::uint32_t pairs = model.numPairs();
    const std::uint32_t environmentPairs =
        static_cast<std::uint32_t>(model.numObjects) * static_cast<std::uint32_t>(m);
    const std::size_t pairElements = static_cast<std::size_t>(numStates) * pairs;
    // A small chunk waits once, at its end (but to measure its raster's counts, CountGuesses); a
    // large one for each count.
    CountGuesses &guesses = ex.guesses();
    const bool small =
        survivorBound(guesses, budget, numStates, pairElements) < budget.waitForCountsFrom && !guesses.outOfMemory;
    // A small chunk whose counts are all guessed issues everything before its one wait without
    // reading anything back: the executor may record it, and replay a pass it has seen before as
    // one graph (PassRecorder).
    if (small && (!settings.rasterize || guesses.measured))
        ex.beginReplayable();

    const unsigned long long zeros[kNumTallies] = {};
    unsigned long long *tallies = ex.upload(BufferTallies, zeros, kNumTallies);
    const double *states = ex.upload(BufferStates, hostStates, static_cast<std::size_t>(numStates) * dof);
    const std::uint8_t *admissible = ex.upload(BufferAdmissible, hostAdmissible, numStates);
    StageSettings st = settings;  // with the chunk's pair paddings in executor memory
    if (settings.extraPadding.any())
    {
        const std::size_t rows = settings.extraPadding.rowPerState ? numStates : 1;
        st.extraPadding.environment =
            ex.upload(BufferExtraEnvironment, settings.extraPadding.environment, rows * static_cast<std::size_t>(m));
        st.extraPadding.self =
            ex.upload(BufferExtraSelf, settings.extraPadding.self, rows * static_cast<std::size_t>(model.numSelfPairs));
    }

    // 1. Forward kinematics and the components' boxes.
    const std::size_t jointElements = static_cast<std::size_t>(numStates) * static_cast<std::size_t>(model.numJoints);
    Pose<double> *jointPoses = ex.template buffer<Pose<double>>(BufferJointPoses, jointElements + 1);
    Pose<double> *links = ex.template buffer<Pose<double>>(BufferLinks, static_cast<std::size_t>(numStates) * numLinks);
    const std::size_t componentElements = static_cast<std::size_t>(numStates) * m;
    Pose<float> *poses = ex.template buffer<Pose<float>>(BufferComponentPose, componentElements + 1);
    OrientedBox *boxes = ex.template buffer<OrientedBox>(BufferComponentBox, componentElements + 1);
    Box *bounds = ex.template buffer<Box>(BufferComponentBounds, componentElements + 1);
    const ModelArrays md = model;
    // Each joint's local pose a thread (its sine and cosine, the joint's own pose), then a thread
    // per state composes the chain: one thread for the whole chain took 19.7 us for one Panda state
    // on an H100, a chain of latencies.
    const int numJoints = model.numJoints;
    ex.forEach(jointElements,
               [=] RC_LAMBDA(std::size_t i)
               {
                   const std::size_t s = i / static_cast<std::size_t>(numJoints);
                   const int j = static_cast<int>(i % static_cast<std::size_t>(numJoints));
                   if (!admissible[s])
                       return;
                   const double *q = states + s * dof;
                   jointPoses[i] = jointLocalPose(md.joints[j], q, jointValue(md.joints, j, q));
               });
    unsigned long long *firstOverlap =
        ex.template buffer<unsigned long long>(BufferFirstOverlap, static_cast<std::size_t>(numStates) + 1);
    ex.forEach(numStates,
               [=] RC_LAMBDA(std::size_t s)
               {
                   firstOverlap[s] = kNoneFound;  // none found yet (noteOverlap)
                   if (admissible[s])
                       placeLinks(md.joints, numJoints, jointPoses + s * static_cast<std::size_t>(numJoints),
                                  links + s * numLinks);
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

    // 2. Culls per (state, pair), then compaction: the survivors in (state, pair) order. Each pair
    // is decided by its component's boxes alone. A thread takes one object and all its pairs with
    // the robot, first testing the robot's bounds (the union of its components', per state) at the
    // largest of those pairs' paddings: an object out of that reach has none of its pairs survive,
    // as the CPU backend's distance filter skips them at once. That test passes wherever one of the
    // pairs' own box tests does (the union holds each component's bounds, and boxesOverlap grows
    // with the boxes and the margin), so the survivors are those of a test per pair; but a scene
    // of many objects takes one test per object and state instead of one per component (the crane
    // in the plant: 101 objects, 9 components, 935 pairs a state, whose tests were two fifths of
    // its stages' work). A self pair is a thread of its own.
    const int numObjects = model.numObjects;
    const bool environment = settings.checkEnvironment && numObjects > 0 && m > 0;
    RobotReach *reach = nullptr;
    if (environment)
    {
        reach = ex.template buffer<RobotReach>(BufferRobotReach, static_cast<std::size_t>(numStates) + 1);
        ex.forEach(numStates,
                   [=] RC_LAMBDA(std::size_t s)
                   {
                       if (!admissible[s])
                           return;
                       RobotReach r{emptyBox(), 0.0f};
                       for (int k = 0; k < m; ++k)
                       {
                           extend(r.bounds, bounds[s * m + k]);
                           const float padding = floatPadding(pairPadding(md, st, s, static_cast<std::uint32_t>(k)));
                           r.padding = padding > r.padding ? padding : r.padding;
                       }
                       reach[s] = r;
                   });
    }
    const int numSelfPairs = model.numSelfPairs;
    const std::size_t cullsPerState = static_cast<std::size_t>(numObjects + numSelfPairs);
    std::uint8_t *flags = ex.template buffer<std::uint8_t>(BufferPairFlags, pairElements + 1);
    ex.forEach(static_cast<std::size_t>(numStates) * cullsPerState,
               [=] RC_LAMBDA(std::size_t i)
               {
                   const std::size_t s = i / cullsPerState;
                   const int j = static_cast<int>(i % cullsPerState);
                   if (j < numObjects)
                   {
                       const int o = j;
                       std::uint8_t *objectFlags = flags + s * pairs + static_cast<std::size_t>(o) * m;
                       const Box &objectBox = md.objectBoxes[o];
                       const bool inReach =
                           environment && admissible[s] && boxesOverlap(reach[s].bounds, objectBox, reach[s].padding);
                       for (int k = 0; k < m; ++k)
                       {
                           const std::uint32_t pair = static_cast<std::uint32_t>(o * m + k);
                           objectFlags[k] = inReach && solidsMayMeet(bounds[s * m + k], boxes[s * m + k], objectBox,
                                                                     md.objectOrientedBoxes[o],
                                                                     floatPadding(pairPadding(md, st, s, pair)))
                                                ? 1
                                                : 0;
                       }
                       return;
                   }
                   const int p = j - numObjects;
                   const std::uint32_t pair = environmentPairs + static_cast<std::uint32_t>(p);
                   const int *self = md.selfPairs + 2 * p;
                   const double padding = pairPadding(md, st, s, pair);
                   const bool survives =
                       admissible[s] && st.checkSelfCollision &&
                       solidsMayMeet(bounds[s * m + self[0]], boxes[s * m + self[0]], bounds[s * m + self[1]],
                                     boxes[s * m + self[1]], floatPadding(padding)) &&
                       !(st.clearanceTables && selfPairApartByTable(md.clearanceTables, static_cast<std::size_t>(p),
                                                                    states + s * dof, padding));
                   flags[s * pairs + pair] = survives ? 1 : 0;
               });
    // The compaction writes every survivor, however many: its output has room for every pair.
    std::uint32_t *candidates = ex.template buffer<std::uint32_t>(BufferCandidates, pairElements + 1);
    ex.selectFlagged(flags, pairElements, candidates, tallies + TallyCandidates);
    // Per surviving pair from here on: element c < survivors.size() is candidates[c]. A small
    // chunk's buffers and launches are sized by the survivors per state its executor has seen
    // (survivorBound); past that bound nothing runs, and the chunk runs again (finishPass).
    const Extent survivors{
        small ? survivorBound(guesses, budget, numStates, pairElements) : waitFor(ex, tallies + TallyCandidates),
        tallies + TallyCandidates};
    const std::size_t survivorBound = survivors.bound;
    const std::uint32_t numSegments = static_cast<std::uint32_t>(survivorBound);

    // 3. Per surviving pair: the proofs, then the image window, the grid, and how many triangles to
    // rasterize. The survivors are in (state, pair) order, so a warp holds different pairs of a few states,
    // each proof with its own hulls and loop lengths (GJK over up to 128 points per solid and
    // passes over hundreds of vertices): the threads diverge (an H200, 2026-11-26: this stage was
    // 2/3 of a safe-mode batch's kernel time, at 6 % occupancy). Taken in pair order, a warp runs
    // one pair's proof for 32 states: the same hull data and trip counts (budget.orderedProofsFrom
    // says when that pays). Slots past the survivors' count (a small chunk's bound) sort last.
    const bool pairOrdered = survivorBound >= budget.orderedProofsFrom;
    std::uint32_t *proofOrder = nullptr;
    if (pairOrdered)
    {
        std::uint32_t *candidatePairs = ex.template buffer<std::uint32_t>(BufferCandidatePairs, survivorBound + 1);
        proofOrder = ex.template buffer<std::uint32_t>(BufferProofOrder, survivorBound + 1);
        ex.forEach(survivorBound, [=] RC_LAMBDA(std::size_t c)
                   { candidatePairs[c] = c < survivors.size() ? candidates[c] % pairs : pairs; });
        ex.orderByKey(candidatePairs, survivorBound, pairs + 1, proofOrder);
    }
    RasterGrid *grids = ex.template buffer<RasterGrid>(BufferGrids, survivorBound + 1);
    float *margins = ex.template buffer<float>(BufferMargins, survivorBound + 1);
    std::int32_t *status = ex.template buffer<std::int32_t>(BufferStatus, survivorBound + 1);
    const std::uint32_t imageWalkDepth = small ? kImageWalkDepth : 0;
    const std::uint32_t partsPerTree = 1u << imageWalkDepth;
    const std::uint32_t imageParts = 2 * partsPerTree;  // a pair's image walks' parts, A's then B's
    const std::size_t imagePartBound = survivorBound * imageParts;
    if (imagePartBound >= (std::size_t(1) << 32))
        return ChunkPass::OverBudget;  // the parts are numbered in 32 bits (findSegment)
    const std::uint32_t numImageParts = static_cast<std::uint32_t>(imagePartBound);
    unsigned long long *triangleCount = ex.template buffer<unsigned long long>(BufferTriangleCount, imagePartBound + 1);
    std::uint8_t *rasterized = ex.template buffer<std::uint8_t>(BufferRasterized, survivorBound + 1);
    // The proof in two kernels: the whole hulls for every pair (relateWholeHulls: GJK and the
    // simplex's own overlap proofs), then relateSolids (scans, shells, patches) for the pairs that
    // left open. One kernel holding both ran at 255 registers per thread with a 5.8 kB stack frame
    // (sm_90, ptxas), 6 % occupancy, for proofs most pairs never reach. Same answers as one
    // relateSolids: the light proof's Apart and Overlapping are its answers too.
    constexpr std::int32_t kFullProofNeeded = -1;  // status between the two kernels only
    ex.forEach(survivorBound, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = pairOrdered ? proofOrder[k] : k;
        if (c >= survivors.size())
            return;
        const std::size_t s = candidates[c] / pairs;
        const std::uint32_t pair = candidates[c] % pairs;
        if (pastFirstOverlap(st, firstOverlap, s, c))
        {
            status[c] = PairOpen;  // and not decided further (pastFirstOverlap)
            return;
        }
        const double padding = pairPadding(md, st, s, pair);
        // A mesh obstacle's proof walks its patches, serially per thread: on FCL's env.obj (an H200,
        // 2026-11-26) the stages ran at 0.3x the CPU backend on 16 cores, which skips that proof.
        const bool meshObstacle =
            st.meshObstaclesUnproven && pair < environmentPairs && hasPatches(md.convex, m + pair / m);
        StageSolid a, b;
        pairSolids(md, pair, poses + s * m, bounds + s * m, a, b);
        const Box window = pairWindow(a.bounds, b.bounds, floatPadding(padding));
        const HullRelation relation =
            isEmpty(window) ? HullRelation::Apart
            : meshObstacle  ? HullRelation::Unknown
                            : pairHullRelation(md, pair, links + s * numLinks, padding, st.proveOverlaps, WholeHullsProof{});
        status[c] = pairStatusOf(relation, meshObstacle ? PairOpen : kFullProofNeeded);
        if (status[c] == PairOverlaps)
            noteFoundOverlap(md, st, firstOverlap, s, c, pair);
    });
    ex.forEachHeavy(survivorBound, [=] RC_LAMBDA(std::size_t k) {
        const std::size_t c = pairOrdered ? proofOrder[k] : k;
        if (c >= survivors.size() || status[c] != kFullProofNeeded)
            return;
        const std::size_t s = candidates[c] / pairs;
        const std::uint32_t pair = candidates[c] % pairs;
        if (pastFirstOverlap(st, firstOverlap, s, c))
        {
            status[c] = PairOpen;  // and not decided further (pastFirstOverlap)
            return;
        }
        const HullRelation relation = pairHullRelation(md, pair, links + s * numLinks, pairPadding(md, st, s, pair),
                                                       st.proveOverlaps, FullProof{});
        // An overlap proven by the hulls has no triangle or place (the contact is not asked).
        status[c] = pairStatusOf(relation, PairOpen);
        if (status[c] == PairOverlaps)
            noteFoundOverlap(md, st, firstOverlap, s, c, pair);
    });
    // The open pairs' images: grid, margin, and how many triangles to rasterize. Each tree's walk
    // for its candidate triangles (the node culls: the leaves near the image) is split into
    // parts in a small chunk, a thread each, which find their own starts (forEachTriangleNearImage):
    // one thread walking both trees of a pair twice (to count, then to write) was a fifth to a third
    // of a 1 000-state Panda call's critical path (docs/benchmarks.md). Slot c * imageParts + j
    // counts part j of pair c: A's parts, then B's, so that the scan's order is the pairs' walks'.
    ex.forEach(imagePartBound + 1,
               [=] RC_LAMBDA(std::size_t e)
               {
                   const std::size_t k = e / imageParts;
                   const std::uint32_t j = static_cast<std::uint32_t>(e % imageParts);
                   const std::size_t c = pairOrdered && k < survivorBound ? proofOrder[k] : k;
                   triangleCount[c * imageParts + j] = 0;
                   if (j == 0)
                       rasterized[c] = 0;
                   if (c >= survivors.size() || status[c] != PairOpen || !st.rasterize)
                       return;  // past the survivors: zeros for the scan, whose last output is then the total
                   const std::size_t s = candidates[c] / pairs;
                   const std::uint32_t pair = candidates[c] % pairs;
                   if (pastFirstOverlap(st, firstOverlap, s, c))
                       return;
                   StageSolid a, b;
                   pairSolids(md, pair, poses + s * m, bounds + s * m, a, b);
                   const double padding = pairPadding(md, st, s, pair);
                   const Box window = pairWindow(a.bounds, b.bounds, floatPadding(padding));
                   if (!rasterUsable(a.slice.closed, b.slice.closed, window, st.pixel))
                       return;  // the exact phase decides
                   const RasterGrid grid = makeGrid(window, st.pixel, st.maxImageSide);
                   const float margin = pairMargin(window, grid, floatPadding(padding));
                   if (j == 0)
                   {
                       grids[c] = grid;
                       margins[c] = margin;
                       rasterized[c] = 1;
                   }
                   unsigned long long count = 0;
                   const StageSolid &solid = j < partsPerTree ? a : b;
                   forEachTriangleNearImage(
                       solid.tree, solid.treePlacement, grid, margin, [&](std::uint32_t) { ++count; }, j % partsPerTree,
                       imageWalkDepth);
                   triangleCount[c * imageParts + j] = count;
               });
    PairOutcome *decided = ex.template buffer<PairOutcome>(BufferOutcomes, survivorBound + 1);
    if (!st.rasterize)
    {
        // Nothing to rasterize (exact and conservative mode, contacts asked): no counts to wait for.
        ex.forEach(survivors, [=] RC_LAMBDA(std::size_t c) {
            decided[c] = PairOutcome{static_cast<std::uint32_t>(candidates[c] / pairs), candidates[c] % pairs,
                                     status[c], -1, {0.0, 0.0, 0.0}};
        });
        const Extent none{0, tallies + TallyItems};  // no raster: its tallies stay zero
        return finishPass(ex, md, st, budget, links, numStates, small, survivors, none, none, proofOrder, decided,
                          firstOverlap, tallies, rasterized, outcomes, numOutcomes, counts);
    }
    unsigned long long *itemStart = ex.template buffer<unsigned long long>(BufferItemStart, imagePartBound + 1);
    ex.exclusiveSum(triangleCount, itemStart, imagePartBound + 1, tallies + TallyItems);
    const std::size_t itemBound =
        countBound(ex, budget.maxItems, small, guesses.items, numStates, tallies + TallyItems);
    if (itemBound > budget.maxItems)
        return ChunkPass::OverBudget;
    const Extent items{itemBound, tallies + TallyItems};
    // The candidates themselves, the same walks again: item i of pair c is triangle itemTriangles[i]
    // of the pair (A's numbers first, then B's after A's count, as rasterizePairTriangle reads them).
    std::uint32_t *itemTriangles = ex.template buffer<std::uint32_t>(BufferItemTriangles, itemBound + 1);
    ex.forEach(imagePartBound,
               [=] RC_LAMBDA(std::size_t e)
               {
                   const std::size_t c = e / imageParts;
                   const std::uint32_t j = static_cast<std::uint32_t>(e % imageParts);
                   if (c >= survivors.size() || triangleCount[e] == 0 || !items.fits())
                       return;
                   const std::size_t s = candidates[c] / pairs;
                   StageSolid a, b;
                   pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
                   const bool partOfA = j < partsPerTree;
                   const StageSolid &solid = partOfA ? a : b;
                   const std::uint32_t firstTriangle = partOfA ? 0 : a.slice.numTriangles;
                   unsigned long long slot = itemStart[e];
                   forEachTriangleNearImage(
                       solid.tree, solid.treePlacement, grids[c], margins[c],
                       [&](std::uint32_t t) { itemTriangles[slot++] = firstTriangle + t; }, j % partsPerTree,
                       imageWalkDepth);
               });

    // Pre-rasterization count per (pair, triangle): the per-triangle cull, then the pixels covered.
    unsigned long long *fragmentCount = ex.template buffer<unsigned long long>(BufferFragmentCount, itemBound + 1);
    ex.forEach(itemBound + 1, [=] RC_LAMBDA(std::size_t i) {
        if (i >= items.size())
        {
            fragmentCount[i] = 0;  // the scan's trailing zeros
            return;
        }
        const std::uint32_t c = findSegment(itemStart, numImageParts, static_cast<unsigned long long>(i)) / imageParts;
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        fragmentCount[i] = static_cast<unsigned long long>(
            rasterizePairTriangle(a, b, itemTriangles[i], grids[c], margins[c], [](int, float, std::uint32_t) {}));
    });
    unsigned long long *fragmentStart = ex.template buffer<unsigned long long>(BufferFragmentStart, itemBound + 1);
    ex.exclusiveSum(fragmentCount, fragmentStart, itemBound + 1, tallies + TallyFragments);
    const std::size_t fragmentBound =
        countBound(ex, budget.maxFragments, small, guesses.fragments, numStates, tallies + TallyFragments);
    if (fragmentBound > budget.maxFragments)
        return ChunkPass::OverBudget;
    const Extent fragmentExtent{fragmentBound, tallies + TallyFragments};

    // 4. Rasterization into the counted slots, each fragment keyed by (pair, pixel); one stable sort
    // of the chunk's fragments by key puts each pair's pixel runs in order. The depth order within a
    // run is step 5's (sortFragments, by depth and then code: the CPU's order). A sort within each
    // pair's segment, keyed by (pixel, depth), has CUB copy its segment groups' sizes to the host
    // and wait (past 500 segments, DeviceSegmentedSort), a second wait in every small chunk.
    const int pixelBits = imagePixelBits(st.maxImageSide);
    unsigned long long *hit = ex.template buffer<unsigned long long>(BufferHit, survivorBound + 1);
    const int keyBits = bitsToNumber(numSegments) + pixelBits;  // pairs 0..numSegments, see below
    unsigned long long *keys = ex.template buffer<unsigned long long>(BufferKeys, fragmentBound + 1);
    std::uint32_t *values = ex.template buffer<std::uint32_t>(BufferValues, fragmentBound + 1);
    Fragment *rasterFragments = ex.template buffer<Fragment>(BufferRasterFragments, fragmentBound + 1);
    ex.forEach(items, [=] RC_LAMBDA(std::size_t i) {
        if (!fragmentExtent.fits())
            return;
        const std::uint32_t c = findSegment(itemStart, numImageParts, static_cast<unsigned long long>(i)) / imageParts;
        const std::size_t s = candidates[c] / pairs;
        StageSolid a, b;
        pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
        std::size_t slot = fragmentStart[i];
        rasterizePairTriangle(a, b, itemTriangles[i], grids[c], margins[c],
                              [&](int pixel, float depth, std::uint32_t code)
                              {
                                  keys[slot] = fragmentKey(c, pixel, pixelBits);
                                  values[slot] = static_cast<std::uint32_t>(slot);
                                  rasterFragments[slot] = Fragment{depth, code};
                                  ++slot;
                              });
    });
    // The slots past the fragments' count (a small chunk sorts its whole bound; all of them when a
    // count outgrew its bound) keyed past every pair's, so that they sort last, and written whole,
    // as the sort reads them; each pair's first hit pixel (step 5) starts at none, in the same pass.
    const unsigned long long pastEveryPair = fragmentKey(numSegments, 0, pixelBits);
    const std::size_t resetElements = fragmentBound > survivorBound + 1 ? fragmentBound : survivorBound + 1;
    ex.forEach(resetElements,
               [=] RC_LAMBDA(std::size_t k)
               {
                   if (k < fragmentBound && k >= fragmentExtent.size())
                   {
                       keys[k] = pastEveryPair;
                       values[k] = static_cast<std::uint32_t>(k);
                   }
                   if (k <= survivorBound)
                       hit[k] = ~0ull;
               });
    ex.sortByKey(keys, values, fragmentBound, keyBits);  // may move them to other buffers

    // 5. Sort_Search_Pair on each pixel's run; the first hit pixel of each pair. The thread of a
    // run's first fragment gathers the run in key order (runs of one fragment hit nothing and are
    // never read), sorts it by depth and walks it.
    Fragment *fragments = ex.template buffer<Fragment>(BufferFragments, fragmentBound + 1);
    ex.forEach(fragmentExtent,
               [=] RC_LAMBDA(std::size_t f)
               {
                   const unsigned long long key = keys[f];
                   if (f > 0 && keys[f - 1] == key)
                       return;  // not the first fragment of its pixel's run
                   const std::size_t total = fragmentExtent.size();
                   std::size_t end = f + 1;
                   while (end < total && keys[end] == key)
                       ++end;
                   const int count = static_cast<int>(end - f);
                   if (count < 2)
                       return;
                   for (std::size_t g = f; g < end; ++g)
                       fragments[g] = rasterFragments[values[g]];
                   sortFragments(fragments + f, count);
                   const std::uint32_t c = pairOfKey(key, pixelBits);
                   const std::size_t s = candidates[c] / pairs;
                   StageSolid a, b;
                   pairSolids(md, candidates[c] % pairs, poses + s * m, bounds + s * m, a, b);
                   if (sortSearchPair(fragments + f, count, a.slice.closed, b.slice.closed) >= 0)
                       atomicMinimum(&hit[c], (static_cast<unsigned long long>(pixelOfKey(key, pixelBits)) << 32) |
                                                  static_cast<unsigned long long>(f));
               });

    // Outcomes, in (state, pair) order.
    ex.forEach(survivors, [=] RC_LAMBDA(std::size_t c) {
        PairOutcome out{static_cast<std::uint32_t>(candidates[c] / pairs), candidates[c] % pairs, status[c], -1,
                        {0.0, 0.0, 0.0}};
        if (out.status == PairOpen && rasterized[c])
        {
            if (hit[c] != ~0ull)
            {
                const int pixel = static_cast<int>(hit[c] >> 32);
                const std::size_t run = static_cast<std::size_t>(hit[c] & 0xffffffffull);
                const std::size_t total = fragmentExtent.size();
                std::size_t end = run + 1;
                while (end < total && keys[end] == keys[run])
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
                noteFoundOverlap(md, st, firstOverlap, s, c, out.pair);
            }
            else if (!st.confirmMisses && !(pairPadding(md, st, out.state, out.pair) > 0))
                out.status = PairApart;
        }
        decided[c] = out;
    });
    return finishPass(ex, md, st, budget, links, numStates, small, survivors, items, fragmentExtent, proofOrder,
                      decided, firstOverlap, tallies, rasterized, outcomes, numOutcomes, counts);
}

/** \brief Runs the stages for \a numStates states (host arrays: \a hostStates row-major,
    \a hostAdmissible 1 per state that passed the bounds check). On return \a outcomes points at
    the surviving pairs' outcomes in host memory the executor keeps (\a numOutcomes of them, in
    (state, pair) order; until its next chunk). Returns false, having decided nothing, when the
    chunk exceeds \a budget (the caller splits it); else adds to \a counts (when not null) what
    the chunk did.

    The executor provides (the host's in collision/StagedBackend.cpp, the GPU's in cuda/):
    buffer(slot, n) (scratch in its memory, kept and grown), upload(slot, host, n) and
    download(slot, its, n) (copies through host mirrors; downloaded data is read after wait()),
    wait() (the host waits for it: counted), beginReplayable() (what is issued until the next wait
    may be recorded and issued there, PassRecorder), forEach(n or Extent, f) (a kernel), forEachHeavy(n, f)
    (a kernel whose per-element code is register-heavy: the GPU holds it to fewer registers),
    selectFlagged, exclusiveSum (their counts and totals written to its memory, not waited for),
    orderByKey, sortByKey, counts() (ExecutorCounts) and guesses() (CountGuesses). */
template <class Exec>
bool runStageChunk(Exec &ex, const ModelArrays &model, const StageSettings &settings, const StageBudget &budget,
                   const double *hostStates, const std::uint8_t *hostAdmissible, std::uint32_t numStates,
                   const PairOutcome *&outcomes, std::uint32_t &numOutcomes, StageCounts *counts = nullptr)
{
    if (static_cast<std::size_t>(numStates) * model.numPairs() > budget.maxPairElements)
        return false;
    for (;;)
    {
        switch (runStagePass(ex, model, settings, budget, hostStates, hostAdmissible, numStates, outcomes, numOutcomes,
                             counts))
        {
        case ChunkPass::Done:
            return true;
        case ChunkPass::OverBudget:
            return false;
        case ChunkPass::Rerun:
            ++ex.counts().reruns;
            break;
        }
    }
}
}  // namespace rastercheck::device
