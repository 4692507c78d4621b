#pragma once

// No Eigen and no CUDA here: the CUDA runner (cuda/) includes this with nvcc.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "rastercheck/device/BatchPipeline.h"

namespace rastercheck
{
/** \brief Runs the batched pipeline's stages (device/BatchPipeline.h) on some executor: the GPU
    (cuda/) or the host (makeHostStageRunner, which runs the GPU's code path on the CPU). The model
    is held once; each call of run() takes an executor of its own (on the GPU: its own stream and
    scratch buffers, kept for later calls), so several threads run passes at the same time. */
class StageRunner
{
public:
    virtual ~StageRunner() = default;
    virtual std::string name() const = 0;
    /** \brief The executors made so far, each with its own scratch (on the GPU its own stream and
        host mirrors): as many as runs ever ran at once. */
    virtual std::size_t executors() const = 0;
    /** \brief Appends to \a outcomes every pair of states [0, n) that survives the culls (with
        StageSettings::onlyDecisive, only those the per-state reduction reads), sorted by (state,
        pair), with state indices of this batch. Thread-safe. */
    virtual void run(const double *q, const std::uint8_t *admissible, std::size_t n,
                     const device::StageSettings &settings, std::vector<device::PairOutcome> &outcomes) = 0;
    /** \brief Whether runs add to counts(): counting the pairs that went to the raster and to the
        exact phase costs two compactions per chunk, so production passes leave it off (the
        default). */
    void countStages(bool on) { countStages_ = on; }
    /** \brief What the stages did in the runs made while countStages was on. */
    device::StageCounts counts() const
    {
        std::lock_guard<std::mutex> lock(countsMutex_);
        return counts_;
    }
    /** \brief The launches, waits and allocations of every run so far (always counted; per call:
        the difference over it, ExecutorCounts::since). */
    device::ExecutorCounts executorCounts() const
    {
        std::lock_guard<std::mutex> lock(countsMutex_);
        return executorCounts_;
    }

protected:
    bool countingStages() const { return countStages_; }
    /** \brief Adds what one run did: its stage counts (null when not counting) and its executor's. */
    void record(const device::StageCounts *stages, const device::ExecutorCounts &executor)
    {
        std::lock_guard<std::mutex> lock(countsMutex_);
        if (stages)
            counts_ += *stages;
        executorCounts_ += executor;
    }

private:
    std::atomic<bool> countStages_{false};
    mutable std::mutex countsMutex_;
    device::StageCounts counts_;
    device::ExecutorCounts executorCounts_;
};
}  // namespace rastercheck
