// OMPL.app .cfg problems written here (OMPL.app's own files are not redistributable): robot
// re-centring on the vertex mean, axis-angle starts, 2D problems and planners (bad input:
// test_bad_input.cpp).
#include <array>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/io/MeshLoader.h"
#include "rastercheck/io/OmplAppProblem.h"

namespace rc = rastercheck;
using rc::test::makeTempDir;
using rc::test::writeFile;

namespace
{
// Tetrahedron with corners (5,5,5) + {0, e_x, e_y, e_z}: vertex mean 5.25, box centre 5.5, so the
// two choices of centre differ.
const char *kRobotObj = "v 5 5 5\nv 6 5 5\nv 5 6 5\nv 5 5 6\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// Two closed boxes as two OBJ objects (two assimp nodes).
const char *kWorldObj =
    "o wallA\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n"
    "o wallB\n"
    "v 10 0 0\nv 11 0 0\nv 11 1 0\nv 10 1 0\nv 10 0 2\nv 11 0 2\nv 11 1 2\nv 10 1 2\n"
    "f 9 12 11\nf 9 11 10\nf 13 14 15\nf 13 15 16\nf 9 10 14\nf 9 14 13\nf 12 16 15\nf 12 15 11\n"
    "f 9 13 16\nf 9 16 12\nf 10 11 15\nf 10 15 14\n";

const char *kProblem3d = R"(# a test problem
[problem]
name = tetra
robot = robot.obj
world = world.obj
start.x = 1
start.y = 2
start.z = 3
start.theta = 1.5707963267948966
start.axis.x = 0
start.axis.y = 0
start.axis.z = 2   # not unit length
goal.x = 4
goal.y = 5
goal.z = 6
goal.theta = 0
goal.axis.x = 1
goal.axis.y = 0
goal.axis.z = 0
volume.min.x = -10
volume.min.y = -20
volume.min.z = -30
volume.max.x = 10
volume.max.y = 20
volume.max.z = 30
objective = length
objective.threshold = 12.5

[benchmark]
time_limit=20.0
mem_limit=1000.0
run_count=50

[planner]
rrt=
rrt.range=5
prm=
rrt=
rrt.goal_bias=0.1
)";

// A block with an L-shaped cross-section in the xz plane, extruded along y from 0 to 1: corners
// p0 (0,0) p1 (1,0) p2 (3,0) p3 (3,1) p4 (1,1) p5 (1,3) p6 (0,3), p1 splitting the bottom edge.
// Vertices 1-7 are p0..p6 at y = 0, 8-14 at y = 1. Faces outward; closed. No normals.
const char *kBlockObj =
    "v 0 0 0\nv 1 0 0\nv 3 0 0\nv 3 0 1\nv 1 0 1\nv 1 0 3\nv 0 0 3\n"
    "v 0 1 0\nv 1 1 0\nv 3 1 0\nv 3 1 1\nv 1 1 1\nv 1 1 3\nv 0 1 3\n"
    "f 1 2 5\nf 1 5 6\nf 1 6 7\nf 2 3 4\nf 2 4 5\n"           // y = 0
    "f 8 12 9\nf 8 13 12\nf 8 14 13\nf 9 11 10\nf 9 12 11\n"  // y = 1
    "f 1 8 2\nf 2 8 9\nf 2 9 3\nf 3 9 10\n"                   // bottom, two rectangles
    "f 3 10 4\nf 4 10 11\nf 4 11 5\nf 5 11 12\nf 5 12 6\nf 6 12 13\n"
    "f 6 13 7\nf 7 13 14\nf 7 14 1\nf 1 14 8\n";

// OMPL.app's vertices of an OBJ without normals, from its faces: assimp's GenNormals gives each
// corner of a face the face's normal, and JoinIdenticalVertices then keeps one vertex per (position,
// normal); flat faces only, normals rounded so that coplanar faces share theirs.
std::vector<Eigen::Vector3d> cornersPerFaceNormal(const std::string &objText)
{
    std::vector<Eigen::Vector3d> positions;
    std::set<std::array<double, 6>> corners;
    std::istringstream in(objText);
    std::string line;
    while (std::getline(in, line))
    {
        std::istringstream fields(line);
        std::string kind;
        fields >> kind;
        if (kind == "v")
        {
            Eigen::Vector3d p;
            fields >> p.x() >> p.y() >> p.z();
            positions.push_back(p);
        }
        else if (kind == "f")
        {
            std::array<Eigen::Vector3d, 3> p;
            for (Eigen::Vector3d &corner : p)
            {
                std::string index;
                fields >> index;
                corner = positions.at(std::stoul(index.substr(0, index.find('/'))) - 1);
            }
            const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
            auto rounded = [](double x) { return std::round(x * 1e4) / 1e4 + 0.0; };
            for (const Eigen::Vector3d &c : p)
                corners.insert({c.x(), c.y(), c.z(), rounded(n.x()), rounded(n.y()), rounded(n.z())});
        }
    }
    std::vector<Eigen::Vector3d> vertices;
    for (const auto &c : corners)
        vertices.emplace_back(c[0], c[1], c[2]);
    return vertices;
}

Eigen::Vector3d mean(const std::vector<Eigen::Vector3d> &points)
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d &p : points)
        sum += p;
    return sum / static_cast<double>(points.size());
}

const char *kWideVolume =
    "volume.min.x = -1000\nvolume.min.y = -1000\nvolume.min.z = -1000\n"
    "volume.max.x = 1000\nvolume.max.y = 1000\nvolume.max.z = 1000\n";

// A 3D .cfg for \a robot, start and goal at the origin, then the [problem] lines \a more.
std::string robotCfg(const std::string &robot, const std::string &more = kWideVolume)
{
    return "[problem]\nrobot = " + robot +
           "\nstart.x = 0\nstart.y = 0\nstart.z = 0\nstart.theta = 0\nstart.axis.x = 1\nstart.axis.y = 0\n"
           "start.axis.z = 0\ngoal.x = 0\ngoal.y = 0\ngoal.z = 0\ngoal.theta = 0\ngoal.axis.x = 1\n"
           "goal.axis.y = 0\ngoal.axis.z = 0\n" +
           more;
}

std::string problemFolder()
{
    const std::string folder = makeTempDir("omplapp");
    writeFile(folder + "/robot.obj", kRobotObj);
    writeFile(folder + "/world.obj", kWorldObj);
    return folder;
}
}  // namespace

TEST(OmplApp, ThreeDimensionalProblem)
{
    const std::string folder = problemFolder();
    const rc::OmplAppProblem problem = rc::loadOmplAppProblem(writeFile(folder + "/tetra.cfg", kProblem3d));
    EXPECT_EQ(problem.name, "tetra");
    EXPECT_FALSE(problem.planar);
    EXPECT_EQ(problem.robotMeshPath, folder + "/robot.obj");
    EXPECT_EQ(problem.worldMeshPath, folder + "/world.obj");

    // 90 degrees about z (axis normalised): quaternion (0, 0, sin 45, cos 45), w last.
    const double h = std::sqrt(0.5);
    ASSERT_EQ(problem.start.size(), 7u);
    const std::vector<double> start{1, 2, 3, 0, 0, h, h};
    for (std::size_t i = 0; i < 7; ++i)
        EXPECT_NEAR(problem.start[i], start[i], 1e-12) << i;
    const std::vector<double> goal{4, 5, 6, 0, 0, 0, 1};
    for (std::size_t i = 0; i < 7; ++i)
        EXPECT_NEAR(problem.goal[i], goal[i], 1e-12) << i;

    const rc::RobotModel &robot = *problem.robot;
    EXPECT_EQ(robot.coordinateNames, (std::vector<std::string>{"x", "y", "z", "qx", "qy", "qz", "qw"}));
    EXPECT_EQ(robot.lowerBounds, (std::vector<double>{-10, -20, -30, -1, -1, -1, -1}));
    EXPECT_EQ(robot.upperBounds, (std::vector<double>{10, 20, 30, 1, 1, 1, 1}));
    ASSERT_EQ(robot.numComponents(), 1u);
    // Shifted by the vertex mean (5.25), not the box centre (5.5).
    const rc::Aabb box = robot.components[0].localAabb;
    EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d::Constant(-0.25), 1e-12));
    EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d::Constant(0.75), 1e-12));
    EXPECT_TRUE(robot.components[0].topology.closed);

    ASSERT_EQ(problem.scene->numObjects(), 2u);
    EXPECT_EQ(problem.scene->objects[0].name, "wallA");
    EXPECT_EQ(problem.scene->objects[1].name, "wallB");
    EXPECT_EQ(problem.scene->numTriangles(), 24u);
    EXPECT_TRUE(problem.scene->bounds().max.isApprox(Eigen::Vector3d(11, 1, 2)));

    EXPECT_DOUBLE_EQ(problem.timeLimit, 20.0);
    EXPECT_DOUBLE_EQ(problem.memoryLimit, 1000.0);
    EXPECT_EQ(problem.runCount, 50);
    EXPECT_EQ(problem.objective, "length");
    EXPECT_DOUBLE_EQ(problem.objectiveThreshold, 12.5);
    ASSERT_EQ(problem.planners.size(), 3u);
    EXPECT_EQ(problem.planners[0].first, "rrt");
    EXPECT_EQ(problem.planners[0].second, (std::vector<std::pair<std::string, std::string>>{{"range", "5"}}));
    EXPECT_EQ(problem.planners[1].first, "prm");
    EXPECT_TRUE(problem.planners[1].second.empty());
    EXPECT_EQ(problem.planners[2].second, (std::vector<std::pair<std::string, std::string>>{{"goal_bias", "0.1"}}));
}

TEST(OmplApp, TwoDimensionalProblemKeepsTheRobotHeight)
{
    const std::string folder = problemFolder();
    const std::string cfg = writeFile(folder + "/planar.cfg", R"([problem]
robot = robot.obj
world = world.obj
start.x = 1
start.y = 2
start.theta = 0.5
goal.x = 3
goal.y = 4
goal.theta = -0.5
volume.min.x = 0
volume.min.y = 0
volume.max.x = 50
volume.max.y = 60
)");
    const rc::OmplAppProblem problem = rc::loadOmplAppProblem(cfg);
    EXPECT_TRUE(problem.planar);
    EXPECT_EQ(problem.start, (std::vector<double>{1, 2, 0.5}));
    EXPECT_EQ(problem.goal, (std::vector<double>{3, 4, -0.5}));
    EXPECT_EQ(problem.robot->coordinateNames, (std::vector<std::string>{"x", "y", "yaw"}));
    EXPECT_EQ(problem.robot->lowerBounds, (std::vector<double>{0, 0, -M_PI}));
    EXPECT_EQ(problem.robot->upperBounds, (std::vector<double>{50, 60, M_PI}));
    EXPECT_EQ(problem.robot->joints[0].kind, rc::JointKind::Planar);
    const rc::Aabb box = problem.robot->components[0].localAabb;
    EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d(-0.25, -0.25, 5.0), 1e-12)) << "z shift is 0 in 2D";
    EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d(0.75, 0.75, 6.0), 1e-12));
}

TEST(OmplApp, WithoutVolumeTheWorldBoundsAreUsed)
{
    const std::string folder = problemFolder();
    std::string text = kProblem3d;
    for (const char *axis : {"x", "y", "z"})
        for (const char *side : {"min", "max"})
        {
            const std::string key = std::string("volume.") + side + "." + axis + " = ";
            const std::size_t at = text.find(key);
            text.erase(at, text.find('\n', at) - at + 1);
        }
    const rc::OmplAppProblem problem = rc::loadOmplAppProblem(writeFile(folder + "/novolume.cfg", text));
    EXPECT_EQ(problem.robot->lowerBounds, (std::vector<double>{0, 0, 0, -1, -1, -1, -1}));
    EXPECT_EQ(problem.robot->upperBounds, (std::vector<double>{11, 1, 2, 1, 1, 1, 1}));
}

// OMPL.app reads meshes with GenNormals, so a mesh without normals keeps a corner once per face
// normal around it, and its centre is the mean of those vertices, not of the distinct corners
// (issue 19: FCL's rob.obj sat 75 units away from where OMPL.app puts it).
TEST(OmplApp, RobotWithoutNormalsIsCentredAsOmplAppCentresIt)
{
    const std::string folder = makeTempDir("omplapp");
    writeFile(folder + "/block.obj", kBlockObj);
    const rc::OmplAppProblem problem = rc::loadOmplAppProblem(writeFile(folder + "/block.cfg", robotCfg("block.obj")));

    // By hand: each of the 14 positions has the normal of its end face (-y or +y) and those of the
    // side faces at its corner: two for every corner but p1, where both bottom rectangles face -z.
    // So 2 x (6 x 3 + 2) = 40 vertices with mean x = (3 x (0+3+3+1+1+0) + 2 x 1) / 20 = 1.3, y = 0.5,
    // z = (3 x (0+0+1+1+3+3) + 2 x 0) / 20 = 1.2; the 14 distinct corners' mean is (9/7, 0.5, 8/7).
    const std::vector<Eigen::Vector3d> expected = cornersPerFaceNormal(kBlockObj);
    ASSERT_EQ(expected.size(), 40u);
    EXPECT_TRUE(mean(expected).isApprox(Eigen::Vector3d(1.3, 0.5, 1.2), 1e-12));
    const rc::OmplAppVertices omplApp = rc::loadOmplAppVertices(folder + "/block.obj");
    EXPECT_EQ(omplApp.vertices.size(), 40u);
    EXPECT_TRUE(omplApp.center.isApprox(Eigen::Vector3d(1.3, 0.5, 1.2), 1e-6)) << omplApp.center.transpose();

    const rc::Component &body = problem.robot->components.at(0);
    const rc::Aabb box = body.localAabb;
    EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d(-1.3, -0.5, -1.2), 1e-6)) << box.min.transpose();
    EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d(1.7, 0.5, 1.8), 1e-6)) << box.max.transpose();
    // The geometry keeps its corners joined: 14 vertices, one closed shell.
    EXPECT_EQ(body.mesh.numVertices(), 14u);
    EXPECT_EQ(body.mesh.numTriangles(), 24u);
    EXPECT_TRUE(body.topology.closed) << body.topology.summary();
    EXPECT_EQ(body.topology.shells, 1u);
}

// FCL's rob.obj (shared data): 141 distinct corners, 361 vertices for OMPL.app.
TEST(OmplApp, FclRobotIsCentredOnOmplAppsVertices)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::string robot = root + "/meshes/fcl/rob.obj";
    std::ifstream in(robot);
    if (!in)
        GTEST_SKIP() << "shared data has no " << robot;
    std::ostringstream text;
    text << in.rdbuf();

    const std::vector<Eigen::Vector3d> expected = cornersPerFaceNormal(text.str());
    ASSERT_EQ(expected.size(), 361u);
    const rc::OmplAppVertices omplApp = rc::loadOmplAppVertices(robot);
    EXPECT_EQ(omplApp.vertices.size(), 361u);
    // assimp sums in float as OMPL.app does: within 1e-3 of the double mean (-102.611, -98.850, 30.928).
    EXPECT_LT((omplApp.center - mean(expected)).norm(), 1e-3) << omplApp.center.transpose();
    EXPECT_LT((omplApp.center - Eigen::Vector3d(-102.611, -98.850, 30.928)).norm(), 1e-3);

    const rc::OmplAppProblem problem =
        rc::loadOmplAppProblem(writeFile(makeTempDir("omplapp") + "/rob.cfg", robotCfg(robot)));
    const rc::Component &body = problem.robot->components.at(0);
    const rc::Aabb file = rc::loadMesh(robot).bounds();
    EXPECT_TRUE(body.localAabb.min.isApprox(file.min - omplApp.center, 1e-9));
    EXPECT_TRUE(body.localAabb.max.isApprox(file.max - omplApp.center, 1e-9));
    EXPECT_EQ(body.mesh.numVertices(), 141u);
    EXPECT_EQ(body.mesh.numTriangles(), 216u);
}

// Without volume.*, OMPL.app bounds the positions by the box of every world vertex, a line's too.
TEST(OmplApp, WithoutVolumeTheBoundsIncludeEveryWorldVertex)
{
    const std::string folder = problemFolder();
    writeFile(folder + "/lined.obj", std::string(kWorldObj) + "v -4 7 9\nl 1 17\n");
    const rc::OmplAppProblem problem =
        rc::loadOmplAppProblem(writeFile(folder + "/lined.cfg", robotCfg("robot.obj", "world = lined.obj\n")));
    EXPECT_EQ(problem.scene->numTriangles(), 24u);
    EXPECT_EQ(problem.robot->lowerBounds, (std::vector<double>{-4, 0, 0, -1, -1, -1, -1}));
    EXPECT_EQ(problem.robot->upperBounds, (std::vector<double>{11, 7, 9, 1, 1, 1, 1}));
}
