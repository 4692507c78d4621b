// Tessellated primitives: closed, outward, convex, containing the exact shape, within maxError.
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Primitives.h"

namespace rc = rastercheck;

namespace
{
// Signed distance of p to the plane of each face; the largest is <= 0 inside a convex mesh.
double maxPlaneDistance(const rc::Mesh &mesh, const Eigen::Vector3d &p)
{
    double worst = -std::numeric_limits<double>::infinity();
    for (const rc::Mesh::Triangle &t : mesh.triangles)
    {
        const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        worst = std::max(worst, (b - a).cross(c - a).normalized().dot(p - a));
    }
    return worst;
}

// Distance in the (rho, z) half plane from a point to a convex polygon (0 inside).
double distanceToPolygon2d(const Eigen::Vector2d &p, const std::vector<Eigen::Vector2d> &polygon)
{
    bool inside = true;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < polygon.size(); ++i)
    {
        const Eigen::Vector2d a = polygon[i], b = polygon[(i + 1) % polygon.size()];
        const Eigen::Vector2d edge = b - a;
        const double cross = edge.x() * (p - a).y() - edge.y() * (p - a).x();
        if (cross < 0)
            inside = false;
        const double t = std::clamp((p - a).dot(edge) / edge.squaredNorm(), 0.0, 1.0);
        best = std::min(best, (a + t * edge - p).norm());
    }
    return inside ? 0.0 : best;
}

struct Shape
{
    std::string name;
    rc::Mesh mesh;
    double maxError;
    std::function<double(const Eigen::Vector3d &)> distanceToSolid;  // 0 inside the exact solid
    std::function<Eigen::Vector3d(std::mt19937 &)> sampleSurface;    // a point on the exact surface
};

std::vector<Shape> shapes()
{
    std::vector<Shape> out;
    for (double error : {1e-3, 1e-2})
    {
        const double r = 0.09, length = 0.3;
        out.push_back({"sphere", rc::makeSphere(r, error), error,
                       [r](const Eigen::Vector3d &p) { return std::max(0.0, p.norm() - r); },
                       [r](std::mt19937 &rng) -> Eigen::Vector3d
                       {
                           std::normal_distribution<double> n;
                           return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * r;
                       }});
        // (rho, z) cross-sections of the exact solids, counter-clockwise.
        const std::vector<Eigen::Vector2d> cylinder{
            {0, -length / 2}, {r, -length / 2}, {r, length / 2}, {0, length / 2}};
        const std::vector<Eigen::Vector2d> cone{{0, -length / 2}, {r, -length / 2}, {0, length / 2}};
        for (const auto &[name, section] :
             {std::make_pair(std::string("cylinder"), cylinder), std::make_pair(std::string("cone"), cone)})
        {
            const rc::Mesh mesh =
                name == "cylinder" ? rc::makeCylinder(r, length, error) : rc::makeCone(r, length, error);
            out.push_back({name, mesh, error,
                           [section](const Eigen::Vector3d &p)
                           { return distanceToPolygon2d(Eigen::Vector2d(p.head<2>().norm(), p.z()), section); },
                           [section](std::mt19937 &rng) -> Eigen::Vector3d
                           {
                               // A point on the boundary of the cross-section, spun about z.
                               std::uniform_real_distribution<double> u(0.0, 1.0);
                               const std::size_t edge =
                                   std::uniform_int_distribution<std::size_t>(1, section.size() - 1)(rng);
                               const Eigen::Vector2d a = section[edge - 1], b = section[edge % section.size()];
                               const Eigen::Vector2d q = a + u(rng) * (b - a);
                               const double angle = 2 * M_PI * u(rng);
                               return Eigen::Vector3d(q.x() * std::cos(angle), q.x() * std::sin(angle), q.y());
                           }});
        }
    }
    return out;
}
}  // namespace

TEST(Primitives, BoxIsExactClosedAndOutward)
{
    rc::Mesh box = rc::makeBox(Eigen::Vector3d(1, 2, 3));
    EXPECT_EQ(box.numTriangles(), 12u);
    EXPECT_NEAR(rc::signedVolume(box), 6.0, 1e-12);
    const rc::Aabb bounds = box.bounds();
    EXPECT_TRUE(bounds.min.isApprox(Eigen::Vector3d(-0.5, -1, -1.5)));
    EXPECT_TRUE(bounds.max.isApprox(Eigen::Vector3d(0.5, 1, 1.5)));
    EXPECT_TRUE(rc::cleanMesh(box).closed);
    EXPECT_NEAR(rc::signedVolume(box), 6.0, 1e-12);  // not flipped: already outward
}

TEST(Primitives, CurvedShapesAreClosedOutwardConvexAndContainTheExactShape)
{
    std::mt19937 rng(7);
    for (Shape &shape : shapes())
    {
        SCOPED_TRACE(shape.name + " maxError " + std::to_string(shape.maxError));
        const double before = rc::signedVolume(shape.mesh);
        EXPECT_GT(before, 0.0) << "triangles must be counter-clockwise seen from outside";
        rc::Mesh cleaned = shape.mesh;
        const rc::MeshTopology topology = rc::cleanMesh(cleaned);
        EXPECT_TRUE(topology.closed) << topology.summary();
        EXPECT_EQ(topology.degenerateTriangles, 0u);
        EXPECT_EQ(cleaned.numTriangles(), shape.mesh.numTriangles());

        // Convex: every vertex behind every face plane, so the plane test below is containment.
        for (const Eigen::Vector3d &v : shape.mesh.vertices)
            ASSERT_LE(maxPlaneDistance(shape.mesh, v), 1e-12);
        for (int i = 0; i < 2000; ++i)
            ASSERT_LE(maxPlaneDistance(shape.mesh, shape.sampleSurface(rng)), 1e-12);

        // Deviation: vertices and random points on every face stay within maxError of the solid.
        std::uniform_real_distribution<double> u(0.0, 1.0);
        double worst = 0.0;
        for (const rc::Mesh::Triangle &t : shape.mesh.triangles)
            for (int k = 0; k < 4; ++k)
            {
                double a = u(rng), b = u(rng);
                if (a + b > 1)
                {
                    a = 1 - a;
                    b = 1 - b;
                }
                const Eigen::Vector3d &p0 = shape.mesh.vertices[t[0]], &p1 = shape.mesh.vertices[t[1]],
                                      &p2 = shape.mesh.vertices[t[2]];
                worst = std::max(
                    {worst, shape.distanceToSolid(p0), shape.distanceToSolid(p0 + a * (p1 - p0) + b * (p2 - p0))});
            }
        EXPECT_LE(worst, shape.maxError * (1 + 1e-9));
        EXPECT_GT(worst, 0.2 * shape.maxError) << "tessellation much finer than asked";
    }
}

TEST(Primitives, CylinderUsesTheSmallestSideCountThatMeetsTheError)
{
    // r = 1 m, 1 mm: sides n with 1 / cos(pi / n) - 1 <= 1e-3 first holds at n = 71.
    const rc::Mesh cylinder = rc::makeCylinder(1.0, 2.0, 1e-3);
    EXPECT_EQ(cylinder.numTriangles(), 4u * 71u);
    EXPECT_GT(1.0 / std::cos(M_PI / 70) - 1.0, 1e-3);
    EXPECT_LE(1.0 / std::cos(M_PI / 71) - 1.0, 1e-3);
    // A coarse request still gives a closed triangle prism.
    EXPECT_EQ(rc::makeCylinder(1.0, 1.0, 10.0).numTriangles(), 12u);
    EXPECT_EQ(rc::makeCone(1.0, 1.0, 10.0).numTriangles(), 6u);
}

TEST(Primitives, RejectsNonPositiveOrNonFiniteSizes)
{
    EXPECT_THROW(rc::makeBox(Eigen::Vector3d(1, 0, 1)), rc::ConfigurationError);
    EXPECT_THROW(rc::makeSphere(-1.0, 1e-3), rc::ConfigurationError);
    EXPECT_THROW(rc::makeSphere(1.0, 0.0), rc::ConfigurationError);
    EXPECT_THROW(rc::makeCylinder(std::nan(""), 1.0, 1e-3), rc::ConfigurationError);
    EXPECT_THROW(rc::makeCone(1.0, std::numeric_limits<double>::infinity(), 1e-3), rc::ConfigurationError);
}

TEST(Primitives, AHugeSphereHasBoundedTrianglesAndStillContainsTheSphere)
{
    // One sphere of radius 605 m at the default 1 mm made a million triangles (9.3 s and 855 MB to
    // load a three-line scene): the bands stop at kMaxSphereBands, the mesh still contains the
    // sphere, and its vertices stand out by at most about 1.5e-4 of the radius.
    const double radius = 605.0;
    const rc::Mesh mesh = rc::makeSphere(radius, 1e-3);
    const std::size_t bands = rc::kMaxSphereBands;
    EXPECT_EQ(mesh.numTriangles(), 4 * bands * bands - 4 * bands);
    double nearestPlane = std::numeric_limits<double>::infinity(), farthestVertex = 0.0;
    for (const rc::Mesh::Triangle &t : mesh.triangles)
    {
        const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        nearestPlane = std::min(nearestPlane, (b - a).cross(c - a).normalized().dot(a));
    }
    for (const Eigen::Vector3d &v : mesh.vertices)
        farthestVertex = std::max(farthestVertex, v.norm());
    EXPECT_GE(nearestPlane, radius * (1.0 - 1e-12));      // every face plane outside the sphere
    EXPECT_LE(farthestVertex - radius, 1.6e-4 * radius);  // the cap's deviation
    // Below the cap the asked error still holds: 5 m at 1 mm (about 6 m reaches the cap).
    const rc::Mesh five = rc::makeSphere(5.0, 1e-3);
    double farthestFive = 0.0;
    for (const Eigen::Vector3d &v : five.vertices)
        farthestFive = std::max(farthestFive, v.norm());
    EXPECT_LE(farthestFive - 5.0, 1e-3);
    EXPECT_LT(five.numTriangles(), mesh.numTriangles());
}
