#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Geometry>

namespace rastercheck
{
class CollisionModel;

/** \brief Relative tolerance of a penetration depth: the expanding polytope stops once its upper
    and lower bounds on the depth meet within this fraction of the pair's size (the sum of the two
    solids' bounding radii). */
constexpr double kPenetrationTolerance = 1e-9;

/** \brief How deep the two solids of a colliding pair overlap (DistanceRequest::penetration).

    The penetration depth of solids A and B is the length of the shortest translation of A after
    which the two no longer overlap (they may touch). Two sound bounds on it are returned, each up
    to rounding:

    - \a depth, an upper bound with its proof: moving the component by depth * direction leaves the
      pair at most touching (any farther, apart). It is the depth of the pair's convex hulls (EPA,
      device/Penetration.h, on the hulls of their vertices, or of their primitive shapes), whose
      shortest way out takes the solids out too, since each hull holds its solid.
    - \a lowerBound: no translation shorter than it separates the pair. It is the largest depth
      among pairs of convex bodies known to lie inside the solids, each pair's depth being at most
      the solids' (a translation that separates the solids separates any parts of them): a
      primitive shape (Component::shapes, SceneObject::shapes) is one; a closed shell whose every
      face is on its hull (a convex mesh, to 1e-9 of its size) is its hull; a closed shell close to
      convex (one that keeps face planes: ConvexPiece::numPlanes, at most 2 % of its size in front
      of a face) holds its hull shrunk towards its centre until it lies behind every face plane (a
      point behind every face of a closed, outward-oriented surface is inside it). Each shell of a
      solid made of several counts on its own. A solid with none of these (an open mesh, a shell far
      from convex: an L, a U, a room) has no convex body known inside it: its pairs' lower bound is 0.

    For a pair of convex solids (single primitives, convex meshes) the two meet: \a exact, and depth
    is the penetration depth within kPenetrationTolerance of the pair's size. A curved pair whose
    depth is nearly the same along many ways out (a sphere nearly concentric inside a cylinder) can
    leave the polytope's room (device::kPolytopePoints) before the bounds meet: then \a exact is false
    and both bounds still hold. For non-convex solids the hull's depth can exceed the true depth by
    any amount (a small box pressed 1 mm into the inner wall of a U's notch is 1 mm deep, but deep
    inside the U's hull), and the lower bound can be 0 while the solids overlap deeply. */
struct Penetration
{
    /** \brief Metres: the upper bound. NaN when not measured (not asked, or the state does not
        collide: DistanceResult::colliding()); 0 when the hulls only touch. */
    double depth = std::numeric_limits<double>::quiet_NaN();
    /** \brief Metres: the lower bound, <= depth; NaN when not measured. */
    double lowerBound = std::numeric_limits<double>::quiet_NaN();
    /** \brief depth - lowerBound is within the tolerance: depth is the penetration depth. */
    bool exact = false;
    /** \brief Unit, world frame: the way to move the component out of the other solid (zero when
        depth is 0 or not measured). */
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();
    /** \brief The deepest points along direction, on the hulls (on the solids when exact), world
        frame: pointOnOther - pointOnComponent is about depth * direction. */
    Eigen::Vector3d pointOnComponent = Eigen::Vector3d::Zero();
    Eigen::Vector3d pointOnOther = Eigen::Vector3d::Zero();
};

/** \brief The penetration depths of a model's pairs (Penetration, which says what is measured).
    Each step of the expanding polytope reads every vertex of a mesh side (its hull's support
    point), a few dozen steps a pair: a large scene mesh costs in proportion. What it reads of each
    solid is prepared once, the first time a pair of it is measured (the shrunken hulls of its
    shells read every vertex against every face plane). Thread-safe. */
class PairPenetration
{
public:
    explicit PairPenetration(const CollisionModel &model);
    ~PairPenetration();

    /** \brief Measures pair \a pair (CollisionModel numbering) with its component placed by \a poseA
        (link pose) and the other solid by \a poseB (the other component's link pose, or the
        identity for a scene object). \a relativeTolerance: kPenetrationTolerance unless a test
        asks for less. Solids that do not overlap have depth 0. */
    void measure(std::uint32_t pair, const Eigen::Isometry3d &poseA, const Eigen::Isometry3d &poseB,
                 Penetration &result, double relativeTolerance = kPenetrationTolerance) const;

private:
    struct Solid;
    const Solid &solid(std::size_t index) const;

    const CollisionModel &model_;
    mutable std::unique_ptr<std::once_flag[]> prepared_;
    mutable std::vector<Solid> solids_;
};
}  // namespace rastercheck
