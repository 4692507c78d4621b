// MoveIt scene and request YAML: every MotionBenchMaker Panda problem, known answers for one, pose
// composition and shape kinds (malformed files: test_bad_input.cpp).
#include <dirent.h>

#include <algorithm>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/io/MoveItYaml.h"

namespace rc = rastercheck;

namespace
{
std::vector<std::string> listDirectory(const std::string &folder)
{
    std::vector<std::string> names;
    if (DIR *dir = opendir(folder.c_str()))
    {
        while (dirent *entry = readdir(dir))
            if (entry->d_name[0] != '.')
                names.push_back(entry->d_name);
        closedir(dir);
    }
    std::sort(names.begin(), names.end());
    return names;
}
}  // namespace

TEST(MoveItYaml, EveryPandaProblemLoads)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string problems = root + "/mbm/panda/problems";
    std::size_t scenes = 0, requests = 0;
    for (const std::string &scenario : listDirectory(problems))
        for (const std::string &name : listDirectory(problems + "/" + scenario))
        {
            const std::string path = problems + "/" + scenario + "/" + name;
            SCOPED_TRACE(path);
            if (name.rfind("scene", 0) == 0)
            {
                const rc::ScenePtr scene = rc::loadMoveItScene(path);
                EXPECT_GT(scene->numObjects(), 0u);
                for (const rc::SceneObject &object : scene->objects)
                    EXPECT_TRUE(object.topology.closed) << object.name;
                ++scenes;
            }
            else if (name.rfind("request", 0) == 0)
            {
                const rc::MotionPlanRequest request = rc::loadMoveItRequest(path);
                EXPECT_EQ(request.groupName, "panda_arm");
                EXPECT_EQ(request.goalJoints.size(), 7u);
                EXPECT_EQ(request.startJoints.size(), 9u);
                ++requests;
            }
        }
    EXPECT_EQ(scenes, 700u);
    EXPECT_EQ(requests, 700u);
}

TEST(MoveItYaml, BoxPandaSceneAndRequestKnownAnswers)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string folder = root + "/mbm/panda/problems/box_panda/";
    const rc::ScenePtr scene = rc::loadMoveItScene(folder + "scene0001.yaml");
    ASSERT_EQ(scene->numObjects(), 7u);
    const std::vector<std::string> names{"Can1",       "base",      "side_back", "side_cap",
                                         "side_front", "side_left", "side_right"};
    for (std::size_t i = 0; i < names.size(); ++i)
        EXPECT_EQ(scene->objects[i].name, names[i]);
    // Can1: cylinder height 0.14, radius 0.03: 13 sides within 1 mm, 4 triangles per side.
    const rc::SceneObject &can = scene->objects[0];
    EXPECT_EQ(can.mesh.numTriangles(), 52u);
    EXPECT_NEAR(can.bounds.min.z(), -0.3762264457751537 - 0.07, 1e-12);
    EXPECT_NEAR(can.bounds.max.z(), -0.3762264457751537 + 0.07, 1e-12);
    EXPECT_EQ(scene->objects[1].mesh.numTriangles(), 12u);
    EXPECT_EQ(scene->numTriangles(), 52u + 6 * 12u);

    const rc::MotionPlanRequest request = rc::loadMoveItRequest(folder + "request0001.yaml");
    EXPECT_DOUBLE_EQ(request.startJoints.at("panda_joint4"), -2.356);
    EXPECT_DOUBLE_EQ(request.startJoints.at("panda_finger_joint1"), 0.065);
    EXPECT_DOUBLE_EQ(request.goalJoints.at("panda_joint2"), 1.7628);
    EXPECT_DOUBLE_EQ(request.goalJoints.at("panda_joint7"), -0.1898611792470702);
    EXPECT_TRUE(request.goalToleranceAbove.empty());
}

TEST(MoveItYaml, ObjectPoseComposesWithShapePosesAndShapesAreNamed)
{
    // Object pose: 90 degrees about z, then 1 m along x; its box sits 1 m along the object's x.
    const std::string yaml = R"(
world:
  collision_objects:
    - id: shelf
      pose:
        position: {x: 1, y: 0, z: 0}
        orientation: {x: 0, y: 0, z: 0.7071067811865476, w: 0.7071067811865476}
      primitives:
        - type: box
          dimensions: [0.2, 0.4, 0.6]
        - type: 2
          dimensions: [0.5]
      primitive_poses:
        - position: [1, 0, 0]
          orientation: [0, 0, 0, 1]
        - position: [0, 0, 3]
      meshes:
        - vertices: [{x: 0, y: 0, z: 0}, {x: 1, y: 0, z: 0}, {x: 0, y: 1, z: 0}, {x: 0, y: 0, z: 1}]
          triangles: [{vertex_indices: [0, 2, 1]}, {vertex_indices: [0, 1, 3]}, {vertex_indices: [0, 3, 2]},
                      {vertex_indices: [1, 2, 3]}]
      mesh_poses:
        - position: [0, 0, -5]
          orientation: [0, 0, 0, 2]
    - id: cone
      primitives:
        - type: cone
          dimensions: [1.0, 0.25]
      primitive_poses:
        - position: [0, 0, 0]
          orientation: [0, 0, 0, 1]
)";
    const rc::ScenePtr scene = rc::loadMoveItSceneString(yaml, "composed.yaml");
    ASSERT_EQ(scene->numObjects(), 4u);
    EXPECT_EQ(scene->objects[0].name, "shelf/0");
    EXPECT_EQ(scene->objects[1].name, "shelf/1");
    EXPECT_EQ(scene->objects[2].name, "shelf/2");
    EXPECT_EQ(scene->objects[3].name, "cone");
    // The box centre lands at (1, 1, 0) and its 0.2 x 0.4 footprint turns to 0.4 x 0.2.
    const rc::Aabb box = scene->objects[0].bounds;
    EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d(0.8, 0.9, -0.3), 1e-12));
    EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d(1.2, 1.1, 0.3), 1e-12));
    EXPECT_TRUE(scene->objects[1].bounds.center().isApprox(Eigen::Vector3d(1, 0, 3), 1e-9));
    EXPECT_EQ(scene->objects[2].mesh.numTriangles(), 4u);
    EXPECT_TRUE(scene->objects[2].topology.closed);
    EXPECT_NEAR(scene->objects[2].bounds.min.z(), -5.0, 1e-12);
    EXPECT_NEAR(scene->objects[3].bounds.max.z(), 0.5, 1e-12);
}
