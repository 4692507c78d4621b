// The bad-input matrix (docs/bad-input.md): one test per row, named as in the table's test column.
// Each asserts what a user sees: an InputError naming the file and the element, a
// ConfigurationError for a malformed call, or the documented fallback with its warning and a
// verdict checked against the exact oracle. BadInputTable keeps the table and this file one to one.
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/SE3StateSpace.h>
#include <ompl/base/spaces/SO2StateSpace.h>

#include "BlindSpots.h"
#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/MeshLoader.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/StatesCsv.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/RigidBody.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;
using rc::test::expectInputError;
using rc::test::kCubeObj;
using rc::test::LogCapture;
using rc::test::makeTempDir;
using rc::test::urdfCollisionMesh;
using rc::test::urdfJoint;
using rc::test::urdfLink;
using rc::test::urdfRobot;
using rc::test::writeFile;

namespace
{
const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
const rc::CollisionMode kModes[] = {rc::CollisionMode::Safe, rc::CollisionMode::Raster, rc::CollisionMode::Exact};

std::string limit(double lower, double upper)
{
    std::ostringstream text;
    text << "<limit lower=\"" << lower << "\" upper=\"" << upper << "\" effort=\"1\" velocity=\"1\"/>";
    return text.str();
}

std::string collisionBox(const std::string &size, const std::string &xyz = "0 0 0")
{
    return "<collision><origin xyz=\"" + xyz + "\"/><geometry><box size=\"" + size + "\"/></geometry></collision>";
}

// Writes \a text as \a name in a fresh folder and returns its path.
std::string fileWith(const std::string &name, const std::string &text)
{
    return writeFile(makeTempDir("bad") + "/" + name, text);
}

rc::Mesh boxAt(const Eigen::Vector3d &size, const Eigen::Vector3d &center)
{
    rc::Mesh mesh = rc::makeBox(size);
    mesh.transform(Eigen::Isometry3d(Eigen::Translation3d(center)));
    return mesh;
}

// A free-flying 0.2 m cube in [-5, 5]^3 over a 1 x 1 x 0.1 table whose top is z = 0.
rc::RobotModelConstPtr flyingCube()
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d::Constant(-5);
    bounds.max = Eigen::Vector3d::Constant(5);
    return rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d::Constant(0.2)), bounds);
}

rc::SceneConstPtr tableScene()
{
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("table", boxAt({1.0, 1.0, 0.1}, {0, 0, -0.05}));
    return scene;
}

std::vector<double> at(double x, double y, double z)
{
    return {x, y, z, 0, 0, 0, 1};
}

// base (0.1 m cube) -j1-> middle (5 cm cube) -j2-> tip (0.1 m cube 0.6 m out): folding j2 by pi
// lands the tip on the base, a pair that is not adjacent. \a placement: origin of the base.
std::string foldingArm(const std::string &placement = "0 0 0", const std::string &rootJoint = "fixed")
{
    return urdfRobot(
        urdfLink("world") + urdfLink("base", collisionBox("0.1 0.1 0.1")) +
        urdfLink("middle", collisionBox("0.05 0.05 0.05")) + urdfLink("tip", collisionBox("0.1 0.1 0.1", "0.6 0 0")) +
        urdfJoint("mount", rootJoint, "world", "base", "<origin xyz=\"" + placement + "\"/>") +
        urdfJoint("j1", "revolute", "base", "middle", "<origin xyz=\"0.3 0 0\"/><axis xyz=\"0 0 1\"/>" + limit(-4, 4)) +
        urdfJoint("j2", "revolute", "middle", "tip", "<origin xyz=\"0.3 0 0\"/><axis xyz=\"0 0 1\"/>" + limit(-4, 4)));
}

// A valid MoveIt scene with one box, "crate", 1 m, at the origin.
const char *kCrateScene =
    "world:\n"
    "  collision_objects:\n"
    "    - id: crate\n"
    "      primitives: [{type: box, dimensions: [1, 1, 1]}]\n"
    "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n";

// One collision object "thing" whose shapes the test appends.
const std::string kThing = "world:\n  collision_objects:\n    - id: thing\n";

// An OMPL.app problem: a unit cube flying over a unit cube, files robot.obj and world.obj.
const char *kCfg =
    "[problem]\n"
    "name = cubes\n"
    "robot = robot.obj\n"
    "world = world.obj\n"
    "start.x = 0\nstart.y = 0\nstart.z = 3\n"
    "start.theta = 0\nstart.axis.x = 1\nstart.axis.y = 0\nstart.axis.z = 0\n"
    "goal.x = 3\ngoal.y = 0\ngoal.z = 3\n"
    "goal.theta = 0\ngoal.axis.x = 1\ngoal.axis.y = 0\ngoal.axis.z = 0\n"
    "volume.min.x = -5\nvolume.min.y = -5\nvolume.min.z = -5\n"
    "volume.max.x = 5\nvolume.max.y = 5\nvolume.max.z = 5\n"
    "[benchmark]\n"
    "time_limit = 1\n";

// Writes kCfg with \a line replaced by \a replacement (and its meshes) and expects the InputError.
void expectCfgError(const std::string &line, const std::string &replacement, const std::string &element,
                    const std::string &what)
{
    std::string text = kCfg;
    const std::size_t found = text.find(line);
    ASSERT_NE(found, std::string::npos) << line;
    text.replace(found, line.size(), replacement);
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/robot.obj", kCubeObj);
    writeFile(folder + "/world.obj", kCubeObj);
    writeFile(folder + "/empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    const std::string path = writeFile(folder + "/problem.cfg", text);
    expectInputError([&] { rc::loadOmplAppProblem(path); }, path, element, what);
}

// Every mode against the exact oracle: safe and exact must agree on every state, raster may miss
// (its documented blind spots, unless \a rasterMisses is false) but never reports a free state as
// colliding. Returns the number of colliding states.
std::size_t expectModesMatchTheOracle(const rc::Checker &checker, const std::vector<double> &states,
                                      const std::string &what, bool rasterMisses = true)
{
    const std::size_t dof = checker.dof(), n = states.size() / dof;
    std::vector<std::uint8_t> truth(n);
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
        truth[i] = rc::test::bruteForceCollides(checker.collisionModel(), states.data() + i * dof, 0.0) ? 0 : 1;
        colliding += !truth[i];
    }
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        std::vector<std::uint8_t> valid(n);
        checker.check(states.data(), n, valid.data(), request);
        std::size_t falseNegatives = 0, falsePositives = 0;
        for (std::size_t i = 0; i < n; ++i)
        {
            falseNegatives += valid[i] && !truth[i];
            falsePositives += !valid[i] && truth[i];
        }
        EXPECT_EQ(falsePositives, 0u) << what << " " << rc::toString(mode);
        if (mode != rc::CollisionMode::Raster || !rasterMisses)
        {
            EXPECT_EQ(falseNegatives, 0u) << what << " " << rc::toString(mode);
        }
    }
    return colliding;
}
}  // namespace

// ---- URDF ------------------------------------------------------------------------------------

TEST(BadInput, TruncatedUrdf)
{
    const std::string full = foldingArm();
    const std::string path = fileWith("cut.urdf", full.substr(0, full.size() / 2));
    expectInputError([&] { rc::loadUrdf(path); }, path, "line", "malformed XML");
}

TEST(BadInput, MalformedUrdfXml)
{
    const std::string path = fileWith("malformed.urdf", "<robot name=\"r\"><link name=\"a\"></robot>");
    expectInputError([&] { rc::loadUrdf(path); }, path, "line 1", "malformed XML");
}

TEST(BadInput, UrdfWithoutRobotRoot)
{
    const std::string path = fileWith("root.urdf", "<?xml version=\"1.0\"?>\n<model name=\"r\"/>\n");
    expectInputError([&] { rc::loadUrdf(path); }, path, "", "no <robot> root element");
}

TEST(BadInput, UrdfWithoutLinks)
{
    const std::string path = fileWith("empty.urdf", urdfRobot(""));
    expectInputError([&] { rc::loadUrdf(path); }, path, "robot", "has no links");
}

TEST(BadInput, MissingUrdfFile)
{
    const std::string path = makeTempDir("bad") + "/nothing.urdf";
    expectInputError([&] { rc::loadUrdf(path); }, path, "", "file not found");
}

TEST(BadInput, UnknownJointType)
{
    const std::string path =
        fileWith("type.urdf", urdfRobot(urdfLink("a") + urdfLink("b") + urdfJoint("wobble", "spherical", "a", "b")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'wobble'", "unknown joint type 'spherical'");
}

TEST(BadInput, JointNamesMissingLink)
{
    const std::string path = fileWith("link.urdf", urdfRobot(urdfLink("a") + urdfJoint("j", "fixed", "a", "ghost")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j' child", "link 'ghost' does not exist");
}

TEST(BadInput, RevoluteJointWithoutLimit)
{
    const std::string path =
        fileWith("limit.urdf", urdfRobot(urdfLink("a") + urdfLink("b") + urdfJoint("j", "revolute", "a", "b")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j'", "needs <limit");
}

TEST(BadInput, NanJointLimit)
{
    const std::string path =
        fileWith("nan.urdf", urdfRobot(urdfLink("a") + urdfLink("b") +
                                       urdfJoint("j", "revolute", "a", "b",
                                                 "<limit lower=\"nan\" upper=\"1\" effort=\"1\" velocity=\"1\"/>")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j' limit 'lower'", "not a finite number");
}

TEST(BadInput, NanOrigin)
{
    const std::string path =
        fileWith("nan_origin.urdf", urdfRobot(urdfLink("a",
                                                       "<collision><origin xyz=\"0 NaN 0\"/>"
                                                       "<geometry><box size=\"1 1 1\"/></geometry></collision>")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision 0 origin 'xyz'", "'NaN'");
}

TEST(BadInput, ZeroJointAxis)
{
    const std::string path =
        fileWith("axis.urdf", urdfRobot(urdfLink("a") + urdfLink("b") +
                                        urdfJoint("j", "revolute", "a", "b", "<axis xyz=\"0 0 0\"/>" + limit(-1, 1))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j' axis", "zero length");
}

TEST(BadInput, PlanarJointOffAxis)
{
    const std::string path = fileWith(
        "planar.urdf",
        urdfRobot(urdfLink("a") + urdfLink("b") + urdfJoint("p", "planar", "a", "b", "<axis xyz=\"1 0 0\"/>")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'p' axis", "axis 0 0 1");
}

TEST(BadInput, NonPositiveBoxSize)
{
    const std::string path = fileWith("box.urdf", urdfRobot(urdfLink("a", collisionBox("1 0 1"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision 0", "box size y must be positive");
}

TEST(BadInput, ZeroMeshScale)
{
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/cube.obj", kCubeObj);
    const std::string path =
        writeFile(folder + "/scale.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("cube.obj", " scale=\"1 0 1\""))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision mesh 'cube.obj'",
                     "scale must be finite and non-zero");
}

TEST(BadInput, UnsupportedMeshUri)
{
    const std::string path =
        fileWith("uri.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("http://example.com/cube.stl"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision mesh 'http://example.com/cube.stl'",
                     "unsupported URI scheme");
}

TEST(BadInput, TwoRootLinks)
{
    const std::string path = fileWith("roots.urdf", urdfRobot(urdfLink("a") + urdfLink("b")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "robot", "");
}

TEST(BadInput, DuplicateLinkNames)
{
    const std::string path = fileWith(
        "links.urdf", urdfRobot(urdfLink("a") + urdfLink("b") + urdfLink("a") + urdfJoint("j", "fixed", "a", "b")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a'", "defined twice");
}

TEST(BadInput, DuplicateJointNames)
{
    const std::string path =
        fileWith("joints.urdf", urdfRobot(urdfLink("a") + urdfLink("b") + urdfLink("c") +
                                          urdfJoint("j", "fixed", "a", "b") + urdfJoint("j", "fixed", "b", "c")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j'", "defined twice");
}

TEST(BadInput, MimicCycle)
{
    const std::string path = fileWith(
        "cycle.urdf", urdfRobot(urdfLink("a") + urdfLink("b") + urdfLink("c") +
                                urdfJoint("j1", "revolute", "a", "b", limit(-1, 1) + "<mimic joint=\"j2\"/>") +
                                urdfJoint("j2", "revolute", "b", "c", limit(-1, 1) + "<mimic joint=\"j1\"/>")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j1' mimic", "mimic cycle: j1 -> j2 -> j1");
}

TEST(BadInput, MimicOfUnknownJoint)
{
    const std::string path = fileWith(
        "mimic.urdf", urdfRobot(urdfLink("a") + urdfLink("b") +
                                urdfJoint("j1", "revolute", "a", "b", limit(-1, 1) + "<mimic joint=\"nope\"/>")));
    expectInputError([&] { rc::loadUrdf(path); }, path, "joint 'j1' mimic", "'nope' does not exist");
}

TEST(BadInput, InvertedJointLimits)
{
    // Documented fallback (the public crane has such a joint): swapped, with a warning.
    const std::string xml =
        urdfRobot(urdfLink("a") + urdfLink("b") +
                  urdfJoint("backwards", "prismatic", "a", "b", limit(0.3, -0.2) + "<axis xyz=\"1 0 0\"/>"));
    LogCapture log;
    const rc::RobotModelPtr model = rc::loadUrdfString(xml, ".", {}, "limits.urdf");
    EXPECT_EQ(model->lowerBounds, std::vector<double>{-0.2});
    EXPECT_EQ(model->upperBounds, std::vector<double>{0.3});
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_TRUE(
        log.warned("limits.urdf: joint 'backwards': lower limit 0.300000 is above upper limit -0.200000; "
                   "the limits are swapped"))
        << log.warnings[0];
}

TEST(BadInput, EqualJointLimits)
{
    // A joint that cannot move keeps its coordinate, fixed at the limit: the checker accepts only that
    // value and OMPL samples only that value.
    const std::string xml = urdfRobot(urdfLink("a", collisionBox("0.1 0.1 0.1")) + urdfLink("b") +
                                      urdfLink("c", collisionBox("0.1 0.1 0.1", "0.5 0 0")) +
                                      urdfJoint("pinned", "revolute", "a", "b", limit(0.1, 0.1)) +
                                      urdfJoint("free", "revolute", "b", "c", limit(-1, 1)));
    LogCapture log;
    const rc::RobotModelPtr model = rc::loadUrdfString(xml, ".", {}, "pinned.urdf");
    EXPECT_TRUE(log.warnings.empty());
    EXPECT_EQ(model->coordinateNames, (std::vector<std::string>{"pinned", "free"}));
    EXPECT_EQ(model->lowerBounds[0], 0.1);
    EXPECT_EQ(model->upperBounds[0], 0.1);

    const auto checker = std::make_shared<const rc::Checker>(model, nullptr);
    EXPECT_TRUE(checker->isValid(std::vector<double>{0.1, 0.5}));
    rc::Contact contact;
    EXPECT_FALSE(checker->isValid(std::vector<double>{0.1001, 0.5}, {}, &contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);

    const auto mapping = std::make_shared<const rco::StateMapping>(model);
    auto si = std::make_shared<ob::SpaceInformation>(mapping->getStateSpace());
    si->setStateValidityChecker(std::make_shared<rco::StateValidityChecker>(si, mapping, checker));
    si->setup();
    ob::StateSamplerPtr sampler = si->allocStateSampler();
    ob::ScopedState<> state(si->getStateSpace());
    for (int i = 0; i < 20; ++i)
    {
        sampler->sampleUniform(state.get());
        EXPECT_EQ(mapping->toConfiguration(state.get())[0], 0.1);
        EXPECT_TRUE(si->isValid(state.get()));
    }
}

// ---- mesh files -------------------------------------------------------------------------------

TEST(BadInput, MissingMeshFile)
{
    const std::string path =
        fileWith("missing.urdf", urdfRobot(urdfLink("panda_link6", urdfCollisionMesh("meshes/x.stl"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'panda_link6' collision mesh 'meshes/x.stl'",
                     "file not found");
}

TEST(BadInput, EmptyMeshFile)
{
    const std::string path = fileWith("empty.stl", "");
    expectInputError([&] { rc::loadMesh(path); }, path, "", "cannot read mesh: File is empty");
    expectInputError([] { rc::loadMeshNodesFromMemory("", 0, "stl", "<bytes>"); }, "<bytes>", "", "mesh data is empty");
}

TEST(BadInput, MeshWithoutTriangles)
{
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    const std::string path =
        writeFile(folder + "/points.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("points.obj"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision mesh 'points.obj'",
                     "mesh has no triangles");
}

TEST(BadInput, TruncatedStl)
{
    // A binary STL whose header promises 12 facets, cut after 3.
    std::string bytes(80, ' ');
    const std::uint32_t count = 12;
    bytes.append(reinterpret_cast<const char *>(&count), 4);
    bytes.append(3 * 50, '\0');
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/cut.stl", bytes);
    const std::string path = writeFile(folder + "/cut.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("cut.stl"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision mesh 'cut.stl'", "cannot read mesh");
}

TEST(BadInput, TruncatedObj)
{
    // OBJ has no length field: a cube cut inside its last face reads as 11 triangles. The link is
    // open (reported); the exact narrow phase still finds every surface contact.
    const std::string cube = kCubeObj;
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/cut.obj", cube.substr(0, cube.size() - 3));
    const std::string path =
        writeFile(folder + "/cut.urdf",
                  urdfRobot(urdfLink("world") + urdfLink("a", urdfCollisionMesh("cut.obj")) +
                            urdfJoint("slide", "prismatic", "world", "a", "<axis xyz=\"1 0 0\"/>" + limit(-5, 5))));
    LogCapture log;
    const rc::RobotModelPtr robot = rc::loadUrdf(path);
    EXPECT_EQ(robot->components[0].mesh.numTriangles(), 11u);
    EXPECT_FALSE(robot->components[0].topology.closed);
    EXPECT_TRUE(log.noticed(path + ": link 'a' collision geometry is open (")) << ::testing::PrintToString(log.notices);
    EXPECT_TRUE(log.noticed("the exact narrow phase checks it"));
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("post", boxAt({0.2, 0.2, 2.0}, {2.0, 0, 0}));
    const rc::Checker checker(robot, scene);
    EXPECT_EQ(expectModesMatchTheOracle(checker, {0.0, 1.5, 2.0, 2.55, 3.0}, "cut cube"), 3u);
}

TEST(BadInput, MalformedCollada)
{
    const std::string path = fileWith("garbage.dae", "<COLLADA><not closed");
    expectInputError([&] { rc::loadMesh(path); }, path, "", "cannot read mesh");
}

TEST(BadInput, MeshIndexOutOfRange)
{
    const std::string path = fileWith("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    expectInputError([&] { rc::loadMesh(path); }, path, "", "vertex index out of range");
}

TEST(BadInput, NanMeshVertex)
{
    const std::string path = fileWith("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    expectInputError([&] { rc::loadMesh(path); }, path, "node 'defaultobject'",
                     "vertex coordinate is not a finite number");
}

TEST(BadInput, DegenerateTriangles)
{
    // A cube plus a triangle with a repeated vertex and one with three collinear vertices: both are
    // dropped and counted, and the cube stays closed.
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/cube.obj", std::string(kCubeObj) + "v 0 -0.5 -0.5\nf 1 1 2\nf 1 9 2\n");
    const std::string path = writeFile(folder + "/cube.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("cube.obj"))));
    LogCapture log;
    const rc::RobotModelPtr robot = rc::loadUrdf(path);
    const rc::Component &cube = robot->components[0];
    EXPECT_EQ(cube.mesh.numTriangles(), 12u);
    EXPECT_EQ(cube.topology.degenerateTriangles, 2u);
    EXPECT_TRUE(cube.topology.closed) << cube.topology.summary();
    EXPECT_TRUE(log.notices.empty() && log.warnings.empty());
}

TEST(BadInput, OnlyDegenerateTriangles)
{
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    const std::string path = writeFile(folder + "/line.urdf", urdfRobot(urdfLink("a", urdfCollisionMesh("line.obj"))));
    expectInputError([&] { rc::loadUrdf(path); }, path, "link 'a' collision",
                     "geometry has no triangles after cleaning");
}

TEST(BadInput, OpenSceneMesh)
{
    // A 1 m crate without its lid: a surface with no inside. A cube inside it is free (documented,
    // as FCL); one through its wall collides. Every mode agrees with the oracle.
    const std::string cube = kCubeObj;
    const std::string path =
        fileWith("crate.obj", "o crate\n" + cube.substr(0, cube.find("f 5 6 7")) + cube.substr(cube.find("f 1 2 6")));
    LogCapture log;
    const rc::ScenePtr scene = rc::loadSceneFile(path);
    ASSERT_EQ(scene->numObjects(), 1u);
    EXPECT_FALSE(scene->objects[0].topology.closed);
    EXPECT_TRUE(log.warned("scene object 'crate' is open (4 boundary edges")) << ::testing::PrintToString(log.warnings);
    EXPECT_TRUE(log.warned("a component entirely inside it is not a collision"));
    const rc::Checker checker(flyingCube(), scene);
    EXPECT_TRUE(checker.isValid(at(0, 0, 0)));
    EXPECT_FALSE(checker.isValid(at(0.5, 0, 0)));
    expectModesMatchTheOracle(checker, {0, 0, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 0, 0, 1, 0, 0, 0.55, 0, 0, 0, 1}, "crate");
}

TEST(BadInput, DoubleSidedMesh)
{
    // SketchUp's COLLADA stores every face twice, front and back; parity would toggle twice per
    // surface and see nothing inside. The copies are removed, the box is closed, and a cube buried
    // inside it collides in every mode.
    std::string doubled = std::string("o box\n") + kCubeObj;
    std::istringstream faces(kCubeObj);
    for (std::string line; std::getline(faces, line);)
        if (line[0] == 'f')
        {
            std::istringstream f(line.substr(2));
            int a, b, c;
            f >> a >> b >> c;
            doubled += "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(b) + "\n";
        }
    const rc::ScenePtr scene = rc::loadSceneFile(fileWith("double.obj", doubled));
    ASSERT_EQ(scene->numObjects(), 1u);
    EXPECT_EQ(scene->objects[0].topology.removedDuplicateFaces, 12u);
    EXPECT_EQ(scene->objects[0].mesh.numTriangles(), 12u);
    EXPECT_TRUE(scene->objects[0].topology.closed);
    const rc::Checker checker(flyingCube(), scene);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        EXPECT_FALSE(checker.isValid(at(0.1, 0, 0), request)) << rc::toString(mode);
        EXPECT_TRUE(checker.isValid(at(2, 0, 0), request)) << rc::toString(mode);
    }
}

// ---- SRDF -------------------------------------------------------------------------------------

TEST(BadInput, TruncatedSrdf)
{
    expectInputError([] { rc::loadSrdfString("<robot name=\"r\"><disable_collisions link1=\"a\"", "cut.srdf"); },
                     "cut.srdf", "line", "malformed XML");
}

TEST(BadInput, SrdfWithoutRobotRoot)
{
    expectInputError([] { rc::loadSrdfString("<notrobot/>", "root.srdf"); }, "root.srdf", "", "no <robot>");
}

TEST(BadInput, SrdfPairWithoutSecondLink)
{
    expectInputError(
        []
        {
            rc::loadSrdfString(
                "<robot name=\"r\"><disable_collisions link1=\"a\" link2=\"b\"/>"
                "<disable_collisions link1=\"a\"/></robot>",
                "pair.srdf");
        },
        "pair.srdf", "disable_collisions #1", "missing attribute 'link2'");
}

TEST(BadInput, NanGroupStateValue)
{
    expectInputError(
        []
        {
            rc::loadSrdfString(
                "<robot name=\"r\"><group_state name=\"home\" group=\"arm\">"
                "<joint name=\"j1\" value=\"nan\"/></group_state></robot>",
                "value.srdf");
        },
        "value.srdf", "group_state 'home' joint 'j1' 'value'", "not a finite number");
}

TEST(BadInput, MissingSrdfFile)
{
    const std::string path = makeTempDir("bad") + "/none.srdf";
    expectInputError([&] { rc::loadSrdf(path); }, path, "", "file not found");
}

TEST(BadInput, SrdfNamesUnknownLink)
{
    // As MoveIt: the pair is skipped with a warning, the other pairs apply.
    rc::RobotModelPtr arm = rc::loadUrdfString(foldingArm(), ".", {}, "arm.urdf");
    const rc::Srdf srdf = rc::loadSrdfString(
        "<robot name=\"test\"><disable_collisions link1=\"base\" link2=\"ghost\"/>"
        "<disable_collisions link1=\"base\" link2=\"tip\"/></robot>",
        "arm.srdf");
    LogCapture log;
    rc::applySrdf(*arm, srdf);
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_TRUE(log.warned("SRDF disable_collisions names link 'ghost', which robot 'test' lacks; pair skipped"));
    EXPECT_TRUE(arm->isCollisionAllowed(arm->links[arm->linkIndex("base")].component,
                                        arm->links[arm->linkIndex("tip")].component));
}

TEST(BadInput, SrdfForAnotherRobot)
{
    rc::RobotModelPtr arm = rc::loadUrdfString(foldingArm(), ".", {}, "arm.urdf");
    LogCapture log;
    rc::applySrdf(*arm, rc::loadSrdfString("<robot name=\"panda\"/>", "panda.srdf"));
    EXPECT_TRUE(log.warned("SRDF is for robot 'panda', applied to robot 'test'"));
}

TEST(BadInput, MultiDofGroupStateValue)
{
    LogCapture log;
    const rc::Srdf srdf = rc::loadSrdfString(
        "<robot name=\"r\"><group_state name=\"home\" group=\"arm\">"
        "<joint name=\"base\" value=\"1 2 3\"/><joint name=\"j1\" value=\"0.5\"/>"
        "</group_state></robot>",
        "multi.srdf");
    EXPECT_TRUE(log.warned("multi.srdf: group_state 'home' joint 'base': 3 values (multi-DOF joint) are ignored"));
    EXPECT_EQ(srdf.groupStates.at("home"), (std::map<std::string, double>{{"j1", 0.5}}));
}

// ---- MoveIt scene YAML ------------------------------------------------------------------------

TEST(BadInput, TruncatedSceneYaml)
{
    const std::string scene = kCrateScene;
    const std::string cut = scene.substr(0, scene.find("1, 1]}]") + 4);
    expectInputError([&] { rc::loadMoveItSceneString(cut, "cut.yaml"); }, "cut.yaml", "line", "malformed YAML");
}

TEST(BadInput, MalformedSceneYaml)
{
    expectInputError([] { rc::loadMoveItSceneString("world: {collision_objects: [{id: crate}]]}", "bad.yaml"); },
                     "bad.yaml", "line 1", "malformed YAML");
}

TEST(BadInput, SceneYamlOfWrongShape)
{
    for (const char *text : {"world: 3", "world: {collision_objects: 5}", "world: {collision_objects: [7]}",
                             "world: {collision_objects: [{id: [1, 2]}]}", "- just\n- a list\n"})
        EXPECT_THROW(rc::loadMoveItSceneString(text, "odd.yaml"), rc::InputError) << text;
    expectInputError([] { rc::loadMoveItSceneString("world: {collision_objects: [7]}", "odd.yaml"); }, "odd.yaml",
                     "collision object #0", "expected a map");
}

TEST(BadInput, NanPrimitiveDimension)
{
    expectInputError(
        [&]
        {
            rc::loadMoveItSceneString(kThing +
                                          "      primitives: [{type: box, dimensions: [1, .nan, 1]}]\n"
                                          "      primitive_poses: [{position: [0, 0, 0]}]\n",
                                      "nan.yaml");
        },
        "nan.yaml", "collision object 'thing' primitives[0].dimensions[1]", "not a finite number");
}

TEST(BadInput, UnknownPrimitiveType)
{
    expectInputError(
        [&]
        {
            rc::loadMoveItSceneString(kThing +
                                          "      primitives: [{type: torus, dimensions: [1, 1]}]\n"
                                          "      primitive_poses: [{position: [0, 0, 0]}]\n",
                                      "type.yaml");
        },
        "type.yaml", "collision object 'thing' primitives[0].type", "unknown primitive type 'torus'");
}

TEST(BadInput, PrimitivesWithoutPoses)
{
    expectInputError(
        [&] {
            rc::loadMoveItSceneString(kThing + "      primitives: [{type: box, dimensions: [1, 1, 1]}]\n",
                                      "poses.yaml");
        },
        "poses.yaml", "collision object 'thing' primitive_poses", "1 primitives need as many primitive_poses");
}

TEST(BadInput, CylinderWithOneDimension)
{
    expectInputError(
        [&]
        {
            rc::loadMoveItSceneString(kThing +
                                          "      primitives: [{type: cylinder, dimensions: [1]}]\n"
                                          "      primitive_poses: [{position: [0, 0, 0]}]\n",
                                      "dims.yaml");
        },
        "dims.yaml", "collision object 'thing' primitives[0].dimensions", "cylinder needs 2 dimensions");
}

TEST(BadInput, ShortPosition)
{
    expectInputError(
        [&] {
            rc::loadMoveItSceneString(kThing + "      pose: {position: [0, 0], orientation: [0, 0, 0, 1]}\n",
                                      "pose.yaml");
        },
        "pose.yaml", "collision object 'thing' pose.position", "expected 3 numbers");
}

TEST(BadInput, ZeroQuaternion)
{
    expectInputError(
        [&] {
            rc::loadMoveItSceneString(kThing + "      pose: {position: [0, 0, 0], orientation: [0, 0, 0, 0]}\n",
                                      "q.yaml");
        },
        "q.yaml", "collision object 'thing' pose.orientation", "quaternion has zero length");
}

TEST(BadInput, SceneMeshIndexOutOfRange)
{
    expectInputError(
        [&]
        {
            rc::loadMoveItSceneString(kThing +
                                          "      meshes: [{vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]],"
                                          " triangles: [[0, 1, 3]]}]\n"
                                          "      mesh_poses: [{position: [0, 0, 0]}]\n",
                                      "mesh.yaml");
        },
        "mesh.yaml", "collision object 'thing' meshes[0].triangles[0]", "vertex index 3.000000 out of range");
}

TEST(BadInput, RemoveOperation)
{
    expectInputError([&] { rc::loadMoveItSceneString(kThing + "      operation: 1\n", "remove.yaml"); }, "remove.yaml",
                     "collision object 'thing' operation", "only ADD/APPEND objects can be loaded");
}

TEST(BadInput, DuplicateObjectIds)
{
    // MoveIt would let the second ADD replace the first: an obstacle of the file silently lost.
    const std::string scene =
        std::string(kCrateScene) + std::string(kCrateScene).substr(std::string(kCrateScene).find("    - id"));
    expectInputError([&] { rc::loadMoveItSceneString(scene, "twice.yaml"); }, "twice.yaml",
                     "collision object 'crate' (#1)", "id defined twice");
}

TEST(BadInput, DuplicateSceneObjectName)
{
    rc::Scene scene;
    scene.addObject("crate", boxAt({1, 1, 1}, {0, 0, 0}));
    try
    {
        scene.addObject("crate", boxAt({1, 1, 1}, {3, 0, 0}));
        ADD_FAILURE() << "expected a ConfigurationError";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_STREQ(e.what(), "scene object 'crate' is defined twice");
    }
    EXPECT_EQ(scene.numObjects(), 1u);
}

TEST(BadInput, RepeatedMeshNodeNames)
{
    // Mesh node names are labels (exporters repeat them, or leave them empty): made unique. Two
    // COLLADA nodes named "wall" place one tetrahedron twice.
    const std::string tetrahedron =
        "<geometry id=\"tet\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"12\">0 0 0 1 0 0 0 1 0 0 0 1"
        "</float_array><technique_common><accessor source=\"#pa\" count=\"4\" stride=\"3\"><param name=\"X\" "
        "type=\"float\"/><param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor>"
        "</technique_common></source><vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>"
        "<triangles count=\"4\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>"
        "<p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles></mesh></geometry>";
    auto wall = [](const std::string &x)
    {
        return "<node id=\"wall\" name=\"wall\"><matrix>1 0 0 " + x +
               " 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url=\"#tet\"/></node>";
    };
    const std::string dae =
        "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" "
        "version=\"1.4.1\"><library_geometries>" +
        tetrahedron + "</library_geometries><library_visual_scenes><visual_scene id=\"s\">" + wall("0") + wall("3") +
        "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene>"
        "</COLLADA>";
    const rc::ScenePtr scene = rc::loadSceneFile(fileWith("walls.dae", dae));
    ASSERT_EQ(scene->numObjects(), 2u);
    EXPECT_EQ(scene->objects[0].name, "wall");
    EXPECT_EQ(scene->objects[1].name, "wall/1");
    EXPECT_NEAR(scene->objects[1].bounds.min.x(), 3.0, 1e-9);
}

TEST(BadInput, MissingSceneFile)
{
    const std::string path = makeTempDir("bad") + "/none.yaml";
    expectInputError([&] { rc::loadMoveItScene(path); }, path, "", "file not found");
}

TEST(BadInput, EmptyScene)
{
    // Loads with a warning; then only self-collision is checked.
    LogCapture log;
    const rc::ScenePtr scene = rc::loadMoveItSceneString("world: {collision_objects: []}\n", "empty.yaml");
    EXPECT_EQ(scene->numObjects(), 0u);
    EXPECT_TRUE(log.warned("empty.yaml: the scene has no collision objects: only self-collision is checked"));
    const rc::Checker checker(rc::loadUrdfString(foldingArm(), ".", {}, "arm.urdf"), scene);
    rc::Contact contact;
    EXPECT_TRUE(checker.isValid(std::vector<double>{0.0, 0.0}));
    EXPECT_FALSE(checker.isValid(std::vector<double>{0.0, M_PI}, {}, &contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::SelfCollision);
}

// ---- MoveIt request YAML ----------------------------------------------------------------------

TEST(BadInput, TruncatedRequestYaml)
{
    expectInputError(
        [] {
            rc::loadMoveItRequestString("start_state:\n  joint_state:\n    name: [j1, j2]\n    position: [0.1, 0",
                                        "cut.yaml");
        },
        "cut.yaml", "line", "malformed YAML");
}

TEST(BadInput, RequestYamlOfWrongShape)
{
    for (const char *text : {"goal_constraints: [5]", "goal_constraints: [{joint_constraints: [3]}]",
                             "start_state: {joint_state: 4}", "start_state: 2", "- just\n- a list\n"})
        EXPECT_THROW(rc::loadMoveItRequestString(text, "odd.yaml"), rc::InputError) << text;
    expectInputError([] { rc::loadMoveItRequestString("start_state: 2", "odd.yaml"); }, "odd.yaml", "start_state",
                     "expected a map");
}

TEST(BadInput, RequestNamesAndPositionsDiffer)
{
    expectInputError(
        [] {
            rc::loadMoveItRequestString("start_state:\n  joint_state:\n    name: [a, b]\n    position: [1]\n",
                                        "request.yaml");
        },
        "request.yaml", "start_state.joint_state", "2 names but 1 positions");
}

TEST(BadInput, RequestPositionNotANumber)
{
    expectInputError(
        []
        {
            rc::loadMoveItRequestString(
                "goal_constraints:\n  - joint_constraints:\n      - {joint_name: a, position: abc}\n", "goal.yaml");
        },
        "goal.yaml", "goal_constraints[0].joint_constraints[0].position", "'abc' is not a number");
}

TEST(BadInput, RequestJointTwice)
{
    expectInputError(
        []
        {
            rc::loadMoveItRequestString("start_state:\n  joint_state:\n    name: [a, a]\n    position: [1, 2]\n",
                                        "twice.yaml");
        },
        "twice.yaml", "start_state.joint_state.name[1]", "joint 'a' appears twice");
    expectInputError(
        []
        {
            rc::loadMoveItRequestString(
                "goal_constraints:\n  - joint_constraints:\n      - {joint_name: a, position: 1}\n"
                "      - {joint_name: a, position: 2}\n",
                "twice.yaml");
        },
        "twice.yaml", "goal_constraints[0].joint_constraints[1].joint_name", "joint 'a' is constrained twice");
}

TEST(BadInput, RequestNamesUnknownJoint)
{
    const auto mapping =
        std::make_shared<const rco::StateMapping>(rc::loadUrdfString(foldingArm(), ".", {}, "arm.urdf"));
    const rc::MotionPlanRequest request = rc::loadMoveItRequestString(
        "start_state:\n  joint_state:\n    name: [j1, ghost]\n    position: [0.1, 0.2]\n", "request.yaml");
    // A goal the robot cannot meet is an error.
    try
    {
        rco::configurationFromJoints(*mapping, request.startJoints, "goal");
        ADD_FAILURE() << "expected a ConfigurationError";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_STREQ(e.what(), "goal names joint 'ghost', which robot 'test' lacks");
    }
    // A start state lists the whole robot (a reduced model may lack some): skipped, the rest kept.
    const std::vector<double> start =
        rco::configurationFromJoints(*mapping, request.startJoints, "start", rco::UnknownJoints::Skip);
    EXPECT_DOUBLE_EQ(start[0], 0.1);
}

// ---- OMPL.app .cfg ----------------------------------------------------------------------------

TEST(BadInput, TruncatedCfg)
{
    // Cut after "goal.y =": the goal's first key read (theta) is missing.
    const std::string text = kCfg;
    const std::string folder = makeTempDir("bad");
    writeFile(folder + "/robot.obj", kCubeObj);
    writeFile(folder + "/world.obj", kCubeObj);
    const std::string path = writeFile(folder + "/cut.cfg", text.substr(0, text.find("goal.y") + 8));
    expectInputError([&] { rc::loadOmplAppProblem(path); }, path, "[problem] goal.theta", "missing");
}

TEST(BadInput, CfgLineWithoutEquals)
{
    expectCfgError("name = cubes", "this line has no equals sign", "line 2", "expected 'key = value'");
}

TEST(BadInput, CfgMalformedSection)
{
    expectCfgError("[benchmark]", "[benchmark", "line", "malformed section header '[benchmark'");
}

TEST(BadInput, CfgMissingKey)
{
    expectCfgError("start.x = 0\n", "", "[problem] start.x", "missing");
}

TEST(BadInput, CfgNanNumber)
{
    expectCfgError("start.y = 0", "start.y = nan", "[problem] start.y", "'nan' is not a finite number");
}

TEST(BadInput, CfgWordForNumber)
{
    expectCfgError("goal.z = 3", "goal.z = three", "[problem] goal.z", "'three' is not a finite number");
}

TEST(BadInput, CfgInvertedVolume)
{
    expectCfgError("volume.min.y = -5", "volume.min.y = 6", "[problem] volume.min.y",
                   "min 6.000000 is above max 5.000000");
}

TEST(BadInput, CfgMissingMesh)
{
    expectCfgError("robot = robot.obj", "robot = nothing.obj", "[problem] robot 'nothing.obj'", "file not found");
}

TEST(BadInput, CfgEmptyMesh)
{
    expectCfgError("robot = robot.obj", "robot = empty.obj", "[problem] robot 'empty.obj'", "mesh has no triangles");
}

TEST(BadInput, CfgZeroRotationAxis)
{
    expectCfgError("start.theta = 0\nstart.axis.x = 1", "start.theta = 1\nstart.axis.x = 0", "[problem] start.axis",
                   "rotation axis has zero length");
}

TEST(BadInput, MissingCfgFile)
{
    const std::string path = makeTempDir("bad") + "/none.cfg";
    expectInputError([&] { rc::loadOmplAppProblem(path); }, path, "", "file not found");
}

// ---- states CSV -------------------------------------------------------------------------------

TEST(BadInput, TruncatedStatesCsv)
{
    const std::string path = fileWith("cut.csv", "a,b\n1,2\n3");
    expectInputError([&] { rc::readStatesCsv(path, {"a", "b"}); }, path, "line 3 column 'b'", "row has only 1 cells");
}

TEST(BadInput, StatesCsvCellNotANumber)
{
    expectInputError(
        [] {
            rc::parseStatesCsv("a,b\n1,x\n", {"a", "b"}, "s.csv");
        },
        "s.csv", "line 2 column 'b'", "'x' is not a number");
}

TEST(BadInput, StatesCsvBlankCell)
{
    expectInputError(
        [] {
            rc::parseStatesCsv("a,b\n1,\n", {"a", "b"}, "s.csv");
        },
        "s.csv", "line 2 column 'b'", "'' is not a number");
}

TEST(BadInput, StatesCsvMissingColumn)
{
    expectInputError(
        [] {
            rc::parseStatesCsv("a,c\n1,2\n", {"a", "b"}, "s.csv");
        },
        "s.csv", "column 'b'", "missing from the header");
}

TEST(BadInput, StatesCsvDuplicateColumn)
{
    expectInputError(
        [] {
            rc::parseStatesCsv("a,b,a\n1,2,3\n", {"a", "b"}, "s.csv");
        },
        "s.csv", "column 'a'", "appears twice in the header");
}

TEST(BadInput, EmptyStatesCsv)
{
    expectInputError(
        [] {
            rc::parseStatesCsv("\n\n", {"a", "b"}, "s.csv");
        },
        "s.csv", "header", "no header row (expected columns a, ...)");
}

TEST(BadInput, MissingStatesCsv)
{
    const std::string path = makeTempDir("bad") + "/none.csv";
    expectInputError([&] { rc::readStatesCsv(path, {"a"}); }, path, "", "cannot open the states file");
}

TEST(BadInput, StatesCsvExtraColumns)
{
    // Documented: columns are matched by name, others are ignored (an id, a label).
    const rc::StatesTable table = rc::parseStatesCsv("id,b,a,label\n7,2,1,x\n8,4,3,y\n", {"a", "b"}, "s.csv");
    EXPECT_EQ(table.rows, 2u);
    EXPECT_EQ(table.values, (std::vector<double>{1, 2, 3, 4}));
}

TEST(BadInput, NanStateThroughCheckCli)
{
    // "nan" and "inf" cells read as such; those states are invalid, with one warning, and the run
    // succeeds.
    const std::string folder = makeTempDir("bad");
    const std::string urdf = writeFile(folder + "/arm.urdf", foldingArm());
    const std::string states = writeFile(folder + "/states.csv", "j1,j2\n0,0\nnan,0\n0,inf\n0,3.14159\n");
    const rc::test::CommandRun run =
        rc::test::runCli("check --robot " + urdf + " --states " + states + " --out " + folder + "/out.csv");
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("states=4 invalid=3"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("rastercheck: warning: state 1 of 4 has coordinate 'j1' = nan: a state that is not "
                              "finite is invalid (reported once per checker)"),
              std::string::npos)
        << run.output;
    std::ifstream out(folder + "/out.csv");
    std::stringstream verdicts;
    verdicts << out.rdbuf();
    EXPECT_EQ(verdicts.str().substr(0, verdicts.str().find("\n0,base")),
              "valid,component,object,triangle,x,y,z,reason\n1,,,,,,,\n0,,,,,,,bounds:j1\n0,,,,,,,bounds:j2");
}

// ---- states -----------------------------------------------------------------------------------

TEST(BadInput, NanStateIsInvalid)
{
    const rc::Checker checker(flyingCube(), tableScene());
    LogCapture log;
    rc::Contact contact;
    EXPECT_FALSE(checker.isValid(std::vector<double>{kNan, 0, 3, 0, 0, 0, 1}, {}, &contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);
    EXPECT_EQ(contact.coordinate, 0);
    EXPECT_EQ(checker.describe(contact), "coordinate 'x' out of bounds or not finite");
    EXPECT_FALSE(checker.isValid(std::vector<double>{0, 0, 3, 0, 0, kNan, 1}));
    ASSERT_EQ(log.warnings.size(), 1u) << "once per checker";
    EXPECT_EQ(log.warnings[0],
              "a state has coordinate 'x' = nan: a state that is not finite is invalid (reported once per checker)");
}

TEST(BadInput, InfiniteStateInBatch)
{
    const rc::Checker checker(flyingCube(), tableScene());
    LogCapture log;
    std::vector<double> q = at(0, 0, 3);
    const std::vector<double> bad{0, kInf, 3, 0, 0, 0, 1}, sunk = at(0, 0, 0.05);
    q.insert(q.end(), bad.begin(), bad.end());
    q.insert(q.end(), sunk.begin(), sunk.end());
    std::vector<std::uint8_t> valid(3);
    std::vector<rc::Contact> contacts(3);
    checker.check(q.data(), 3, valid.data(), {}, contacts.data());
    EXPECT_EQ(valid, (std::vector<std::uint8_t>{1, 0, 0}));
    EXPECT_EQ(contacts[1].kind, rc::Contact::Kind::OutOfBounds);
    EXPECT_EQ(contacts[2].kind, rc::Contact::Kind::Environment);
    EXPECT_TRUE(log.warned("state 1 of 3 has coordinate 'y' = inf")) << ::testing::PrintToString(log.warnings);
}

TEST(BadInput, NanStateThroughOmpl)
{
    // OMPL's real-vector satisfiesBounds lets NaN through (every comparison with it is false); the
    // checker must still call such a state invalid: a real vector (SE3 position), an SO2 and an SO3.
    LogCapture log;
    auto makeContext = [](const rc::RobotModelConstPtr &robot)
    {
        auto mapping = std::make_shared<const rco::StateMapping>(robot);
        auto si = std::make_shared<ob::SpaceInformation>(mapping->getStateSpace());
        auto checker = std::make_shared<const rc::Checker>(robot, tableScene());
        si->setStateValidityChecker(std::make_shared<rco::StateValidityChecker>(si, mapping, checker));
        si->setup();
        return std::make_pair(si, mapping);
    };
    const auto [cubeSi, cubeMapping] = makeContext(flyingCube());
    ob::ScopedState<ob::SE3StateSpace> pose(cubeSi->getStateSpace());
    cubeMapping->fromConfiguration(at(0, 0, 3), pose.get());
    EXPECT_TRUE(cubeSi->isValid(pose.get()));
    pose->setY(kNan);
    EXPECT_TRUE(cubeSi->satisfiesBounds(pose.get())) << "OMPL's own bounds check lets NaN pass";
    EXPECT_FALSE(cubeSi->isValid(pose.get()));
    cubeMapping->fromConfiguration(at(0, 0, 3), pose.get());
    pose->rotation().x = kNan;
    EXPECT_FALSE(cubeSi->isValid(pose.get()));

    const std::string spinner = urdfRobot(urdfLink("world") + urdfLink("arm", collisionBox("1 0.1 0.1", "0.5 0 3")) +
                                          urdfJoint("spin", "continuous", "world", "arm", "<axis xyz=\"0 0 1\"/>"));
    const auto [spinSi, spinMapping] = makeContext(rc::loadUrdfString(spinner, ".", {}, "spinner.urdf"));
    ob::ScopedState<ob::SO2StateSpace> angle(spinSi->getStateSpace());
    angle->value = 0.5;
    EXPECT_TRUE(spinSi->isValid(angle.get()));
    angle->value = kNan;
    EXPECT_FALSE(spinSi->isValid(angle.get()));
    // SO2 and SO3 bounds checks refuse NaN before the checker sees it; the position reached it.
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_TRUE(log.warned("a state has coordinate 'y' = nan"));
}

TEST(BadInput, OutOfBoundsState)
{
    const rc::Checker checker(flyingCube(), tableScene());
    rc::Contact contact;
    EXPECT_FALSE(checker.isValid(at(0, 0, 6), {}, &contact));  // z above its bound of 5
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);
    EXPECT_FALSE(checker.isValid(std::vector<double>{0, 0, 3, 0, 0, 0, 2}));   // qw outside [-1, 1]
    EXPECT_TRUE(checker.isValid(std::vector<double>{0, 0, 3, 0, 0, 0, 0.5}));  // unnormalised: normalised
}

TEST(BadInput, OutOfBoundsStateThroughOmpl)
{
    const auto mapping = std::make_shared<const rco::StateMapping>(flyingCube());
    auto si = std::make_shared<ob::SpaceInformation>(mapping->getStateSpace());
    auto validity = std::make_shared<rco::StateValidityChecker>(
        si, mapping, std::make_shared<const rc::Checker>(flyingCube(), tableScene()));
    si->setStateValidityChecker(validity);
    si->setup();
    ob::ScopedState<> state(si->getStateSpace());
    mapping->fromConfiguration(at(0, 0, 5.5), state.get());
    rc::Contact contact;
    EXPECT_FALSE(validity->isValid(state.get(), contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);
}

TEST(BadInput, ZeroQuaternionState)
{
    const rc::Checker checker(flyingCube(), tableScene());
    rc::Contact contact;
    EXPECT_FALSE(checker.isValid(std::vector<double>{0, 0, 3, 0, 0, 0, 0}, {}, &contact));
    EXPECT_EQ(contact.kind, rc::Contact::Kind::OutOfBounds);
}

TEST(BadInput, WrongSizeStateVector)
{
    const rc::Checker checker(flyingCube(), tableScene());
    for (std::size_t size : {0u, 6u, 8u})
    {
        try
        {
            checker.isValid(std::vector<double>(size, 0.0));
            ADD_FAILURE() << "expected a ConfigurationError for " << size << " values";
        }
        catch (const rc::ConfigurationError &e)
        {
            EXPECT_EQ(std::string(e.what()), "Checker::isValid: the configuration has " + std::to_string(size) +
                                                 " values, robot 'cube' has 7 coordinates");
        }
    }
}

// ---- collision requests -----------------------------------------------------------------------

TEST(BadInput, ZeroPadding)
{
    // The default: solids collide when they overlap, in every mode, down to 0.1 mm here.
    const rc::Checker checker(flyingCube(), tableScene());
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        EXPECT_EQ(request.padding, 0.0);
        EXPECT_FALSE(checker.isValid(at(0.2, 0.1, 0.0999), request)) << rc::toString(mode);
        EXPECT_TRUE(checker.isValid(at(0.2, 0.1, 0.1001), request)) << rc::toString(mode);
    }
}

TEST(BadInput, HugePadding)
{
    // Everything within reach collides, and nothing overflows: the float culls saturate at the
    // largest float (1e300 m), the exact phase works with the double. Self pairs too.
    const rc::Checker checker(flyingCube(), tableScene());
    const rc::Checker alone(flyingCube(), nullptr);
    const rc::Checker arm(rc::loadUrdfString(foldingArm(), ".", {}, "arm.urdf"), nullptr);
    for (double padding : {1e9, 1e300})
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.padding = padding;
            rc::Contact contact;
            EXPECT_FALSE(checker.isValid(at(4.9, -4.9, 4.9), request, &contact)) << padding << rc::toString(mode);
            EXPECT_EQ(contact.kind, rc::Contact::Kind::Environment);
            EXPECT_FALSE(arm.isValid(std::vector<double>{0.0, 0.0}, request, &contact))
                << padding << rc::toString(mode);
            EXPECT_EQ(contact.kind, rc::Contact::Kind::SelfCollision);
            EXPECT_TRUE(alone.isValid(at(4.9, -4.9, 4.9), request)) << "nothing else to collide with";
        }
}

TEST(BadInput, NegativePadding)
{
    const rc::Checker checker(flyingCube(), tableScene());
    rc::CollisionRequest request;
    request.padding = -0.01;
    try
    {
        checker.isValid(at(0, 0, 3), request);
        ADD_FAILURE() << "expected a ConfigurationError";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_STREQ(e.what(), "CollisionRequest::padding must be finite and >= 0, got -0.010000");
    }
    std::uint8_t valid = 2;
    EXPECT_THROW(checker.check(at(0, 0, 3).data(), 1, &valid, request), rc::ConfigurationError);
    EXPECT_EQ(valid, 2) << "no verdict written";
    // The OMPL adapter refuses it when it is built, not inside a planner.
    const auto mapping = std::make_shared<const rco::StateMapping>(flyingCube());
    auto si = std::make_shared<ob::SpaceInformation>(mapping->getStateSpace());
    EXPECT_THROW(std::make_shared<rco::StateValidityChecker>(
                     si, mapping, std::make_shared<const rc::Checker>(flyingCube(), tableScene()), request),
                 rc::ConfigurationError);
    // The command line says so before loading anything.
    const rc::test::CommandRun run = rc::test::runCli("check --robot x.urdf --states x.csv --padding -1");
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.output.find("--padding: Value -1 not in range"), std::string::npos) << run.output;
}

TEST(BadInput, NanPadding)
{
    const rc::Checker checker(flyingCube(), tableScene());
    for (double padding : {kNan, kInf})
    {
        rc::CollisionRequest request;
        request.padding = padding;
        EXPECT_THROW(checker.isValid(at(0, 0, 3), request), rc::ConfigurationError) << padding;
    }
    // CLI11's range check refuses inf but lets nan through; the command refuses it before loading.
    const rc::test::CommandRun run = rc::test::runCli("check --robot x.urdf --states x.csv --padding nan");
    EXPECT_EQ(run.status, 1);
    EXPECT_NE(run.output.find("rastercheck: error: --padding must be a finite number >= 0"), std::string::npos)
        << run.output;
}

TEST(BadInput, DeviceMemoryLimitOnTheCommandLine)
{
    // A negative or non-integer amount is refused naming the option; a valid one is accepted, and
    // where the run is on the CPU (no device here, or --backend cpu) the verdicts are unchanged.
    for (const char *bad : {"-1", "nan", "1.5"})
    {
        const rc::test::CommandRun run =
            rc::test::runCli(std::string("check --robot x.urdf --states x.csv --device-memory ") + bad);
        EXPECT_NE(run.status, 0) << bad;
        EXPECT_NE(run.output.find("--device-memory"), std::string::npos) << bad << ": " << run.output;
    }
    const std::string folder = makeTempDir("bad");
    const std::string urdf = writeFile(folder + "/arm.urdf", foldingArm());
    const std::string states = writeFile(folder + "/states.csv", "j1,j2\n0,0\n0,3.14159\n");
    const rc::test::CommandRun run =
        rc::test::runCli("check --backend cpu --device-memory 16 --robot " + urdf + " --states " + states);
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("states=2 invalid=1"), std::string::npos) << run.output;
}

TEST(BadInput, ZeroPixelSize)
{
    // 0 means automatic: CollisionModel::defaultPixelSize.
    const rc::Checker checker(flyingCube(), tableScene());
    rc::CollisionRequest automatic, explicitSize;
    automatic.mode = explicitSize.mode = rc::CollisionMode::Raster;
    explicitSize.pixelSize = checker.collisionModel().defaultPixelSize;
    EXPECT_GT(explicitSize.pixelSize, 0.0);
    for (double z : {0.05, 0.0999, 0.1001, 0.3})
    {
        rc::Contact a, b;
        EXPECT_EQ(checker.isValid(at(0.2, 0.1, z), automatic, &a), checker.isValid(at(0.2, 0.1, z), explicitSize, &b));
        EXPECT_EQ(a.position, b.position);
    }
}

TEST(BadInput, NegativePixelSize)
{
    const rc::Checker checker(flyingCube(), tableScene());
    for (double pixel : {-1e-3, kNan, kInf})
    {
        rc::CollisionRequest request;
        request.pixelSize = pixel;
        EXPECT_THROW(checker.isValid(at(0, 0, 3), request), rc::ConfigurationError) << pixel;
    }
}

TEST(BadInput, ImageSideOutOfRange)
{
    const rc::Checker checker(flyingCube(), tableScene());
    for (int side : {0, -5, 4097, 1 << 20})
    {
        rc::CollisionRequest request;
        request.maxImageSide = side;
        EXPECT_THROW(checker.isValid(at(0, 0, 3), request), rc::ConfigurationError) << side;
    }
}

// ---- coordinates far from the origin ----------------------------------------------------------

TEST(BadInput, FarFromOrigin)
{
    // A plant in site coordinates: the blind-spot suites (thin plates, parallel walls, buried
    // bodies, 1e-5 to 1e-3 m grazing contacts) moved 1e6 m away. A float resolves 6 cm there;
    // re-centred on the scene, every verdict still matches the oracle, and contacts are reported
    // in world coordinates.
    const Eigen::Vector3d offset(1e6, -2e6, 3e5);
    for (const rc::test::BlindSpotSuite &original : rc::test::blindSpotSuites(150))
    {
        const rc::test::BlindSpotSuite suite = rc::test::movedBy(original, offset);
        const std::vector<double> &states = suite.states;
        const rc::Checker checker(suite.robot, suite.scene);
        EXPECT_GT(expectModesMatchTheOracle(checker, states, suite.name), suite.numStates() / 10) << suite.name;

        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            for (std::size_t i = 0; i < suite.numStates(); ++i)
            {
                rc::Contact contact;
                if (!checker.isValid(states.data() + 7 * i, request, &contact))
                {
                    EXPECT_LT((contact.position - offset).norm(), 10.0) << suite.name << " " << rc::toString(mode);
                    break;
                }
            }
        }
    }
}

TEST(BadInput, RobotFarFromOrigin)
{
    // An arm on a floating base whose bounds are centred on 0, flown 1e6 m out with no scene: its
    // self-collision pairs are far from CollisionModel::origin, where the float culls are grown by
    // their rounding and the raster, which would miss a third of the contacts, hands its pairs to
    // the exact phase.
    const std::string xml = foldingArm("0 0 0", "floating");
    rc::RobotModelPtr arm = rc::loadUrdfString(xml, ".", {}, "arm.urdf");
    for (int k = 0; k < 3; ++k)
    {
        arm->joints[arm->jointIndex("mount")].lower[k] = -2e6;
        arm->joints[arm->jointIndex("mount")].upper[k] = 2e6;
    }
    arm->finalize();
    const rc::Checker checker(arm, nullptr);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> fold(2.6, 3.7), tilt(-0.05, 0.05);
    std::vector<double> states;
    for (int i = 0; i < 200; ++i)
    {
        // base x y z, quaternion (a small tilt), j1 near 0, j2 near the fold where the tip meets the base
        const Eigen::Quaterniond q(Eigen::AngleAxisd(tilt(rng), Eigen::Vector3d::UnitX()));
        const std::vector<double> state{1e6 + tilt(rng), -1e6,  12345.0,   q.x(),    q.y(),
                                        q.z(),           q.w(), tilt(rng), fold(rng)};
        states.insert(states.end(), state.begin(), state.end());
    }
    const std::size_t colliding = expectModesMatchTheOracle(checker, states, "far arm", false);
    EXPECT_GT(colliding, 20u);
    EXPECT_LT(colliding, 180u);
}

// ---- the table --------------------------------------------------------------------------------

TEST(BadInputTable, EveryRowHasExactlyOneTestAndEveryTestARow)
{
    // Rows: "| `id` | input | what the user sees | `BadInput.Name` |".
    auto trim = [](const std::string &text)
    {
        const std::size_t first = text.find_first_not_of(" `"), last = text.find_last_not_of(" `");
        return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
    };
    std::ifstream doc(rc::test::sourcePath("docs/bad-input.md"));
    ASSERT_TRUE(doc) << "docs/bad-input.md";
    std::vector<std::string> rows;
    std::set<std::string> ids;
    for (std::string line; std::getline(doc, line);)
    {
        std::vector<std::string> cells;
        std::istringstream split(line);
        for (std::string cell; std::getline(split, cell, '|');)
            cells.push_back(trim(cell));
        const std::string prefix = "BadInput.";
        if (line.empty() || line[0] != '|' || cells.size() != 5 || cells[4].compare(0, prefix.size(), prefix) != 0)
            continue;
        EXPECT_EQ(cells[1].find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-"), std::string::npos)
            << "id '" << cells[1] << "' is not kebab-case";
        EXPECT_TRUE(ids.insert(cells[1]).second) << "id used twice: " << cells[1];
        rows.push_back(cells[4].substr(prefix.size()));
    }
    const std::set<std::string> tableTests(rows.begin(), rows.end());
    EXPECT_EQ(tableTests.size(), rows.size()) << "a test is named by two rows";

    std::ifstream source(rc::test::sourcePath("tests/test_bad_input.cpp"));
    ASSERT_TRUE(source);
    std::stringstream text;
    text << source.rdbuf();
    const std::string code = text.str(), opening = "\nTEST(BadInput, ";
    std::set<std::string> sourceTests;
    for (std::size_t at = code.find(opening); at != std::string::npos; at = code.find(opening, at + 1))
    {
        const std::size_t begin = at + opening.size();
        sourceTests.insert(code.substr(begin, code.find(')', begin) - begin));
    }

    EXPECT_GT(sourceTests.size(), 60u);
    for (const std::string &name : sourceTests)
        EXPECT_TRUE(tableTests.count(name)) << "BadInput." << name << " has no row in docs/bad-input.md";
    for (const std::string &name : tableTests)
        EXPECT_TRUE(sourceTests.count(name)) << "docs/bad-input.md names BadInput." << name << ", which does not exist";
}
