#pragma once

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief Closed, outward-oriented triangle meshes of the URDF / MoveIt primitives, centred at the
    origin (cylinder axis = z, as in URDF and MoveIt).

    Curved primitives are tessellated so that the mesh *contains* the exact shape (vertices lie on
    the circumscribed polygon / polyhedron) and no point of the mesh is farther than
    \a maxError (metres) from the exact surface. A collision checker using these meshes therefore
    never misses a contact of the exact primitive; it may report contacts up to maxError early.

    Segment counts follow from maxError (the smallest that meet it for cylinders and cones), capped at
   kMaxPrimitiveSegments around the circumference; only a maxError below about 5e-6 of the radius reaches the cap, and
   then the deviation is radius * (1 / cos(pi / kMaxPrimitiveSegments) - 1) instead. Sizes and maxError must be positive
   and finite (ConfigurationError otherwise); loaders check them first and report the file and element. */
Mesh makeBox(const Eigen::Vector3d &size);
Mesh makeCylinder(double radius, double length, double maxError);
Mesh makeSphere(double radius, double maxError);
/** \brief MoveIt's cone (apex at +length/2, base at -length/2); same containment rule. */
Mesh makeCone(double radius, double length, double maxError);

/** \brief Upper bound on polygon sides around a circle (sphere: meridians; half as many bands). */
constexpr int kMaxPrimitiveSegments = 1024;

/** \brief Default tessellation error of primitives: 1 mm. */
constexpr double kDefaultPrimitiveError = 1e-3;
}  // namespace rastercheck
