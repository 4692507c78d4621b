#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "rastercheck/collision/StageRunner.h"
#include "rastercheck/core/Pool.h"
#include "rastercheck/device/BatchPipeline.h"

namespace rastercheck
{
/** \brief Thrown by an executor whose scratch cannot grow: past StageBudget::maxScratchBytes, or
    refused by the allocator (device memory taken by others). The executor has freed its scratch;
    runStagesInChunks then splits the chunk, as for a chunk over the count limits. */
struct StageMemoryExhausted : std::runtime_error
{
    using std::runtime_error::runtime_error;
};

/** \brief memcpy of \a bytes from \a from to \a to, split over the OpenMP threads from 1 MiB up
    (inside another parallel region, one thread). A large chunk's states (65 536 Panda states, 3.7
    MB) take a core a few hundred microseconds to copy into the executor's memory, serially before
    the chunk's first kernel: for the GPU to decide 10^5 states in the 2 ms that ten times the
    16-core CPU backend means, such serial host work has to be a small part of it. */
void copyInParallel(void *to, const void *from, std::size_t bytes);

/** \brief \a host with every array replaced by \a copy(array, count), which returns the copy: how a
    runner moves the model where its executors read it (the GPU's memory; the host executor's
    guarded pages, HostScratch::Guarded). One list of the arrays for both, so that what a GPU reads
    is what the host's guarded runs check. */
template <class Copy>
device::ModelArrays copyModelArrays(const device::ModelArrays &host, Copy &&copy)
{
    const std::size_t m = static_cast<std::size_t>(host.numComponents);
    const std::size_t o = static_cast<std::size_t>(host.numObjects);
    device::ModelArrays arrays = host;
    arrays.joints = copy(host.joints, static_cast<std::size_t>(host.numJoints));
    arrays.componentVertices = copy(host.componentVertices, host.numComponentVertexFloats);
    arrays.componentTriangles = copy(host.componentTriangles, host.numComponentTriangleIndices);
    arrays.components = copy(host.components, m);
    arrays.componentLocalBoxes = copy(host.componentLocalBoxes, m);
    arrays.componentLink = copy(host.componentLink, m);
    arrays.componentSubtreeEnd = copy(host.componentSubtreeEnd, m);
    arrays.objectVertices = copy(host.objectVertices, host.numObjectVertexFloats);
    arrays.objectTriangles = copy(host.objectTriangles, host.numObjectTriangleIndices);
    arrays.objects = copy(host.objects, o);
    arrays.objectBoxes = copy(host.objectBoxes, o);
    arrays.objectOrientedBoxes = copy(host.objectOrientedBoxes, o);
    arrays.selfPairs = copy(host.selfPairs, 2 * static_cast<std::size_t>(host.numSelfPairs));
    arrays.convex.vertices = copy(host.convex.vertices, host.numConvexVertexDoubles);
    arrays.convex.hullPoints = copy(host.convex.hullPoints, host.numConvexHullDoubles);
    arrays.convex.pieces = copy(host.convex.pieces, host.numConvexPieces);
    arrays.convex.solidPieces = copy(host.convex.solidPieces, m + o + 1);
    arrays.convex.planes = copy(host.convex.planes, host.numConvexPlaneDoubles);
    arrays.convex.edges = copy(host.convex.edges, host.numConvexEdgeIndices);
    arrays.convex.supportCellStart = copy(host.convex.supportCellStart, host.numConvexSupportCellOffsets);
    arrays.convex.supportCandidates = copy(host.convex.supportCandidates, host.numConvexSupportCandidates);
    arrays.convex.patchNodes = copy(host.convex.patchNodes, host.numPatchNodes);
    arrays.convex.solidPatchNodes = copy(host.convex.solidPatchNodes, m + o + 1);
    arrays.convex.patchPieces = copy(host.convex.patchPieces, host.numPatches);
    arrays.convex.patchTriangles = copy(host.convex.patchTriangles, host.numPatchTriangleIndices);
    arrays.componentTreeNodes = copy(host.componentTreeNodes, host.numComponentTreeNodes);
    arrays.componentTriangleOrder = copy(host.componentTriangleOrder, host.numComponentTriangleIndices / 3);
    arrays.objectTreeNodes = copy(host.objectTreeNodes, host.numObjectTreeNodes);
    arrays.objectTriangleOrder = copy(host.objectTriangleOrder, host.numObjectTriangleIndices / 3);
    const auto copyExact = [&](const device::ExactArrays &in, std::size_t triangles, std::size_t cells,
                               std::size_t probeDoubles, std::size_t shellStarts, std::size_t meshes)
    {
        return device::ExactArrays{copy(in.corners, 9 * triangles), copy(in.gridCells, cells),
                                   copy(in.probePoints, probeDoubles), copy(in.shellProbeStart, shellStarts),
                                   copy(in.meshes, meshes)};
    };
    arrays.componentExact =
        copyExact(host.componentExact, host.numComponentTriangleIndices / 3, host.numComponentGridCells,
                  host.numComponentProbeDoubles, host.numComponentShellStarts, m);
    arrays.objectExact = copyExact(host.objectExact, host.numObjectTriangleIndices / 3, host.numObjectGridCells,
                                   host.numObjectProbeDoubles, host.numObjectShellStarts, o);
    arrays.curvedPairs = copy(host.curvedPairs, host.numCurvedPairFlags);
    arrays.curvedShapes.shapes = copy(host.curvedShapes.shapes, host.numCurvedShapes);
    arrays.curvedShapes.reach = copy(host.curvedShapes.reach, host.numCurvedShapes);
    arrays.curvedShapes.solidShapes = copy(host.curvedShapes.solidShapes, m + o + 1);
    if (host.clearanceTables.tableOf)
        arrays.clearanceTables = device::ClearanceTableArrays{
            copy(host.clearanceTables.tableOf, static_cast<std::size_t>(host.numSelfPairs)),
            copy(host.clearanceTables.tables, host.numClearanceTables),
            copy(host.clearanceTables.clearance, host.numClearanceNodes)};
    return arrays;
}

/** \brief Executors for concurrent passes: a call takes one no other call uses (made when none is
    idle) and gives it back, with its scratch, for later calls. A thread that calls again gets a
    warm executor, so a steady stream of batches allocates nothing; threads that call at the same
    time each run on their own (on the GPU: their own stream, buffers and host mirrors), and the
    pool holds as many executors as calls ever ran at once. */
template <class Exec>
class ExecutorPool
{
public:
    explicit ExecutorPool(std::function<std::unique_ptr<Exec>()> make) : executors_(std::move(make)) {}

    /** \brief Runs f(executor) on an executor of its own; returns what that executor did. */
    template <class F>
    device::ExecutorCounts run(F &&f)
    {
        std::unique_ptr<Exec> ex = executors_.borrow();
        ex->counts() = {};
        const auto start = std::chrono::steady_clock::now();
        try
        {
            f(*ex);
        }
        catch (...)
        {
            executors_.giveBack(std::move(ex));
            throw;
        }
        device::ExecutorCounts used = ex->counts();
        used.calls = 1;
        used.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        executors_.giveBack(std::move(ex));
        return used;
    }

    /** \brief The executors made so far: the most calls that ran at once. */
    std::size_t size() const { return executors_.made(); }

private:
    Pool<Exec> executors_;
};

/** \brief The most bytes one scratch buffer may grow to while the others hold \a heldByOthers,
    under \a limit (StageBudget::maxScratchBytes; 0 = no limit). */
inline std::size_t scratchRoom(std::size_t limit, std::size_t heldByOthers)
{
    if (limit == 0)
        return SIZE_MAX;
    return limit > heldByOthers ? limit - heldByOthers : 0;
}

/** \brief What an executor throws when \a buffer cannot grow to \a need bytes: past \a limit when
    \a need exceeds \a room (scratchRoom), else because the allocator refused. */
inline StageMemoryExhausted scratchExhausted(const std::string &buffer, std::size_t need, std::size_t room,
                                             std::size_t limit)
{
    return StageMemoryExhausted(
        buffer + ": no room for " + std::to_string(need) + " bytes" +
        (need > room ? " within the scratch limit of " + std::to_string(limit) + " bytes" : " on the device"));
}

/** \brief runStageChunk, with an executor out of scratch memory counted as a chunk over budget;
    from then on its chunks size their buffers by the counts, not by bounds (CountGuesses). */
template <class Exec>
bool runStageChunkWithin(Exec &ex, const device::ModelArrays &model, const device::StageSettings &settings,
                         const device::StageBudget &budget, const double *q, const std::uint8_t *admissible,
                         std::uint32_t count, const device::PairOutcome *&outcomes, std::uint32_t &numOutcomes,
                         std::string &why, device::StageCounts *counts)
{
    try
    {
        return device::runStageChunk(ex, model, settings, budget, q, admissible, count, outcomes, numOutcomes, counts);
    }
    catch (const StageMemoryExhausted &e)
    {
        ex.guesses().outOfMemory = true;
        why = e.what();
        return false;
    }
}

/** \brief Runs the stages over \a n states in chunks that fit \a budget: a chunk that overflows is
    halved and run again, so a batch of any size gets the verdicts it would get in one pass. A
    single state that still overflows is run without rasterizing: its pairs go to the exact phase,
    slower and never wrong (in raster mode that state gets the exact answer, which may find
    collisions the raster would miss). Shared by the host and CUDA runners. The chunks that ran add
    to \a counts when it is not null. */
template <class Exec>
void runStagesInChunks(Exec &ex, const device::ModelArrays &model, const device::StageSettings &settings,
                       const device::StageBudget &budget, const double *q, const std::uint8_t *admissible,
                       std::size_t n, std::vector<device::PairOutcome> &outcomes, device::StageCounts *counts)
{
    const std::size_t dof = static_cast<std::size_t>(model.numCoordinates);
    const std::size_t pairs = std::max<std::size_t>(1, model.numPairs());
    if (pairs > budget.maxPairElements)
        throw std::length_error("the model has more pairs than one pass can hold");
    std::size_t chunk = std::min({n, budget.maxStates, budget.maxPairElements / pairs});
    std::size_t start = 0;
    while (start < n)
    {
        const std::size_t count = std::min(chunk, n - start);
        const device::PairOutcome *chunkOutcomes = nullptr;
        std::uint32_t numOutcomes = 0;
        std::string why = "over the stage budget";
        device::StageSettings chunkSettings = settings;
        chunkSettings.extraPadding = settings.extraPadding.fromState(start, model.numComponents, model.numSelfPairs);
        if (!runStageChunkWithin(ex, model, chunkSettings, budget, q + start * dof, admissible + start,
                                 static_cast<std::uint32_t>(count), chunkOutcomes, numOutcomes, why, counts))
        {
            if (count > 1)
            {
                chunk = count / 2;
                continue;
            }
            device::StageSettings unrasterized = chunkSettings;
            unrasterized.rasterize = false;
            if (!runStageChunkWithin(ex, model, unrasterized, budget, q + start * dof, admissible + start, 1,
                                     chunkOutcomes, numOutcomes, why, counts))
                throw std::length_error("the stages cannot hold one state's pairs, even without rasterizing (" + why +
                                        ")");
        }
        ++ex.counts().chunks;
        outcomes.insert(outcomes.end(), chunkOutcomes, chunkOutcomes + numOutcomes);
        for (auto o = outcomes.end() - numOutcomes; o != outcomes.end(); ++o)
            o->state += static_cast<std::uint32_t>(start);
        start += count;
    }
}
/** \brief A StageRunner whose passes run the stages in chunks (runStagesInChunks) on executors of
    one kind, each pass on one of its own from a pool: the host's (collision/StagedBackend.cpp) and
    the GPU's (cuda/). The subclass sets arrays_ (the model as the executor reads it) and budget_
    before the first run. */
template <class Exec>
class PooledStageRunner : public StageRunner
{
public:
    std::size_t executors() const override { return executors_.size(); }

    void run(const double *q, const std::uint8_t *admissible, std::size_t n, const device::StageSettings &settings,
             std::vector<device::PairOutcome> &outcomes) override
    {
        device::StageCounts stages;
        device::StageCounts *counted = countingStages() ? &stages : nullptr;
        const device::ExecutorCounts used = executors_.run(
            [&](Exec &ex) { runStagesInChunks(ex, arrays_, settings, budget_, q, admissible, n, outcomes, counted); });
        record(counted, used);
    }

protected:
    explicit PooledStageRunner(std::function<std::unique_ptr<Exec>()> makeExecutor)
        : executors_(std::move(makeExecutor))
    {
    }

    device::ModelArrays arrays_{};
    device::StageBudget budget_;

private:
    ExecutorPool<Exec> executors_;
};
}  // namespace rastercheck
