// Penetration depth (device::convexPenetration, DistanceRequest::penetration): analytic depths of
// spheres, boxes, capsules and cylinders; FCL's signed distance (its EPA, through libccd) on convex
// polytopes and its exact sphere routines; the translation test (moving by the depth and a hair
// separates a pair, by less does not); and, for non-convex meshes, the two bounds' claims against
// the exact oracle.

#include <cmath>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include "BackendSuites.h"
#include "NonConvex.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/device/Penetration.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;
namespace rd = rastercheck::device;
using Eigen::Isometry3d;
using Eigen::Vector3d;

using rastercheck::test::randomPose;

namespace
{

/** \brief Half sizes (or radius, half length) each uniform in [least, least + spread]. */
Vector3d randomSizes(std::mt19937_64 &rng, double spread, double least)
{
    std::uniform_real_distribution<double> u(least, least + spread);
    return Vector3d(u(rng), u(rng), u(rng));
}

Vector3d toEigen(const rd::Vec3<double> &v)
{
    return Vector3d(v.x, v.y, v.z);
}

/** \brief A primitive as ConvexShape reads it: box half sizes; sphere radius; cylinder and cone
    radius, half length. */
rd::ConvexShape shape(rd::ConvexKind kind, const Vector3d &size, const Isometry3d &pose)
{
    rd::ConvexShape s{};
    s.kind = kind;
    s.pose = rc::toDevicePose(pose);
    for (int k = 0; k < 3; ++k)
        s.size[k] = size[k];
    return s;
}

/** \brief A capsule's core: its segment along its frame's z axis, half length \a half (its radius is
    convexPenetration's margin). */
struct CapsuleCore
{
    rd::Pose<double> pose;
    double half;
    rd::Vec3<double> operator()(const rd::Vec3<double> &d) const
    {
        return rd::transformPoint(pose, rd::Vec3<double>{0.0, 0.0, rd::inverseRotate(pose, d).z >= 0.0 ? half : -half});
    }
};

/** \brief convexPenetration of two primitives, a sphere as its centre grown by its radius. */
rd::ConvexPenetration depthOf(const rd::ConvexShape &a, const rd::ConvexShape &b, double tolerance)
{
    rd::ConvexShape coreA = a, coreB = b;
    double marginA = 0.0, marginB = 0.0;
    if (a.kind == rd::ConvexKind::Sphere)
        std::swap(marginA, coreA.size[0]);
    if (b.kind == rd::ConvexKind::Sphere)
        std::swap(marginB, coreB.size[0]);
    rd::ConvexPenetration result;
    rd::convexPenetration(rd::ShapeSupport{&coreA}, rd::ShapeSupport{&coreB}, tolerance, result, marginA, marginB);
    return result;
}

/** \brief The shape \a s moved by \a t (world frame). */
rd::ConvexShape moved(rd::ConvexShape s, const Vector3d &t)
{
    s.pose.m[3] += t.x();
    s.pose.m[7] += t.y();
    s.pose.m[11] += t.z();
    return s;
}

/** \brief Do \a a and \a b overlap, by GJK (convexClosest)? */
bool overlap(const rd::ConvexShape &a, const rd::ConvexShape &b)
{
    rd::Vec3<double> onA, onB;
    return rd::convexClosest(a, b, onA, onB) <= 0.0;
}

/** \brief The faces of the convex hull of \a points (in general position), outward, by brute force:
    every triple with all other points behind its plane. */
std::vector<std::array<int, 3>> hullFaces(const std::vector<Vector3d> &points)
{
    std::vector<std::array<int, 3>> faces;
    const int n = static_cast<int>(points.size());
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            for (int k = j + 1; k < n; ++k)
            {
                const Vector3d normal = (points[j] - points[i]).cross(points[k] - points[i]);
                int front = 0, back = 0;
                for (int m = 0; m < n; ++m)
                {
                    const double side = normal.dot(points[m] - points[i]);
                    front += side > 1e-12 ? 1 : 0;
                    back += side < -1e-12 ? 1 : 0;
                }
                if (front == 0)
                    faces.push_back({i, j, k});
                else if (back == 0)
                    faces.push_back({i, k, j});
            }
    return faces;
}

std::vector<Vector3d> randomPoints(std::mt19937_64 &rng, int n, const Vector3d &half)
{
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vector3d> points;
    for (int i = 0; i < n; ++i)
        points.push_back(Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(half));
    return points;
}

std::shared_ptr<fcl::Convexd> fclConvex(const std::vector<Vector3d> &points)
{
    auto faces = std::make_shared<std::vector<int>>();
    const std::vector<std::array<int, 3>> triangles = hullFaces(points);
    for (const auto &t : triangles)
        faces->insert(faces->end(), {3, t[0], t[1], t[2]});
    return std::make_shared<fcl::Convexd>(std::make_shared<const std::vector<Vector3d>>(points),
                                          static_cast<int>(triangles.size()), faces);
}

/** \brief FCL's penetration depth of two overlapping convex solids: minus its signed distance
    (fcl::distance with enable_signed_distance, its EPA through libccd); 0 when it calls them apart. */
double fclDepth(const std::shared_ptr<fcl::CollisionGeometryd> &a, const Isometry3d &poseA,
                const std::shared_ptr<fcl::CollisionGeometryd> &b, const Isometry3d &poseB)
{
    fcl::CollisionObjectd objectA(a, poseA), objectB(b, poseB);
    fcl::DistanceRequestd request;
    request.enable_signed_distance = true;
    request.enable_nearest_points = true;
    request.gjk_solver_type = fcl::GST_LIBCCD;
    request.distance_tolerance = 1e-12;
    fcl::DistanceResultd result;
    fcl::distance(&objectA, &objectB, request, result);
    return std::max(0.0, -result.min_distance);
}

/** \brief The hull of \a points placed by \a pose, as device::PointsSupport reads it. */
struct PlacedPoints
{
    std::vector<double> xyz;
    rd::PointsSupport support;
    PlacedPoints(const std::vector<Vector3d> &points, const Isometry3d &pose)
        : support{nullptr, static_cast<std::uint32_t>(points.size()), rc::toDevicePose(pose), {0, 0, 0}, 1.0}
    {
        for (const Vector3d &p : points)
            xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
        support.points = xyz.data();
    }
};
}  // namespace

TEST(ConvexPenetration, SpheresAreExact)
{
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> radius(0.05, 0.5);
    int overlapping = 0;
    for (int i = 0; i < 500; ++i)
    {
        const double ra = radius(rng), rb = radius(rng);
        // Every tenth pair concentric: every way out is as short.
        const Isometry3d poseA = randomPose(rng, 0.5), poseB = i % 10 == 0 ? poseA : randomPose(rng, 0.5);
        const rd::ConvexShape a = shape(rd::ConvexKind::Sphere, Vector3d(ra, 0, 0), poseA);
        const rd::ConvexShape b = shape(rd::ConvexKind::Sphere, Vector3d(rb, 0, 0), poseB);
        const Vector3d apart = poseA.translation() - poseB.translation();
        const rd::ConvexPenetration r = depthOf(a, b, 1e-9);
        const double expected = std::max(0.0, ra + rb - apart.norm());
        EXPECT_NEAR(r.depth, expected, 1e-12) << "pair " << i;
        if (expected <= 0.0)
            continue;
        ++overlapping;
        EXPECT_TRUE(r.converged);
        EXPECT_NEAR(r.lowerBound, expected, 1e-12);
        const Vector3d out = toEigen(r.separation);
        EXPECT_NEAR(out.norm(), 1.0, 1e-12);
        if (apart.norm() > 1e-9)
        {
            EXPECT_NEAR(out.dot(apart.normalized()), 1.0, 1e-9) << "pair " << i;
        }
        // The deepest points: on either sphere, along the way out.
        EXPECT_NEAR((toEigen(r.onA) - (poseA.translation() - ra * out)).norm(), 0.0, 1e-12);
        EXPECT_NEAR((toEigen(r.onB) - (poseB.translation() + rb * out)).norm(), 0.0, 1e-12);
    }
    EXPECT_GT(overlapping, 200);
}

TEST(ConvexPenetration, BoxesOnFacesEdgesAndCorners)
{
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    // Boxes with parallel axes (a common random rotation): A - B is a box, whose nearest face is
    // the axis of least overlap.
    int overlapping = 0;
    for (int i = 0; i < 300; ++i)
    {
        const Isometry3d frame = randomPose(rng, 1.0);
        const Vector3d halfA = randomSizes(rng, 0.5, 0.05), halfB = randomSizes(rng, 0.5, 0.05);
        const Vector3d offset = 0.7 * Vector3d(u(rng), u(rng), u(rng));
        Isometry3d poseB = frame;
        poseB.translation() += frame.linear() * offset;
        const Vector3d overlapAlong = halfA + halfB - offset.cwiseAbs();
        if (overlapAlong.minCoeff() <= 0.0)
            continue;
        ++overlapping;
        Eigen::Index axis = 0;
        const double expected = overlapAlong.minCoeff(&axis);
        const rd::ConvexPenetration r =
            depthOf(shape(rd::ConvexKind::Box, halfA, frame), shape(rd::ConvexKind::Box, halfB, poseB), 1e-9);
        EXPECT_TRUE(r.converged);
        EXPECT_NEAR(r.depth, expected, 1e-12) << "pair " << i;
        EXPECT_NEAR(r.lowerBound, expected, 1e-12) << "pair " << i;
        // A leaves along that axis, away from B.
        const Vector3d out = frame.linear().col(axis) * (offset[axis] > 0.0 ? -1.0 : 1.0);
        EXPECT_NEAR(toEigen(r.separation).dot(out), 1.0, 1e-9) << "pair " << i;
        EXPECT_NEAR((toEigen(r.onB) - toEigen(r.onA) - expected * out).norm(), 0.0, 1e-12);
    }
    EXPECT_GT(overlapping, 40);

    // An edge into a face and an edge across an edge, delta deep: the shortest way out is back by
    // delta (any other way is at least a box's half width).
    const double delta = 0.01, root2 = std::sqrt(2.0);
    const Isometry3d frame = randomPose(rng, 1.0);
    const auto turned = [&](const Vector3d &axis, const Vector3d &at)
    {
        Isometry3d pose = Isometry3d::Identity();
        pose.linear() = Eigen::AngleAxisd(M_PI / 4, axis).toRotationMatrix();
        pose.translation() = at;
        return frame * pose;
    };
    const Vector3d unit = Vector3d::Ones();
    // B's edge (along y) points -x into A's +x face.
    const rd::ConvexPenetration edgeIntoFace =
        depthOf(shape(rd::ConvexKind::Box, unit, frame),
                shape(rd::ConvexKind::Box, unit, turned(Vector3d::UnitY(), Vector3d(1 + root2 - delta, 0, 0))), 1e-9);
    // A's edge along z (A turned about z) crosses B's edge along y (B turned about y).
    const rd::ConvexPenetration edgeAcrossEdge =
        depthOf(shape(rd::ConvexKind::Box, unit, turned(Vector3d::UnitZ(), Vector3d::Zero())),
                shape(rd::ConvexKind::Box, unit, turned(Vector3d::UnitY(), Vector3d(2 * root2 - delta, 0, 0))), 1e-9);
    for (const rd::ConvexPenetration &r : {edgeIntoFace, edgeAcrossEdge})
    {
        EXPECT_TRUE(r.converged);
        EXPECT_NEAR(r.depth, delta, 1e-12);
        EXPECT_NEAR(r.lowerBound, delta, 1e-12);
        EXPECT_NEAR(toEigen(r.separation).dot(frame.linear() * -Vector3d::UnitX()), 1.0, 1e-9);
    }
}

TEST(ConvexPenetration, SphereAgainstABox)
{
    const Isometry3d frame = Isometry3d(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
    const rd::ConvexShape box = shape(rd::ConvexKind::Box, Vector3d(1.0, 0.5, 0.25), frame);
    const double r = 0.2;
    // Centre outside the +x face, 0.15 from it: 0.05 deep; centre inside, 0.1 below the +z face
    // (the nearest): r + 0.1 deep, out through that face.
    const struct
    {
        Vector3d centre;
        double depth;
        Vector3d out;
    } cases[] = {{Vector3d(1.15, 0.2, 0.1), 0.05, Vector3d::UnitX()},
                 {Vector3d(0.3, -0.1, 0.15), r + 0.1, Vector3d::UnitZ()},
                 {Vector3d(-0.9, 0.45, -0.05), r + 0.05, Vector3d::UnitY()}};
    for (const auto &c : cases)
    {
        const rd::ConvexShape ball =
            shape(rd::ConvexKind::Sphere, Vector3d(r, 0, 0), frame * Isometry3d(Eigen::Translation3d(c.centre)));
        const rd::ConvexPenetration p = depthOf(ball, box, 1e-9);
        EXPECT_TRUE(p.converged);
        EXPECT_NEAR(p.depth, c.depth, 1e-12) << c.centre.transpose();
        EXPECT_NEAR(toEigen(p.separation).dot(frame.linear() * c.out), 1.0, 1e-9) << c.centre.transpose();
    }
}

TEST(ConvexPenetration, Capsules)
{
    // A capsule is its segment grown by its radius: crossing capsules d apart (segments along x and
    // y, d apart along z) are rA + rB - d deep, out along z; segments that cross (d = 0) leave a
    // flat core, whose normal is still the way out.
    const double ra = 0.1, rb = 0.15;
    const Isometry3d frame = Isometry3d(Eigen::AngleAxisd(1.1, Vector3d(3, -1, 2).normalized()));
    for (double d : {0.0, 0.05, 0.2})
    {
        const Isometry3d alongX = frame * Isometry3d(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY()));
        const Isometry3d alongY =
            frame * Eigen::Translation3d(0, 0, -d) * Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX());
        const CapsuleCore a{rc::toDevicePose(alongX), 0.5}, b{rc::toDevicePose(alongY), 0.4};
        rd::ConvexPenetration r;
        EXPECT_TRUE(rd::convexPenetration(a, b, 1e-9, r, ra, rb));
        EXPECT_TRUE(r.converged);
        EXPECT_NEAR(r.depth, ra + rb - d, 1e-12) << "d " << d;
        EXPECT_NEAR(std::abs(toEigen(r.separation).dot(frame.linear() * Vector3d::UnitZ())), 1.0, 1e-9) << "d " << d;
        if (d > 0.0)
        {
            EXPECT_NEAR(toEigen(r.separation).dot(frame.linear() * Vector3d::UnitZ()), 1.0, 1e-9);
        }
    }
    // A capsule lying on a box's top face (z = 0.25), pressed 0.03 into it.
    const rd::ConvexShape box = shape(rd::ConvexKind::Box, Vector3d(1.0, 1.0, 0.25), frame);
    const CapsuleCore lying{rc::toDevicePose(frame * Eigen::Translation3d(0.1, 0.2, 0.25 + ra - 0.03) *
                                             Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY())),
                            0.3};
    rd::ConvexPenetration r;
    EXPECT_TRUE(rd::convexPenetration(lying, rd::ShapeSupport{&box}, 1e-9, r, ra, 0.0));
    EXPECT_NEAR(r.depth, 0.03, 1e-12);
    EXPECT_NEAR(toEigen(r.separation).dot(frame.linear() * Vector3d::UnitZ()), 1.0, 1e-9);
}

// A cylinder on its side pressed into a box's face: its round surface is where EPA only approaches
// the answer, so the tolerance decides how close it gets; a loose one misses by far more.
TEST(ConvexPenetration, CylinderOnItsSideAndTheTolerance)
{
    const Isometry3d frame = Isometry3d(Eigen::AngleAxisd(0.4, Vector3d(1, 1, 0).normalized()));
    const rd::ConvexShape box = shape(rd::ConvexKind::Box, Vector3d(1.0, 1.0, 0.5), frame);
    const double delta = 0.02, radius = 0.2;
    const auto error = [&](double tolerance)
    {
        double worst = 0.0;
        for (double turn : {0.0, 0.3, 1.0, 2.0})  // about its own axis: the rim's samples differ
        {
            const Isometry3d pose = frame * Eigen::Translation3d(0.1, -0.2, 0.5 + radius - delta) *
                                    Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(turn, Vector3d::UnitZ());
            const rd::ConvexPenetration r =
                depthOf(shape(rd::ConvexKind::Cylinder, Vector3d(radius, 0.4, 0), pose), box, tolerance);
            worst = std::max(worst, std::abs(r.depth - delta));
            worst = std::max(worst, std::abs(r.lowerBound - delta));
        }
        return worst;
    };
    const double size = 2.0;  // the pair's extent
    EXPECT_LT(error(rc::kPenetrationTolerance * size), 1e-9 * size);
    EXPECT_GT(error(1e-3 * size), 1e-9 * size);  // a loosened tolerance fails the same check
    // Standing on its flat end: exact whatever the tolerance.
    const Isometry3d standing = frame * Eigen::Translation3d(0.3, 0.1, 0.5 + 0.4 - delta);
    const rd::ConvexPenetration r =
        depthOf(shape(rd::ConvexKind::Cylinder, Vector3d(radius, 0.4, 0), standing), box, 1e-9);
    EXPECT_NEAR(r.depth, delta, 1e-12);
}

// Moving A by the depth and a hair along the way out separates the pair; by the lower bound less a
// hair, in any direction, does not (checked by GJK: polytopes exactly, curved shapes to about 1e-6
// of their size, hence a wider hair there).
TEST(ConvexPenetration, TheDepthIsTheShortestWayOut)
{
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const rd::ConvexKind kinds[] = {rd::ConvexKind::Box, rd::ConvexKind::Sphere, rd::ConvexKind::Cylinder,
                                    rd::ConvexKind::Cone};
    int overlapping = 0, exact = 0;
    double widest = 0.0;  // depth - lower bound
    for (int i = 0; i < 3000; ++i)
    {
        const rd::ConvexKind kindA = kinds[i % 4], kindB = kinds[(i / 4) % 4];
        const rd::ConvexShape a = shape(kindA, randomSizes(rng, 0.4, 0.1), randomPose(rng, 0.3));
        const rd::ConvexShape b = shape(kindB, randomSizes(rng, 0.4, 0.1), randomPose(rng, 0.3));
        const rd::ConvexPenetration r = depthOf(a, b, 1e-9);
        if (!(r.depth > 0.0))
            continue;
        ++overlapping;
        exact += r.converged ? 1 : 0;
        widest = std::max(widest, r.depth - r.lowerBound);
        EXPECT_LE(r.lowerBound, r.depth);
        const bool curved = kindA != rd::ConvexKind::Box || kindB != rd::ConvexKind::Box;
        const double hair = curved ? 1e-4 : 1e-9;
        const Vector3d out = toEigen(r.separation);
        if (r.converged)
        {
            EXPECT_NEAR((toEigen(r.onB) - toEigen(r.onA) - r.depth * out).norm(), 0.0, 1e-6) << "pair " << i;
        }
        EXPECT_FALSE(overlap(moved(a, (r.depth + hair) * out), b)) << "pair " << i;
        if (r.lowerBound <= hair)
            continue;
        EXPECT_TRUE(overlap(moved(a, (r.lowerBound - hair) * out), b)) << "pair " << i;
        for (int k = 0; k < 4; ++k)
            EXPECT_TRUE(overlap(moved(a, (r.lowerBound - hair) * Vector3d(u(rng), u(rng), u(rng)).normalized()), b))
                << "pair " << i;
    }
    std::printf("%d overlapping pairs, %d converged; widest depth - lower bound %.3g m\n", overlapping, exact, widest);
    EXPECT_GT(overlapping, 1500);
    EXPECT_GE(exact, overlapping - overlapping / 100);  // nearly all bounds meet
}

// FCL's signed distance runs its EPA (through libccd) on convex polytopes: random hulls of 12
// points, and boxes, agree to rounding.
TEST(ConvexPenetration, MatchesFclOnConvexHullsAndBoxes)
{
    std::mt19937_64 rng(4);
    int compared = 0;
    double worst = 0.0;
    for (int i = 0; i < 400; ++i)
    {
        const std::vector<Vector3d> pointsA = randomPoints(rng, 12, Vector3d(0.5, 0.3, 0.4));
        const std::vector<Vector3d> pointsB = randomPoints(rng, 12, Vector3d(0.3, 0.5, 0.4));
        const Isometry3d poseA = randomPose(rng, 0.2), poseB = randomPose(rng, 0.2);
        const PlacedPoints a(pointsA, poseA), b(pointsB, poseB);
        rd::ConvexPenetration r;
        const bool ours = rd::convexPenetration(a.support, b.support, 1e-9, r);
        const double theirs = fclDepth(fclConvex(pointsA), poseA, fclConvex(pointsB), poseB);
        if (!ours || theirs <= 0.0)
        {
            EXPECT_LT(std::max(r.depth, theirs), 1e-9) << "hulls " << i;  // both apart, or within rounding
            continue;
        }
        ++compared;
        EXPECT_TRUE(r.converged);
        EXPECT_NEAR(r.depth, theirs, 1e-9) << "hulls " << i;
        EXPECT_NEAR(r.lowerBound, theirs, 1e-9) << "hulls " << i;
        EXPECT_NEAR((toEigen(r.onB) - toEigen(r.onA) - r.depth * toEigen(r.separation)).norm(), 0.0, 1e-9);
        worst = std::max(worst, std::abs(r.depth - theirs));
    }
    for (int i = 0; i < 400; ++i)
    {
        const Vector3d halfA = randomSizes(rng, 0.4, 0.1), halfB = randomSizes(rng, 0.4, 0.1);
        const Isometry3d poseA = randomPose(rng, 0.3), poseB = randomPose(rng, 0.3);
        const double theirs =
            fclDepth(std::make_shared<fcl::Boxd>(2 * halfA), poseA, std::make_shared<fcl::Boxd>(2 * halfB), poseB);
        const rd::ConvexPenetration r =
            depthOf(shape(rd::ConvexKind::Box, halfA, poseA), shape(rd::ConvexKind::Box, halfB, poseB), 1e-9);
        if (theirs <= 0.0)
            continue;
        ++compared;
        EXPECT_NEAR(r.depth, theirs, 1e-9) << "boxes " << i;
        worst = std::max(worst, std::abs(r.depth - theirs));
    }
    std::printf("compared %d overlapping pairs with FCL's signed distance: worst |ours - FCL| %.3g m\n", compared,
                worst);
    EXPECT_GT(compared, 500);
}

// A sphere against a box, a sphere, a cylinder or a capsule: FCL's collide (GST_INDEP) answers those
// with exact formulas of its own.
TEST(ConvexPenetration, MatchesFclsSphereFormulas)
{
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.1, 0.5);
    int compared = 0;
    double worst = 0.0;
    for (int i = 0; i < 800; ++i)
    {
        const double radius = u(rng), sizeX = u(rng), sizeY = u(rng), sizeZ = u(rng);
        const Isometry3d poseA = randomPose(rng, 0.3), poseB = randomPose(rng, 0.3);
        std::shared_ptr<fcl::CollisionGeometryd> other;
        rd::ConvexPenetration r;
        const rd::ConvexShape ball = shape(rd::ConvexKind::Sphere, Vector3d(radius, 0, 0), poseA);
        switch (i % 4)
        {
            case 0:
                other = std::make_shared<fcl::Boxd>(2 * sizeX, 2 * sizeY, 2 * sizeZ);
                r = depthOf(ball, shape(rd::ConvexKind::Box, Vector3d(sizeX, sizeY, sizeZ), poseB), 1e-9);
                break;
            case 1:
                other = std::make_shared<fcl::Sphered>(sizeX);
                r = depthOf(ball, shape(rd::ConvexKind::Sphere, Vector3d(sizeX, 0, 0), poseB), 1e-9);
                break;
            case 2:
                other = std::make_shared<fcl::Cylinderd>(sizeX, 2 * sizeY);
                r = depthOf(ball, shape(rd::ConvexKind::Cylinder, Vector3d(sizeX, sizeY, 0), poseB), 1e-9);
                break;
            default:
            {
                other = std::make_shared<fcl::Capsuled>(sizeX, 2 * sizeY);
                rd::ConvexShape centre = ball;
                centre.size[0] = 0.0;
                rd::convexPenetration(rd::ShapeSupport{&centre}, CapsuleCore{rc::toDevicePose(poseB), sizeY}, 1e-9, r,
                                      radius, sizeX);
            }
        }
        fcl::CollisionObjectd a(std::make_shared<fcl::Sphered>(radius), poseA), b(other, poseB);
        fcl::CollisionRequestd request;
        request.enable_contact = true;
        request.gjk_solver_type = fcl::GST_INDEP;
        fcl::CollisionResultd result;
        if (fcl::collide(&a, &b, request, result) == 0 || r.depth <= 0.0)
            continue;
        ++compared;
        const double theirs = std::abs(result.getContact(0).penetration_depth);
        EXPECT_NEAR(r.depth, theirs, 1e-8) << "pair " << i << " kind " << i % 4;
        worst = std::max(worst, std::abs(r.depth - theirs));
    }
    std::printf("compared %d sphere pairs with FCL's formulas: worst |ours - FCL| %.3g m\n", compared, worst);
    EXPECT_GT(compared, 300);
}

// GJK's distance (convexClosest) is proven by its witnesses: the plane normal to them between the
// shapes. A step that got no closer used to take the farther point as the answer and called
// overlapping pairs (spheres 0.36 deep) apart.
TEST(ConvexPenetration, GjkCallsNoOverlappingPairApart)
{
    std::mt19937_64 rng(7);
    int apart = 0;
    for (int i = 0; i < 20000; ++i)
    {
        const auto random = [&](int kind)
        { return shape(static_cast<rd::ConvexKind>(kind), randomSizes(rng, 0.5, 0.1), randomPose(rng, 0.5)); };
        const rd::ConvexShape a = random(i % 4), b = random((i / 4) % 4);
        rd::Vec3<double> onA, onB;
        const double d = rd::convexClosest(a, b, onA, onB);
        if (!(d > 1e-3))  // GJK is looser near contact on curved shapes
            continue;
        ++apart;
        const rd::Vec3<double> n = (1.0 / d) * (onA - onB);
        const double gap =
            rd::dot(n, rd::supportPoint(a, rd::Vec3<double>{-n.x, -n.y, -n.z})) - rd::dot(n, rd::supportPoint(b, n));
        EXPECT_GT(gap, 0.0) << "pair " << i << ": distance " << d;
    }
    EXPECT_GT(apart, 5000);
}

namespace
{
/** \brief A robot of one link, \a collision (URDF XML), on three prismatic joints along x, y and z:
    its state is the link's translation. Mesh files are read from \a folder. */
rc::RobotModelPtr slidingBody(const std::string &collision, const std::string &folder = ".")
{
    const std::string limit = "<limit lower=\"-5\" upper=\"5\" effort=\"1\" velocity=\"1\"/>";
    const auto slide = [&](const char *name, const char *parent, const char *child, const char *axis) {
        return rc::test::urdfJoint(name, "prismatic", parent, child,
                                   std::string("<axis xyz=\"") + axis + "\"/>" + limit);
    };
    return rc::loadUrdfString(
        rc::test::urdfRobot(rc::test::urdfLink("base") + rc::test::urdfLink("lx") + rc::test::urdfLink("ly") +
                            rc::test::urdfLink("body", collision) + slide("x", "base", "lx", "1 0 0") +
                            slide("y", "lx", "ly", "0 1 0") + slide("z", "ly", "body", "0 0 1")),
        folder);
}

rc::Mesh hullMesh(const std::vector<Vector3d> &points)
{
    rc::Mesh mesh;
    mesh.vertices = points;
    for (const auto &f : hullFaces(points))
        mesh.triangles.push_back(
            {static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]), static_cast<std::uint32_t>(f[2])});
    return mesh;
}

rc::DistanceResult penetrationAt(const rc::Checker &checker, const Vector3d &q)
{
    rc::DistanceRequest request;
    request.penetration = true;
    rc::DistanceResult result;
    checker.distance(q.data(), request, &result);
    return result;
}

bool valid(const rc::Checker &checker, const Vector3d &q)
{
    rc::CollisionRequest exact;
    exact.mode = rc::CollisionMode::Exact;
    return checker.isValid(q.data(), exact);
}

Vector3d randomDirection(std::mt19937_64 &rng)
{
    std::normal_distribution<double> n;
    return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

/** \brief The penetration at \a n states that \a draw gives: \a check(q, penetration) at each one
    that collides; returns how many did. */
template <class Draw, class Check>
int atCollidingStates(const rc::Checker &checker, int n, Draw &&draw, Check &&check)
{
    int colliding = 0;
    for (int i = 0; i < n; ++i)
    {
        const Vector3d q = draw();
        const rc::DistanceResult result = penetrationAt(checker, q);
        if (!result.colliding())
            continue;
        ++colliding;
        check(q, result.penetration);
    }
    return colliding;
}
}  // namespace

TEST(CheckerPenetration, MeasuredOnlyWhenAskedAndColliding)
{
    const rc::Checker checker(
        slidingBody("<collision><geometry><sphere radius=\"0.2\"/></geometry></collision>"),
        rc::loadMoveItSceneString("world:\n  collision_objects:\n    - id: box\n      primitives: "
                                  "[{type: box, dimensions: [1, 1, 1]}]\n      primitive_poses: "
                                  "[{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n"));
    const Vector3d inside(0.55, 0.0, 0.0), apart(0.8, 0.0, 0.0);
    rc::DistanceResult plain;
    checker.distance(inside.data(), rc::DistanceRequest{}, &plain);
    EXPECT_TRUE(plain.colliding());
    EXPECT_TRUE(std::isnan(plain.penetration.depth));
    EXPECT_TRUE(std::isnan(plain.penetration.lowerBound));
    const rc::DistanceResult free = penetrationAt(checker, apart);
    EXPECT_FALSE(free.colliding());
    EXPECT_TRUE(std::isnan(free.penetration.depth));
    const rc::DistanceResult deep = penetrationAt(checker, inside);
    EXPECT_NEAR(deep.penetration.depth, 0.15, 1e-12);
    EXPECT_TRUE(deep.penetration.exact);
    EXPECT_NEAR(deep.penetration.direction.x(), 1.0, 1e-12);
    EXPECT_NEAR((deep.penetration.pointOnComponent - Vector3d(0.35, 0, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((deep.penetration.pointOnOther - Vector3d(0.5, 0, 0)).norm(), 0.0, 1e-12);
}

// A ball against a turned box (its exact shapes): the depth of the ball's centre outside the box is
// its radius less the centre's distance to the box, inside it the radius plus the distance to the
// nearest face; the oracle sees the state free after moving by the depth and a hair, not before.
TEST(CheckerPenetration, BallAgainstABoxIsExact)
{
    const double r = 0.2;
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(M_PI / 6, Vector3d::UnitZ()));
    const Vector3d half(0.5, 0.3, 0.2), centre(0.5, 0.0, 0.0);
    const rc::Checker checker(
        slidingBody("<collision><geometry><sphere radius=\"0.2\"/></geometry></collision>"),
        rc::loadMoveItSceneString(
            "world:\n  collision_objects:\n    - id: box\n      primitives: [{type: box, dimensions: "
            "[1, 0.6, 0.4]}]\n      primitive_poses: [{position: [0.5, 0, 0], orientation: [0, "
            "0, 0.25881904510252074, 0.96592582628906831]}]\n"));
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int colliding = atCollidingStates(
        checker, 300, [&] { return Vector3d(centre + Vector3d(0.8 * u(rng), 0.6 * u(rng), 0.5 * u(rng))); },
        [&](const Vector3d &q, const rc::Penetration &p)
        {
            const Vector3d local = turn.inverse() * (q - centre);
            const Vector3d outside = (local.cwiseAbs() - half).cwiseMax(0.0);
            const double expected =
                outside.norm() > 0.0 ? r - outside.norm() : r + (half - local.cwiseAbs()).minCoeff();
            EXPECT_NEAR(p.depth, expected, 1e-12) << q.transpose();
            EXPECT_TRUE(p.exact);
            EXPECT_NEAR(p.lowerBound, p.depth, 1e-12);
            EXPECT_NEAR((p.pointOnOther - p.pointOnComponent - p.depth * p.direction).norm(), 0.0, 1e-9);
            // The exact mode calls a curved pair within about 1e-6 of touching colliding (convexWithin).
            EXPECT_TRUE(valid(checker, q + (p.depth + 1e-5) * p.direction)) << q.transpose();
            if (p.depth > 1e-7)
            {
                EXPECT_FALSE(valid(checker, q + (p.depth - 1e-7) * p.direction)) << q.transpose();
            }
        });
    EXPECT_GT(colliding, 60);
}

// A convex mesh link against a convex mesh object: exact, and as FCL's signed distance says.
TEST(CheckerPenetration, ConvexMeshesAreExactAndMatchFcl)
{
    const std::string folder = rc::test::makeTempDir("penetration_hulls");
    std::mt19937_64 rng(9);
    std::normal_distribution<double> n;
    const auto roundish = [&](double radius)
    {
        std::vector<Vector3d> points;
        for (int i = 0; i < 24; ++i)
            points.push_back(radius * Vector3d(n(rng), n(rng), 0.6 * n(rng)).normalized());
        return hullMesh(points);
    };
    rc::test::writeFile(folder + "/body.obj", rc::test::objText(roundish(0.3)));
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("rock", roundish(0.5));
    const rc::Checker checker(slidingBody(rc::test::urdfCollisionMesh("body.obj"), folder), scene);
    const rc::Mesh &body = checker.robot().components.at(0).mesh, &rock = checker.scene().objects.at(0).mesh;
    const auto fclRock = fclConvex(rock.vertices), fclBody = fclConvex(body.vertices);
    std::uniform_real_distribution<double> u(-0.7, 0.7);
    double worst = 0.0;
    const int colliding = atCollidingStates(
        checker, 200, [&] { return Vector3d(u(rng), u(rng), u(rng)); },
        [&](const Vector3d &q, const rc::Penetration &p)
        {
            EXPECT_TRUE(p.exact) << q.transpose() << ": " << p.depth << " / " << p.lowerBound;
            const double theirs =
                fclDepth(fclBody, Isometry3d(Eigen::Translation3d(q)), fclRock, Isometry3d::Identity());
            EXPECT_NEAR(p.depth, theirs, 1e-9) << q.transpose();
            worst = std::max(worst, std::abs(p.depth - theirs));
            EXPECT_TRUE(valid(checker, q + (p.depth + 1e-7) * p.direction)) << q.transpose();
            if (p.depth > 1e-7)
            {
                EXPECT_FALSE(valid(checker, q + (p.depth - 1e-7) * p.direction)) << q.transpose();
            }
        });
    std::printf("%d colliding states, worst |ours - FCL| %.3g m\n", colliding, worst);
    EXPECT_GT(colliding, 50);
}

// A link of two cube shells pressed delta into a box that sits in the gap between them: the shells'
// own depth (delta) bounds the depth from below, and is the way out; the hull of both holds the box,
// and its depth (0.35, sideways) is only an upper bound.
TEST(CheckerPenetration, TwoShellsBoundTheDepthFromBothSides)
{
    const std::string folder = rc::test::makeTempDir("penetration_shells");
    rc::test::writeFile(folder + "/two.obj", rc::test::objBox("a", -1, -0.25, -0.25, -0.5, 0.25, 0.25, 0) +
                                                 rc::test::objBox("b", 0.5, -0.25, -0.25, 1, 0.25, 0.25, 8));
    const double delta = 0.01;
    auto scene = std::make_shared<rc::Scene>();
    rc::PrimitiveShape box;
    box.size = Vector3d(0.7 + delta, 0.2, 0.2);
    box.pose = Isometry3d(Eigen::Translation3d(0.15 + delta / 2, 0, 0));
    rc::Mesh boxMesh = rc::makeBox(box.size);
    for (Vector3d &v : boxMesh.vertices)
        v = box.pose * v;
    scene->addObject("box", boxMesh, {box});
    const rc::Checker checker(slidingBody(rc::test::urdfCollisionMesh("two.obj"), folder), scene);
    const Vector3d q = Vector3d::Zero();
    const rc::DistanceResult result = penetrationAt(checker, q);
    ASSERT_TRUE(result.colliding());
    const rc::Penetration &p = result.penetration;
    EXPECT_NEAR(p.lowerBound, delta, 1e-12);
    EXPECT_NEAR(p.depth, 0.35, 1e-12);
    EXPECT_FALSE(p.exact);
    EXPECT_TRUE(valid(checker, q + (p.depth + 1e-9) * p.direction));
    EXPECT_TRUE(valid(checker, q + (delta + 1e-9) * Vector3d::UnitX()));  // the true way out
    std::mt19937_64 rng(10);
    for (int i = 0; i < 200; ++i)
        EXPECT_FALSE(valid(checker, q + (p.lowerBound - 1e-9) * randomDirection(rng)));
}

// A small box pressed 1 mm into the inner wall of a U's notch: the U (one shell, far from convex)
// has no convex body known inside it, so the lower bound is 0; the depth is its hull's, 0.599,
// though 1 mm back into the notch frees it. L bars about the U: the depth always frees them.
TEST(CheckerPenetration, NonConvexMeshesGetTheirHullsDepth)
{
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("u", rc::test::uShape(0.2));
    const rc::Checker box(slidingBody("<collision><geometry><box size=\"0.2 0.2 0.2\"/></geometry></collision>"),
                          scene);
    const Vector3d q(0.499, 1.0, 0.5);
    const rc::DistanceResult pressed = penetrationAt(box, q);
    ASSERT_TRUE(pressed.colliding());
    EXPECT_EQ(pressed.penetration.lowerBound, 0.0);
    EXPECT_NEAR(pressed.penetration.depth, 0.599, 1e-12);
    EXPECT_FALSE(pressed.penetration.exact);
    EXPECT_TRUE(valid(box, q + (pressed.penetration.depth + 1e-9) * pressed.penetration.direction));
    EXPECT_TRUE(valid(box, q + Vector3d(0.001 + 1e-9, 0, 0)));

    const std::string folder = rc::test::makeTempDir("penetration_lbar");
    rc::test::writeFile(folder + "/l.obj", rc::test::objText(rc::test::lBar(1.0)));
    const rc::Checker bar(slidingBody(rc::test::urdfCollisionMesh("l.obj"), folder), scene);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> x(-0.3, 2.3), z(-0.3, 1.3);
    const int colliding = atCollidingStates(
        bar, 300, [&] { return Vector3d(x(rng), x(rng), z(rng)); },
        [&](const Vector3d &at, const rc::Penetration &p)
        {
            EXPECT_EQ(p.lowerBound, 0.0);
            EXPECT_GE(p.depth, 0.0);
            EXPECT_TRUE(valid(bar, at + (p.depth + 1e-9) * p.direction)) << at.transpose();
        });
    std::printf("%d colliding L bar states\n", colliding);
    EXPECT_GT(colliding, 100);
}

// A cube with a shallow dimple in its top (its centre sunk 0.015: close to convex, so it keeps face
// planes) and a small box pressed into the dimple, its bottom 0.02 below the top: the dimple's walls
// come 0.0056 into the box's corners, which is the depth. The cube's hull would say 0.02; the lower
// bound reads the hull shrunk until it lies behind the dimple, which stays below the box (0).
TEST(CheckerPenetration, ADentIsNotInTheLowerBound)
{
    rc::Mesh dimpled;
    for (int i = 0; i < 8; ++i)
        dimpled.vertices.push_back(Vector3d(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5));
    dimpled.vertices.push_back(Vector3d(0, 0, 0.485));
    const std::uint32_t faces[][3] = {{0, 1, 3}, {0, 3, 2}, {0, 4, 5}, {0, 5, 1}, {1, 5, 7}, {1, 7, 3}, {3, 7, 6},
                                      {3, 6, 2}, {2, 6, 4}, {2, 4, 0}, {4, 8, 5}, {5, 8, 7}, {7, 8, 6}, {6, 8, 4}};
    for (const auto &f : faces)
    {
        rc::Mesh::Triangle t{f[0], f[1], f[2]};
        const Vector3d &a = dimpled.vertices[t[0]], &b = dimpled.vertices[t[1]], &c = dimpled.vertices[t[2]];
        if ((b - a).cross(c - a).dot(a + b + c) < 0.0)  // outward: away from the cube's centre
            std::swap(t[1], t[2]);
        dimpled.triangles.push_back(t);
    }
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("dimpled", dimpled);
    const rc::Checker checker(slidingBody("<collision><geometry><box size=\"0.04 0.04 0.04\"/></geometry></collision>"),
                              scene);
    ASSERT_GT(checker.collisionModel().convex.arrays().pieces[1].numPlanes, 0u);  // the cube keeps its planes
    const Vector3d q(0, 0, 0.5), up = Vector3d::UnitZ();
    const rc::DistanceResult result = penetrationAt(checker, q);
    ASSERT_TRUE(result.colliding());
    const rc::Penetration &p = result.penetration;
    EXPECT_NEAR(p.depth, 0.02, 1e-12);
    EXPECT_NEAR(p.direction.dot(up), 1.0, 1e-12);
    EXPECT_EQ(p.lowerBound, 0.0);
    EXPECT_FALSE(p.exact);
    const double depth = 0.485 + 0.03 * 0.02 - (0.5 - 0.02);  // under the box's corners the dimple is 0.4856 high
    EXPECT_LE(p.lowerBound, depth);
    EXPECT_TRUE(valid(checker, q + (depth + 1e-9) * up));
    EXPECT_FALSE(valid(checker, q + (depth - 1e-6) * up));
}

// The Panda's links are close to convex (dents within 0.7 % of their size): each holds its hull
// shrunk towards its centre, which bounds the depth from below. Checked against the exact oracle on
// the pair itself: the component moved by the depth and a hair along the way out is free of the
// other solid, and moved by the lower bound less a hair in any direction is not.
TEST(CheckerPenetration, PandaBoundsHold)
{
    RASTERCHECK_REQUIRE_DATA(root);
    int colliding = 0, bounded = 0, checked = 0;
    double ratio = 0.0;
    for (const char *scenario : {"bookshelf_small", "box", "cage", "table_pick"})
    {
        SCOPED_TRACE(scenario);
        const rc::Problem problem = rc::test::pandaProblem(root, scenario);
        const rc::Checker checker(problem.robot, problem.scene);  // distance queries run on the CPU
        const rc::CollisionModel &model = checker.collisionModel();
        const std::size_t n = 200;
        const std::vector<double> q = rc::test::randomStates(checker.robot(), n, 12);
        rc::DistanceRequest request;
        request.penetration = true;
        std::vector<rc::DistanceResult> batch(n);
        checker.distance(q.data(), n, request, batch.data());
        rc::RobotData data(checker.robot());
        std::mt19937_64 rng(13);
        for (std::size_t i = 0; i < n; ++i)
        {
            const double *state = q.data() + i * checker.dof();
            rc::DistanceResult single;
            checker.distance(state, request, &single);
            if (!single.colliding())
                continue;
            EXPECT_EQ(single.penetration.depth, batch[i].penetration.depth) << "state " << i;
            EXPECT_EQ(single.penetration.lowerBound, batch[i].penetration.lowerBound) << "state " << i;
            const rc::Penetration &p = single.penetration;
            ++colliding;
            ASSERT_LE(p.lowerBound, p.depth);
            if (p.lowerBound > 0.0)
            {
                ++bounded;
                ratio += p.lowerBound / p.depth;
            }
            rc::forwardKinematics(checker.robot(), data, state);
            const std::size_t c = static_cast<std::size_t>(single.component);
            const Isometry3d poseA = data.oMl[static_cast<std::size_t>(model.componentLink[c])];
            const bool environment = single.kind == rc::Contact::Kind::Environment;
            const std::size_t other = static_cast<std::size_t>(environment ? single.object : single.otherComponent);
            const rc::MeshBvh &a = *model.componentBvhs[c];
            const rc::MeshBvh &b = environment ? *model.objectBvhs[other] : *model.componentBvhs[other];
            const Isometry3d poseB =
                environment ? Isometry3d::Identity() : data.oMl[static_cast<std::size_t>(model.componentLink[other])];
            // The oracle reads meshes: a curved primitive's lies outside its exact shape, which the
            // depth is measured on.
            const std::vector<rc::PrimitiveShape> &shapesB =
                environment ? checker.scene().objects[other].shapes : checker.robot().components[other].shapes;
            const auto curved = [](const std::vector<rc::PrimitiveShape> &shapes) {
                return std::any_of(shapes.begin(), shapes.end(),
                                   [](const rc::PrimitiveShape &s) { return s.curved(); });
            };
            if (curved(checker.robot().components[c].shapes) || curved(shapesB))
                continue;
            ++checked;
            const bool closedA = model.components[c].closed;
            const bool closedB = environment ? model.objects[other].closed : model.components[other].closed;
            const auto overlapsAfter = [&](const Vector3d &t)
            { return rc::solidsOverlap(a, Eigen::Translation3d(t) * poseA, closedA, b, poseB, closedB, 0.0); };
            EXPECT_FALSE(overlapsAfter((p.depth + 1e-7) * p.direction)) << "state " << i;
            if (p.lowerBound <= 1e-7)
                continue;
            EXPECT_TRUE(overlapsAfter((p.lowerBound - 1e-7) * p.direction)) << "state " << i;
            for (int k = 0; k < 20; ++k)
                EXPECT_TRUE(overlapsAfter((p.lowerBound - 1e-7) * randomDirection(rng))) << "state " << i;
        }
    }
    std::printf(
        "%d colliding states (%d checked by the oracle), %d with a lower bound above 0 (mean lower / depth "
        "%.3f)\n",
        colliding, checked, bounded, bounded > 0 ? ratio / bounded : 0.0);
    EXPECT_GT(colliding, 100);
    EXPECT_GT(checked, 50);
    EXPECT_GT(bounded, colliding / 2);
}
