#pragma once

#include <memory>
#include <vector>

#include "rastercheck/collision/CollisionModel.h"

namespace rastercheck::test
{
/** \brief The exact oracle with no culling at all: every component against every object and every
    self pair the ACM does not allow, by solidsOverlap, a pair with curved primitives then on their
    exact shapes (CurvedSolids). Independent of the pipeline's box culls, so it checks them too.
    Single-threaded; for tests and benches. */
bool bruteForceCollides(const CollisionModel &model, const double *q, double padding);

/** \brief FCL 0.7 as OMPL.app and MoveIt use it: BVHModel<OBBRSS> per component and object, a
    dynamic AABB tree over the objects, fcl::collide (surfaces only: FCL does not report a solid
    buried inside another) or fcl::distance when padding > 0. Not thread-safe (one per thread). */
class FclReference
{
public:
    /** \brief \a exactPrimitives: a component or object of one primitive shape (Component::shapes,
        SceneObject::shapes) is that FCL shape (fcl::Boxd, Sphered, Cylinderd, Coned) instead of its
        mesh, as MoveIt loads a scene's primitives. */
    explicit FclReference(const CollisionModel &model, bool exactPrimitives = false);
    ~FclReference();
    bool collides(const double *q, double padding = 0.0);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
/** \brief FCL 0.7's fcl::distance over the pairs a validity check decides (components against
    objects, the self pairs the ACM does not exempt), meshes as BVHModel<OBBRSS> (and, with
    \a exactPrimitives, single primitives as FCL shapes, as FclReference). Per state one
    DistanceResult is shared by every pair, so each pair's traversal prunes against the running
    minimum (FCL's traversal reads the result's min_distance), which is how FCL's own broadphase
    distance runs. Exact (rel_err = abs_err = 0) for meshes; FCL's GJK decides shapes. Surfaces
    only: a solid inside another is apart. Not thread-safe (one per thread). */
class FclDistance
{
public:
    explicit FclDistance(const CollisionModel &model, bool exactPrimitives = false);
    ~FclDistance();
    /** \brief The minimum distance at \a q (an admissible state) over the pairs asked for; the
        two nearest points (world frame) when \a points is not null. Infinity with no pair. */
    double distance(const double *q, bool environment = true, bool self = true, Eigen::Vector3d *points = nullptr);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/** \brief fcl::distance between two meshes (BVHModel<OBBRSS>, built per call) placed by the poses. */
double fclMeshDistance(const Mesh &a, const Eigen::Isometry3d &poseA, const Mesh &b, const Eigen::Isometry3d &poseB);
}  // namespace rastercheck::test
