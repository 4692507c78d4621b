#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "rastercheck/collision/Backend.h"
#include "rastercheck/device/Raster.h"

namespace rastercheck
{
struct CpuWorkspace;

/** \brief One pair's image plane: coverage per pixel (bit 0: the component, bit 1: the other solid)
    and the pixels whose rays find the solids overlapping. Row-major, grid.width x grid.height. */
struct RasterImage
{
    device::RasterGrid grid{};
    std::vector<std::uint8_t> coverage;
    std::vector<std::uint8_t> hits;
};

/** \brief The reference backend: the pipeline's stages run per state on the CPU, using the same
    per-element functions (device/) as the CUDA kernels; states are spread over threads (OpenMP).
    Scratch buffers are pooled and reused, so steady-state checking does not allocate. */
class CpuBackend : public Backend
{
public:
    explicit CpuBackend(CollisionModelConstPtr model);
    ~CpuBackend() override;

    std::string name() const override { return "cpu"; }
    void check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts,
               const CollisionRequest &request, int threads) const override;

    /** \brief Decides one state with the caller's workspace (no locking, no allocation once warm). */
    bool isValid(const double *q, const CollisionRequest &request, CpuWorkspace &workspace, Contact *contact) const;

    std::unique_ptr<CpuWorkspace> makeWorkspace() const;

    /** \brief The raster image of the pair named by \a contact at state \a q (the paper's Fig. 6):
        which pixels each solid covers and where Sort_Search_Pair finds the overlap. For pictures and
        debugging; allocates. False when the contact names no pair or their boxes do not meet. */
    bool rasterImage(const double *q, const Contact &contact, const CollisionRequest &request, RasterImage &image) const;

private:
    std::unique_ptr<CpuWorkspace> acquire() const;
    void release(std::unique_ptr<CpuWorkspace> workspace) const;

    CollisionModelConstPtr model_;
    mutable std::mutex poolMutex_;
    mutable std::vector<std::unique_ptr<CpuWorkspace>> pool_;
};
}  // namespace rastercheck
