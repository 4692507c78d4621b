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
}  // namespace rastercheck::test
