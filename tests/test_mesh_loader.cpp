// Mesh files through assimp: node transforms, COLLADA units and up axis, non-triangle primitives,
// and in-memory input (unreadable and empty files: test_bad_input.cpp).
#include <cstring>
#include <fstream>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MeshLoader.h"

namespace rc = rastercheck;
using rc::test::makeTempDir;
using rc::test::writeFile;

namespace
{
// A triangle and a line in centimetres, Z up, placed by its node 10 cm along x.
const char *kCollada = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri">
      <mesh>
        <source id="tri-pos">
          <float_array id="tri-pos-array" count="12">0 0 0 1 0 0 0 1 0 5 5 5</float_array>
          <technique_common><accessor source="#tri-pos-array" count="4" stride="3">
            <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
        <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
        <lines count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 3</p></lines>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene">
      <node id="moved" name="moved">
        <matrix>1 0 0 10 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
        <instance_geometry url="#tri"/>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
)";

const char *kTetrahedronObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// Binary STL of the same tetrahedron (80-byte header, count, 50 bytes per facet).
std::string tetrahedronStl()
{
    const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    std::string bytes(80, ' ');
    const std::uint32_t count = 4;
    bytes.append(reinterpret_cast<const char *>(&count), 4);
    for (const auto &f : faces)
    {
        const float normal[3] = {0, 0, 0};
        bytes.append(reinterpret_cast<const char *>(normal), 12);
        for (int k = 0; k < 3; ++k)
            bytes.append(reinterpret_cast<const char *>(v[f[k]]), 12);
        bytes.append(2, '\0');
    }
    return bytes;
}
}  // namespace

TEST(MeshLoader, ColladaNodeTransformUnitAndUpAxis)
{
    const std::string dae = writeFile(makeTempDir("mesh") + "/tri.dae", kCollada);
    const std::vector<rc::MeshNode> kept = rc::loadMeshNodes(dae);
    ASSERT_EQ(kept.size(), 1u);
    EXPECT_EQ(kept[0].name, "moved");
    ASSERT_EQ(kept[0].mesh.numTriangles(), 1u) << "the <lines> primitive is dropped";
    const rc::Aabb box = kept[0].mesh.bounds();
    // Centimetres to metres, node offset 10 cm, Z_UP kept (ROS convention).
    EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d(0.10, 0.0, 0.0), 1e-6));
    EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d(0.11, 0.01, 0.0), 1e-6));

    // assimp's default turns Z up into Y up: (x, y, z) -> (x, z, -y).
    const rc::Mesh converted = rc::loadMesh(dae, rc::ColladaUpAxis::ConvertToYUp);
    const rc::Aabb turned = converted.bounds();
    EXPECT_TRUE(turned.min.isApprox(Eigen::Vector3d(0.10, 0.0, -0.01), 1e-6));
    EXPECT_TRUE(turned.max.isApprox(Eigen::Vector3d(0.11, 0.0, 0.0), 1e-6));

    // OMPL.app's vertices: turned Y up, placed by the node, the line's included (its centre and
    // bounds count them), the triangle's three corners once each (one face normal).
    const rc::OmplAppVertices omplApp = rc::loadOmplAppVertices(dae);
    ASSERT_EQ(omplApp.vertices.size(), 5u);
    rc::Aabb all;
    for (const Eigen::Vector3d &vertex : omplApp.vertices)
        all.extend(vertex);
    EXPECT_TRUE(all.min.isApprox(Eigen::Vector3d(0.10, 0.0, -0.05), 1e-6));
    EXPECT_TRUE(all.max.isApprox(Eigen::Vector3d(0.15, 0.05, 0.0), 1e-6));
    EXPECT_TRUE(omplApp.center.isApprox(Eigen::Vector3d(0.56, 0.05, -0.06) / 5, 1e-6));
}

TEST(MeshLoader, StlObjAndMemoryGiveTheSameTetrahedron)
{
    const std::string folder = makeTempDir("mesh");
    const std::string stl = tetrahedronStl();
    const rc::Mesh fromStl = rc::loadMesh(writeFile(folder + "/tet.stl", stl));
    const rc::Mesh fromObj = rc::loadMesh(writeFile(folder + "/tet.obj", kTetrahedronObj));
    const std::vector<rc::MeshNode> fromMemory = rc::loadMeshNodesFromMemory(stl.data(), stl.size(), "stl", "tet");
    for (const rc::Mesh *mesh : {&fromStl, &fromObj, &fromMemory.at(0).mesh})
    {
        EXPECT_EQ(mesh->numTriangles(), 4u);
        EXPECT_TRUE(mesh->bounds().max.isApprox(Eigen::Vector3d(1, 1, 1)));
        EXPECT_TRUE(mesh->bounds().min.isApprox(Eigen::Vector3d(0, 0, 0)));
    }
}

// assimp's PLY importer hangs without end_header and allocates the declared element counts before
// reading (fuzz_mesh found both); files go through the same header check as bytes in memory.
TEST(MeshLoader, PlyHeaderIsCheckedBeforeAssimpReadsTheFile)
{
    const std::string folder = makeTempDir("mesh");
    const std::string good = writeFile(folder + "/tet.ply",
                                       "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                       "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                                       "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    EXPECT_EQ(rc::loadMesh(good).numTriangles(), 4u);
    // No extension assimp knows: it goes by content, so the check applies too.
    for (const char *name : {"/open.ply", "/open.notamesh"})
    {
        const std::string open =
            writeFile(folder + name, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
        try
        {
            rc::loadMesh(open);
            ADD_FAILURE() << "expected an InputError for " << open;
        }
        catch (const rc::InputError &e)
        {
            EXPECT_EQ(e.file(), open);
            EXPECT_EQ(e.element(), "PLY header");
        }
    }
    const std::string huge = writeFile(folder + "/huge.ply",
                                       "ply\nformat binary_little_endian 1.0\n"
                                       "element vertex 400000000\nproperty float x\nend_header\n");
    try
    {
        rc::loadMesh(huge);
        ADD_FAILURE() << "expected an InputError for " << huge;
    }
    catch (const rc::InputError &e)
    {
        EXPECT_EQ(e.element(), "PLY element 'vertex'");
        EXPECT_NE(std::string(e.what()).find("declares 400000000 instances"), std::string::npos) << e.what();
    }
}

// assimp's MTL parser crashes on a texture line before any `newmtl` (fuzz_mesh); material libraries
// are never opened, and the OBJ's meshes are the same without them.
TEST(MeshLoader, ObjMaterialLibraryIsNotOpened)
{
    const std::string folder = makeTempDir("mesh");
    writeFile(folder + "/bad.mtl", "map_Kd texture.png\n");
    const std::string obj = writeFile(folder + "/two.obj",
                                      "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                      "usemtl red\nf 1 2 3\nusemtl blue\nf 2 4 3\n");
    const std::vector<rc::MeshNode> nodes = rc::loadMeshNodes(obj);
    ASSERT_EQ(nodes.size(), 1u);
    EXPECT_EQ(nodes[0].mesh.numTriangles(), 2u);
    EXPECT_EQ(nodes[0].mesh.numVertices(), 6u);  // one mesh per usemtl name, as with the library
}
