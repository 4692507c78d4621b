#pragma once

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief Closed, outward-oriented triangle meshes of the URDF / MoveIt primitives, centred at the
    origin (cylinder axis = z, as in URDF and MoveIt).

    Curved primitives are tessellated so that the mesh *contains* the exact shape (vertices lie on
    the circumscribed polygon / polyhedron) and no point of the mesh is farther than
    \a maxError (metres) from the exact surface. A collision checker using these meshes therefore
    never misses a contact of the exact primitive; it may report contacts up to maxError early. */
Mesh makeBox(const Eigen::Vector3d &size);
Mesh makeCylinder(double radius, double length, double maxError);
Mesh makeSphere(double radius, double maxError);
/** \brief MoveIt's cone (apex at +length/2, base at -length/2); same containment rule. */
Mesh makeCone(double radius, double length, double maxError);

/** \brief Default tessellation error of primitives: 1 mm. */
constexpr double kDefaultPrimitiveError = 1e-3;
}  // namespace rastercheck
