#pragma once

#include <Eigen/Geometry>

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief Closed, outward-oriented triangle meshes of the URDF / MoveIt primitives, centred at the
    origin (cylinder axis = z, as in URDF and MoveIt).

    Curved primitives are tessellated so that the mesh *contains* the exact shape (vertices lie on
    the circumscribed polygon / polyhedron) and no point of the mesh is farther than
    \a maxError (metres) from the exact surface. A collision checker using these meshes therefore
    never misses a contact of the exact primitive; it may report contacts up to maxError early
    (safe and exact mode then decide the pair on the exact shapes: PrimitiveShape, CurvedSolids).

    Segment counts follow from maxError (the smallest that meet it for cylinders and cones), capped at
   kMaxPrimitiveSegments around the circumference (a sphere at kMaxSphereBands); only a maxError below about 5e-6 of
   the radius reaches the cap (a sphere's: 1.5e-4), and then the deviation is radius * (1 / cos(pi /
   kMaxPrimitiveSegments) - 1) instead (a sphere's: about 1.5e-4 of its radius). Sizes and maxError must be positive
   and finite (ConfigurationError otherwise); loaders check them first and report the file and element. */
Mesh makeBox(const Eigen::Vector3d &size);
Mesh makeCylinder(double radius, double length, double maxError);
Mesh makeSphere(double radius, double maxError);
/** \brief MoveIt's cone (apex at +length/2, base at -length/2); same containment rule. */
Mesh makeCone(double radius, double length, double maxError);

/** \brief The exact shape a primitive's mesh stands for, placed in the frame of the solid it belongs
    to (a link's frame, or the world for a scene object): what the curved primitives' exact tests
    (collision/CurvedSolids.h) read. */
struct PrimitiveShape
{
    enum class Kind
    {
        Box,
        Sphere,
        Cylinder,
        Cone
    };
    Kind kind = Kind::Box;
    /** \brief Box: edge lengths x y z; sphere: radius; cylinder and cone: radius, length (metres). */
    Eigen::Vector3d size = Eigen::Vector3d::Zero();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    /** \brief Whether its mesh only approximates it (from outside: makeSphere, makeCylinder,
        makeCone). */
    bool curved() const { return kind != Kind::Box; }
};

/** \brief Upper bound on polygon sides around a circle (cylinders and cones). */
constexpr int kMaxPrimitiveSegments = 1024;

/** \brief Upper bound on a sphere's bands (it has twice as many meridians, and 4 bands^2 - 4 bands
    triangles: 65 024 at the bound). A sphere's triangles grow with the square of its bands: at 1 024
    meridians, a MoveIt scene with one sphere of radius 605 m (1 mm error asked) took 9.3 s and
    855 MB to load (found by fuzz_scene; 0.65 s and 97 MB at this bound). A maxError below about
    1.5e-4 of the radius (a sphere over about 6 m at the default 1 mm) reaches the bound; the mesh
    still contains the sphere, its vertices then up to 1.5e-4 of the radius outside it, and safe and
    exact mode decide the sphere's pairs on the exact shape anyway (CurvedSolids). */
constexpr int kMaxSphereBands = 128;

/** \brief Default tessellation error of primitives: 1 mm. */
constexpr double kDefaultPrimitiveError = 1e-3;
}  // namespace rastercheck
