#pragma once

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
};

/** \brief Reads a mesh file (STL, OBJ, DAE, anything assimp reads) as one node per assimp node
    that owns meshes. Units are those of the file (COLLADA <unit> is applied by assimp).
    Throws InputError naming the file when it is missing, unreadable, or has no triangles. */
std::vector<MeshNode> loadMeshNodes(const std::string &path);

/** \brief All triangles of a mesh file merged into one mesh (root frame). */
Mesh loadMesh(const std::string &path);

/** \brief As loadMeshNodes, from bytes in memory; \a formatHint is a file extension ("stl").
    \a name is used in error messages. */
std::vector<MeshNode> loadMeshNodesFromMemory(const void *data, std::size_t size, const std::string &formatHint,
                                              const std::string &name = "<memory>");
}  // namespace rastercheck
