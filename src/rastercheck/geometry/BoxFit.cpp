#include "rastercheck/geometry/BoxFit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;

// Normals within 5 degrees are tried once (a 1e6-triangle terrain's tree: 10.2 s to build with half
// a degree, 8.2 s with this, one triangle per leaf then; the same distance query times on
// OMPL.app's scenes).
constexpr double kSameDirection = 0.996;

const Vec kExtremeDirections[13] = {{1, 0, 0}, {0, 1, 0},  {0, 0, 1}, {1, 1, 1},  {1, 1, -1}, {1, -1, 1}, {1, -1, -1},
                                    {1, 1, 0}, {1, -1, 0}, {1, 0, 1}, {1, 0, -1}, {0, 1, 1},  {0, 1, -1}};

// Half the surface area of the box along \a frame's columns about \a points.
double boxArea(const std::vector<Vec> &points, const Eigen::Matrix3d &frame)
{
    Vec lower = Vec::Constant(std::numeric_limits<double>::infinity()), upper = -lower;
    for (const Vec &p : points)
    {
        const Vec local = frame.transpose() * p;
        lower = lower.cwiseMin(local);
        upper = upper.cwiseMax(local);
    }
    const Vec e = upper - lower;
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

// Of the frames whose third axis is the unit \a normal, the one with the least box about \a points (a
// side of its rectangle along an edge of the projection's hull) replaces \a best when its area is
// below \a bestArea.
void fitAboutNormal(const std::vector<Vec> &points, const Vec &normal, Eigen::Matrix3d &best, double &bestArea,
                    BoxFitScratch &scratch)
{
    const Vec u = normal.unitOrthogonal(), v = normal.cross(u);
    std::vector<Eigen::Vector2d> &plane = scratch.plane, &hull = scratch.hull;
    plane.clear();
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (const Vec &p : points)
    {
        plane.emplace_back(u.dot(p), v.dot(p));
        low = std::min(low, normal.dot(p));
        high = std::max(high, normal.dot(p));
    }
    const double height = high - low;
    // Andrew's monotone chain.
    std::sort(plane.begin(), plane.end(),
              [](const Eigen::Vector2d &a, const Eigen::Vector2d &b)
              { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
    const auto turn = [](const Eigen::Vector2d &o, const Eigen::Vector2d &a, const Eigen::Vector2d &b)
    { return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x()); };
    hull.resize(2 * plane.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < plane.size(); ++i)
    {
        while (k >= 2 && turn(hull[k - 2], hull[k - 1], plane[i]) <= 0.0)
            --k;
        hull[k++] = plane[i];
    }
    for (std::size_t i = plane.size() - 1, lowerEnd = k + 1; i > 0; --i)
    {
        while (k >= lowerEnd && turn(hull[k - 2], hull[k - 1], plane[i - 1]) <= 0.0)
            --k;
        hull[k++] = plane[i - 1];
    }
    hull.resize(k > 1 ? k - 1 : k);  // the last point repeats the first
    for (std::size_t i = 0; i < hull.size(); ++i)
    {
        const Eigen::Vector2d edge = hull[(i + 1) % hull.size()] - hull[i];
        if (!(edge.squaredNorm() > 0.0))
            continue;
        const Eigen::Vector2d along = edge.normalized(), across(-along.y(), along.x());
        double a0 = std::numeric_limits<double>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
        for (const Eigen::Vector2d &h : hull)
        {
            a0 = std::min(a0, along.dot(h));
            a1 = std::max(a1, along.dot(h));
            b0 = std::min(b0, across.dot(h));
            b1 = std::max(b1, across.dot(h));
        }
        const double w = a1 - a0, l = b1 - b0, area = w * l + (w + l) * height;
        if (area < bestArea)
        {
            bestArea = area;
            best.col(0) = along.x() * u + along.y() * v;
            best.col(1) = across.x() * u + across.y() * v;
            best.col(2) = normal;
        }
    }
}
}  // namespace

Eigen::Matrix3d leastAreaAxes(const std::vector<Vec> &points, const Eigen::Matrix3d &start,
                              const std::vector<Vec> &normals, BoxFitScratch &scratch)
{
    Eigen::Matrix3d axes = start;
    // Nothing to choose by, or coordinates the hull's sort cannot order (the caller's box then
    // says so; MeshBvh refuses such vertices, loaded meshes never hold them).
    if (points.empty() || !std::all_of(points.begin(), points.end(), [](const Vec &p) { return p.allFinite(); }))
        return axes;
    double bestArea = boxArea(points, axes);
    scratch.tried.clear();
    for (const Vec &direction : normals)
    {
        if (!(direction.squaredNorm() > 0.0))
            continue;
        const Vec normal = direction.normalized();
        if (std::any_of(scratch.tried.begin(), scratch.tried.end(),
                        [&](const Vec &t) { return std::abs(t.dot(normal)) > kSameDirection; }))
            continue;
        scratch.tried.push_back(normal);
        fitAboutNormal(points, normal, axes, bestArea, scratch);
    }
    return axes;
}

ExtremePoints::ExtremePoints()
{
    std::fill(low_, low_ + kDirections, std::numeric_limits<double>::infinity());
    std::fill(high_, high_ + kDirections, -std::numeric_limits<double>::infinity());
}

void ExtremePoints::add(const Vec &p)
{
    any_ = true;
    for (int d = 0; d < kDirections; ++d)
    {
        const double t = kExtremeDirections[d].dot(p);
        if (t < low_[d])
            low_[d] = t, lowest_[d] = p;
        if (t > high_[d])
            high_[d] = t, highest_[d] = p;
    }
}

void ExtremePoints::appendTo(std::vector<Vec> &points) const
{
    if (!any_)
        return;
    for (int d = 0; d < kDirections; ++d)
    {
        points.push_back(lowest_[d]);
        points.push_back(highest_[d]);
    }
}
}  // namespace rastercheck
