#pragma once

#include <limits>
#include <vector>

#include "rastercheck/geometry/Aabb.h"
#include "rastercheck/geometry/Mesh.h"

namespace rastercheck::test
{
/** \brief An axis-aligned box from its two corners. */
Aabb box(const Eigen::Vector3d &min, const Eigen::Vector3d &max);

/** \brief The union of \a boxes as one closed, outward-oriented, watertight surface: the boundary
    faces of the rectilinear grid their coordinates span (every grid interval longer than \a maxCell
    split evenly, so large flat faces become many triangles), two triangles per grid face. Boxes that
    overlap or share faces merge into one shell; no T-junctions. The union must not touch itself
    along an edge only (two cells diagonal across an edge, empty on both other sides), or that edge
    is non-manifold. */
Mesh blockSolid(const std::vector<Aabb> &boxes, double maxCell = std::numeric_limits<double>::infinity());

/** \brief A room, one shell with a doorway (genus 1): outer box [0,4] x [0,3] x [0,2.4], floor,
    ceiling and walls 0.2 thick (inside [0.2,3.8] x [0.2,2.8] x [0.2,2.2]); the doorway goes through
    the +x wall (x in [3.8,4]) at y in [1,2], z in [0.2,2.0] (lintel z in [2.0,2.2]). Grid faces at
    most \a maxCell wide. */
Mesh roomWithDoorway(double maxCell = 0.25);

/** \brief A U, one shell, an extruded polygon: base [0,2] x [0,0.4] x [0,1] and arms [0,0.4] and
    [1.6,2] in x, y in [0.4,2]; the notch is x in [0.4,1.6], y in [0.4,2] (open at y = 2, top and
    bottom). */
Mesh uShape(double maxCell = 0.2);

/** \brief An L-shaped bar, one shell, in its body frame: [-0.3,0.3] x [-0.05,0.05] x [-0.05,0.05]
    and a leg [-0.3,-0.2] x [0.05,0.35] x [-0.05,0.05], times \a scale. Every point is within
    0.47 * scale of the frame's origin. */
Mesh lBar(double scale = 1.0);

/** \brief A maze: a floor slab [-0.05,4.05]^2 x [0,0.2] and eleven walls 0.1 thick sunk into it,
    as twelve overlapping closed boxes in one mesh (more shells than the separation cull splits a
    solid into). Walls along y (x range, y range), z in [0.15,1.15]: [0,0.1] x [0.02,3.98], [3.9,4] x
    [0.02,3.98], [0.95,1.05] x [0.05,3], [1.95,2.05] x [1,3.95], [2.95,3.05] x [0.05,3]; walls along
    x, z in [0.12,1.1]: [0.05,3.95] x [0,0.1], [0.05,3.95] x [3.9,4], [0.05,0.5] x [1.45,1.55],
    [1.5,2] x [2.45,2.55], [2.5,3] x [0.95,1.05], [3.4,3.95] x [3.2,3.3]. Overlapping boxes never
    share a face plane where they overlap. Each box's faces split into cells at most \a maxCell wide. */
Mesh mazeOnSlab(double maxCell = 0.25);

/** \brief A bookshelf, one shell, opening towards -x: back panel x in [0.8,0.85], sides y in
    [-0.6,-0.56] and [0.56,0.6], boards z in [0,0.03], [0.4,0.43], [0.8,0.83], [1.17,1.2]; depth x
    in [0.45,0.85], width y in [-0.6,0.6]. */
Mesh bookshelf(double maxCell = 0.1);
}  // namespace rastercheck::test
