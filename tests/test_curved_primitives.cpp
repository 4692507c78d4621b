// Curved primitives decided exactly: the analytic test (device/ConvexDistance.h) against known
// distances and FCL, and the checker on spheres, cylinders and cones 0.1 mm apart and 0.1 mm in,
// whose meshes (1 mm outside the exact shapes) alone would call all of them colliding.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cone.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "NonConvex.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/StageRunner.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/device/ConvexDistance.h"
#include "rastercheck/device/CurvedShapes.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;
namespace rd = rastercheck::device;
using rc::test::urdfJoint;
using rc::test::urdfLink;
using rc::test::urdfRobot;

namespace
{
constexpr double kGap = 1e-4;  // 0.1 mm

rd::ConvexShape shape(rd::ConvexKind kind, const Eigen::Isometry3d &pose, double s0, double s1 = 0, double s2 = 0)
{
    rd::ConvexShape out{};
    out.kind = kind;
    out.pose = rc::toDevicePose(pose);
    out.size[0] = s0;
    out.size[1] = s1;
    out.size[2] = s2;
    return out;
}

Eigen::Isometry3d at(double x, double y, double z, const Eigen::Matrix3d &rotation = Eigen::Matrix3d::Identity())
{
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation;
    pose.translation() = Eigen::Vector3d(x, y, z);
    return pose;
}

// A pair of shapes whose true distance is `distance` (negative: that deep in).
void expectDecided(const rd::ConvexShape &a, const rd::ConvexShape &b, double distance, const char *what)
{
    EXPECT_EQ(rd::convexWithin(a, b, 0.0), distance <= 0) << what << " at " << distance;
    EXPECT_EQ(rd::convexWithin(b, a, 0.0), distance <= 0) << what << " swapped, at " << distance;
    if (distance > 0)  // padding moves the line to the distance
    {
        EXPECT_TRUE(rd::convexWithin(a, b, distance + 1e-6)) << what;
        EXPECT_FALSE(rd::convexWithin(a, b, distance - 1e-6)) << what;
    }
}
}  // namespace

TEST(CurvedPrimitives, AnalyticPairsNearContact)
{
    using K = rd::ConvexKind;
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (double d : {kGap, -kGap})
    {
        // Spheres (radii 0.1 and 0.2) along a skew direction.
        const Eigen::Vector3d u = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
        const Eigen::Vector3d c = (0.3 + d) * u;
        expectDecided(shape(K::Sphere, at(0, 0, 0), 0.1), shape(K::Sphere, at(c.x(), c.y(), c.z()), 0.2), d,
                      "sphere-sphere");
        // Sphere over a tilted box's face centre.
        const Eigen::Vector3d face = tilt * Eigen::Vector3d(0, 0, 0.15 + 0.05 + d);
        expectDecided(shape(K::Box, at(0, 0, 0, tilt), 0.2, 0.3, 0.15),
                      shape(K::Sphere, at(face.x(), face.y(), face.z()), 0.05), d, "box-sphere");
        // Sphere off a cylinder's rim (the circle edge), along the diagonal of the (radial, axial) plane.
        const double s = std::sqrt(0.5);
        const Eigen::Vector3d rim = tilt * Eigen::Vector3d(0.1 + s * (0.05 + d), 0, 0.2 + s * (0.05 + d));
        expectDecided(shape(K::Cylinder, at(0, 0, 0, tilt), 0.1, 0.2),
                      shape(K::Sphere, at(rim.x(), rim.y(), rim.z()), 0.05), d, "cylinder rim-sphere");
        // Parallel cylinders side by side (radii 0.1 and 0.05), and crossed ones.
        expectDecided(shape(K::Cylinder, at(0, 0, 0), 0.1, 0.3), shape(K::Cylinder, at(0.15 + d, 0, 0.1), 0.05, 0.3), d,
                      "parallel cylinders");
        const Eigen::Matrix3d crossed = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
        expectDecided(shape(K::Cylinder, at(0, 0, 0), 0.1, 0.3),
                      shape(K::Cylinder, at(0.15 + d, 0, 0, crossed), 0.05, 0.3), d, "crossed cylinders");
        // Cylinder end cap on a box; a sphere on a cone's apex.
        expectDecided(shape(K::Cylinder, at(0, 0, 0.5 + d), 0.1, 0.2), shape(K::Box, at(0, 0, 0), 0.5, 0.5, 0.3), d,
                      "cylinder cap-box");
        expectDecided(shape(K::Cone, at(0, 0, 0), 0.1, 0.2), shape(K::Sphere, at(0, 0, 0.2 + 0.05 + d), 0.05), d,
                      "cone apex-sphere");
        // A triangle below a sphere.
        rd::ConvexShape triangle{};
        triangle.kind = K::Triangle;
        triangle.corner[0] = {-1, -1, -d};
        triangle.corner[1] = {1, -1, -d};
        triangle.corner[2] = {0, 1, -d};
        expectDecided(shape(K::Sphere, at(0, 0, 0.1), 0.1), triangle, d, "sphere-triangle");
    }
    // One solid inside the other is a collision.
    EXPECT_TRUE(rd::convexWithin(shape(K::Box, at(0, 0, 0), 1, 1, 1), shape(K::Sphere, at(0.1, 0, 0), 0.1), 0.0));
}

TEST(CurvedPrimitives, AgreeWithFclOnRandomPairs)
{
    using K = rd::ConvexKind;
    std::mt19937 random(36);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto randomPose = [&](double spread)
    {
        const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
        return at(spread * (unit(random) - 0.5), spread * (unit(random) - 0.5), spread * (unit(random) - 0.5),
                  q.toRotationMatrix());
    };
    int decided = 0;
    for (int i = 0; i < 3000; ++i)
    {
        const int kindA = i % 4, kindB = (i / 4) % 4;
        auto make = [&](int kind, const Eigen::Isometry3d &pose, rd::ConvexShape &ours)
        {
            const double r = 0.05 + 0.1 * unit(random), l = 0.05 + 0.3 * unit(random);
            const double x = 0.05 + 0.2 * unit(random), y = 0.05 + 0.2 * unit(random);
            std::shared_ptr<fcl::CollisionGeometryd> geometry;
            switch (kind)
            {
                case 0:
                    ours = shape(K::Box, pose, x / 2, y / 2, l / 2);
                    geometry = std::make_shared<fcl::Boxd>(x, y, l);
                    break;
                case 1:
                    ours = shape(K::Sphere, pose, r);
                    geometry = std::make_shared<fcl::Sphered>(r);
                    break;
                case 2:
                    ours = shape(K::Cylinder, pose, r, l / 2);
                    geometry = std::make_shared<fcl::Cylinderd>(r, l);
                    break;
                default:
                    ours = shape(K::Cone, pose, r, l / 2);
                    geometry = std::make_shared<fcl::Coned>(r, l);
                    break;
            }
            return fcl::CollisionObjectd(geometry, pose);
        };
        rd::ConvexShape a{}, b{};
        const fcl::CollisionObjectd fa = make(kindA, randomPose(0.6), a);
        const fcl::CollisionObjectd fb = make(kindB, randomPose(0.6), b);
        fcl::CollisionRequestd request;
        fcl::CollisionResultd result;
        fcl::DistanceRequestd distanceRequest;
        distanceRequest.enable_nearest_points = false;
        fcl::DistanceResultd distance;
        fcl::distance(&fa, &fb, distanceRequest, distance);
        const bool fclCollides = fcl::collide(&fa, &fb, request, result) > 0;
        if (!fclCollides && distance.min_distance < 1e-5)
            continue;  // within FCL's own tolerance of contact
        ++decided;
        EXPECT_EQ(rd::convexWithin(a, b, 0.0), fclCollides)
            << "pair " << i << " kinds " << kindA << "/" << kindB << ", FCL distance " << distance.min_distance;
    }
    EXPECT_GT(decided, 2900);
}

namespace
{
std::string sphereOnSlider(const std::string &extraLinks = "", const std::string &extraJoints = "")
{
    // A sphere (r = 0.1) that slides along x, and whatever the caller adds.
    return urdfRobot(urdfLink("world") +
                     urdfLink("ball", "<collision><geometry><sphere radius=\"0.1\"/></geometry></collision>") +
                     extraLinks +
                     urdfJoint("slide", "prismatic", "world", "ball",
                               "<axis xyz=\"1 0 0\"/><limit lower=\"-2\" upper=\"2\" effort=\"1\" velocity=\"1\"/>") +
                     extraJoints);
}

rc::ScenePtr sceneWith(const std::string &type, const std::string &dimensions, const std::string &position,
                       const std::string &orientation = "[0, 0, 0, 1]")
{
    return rc::loadMoveItSceneString(
        "world:\n  collision_objects:\n    - id: thing\n      primitives: [{type: " + type + ", dimensions: " +
        dimensions + "}]\n      primitive_poses: [{position: " + position + ", orientation: " + orientation + "}]\n");
}

// In safe and exact mode: the sphere at x = contact - 0.1 mm is free, at contact + 0.1 mm collides.
void expectExactLine(const rc::RobotModelConstPtr &robot, const rc::ScenePtr &scene, double contact, const char *what)
{
    const rc::Checker checker(robot, scene);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
    {
        rc::CollisionRequest request;
        request.mode = mode;
        rc::Contact found;
        EXPECT_TRUE(checker.isValid(std::vector<double>{contact - kGap}, request)) << what << " 0.1 mm apart";
        EXPECT_FALSE(checker.isValid(std::vector<double>{contact + kGap}, request, &found)) << what << " 0.1 mm in";
        EXPECT_EQ(found.kind, rc::Contact::Kind::Environment) << what;
        std::vector<double> q{contact - kGap, contact + kGap};
        std::vector<std::uint8_t> valid(2);
        checker.check(q.data(), 2, valid.data(), request);
        EXPECT_EQ(valid, (std::vector<std::uint8_t>{1, 0})) << what << " (batch)";
        // The batched stages (on the host executor, the GPU's code) decide the pair on the exact
        // shapes in their exact phase, with nothing left to the host.
        const rc::StagedBackend staged(checker.collisionModelPtr(),
                                       rc::makeHostStageRunner(checker.collisionModelPtr(), {}));
        std::vector<rc::Contact> contacts(2);
        staged.check(q.data(), 2, valid.data(), contacts.data(), request, 1);
        EXPECT_EQ(valid, (std::vector<std::uint8_t>{1, 0})) << what << " (stages)";
        EXPECT_EQ(contacts[1].kind, rc::Contact::Kind::Environment) << what << " (stages)";
        // The tessellated meshes see the gap as a contact: conservative mode may say so, never the reverse.
        request.mode = rc::CollisionMode::Conservative;
        EXPECT_FALSE(checker.isValid(std::vector<double>{contact + kGap}, request)) << what << " conservative";
    }
}
}  // namespace

TEST(CurvedPrimitives, ShapesAgainstAMeshTreeDecideAsEveryTriangleDoes)
{
    // shapesMeetTree walks the mesh's tree behind the shape's ball and box, after a hinted triangle:
    // the answer must be that of testing every triangle (then the shape's origin inside the closed
    // solid), for long, flat and round shapes near a non-convex mesh, with and without padding.
    const rc::Mesh mesh = rc::test::bookshelf(0.1);
    const rc::MeshBvh bvh(mesh);
    const rd::ExactTree tree = bvh.exactTree();
    const rc::Aabb bounds = mesh.bounds();
    std::mt19937 random(52);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int meets = 0, apart = 0, inside = 0;
    for (int i = 0; i < 600; ++i)
    {
        const auto kind = static_cast<rd::ConvexKind>(i % 4);
        const Eigen::Vector3d centre =
            bounds.min +
            (bounds.max - bounds.min).cwiseProduct(Eigen::Vector3d(unit(random), unit(random), unit(random)));
        const Eigen::Isometry3d pose =
            at(centre.x(), centre.y(), centre.z(), Eigen::Quaterniond::UnitRandom().toRotationMatrix());
        // Long or flat: one size up to half the mesh's, the others down to a millimetre.
        const double big = 0.5 * (bounds.max - bounds.min).maxCoeff() * unit(random);
        const double small = 0.001 + 0.05 * unit(random);
        const rd::ConvexShape placed = shape(kind, pose, kind == rd::ConvexKind::Box ? big : small, big, small);
        const rd::Vec3<double> half = rd::shapeHalfSizes(placed);
        const double reach = std::sqrt(rd::dot(half, half));
        const std::uint32_t solidShapes[2] = {0, 1};
        const rd::CurvedArrays arrays{&placed, &reach, solidShapes};
        const double padding = i % 3 == 0 ? 0.02 : 0.0;
        bool everyTriangle = false;
        std::int32_t meeting = -1;  // the first slot whose triangle the shape meets
        for (std::uint32_t slot = 0; slot < tree.numTriangles && !everyTriangle; ++slot)
            if (rd::convexWithin(placed, rd::slotTriangle(tree, slot), padding))
            {
                everyTriangle = true;
                meeting = static_cast<std::int32_t>(slot);
            }
        const bool originInside =
            !everyTriangle && rd::pointInsideClosedTree(tree, {centre.x(), centre.y(), centre.z()});
        const bool expected = everyTriangle || originInside;
        ASSERT_EQ(rd::shapesMeetTree(arrays, 0, rd::Pose<double>::identity(), tree, true, rd::Pose<double>::identity(),
                                     padding),
                  expected)
            << "shape " << i << " (kind " << i % 4 << ")";
        // A hint (the meshes' contact triangle, tested first) changes no answer, whatever it is.
        for (std::int32_t hint : {meeting, static_cast<std::int32_t>(random() % tree.numTriangles)})
            ASSERT_EQ(rd::shapesMeetTree(arrays, 0, rd::Pose<double>::identity(), tree, true,
                                         rd::Pose<double>::identity(), padding, hint),
                      expected)
                << "shape " << i << " (kind " << i % 4 << "), hint " << hint;
        meets += everyTriangle;
        inside += originInside;
        apart += !expected;
    }
    EXPECT_GT(meets, 100);
    EXPECT_GT(apart, 50);
    EXPECT_GT(inside, 0);  // within a shelf board
}

TEST(CurvedPrimitives, CheckerDecidesSpheresCylindersAndConesExactly)
{
    const rc::RobotModelPtr robot = rc::loadUrdfString(sphereOnSlider(), ".", {}, "ball.urdf");
    // Box face at x = 0.4 (exact as a mesh too), a scene sphere, a cylinder's side, a cone's apex
    // (pointing at the ball), each met by the ball's surface at x + 0.1.
    expectExactLine(robot, sceneWith("box", "[0.2, 0.2, 0.2]", "[0.5, 0, 0]"), 0.3, "box");
    expectExactLine(robot, sceneWith("sphere", "[0.15]", "[0.6, 0.03, 0.02]"),
                    0.6 - std::sqrt(0.25 * 0.25 - 0.03 * 0.03 - 0.02 * 0.02), "sphere");
    // Turned about its axis by 0.3 rad, so that no face of its mesh is tangent along x.
    expectExactLine(robot, sceneWith("cylinder", "[0.4, 0.1]", "[0.5, 0, 0]", "[0, 0, 0.1494381, 0.9887711]"), 0.3,
                    "cylinder");
    // Cone (height 0.2, radius 0.1) turned so that its apex points along -x, at x = 0.4.
    expectExactLine(robot, sceneWith("cone", "[0.2, 0.1]", "[0.5, 0, 0]", "[0, -0.7071068, 0, 0.7071068]"), 0.3,
                    "cone");
}

TEST(CurvedPrimitives, SphereAgainstAMeshLinkAndInsideIt)
{
    // The sliding ball against a link whose collision element is a mesh (a 1 m cube centred at
    // x = 1): the ball's exact shape against the cube's triangles, and inside the cube.
    const std::string folder = rc::test::makeTempDir("curved");
    rc::test::writeFile(folder + "/cube.obj", rc::test::kCubeObj);
    const std::string cube = "<collision><geometry><mesh filename=\"cube.obj\"/></geometry></collision>";
    const rc::RobotModelPtr robot = rc::loadUrdfString(
        sphereOnSlider(urdfLink("block", cube), urdfJoint("fix", "fixed", "world", "block", "<origin xyz=\"1 0 0\"/>")),
        folder, {}, "ball.urdf");
    const rc::Checker checker(robot, nullptr);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
    {
        rc::CollisionRequest request;
        request.mode = mode;
        // Cube face at x = 0.5: the ball touches at x = 0.4.
        EXPECT_TRUE(checker.isValid(std::vector<double>{0.4 - kGap}, request));
        EXPECT_FALSE(checker.isValid(std::vector<double>{0.4 + kGap}, request));
        EXPECT_FALSE(checker.isValid(std::vector<double>{1.0}, request));  // wholly inside
        const std::vector<rc::Contact> contacts = checker.contacts(std::vector<double>{0.4 - kGap}.data(), request);
        EXPECT_TRUE(contacts.empty());
    }
}

TEST(CurvedPrimitives, FetchBookshelfSmallProblem77GoalIsFree)
{
    // head_pan_link's sphere 0.193 mm from upperarm_roll_link (FCL's distance): the sphere's mesh,
    // up to 1 mm outside it, made this a collision before.
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string fetch = root + "/mbm/fetch/";
    rc::ProblemSource source;
    source.urdfPath = fetch + "fetch.urdf";
    source.srdfPath = fetch + "fetch.srdf";
    source.scenePath = fetch + "problems/bookshelf_small_fetch/scene0077.yaml";
    const rc::Problem problem = rc::loadProblem(source);
    const rc::MotionPlanRequest request =
        rc::loadMoveItRequest(fetch + "problems/bookshelf_small_fetch/request0077.yaml");
    const rastercheck::ompl::StateMapping mapping(problem.robot);
    std::vector<double> goal = rastercheck::ompl::configurationFromJoints(mapping, request.goalJoints, "goal");
    goal = rastercheck::ompl::ontoBounds(mapping, goal, "goal");
    const rc::Checker checker(problem.robot, problem.scene);
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
    {
        rc::CollisionRequest exact;
        exact.mode = mode;
        rc::Contact contact;
        EXPECT_TRUE(checker.isValid(goal, exact, &contact)) << checker.describe(contact);
        // 0.193 mm: a padding of 0.3 mm makes it a contact of that very pair.
        exact.padding = 3e-4;
        bool named = false;
        for (const rc::Contact &c : checker.contacts(goal.data(), exact))
        {
            const std::string text = checker.describe(c);
            named = named || (text.find("head_pan_link") != std::string::npos &&
                              text.find("upperarm_roll_link") != std::string::npos);
        }
        EXPECT_TRUE(named);
    }
}
