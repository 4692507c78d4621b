#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief The triangles of one assimp node (all its meshes), in the file's root frame: the node's
    accumulated transform is applied. Faces that are not triangles (lines, points) are dropped. */
struct MeshNode
{
    std::string name;
    Mesh mesh;
    /** \brief Sum and number of every vertex assimp returns for this node's meshes (after
        JoinIdenticalVertices, in the root frame), including vertices only lines or points use.
        OMPL.app centres its robot on the mean of exactly these vertices. */
    Eigen::Vector3d vertexSum = Eigen::Vector3d::Zero();
    std::size_t vertexCount = 0;
};

/** \brief How the COLLADA `<up_axis>` is treated (other formats have none). */
enum class ColladaUpAxis
{
    /** \brief Keep the file's axes (a Z_UP file stays Z up): the ROS convention for URDF meshes
        (RViz and MoveIt drop assimp's rotation). */
    Keep,
    /** \brief assimp's default: rotate into Y up. OMPL.app reads its problems this way, so the .cfg
        coordinates refer to the rotated meshes. */
    ConvertToYUp
};

/** \brief Reads a mesh file (STL, OBJ, DAE, anything assimp reads) as one node per assimp node
    that owns meshes (assimp flags Triangulate | JoinIdenticalVertices | SortByPType, as OMPL.app,
    applied after a check that every face has vertices and names only vertices the mesh has).
    Units are those of the file (COLLADA <unit> is applied by assimp).
    Throws InputError naming the file when it is missing, unreadable (a face naming no vertex or a missing one included),
    or has no triangles, when a vertex coordinate is not finite, or when a PLY file is not in the
    form detail::checkPly (io/PlyCheck.h) accepts (assimp would hang or allocate what a malformed one
    declares: checked before assimp reads it). OBJ material libraries
    (.mtl) are not opened: only geometry is used, and assimp's MTL parser crashes on some files. */
std::vector<MeshNode> loadMeshNodes(const std::string &path, ColladaUpAxis upAxis = ColladaUpAxis::Keep);

/** \brief All triangles of a mesh file merged into one mesh (root frame). */
Mesh loadMesh(const std::string &path, ColladaUpAxis upAxis = ColladaUpAxis::Keep);

/** \brief As loadMeshNodes, from bytes in memory; \a formatHint is a file extension ("stl").
    \a name is used in error messages. No file is opened (an OBJ's `mtllib` is not read; materials
    are not used anyway). */
std::vector<MeshNode> loadMeshNodesFromMemory(const void *data, std::size_t size, const std::string &formatHint,
                                              const std::string &name = "<memory>",
                                              ColladaUpAxis upAxis = ColladaUpAxis::Keep);
}  // namespace rastercheck
