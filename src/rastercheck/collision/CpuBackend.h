#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/collision/Backend.h"
#include "rastercheck/core/Pool.h"
#include "rastercheck/device/Boxes.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/Raster.h"

namespace rastercheck
{
/** \brief Scratch of one thread: every buffer the stages write, sized on first use and reused. */
struct CpuWorkspace
{
    explicit CpuWorkspace(const CollisionModel &model)
        : jointValues(model.robot->joints.size()),
          linkPoses(model.robot->links.size()),
          componentPose(model.numComponents()),
          componentBox(model.numComponents()),
          componentBounds(model.numComponents()),
          layerBounds(model.numComponents()),
          layerPadding(model.numComponents()),
          layerLargest(model.numComponents()),
          componentWorld(model.numComponents()),
          componentWorldState(model.numComponents(), 0),
          proofDirection(model.numPairs(), device::Vec3<double>{0.0, 0.0, 0.0})
    {
    }

    std::vector<double> jointValues;                 // n_joints
    std::vector<device::Pose<double>> linkPoses;     // n_links
    std::vector<device::Pose<float>> componentPose;  // n_components
    std::vector<device::OrientedBox> componentBox;   // n_components, world
    std::vector<device::Box> componentBounds;        // n_components, world
    std::vector<device::Box> layerBounds;            // n_components: bounds of layer k's subtree
    std::vector<float> layerPadding;                 // n_components: largest padding in layer k's subtree
    std::vector<double> layerLargest;                // n_components: the same in double

    // World vertices of each component, transformed once per state on first use (a component
    // meets several objects); componentWorldState says for which state they are current.
    std::vector<std::vector<device::Vec3<float>>> componentWorld;  // n_components x n_vertices
    std::vector<std::uint64_t> componentWorldState;                // n_components
    std::uint64_t state = 0;
    // Per pair (CollisionModel numbering): the direction that last proved it apart, tried first at
    // the next state (consecutive states of a motion are close); zero until a proof.
    std::vector<device::Vec3<double>> proofDirection;  // n_pairs
    std::vector<std::uint32_t> candidatesA, candidatesB;
    std::vector<int> pixelCount;              // n_pixels
    std::vector<int> pixelStart;              // n_pixels + 1
    std::vector<device::Fragment> fragments;  // total fragments
    ExactWorkspace exact;                     // the exact phase's scratch
};

/** \brief Worker threads for a batch of \a n states: \a requested (0 = all cores), but at least
    16 states each. Forking a team for a handful of states (the motion validator's first rakes)
    costs more than it saves, and far more when the cores are busy (threads spin at the join). */
int batchWorkers(std::size_t n, int requested);

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
    void check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts, const CollisionRequest &request,
               int threads) const override;

    /** \brief One pass: a pair that misses its wider padding is tried at the request's own, and
        the pairs after it only at theirs. */
    bool checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts, const CollisionRequest &request,
                          const PairPadding &wider, int threads) const override;

    /** \brief Decides one state with the caller's workspace (no locking, no allocation once warm),
        with row \a paddingRow of the request's pairPadding. With \a wider (row \a paddingRow
        too), a PaddedVerdict: Clear at the wider paddings, Near, or Collides at the request's;
        without, 1 = valid, 0 = not. */
    std::uint8_t isValid(const double *q, const CollisionRequest &request, CpuWorkspace &workspace, Contact *contact,
                         std::size_t paddingRow = 0, const PairPadding *wider = nullptr) const;

    std::unique_ptr<CpuWorkspace> makeWorkspace() const;
    /** \brief A pooled workspace (made when the pool is empty); give it back with giveBack(). */
    std::unique_ptr<CpuWorkspace> borrow() const;
    void giveBack(std::unique_ptr<CpuWorkspace> workspace) const;

    /** \brief Forward kinematics and box refit of state \a q into \a workspace: what decideOpenPair needs. */
    void refitState(const double *q, CpuWorkspace &workspace) const;
    /** \brief Decides one pair (CollisionModel's numbering) that the culls and proofs left open, at
        the state last refitted into \a workspace: by the exact narrow phase with the pair's padding
        (PairPaddings: the request's, plus row \a paddingRow of its pairPadding), or in
        conservative mode as colliding. On collision fills \a contact completely. The staged
        backends finish the pairs their stages could not settle with this; the stages have already
        tried the hull proof on those pairs, so it is not repeated here. */
    bool decideOpenPair(std::uint32_t pair, const CollisionRequest &request, CpuWorkspace &workspace,
                        Contact &contact, std::size_t paddingRow = 0) const;

    /** \brief The raster image of the pair named by \a contact at state \a q (the paper's Fig. 6):
        which pixels each solid covers and where Sort_Search_Pair finds the overlap. For pictures and
        debugging; allocates. False when the contact names no pair or their boxes do not meet. */
    bool rasterImage(const double *q, const Contact &contact, const CollisionRequest &request,
                     RasterImage &image) const;

private:
    /** \brief check() (\a wider null) and checkTwoPaddings(): isValid over \a n states, on threads. */
    void decide(const double *q, std::size_t n, std::uint8_t *verdicts, Contact *contacts,
                const CollisionRequest &request, const PairPadding *wider, int threads) const;

    CollisionModelConstPtr model_;
    Pool<CpuWorkspace> workspaces_;
};
}  // namespace rastercheck
