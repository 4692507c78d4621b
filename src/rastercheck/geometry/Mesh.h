#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/geometry/Aabb.h"

namespace rastercheck
{
/** \brief A triangle mesh as flat arrays: vertices (metres, in the mesh's own frame) and triangles
    as three vertex indices each, counter-clockwise seen from outside for a closed, consistently
    oriented mesh. The layout maps one to one onto device buffers. */
struct Mesh
{
    using Triangle = std::array<std::uint32_t, 3>;

    std::vector<Eigen::Vector3d> vertices;
    std::vector<Triangle> triangles;

    std::size_t numVertices() const { return vertices.size(); }
    std::size_t numTriangles() const { return triangles.size(); }
    bool empty() const { return triangles.empty(); }
    /** \brief Triangle \a t's normal by its corners' order (counter-clockwise seen from its tip),
        twice its area long. */
    Eigen::Vector3d triangleNormal(std::size_t t) const
    {
        const Triangle &c = triangles[t];
        return (vertices[c[1]] - vertices[c[0]]).cross(vertices[c[2]] - vertices[c[0]]);
    }

    /** \brief Axis-aligned bounds of the vertices used by triangles (empty box for an empty mesh). */
    Aabb bounds() const;

    /** \brief Indices of the vertices extreme along \a directions directions spread evenly over the
        sphere (a Fibonacci lattice), without repeats, in ascending order: a small set whose convex
        hull approaches the mesh's from inside (within about 1 - cos of the directions' spacing, a
        few percent of the size for 128 directions). Every vertex when there are no more than
        \a directions. */
    std::vector<std::uint32_t> extremeVertices(std::size_t directions) const;

    /** \brief Applies \a transform to every vertex. */
    void transform(const Eigen::Isometry3d &transform);

    /** \brief Scales every vertex coordinate-wise (URDF mesh `scale`). A negative number of negative
        factors mirrors the mesh, so triangle orientation is flipped to stay outward. */
    void scale(const Eigen::Vector3d &factors);

    /** \brief Appends \a other, optionally placed by \a transform. */
    void append(const Mesh &other, const Eigen::Isometry3d &transform = Eigen::Isometry3d::Identity());
};
}  // namespace rastercheck
