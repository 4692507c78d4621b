#pragma once

// No Eigen and no CUDA here: the CUDA runner (cuda/) includes this with nvcc.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rastercheck/device/BatchPipeline.h"

namespace rastercheck
{
/** \brief Runs the batched pipeline's stages (device/BatchPipeline.h) on some executor: the GPU
    (cuda/) or the host (makeHostStageRunner, which runs the GPU's code path on the CPU). */
class StageRunner
{
public:
    virtual ~StageRunner() = default;
    virtual std::string name() const = 0;
    /** \brief Appends to \a outcomes every pair of states [0, n) that survives the culls, sorted by
        (state, pair), with state indices of this batch. Not thread-safe (StagedBackend locks). */
    virtual void run(const double *q, const std::uint8_t *admissible, std::size_t n,
                     const device::StageSettings &settings, std::vector<device::PairOutcome> &outcomes) = 0;
    /** \brief What the stages did in every run so far. */
    const device::StageCounts &counts() const { return counts_; }

protected:
    device::StageCounts counts_;
};
}  // namespace rastercheck
