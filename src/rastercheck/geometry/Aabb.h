#pragma once

#include <limits>

#include <Eigen/Core>

namespace rastercheck
{
/** \brief Axis-aligned box [min, max] in some frame (named by the owner). Default-constructed
    boxes are empty (min > max) and absorb the first point extended into them. */
struct Aabb
{
    Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

    bool empty() const { return (min.array() > max.array()).any(); }
    void extend(const Eigen::Vector3d &p)
    {
        min = min.cwiseMin(p);
        max = max.cwiseMax(p);
    }
    void extend(const Aabb &other)
    {
        min = min.cwiseMin(other.min);
        max = max.cwiseMax(other.max);
    }
    Eigen::Vector3d center() const { return 0.5 * (min + max); }
    Eigen::Vector3d halfExtents() const { return 0.5 * (max - min); }
    /** \brief Grows the box by \a margin on every side. */
    Aabb inflated(double margin) const
    {
        Aabb box = *this;
        box.min.array() -= margin;
        box.max.array() += margin;
        return box;
    }
    bool overlaps(const Aabb &other) const
    {
        return (min.array() <= other.max.array()).all() && (other.min.array() <= max.array()).all();
    }
    bool contains(const Eigen::Vector3d &p) const
    {
        return (min.array() <= p.array()).all() && (p.array() <= max.array()).all();
    }
};
}  // namespace rastercheck
