#pragma once

#include <cstdint>
#include <vector>

#include "rastercheck/device/CurvedShapes.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/geometry/MeshDistance.h"

namespace rastercheck
{
class CollisionModel;

/** \brief Exact decisions for the pairs that involve spheres, cylinders and cones.

    Their meshes contain the exact shapes and lie up to the tessellation error (1 mm by default)
    outside them (geometry/Primitives.h): every cull, proof and exact test that calls such a pair
    apart is right, but one that calls it colliding may see a gap thinner than that error as a
    contact. So in safe and exact mode a pair the meshes call colliding is decided again here, on the
    exact shapes, whenever a side of it is made of primitives only (Component::shapes,
    SceneObject::shapes) and a side has a curved one: primitive against primitive by GJK
    (device/ConvexDistance.h) on each pair of shapes; primitives against the other side's mesh by
    GJK against each triangle its tree cannot rule out, then whether the primitive lies inside that
    mesh (closed meshes). A side that mixes curved primitives with meshes keeps its mesh, which is
    on the safe side: a false alarm within the error is possible there, a missed contact never. */
class CurvedSolids
{
public:
    CurvedSolids() = default;
    /** \brief Reads the model's robot and scene shapes, its self pairs and pair numbering. */
    explicit CurvedSolids(const CollisionModel &model);

    /** \brief Whether pair \a pair (CollisionModel numbering) is decided again by collide(). */
    bool refines(std::uint32_t pair) const { return pair < refines_.size() && refines_[pair] != 0; }
    /** \brief refines() as flags, 1 per pair (shorter than the pair count when the last pairs have none). */
    const std::vector<std::uint8_t> &refinedPairs() const { return refines_; }

    /** \brief Every solid's shapes as the per-element code reads them (device::CurvedArrays): the
        components, then the scene objects. */
    device::CurvedArrays arrays() const { return {shapes_.data(), reach_.data(), solidShapes_.data()}; }
    /** \brief The flat arrays themselves, for uploading. */
    const std::vector<device::ConvexShape> &shapes() const { return shapes_; }
    const std::vector<double> &reach() const { return reach_; }
    const std::vector<std::uint32_t> &solidShapes() const { return solidShapes_; }

    /** \brief Do the exact shapes of pair \a pair come within \a padding (>= 0)? \a poseA: the pair's
        component's link pose; \a poseB: the other component's link pose, or the identity for a
        scene object (world frame). Only for pairs that refines(). Thread-safe, no allocation.
        device::curvedPairCollides, which the batched stages run too. */
    bool collide(const CollisionModel &model, std::uint32_t pair, const device::Pose<double> &poseA,
                 const device::Pose<double> &poseB, double padding) const;

    /** \brief The distance between the exact shapes of pair \a pair (one that refines()) when it is
        below \a bound (metres): true, and \a result holds it with a closest pair of points (world
        frame; A is the pair's component) and the triangle of a mesh side (-1 on a shape). False
        when they are at least \a bound apart. Primitive against primitive by GJK
        (device::convexClosest) on each pair of shapes; primitives against the other side's mesh by
        GJK against each triangle its tree cannot rule out (node bounds against the best distance so
        far), then 0 when the primitive lies inside that mesh (closed meshes). Poses as collide().
        Thread-safe, no allocation. */
    bool distance(const CollisionModel &model, std::uint32_t pair, const device::Pose<double> &poseA,
                  const device::Pose<double> &poseB, double bound, SurfaceDistance &result) const;

private:
    std::vector<std::uint8_t> refines_;  // n_pairs
    std::vector<device::ConvexShape> shapes_;  // every solid's, in its own frame
    std::vector<double> reach_;                // per shape
    std::vector<std::uint32_t> solidShapes_;   // n_components + n_objects + 1 starts
};
}  // namespace rastercheck
