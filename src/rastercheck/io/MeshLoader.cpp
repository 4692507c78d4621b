#include "rastercheck/io/MeshLoader.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <utility>

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/MemoryIOWrapper.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/core/Text.h"
#include "rastercheck/io/PlyCheck.h"

namespace rastercheck
{
namespace
{
// Files are read without post-processing, checked (checkAndPostProcess), then post-processed.
// assimp's importers can return face indices past the vertices or faces without
// vertices on malformed input (a PLY, found by fuzz_mesh), which crashed the later steps and would be
// copied into our meshes. assimp's own ValidateDataStructure would catch them too, but it also
// rejects what the post-processing repairs (a truncated OBJ's last face read as a line, a file of
// points only) with messages that do not say what is wrong for us.
constexpr unsigned int kReadFlags = 0;
// Our meshes: one vertex per distinct corner of a file without normals, and assimp's node structure
// kept (one scene object per node).
constexpr unsigned int kPostProcessFlags =
    aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType;
// OMPL.app's RigidBodyGeometry::addRobotMesh and addEnvironmentMesh.
constexpr unsigned int kOmplAppFlags = aiProcess_GenNormals | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_SortByPType | aiProcess_OptimizeGraph;

void configure(Assimp::Importer &importer, ColladaUpAxis upAxis)
{
    importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, upAxis == ColladaUpAxis::Keep);
}

// ---- what assimp may open ----------------------------------------------------------------------
// assimp 5.2.5's OBJ material-library parser dereferences a null material on a texture line before
// any `newmtl` (found by fuzz_mesh: for bytes in memory, the fallback "<name>.mtl" assimp tries when
// `mtllib` cannot be opened is served from the OBJ's own bytes). Only geometry is used here, and an
// OBJ read without its .mtl has the same meshes (assimp makes a material per `usemtl` name), so .mtl
// files are never opened.
bool isMaterialLibrary(const char *file)
{
    const std::string name(file ? file : "");
    if (name.size() < 4)
        return false;
    return lowerCase(name.substr(name.size() - 4)) == ".mtl";
}

// Mesh files: the file system, without material libraries.
class GeometryFiles : public Assimp::DefaultIOSystem
{
public:
    bool Exists(const char *file) const override { return !isMaterialLibrary(file) && DefaultIOSystem::Exists(file); }
    Assimp::IOStream *Open(const char *file, const char *mode) override
    {
        return isMaterialLibrary(file) ? nullptr : DefaultIOSystem::Open(file, mode);
    }
};

// Bytes in memory as the only file there is (assimp's own ReadFileFromMemory falls back to the file
// system, and serves its magic name's .mtl from the same bytes): nothing else is opened.
class MemoryFile : public Assimp::IOSystem
{
public:
    MemoryFile(std::string name, const void *data, std::size_t size)
        : name_(std::move(name)), data_(static_cast<const std::uint8_t *>(data)), size_(size)
    {
    }
    bool Exists(const char *file) const override { return file && name_ == file; }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream *Open(const char *file, const char *) override
    {
        return Exists(file) ? new Assimp::MemoryIOStream(data_, size_) : nullptr;
    }
    void Close(Assimp::IOStream *stream) override { delete stream; }

private:
    std::string name_;
    const std::uint8_t *data_;
    std::size_t size_;
};

// The PLY importer is assimp's choice when the extension (or memory hint) says ply, or when no
// importer claims the extension and assimp goes by content.
bool plyImporterMayRun(const Assimp::Importer &importer, const std::string &written)
{
    const std::string extension = lowerCase(written);
    return extension == "ply" || !importer.IsExtensionSupported("." + extension);
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
                result.mesh.vertices.push_back((transform * local.homogeneous()).head<3>());
            }
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

// A face without indices passes assimp's validation but makes its Triangulate step abort on an
// assertion (Debian builds assimp with them; found by fuzz_mesh with a PLY face list of count 0).
// Valid files have none, so such a scene is rejected before post-processing.
const aiScene *checkAndPostProcess(Assimp::Importer &importer, const aiScene *scene, const std::string &name,
                                   unsigned int postProcessFlags)
{
    if (!scene)
        return nullptr;  // extract reports assimp's error
    for (unsigned int m = 0; m < scene->mNumMeshes; ++m)
    {
        const aiMesh *mesh = scene->mMeshes[m];
        for (unsigned int f = 0; f < mesh->mNumFaces; ++f)
        {
            const aiFace &face = mesh->mFaces[f];
            if (face.mNumIndices == 0 || !face.mIndices)
                throw InputError(name, "mesh '" + std::string(mesh->mName.C_Str()) + "'",
                                 "face " + std::to_string(f) + " has no vertices");
            for (unsigned int k = 0; k < face.mNumIndices; ++k)
                if (face.mIndices[k] >= mesh->mNumVertices)
                    throw InputError(name, "mesh '" + std::string(mesh->mName.C_Str()) + "'",
                                     "face " + std::to_string(f) + " names vertex " + std::to_string(face.mIndices[k]) +
                                         " of " + std::to_string(mesh->mNumVertices));
        }
    }
    return importer.ApplyPostProcessing(postProcessFlags);
}

void requireScene(const aiScene *scene, const Assimp::Importer &importer, const std::string &name)
{
    if (!scene || !scene->mRootNode)
        throw InputError(name, "", std::string("cannot read mesh: ") + importer.GetErrorString());
}

std::vector<MeshNode> extract(const aiScene *scene, const Assimp::Importer &importer, const std::string &name)
{
    requireScene(scene, importer, name);
    std::vector<MeshNode> nodes;
    collect(scene, scene->mRootNode, Eigen::Matrix4d::Identity(), name, nodes);
    std::size_t triangles = 0;
    for (const MeshNode &node : nodes)
        triangles += node.mesh.numTriangles();
    if (triangles == 0)
        throw InputError(name, "", "mesh has no triangles");
    return nodes;
}

// OMPL.app's scene::extractVerticesAux, in its types: assimp's float matrices and vectors. Counts the
// triangles it passes too.
void collectOmplApp(const aiScene *scene, const aiNode *node, aiMatrix4x4 transform, const std::string &name,
                    std::vector<aiVector3D> &out, std::size_t &triangles)
{
    transform *= node->mTransformation;
    for (unsigned int m = 0; m < node->mNumMeshes; ++m)
    {
        const aiMesh *mesh = scene->mMeshes[node->mMeshes[m]];
        for (unsigned int v = 0; v < mesh->mNumVertices; ++v)
        {
            const aiVector3D placed = transform * mesh->mVertices[v];
            if (!std::isfinite(placed.x) || !std::isfinite(placed.y) || !std::isfinite(placed.z))
                throw InputError(name, "node '" + std::string(node->mName.C_Str()) + "'",
                                 "vertex coordinate is not a finite number");
            out.push_back(placed);
        }
        for (unsigned int f = 0; f < mesh->mNumFaces; ++f)
            triangles += mesh->mFaces[f].mNumIndices == 3 ? 1 : 0;
    }
    for (unsigned int c = 0; c < node->mNumChildren; ++c)
        collectOmplApp(scene, node->mChildren[c], transform, name, out, triangles);
}

// A mesh file read, checked and post-processed with \a postProcessFlags (scene owned by \a importer).
const aiScene *readFile(Assimp::Importer &importer, const std::string &path, ColladaUpAxis upAxis,
                        unsigned int postProcessFlags)
{
    if (!isFile(path))
        throw InputError(path, "", "file not found");
    configure(importer, upAxis);
    importer.SetIOHandler(new GeometryFiles);  // the importer owns it
    if (plyImporterMayRun(importer, extensionOf(path)))
    {
        // assimp's PLY reader needs the whole file checked first (io/PlyCheck.h).
        std::ifstream in(path, std::ios::binary);
        std::string start(4096, '\0');
        in.read(start.data(), static_cast<std::streamsize>(start.size()));
        if (detail::looksLikePly(start.data(), static_cast<std::size_t>(in.gcount())))
        {
            std::ostringstream whole;
            whole << std::ifstream(path, std::ios::binary).rdbuf();
            const std::string bytes = whole.str();
            detail::checkPly(bytes.data(), bytes.size(), path);
        }
    }
    return checkAndPostProcess(importer, importer.ReadFile(path, kReadFlags), path, postProcessFlags);
}
}  // namespace

std::vector<MeshNode> loadMeshNodes(const std::string &path, ColladaUpAxis upAxis)
{
    Assimp::Importer importer;
    const aiScene *scene = readFile(importer, path, upAxis, kPostProcessFlags);
    return extract(scene, importer, path);
}

OmplAppVertices loadOmplAppVertices(const std::string &path)
{
    Assimp::Importer importer;
    const aiScene *scene = readFile(importer, path, ColladaUpAxis::ConvertToYUp, kOmplAppFlags);
    requireScene(scene, importer, path);
    std::vector<aiVector3D> vertices;
    std::size_t triangles = 0;
    collectOmplApp(scene, scene->mRootNode, aiMatrix4x4(), path, vertices, triangles);
    if (triangles == 0)
        throw InputError(path, "", "mesh has no triangles");

    // scene::sceneCenter: a float sum in node order, divided by the count as a float.
    aiVector3D center(0, 0, 0);
    for (const aiVector3D &vertex : vertices)
        center += vertex;
    center /= static_cast<float>(vertices.size());
    OmplAppVertices result;
    result.vertices.reserve(vertices.size());
    for (const aiVector3D &vertex : vertices)
        result.vertices.emplace_back(vertex.x, vertex.y, vertex.z);
    result.center = Eigen::Vector3d(center.x, center.y, center.z);
    return result;
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
    const char *bytes = static_cast<const char *>(data);
    if (plyImporterMayRun(importer, formatHint) && detail::looksLikePly(bytes, size))
        detail::checkPly(bytes, size, name);  // assimp's PLY reader is unsafe on malformed files
    // The hint is the file's extension, by which assimp picks the importer.
    const std::string file = formatHint.empty() ? "memory" : "memory." + formatHint;
    importer.SetIOHandler(new MemoryFile(file, data, size));  // the importer owns it
    const aiScene *scene = checkAndPostProcess(importer, importer.ReadFile(file, kReadFlags), name, kPostProcessFlags);
    return extract(scene, importer, name);
}
}  // namespace rastercheck
