#include "rastercheck/geometry/TriangleTests.h"

#include "rastercheck/device/SolidRelation.h"
#include "rastercheck/device/TriangleTests.h"
#include "rastercheck/geometry/EigenDevice.h"

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;

}  // namespace

bool trianglesIntersect(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                        Vec *point)
{
    device::Vec3<double> at{0.0, 0.0, 0.0};
    const bool meet = device::trianglesIntersect(toDevice(p0), toDevice(p1), toDevice(p2), toDevice(q0), toDevice(q1),
                                                 toDevice(q2), point ? &at : nullptr);
    if (meet && point)
        *point = toEigen(at);
    return meet;
}

double triangleDistance(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                        Vec *pointOnP, Vec *pointOnQ)
{
    device::Vec3<double> onP{0.0, 0.0, 0.0}, onQ{0.0, 0.0, 0.0};
    const double distance = device::triangleDistance(toDevice(p0), toDevice(p1), toDevice(p2), toDevice(q0),
                                                     toDevice(q1), toDevice(q2), &onP, &onQ);
    if (pointOnP)
        *pointOnP = toEigen(onP);
    if (pointOnQ)
        *pointOnQ = toEigen(onQ);
    return distance;
}

bool trianglesWithin(const Vec &p0, const Vec &p1, const Vec &p2, const Vec &q0, const Vec &q1, const Vec &q2,
                     double distance, Vec *point)
{
    device::Vec3<double> at{0.0, 0.0, 0.0};
    const bool within = device::trianglesWithin(toDevice(p0), toDevice(p1), toDevice(p2), toDevice(q0), toDevice(q1),
                                                toDevice(q2), distance, point ? &at : nullptr);
    if (within && point)
        *point = toEigen(at);
    return within;
}

int rayTriangle(const Vec &origin, const Vec &direction, const Vec &a, const Vec &b, const Vec &c, double tolerance,
                double &t)
{
    return device::rayCrossesTriangle(toDevice(origin), toDevice(direction), toDevice(a), toDevice(b), toDevice(c),
                                      tolerance, t);
}
}  // namespace rastercheck
