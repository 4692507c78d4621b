// The convex separation cull (device/Separation.h): a proof by a plane that two solids are more
// than the padding apart. It must never contradict the exact oracle (solidsOverlap), must be tight
// on shapes whose distance is known, and must settle convex pairs whenever they are clearly apart.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "NonConvex.h"
#include "TestSupport.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;
using Vec = Eigen::Vector3d;

namespace
{
/** \brief Meshes as both the proof and the oracle see them. */
class Solids
{
public:
    std::size_t add(const rc::Mesh &mesh, bool closed = true)
    {
        meshes_.push_back(std::make_unique<rc::Mesh>(mesh));  // the BVH reads the mesh it was built on
        bvhs_.push_back(std::make_unique<rc::MeshBvh>(*meshes_.back()));
        convex_.add(*bvhs_.back(), closed);  // the patches are a cut of the oracle's tree
        closed_.push_back(closed);
        return convex_.numSolids() - 1;
    }

    /** \brief The hull test, overlaps proven too (as when no contact is asked). */
    rc::device::HullRelation relation(std::size_t a, const Eigen::Isometry3d &poseA, std::size_t b,
                                      const Eigen::Isometry3d &poseB, double padding, bool proveOverlap = true) const
    {
        return rc::device::relateSolids(convex_.arrays(), static_cast<std::uint32_t>(a), rc::toDevicePose(poseA),
                                        static_cast<std::uint32_t>(b), rc::toDevicePose(poseB), padding, proveOverlap);
    }

    /** \brief The hull test starting from \a direction (a proof's direction at a nearby state, as
        the CPU backend keeps per pair), which it updates after a proof. */
    rc::device::HullRelation relationFrom(std::size_t a, const Eigen::Isometry3d &poseA, std::size_t b,
                                          const Eigen::Isometry3d &poseB, double padding,
                                          rc::device::Vec3<double> &direction) const
    {
        return rc::device::relateSolids(convex_.arrays(), static_cast<std::uint32_t>(a), rc::toDevicePose(poseA),
                                        static_cast<std::uint32_t>(b), rc::toDevicePose(poseB), padding, true,
                                        &direction);
    }

    bool provenApart(std::size_t a, const Eigen::Isometry3d &poseA, std::size_t b, const Eigen::Isometry3d &poseB,
                     double padding) const
    {
        return relation(a, poseA, b, poseB, padding, false) == rc::device::HullRelation::Apart;
    }

    bool provenOverlapping(std::size_t a, const Eigen::Isometry3d &poseA, std::size_t b, const Eigen::Isometry3d &poseB,
                           double padding) const
    {
        return relation(a, poseA, b, poseB, padding) == rc::device::HullRelation::Overlapping;
    }

    bool oracleOverlaps(std::size_t a, const Eigen::Isometry3d &poseA, std::size_t b, const Eigen::Isometry3d &poseB,
                        double padding) const
    {
        return rc::solidsOverlap(*bvhs_[a], poseA, closed_[a], *bvhs_[b], poseB, closed_[b], padding);
    }

    /** \brief The whole mesh's convex piece of solid \a s. */
    const rc::device::ConvexPiece &whole(std::size_t s) const
    {
        return convex_.arrays().pieces[convex_.arrays().solidPieces[s]];
    }
    double radius(std::size_t s) const { return whole(s).radius; }
    /** \brief Whether piece \a k of solid \a s (0: the whole mesh) keeps face planes (overlap proofs). */
    bool hasPlanes(std::size_t s, std::size_t k = 0) const
    {
        return convex_.arrays().pieces[convex_.arrays().solidPieces[s] + k].numPlanes > 0;
    }
    std::size_t numPieces(std::size_t s) const { return convex_.numPieces(s); }

private:
    rc::ConvexSolids convex_;
    std::vector<std::unique_ptr<rc::Mesh>> meshes_;
    std::vector<std::unique_ptr<rc::MeshBvh>> bvhs_;
    std::vector<bool> closed_;
};

/** \brief \a a and \a b as one mesh of two shells. */
rc::Mesh joined(rc::Mesh a, const rc::Mesh &b)
{
    const std::uint32_t offset = static_cast<std::uint32_t>(a.vertices.size());
    a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (rc::Mesh::Triangle t : b.triangles)
    {
        for (std::uint32_t &v : t)
            v += offset;
        a.triangles.push_back(t);
    }
    return a;
}

rc::Mesh movedBox(const Vec &size, const Vec &centre)
{
    rc::Mesh box = rc::makeBox(size);
    Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
    shift.translation() = centre;
    box.transform(shift);
    return box;
}

Eigen::Isometry3d at(double x, double y = 0, double z = 0)
{
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Vec(x, y, z);
    return pose;
}

Eigen::Isometry3d randomPose(std::mt19937 &rng, double reach)
{
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    Eigen::Quaterniond q(unit(rng), unit(rng), unit(rng), unit(rng));
    if (q.norm() < 1e-3)
        q = Eigen::Quaterniond::Identity();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = q.normalized().toRotationMatrix();
    pose.translation() = reach * Vec(unit(rng), unit(rng), unit(rng));
    return pose;
}

/** \brief What checkAgainstTheOracle counted. */
struct OracleTally
{
    int apart = 0;        ///< pairs the oracle calls apart
    int provenApart = 0;  ///< of those, settled by the hull test
    int overlapping = 0;  ///< pairs the oracle calls colliding
    int provenOverlapping = 0;
};

/** \brief Over random poses of solids \a a and \a b (B's origin within \a reach of A's): every
    proof, of separation or of overlap, agrees with the oracle. */
OracleTally checkAgainstTheOracle(const Solids &solids, std::size_t a, std::size_t b, double reach, int trials,
                                  unsigned seed)
{
    std::mt19937 rng(seed);
    const double paddings[] = {0.0, 0.002, 0.02};
    OracleTally tally;
    for (int trial = 0; trial < trials; ++trial)
    {
        const Eigen::Isometry3d poseA = randomPose(rng, 0.1 * reach), poseB = poseA * randomPose(rng, reach);
        const double padding = paddings[trial % 3];
        const rc::device::HullRelation relation = solids.relation(a, poseA, b, poseB, padding);
        const bool overlaps = solids.oracleOverlaps(a, poseA, b, poseB, padding);
        EXPECT_FALSE(relation == rc::device::HullRelation::Apart && overlaps)
            << "trial " << trial << ": proven apart, but the oracle finds them within " << padding;
        EXPECT_FALSE(relation == rc::device::HullRelation::Overlapping && !overlaps)
            << "trial " << trial << ": proven overlapping, but the oracle finds them apart";
        // Without overlap proofs, the separation proofs are the same.
        EXPECT_EQ(solids.provenApart(a, poseA, b, poseB, padding), relation == rc::device::HullRelation::Apart);
        (overlaps ? tally.overlapping : tally.apart) += 1;
        tally.provenApart += relation == rc::device::HullRelation::Apart ? 1 : 0;
        tally.provenOverlapping += relation == rc::device::HullRelation::Overlapping ? 1 : 0;
    }
    return tally;
}
}  // namespace

TEST(Separation, CubesAreProvenApartUpToTheirGapAndNoFurther)
{
    Solids solids;
    const std::size_t cube = solids.add(rc::makeBox(Vec(1, 1, 1)));
    // Faces 0.5 m apart along x.
    EXPECT_TRUE(solids.provenApart(cube, at(0), cube, at(1.5), 0.0));
    EXPECT_TRUE(solids.provenApart(cube, at(0), cube, at(1.5), 0.49));
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, at(1.5), 0.51));
    // The same gap on a diagonal offset: the nearest features are still the facing faces.
    EXPECT_TRUE(solids.provenApart(cube, at(0), cube, at(1.5, 0.7, -0.3), 0.49));
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, at(1.5, 0.7, -0.3), 0.51));
}

TEST(Separation, AProofDirectionFromANearbyStateStartsTheTestButNeverReplacesTheGap)
{
    using rc::device::HullRelation;
    Solids solids;
    const std::size_t cube = solids.add(rc::makeBox(Vec(1, 1, 1)));
    rc::device::Vec3<double> direction{0.0, 0.0, 0.0};
    ASSERT_EQ(solids.relationFrom(cube, at(0), cube, at(1.5), 0.0, direction), HullRelation::Apart);
    EXPECT_LT(direction.x, 0.0);  // from B towards A
    // A nearby state: settled along the kept direction; the gap still has to clear the padding.
    EXPECT_EQ(solids.relationFrom(cube, at(0), cube, at(1.55, 0.05), 0.49, direction), HullRelation::Apart);
    EXPECT_EQ(solids.relationFrom(cube, at(0), cube, at(1.5), 0.51, direction), HullRelation::Unknown);
    // Moved into the first cube, or behind it: the old direction proves nothing wrong.
    EXPECT_EQ(solids.relationFrom(cube, at(0), cube, at(0.5), 0.0, direction), HullRelation::Overlapping);
    EXPECT_EQ(solids.relationFrom(cube, at(0), cube, at(-1.5), 0.49, direction), HullRelation::Apart);
    EXPECT_GT(direction.x, 0.0);
    // A direction that separates nothing only costs GJK its first step.
    rc::device::Vec3<double> sideways{0.0, 1.0, 0.0};
    EXPECT_EQ(solids.relationFrom(cube, at(0), cube, at(1.5), 0.49, sideways), HullRelation::Apart);
}

TEST(Separation, TouchingOverlappingOrNestedSolidsAreNeverProvenApart)
{
    Solids solids;
    const std::size_t cube = solids.add(rc::makeBox(Vec(1, 1, 1)));
    const std::size_t big = solids.add(rc::makeBox(Vec(3, 3, 3)));
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, at(1.0), 0.0));  // faces touch
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, at(0.9), 0.0));
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, at(0), 0.0));   // coincide
    EXPECT_FALSE(solids.provenApart(big, at(0), cube, at(0.2), 0.0));  // one inside the other
    EXPECT_FALSE(solids.provenApart(cube, at(0.2), big, at(0), 0.0));
}

TEST(Separation, ACubeTurnedOnItsEdgeIsSeparatedByItsTrueGap)
{
    Solids solids;
    const std::size_t cube = solids.add(rc::makeBox(Vec(1, 1, 1)));
    // B turned 45 degrees about z: its nearest feature is an edge, 0.5 * sqrt(2) from its centre.
    Eigen::Isometry3d turned = at(0.5 + 0.5 * std::sqrt(2.0) + 0.01, 0.1, 0.05);
    turned.linear() = Eigen::AngleAxisd(M_PI / 4, Vec::UnitZ()).toRotationMatrix();
    EXPECT_TRUE(solids.provenApart(cube, at(0), cube, turned, 0.0099));
    EXPECT_FALSE(solids.provenApart(cube, at(0), cube, turned, 0.0101));
    EXPECT_FALSE(solids.oracleOverlaps(cube, at(0), cube, turned, 0.0099));
    EXPECT_TRUE(solids.oracleOverlaps(cube, at(0), cube, turned, 0.0101));
}

TEST(Separation, FineSpheresAreProvenApartAlongTheirCentreLineThroughTheirHullPoints)
{
    Solids solids;
    const std::size_t sphere = solids.add(rc::makeSphere(1.0, 1e-4));
    ASSERT_GT(solids.whole(sphere).numVertices, 4 * rc::kConvexHullDirections);  // GJK sees a small subset
    EXPECT_LE(solids.whole(sphere).numHullPoints, rc::kConvexHullDirections);
    // The mesh contains the unit sphere and lies within 1e-4 of it: the gap is between 0.0498 and 0.05.
    const Eigen::Isometry3d apart = at(1.2, 1.2, std::sqrt(2.05 * 2.05 - 2 * 1.2 * 1.2));
    EXPECT_TRUE(solids.provenApart(sphere, at(0), sphere, apart, 0.049));
    EXPECT_FALSE(solids.provenApart(sphere, at(0), sphere, apart, 0.0501));
}

namespace
{
/** \brief A closed U, one shell: the outline (0,0) (3,0) (3,2) (2,2) (2,1) (1,1) (1,2) (0,2) in
    the x-z plane, extruded from y = -0.5 to 0.5; its notch, x 1..2 and z 1..2, is empty. */
rc::Mesh uShape()
{
    const double outline[8][2] = {{0, 0}, {3, 0}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    rc::Mesh mesh;
    for (double y : {-0.5, 0.5})
        for (const auto &p : outline)
            mesh.vertices.emplace_back(p[0], y, p[1]);
    // The outline in six triangles, counter-clockwise in (x, z): their normal is x cross z = -y.
    const std::uint32_t cap[6][3] = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {0, 4, 5}, {0, 5, 7}, {5, 6, 7}};
    for (const auto &t : cap)
    {
        mesh.triangles.push_back({t[0], t[1], t[2]});              // y = -0.5, facing -y
        mesh.triangles.push_back({t[0] + 8, t[2] + 8, t[1] + 8});  // y = +0.5, facing +y
    }
    for (std::uint32_t i = 0; i < 8; ++i)
    {
        const std::uint32_t j = (i + 1) % 8;
        mesh.triangles.push_back({i, j + 8, j});
        mesh.triangles.push_back({i, i + 8, j + 8});
    }
    EXPECT_GT(rc::signedVolume(mesh), 0.0);  // outward
    return mesh;
}

/** \brief A unit cube (centred on the origin) whose top face dips to a point \a dent below its
    centre: four triangles from the corners to (0, 0, 0.5 - dent). */
rc::Mesh dentedCube(double dent)
{
    rc::Mesh mesh = rc::makeBox(Vec(1, 1, 1));
    mesh.vertices.emplace_back(0.0, 0.0, 0.5 - dent);
    mesh.triangles.erase(mesh.triangles.begin() + 2, mesh.triangles.begin() + 4);  // the flat top
    for (const rc::Mesh::Triangle &t : {rc::Mesh::Triangle{4, 5, 8}, rc::Mesh::Triangle{5, 7, 8},
                                        rc::Mesh::Triangle{7, 6, 8}, rc::Mesh::Triangle{6, 4, 8}})
        mesh.triangles.push_back(t);
    EXPECT_GT(rc::signedVolume(mesh), 0.0);  // outward
    return mesh;
}
}  // namespace

TEST(Separation, OnlyClosedShellsNearlyConvexProveOverlaps)
{
    Solids solids;
    const std::size_t box = solids.add(rc::makeBox(Vec(0.6, 0.6, 0.6)));
    const std::size_t openBox = solids.add(rc::makeBox(Vec(0.6, 0.6, 0.6)), false);
    const std::size_t u = solids.add(uShape());
    ASSERT_TRUE(solids.hasPlanes(box));
    EXPECT_FALSE(solids.hasPlanes(openBox));  // an open surface has no inside
    EXPECT_FALSE(solids.hasPlanes(u));        // the notch is far too deep to look behind every face
    rc::Mesh insideOut = rc::makeBox(Vec(0.6, 0.6, 0.6));
    for (rc::Mesh::Triangle &t : insideOut.triangles)
        std::swap(t[1], t[2]);
    EXPECT_FALSE(solids.hasPlanes(solids.add(insideOut)));  // "behind" its faces is outside
    const Eigen::Isometry3d here = at(0);
    // The U is outward-oriented and closed, as the oracle needs.
    EXPECT_TRUE(solids.oracleOverlaps(u, here, box, at(0.5, 0, 0.5), 0.0));

    // Two boxes, the second 0.3 into the first: proven overlapping, but not when a contact is asked.
    EXPECT_TRUE(solids.provenOverlapping(box, here, box, at(0.3, 0.1, -0.05), 0.0));
    EXPECT_EQ(solids.relation(box, here, box, at(0.3, 0.1, -0.05), 0.0, false), rc::device::HullRelation::Unknown);
    // One box wholly inside another (surfaces apart): the solids overlap, and the hulls prove it.
    const std::size_t small = solids.add(rc::makeBox(Vec(0.1, 0.1, 0.1)));
    EXPECT_TRUE(solids.oracleOverlaps(box, here, small, at(0.05, 0, 0), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(box, here, small, at(0.05, 0, 0), 0.0));
    // The open box is only its surface: the small box inside it does not touch it.
    EXPECT_FALSE(solids.oracleOverlaps(openBox, here, small, at(0.05, 0, 0), 0.0));
    EXPECT_FALSE(solids.provenOverlapping(openBox, here, small, at(0.05, 0, 0), 0.0));
    // Its corner (0.3, 0.3, 0.3) inside the closed box: its surface reaches in, proven.
    EXPECT_TRUE(solids.oracleOverlaps(openBox, here, box, at(0.35, 0.05, 0.02), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(openBox, here, box, at(0.35, 0.05, 0.02), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(box, at(0.35, 0.05, 0.02), openBox, here, 0.0));
    // Its face through the small box, no vertex of either inside the other: the face's diagonal
    // edge runs through the small box's middle, and proves it.
    EXPECT_TRUE(solids.oracleOverlaps(openBox, here, small, at(0.3, 0, 0), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(openBox, here, small, at(0.3, 0, 0), 0.0));
    // Off both of the face's diagonals (0.106 from each, the small box reaches 0.071 across them),
    // no edge of the open box enters the small one, and the open box has no inside of its own:
    // left to the exact phase.
    EXPECT_TRUE(solids.oracleOverlaps(openBox, here, small, at(0.3, 0.15, 0), 0.0));
    EXPECT_EQ(solids.relation(openBox, here, small, at(0.3, 0.15, 0), 0.0), rc::device::HullRelation::Unknown);

    // The box in the U's notch: the hulls overlap deeply, the solids are 0.2 apart. The U's
    // patches (flat pieces of its surface) prove it, up to a padding under the gap.
    const Eigen::Isometry3d notch = at(1.5, 0, 1.5);
    const std::size_t cube = solids.add(rc::makeBox(Vec(0.6, 0.6, 0.6)));
    EXPECT_FALSE(solids.oracleOverlaps(u, here, cube, notch, 0.0));
    EXPECT_EQ(solids.relation(u, here, cube, notch, 0.0), rc::device::HullRelation::Apart);
    EXPECT_EQ(solids.relation(u, here, cube, notch, 0.19), rc::device::HullRelation::Apart);
    EXPECT_EQ(solids.relation(u, here, cube, notch, 0.3), rc::device::HullRelation::Unknown);
    // Sunk 0.5 into the U's base: the U keeps no planes, but its surface (a vertex or an edge)
    // reaches inside the closed cube, which proves the overlap.
    EXPECT_TRUE(solids.oracleOverlaps(u, here, cube, at(1.5, 0, 0.9), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(u, here, cube, at(1.5, 0, 0.9), 0.0));
}

TEST(Separation, OverlapProofsLookOnlyBehindEveryFaceOfANearlyConvexShell)
{
    // A cube whose top dips 0.015 at its centre (1.5 % of its size, below the 2 % limit): its hull
    // holds the dip, the solid does not.
    Solids solids;
    const std::size_t dented = solids.add(dentedCube(0.015));
    const std::size_t speck = solids.add(rc::makeBox(Vec(0.01, 0.01, 0.01)));
    ASSERT_TRUE(solids.hasPlanes(dented));
    ASSERT_TRUE(solids.hasPlanes(speck));
    const Eigen::Isometry3d here = at(0);
    // In the dip (z 0.4875 to 0.4975 above its lowest point 0.485): outside the solid, inside its hull.
    EXPECT_FALSE(solids.oracleOverlaps(dented, here, speck, at(0, 0, 0.4925), 0.0));
    EXPECT_EQ(solids.relation(dented, here, speck, at(0, 0, 0.4925), 0.0), rc::device::HullRelation::Unknown);
    // Inside, near the dip and deep in the middle: proven.
    EXPECT_TRUE(solids.oracleOverlaps(dented, here, speck, at(0, 0, 0.47), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(dented, here, speck, at(0, 0, 0.47), 0.0));
    EXPECT_TRUE(solids.provenOverlapping(dented, here, speck, at(0.1, -0.2, 0.0), 0.0));
    // A dip of 5 % is beyond the limit: no planes, no overlap proofs.
    Solids deeper;
    EXPECT_FALSE(deeper.hasPlanes(deeper.add(dentedCube(0.05))));
}

TEST(Separation, AnEdgeReachingInsideAClosedSolidProvesTheOverlap)
{
    // A bar through a cube, off its middle: no vertex of either lies inside the other.
    Solids solids;
    const std::size_t cube = solids.add(rc::makeBox(Vec(0.6, 0.6, 0.6)));
    const std::size_t openCube = solids.add(rc::makeBox(Vec(0.6, 0.6, 0.6)), false);
    const std::size_t openBar = solids.add(rc::makeBox(Vec(2.0, 0.05, 0.05)), false);
    const std::size_t bar = solids.add(rc::makeBox(Vec(2.0, 0.05, 0.05)));
    const Eigen::Isometry3d here = at(0), through = at(0, 0.15, 0);
    // The open bar has no inside, so only its edges, which run through the cube, prove it.
    EXPECT_TRUE(solids.oracleOverlaps(openBar, through, cube, here, 0.0));
    EXPECT_TRUE(solids.provenOverlapping(openBar, through, cube, here, 0.0));
    EXPECT_TRUE(solids.provenOverlapping(cube, here, openBar, through, 0.0));
    // The other way round, the open cube's edges miss the bar (its face diagonals pass 0.106 from
    // it; the bar reaches 0.035 across them): the surfaces cross, and only the exact phase says so.
    EXPECT_TRUE(solids.oracleOverlaps(bar, through, openCube, here, 0.0));
    EXPECT_EQ(solids.relation(bar, through, openCube, here, 0.0), rc::device::HullRelation::Unknown);
    // Lifted to 0.01 above the cube: apart, and never proven overlapping.
    const Eigen::Isometry3d above = at(0, 0.15, 0.3 + 0.025 + 0.01);
    EXPECT_FALSE(solids.oracleOverlaps(openBar, above, cube, here, 0.0));
    EXPECT_NE(solids.relation(openBar, above, cube, here, 0.0), rc::device::HullRelation::Overlapping);
    EXPECT_NE(solids.relation(openBar, above, cube, here, 0.02), rc::device::HullRelation::Overlapping);
}

TEST(Separation, SolidsOfSeveralShellsAreSeparatedShellByShellWhenTheirHullsInterlock)
{
    // Two L shapes of two boxes each (a link with two collision elements), hooked into each
    // other: each one's hull holds part of the other, but every box is 0.1 from every other box.
    Solids solids;
    const std::size_t lower = solids.add(joined(movedBox(Vec(2, 0.2, 1), Vec(0, 0, 0)),        // x -1..1, z -0.5..0.5
                                                movedBox(Vec(0.2, 0.2, 1), Vec(0.9, 0, 1))));  // x 0.8..1, z 0.5..1.5
    const std::size_t upper = solids.add(joined(movedBox(Vec(1.5, 0.2, 0.2), Vec(-0.05, 0, 1.2)),    // x -0.8..0.7
                                                movedBox(Vec(0.2, 0.2, 0.5), Vec(-0.7, 0, 0.85))));  // z 0.6..1.1
    ASSERT_EQ(solids.numPieces(lower), 3u);  // the whole, then the two shells
    ASSERT_EQ(solids.numPieces(upper), 3u);
    const Eigen::Isometry3d here = at(0);
    EXPECT_FALSE(solids.oracleOverlaps(lower, here, upper, here, 0.099));
    EXPECT_TRUE(solids.oracleOverlaps(lower, here, upper, here, 0.101));
    EXPECT_TRUE(solids.provenApart(lower, here, upper, here, 0.09));
    EXPECT_FALSE(solids.provenApart(lower, here, upper, here, 0.101));
    // Lowered by 0.15, the upper bar cuts into the lower box: never proven apart.
    EXPECT_TRUE(solids.oracleOverlaps(lower, here, upper, at(0, 0, -0.15), 0.0));
    EXPECT_FALSE(solids.provenApart(lower, here, upper, at(0, 0, -0.15), 0.0));
}

TEST(Separation, ProofsNeverContradictTheOracleAndSettleConvexPairsThatAreClearlyApart)
{
    Solids solids;
    const std::size_t box = solids.add(rc::makeBox(Vec(0.4, 0.1, 0.25)));
    const std::size_t cylinder = solids.add(rc::makeCylinder(0.08, 0.5, 1e-3));
    const std::size_t cone = solids.add(rc::makeCone(0.15, 0.3, 1e-3));
    // A table top: large and thin beside the others, where a GJK that starts badly gives up early.
    const std::size_t slab = solids.add(rc::makeBox(Vec(2.0, 1.2, 0.04)));
    const std::size_t shapes[] = {box, cylinder, cone, slab};
    std::mt19937 rng(7);
    int settled = 0, clearlyApart = 0, overlapping = 0, provenOverlapping = 0;
    for (std::size_t a : shapes)
        for (std::size_t b : shapes)
        {
            const OracleTally t = checkAgainstTheOracle(solids, a, b, 1.2, 300, static_cast<unsigned>(10 * a + b));
            overlapping += t.overlapping;
            provenOverlapping += t.provenOverlapping;
            // Completeness for convex solids: apart by more than the padding (and a micrometre for
            // GJK's convergence), the proof is found, though GJK starts from a subset of vertices.
            const double slack = 1e-6;
            for (int trial = 0; trial < 200; ++trial)
            {
                const Eigen::Isometry3d poseA = randomPose(rng, 0.1), poseB = poseA * randomPose(rng, 1.2);
                if (solids.oracleOverlaps(a, poseA, b, poseB, 0.01 + slack))
                    continue;
                ++clearlyApart;
                settled += solids.provenApart(a, poseA, b, poseB, 0.01) ? 1 : 0;
            }
        }
    ASSERT_GT(clearlyApart, 300);
    EXPECT_EQ(settled, clearlyApart);
    // Closed convex solids: most overlapping pairs are proven so (not those that barely touch, nor
    // those within the padding but apart).
    std::printf("clearly apart %d, proven %d; overlapping %d, proven %d\n", clearlyApart, settled, overlapping,
                provenOverlapping);
    ASSERT_GT(overlapping, 300);
    EXPECT_GT(provenOverlapping, overlapping / 2) << provenOverlapping << " of " << overlapping;
}

TEST(Separation, ProofsNeverContradictTheOracleOnThePandasLinks)
{
    const std::string root = rc::test::sharedData();
    if (root.empty())
        GTEST_SKIP() << "shared data not found (set RASTERCHECK_DATA): the Panda's meshes are needed";
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    Solids solids;
    std::vector<std::size_t> links;
    for (const rc::Component &component : problem.robot->components)
        links.push_back(solids.add(component.mesh, component.topology.closed));
    OracleTally all;
    for (std::size_t i = 0; i < links.size(); ++i)
    {
        const std::size_t j = (i * 5 + 3) % links.size();  // a spread of pairs, link6 (open) included
        const OracleTally t = checkAgainstTheOracle(solids, links[i], links[j], 0.25, 400, static_cast<unsigned>(i));
        all.apart += t.apart;
        all.provenApart += t.provenApart;
        all.overlapping += t.overlapping;
        all.provenOverlapping += t.provenOverlapping;
    }
    // Links are not convex, so some apart pairs have overlapping hulls; most do not.
    ASSERT_GT(all.apart, 1000);
    EXPECT_GT(all.provenApart, all.apart / 2) << all.provenApart << " of " << all.apart << " apart pairs proven";
    std::printf("apart %d, proven %d; overlapping %d, proven %d\n", all.apart, all.provenApart, all.overlapping,
                all.provenOverlapping);
    // The closed links are nearly convex (dents under 1 % of their size), so many colliding pairs
    // that do not involve the open link6 are proven overlapping.
    ASSERT_GT(all.overlapping, 300);
    EXPECT_GT(all.provenOverlapping, all.overlapping / 3)
        << all.provenOverlapping << " of " << all.overlapping << " overlapping pairs proven";
}

TEST(Separation, ABoxsFacePlanesCullThePatchesOfTheOpenLink6WithoutContradictingTheOracle)
{
    const std::string root = rc::test::sharedData();
    if (root.empty())
        GTEST_SKIP() << "shared data not found (set RASTERCHECK_DATA): the Panda's meshes are needed";
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    const rc::Component &link6 = problem.robot->components[6];
    ASSERT_FALSE(link6.topology.closed);
    Solids solids;
    const std::size_t link = solids.add(link6.mesh, false);
    // A table top, a shelf board and a small block, as the MotionBenchMaker scenes have them: the
    // box's planes cull the link's patch tree (patchesApart) before any patch's hull test.
    const std::size_t boxes[] = {solids.add(rc::makeBox(Vec(1.2, 0.8, 0.04))),
                                 solids.add(rc::makeBox(Vec(0.6, 0.3, 0.02))),
                                 solids.add(rc::makeBox(Vec(0.05, 0.05, 0.1)))};
    OracleTally all;
    for (std::size_t k = 0; k < 3; ++k)
    {
        // Both orders: relateSolids walks the link's patches either way.
        for (const bool boxFirst : {true, false})
        {
            const OracleTally t = boxFirst ? checkAgainstTheOracle(solids, boxes[k], link, 0.3, 300, 17 + k)
                                           : checkAgainstTheOracle(solids, link, boxes[k], 0.3, 300, 31 + k);
            all.apart += t.apart;
            all.provenApart += t.provenApart;
            all.overlapping += t.overlapping;
        }
    }
    std::printf("apart %d, proven %d; overlapping %d\n", all.apart, all.provenApart, all.overlapping);
    ASSERT_GT(all.apart, 300);
    ASSERT_GT(all.overlapping, 100);
    EXPECT_GT(all.provenApart, all.apart * 3 / 4) << all.provenApart << " of " << all.apart << " apart pairs proven";
}

namespace
{
/** \brief Largest amount by which a vertex of \a piece sticks out of its hull points' hull along any
    of \a directions random directions: a lower bound on the largest vertex distance from that hull,
    which the piece's hull slack must not undercut. */
double largestOvershoot(const rc::device::ConvexArrays &arrays, const rc::device::ConvexPiece &piece, int directions,
                        std::mt19937 &rng)
{
    std::normal_distribution<double> normal;
    double largest = 0.0;
    for (int k = 0; k < directions; ++k)
    {
        Vec u(normal(rng), normal(rng), normal(rng));
        u.normalize();
        const rc::device::Vec3<double> d{u.x(), u.y(), u.z()};
        const double overVertices =
            rc::device::supportValue(arrays.vertices + 3 * std::size_t{piece.firstVertex}, piece.numVertices, d);
        const double overHull =
            rc::device::supportValue(arrays.hullPoints + 3 * std::size_t{piece.firstHullPoint}, piece.numHullPoints, d);
        largest = std::max(largest, overVertices - overHull);
    }
    return largest;
}
}  // namespace

namespace
{
/** \brief Appends the Panda's links (MotionBenchMaker URDF) and their names, when the shared data is there. */
void addPandaLinks(rc::ConvexSolids &convex, std::vector<std::string> &names)
{
    const std::string root = rc::test::sharedData();
    if (root.empty())
        return;
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    for (const rc::Component &component : problem.robot->components)
    {
        convex.add(rc::MeshBvh(component.mesh), component.topology.closed);
        names.push_back(component.name);
    }
}
}  // namespace

TEST(Separation, TheHullSlackBoundsHowFarVerticesStickOutOfTheHullPointsHull)
{
    rc::ConvexSolids convex;
    convex.add(rc::MeshBvh(rc::makeBox(Vec(0.4, 0.1, 0.25))), true);  // 8 vertices: all hull points, no slack
    convex.add(rc::MeshBvh(rc::makeSphere(1.0, 1e-4)), true);         // 60 000 vertices on the unit sphere
    std::vector<std::string> names = {"box", "sphere"};
    addPandaLinks(convex, names);
    const rc::device::ConvexArrays arrays = convex.arrays();
    EXPECT_EQ(arrays.pieces[0].hullSlack, 0.0);
    // Between 128 extreme points of the unit sphere a vertex stands out by a few percent at most.
    EXPECT_GT(arrays.pieces[1].hullSlack, 1e-3);
    EXPECT_LT(arrays.pieces[1].hullSlack, 0.05);
    std::mt19937 rng(11);
    for (std::size_t s = 0; s < convex.numSolids(); ++s)
    {
        const rc::device::ConvexPiece &piece = arrays.pieces[arrays.solidPieces[s]];
        const double overshoot = largestOvershoot(arrays, piece, piece.numVertices > 1000 ? 2000 : 20000, rng);
        EXPECT_GE(piece.hullSlack, overshoot) << names[s];
        // Tight enough to pay: within a few times what random directions find.
        EXPECT_LE(piece.hullSlack, 3.0 * overshoot + 1e-5 * piece.radius) << names[s];
        std::printf("%-14s vertices %5u hull points %3u radius %.4f slack %.6f overshoot %.6f\n", names[s].c_str(),
                    piece.numVertices, piece.numHullPoints, piece.radius, piece.hullSlack, overshoot);
    }
}

TEST(Separation, TheCellSupportSearchFindsWhatReadingEveryHullPointFinds)
{
    rc::ConvexSolids convex;
    convex.add(rc::MeshBvh(rc::makeBox(Vec(0.4, 0.1, 0.25))), true);  // 8 hull points: searched one by one
    convex.add(rc::MeshBvh(rc::makeSphere(1.0, 1e-4)), true);         // 128 hull points in cells
    rc::Mesh rod = rc::makeCylinder(0.05, 2.0, 1e-4);                 // long and thin, far from its frame's origin
    rod.transform(Eigen::Isometry3d(Eigen::Translation3d(30.0, -20.0, 50.0)));
    convex.add(rc::MeshBvh(rod), true);
    std::vector<std::string> names = {"box", "sphere", "cylinder"};
    addPandaLinks(convex, names);
    const rc::device::ConvexArrays arrays = convex.arrays();
    EXPECT_EQ(arrays.pieces[0].hasSupportCells, 0u);
    EXPECT_EQ(arrays.pieces[1].hasSupportCells, 1u);
    // Directions a cell boundary, an edge or a corner of the cube map, an axis or a face's centre
    // passes through, which rounding may put in either cell, and random ones of every scale.
    std::vector<rc::device::Vec3<double>> directions;
    const double steps[] = {-1.0, -0.75, -0.5, -0.25, 0.0, 0.25, 0.5, 0.75, 1.0, 1e-300, -1e-17};
    for (const double a : steps)
        for (const double b : steps)
            for (const double scale : {1.0, -1.0, 3e-7, 2e5})
            {
                directions.push_back({scale, scale * a, scale * b});
                directions.push_back({scale * b, scale, scale * a});
                directions.push_back({scale * a, scale * b, scale});
            }
    std::mt19937 rng(5);
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> exponent(-3.0, 3.0);
    for (int trial = 0; trial < 20000; ++trial)
    {
        const double scale = std::pow(10.0, exponent(rng));
        directions.push_back({scale * normal(rng), scale * normal(rng), scale * normal(rng)});
    }
    for (std::size_t s = 0; s < convex.numSolids(); ++s)
    {
        const rc::device::ConvexProxy piece = rc::device::convexProxy(arrays, arrays.solidPieces[s]);
        if (piece.supportCellStart)
        {
            // Every cell lists a point, and on average under a tenth of them (what makes it fast).
            const std::uint32_t listed = piece.supportCellStart[rc::device::kSupportCells] - piece.supportCellStart[0];
            for (std::uint32_t cell = 0; cell < rc::device::kSupportCells; ++cell)
                EXPECT_LT(piece.supportCellStart[cell], piece.supportCellStart[cell + 1]) << names[s];
            EXPECT_LT(listed, rc::device::kSupportCells * piece.numHullPoints / 10) << names[s];
        }
        for (std::size_t k = 0; k < directions.size(); ++k)
        {
            const rc::device::Vec3<double> &d = directions[k];
            const double everyPoint = rc::device::supportValue(piece.hullPoints, piece.numHullPoints, d);
            const double *found = piece.hullPoints + 3 * rc::device::detail::hullSupportIndex(piece, d);
            ASSERT_EQ(d.x * found[0] + d.y * found[1] + d.z * found[2], everyPoint) << names[s] << " direction " << k;
        }
    }
}

TEST(Separation, TheSupportCellOfADirectionIsItsCubeFaceAndSquare)
{
    namespace dev = rc::device;
    constexpr std::uint32_t side = dev::kSupportCellsPerSide;
    // Face +x, the square at (y, z) / x = (-1, -1): row 0, column 0; (+1, +1) is the last row and column.
    EXPECT_EQ(dev::supportCell({1.0, -1.0 + 1e-9, -1.0 + 1e-9}), 0u);
    EXPECT_EQ(dev::supportCell({2.0, 2.0 - 1e-9, 2.0 - 1e-9}), side * side - 1);
    EXPECT_EQ(dev::supportCell({-3.0, 0.0, 0.0}), (1 * side + side / 2) * side + side / 2);  // face -x
    EXPECT_EQ(dev::supportCell({0.1, 0.5, 0.0}) / (side * side), 2u);                        // face +y
    EXPECT_EQ(dev::supportCell({0.0, -0.5, 0.1}) / (side * side), 3u);                       // face -y
    EXPECT_EQ(dev::supportCell({0.0, 0.0, 1e-300}) / (side * side), 4u);                     // face +z
    EXPECT_EQ(dev::supportCell({0.2, 0.3, -0.4}) / (side * side), 5u);                       // face -z
    // No cell: the zero direction, an infinite one and NaN (the search then reads every point).
    EXPECT_EQ(dev::supportCell({0.0, 0.0, 0.0}), dev::kSupportCells);
    EXPECT_EQ(dev::supportCell({std::numeric_limits<double>::infinity(), 0.0, 0.0}), dev::kSupportCells);
    EXPECT_EQ(dev::supportCell({0.0, std::numeric_limits<double>::quiet_NaN(), 1.0}), dev::kSupportCells);
}

namespace
{
/** \brief The test's own answer: the nearest point to the origin of the hull of \a points, the least
    norm over every face (every non-empty subset) whose projection of the origin falls inside it,
    solved with Eigen's least squares. */
double nearestNormOfHull(const std::vector<Vec> &points)
{
    const int count = static_cast<int>(points.size());
    double best = std::numeric_limits<double>::infinity();
    for (int mask = 1; mask < (1 << count); ++mask)
    {
        std::vector<Vec> face;
        for (int i = 0; i < count; ++i)
            if (mask & (1 << i))
                face.push_back(points[static_cast<std::size_t>(i)]);
        const int n = static_cast<int>(face.size()) - 1;
        if (n == 0)
        {
            best = std::min(best, face[0].norm());
            continue;
        }
        Eigen::MatrixXd edges(3, n);
        for (int k = 0; k < n; ++k)
            edges.col(k) = face[static_cast<std::size_t>(k + 1)] - face[0];
        const Eigen::VectorXd lambda = edges.colPivHouseholderQr().solve(-face[0]);
        if ((edges * lambda + face[0]).norm() > 1e-9 && n == 3)
            continue;  // a flat tetrahedron: its faces hold the answer
        if ((lambda.array() < 0.0).any() || lambda.sum() > 1.0)
            continue;
        best = std::min(best, (face[0] + edges * lambda).norm());
    }
    return best;
}
}  // namespace

TEST(Separation, GjksSimplexStepFindsTheNearestPointOfTheHull)
{
    // As GJK calls it: the simplex kept from the last step (whose nearest point is v), plus a point w
    // that gets closer along v (v . w < v . v). Only the faces that face the origin are searched
    // (signed volumes); the answer must be the hull's nearest point all the same.
    std::mt19937 rng(17);
    std::normal_distribution<double> normal;
    int origins = 0, steps = 0;
    for (int trial = 0; trial < 20000; ++trial)
    {
        const auto random = [&] { return rc::device::Vec3<double>{normal(rng), normal(rng), normal(rng)}; };
        rc::device::Vec3<double> simplex[4] = {random()};
        int count = 1;
        rc::device::Vec3<double> v = simplex[0];
        const int size = 2 + trial % 3;  // the simplex the step sees: 2, 3 or 4 points
        while (count < size)
        {
            rc::device::Vec3<double> w = random();
            if (!(rc::device::dot(v, w) < 0.9 * rc::device::dot(v, v)))
                continue;  // GJK adds only a point that gets closer
            simplex[count++] = w;
            std::vector<Vec> points;
            for (int i = 0; i < count; ++i)
                points.emplace_back(simplex[i].x, simplex[i].y, simplex[i].z);
            rc::device::Vec3<double> next = v;
            const rc::device::detail::SimplexStep step = rc::device::detail::closestOnSimplex(simplex, count, next);
            if (step == rc::device::detail::SimplexStep::OriginInside)
            {
                ++origins;
                EXPECT_LT(nearestNormOfHull(points), 1e-9) << "trial " << trial;
                break;
            }
            ASSERT_EQ(step, rc::device::detail::SimplexStep::Closer) << "trial " << trial;
            ++steps;
            const double expected = nearestNormOfHull(points);
            ASSERT_NEAR(std::sqrt(rc::device::dot(next, next)), expected, 1e-9 * (1.0 + expected)) << "trial " << trial;
            ASSERT_LT(rc::device::dot(next, next), rc::device::dot(v, v)) << "trial " << trial;
            v = next;
        }
    }
    EXPECT_GT(steps, 20000);
    EXPECT_GT(origins, 100);
}

TEST(Separation, GjksSimplexStepFindsTheNearestPointOfFlatSimplices)
{
    // Rounding and touching solids give GJK flat simplices: a tetrahedron in a plane, a triangle on
    // a line, a point twice. The nearest point of the hull must come back all the same (from the
    // faces the flat simplex is made of), never a claim that the origin lies inside.
    using V = rc::device::Vec3<double>;
    const std::vector<std::vector<V>> cases = {
        {{1, -1, 0.5}, {1, 1, 0.5}, {3, 0, 0.5}, {2, 0, 0.5}},                 // a flat tetrahedron above the origin
        {{-1, -1, 0}, {1, -1, 0}, {0, 2, 0}, {0, 0.5, 0}},                     // flat, around the origin
        {{-1, 1, 1}, {1, 1, 1}, {3, 1, 1}},                                    // a triangle on a line
        {{2, 0, 0}, {2, 0, 0}, {2, 1, 0}},                                     // a point twice
        {{2, 0, 0}, {2, 0, 0}},                                                // a segment of no length
        {{0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}},  // one point four times
        {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}},                        // flat, the origin inside it
    };
    for (std::size_t c = 0; c < cases.size(); ++c)
    {
        V simplex[4];
        std::vector<Vec> points;
        for (std::size_t i = 0; i < cases[c].size(); ++i)
        {
            simplex[i] = cases[c][i];
            points.emplace_back(simplex[i].x, simplex[i].y, simplex[i].z);
        }
        int count = static_cast<int>(cases[c].size());
        V next{};
        double weights[4];
        V companion[4] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
        ASSERT_EQ(rc::device::detail::closestOnSimplex(simplex, count, next, companion, weights),
                  rc::device::detail::SimplexStep::Closer)
            << "case " << c;
        EXPECT_NEAR(std::sqrt(rc::device::dot(next, next)), nearestNormOfHull(points), 1e-12) << "case " << c;
        // The kept points, their companions and weights say the same point.
        ASSERT_GE(count, 1);
        V fromWeights{0, 0, 0};
        double sum = 0.0;
        for (int i = 0; i < count; ++i)
        {
            EXPECT_GE(weights[i], 0.0) << "case " << c;
            sum += weights[i];
            fromWeights = fromWeights + weights[i] * simplex[i];
            const auto original = static_cast<std::size_t>(companion[i].x);
            EXPECT_EQ(simplex[i].x, cases[c][original].x) << "case " << c;
            EXPECT_EQ(simplex[i].y, cases[c][original].y) << "case " << c;
            EXPECT_EQ(simplex[i].z, cases[c][original].z) << "case " << c;
        }
        EXPECT_NEAR(sum, 1.0, 1e-12) << "case " << c;
        EXPECT_NEAR(fromWeights.x, next.x, 1e-12) << "case " << c;
        EXPECT_NEAR(fromWeights.y, next.y, 1e-12) << "case " << c;
        EXPECT_NEAR(fromWeights.z, next.z, 1e-12) << "case " << c;
    }
}

TEST(Separation, GjksSimplexStepWritesNothingForNaNCoordinates)
{
    // A NaN support point (a NaN pose) must not leave a simplex of no points behind: nothing is
    // written, and the caller, seeing no progress, stops.
    using V = rc::device::Vec3<double>;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int count0 = 1; count0 <= 4; ++count0)
    {
        V simplex[4] = {{nan, 0, 0}, {nan, 1, 0}, {nan, 0, 1}, {nan, 1, 1}};
        int count = count0;
        V next{3.0, 4.0, 5.0};
        EXPECT_EQ(rc::device::detail::closestOnSimplex(simplex, count, next), rc::device::detail::SimplexStep::Closer);
        EXPECT_EQ(count, count0);
        EXPECT_EQ(next.x, 3.0);
        EXPECT_EQ(next.y, 4.0);
        EXPECT_EQ(next.z, 5.0);
    }
}

namespace
{
/** \brief Checks that solid \a solid's patch tree in \a arrays is a cut of \a tree (the solid's
    triangle tree): its root stands for the tree's root, an inner patch node for an inner tree node
    whose two children its two children stand for, in order, and a patch holds exactly the triangles
    under its tree node, in slot order, with its box around them; every triangle of the mesh lies in
    exactly one patch. Returns the number of patches (0: the solid has no patch tree). */
std::size_t expectPatchesCutTheTree(const rc::device::ConvexArrays &arrays, std::size_t solid, const rc::MeshBvh &tree,
                                    const std::string &name)
{
    const rc::device::PatchNode *nodes = arrays.patchNodes + arrays.solidPatchNodes[solid];
    const std::uint32_t numNodes = arrays.solidPatchNodes[solid + 1] - arrays.solidPatchNodes[solid];
    if (numNodes == 0)
        return 0;
    const rc::Mesh &mesh = tree.mesh();
    const std::vector<rc::MeshBvh::SlotRange> slots = tree.nodeSlotRanges();
    std::vector<int> inPatches(mesh.numTriangles(), 0);
    std::vector<int> visited(numNodes, 0);
    std::size_t patches = 0;
    EXPECT_EQ(nodes[0].treeNode, 0u) << name;
    std::vector<std::uint32_t> pending{0};
    while (!pending.empty())
    {
        const std::uint32_t i = pending.back();
        pending.pop_back();
        ++visited[i];
        const rc::device::PatchNode &node = nodes[i];
        EXPECT_LT(node.treeNode, tree.numNodes()) << name;
        if (node.treeNode >= tree.numNodes())
            continue;
        const rc::MeshBvh::Node &treeNode = tree.nodes()[node.treeNode];
        if (node.first >= 0)
        {
            EXPECT_FALSE(treeNode.isLeaf()) << name << ": patch node " << i << " is inner, its tree node a leaf";
            EXPECT_EQ(nodes[node.first].treeNode, static_cast<std::uint32_t>(treeNode.first)) << name;
            EXPECT_EQ(nodes[node.first + 1].treeNode, static_cast<std::uint32_t>(treeNode.first + 1)) << name;
            pending.push_back(static_cast<std::uint32_t>(node.first));
            pending.push_back(static_cast<std::uint32_t>(node.first + 1));
            continue;
        }
        ++patches;
        const rc::device::ConvexPiece &patch = arrays.patchPieces[-(node.first + 1)];
        const rc::MeshBvh::SlotRange range = slots[node.treeNode];
        EXPECT_TRUE(treeNode.isLeaf() || range.end - range.begin <= rc::kPatchTriangles) << name;
        EXPECT_EQ(patch.numTriangles, range.end - range.begin) << name << ": patch node " << i;
        if (patch.numTriangles != range.end - range.begin)
            continue;
        const double *vertices = arrays.vertices + 3 * std::size_t{patch.firstVertex};
        const std::uint32_t *triangles = arrays.patchTriangles + 3 * std::size_t{patch.firstTriangle};
        for (std::uint32_t t = 0; t < patch.numTriangles; ++t)
        {
            const std::uint32_t triangle = tree.triangleOrder()[range.begin + t];
            ++inPatches[triangle];
            for (int k = 0; k < 3; ++k)
            {
                const Vec &expected = mesh.vertices[mesh.triangles[triangle][k]];
                const double *corner = vertices + 3 * std::size_t{triangles[3 * t + k]};
                EXPECT_EQ(Vec(corner[0], corner[1], corner[2]), expected)
                    << name << ": patch node " << i << " triangle " << t << " corner " << k;
                for (int d = 0; d < 3; ++d)
                {
                    EXPECT_LE(node.min[d], expected[d]) << name;
                    EXPECT_GE(node.max[d], expected[d]) << name;
                }
            }
        }
    }
    for (std::uint32_t i = 0; i < numNodes; ++i)
        EXPECT_EQ(visited[i], 1) << name << ": patch node " << i << " reached " << visited[i] << " times";
    for (std::size_t t = 0; t < inPatches.size(); ++t)
        EXPECT_EQ(inPatches[t], 1) << name << ": triangle " << t << " in " << inPatches[t] << " patches";
    return patches;
}
}  // namespace

TEST(Separation, EveryPatchIsTheSubtreeOfOneNodeOfTheSolidsTriangleTree)
{
    const std::vector<std::pair<std::string, rc::Mesh>> meshes = {{"room", rc::test::roomWithDoorway()},
                                                                  {"u_shape", rc::test::uShape()},
                                                                  {"maze", rc::test::mazeOnSlab()},
                                                                  {"bookshelf", rc::test::bookshelf()}};
    for (const unsigned leafTriangles : {1u, 2u, 4u})
    {
        rc::ConvexSolids convex;
        std::vector<std::unique_ptr<rc::MeshBvh>> trees;
        for (const auto &[name, mesh] : meshes)
        {
            trees.push_back(std::make_unique<rc::MeshBvh>(mesh, leafTriangles));
            convex.add(*trees.back(), true);
        }
        for (std::size_t s = 0; s < meshes.size(); ++s)
        {
            const std::string name = meshes[s].first + " (" + std::to_string(leafTriangles) + " per leaf)";
            const std::size_t patches = expectPatchesCutTheTree(convex.arrays(), s, *trees[s], name);
            // Non-convex, so cut into patches, some of several triangles (flat pieces of walls).
            EXPECT_GT(patches, 4u) << name;
            EXPECT_LT(patches, meshes[s].second.numTriangles() * 2 / 3) << name;
        }
    }
}

TEST(Separation, TheModelsPatchesAreCutsOfTheTreesItsExactPhaseWalks)
{
    const std::string root = rc::test::sharedData();
    if (root.empty())
        GTEST_SKIP() << "shared data not found (set RASTERCHECK_DATA): the Panda's meshes are needed";
    const rc::Problem problem = rc::test::pandaProblem(root, "bookshelf_small");
    auto scene = std::make_shared<rc::Scene>(*problem.scene);
    scene->addObject("bookshelf", rc::test::bookshelf());
    scene->addObject("room", rc::test::roomWithDoorway());
    const rc::CollisionModel model(problem.robot, scene);
    const rc::device::ConvexArrays arrays = model.convex.arrays();
    std::size_t patched = 0;
    for (std::size_t k = 0; k < model.numComponents(); ++k)
        patched += expectPatchesCutTheTree(arrays, k, *model.componentBvhs[k], problem.robot->components[k].name) > 0;
    for (std::size_t o = 0; o < model.numObjects(); ++o)
        patched += expectPatchesCutTheTree(arrays, model.numComponents() + o, *model.objectBvhs[o],
                                           scene->objects[o].name) > 0;
    EXPECT_GE(patched, 3u);  // the open link6, the bookshelf and the room at least
}
