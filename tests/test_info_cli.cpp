// `rastercheck info` end to end: the binary's output for a robot, a scene, a request and a problem,
// and its error format and exit status.
#include <sys/wait.h>

#include <cstdio>

#include <gtest/gtest.h>

#include "TestSupport.h"

namespace
{
using CliRun = rastercheck::test::CommandRun;
using rastercheck::test::runCli;

bool contains(const std::string &text, const std::string &part)
{
    return text.find(part) != std::string::npos;
}
}  // namespace

TEST(InfoCli, RobotWithSrdf)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const CliRun run = runCli("info " + root + "/robots/panda/panda.urdf --srdf " + root + "/robots/panda/panda.srdf");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "robot 'panda': 13 links, 12 joints, dof 8, 11 components (2396 triangles)"))
        << run.output;
    EXPECT_TRUE(
        contains(run.output, "panda_joint4  revolute  panda_link3 -> panda_link4  panda_joint4 [-3.0718, -0.0698]"))
        << run.output;
    EXPECT_TRUE(contains(run.output,
                         "panda_finger_joint2  prismatic  panda_hand -> panda_rightfinger  mimic "
                         "panda_finger_joint1 * 1 + 0"))
        << run.output;
    EXPECT_TRUE(contains(run.output, "dof: 8")) << run.output;
    EXPECT_TRUE(contains(run.output, "  panda_link1: 300 triangles, closed")) << run.output;
    EXPECT_TRUE(contains(run.output, "closed components: 11 of 11")) << run.output;
    EXPECT_TRUE(contains(run.output, "allowed collision pairs: 35 of 55")) << run.output;
}

TEST(InfoCli, CraneWithVisualFallback)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const CliRun run = runCli("info " + root + "/robots/crane_public/green_crane.urdf --visual-fallback");
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "warning:")) << run.output;
    EXPECT_TRUE(contains(run.output, "base_to_crane_boom [-0.6948, 0.3267]")) << run.output;
    EXPECT_TRUE(contains(run.output, "crane_boom: 1660 triangles, closed")) << run.output;
}

TEST(InfoCli, SceneAndRequest)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string folder = root + "/mbm/panda/problems/box_panda/";
    const CliRun scene = runCli("info " + folder + "scene0001.yaml");
    ASSERT_EQ(scene.status, 0) << scene.output;
    EXPECT_TRUE(contains(scene.output, "scene: 7 objects, 124 triangles")) << scene.output;
    EXPECT_TRUE(contains(scene.output, "  Can1: 52 triangles, closed, bounds (")) << scene.output;
    EXPECT_TRUE(contains(scene.output, "closed objects: 7 of 7")) << scene.output;
    EXPECT_TRUE(contains(scene.output, "bounds: (")) << scene.output;
    const CliRun request = runCli("info " + folder + "request0001.yaml");
    ASSERT_EQ(request.status, 0) << request.output;
    EXPECT_TRUE(contains(request.output, "request: group 'panda_arm'")) << request.output;
    EXPECT_TRUE(contains(request.output, "panda_joint2=1.7628")) << request.output;
}

TEST(InfoCli, OmplAppProblem)
{
    const std::string folder = rastercheck::test::makeTempDir("cli");
    rastercheck::test::writeFile(folder + "/robot.obj",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const std::string cfg = rastercheck::test::writeFile(folder + "/p.cfg", R"([problem]
name = tiny
robot = robot.obj
start.x = 0
start.y = 0
start.theta = 0
goal.x = 1
goal.y = 1
goal.theta = 0
volume.min.x = -5
volume.min.y = -5
volume.max.x = 5
volume.max.y = 5
[planner]
rrtconnect=
)");
    const CliRun run = runCli("info " + cfg);
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "problem 'tiny': SE(2)")) << run.output;
    EXPECT_TRUE(contains(run.output, "coordinates: x y yaw")) << run.output;
    EXPECT_TRUE(contains(run.output, "planners: rrtconnect")) << run.output;
    EXPECT_TRUE(contains(run.output, "scene: 0 objects")) << run.output;
}

TEST(InfoCli, ErrorsArePrefixedAndExitWithOne)
{
    const std::string folder = rastercheck::test::makeTempDir("cli");
    const std::string bad = rastercheck::test::writeFile(
        folder + "/bad.urdf",
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"ball\"><parent link=\"a\"/>"
        "<child link=\"b\"/></joint></robot>");
    const CliRun run = runCli("info " + bad);
    EXPECT_EQ(run.status, 1);
    EXPECT_TRUE(contains(run.output, "rastercheck: error: " + bad + ": joint 'j': unknown joint type 'ball'"))
        << run.output;

    const CliRun missing = runCli("info " + folder + "/absent.urdf");
    EXPECT_EQ(missing.status, 1);
    EXPECT_TRUE(contains(missing.output, "rastercheck: error: " + folder + "/absent.urdf: file not found"))
        << missing.output;

    const CliRun unknown = runCli("info " + folder + "/thing.txt");
    EXPECT_EQ(unknown.status, 1);
    EXPECT_TRUE(contains(unknown.output, "rastercheck: error: cannot tell what")) << unknown.output;

    const CliRun srdfOnScene = runCli("info " + folder + "/x.yaml --srdf y.srdf");
    EXPECT_EQ(srdfOnScene.status, 1);
    EXPECT_TRUE(contains(srdfOnScene.output, "apply to URDF files only")) << srdfOnScene.output;
}
