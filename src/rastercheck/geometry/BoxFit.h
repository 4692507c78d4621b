#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace rastercheck
{
/** \brief Scratch of leastAreaAxes, reused by a caller that fits many boxes. */
struct BoxFitScratch
{
    std::vector<Eigen::Vector3d> tried;
    std::vector<Eigen::Vector2d> plane, hull;
};

/** \brief The axes (columns, orthonormal) of the box of least surface area about \a points among
    \a start and the frames about each of \a normals (any length but zero; a normal within 5
    degrees of one tried is skipped). About a normal, the least rectangle about the points'
    projection has a side along an edge of their convex hull (Freeman and Shapira, 1975), so each
    hull edge gives one frame. The frames about a normal are right-handed; \a start is returned as
    given when nothing beats it, and when a point is not finite. */
Eigen::Matrix3d leastAreaAxes(const std::vector<Eigen::Vector3d> &points, const Eigen::Matrix3d &start,
                              const std::vector<Eigen::Vector3d> &normals, BoxFitScratch &scratch);

/** \brief Triangles (evenly spread over a box's) whose normals appendFitNormals offers. */
constexpr std::size_t kFitTriangleNormals = 16;

/** \brief Appends the normals a box's frame is chosen about (leastAreaAxes): the columns of
    \a principal and the mesh's axes, unless the box holds a single triangle (whose least box lies
    about its normal), and the normals of up to kFitTriangleNormals of its \a triangles triangles,
    evenly spread; \a normalOf(i) is triangle i's normal (any length). */
template <class NormalOf>
void appendFitNormals(const Eigen::Matrix3d &principal, std::size_t triangles, const NormalOf &normalOf,
                      std::vector<Eigen::Vector3d> &normals)
{
    if (triangles > 1)
        for (int k = 0; k < 3; ++k)
        {
            normals.push_back(principal.col(k));
            normals.push_back(Eigen::Vector3d::Unit(k));
        }
    const std::size_t step = std::max<std::size_t>(1, triangles / kFitTriangleNormals);
    for (std::size_t i = 0; i < triangles; i += step)
        normals.push_back(normalOf(i));
}

/** \brief The points of a set extreme along 13 directions (the axes, the cube's diagonals and its
    face diagonals): 26 points that stand in for a large set while a box's frame is chosen (the box
    is then sized to every point). */
class ExtremePoints
{
public:
    ExtremePoints();
    void add(const Eigen::Vector3d &p);
    /** \brief Appends the extreme points (nothing when none was added). */
    void appendTo(std::vector<Eigen::Vector3d> &points) const;

private:
    static constexpr int kDirections = 13;
    double low_[kDirections], high_[kDirections];
    Eigen::Vector3d lowest_[kDirections], highest_[kDirections];
    bool any_ = false;
};
}  // namespace rastercheck
