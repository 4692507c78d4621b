#include "rastercheck/io/MeshLoader.h"

#include <cmath>
#include <sys/stat.h>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "rastercheck/core/Error.h"

namespace rastercheck
{
namespace
{
constexpr unsigned int kImportFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType;

void configure(Assimp::Importer &importer, ColladaUpAxis upAxis)
{
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, upAxis == ColladaUpAxis::Keep);
}

Eigen::Matrix4d toEigen(const aiMatrix4x4 &m)
{
    Eigen::Matrix4d out;
    out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
    return out;
}

void collect(const aiScene *scene, const aiNode *node, const Eigen::Matrix4d &parent, const std::string &name,
             std::vector<MeshNode> &out)
{
    const Eigen::Matrix4d transform = parent * toEigen(node->mTransformation);
    if (node->mNumMeshes > 0)
    {
        MeshNode result;
        result.name = node->mName.C_Str();
        for (unsigned int m = 0; m < node->mNumMeshes; ++m)
        {
            const aiMesh *mesh = scene->mMeshes[node->mMeshes[m]];
            const auto offset = static_cast<std::uint32_t>(result.mesh.vertices.size());
            for (unsigned int v = 0; v < mesh->mNumVertices; ++v)
            {
                const aiVector3D &p = mesh->mVertices[v];
                const Eigen::Vector3d local(p.x, p.y, p.z);
                if (!local.allFinite())
                    throw InputError(name, "node '" + result.name + "'", "vertex coordinate is not a finite number");
                const Eigen::Vector3d placed = (transform * local.homogeneous()).head<3>();
                result.mesh.vertices.push_back(placed);
                result.vertexSum += placed;
            }
            result.vertexCount += mesh->mNumVertices;
            for (unsigned int f = 0; f < mesh->mNumFaces; ++f)
            {
                const aiFace &face = mesh->mFaces[f];
                if (face.mNumIndices != 3)
                    continue;
                result.mesh.triangles.push_back(
                    {offset + face.mIndices[0], offset + face.mIndices[1], offset + face.mIndices[2]});
            }
        }
        out.push_back(std::move(result));
    }
    for (unsigned int c = 0; c < node->mNumChildren; ++c)
        collect(scene, node->mChildren[c], transform, name, out);
}

std::vector<MeshNode> extract(const aiScene *scene, const Assimp::Importer &importer, const std::string &name)
{
    if (!scene || !scene->mRootNode)
        throw InputError(name, "", std::string("cannot read mesh: ") + importer.GetErrorString());
    std::vector<MeshNode> nodes;
    collect(scene, scene->mRootNode, Eigen::Matrix4d::Identity(), name, nodes);
    std::size_t triangles = 0;
    for (const MeshNode &node : nodes)
        triangles += node.mesh.numTriangles();
    if (triangles == 0)
        throw InputError(name, "", "mesh has no triangles");
    return nodes;
}
}  // namespace

std::vector<MeshNode> loadMeshNodes(const std::string &path, ColladaUpAxis upAxis)
{
    struct stat info;
    if (stat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode))
        throw InputError(path, "", "file not found");
    Assimp::Importer importer;
    configure(importer, upAxis);
    const aiScene *scene = importer.ReadFile(path, kImportFlags);
    return extract(scene, importer, path);
}

Mesh loadMesh(const std::string &path, ColladaUpAxis upAxis)
{
    Mesh merged;
    for (const MeshNode &node : loadMeshNodes(path, upAxis))
        merged.append(node.mesh);
    return merged;
}

std::vector<MeshNode> loadMeshNodesFromMemory(const void *data, std::size_t size, const std::string &formatHint,
                                              const std::string &name, ColladaUpAxis upAxis)
{
    if (!data || size == 0)
        throw InputError(name, "", "mesh data is empty");
    Assimp::Importer importer;
    configure(importer, upAxis);
    const aiScene *scene = importer.ReadFileFromMemory(data, size, kImportFlags, formatHint.c_str());
    return extract(scene, importer, name);
}
}  // namespace rastercheck
