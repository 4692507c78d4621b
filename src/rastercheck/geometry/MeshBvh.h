#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/geometry/Aabb.h"
#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief Bounding-volume hierarchy over a mesh's triangles, in the mesh's own frame: a flat array
    of nodes (AABBs) linked by index, leaves holding a few triangles. Immutable after build; share
    it between threads freely. This is the exact oracle's acceleration structure. */
class MeshBvh
{
public:
    struct Node
    {
        Aabb box;
        /** \brief Inner node: index of the first child (the second is first + 1), >= 0.
            Leaf: -(1 + first triangle slot) into triangleOrder. */
        std::int32_t first = 0;
        std::uint32_t count = 0;  ///< leaf: number of triangles; inner: 0
        bool isLeaf() const { return first < 0; }
    };

    /** \brief Builds over \a mesh, which must outlive this object and not change. */
    explicit MeshBvh(const Mesh &mesh, unsigned maxLeafTriangles = 4);

    const Mesh &mesh() const { return *mesh_; }
    const std::vector<Node> &nodes() const { return nodes_; }
    const std::vector<std::uint32_t> &triangleOrder() const { return triangleOrder_; }

private:
    const Mesh *mesh_;
    std::vector<Node> nodes_;
    std::vector<std::uint32_t> triangleOrder_;
};

/** \brief Where two meshes touch: a point (world frame) and the triangle of each mesh. */
struct MeshContact
{
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    std::int32_t triangleA = -1;  ///< -1 when found by containment (no surface crossing)
    std::int32_t triangleB = -1;
};

/** \brief Do the surfaces of A (placed by poseA) and B (placed by poseB) come within \a padding
    (metres; 0 = intersect or touch)? Exact triangle tests over both BVHs. */
bool surfacesWithin(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b,
                    const Eigen::Isometry3d &poseB, double padding, MeshContact *contact = nullptr);

/** \brief Is \a point (frame of the mesh) strictly inside the closed mesh of \a bvh? Parity of a
    ray cast, retried along other directions when the ray grazes an edge or vertex. Meaningful
    only for closed meshes. */
bool pointInsideClosedMesh(const MeshBvh &bvh, const Eigen::Vector3d &point);

/** \brief The exact oracle for two solids: true when their surfaces come within \a padding or one
    contains the other (tested for closed meshes only: \a closedA / \a closedB). */
bool solidsOverlap(const MeshBvh &a, const Eigen::Isometry3d &poseA, bool closedA, const MeshBvh &b,
                   const Eigen::Isometry3d &poseB, bool closedB, double padding, MeshContact *contact = nullptr);
}  // namespace rastercheck
