// Distance queries (Checker::distance, surfaceDistance, CurvedSolids::distance): against a
// brute-force minimum over every triangle pair, against FCL's fcl::distance on the same meshes, and
// against the exact validity oracle (distance 0 exactly when the state collides; padding just below
// the distance valid, just above it invalid).

#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "BackendSuites.h"
#include "NonConvex.h"
#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/MeshDistance.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/geometry/TriangleTests.h"
#include "rastercheck/io/MeshLoader.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;
using Eigen::Isometry3d;
using Eigen::Vector3d;

using rastercheck::test::randomPose;

namespace
{

/** \brief The minimum of triangleDistance over every pair of triangles, with both placed in the world. */
double bruteForceDistance(const rc::Mesh &a, const Isometry3d &poseA, const rc::Mesh &b, const Isometry3d &poseB)
{
    std::vector<Vector3d> wa, wb;
    for (const Vector3d &v : a.vertices)
        wa.push_back(poseA * v);
    for (const Vector3d &v : b.vertices)
        wb.push_back(poseB * v);
    double best = std::numeric_limits<double>::infinity();
    for (const rc::Mesh::Triangle &ta : a.triangles)
        for (const rc::Mesh::Triangle &tb : b.triangles)
            best =
                std::min(best, rc::triangleDistance(wa[ta[0]], wa[ta[1]], wa[ta[2]], wb[tb[0]], wb[tb[1]], wb[tb[2]]));
    return best;
}

/** \brief Distance from \a p to triangle \a t of \a mesh placed by \a pose. */
double pointToTriangle(const Vector3d &p, const rc::Mesh &mesh, int t, const Isometry3d &pose)
{
    const rc::Mesh::Triangle &tri = mesh.triangles.at(static_cast<std::size_t>(t));
    return rc::triangleDistance(p, p, p, pose * mesh.vertices[tri[0]], pose * mesh.vertices[tri[1]],
                                pose * mesh.vertices[tri[2]]);
}

double extentOf(const rc::Mesh &a, const rc::Mesh &b)
{
    return (a.bounds().max - a.bounds().min).norm() + (b.bounds().max - b.bounds().min).norm();
}

/** \brief surfaceDistance against the brute-force minimum and against FCL at \a poses random
    placements of \a b about \a a; the witnesses lie on the triangles named, as far apart as the
    distance says. Returns how many placements were apart (so the caller can ask for enough). */
int compareMeshes(const rc::Mesh &a, const rc::Mesh &b, int poses, double spread, unsigned seed)
{
    const rc::MeshBvh bvhA(a), bvhB(b);
    std::mt19937_64 rng(seed);
    const double extent = extentOf(a, b);
    int apart = 0;
    for (int i = 0; i < poses; ++i)
    {
        const Isometry3d poseA = randomPose(rng, 0.1 * spread), poseB = randomPose(rng, spread);
        rc::SurfaceDistance d;
        EXPECT_TRUE(rc::surfaceDistance(bvhA, poseA, bvhB, poseB, std::numeric_limits<double>::infinity(), d));
        const double brute = bruteForceDistance(a, poseA, b, poseB);
        EXPECT_NEAR(d.distance, brute, 1e-12 * extent) << "pose " << i;
        if (brute > 0.0)
        {
            ++apart;
            EXPECT_NEAR(d.distance, rc::test::fclMeshDistance(a, poseA, b, poseB), 1e-9 * extent) << "pose " << i;
        }
        EXPECT_NEAR((d.pointA - d.pointB).norm(), d.distance, 1e-9 * extent);
        EXPECT_LT(pointToTriangle(d.pointA, a, d.triangleA, poseA), 1e-9 * extent);
        EXPECT_LT(pointToTriangle(d.pointB, b, d.triangleB, poseB), 1e-9 * extent);
        // The bounded form: below the distance nothing is found, above it the same distance.
        if (d.distance > 0.0)
        {
            rc::SurfaceDistance capped;
            EXPECT_FALSE(rc::surfaceDistance(bvhA, poseA, bvhB, poseB, 0.999 * d.distance, capped));
            EXPECT_TRUE(rc::surfaceDistance(bvhA, poseA, bvhB, poseB, 1.001 * d.distance, capped));
            EXPECT_EQ(capped.distance, d.distance);
        }
    }
    return apart;
}

double sceneExtent(const rc::Checker &checker)
{
    const rc::Aabb bounds = checker.scene().bounds();
    return (bounds.max - bounds.min).norm();
}

/** \brief Checker::distance at \a n random states of \a checker's robot: against FCL (the same pairs,
    \a exactPrimitives: primitives as FCL shapes) where both call the state apart, against the exact
    oracle everywhere (0 exactly when the state collides; padding just under the distance valid,
    just over it invalid), and the witnesses as far apart as the distance. */
void compareChecker(const rc::Checker &checker, std::size_t n, unsigned seed, bool exactPrimitives, double tolerance,
                    int &apartStates)
{
    const std::vector<double> q = rc::test::randomStates(checker.robot(), n, seed);
    rc::test::FclDistance fcl(checker.collisionModel(), exactPrimitives);
    const double extent = sceneExtent(checker);
    const std::size_t dof = checker.dof();
    std::vector<rc::DistanceResult> results(n);
    checker.distance(q.data(), n, rc::DistanceRequest{}, results.data());
    rc::CollisionRequest exact;
    exact.mode = rc::CollisionMode::Exact;
    for (std::size_t i = 0; i < n; ++i)
    {
        const double *state = q.data() + i * dof;
        const rc::DistanceResult &r = results[i];
        ASSERT_NE(r.kind, rc::Contact::Kind::None) << "state " << i;
        const bool collides = !checker.isValid(state, exact);
        EXPECT_EQ(r.distance <= 0.0, collides) << "state " << i << ": " << checker.describe(r);
        EXPECT_NEAR((r.pointOnComponent - r.pointOnOther).norm(), r.distance, 1e-9 * extent) << "state " << i;
        if (collides)
            continue;
        ++apartStates;
        const double theirs = fcl.distance(state);
        if (theirs > 0.0)
        {
            EXPECT_NEAR(r.distance, theirs, tolerance * extent) << "state " << i << ": " << checker.describe(r);
        }
        rc::CollisionRequest padded = exact;
        padded.padding = r.distance * (1.0 - 1e-6);
        EXPECT_TRUE(checker.isValid(state, padded)) << "state " << i << ": " << checker.describe(r);
        padded.padding = r.distance * (1.0 + 1e-6) + 1e-12 * extent;
        EXPECT_FALSE(checker.isValid(state, padded)) << "state " << i << ": " << checker.describe(r);
    }
}

/** \brief A flat square grid of n x n cells (two triangles each) in the plane z = 0, side 1. */
rc::Mesh flatGrid(int n)
{
    rc::Mesh grid;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            grid.vertices.emplace_back(static_cast<double>(i) / n, static_cast<double>(j) / n, 0.0);
    const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
        {
            grid.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            grid.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return grid;
}
}  // namespace

TEST(SurfaceDistance, MatchesBruteForceAndFclOnNonConvexMeshes)
{
    // An L bar against a U and against a room with a doorway: their concave corners are where a
    // loose node bound would skip the nearest triangles.
    const rc::Mesh bar = rc::test::lBar(1.0), u = rc::test::uShape(0.2), room = rc::test::roomWithDoorway(0.5);
    EXPECT_GT(compareMeshes(bar, u, 60, 1.5, 1), 20);
    EXPECT_GT(compareMeshes(bar, room, 30, 2.5, 2), 10);
}

TEST(SurfaceDistance, MatchesBruteForceAndFclOnPrimitives)
{
    const rc::Mesh sphere = rc::makeSphere(0.3, 0.01), cylinder = rc::makeCylinder(0.2, 0.8, 0.01);
    EXPECT_GT(compareMeshes(sphere, cylinder, 60, 0.8, 3), 20);
}

TEST(SurfaceDistance, MatchesFclOnFclsEnvAndRob)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Mesh env = rc::loadMesh(root + "/meshes/fcl/env.obj"), rob = rc::loadMesh(root + "/meshes/fcl/rob.obj");
    const rc::MeshBvh bvhEnv(env), bvhRob(rob);
    const rc::Aabb bounds = env.bounds();
    const double extent = (bounds.max - bounds.min).norm();
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int apart = 0;
    for (int i = 0; i < 60; ++i)
    {
        Isometry3d pose = randomPose(rng, 0.0);
        pose.translation() = bounds.min + Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(bounds.max - bounds.min);
        rc::SurfaceDistance d;
        ASSERT_TRUE(rc::surfaceDistance(bvhRob, pose, bvhEnv, Isometry3d::Identity(),
                                        std::numeric_limits<double>::infinity(), d));
        const double theirs = rc::test::fclMeshDistance(rob, pose, env, Isometry3d::Identity());
        if (d.distance > 0.0 && theirs > 0.0)
        {
            ++apart;
            EXPECT_NEAR(d.distance, theirs, 1e-9 * extent) << "pose " << i;
        }
        EXPECT_LT(pointToTriangle(d.pointA, rob, d.triangleA, pose), 1e-9 * extent);
        EXPECT_LT(pointToTriangle(d.pointB, env, d.triangleB, Isometry3d::Identity()), 1e-9 * extent);
    }
    EXPECT_GT(apart, 20);
}

TEST(SurfaceDistance, SingleTrianglesMatchTriangleDistance)
{
    // One triangle each: the walk's own tests of a triangle pair (beyond a plane, a corner over a
    // face) decide alone, so every answer must be triangleDistance's, near pairs and slivers included.
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int atCorner = 0;
    for (int trial = 0; trial < 20000; ++trial)
    {
        rc::Mesh a, b;
        for (int k = 0; k < 3; ++k)
        {
            a.vertices.emplace_back(u(rng), u(rng), u(rng));
            b.vertices.emplace_back(u(rng) + 1.5, u(rng), u(rng));
        }
        if (trial % 4 == 1)  // a sliver
            a.vertices[2] = 0.5 * (a.vertices[0] + a.vertices[1]) + Vector3d::Constant(1e-7 * u(rng));
        if (trial % 4 == 2)  // a flat triangle over the other's face
            b.vertices[2] = Vector3d(b.vertices[2].x(), b.vertices[0].y(), b.vertices[0].z() + 0.5);
        a.triangles.push_back({0, 1, 2});
        b.triangles.push_back({0, 1, 2});
        const rc::MeshBvh bvhA(a), bvhB(b);
        Vector3d x, y;
        const double expected = rc::triangleDistance(a.vertices[0], a.vertices[1], a.vertices[2], b.vertices[0],
                                                     b.vertices[1], b.vertices[2], &x, &y);
        rc::SurfaceDistance d;
        ASSERT_TRUE(rc::surfaceDistance(bvhA, Isometry3d::Identity(), bvhB, Isometry3d::Identity(),
                                        std::numeric_limits<double>::infinity(), d));
        ASSERT_NEAR(d.distance, expected, 1e-13) << "trial " << trial;
        ASSERT_NEAR((d.pointA - d.pointB).norm(), d.distance, 1e-12) << "trial " << trial;
        for (int k = 0; k < 3; ++k)  // a corner of either is a closest point
            if (expected > 0.0 && (d.pointA == a.vertices[k] || d.pointB == b.vertices[k]))
            {
                ++atCorner;
                break;
            }
        if (expected > 0.0)
        {
            rc::SurfaceDistance capped;
            ASSERT_FALSE(rc::surfaceDistance(bvhA, Isometry3d::Identity(), bvhB, Isometry3d::Identity(),
                                             expected * (1.0 - 1e-9), capped));
        }
    }
    std::printf("[ info     ] 20000 pairs, %d with a corner as a closest point\n", atCorner);
    EXPECT_GT(atCorner, 5000);
}

TEST(SurfaceDistance, ParallelGridsWhereThousandsOfPairsTie)
{
    // Two fine grids facing each other: every pair of triangles one above the other is at (nearly)
    // the same distance, so the nearest-first walk keeps hundreds of node pairs waiting at once
    // (more than it holds on the stack) and no bound settles the ties.
    const rc::Mesh a = flatGrid(24), b = flatGrid(20);
    const rc::MeshBvh bvhA(a), bvhB(b, 2);
    const double extent = extentOf(a, b);
    for (int k = 0; k < 6; ++k)
    {
        Isometry3d pose = Isometry3d::Identity();
        pose.linear() = (Eigen::AngleAxisd(0.3 * k, Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(k % 2 ? 1e-4 * k : 0.0, Vector3d::UnitX()))
                            .toRotationMatrix();
        pose.translation() = Vector3d(0.1 + 0.05 * k, 0.2 - 0.03 * k, 0.01 * (k + 1));
        rc::SurfaceDistance d;
        ASSERT_TRUE(
            rc::surfaceDistance(bvhA, Isometry3d::Identity(), bvhB, pose, std::numeric_limits<double>::infinity(), d));
        const double brute = bruteForceDistance(a, Isometry3d::Identity(), b, pose);
        EXPECT_NEAR(d.distance, brute, 1e-12 * extent) << "pose " << k;
        EXPECT_NEAR(d.distance, rc::test::fclMeshDistance(a, Isometry3d::Identity(), b, pose), 1e-9 * extent);
        EXPECT_LT(pointToTriangle(d.pointA, a, d.triangleA, Isometry3d::Identity()), 1e-9 * extent);
        EXPECT_LT(pointToTriangle(d.pointB, b, d.triangleB, pose), 1e-9 * extent);
        rc::SurfaceDistance capped;
        EXPECT_FALSE(rc::surfaceDistance(bvhA, Isometry3d::Identity(), bvhB, pose, 0.999 * d.distance, capped));
    }
}

TEST(SurfaceDistance, SolidInsideAnotherIsFound)
{
    const rc::Mesh box = rc::test::blockSolid({rc::test::box(Vector3d(-1, -1, -1), Vector3d(1, 1, 1))});
    const rc::Mesh bar = rc::test::lBar(0.5);
    const rc::MeshBvh outer(box, 1, true), inner(bar);
    Vector3d point;
    EXPECT_TRUE(rc::solidInside(inner, Isometry3d::Identity(), outer, Isometry3d::Identity(), &point));
    EXPECT_LT(point.cwiseAbs().maxCoeff(), 1.0);
    Isometry3d away = Isometry3d::Identity();
    away.translation().x() = 3.0;
    EXPECT_FALSE(rc::solidInside(inner, away, outer, Isometry3d::Identity()));
}

TEST(CheckerDistance, PandaScenesMatchFclAndTheOracle)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const std::size_t n = static_cast<std::size_t>(rc::test::scaledCount(60, "RASTERCHECK_TEST_SCALE"));
    int apart = 0;
    for (const char *scenario : {"bookshelf_small", "box", "cage", "table_pick"})
    {
        SCOPED_TRACE(scenario);
        const rc::Problem problem = rc::test::pandaProblem(root, scenario);
        rc::CheckerOptions options;
        options.backend = rc::BackendChoice::Cpu;
        const rc::Checker checker(problem.robot, problem.scene, options);
        // FCL's GJK measures the scenes' cylinders (libccd, tolerance 1e-6) less exactly than its
        // mesh traversal: 1e-6 of the extent, the agreement target.
        compareChecker(checker, n, 11, true, 1e-6, apart);
    }
    EXPECT_GT(apart, 40);
}

TEST(CheckerDistance, CraneInThePlantMatchesTheOracle)
{
    const rc::Problem &plant = rc::test::plant();
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cpu;
    const rc::Checker checker(plant.robot, plant.scene, options);
    int apart = 0;
    // The crane's components of several shapes stay meshes in FCL (one shape per FCL object), whose
    // cylinders' tessellation lies up to kDefaultPrimitiveError outside the exact shapes we measure:
    // FCL's distance may be that much shorter. The oracle's padding checks stay exact.
    const double tolerance = rc::kDefaultPrimitiveError / sceneExtent(checker);
    compareChecker(checker, static_cast<std::size_t>(rc::test::scaledCount(40, "RASTERCHECK_TEST_SCALE")), 5, true,
                   tolerance, apart);
    EXPECT_GT(apart, 5);
}

TEST(CheckerDistance, BoundedQueryStopsAtTheBound)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    const rc::Checker checker(problem.robot, problem.scene);
    const std::vector<double> q = rc::test::randomStates(checker.robot(), 40, 3);
    int apart = 0;
    for (std::size_t i = 0; i < 40; ++i)
    {
        const double *state = q.data() + i * checker.dof();
        rc::DistanceResult exact;
        checker.distance(state, rc::DistanceRequest{}, &exact);
        if (exact.distance <= 0.0)
            continue;
        ++apart;
        rc::DistanceRequest below;
        below.upperBound = 0.5 * exact.distance;
        rc::DistanceResult capped;
        checker.distance(state, below, &capped);
        EXPECT_TRUE(capped.capped);
        EXPECT_EQ(capped.distance, below.upperBound);
        EXPECT_EQ(capped.kind, rc::Contact::Kind::None);
        rc::DistanceRequest above;
        above.upperBound = 2.0 * exact.distance;
        rc::DistanceResult found;
        checker.distance(state, above, &found);
        EXPECT_FALSE(found.capped);
        EXPECT_EQ(found.distance, exact.distance);
        EXPECT_EQ(found.component, exact.component);
    }
    EXPECT_GT(apart, 5);
}

TEST(CheckerDistance, EnvironmentAndSelfApart)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "cage");
    const rc::Checker checker(problem.robot, problem.scene);
    rc::test::FclDistance fcl(checker.collisionModel(), true);
    const std::vector<double> q = rc::test::randomStates(checker.robot(), 30, 9);
    const double extent = sceneExtent(checker);
    for (std::size_t i = 0; i < 30; ++i)
    {
        const double *state = q.data() + i * checker.dof();
        for (const bool environment : {true, false})
        {
            rc::DistanceRequest request;
            request.checkEnvironment = environment;
            request.checkSelfCollision = !environment;
            rc::DistanceResult r;
            checker.distance(state, request, &r);
            EXPECT_EQ(r.kind, environment ? rc::Contact::Kind::Environment : rc::Contact::Kind::SelfCollision);
            const double theirs = fcl.distance(state, environment, !environment);
            if (r.distance > 0.0 && theirs > 0.0)
            {
                EXPECT_NEAR(r.distance, theirs, 1e-6 * extent) << "state " << i;
            }
        }
    }
}

TEST(CheckerDistance, BadInput)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "box");
    const rc::Checker checker(problem.robot, problem.scene);
    std::vector<double> q(checker.dof(), 0.0);
    q[2] = std::nan("");
    rc::test::LogCapture log;
    rc::DistanceResult r;
    checker.distance(q.data(), rc::DistanceRequest{}, &r);
    EXPECT_EQ(r.kind, rc::Contact::Kind::OutOfBounds);
    EXPECT_EQ(r.coordinate, 2);
    EXPECT_EQ(r.distance, 0.0);
    EXPECT_TRUE(log.warned("not finite"));
    for (const double bad : {0.0, -1.0, std::nan("")})
    {
        rc::DistanceRequest request;
        request.upperBound = bad;
        EXPECT_THROW(checker.distance(q.data(), request, &r), rc::ConfigurationError);
    }
}

TEST(CheckerDistance, BatchOverThreadsEqualsOneAtATime)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "table_pick");
    rc::CheckerOptions options;
    options.threads = 4;
    const rc::Checker checker(problem.robot, problem.scene, options);
    const std::size_t n = 200;
    const std::vector<double> q = rc::test::randomStates(checker.robot(), n, 21);
    std::vector<rc::DistanceResult> batch(n);
    checker.distance(q.data(), n, rc::DistanceRequest{}, batch.data());
    // Four threads calling the single-state form at once, each on a quarter.
    std::vector<rc::DistanceResult> single(n);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back(
            [&, t]
            {
                for (std::size_t i = static_cast<std::size_t>(t); i < n; i += 4)
                    checker.distance(q.data() + i * checker.dof(), rc::DistanceRequest{}, &single[i]);
            });
    for (std::thread &thread : threads)
        thread.join();
    for (std::size_t i = 0; i < n; ++i)
    {
        EXPECT_EQ(batch[i].distance, single[i].distance) << "state " << i;
        EXPECT_EQ(batch[i].component, single[i].component) << "state " << i;
    }
}

namespace
{
/** \brief The CLI's check of \a n random Panda states (box scene) with \a flags: its verdicts file,
    the header and each row's fields, with the states themselves. */
struct CheckRun
{
    std::vector<double> q;
    std::string header;
    std::vector<std::vector<std::string>> rows;
    std::string output;
};

CheckRun runCheckCommand(const std::string &root, const rc::Checker &checker, std::size_t n, const std::string &flags)
{
    const std::string folder = rc::test::makeTempDir("distance_cli");
    const std::string urdf = root + "/mbm/panda/panda.urdf", srdf = root + "/mbm/panda/panda.srdf";
    const std::string scene = root + "/mbm/panda/problems/box_panda/scene0001.yaml";
    CheckRun run;
    run.q = rc::test::randomStates(checker.robot(), n, 31);
    std::ostringstream csv;
    csv << std::setprecision(17);
    for (std::size_t k = 0; k < checker.dof(); ++k)
        csv << (k ? "," : "") << checker.robot().coordinateNames[k];
    csv << '\n';
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < checker.dof(); ++k)
            csv << run.q[i * checker.dof() + k] << (k + 1 < checker.dof() ? "," : "\n");
    const std::string states = rc::test::writeFile(folder + "/states.csv", csv.str());
    const rc::test::CommandRun command =
        rc::test::runCli("check --robot " + urdf + " --srdf " + srdf + " --scene " + scene + " --states " + states +
                         " --out " + folder + "/out.csv " + flags);
    EXPECT_EQ(command.status, 0) << command.output;
    run.output = command.output;
    std::ifstream out(folder + "/out.csv");
    std::getline(out, run.header);
    for (std::string line; std::getline(out, line);)
    {
        std::vector<std::string> fields;
        std::stringstream row(line);
        for (std::string field; std::getline(row, field, ',');)
            fields.push_back(field);
        if (!line.empty() && line.back() == ',')
            fields.emplace_back();  // getline drops a trailing empty field
        run.rows.push_back(fields);
    }
    return run;
}
}  // namespace

TEST(CheckerDistance, CheckCommandWritesTheDistanceColumns)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "box");
    const rc::Checker checker(problem.robot, problem.scene);
    const std::size_t n = 12;
    const CheckRun run = runCheckCommand(root, checker, n, "--distance");
    EXPECT_NE(run.output.find(" min_distance="), std::string::npos) << run.output;
    EXPECT_EQ(run.header,
              "valid,component,object,triangle,x,y,z,reason,distance,distance_component,distance_other,ax,ay,az,bx,by,"
              "bz");
    ASSERT_EQ(run.rows.size(), n);
    for (std::size_t i = 0; i < n; ++i)
    {
        const std::vector<std::string> &fields = run.rows[i];
        ASSERT_EQ(fields.size(), 17u) << "row " << i;
        rc::DistanceResult expected;
        checker.distance(run.q.data() + i * checker.dof(), rc::DistanceRequest{}, &expected);
        EXPECT_NEAR(std::stod(fields[8]), expected.distance, 1e-8 * std::max(1.0, expected.distance)) << "row " << i;
        EXPECT_EQ(fields[9], checker.robot().components[expected.component].name) << "row " << i;
        const Vector3d a(std::stod(fields[11]), std::stod(fields[12]), std::stod(fields[13]));
        const Vector3d b(std::stod(fields[14]), std::stod(fields[15]), std::stod(fields[16]));
        EXPECT_NEAR((a - b).norm(), expected.distance, 1e-7) << "row " << i;
        // A colliding row has distance 0, a free one more.
        EXPECT_EQ(fields[0] == "1", expected.distance > 0.0) << "row " << i;
    }
}

TEST(CheckerDistance, CheckCommandWritesThePenetrationColumns)
{
    // Colliding rows carry the named pair's depth (an upper bound), a proven lower bound and the way
    // out, as Checker::distance with DistanceRequest::penetration gives them; free rows leave them
    // empty.
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "box");
    const rc::Checker checker(problem.robot, problem.scene);
    const std::size_t n = 24;
    const CheckRun run = runCheckCommand(root, checker, n, "--penetration");
    EXPECT_NE(run.output.find(" max_penetration="), std::string::npos) << run.output;
    EXPECT_EQ(run.header,
              "valid,component,object,triangle,x,y,z,reason,distance,distance_component,distance_other,ax,ay,az,bx,by,"
              "bz,penetration,penetration_lower,penetration_exact,px,py,pz");
    ASSERT_EQ(run.rows.size(), n);
    rc::DistanceRequest request;
    request.penetration = true;
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
        const std::vector<std::string> &fields = run.rows[i];
        ASSERT_EQ(fields.size(), 23u) << "row " << i;
        rc::DistanceResult expected;
        checker.distance(run.q.data() + i * checker.dof(), request, &expected);
        if (!expected.colliding())
        {
            for (std::size_t k = 17; k < 23; ++k)
                EXPECT_EQ(fields[k], "") << "row " << i << ", column " << k;
            continue;
        }
        ++colliding;
        const double depth = std::stod(fields[17]), lower = std::stod(fields[18]);
        EXPECT_NEAR(depth, expected.penetration.depth, 1e-8) << "row " << i;
        EXPECT_NEAR(lower, expected.penetration.lowerBound, 1e-8) << "row " << i;
        EXPECT_LE(lower, depth + 1e-9) << "row " << i;
        EXPECT_EQ(fields[19], expected.penetration.exact ? "1" : "0") << "row " << i;
        const Vector3d way(std::stod(fields[20]), std::stod(fields[21]), std::stod(fields[22]));
        if (depth > 0.0)
        {
            EXPECT_NEAR(way.norm(), 1.0, 1e-6) << "row " << i;
        }
    }
    EXPECT_GT(colliding, 0u) << "no colliding state among the random ones";
    EXPECT_LT(colliding, n) << "no free state among the random ones";
}

// A ball (a URDF sphere, measured on its exact shape: CurvedSolids::distance) moved about a U-shaped
// solid: its distance is its centre's distance to the U's surface less its radius, which a scan of
// every triangle gives independently of the tree's node bounds.
TEST(CheckerDistance, BallAgainstAMeshIsItsCentresDistanceLessItsRadius)
{
    const std::string folder = rc::test::makeTempDir("distance_ball");
    rc::ProblemSource source;
    source.scenePath = rc::test::writeFile(folder + "/u.obj", rc::test::objText(rc::test::uShape(0.2)));
    const std::string limit = "<axis xyz=\"%\"/><limit lower=\"-1\" upper=\"3\" effort=\"1\" velocity=\"1\"/>";
    const auto axis = [&](const char *xyz)
    {
        std::string text = limit;
        return text.replace(text.find('%'), 1, xyz);
    };
    source.urdfPath = rc::test::writeFile(
        folder + "/ball.urdf",
        rc::test::urdfRobot(rc::test::urdfLink("base") + rc::test::urdfLink("lx") + rc::test::urdfLink("ly") +
                            rc::test::urdfLink("ball",
                                               "<collision><geometry><sphere radius=\"0.15\"/></geometry>"
                                               "</collision>") +
                            rc::test::urdfJoint("x", "prismatic", "base", "lx", axis("1 0 0")) +
                            rc::test::urdfJoint("y", "prismatic", "lx", "ly", axis("0 1 0")) +
                            rc::test::urdfJoint("z", "prismatic", "ly", "ball", axis("0 0 1"))));
    const rc::Problem problem = rc::loadProblem(source);
    ASSERT_EQ(problem.robot->components.size(), 1u);
    ASSERT_EQ(problem.robot->components[0].shapes.size(), 1u);
    const rc::Checker checker(problem.robot, problem.scene);
    ASSERT_TRUE(checker.collisionModel().curved.refines(0));
    const rc::Mesh &scene = problem.scene->objects.at(0).mesh;  // as loaded (the file's float precision)
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> coordinate(-0.5, 2.5);
    int apart = 0;
    for (int i = 0; i < 200; ++i)
    {
        const Vector3d centre(coordinate(rng), coordinate(rng), coordinate(rng));
        rc::DistanceResult r;
        checker.distance(centre.data(), rc::DistanceRequest{}, &r);
        double toSurface = std::numeric_limits<double>::infinity();
        for (const rc::Mesh::Triangle &t : scene.triangles)
            toSurface = std::min(toSurface, rc::triangleDistance(centre, centre, centre, scene.vertices[t[0]],
                                                                 scene.vertices[t[1]], scene.vertices[t[2]]));
        rc::CollisionRequest exact;
        exact.mode = rc::CollisionMode::Exact;
        if (!checker.isValid(centre.data(), exact))
        {
            EXPECT_EQ(r.distance, 0.0) << centre.transpose();
            continue;
        }
        ++apart;
        EXPECT_NEAR(r.distance, toSurface - 0.15, 1e-9) << centre.transpose() << ": " << checker.describe(r);
        EXPECT_EQ(r.triangle, -1);  // the ball's side is its exact shape
        EXPECT_LT(pointToTriangle(r.pointOnOther, scene, r.otherTriangle, Isometry3d::Identity()), 1e-9);
        EXPECT_NEAR((r.pointOnComponent - centre).norm(), 0.15, 1e-9);
    }
    EXPECT_GT(apart, 100);
}

namespace
{
/** \brief \a request with every pair padded by its padding there plus its rate (row 0 of \a rates)
    times \a t. */
rc::CollisionRequest advanced(const rc::CollisionRequest &request, const rc::PairPadding &rates, double t)
{
    auto padding = std::make_shared<rc::PairPadding>(*request.pairPadding);
    for (std::size_t k = 0; k < padding->environment.size(); ++k)
        padding->environment[k] += rates.environment[k] * t;
    for (std::size_t k = 0; k < padding->self.size(); ++k)
        padding->self[k] += rates.self[k] * t;
    rc::CollisionRequest grown = request;
    grown.pairPadding = padding;
    return grown;
}
}  // namespace

TEST(CheckerFreeRadius, IsTheLongestStepThePairsRatesAllow)
{
    // Per state, random rates and paddings per pair (some self pairs with rate 0): the state is
    // valid with every pair padded by its padding plus its rate x (radius x (1 - 1e-6)) and invalid
    // at (1 + 1e-4), unless the radius is the cap; radius 0 exactly when the state is not valid at
    // its paddings. Exact mode is the oracle.
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "cage");
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cpu;
    const rc::Checker checker(problem.robot, problem.scene, options);
    const rc::CollisionModel &model = checker.collisionModel();
    const std::size_t n = 40;
    const std::vector<double> q = rc::test::randomStates(checker.robot(), n, 21);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int limited = 0, zero = 0, capped = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
        const double *state = q.data() + i * checker.dof();
        rc::PairPadding rates, pads;
        for (std::size_t c = 0; c < model.numComponents(); ++c)
        {
            rates.environment.push_back(0.2 + 2.0 * unit(rng));
            pads.environment.push_back(0.01 * unit(rng));
        }
        for (std::size_t p = 0; p < model.selfPairs.size(); ++p)
        {
            rates.self.push_back(p % 3 == 0 ? 0.0 : unit(rng));
            pads.self.push_back(0.01 * unit(rng));
        }
        rc::CollisionRequest request;
        request.mode = rc::CollisionMode::Exact;
        request.padding = 0.002;
        request.pairPadding = std::make_shared<rc::PairPadding>(pads);
        const double cap = i % 4 == 0 ? 0.004 : 1e3;
        double radius = -1.0;
        checker.freeRadius(state, 1, request, rates, &cap, &radius);
        ASSERT_GE(radius, 0.0);
        ASSERT_LE(radius, cap);
        if (radius == 0.0)
        {
            ++zero;
            EXPECT_FALSE(checker.isValid(state, request)) << "state " << i;
            continue;
        }
        EXPECT_TRUE(checker.isValid(state, advanced(request, rates, radius * (1.0 - 1e-6)))) << "state " << i;
        if (radius == cap)
        {
            ++capped;
            continue;
        }
        ++limited;
        EXPECT_FALSE(checker.isValid(state, advanced(request, rates, radius * (1.0 + 1e-4)))) << "state " << i;
    }
    EXPECT_GT(limited, 5);  // every case occurs
    EXPECT_GT(zero, 2);
    EXPECT_GT(capped, 0);
}

/** \brief freeRadius with ClearanceMeasure::HullBound against the exact one at random states of
    \a problem, random rates and paddings per pair: never longer (the state stays valid, exact mode
    the oracle, with every pair advanced by 1 - 1e-6 of it), 0 where the exact one is 0, and close
    enough that 1 % more than the bound would be longer than the exact step on some states (a
    loosened bound fails). Returns {states whose bound is within 1 % of the exact step, states
    with a positive exact step}. */
std::array<int, 2> compareHullBound(const rc::Problem &problem, std::size_t n, double rateScale, unsigned seed)
{
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cpu;
    const rc::Checker checker(problem.robot, problem.scene, options);
    const rc::CollisionModel &model = checker.collisionModel();
    const std::vector<double> q = rc::test::randomStates(checker.robot(), n, seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::array<int, 2> counts{0, 0};
    for (std::size_t i = 0; i < n; ++i)
    {
        const double *state = q.data() + i * checker.dof();
        rc::PairPadding rates, pads;
        for (std::size_t c = 0; c < model.numComponents(); ++c)
        {
            rates.environment.push_back(rateScale * (0.2 + 2.0 * unit(rng)));
            pads.environment.push_back(0.01 * rateScale * unit(rng));
        }
        for (std::size_t p = 0; p < model.selfPairs.size(); ++p)
        {
            rates.self.push_back(p % 3 == 0 ? 0.0 : rateScale * unit(rng));
            pads.self.push_back(0.01 * rateScale * unit(rng));
        }
        rc::CollisionRequest request;
        request.mode = rc::CollisionMode::Exact;
        request.pairPadding = std::make_shared<rc::PairPadding>(pads);
        const double cap = 1e3;
        double exact = -1.0, bound = -1.0;
        checker.freeRadius(state, 1, request, rates, &cap, &exact);
        checker.freeRadius(state, 1, request, rates, &cap, &bound, rc::ClearanceMeasure::HullBound);
        EXPECT_GE(bound, 0.0) << "state " << i;
        EXPECT_LE(bound, exact) << "state " << i;
        if (exact == 0.0)
        {
            EXPECT_EQ(bound, 0.0) << "state " << i;
            continue;
        }
        ++counts[1];
        if (bound > 0.0)
        {
            EXPECT_TRUE(checker.isValid(state, advanced(request, rates, bound * (1.0 - 1e-6)))) << "state " << i;
        }
        if (1.01 * bound > exact)
            ++counts[0];
    }
    return counts;
}

TEST(CheckerFreeRadius, HullBoundIsNoLongerThanTheExactStep)
{
    // The Panda's links stand well inside their hulls near the joints, so its bounds are rarely
    // within 1 % (soundness is what is checked there); the crane's parts are boxes and plates, whose
    // bounds are the distance within GJK's 1e-3: a bound 1 % looser would be caught on them.
    RASTERCHECK_REQUIRE_DATA(root);
    for (const char *scenario : {"cage", "bookshelf_small", "table_pick"})
    {
        const std::array<int, 2> counts = compareHullBound(rc::test::pandaProblem(root, scenario), 60, 1.0, 3);
        EXPECT_GT(counts[1], 20) << scenario;
        std::printf("%s: the hull bound within 1 %% of the exact step at %d of %d states\n", scenario, counts[0],
                    counts[1]);
    }
    const std::array<int, 2> crane = compareHullBound(rc::test::plant(), 40, 1.0, 8);
    EXPECT_GT(crane[1], 10);
    EXPECT_GT(crane[0], crane[1] / 2);
    std::printf("crane: the hull bound within 1 %% of the exact step at %d of %d states\n", crane[0], crane[1]);
}

TEST(CheckerFreeRadius, HullBoundAmongNonConvexMeshes)
{
    // OMPL.app's Home: a table of five shells flying through a house in patches.
    const char *omplapp = std::getenv("RASTERCHECK_OMPLAPP");
    if (!omplapp)
        GTEST_SKIP() << "RASTERCHECK_OMPLAPP not set";
    const rc::OmplAppProblem home = rc::loadOmplAppProblem(std::string(omplapp) + "/Home.cfg");
    rc::Problem problem;
    problem.robot = home.robot;
    problem.scene = home.scene;
    const std::array<int, 2> counts = compareHullBound(problem, 60, 10.0, 12);
    EXPECT_GT(counts[1], 10);
    EXPECT_GT(counts[0], counts[1] / 2);
    std::printf("Home: the hull bound within 1 %% of the exact step at %d of %d states\n", counts[0], counts[1]);
}

TEST(CheckerFreeRadius, WithUnitRatesIsTheDistanceAndAcceptsOnlyGoodRates)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rc::test::pandaProblem(root, "box");
    const rc::Checker checker(problem.robot, problem.scene);
    const rc::CollisionModel &model = checker.collisionModel();
    const std::size_t n = 20;
    const std::vector<double> q = rc::test::randomStates(checker.robot(), n, 4);
    rc::PairPadding unitRates;
    unitRates.environment.assign(model.numComponents(), 1.0);
    unitRates.self.assign(model.selfPairs.size(), 1.0);
    const std::vector<double> caps(n, 1e3);
    std::vector<double> radii(n);
    checker.freeRadius(q.data(), n, rc::CollisionRequest{}, unitRates, caps.data(), radii.data());
    std::vector<rc::DistanceResult> distances(n);
    checker.distance(q.data(), n, rc::DistanceRequest{}, distances.data());
    for (std::size_t i = 0; i < n; ++i)
    {
        EXPECT_LE(radii[i], distances[i].distance) << "state " << i;
        EXPECT_NEAR(radii[i], distances[i].distance, 1e-8 * (1.0 + distances[i].distance)) << "state " << i;
    }

    double radius = 0.0;
    rc::PairPadding bad = unitRates;
    bad.environment[0] = -1.0;
    EXPECT_THROW(checker.freeRadius(q.data(), 1, rc::CollisionRequest{}, bad, caps.data(), &radius),
                 rc::ConfigurationError);
    bad = unitRates;
    bad.self[0] = std::nan("");
    EXPECT_THROW(checker.freeRadius(q.data(), 1, rc::CollisionRequest{}, bad, caps.data(), &radius),
                 rc::ConfigurationError);
    bad = unitRates;
    bad.rows = 2;  // two rows announced, one given
    EXPECT_THROW(checker.freeRadius(q.data(), 3, rc::CollisionRequest{}, bad, caps.data(), radii.data()),
                 rc::ConfigurationError);
    // A state outside the bounds has no step.
    std::vector<double> outside(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(checker.dof()));
    outside[0] = 1e3;
    checker.freeRadius(outside.data(), 1, rc::CollisionRequest{}, unitRates, caps.data(), &radius);
    EXPECT_EQ(radius, 0.0);
}
