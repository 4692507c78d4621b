#pragma once

// The CUDA backend's entry points, free of CUDA types: the core calls them when the build has CUDA
// (RASTERCHECK_WITH_CUDA), and never includes a CUDA header.

#include <cstddef>
#include <memory>
#include <string>

#include "rastercheck/collision/StageRunner.h"

namespace rastercheck::cuda
{
/** \brief Whether a CUDA device can run this build's kernels. Fills \a description with the
    device ("NVIDIA H100 80GB HBM3, compute 9.0, 79 GiB free") or the reason there is none. Never
    throws. */
bool deviceUsable(std::string &description);

/** \brief A runner on device 0 with \a model's arrays (host memory) uploaded once. Its scratch
    (the stages' buffers) stays within \a memoryLimit bytes, or half the device's free memory when
    0; batches that need more are split into chunks, with the same verdicts. Throws
    std::runtime_error naming the CUDA call that failed. */
std::unique_ptr<StageRunner> makeStageRunner(const device::ModelArrays &model, std::size_t memoryLimit = 0);
}  // namespace rastercheck::cuda
