#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rastercheck/collision/Backend.h"
#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/core/Pool.h"
#include "rastercheck/collision/StageRunner.h"

namespace rastercheck
{
/** \brief The model's flat arrays in host memory, as the stages read them. */
device::ModelArrays hostModelArrays(const CollisionModel &model);

/** \brief How the stages treat a batch decided under \a request (contacts asked or not). */
device::StageSettings stageSettings(const CollisionModel &model, const CollisionRequest &request, bool contactsAsked);

/** \brief What the host executor's scratch buffers hold when a stage gets them. */
enum class HostScratch
{
    Reused,    ///< whatever the last chunk left (zeros when new), as in production
    Poisoned,  ///< all bytes 0xFF (NaN, -1, all flags set), as uninitialised device memory may be:
               ///< a stage that reads a slot nobody wrote then shows up in the CPU tests
    /** Poisoned, and the scratch and the model's arrays in pages no one may touch (PROT_NONE)
        except while one of the executor's operations runs, with downloads copied into host
        mirrors by an issued copy (as on a GPU, left 0xA5 until then): host code that reads the
        executor's memory, which on a GPU is the device's, faults, and a download read before its
        wait reads junk (tests; every operation changes page protections). */
    Guarded
};

/** \brief How the host executor runs a kernel's elements. */
enum class HostLoop
{
    Parallel,  ///< on OpenMP's threads, as in production
    /** One after the other on the calling thread, each timed (one over a microsecond twice, the
        lower time kept), and per kernel the slowest counted (ExecutorCounts::criticalPathSeconds):
        what one call would wait for on a device besides its launches, measured without one
        (benches; the verdicts are the same). */
    Timed,
    /** One after the other from the last to the first: a device keeps no order among a kernel's
        threads, and a stage that relies on the host's (an earlier element's atomic note seen by a
        later one) answers differently here (tests). */
    Reversed
};

/** \brief The stages on the host, through the same driver as the GPU (plain loops for kernels). */
std::unique_ptr<StageRunner> makeHostStageRunner(CollisionModelConstPtr model, const device::StageBudget &budget = {},
                                                 HostScratch scratch = HostScratch::Reused,
                                                 HostLoop loop = HostLoop::Parallel);

/** \brief A batch backend: the stages decide every pair they can for the whole batch in one pass,
    then the host reduces per state to the first colliding pair, deciding exactly (the CPU
    backend's narrow phase) the pairs the stages leave open. Verdicts and first contacts are the
    CPU backend's: in exact mode by construction; in raster mode through the shared per-element
    code; in safe mode a raster hit settles a pair as colliding when no contacts are asked (the
    fast path), and when contacts are asked every pair is decided exactly, as on the CPU.
    CollisionRequest::pairPadding gives every (state, pair) its own padding in the stages too.
    Several threads may call check() at once: each pass runs on an executor of its own. */
class StagedBackend : public Backend
{
public:
    StagedBackend(CollisionModelConstPtr model, std::unique_ptr<StageRunner> runner);
    ~StagedBackend() override;

    std::string name() const override { return runner_->name(); }
    void check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts, const CollisionRequest &request,
               int threads) const override;
    /** \brief Up to kTwoPaddingsInOnePassMost states: one pass of twice the states, each at the
        wider paddings and again at the request's (a pass's fixed costs once, where the Checker's two
        checks paid them twice: certified edges' rounds of midpoints). Larger batches: false, and
        the Checker's two checks (the second only of the states that missed the wider paddings). */
    bool checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts, const CollisionRequest &request,
                          const PairPadding &wider, int threads) const override;
    /** \brief The most states checkTwoPaddings decides in one pass: a planner's round of midpoints
        (tens to a few thousand) is bound by a call's latency, a larger batch by its states, where
        the second check's fewer states cost less than twice the first's. */
    static constexpr std::size_t kTwoPaddingsInOnePassMost = 4096;
    /** \brief Whether passes count what the stages did (off by default: it costs two compactions
        per chunk). */
    void countStages(bool on) const;
    /** \brief What the stages did in the passes made while countStages was on. */
    device::StageCounts stageCounts() const;
    /** \brief Launches, waits and allocations of every pass so far. */
    device::ExecutorCounts executorCounts() const;
    /** \brief The stages' executors made so far (StageRunner::executors). */
    std::size_t executors() const { return runner_->executors(); }

private:
    struct CallBuffers;
    CollisionModelConstPtr model_;
    CpuBackend exact_;
    std::unique_ptr<StageRunner> runner_;  // thread-safe: an executor per concurrent pass
    Pool<CallBuffers> callBuffers_;         // a call's host-side arrays, kept for later calls
};
}  // namespace rastercheck
