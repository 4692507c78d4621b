#include "rastercheck/collision/Penetration.h"

#include <algorithm>
#include <cmath>

#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/device/CurvedShapes.h"
#include "rastercheck/device/Penetration.h"
#include "rastercheck/geometry/EigenDevice.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
using device::ConvexShape;
using device::Vec3;

/** \brief A convex body inside a mesh solid: the hull of one of its pieces (ConvexSolids), shrunk by
    \a scale towards \a centre (the piece's own frame) so that it lies behind every face plane. */
struct InnerBody
{
    std::uint32_t piece;
    Vec3<double> centre;
    double scale;
};

/** \brief The inner body of piece \a piece when it has face planes (a closed shell close to convex)
    and its centre lies behind all of them: the largest scale towards the centre at which the hull
    lies behind every plane, less a rounding margin, or 1 (\a convex) when no vertex lies farther
    than that margin in front of any plane (the shell is its hull). */
bool innerBody(const device::ConvexArrays &arrays, std::uint32_t piece, InnerBody &body, bool &convex)
{
    const device::ConvexProxy proxy = device::convexProxy(arrays, piece);
    if (proxy.numPlanes == 0 || proxy.numVertices == 0)
        return false;
    Vec3<double> low{proxy.vertices[0], proxy.vertices[1], proxy.vertices[2]}, high = low;
    for (std::uint32_t i = 1; i < proxy.numVertices; ++i)
    {
        const double *v = proxy.vertices + 3 * static_cast<std::size_t>(i);
        low = {std::min(low.x, v[0]), std::min(low.y, v[1]), std::min(low.z, v[2])};
        high = {std::max(high.x, v[0]), std::max(high.y, v[1]), std::max(high.z, v[2])};
    }
    // The planes' rounding: their normals' tilt (device::kPlaneSlack) over the piece's extent, and
    // the offsets' rounding at coordinates as large as the piece's radius.
    const double margin = device::kPlaneSlack * std::sqrt(device::dot(high - low, high - low)) + 1e-12 * proxy.radius;
    double scale = 1.0;
    convex = true;
    for (std::uint32_t f = 0; f < proxy.numPlanes; ++f)
    {
        const double *plane = proxy.planes + 4 * static_cast<std::size_t>(f);
        const Vec3<double> normal{plane[0], plane[1], plane[2]};
        const double highest = device::supportValue(proxy.vertices, proxy.numVertices, normal);
        const double centre = device::dot(normal, proxy.centre);
        const double behind = plane[3] - margin - centre;
        if (!(behind > 0.0))
            return false;
        convex = convex && highest - plane[3] <= margin;
        scale = std::min(scale, behind / (highest - centre));
    }
    body = InnerBody{piece, proxy.centre, convex ? 1.0 : scale};
    return true;
}

/** \brief One side of a pair as the measurement reads it, placed in the frame it runs in. */
struct Side
{
    const device::ConvexArrays *arrays;
    std::uint32_t wholePiece;                   // mesh: the piece of its whole mesh (its hull)
    device::Pose<double> pose;                  // the solid's frame -> the measuring frame
    std::vector<ConvexShape> shapes;            // a side of primitives: them, placed
    const std::vector<InnerBody> *innerBodies;  // a mesh side: its inner bodies
    bool convex;                                // one convex body: its hull is itself

    std::size_t numBodies() const { return shapes.empty() ? innerBodies->size() : shapes.size(); }

    device::PointsSupport points(std::uint32_t piece, const Vec3<double> &centre, double scale) const
    {
        const device::ConvexPiece &p = arrays->pieces[piece];
        return device::PointsSupport{arrays->vertices + 3 * static_cast<std::size_t>(p.firstVertex), p.numVertices,
                                     pose, centre, scale};
    }
};

/** \brief Calls \a f(support, margin) for \a shape: a sphere as its centre grown by its radius
    (device::convexPenetration), any other as itself. */
template <class F>
void withShape(const ConvexShape &shape, F &&f)
{
    if (shape.kind != device::ConvexKind::Sphere)
    {
        f(device::ShapeSupport{&shape}, 0.0);
        return;
    }
    ConvexShape centre = shape;
    centre.size[0] = 0.0;
    f(device::ShapeSupport{&centre}, shape.size[0]);
}

/** \brief Calls \a f(support, margin) for the hull of \a side. */
template <class F>
void withHull(const Side &side, F &&f)
{
    if (side.shapes.size() == 1)
        withShape(side.shapes[0], f);
    else if (!side.shapes.empty())
        f(device::ShapesSupport{side.shapes.data(), static_cast<int>(side.shapes.size())}, 0.0);
    else
        f(side.points(side.wholePiece, Vec3<double>{0.0, 0.0, 0.0}, 1.0), 0.0);
}

/** \brief Calls \a f(support, margin) for the \a k th convex body inside \a side. */
template <class F>
void withBody(const Side &side, std::size_t k, F &&f)
{
    if (!side.shapes.empty())
        withShape(side.shapes[k], f);
    else
    {
        const InnerBody &body = (*side.innerBodies)[k];
        f(side.points(body.piece, body.centre, body.scale), 0.0);
    }
}

/** \brief device::convexPenetration of the bodies \a withA and \a withB give (withHull, withBody). */
template <class WithA, class WithB>
device::ConvexPenetration penetrationOf(WithA &&withA, WithB &&withB, double tolerance)
{
    device::ConvexPenetration result;
    withA(
        [&](const auto &a, double marginA)
        {
            withB([&](const auto &b, double marginB)
                  { device::convexPenetration(a, b, tolerance, result, marginA, marginB); });
        });
    return result;
}
}  // namespace

struct PairPenetration::Solid
{
    std::vector<InnerBody> innerBodies;
    bool convex = false;  // its whole mesh is one convex shell
};

PairPenetration::PairPenetration(const CollisionModel &model)
    : model_(model), prepared_(new std::once_flag[model.convex.numSolids()]), solids_(model.convex.numSolids())
{
}

PairPenetration::~PairPenetration() = default;

const PairPenetration::Solid &PairPenetration::solid(std::size_t index) const
{
    std::call_once(prepared_[index],
                   [&]
                   {
                       const device::ConvexArrays arrays = model_.convex.arrays();
                       Solid &solid = solids_[index];
                       const std::uint32_t first = arrays.solidPieces[index], end = arrays.solidPieces[index + 1];
                       InnerBody body;
                       bool convex = false;
                       // The whole mesh keeps planes only as a single shell; else each shell may.
                       if (innerBody(arrays, first, body, convex))
                       {
                           solid.innerBodies.push_back(body);
                           solid.convex = convex;
                           return;
                       }
                       for (std::uint32_t piece = first + 1; piece < end; ++piece)
                           if (innerBody(arrays, piece, body, convex))
                               solid.innerBodies.push_back(body);
                   });
    return solids_[index];
}

void PairPenetration::measure(std::uint32_t pair, const Eigen::Isometry3d &poseA, const Eigen::Isometry3d &poseB,
                              Penetration &result, double relativeTolerance) const
{
    Contact parties;
    model_.nameParties(pair, parties);
    const std::size_t component = static_cast<std::size_t>(parties.component);
    const bool environment = parties.kind == Contact::Kind::Environment;
    const std::size_t other = static_cast<std::size_t>(environment ? parties.object : parties.otherComponent);
    const std::size_t solidB = environment ? model_.numComponents() + other : other;
    const MeshBvh &bvhA = *model_.componentBvhs[component];
    const MeshBvh &bvhB = environment ? *model_.objectBvhs[other] : *model_.componentBvhs[other];

    // Measured about the component's origin: coordinates of the pair's size, not the world's.
    const Eigen::Vector3d origin = poseA.translation();
    const device::ConvexArrays arrays = model_.convex.arrays();
    const device::CurvedArrays primitives = model_.curved.arrays();  // a solid made of primitives: its shapes
    const auto side = [&](std::size_t solidIndex, const Eigen::Isometry3d &pose)
    {
        const std::uint32_t first = primitives.solidShapes[solidIndex], end = primitives.solidShapes[solidIndex + 1];
        Side s{&arrays,
               arrays.solidPieces[solidIndex],
               toDevicePose(Eigen::Translation3d(-origin) * pose),
               {},
               nullptr,
               end - first == 1};
        for (std::uint32_t k = first; k < end; ++k)
            s.shapes.push_back(device::placedShape(primitives.shapes[k], s.pose));
        if (first == end)
        {
            const Solid &prepared = solid(solidIndex);
            s.innerBodies = &prepared.innerBodies;
            s.convex = prepared.convex;
        }
        return s;
    };
    const Side a = side(component, poseA), b = side(solidB, poseB);
    const double size = (bvhA.empty() ? 0.0 : bvhA.nodes()[0].radius) + (bvhB.empty() ? 0.0 : bvhB.nodes()[0].radius);
    const double tolerance = relativeTolerance * size;

    const device::ConvexPenetration hulls =
        penetrationOf([&](auto &&f) { withHull(a, f); }, [&](auto &&f) { withHull(b, f); }, tolerance);
    double lower = hulls.lowerBound;  // the solids' own when each is its hull
    if (!(a.convex && b.convex))
    {
        lower = 0.0;
        for (std::size_t i = 0; i < a.numBodies(); ++i)
            for (std::size_t j = 0; j < b.numBodies(); ++j)
                lower = std::max(lower, penetrationOf([&](auto &&f) { withBody(a, i, f); },
                                                      [&](auto &&f) { withBody(b, j, f); }, tolerance)
                                            .lowerBound);
    }
    result.depth = hulls.depth;
    result.lowerBound = std::min(lower, hulls.depth);
    result.exact = hulls.depth - result.lowerBound <= tolerance;
    result.direction = hulls.depth > 0.0 ? toEigen(hulls.separation) : Eigen::Vector3d::Zero();
    result.pointOnComponent = origin + toEigen(hulls.onA);
    result.pointOnOther = origin + toEigen(hulls.onB);
}
}  // namespace rastercheck
