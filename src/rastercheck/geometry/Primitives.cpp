#include "rastercheck/geometry/Primitives.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "rastercheck/core/Error.h"

namespace rastercheck
{
namespace
{
void requirePositive(double value, const char *what)
{
    if (!std::isfinite(value) || value <= 0.0)
        throw ConfigurationError(std::string("primitive ") + what + " must be a positive finite number, got " +
                                 std::to_string(value));
}

// Smallest number of sides of a regular polygon circumscribed about a circle of radius r whose
// corners stay within maxError of the circle: r / cos(pi / n) - r <= maxError.
int polygonSides(double radius, double maxError)
{
    const double halfAngle = std::acos(radius / (radius + maxError));
    const double sides = std::ceil(M_PI / halfAngle);
    int n = static_cast<int>(std::clamp(sides, 3.0, static_cast<double>(kMaxPrimitiveSegments)));
    // acos rounding may leave the bound a hair above maxError; one more side fixes it.
    while (n < kMaxPrimitiveSegments && radius / std::cos(M_PI / n) - radius > maxError)
        ++n;
    return n;
}

// Ring of n vertices at height z on the polygon circumscribed about radius r.
void addRing(Mesh &mesh, int n, double radius, double z)
{
    const double circumradius = radius / std::cos(M_PI / n);
    for (int i = 0; i < n; ++i)
    {
        const double angle = 2.0 * M_PI * i / n;
        mesh.vertices.emplace_back(circumradius * std::cos(angle), circumradius * std::sin(angle), z);
    }
}

std::uint32_t index(std::size_t i)
{
    return static_cast<std::uint32_t>(i);
}
}  // namespace

Mesh makeBox(const Eigen::Vector3d &size)
{
    requirePositive(size.x(), "box size x");
    requirePositive(size.y(), "box size y");
    requirePositive(size.z(), "box size z");
    const Eigen::Vector3d h = 0.5 * size;
    Mesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
    // Two counter-clockwise (seen from outside) triangles per face.
    mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    return mesh;
}

Mesh makeCylinder(double radius, double length, double maxError)
{
    requirePositive(radius, "cylinder radius");
    requirePositive(length, "cylinder length");
    requirePositive(maxError, "tessellation error");
    const int n = polygonSides(radius, maxError);
    Mesh mesh;
    addRing(mesh, n, radius, -0.5 * length);
    addRing(mesh, n, radius, 0.5 * length);
    const std::size_t bottom = mesh.vertices.size(), top = bottom + 1;
    mesh.vertices.emplace_back(0.0, 0.0, -0.5 * length);
    mesh.vertices.emplace_back(0.0, 0.0, 0.5 * length);
    for (int i = 0; i < n; ++i)
    {
        const std::size_t a = i, b = (i + 1) % n;
        mesh.triangles.push_back({index(a), index(b), index(n + b)});
        mesh.triangles.push_back({index(a), index(n + b), index(n + a)});
        mesh.triangles.push_back({index(bottom), index(b), index(a)});
        mesh.triangles.push_back({index(top), index(n + a), index(n + b)});
    }
    return mesh;
}

Mesh makeCone(double radius, double length, double maxError)
{
    requirePositive(radius, "cone radius");
    requirePositive(length, "cone length");
    requirePositive(maxError, "tessellation error");
    const int n = polygonSides(radius, maxError);
    Mesh mesh;
    addRing(mesh, n, radius, -0.5 * length);
    const std::size_t bottom = mesh.vertices.size(), apex = bottom + 1;
    mesh.vertices.emplace_back(0.0, 0.0, -0.5 * length);
    mesh.vertices.emplace_back(0.0, 0.0, 0.5 * length);
    for (int i = 0; i < n; ++i)
    {
        const std::size_t a = i, b = (i + 1) % n;
        mesh.triangles.push_back({index(a), index(b), index(apex)});
        mesh.triangles.push_back({index(bottom), index(b), index(a)});
    }
    return mesh;
}

namespace
{
// Latitude-longitude sphere of unit radius with `bands` latitude bands and 2 * bands meridians.
Mesh unitUvSphere(int bands)
{
    const int meridians = 2 * bands;
    Mesh mesh;
    mesh.vertices.emplace_back(0.0, 0.0, -1.0);
    for (int j = 1; j < bands; ++j)
    {
        const double polar = M_PI * j / bands;
        for (int i = 0; i < meridians; ++i)
        {
            const double azimuth = 2.0 * M_PI * i / meridians;
            mesh.vertices.emplace_back(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                                       -std::cos(polar));
        }
    }
    const std::size_t northPole = mesh.vertices.size();
    mesh.vertices.emplace_back(0.0, 0.0, 1.0);
    auto ring = [&](int j, int i) { return index(1 + static_cast<std::size_t>(j - 1) * meridians + (i % meridians)); };
    for (int i = 0; i < meridians; ++i)
    {
        mesh.triangles.push_back({0, ring(1, i + 1), ring(1, i)});
        mesh.triangles.push_back({index(northPole), ring(bands - 1, i), ring(bands - 1, i + 1)});
        for (int j = 1; j + 1 < bands; ++j)
        {
            mesh.triangles.push_back({ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)});
            mesh.triangles.push_back({ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)});
        }
    }
    return mesh;
}

// Distance from the origin of the closest face plane of a convex mesh inscribed in the unit sphere.
double closestFacePlane(const Mesh &mesh)
{
    double closest = 1.0;
    for (const Mesh::Triangle &t : mesh.triangles)
    {
        const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        closest = std::min(closest, std::abs((b - a).cross(c - a).normalized().dot(a)));
    }
    return closest;
}
}  // namespace

Mesh makeSphere(double radius, double maxError)
{
    requirePositive(radius, "sphere radius");
    requirePositive(maxError, "tessellation error");
    // The polyhedron with vertices on the unit sphere contains the ball of radius h (its closest face
    // plane); scaled by radius / h it contains the sphere and its vertices lie radius (1 / h - 1) out.
    // Start from the equatorial cell estimate and refine until the bound holds.
    const double cellAngle = std::acos(radius / (radius + maxError));
    int bands = std::clamp(static_cast<int>(std::floor(M_PI / (2.0 * cellAngle))), 2, kMaxSphereBands);
    Mesh mesh = unitUvSphere(bands);
    double h = closestFacePlane(mesh);
    while (radius / h - radius > maxError && bands < kMaxSphereBands)
    {
        bands = std::min(kMaxSphereBands, bands + std::max(1, bands / 8));
        mesh = unitUvSphere(bands);
        h = closestFacePlane(mesh);
    }
    for (Eigen::Vector3d &v : mesh.vertices)
        v *= radius / h;
    return mesh;
}
}  // namespace rastercheck
