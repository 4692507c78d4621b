// URDF loading: every robot of the shared data, the Panda's exact layout and triangle counts, joint
// kinds, mimic chains and package:// resolution (malformed input: test_bad_input.cpp).
#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rc = rastercheck;
using rc::test::expectInputError;
using rc::test::kCubeObj;
using rc::test::makeTempDir;
using rc::test::urdfJoint;
using rc::test::urdfLink;
using rc::test::urdfRobot;
using rc::test::writeFile;

TEST(Urdf, EveryRobotOfTheSharedDataLoads)
{
    RASTERCHECK_REQUIRE_DATA(root);
    struct Expected
    {
        std::string path;
        std::size_t dof;
        std::size_t components;
    };
    const std::vector<Expected> robots{{"mbm/panda/panda.urdf", 7, 11},
                                       {"mbm/ur5/ur5.urdf", 6, 18},
                                       {"mbm/fetch/fetch.urdf", 8, 15},
                                       {"robots/panda/panda.urdf", 8, 11},
                                       {"robots/panda/panda_collision.urdf", 8, 11},
                                       {"robots/ur5/ur5_robot.urdf", 6, 8},
                                       {"robots/ur5/ur5_joint_limited_robot.urdf", 6, 8},
                                       {"robots/iiwa/model.urdf", 7, 8},
                                       {"robots/crane_public/green_crane.urdf", 1, 0},
                                       {"robots/crane_public/simple_green_crane.urdf", 1, 0}};
    rc::test::LogCapture capture;
    for (const Expected &expected : robots)
    {
        SCOPED_TRACE(expected.path);
        const rc::RobotModelPtr model = rc::loadUrdf(root + "/" + expected.path);
        EXPECT_EQ(model->numCoordinates(), expected.dof);
        EXPECT_EQ(model->numComponents(), expected.components);
        for (const rc::Component &component : model->components)
        {
            EXPECT_FALSE(component.mesh.empty());
            EXPECT_FALSE(component.localAabb.empty());
            EXPECT_GT(component.localObb.volume(), 0.0);
        }
    }
}

TEST(Urdf, PandaLayoutLimitsMimicAndTriangleCounts)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::RobotModelPtr panda = rc::RobotModel::fromUrdf(root + "/robots/panda/panda.urdf");
    EXPECT_EQ(panda->name, "panda");
    EXPECT_EQ(panda->links.size(), 13u);
    EXPECT_EQ(panda->joints.size(), 12u);
    // 9 moving joints: 7 arm joints, finger 1, and finger 2 which mimics finger 1 (no coordinate).
    const std::vector<std::string> coordinates{"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                               "panda_joint5", "panda_joint6", "panda_joint7", "panda_finger_joint1"};
    EXPECT_EQ(panda->coordinateNames, coordinates);
    const rc::Joint &finger2 = panda->joints[panda->jointIndex("panda_finger_joint2")];
    EXPECT_EQ(finger2.kind, rc::JointKind::Prismatic);
    ASSERT_GE(finger2.mimicOf, 0);
    EXPECT_EQ(panda->joints[finger2.mimicOf].name, "panda_finger_joint1");
    EXPECT_EQ(finger2.mimicMultiplier, 1.0);
    EXPECT_EQ(finger2.mimicOffset, 0.0);
    EXPECT_EQ(finger2.firstCoordinate, -1);
    const int j4 = panda->coordinateIndex("panda_joint4"), f1 = panda->coordinateIndex("panda_finger_joint1");
    EXPECT_DOUBLE_EQ(panda->lowerBounds[j4], -3.0718);
    EXPECT_DOUBLE_EQ(panda->upperBounds[j4], -0.0698);
    EXPECT_DOUBLE_EQ(panda->lowerBounds[f1], 0.0);
    EXPECT_DOUBLE_EQ(panda->upperBounds[f1], 0.04);

    // Triangles per component as the STL files store them (binary STL facet counts); each finger is
    // four boxes of 12 triangles. All are closed.
    const std::vector<std::pair<std::string, std::size_t>> triangles{
        {"panda_link0", 200}, {"panda_link1", 300},     {"panda_link2", 300},     {"panda_link3", 300},
        {"panda_link4", 300}, {"panda_link5", 300},     {"panda_link6", 200},     {"panda_link7", 200},
        {"panda_hand", 200},  {"panda_leftfinger", 48}, {"panda_rightfinger", 48}};
    ASSERT_EQ(panda->numComponents(), triangles.size());
    for (std::size_t c = 0; c < triangles.size(); ++c)
    {
        EXPECT_EQ(panda->components[c].name, triangles[c].first);
        EXPECT_EQ(panda->components[c].mesh.numTriangles(), triangles[c].second) << triangles[c].first;
        EXPECT_TRUE(panda->components[c].topology.closed) << triangles[c].first;
    }
    EXPECT_EQ(panda->numTriangles(), 2396u);
}

TEST(Urdf, MotionBenchMakerPandaHasSevenJointsAndAnOpenLink6)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::RobotModelPtr panda = rc::loadUrdf(root + "/mbm/panda/panda.urdf");
    EXPECT_EQ(panda->activeJointNames(),
              (std::vector<std::string>{"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4", "panda_joint5",
                                        "panda_joint6", "panda_joint7"}));
    // Fingers are fixed there; the <mimic> on the fixed finger joint 2 is ignored.
    const rc::Joint &finger2 = panda->joints[panda->jointIndex("panda_finger_joint2")];
    EXPECT_EQ(finger2.kind, rc::JointKind::Fixed);
    EXPECT_EQ(finger2.mimicOf, -1);
    EXPECT_DOUBLE_EQ(panda->upperBounds[panda->coordinateIndex("panda_joint6")], 3.8223);
    // OBJ face counts: link0 200, link1-5 300, link6 1308, link7 200, hand 200, finger 32.
    const std::vector<std::pair<std::string, std::size_t>> triangles{
        {"panda_link0", 200}, {"panda_link1", 300},     {"panda_link2", 300},     {"panda_link3", 300},
        {"panda_link4", 300}, {"panda_link5", 300},     {"panda_link6", 1308},    {"panda_link7", 200},
        {"panda_hand", 200},  {"panda_leftfinger", 32}, {"panda_rightfinger", 32}};
    ASSERT_EQ(panda->numComponents(), triangles.size());
    for (std::size_t c = 0; c < triangles.size(); ++c)
    {
        EXPECT_EQ(panda->components[c].name, triangles[c].first);
        EXPECT_EQ(panda->components[c].mesh.numTriangles(), triangles[c].second) << triangles[c].first;
        EXPECT_EQ(panda->components[c].topology.closed, triangles[c].first != "panda_link6") << triangles[c].first;
    }
    EXPECT_GT(panda->components[6].topology.boundaryEdges, 0u);
}

TEST(Urdf, CraneInvertedLimitsAreSwappedAndVisualsCanStandIn)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string path = root + "/robots/crane_public/green_crane.urdf";
    rc::test::LogCapture capture;
    const rc::RobotModelPtr bare = rc::loadUrdf(path);
    EXPECT_TRUE(capture.warned("base_to_crane_boom")) << "the warning names the joint";
    EXPECT_DOUBLE_EQ(bare->lowerBounds[0], -0.6948);
    EXPECT_DOUBLE_EQ(bare->upperBounds[0], 0.3267);
    EXPECT_EQ(bare->numComponents(), 0u);

    rc::UrdfOptions options;
    options.visualWhenNoCollision = true;
    const rc::RobotModelPtr crane = rc::loadUrdf(path, options);
    ASSERT_EQ(crane->numComponents(), 3u);
    EXPECT_EQ(crane->components[0].mesh.numTriangles(), 6444u);  // frame_URDF.STL
    EXPECT_EQ(crane->components[1].mesh.numTriangles(), 1660u);  // boom_URDF.STL
    EXPECT_TRUE(capture.warned("link 'crane_boom' has no collision geometry"));
}

TEST(Urdf, JointKindsCoordinatesAndBounds)
{
    const std::string xml =
        urdfRobot(urdfLink("base") + urdfLink("a") + urdfLink("b") + urdfLink("c") + urdfLink("d") + urdfLink("e") +
              urdfJoint("spin", "continuous", "base", "a", "<axis xyz=\"0 0 2\"/>") +
              urdfJoint("free", "floating", "a", "b") + urdfJoint("slide", "planar", "b", "c", "<axis xyz=\"0 0 1\"/>") +
              urdfJoint("stuck", "revolute", "c", "d",
                       "<axis xyz=\"1 0 0\"/><limit lower=\"0.5\" upper=\"0.5\" effort=\"1\" "
                       "velocity=\"1\"/>") +
              urdfJoint("weld", "fixed", "d", "e", "<origin xyz=\"1 2 3\" rpy=\"0 0 1.5707963267948966\"/>"));
    const rc::RobotModelPtr model = rc::loadUrdfString(xml, ".", {}, "kinds.urdf");
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(model->coordinateNames,
              (std::vector<std::string>{"spin", "free/x", "free/y", "free/z", "free/qx", "free/qy", "free/qz",
                                        "free/qw", "slide/x", "slide/y", "slide/theta", "stuck"}));
    EXPECT_EQ(model->lowerBounds,
              (std::vector<double>{-M_PI, -inf, -inf, -inf, -1, -1, -1, -1, -inf, -inf, -M_PI, 0.5}));
    EXPECT_EQ(model->upperBounds, (std::vector<double>{M_PI, inf, inf, inf, 1, 1, 1, 1, inf, inf, M_PI, 0.5}));
    const rc::Joint &spin = model->joints[model->jointIndex("spin")];
    EXPECT_TRUE(spin.continuous);
    EXPECT_EQ(spin.kind, rc::JointKind::Revolute);
    EXPECT_TRUE(spin.axis.isApprox(Eigen::Vector3d::UnitZ())) << "axis normalised";
    EXPECT_EQ(model->joints[model->jointIndex("free")].kind, rc::JointKind::Floating);
    EXPECT_EQ(model->joints[model->jointIndex("slide")].kind, rc::JointKind::Planar);
    const rc::Joint &weld = model->joints[model->jointIndex("weld")];
    EXPECT_TRUE(weld.origin.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
    EXPECT_TRUE((weld.origin.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(Urdf, MimicChainsResolveToTheSourceJoint)
{
    const std::string limit = "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";
    const std::string xml = urdfRobot(
        urdfLink("base") + urdfLink("a") + urdfLink("b") + urdfLink("c") + urdfJoint("j0", "revolute", "base", "a", limit) +
        urdfJoint("j1", "revolute", "a", "b", limit + "<mimic joint=\"j0\" multiplier=\"2\" offset=\"0.5\"/>") +
        urdfJoint("j2", "revolute", "b", "c", limit + "<mimic joint=\"j1\" multiplier=\"3\" offset=\"0.25\"/>"));
    const rc::RobotModelPtr model = rc::loadUrdfString(xml, ".", {}, "mimic.urdf");
    EXPECT_EQ(model->coordinateNames, std::vector<std::string>{"j0"});
    const rc::Joint &j2 = model->joints[model->jointIndex("j2")];
    ASSERT_EQ(j2.mimicOf, model->jointIndex("j0"));
    // j2 = 3 (2 j0 + 0.5) + 0.25 = 6 j0 + 1.75.
    EXPECT_DOUBLE_EQ(j2.mimicMultiplier, 6.0);
    EXPECT_DOUBLE_EQ(j2.mimicOffset, 1.75);
    const rc::Joint &j1 = model->joints[model->jointIndex("j1")];
    EXPECT_DOUBLE_EQ(j1.mimicMultiplier, 2.0);
    EXPECT_DOUBLE_EQ(j1.mimicOffset, 0.5);
}

TEST(Urdf, CollisionElementsMergeWithOriginsScaleAndPackagePaths)
{
    const std::string folder = makeTempDir("urdf");
    const std::string packages = folder + "/share";
    ASSERT_EQ(std::system(("mkdir -p " + packages + "/my_robot/meshes " + folder + "/robot").c_str()), 0);
    writeFile(packages + "/my_robot/meshes/cube.obj", kCubeObj);
    const std::string collisions =
        "<collision><origin xyz=\"0 0 1\"/><geometry><box size=\"1 1 1\"/></geometry></collision>"
        "<collision><origin xyz=\"0 0 -1\"/><geometry>"
        "<mesh filename=\"package://my_robot/meshes/cube.obj\" scale=\"2 -1 1\"/></geometry></collision>";
    const std::string path = writeFile(folder + "/robot/r.urdf", urdfRobot(urdfLink("base", collisions)));
    rc::UrdfOptions options;
    options.packagePaths = {packages};
    const rc::RobotModelPtr model = rc::loadUrdf(path, options);
    ASSERT_EQ(model->numComponents(), 1u);
    const rc::Component &body = model->components[0];
    EXPECT_EQ(body.mesh.numTriangles(), 24u);
    EXPECT_TRUE(body.topology.closed) << "mirrored mesh stays outward";
    EXPECT_TRUE(body.localAabb.min.isApprox(Eigen::Vector3d(-1, -0.5, -1.5)));
    EXPECT_TRUE(body.localAabb.max.isApprox(Eigen::Vector3d(1, 0.5, 1.5)));

    // Without the package path the URDF's own folder and its parents are searched: not found here.
    expectInputError([&] { rc::loadUrdf(path); }, path,
                     "link 'base' collision mesh 'package://my_robot/meshes/cube.obj'", "file not found");
    // The environment variable adds folders too.
    setenv("RASTERCHECK_PACKAGE_PATH", ("/nonexistent:" + packages).c_str(), 1);
    EXPECT_EQ(rc::loadUrdf(path)->numComponents(), 1u);
    unsetenv("RASTERCHECK_PACKAGE_PATH");
}

TEST(Urdf, AnOpenMeshIsReportedOncePerFileAndProcess)
{
    // A cube with one face missing is open; a program that loads the same robot three times (a
    // checker, a planner's setup, a picture) reads the notice once. Another file says it again.
    const std::string folder = makeTempDir("urdf");
    const std::string cube = kCubeObj;
    writeFile(folder + "/open.obj", cube.substr(0, cube.rfind("\nf ") + 1));
    const std::string robot = urdfRobot(urdfLink("a", rc::test::urdfCollisionMesh("open.obj")));
    const std::string first = writeFile(folder + "/first.urdf", robot);
    const std::string second = writeFile(folder + "/second.urdf", robot);
    rc::test::LogCapture log;
    for (int k = 0; k < 3; ++k)
        EXPECT_FALSE(rc::loadUrdf(first)->components[0].topology.closed);
    ASSERT_EQ(log.notices.size(), 1u) << ::testing::PrintToString(log.notices);
    EXPECT_NE(log.notices[0].find(first + ": link 'a' collision geometry is open"), std::string::npos) << log.notices[0];
    rc::loadUrdf(second);
    ASSERT_EQ(log.notices.size(), 2u);
    EXPECT_NE(log.notices[1].find(second + ": link 'a'"), std::string::npos) << log.notices[1];
}
