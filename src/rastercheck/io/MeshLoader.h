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
    that owns meshes (assimp flags Triangulate | JoinIdenticalVertices | SortByPType, applied after a
    check that every face has vertices and names only vertices the mesh has; OMPL.app adds flags
    that change the vertices but not the triangles, see loadOmplAppVertices).
    Units are those of the file (COLLADA <unit> is applied by assimp).
    Throws InputError naming the file when it is missing, unreadable (a face naming no vertex or a
    missing one included), or has no triangles, when a vertex coordinate is not finite, or when a
    PLY file is not in the form detail::checkPly (io/PlyCheck.h) accepts (assimp would hang or
    allocate what a malformed one declares: checked before assimp reads it). OBJ material libraries
    (.mtl) are not opened: only geometry is used, and assimp's MTL parser crashes on some files. */
std::vector<MeshNode> loadMeshNodes(const std::string &path, ColladaUpAxis upAxis = ColladaUpAxis::Keep);

/** \brief The vertices OMPL.app's RigidBodyGeometry takes from a mesh file (robot centre, bounds
    inferred from the environment), computed as it computes them. */
struct OmplAppVertices
{
    /** \brief OMPL.app's scene::extractVertices: every vertex of every mesh of every node, placed by
        the node's accumulated transform in assimp's float arithmetic, in node order (points and
        lines included). */
    std::vector<Eigen::Vector3d> vertices;
    /** \brief OMPL.app's scene::sceneCenter, where it puts the robot's origin: the vertices' mean,
        summed in float in the same order (on OMPL.app's own robots the double mean is up to 6e-4
        units, 2e-5 of the coordinates, away from it). */
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
};

/** \brief Reads a mesh file as OMPL.app does (assimp flags GenNormals | Triangulate |
    JoinIdenticalVertices | SortByPType | OptimizeGraph, COLLADA turned Y up) and returns its
    vertices. GenNormals gives a mesh without normals one normal per face, so JoinIdenticalVertices
    keeps a corner once per distinct normal of the faces around it (a mesh with normals keeps its
    own); OptimizeGraph merges nodes and meshes (placing their vertices in float). The triangles are
    those of loadMeshNodes (to float rounding), but the vertices, and so their mean, differ: FCL's
    rob.obj has 141 distinct corners and 361 vertices for OMPL.app, whose mean is 74 units from the
    mean of the 141. Checked and rejected as by loadMeshNodes, and InputError when a placed vertex
    is not finite in float. */
OmplAppVertices loadOmplAppVertices(const std::string &path);

/** \brief All triangles of a mesh file merged into one mesh (root frame). */
Mesh loadMesh(const std::string &path, ColladaUpAxis upAxis = ColladaUpAxis::Keep);

/** \brief As loadMeshNodes, from bytes in memory; \a formatHint is a file extension ("stl").
    \a name is used in error messages. No file is opened (an OBJ's `mtllib` is not read; materials
    are not used anyway). */
std::vector<MeshNode> loadMeshNodesFromMemory(const void *data, std::size_t size, const std::string &formatHint,
                                              const std::string &name = "<memory>",
                                              ColladaUpAxis upAxis = ColladaUpAxis::Keep);
}  // namespace rastercheck
