#pragma once

// The hull test: a proof, by a plane between them, that two solids are more than the padding
// apart (the convex separation cull), or, for closed shells close to convex, a point inside both
// (an overlap proof, used when no contact is asked). It runs after the box culls, on the host
// (CpuBackend) and on the device (BatchPipeline), in double on both: most pairs the boxes pass are
// still apart, and the plane settles them for a few thousand multiply-adds where the exact narrow
// phase walks two BVHs; most of the others collide, and the point settles many of those.

#include <cstddef>
#include <cstdint>

#include "rastercheck/device/Pose.h"

namespace rastercheck::device
{
/** \brief The support search's direction cells (ConvexArrays::supportCellStart): the directions of
    space as a cube map, each face of the cube cut into kSupportCellsPerSide x kSupportCellsPerSide
    cells. A piece with many hull points lists, per cell, every hull point that is the extreme one
    along some direction of the cell (a superset, sure up to rounding: see ConvexSolids), so the
    search along a direction reads the few points of its cell instead of all of them. */
constexpr std::uint32_t kSupportCellsPerSide = 8;
constexpr std::uint32_t kSupportCells = 6 * kSupportCellsPerSide * kSupportCellsPerSide;
/** \brief Fewest hull points for which a piece gets cells; fewer are searched one by one. */
constexpr std::uint32_t kSupportCellsMinPoints = 32;
/** \brief A hull point's number within its piece, as the cells list them (so a piece has at most
    65536 hull points: rastercheck::kConvexHullDirections). */
using HullPointNumber = std::uint16_t;

/** \brief The cell of direction \a d (supportCellStart's order: face +x, -x, +y, -y, +z, -z, then row
    and column), or kSupportCells for a direction with no cell: zero, infinite or NaN. */
RC_HD std::uint32_t supportCell(const Vec3<double> &d)
{
    const double ax = d.x < 0 ? -d.x : d.x, ay = d.y < 0 ? -d.y : d.y, az = d.z < 0 ? -d.z : d.z;
    constexpr double kLargest = 1.7976931348623157e308;  // DBL_MAX: an infinite or NaN sum fails the test
    if (!(ax + ay + az <= kLargest) || ax + ay + az == 0.0)
        return kSupportCells;
    std::uint32_t face;
    double major, u, v;
    if (ax >= ay && ax >= az)
    {
        face = d.x > 0 ? 0u : 1u;
        major = ax;
        u = d.y;
        v = d.z;
    }
    else if (ay >= az)
    {
        face = d.y > 0 ? 2u : 3u;
        major = ay;
        u = d.z;
        v = d.x;
    }
    else
    {
        face = d.z > 0 ? 4u : 5u;
        major = az;
        u = d.x;
        v = d.y;
    }
    // u / major and v / major lie in [-1, 1]; their cells are kSupportCellsPerSide equal steps.
    const auto step = [major](double coordinate)
    {
        const double position = (coordinate / major + 1.0) * (0.5 * kSupportCellsPerSide);
        constexpr std::uint32_t last = kSupportCellsPerSide - 1;
        return position >= static_cast<double>(last) ? last
                                                     : (position > 0.0 ? static_cast<std::uint32_t>(position) : 0u);
    };
    const std::uint32_t row = step(u), column = step(v);
    return (face * kSupportCellsPerSide + row) * kSupportCellsPerSide + column;
}

/** \brief Where one convex piece's points lie in the flat arrays (ConvexArrays): every vertex of the
    piece (the piece lies in their convex hull) and a few of them that span that hull closely (the
    hull points, what GJK searches; no vertex lies farther than hullSlack from their hull). Offsets
    count points (3 doubles each), in the solid's own frame (components: link frame; objects: world
    frame). */
struct ConvexPiece
{
    std::uint32_t firstVertex;
    std::uint32_t numVertices;
    std::uint32_t firstHullPoint;
    std::uint32_t numHullPoints;
    double radius;     ///< largest distance of a vertex from the frame's origin
    double hullSlack;  ///< no vertex lies farther than this from the hull points' convex hull
    /** \brief The piece's face planes (ConvexArrays::planes), when it is a closed surface close
        enough to convex that a point behind all of them is worth looking for: such a point lies
        inside the solid. None (0) for open meshes. */
    std::uint32_t firstPlane;
    std::uint32_t numPlanes;
    double centre[3];  ///< the mean of the hull points: inside the hull, deep in a convex piece
    /** \brief 1 when every vertex is a triangle's corner (on the surface), open meshes included:
        such a vertex inside another solid proves an overlap. */
    std::uint32_t surfaceVertices;
    /** \brief The piece's triangle edges (ConvexArrays::edges, each once): a point of one inside
        another solid proves an overlap, like a vertex. */
    std::uint32_t firstEdge;
    std::uint32_t numEdges;
    /** \brief The piece's direction cells: ConvexArrays::supportCellStart[firstSupportCell ..
        firstSupportCell + kSupportCells] bound each cell's hull points in supportCandidates. Only
        when hasSupportCells (at least kSupportCellsMinPoints hull points); otherwise every hull
        point is searched. */
    std::uint32_t firstSupportCell;
    std::uint32_t hasSupportCells;
    /** \brief A patch's triangles (ConvexArrays::patchTriangles, vertex numbers within the piece),
        for the ray parity test of containment (SolidRelation.h); none (0) for other pieces. */
    std::uint32_t firstTriangle;
    std::uint32_t numTriangles;
    /** \brief 1 when the piece is a whole solid with an inside (a closed mesh). */
    std::uint32_t closed;
};

/** \brief A node of a solid's patch tree (ConvexArrays::patchNodes): the top of the solid's one
    triangle tree (MeshBvh, device::TreeNode), cut where a subtree is small and flat enough to be
    one patch, a piece of up to a few dozen triangles with a hull of its own
    (ConvexArrays::patchPieces). Node for node it mirrors the triangle tree above the cut (same
    splits, same child order), so a patch holds exactly the triangles under its tree node. The
    box bounds every vertex below the node, in the solid's own frame, in double: the separation
    proofs run in double and test it against a piece's exact bounds. */
struct PatchNode
{
    double min[3];
    double max[3];
    /** \brief Inner node: index of the first child (the second follows it) within the solid's
        nodes, >= 1. Leaf: -(1 + the patch's index in ConvexArrays::patchPieces). */
    std::int32_t first;
    /** \brief The node of the solid's triangle tree this node stands for (its index within that
        mesh's tree, MeshSlice::firstNode onwards in CollisionModel's tree arrays). */
    std::uint32_t treeNode;
};

/** \brief The separation cull's view of every solid (CollisionModel::convex): solid s owns pieces
    [solidPieces[s], solidPieces[s + 1]): first its whole mesh, then, when the mesh is made of
    several closed shells (a link with several collision elements), each shell on its own. */
struct ConvexArrays
{
    const double *vertices;
    const double *hullPoints;
    const ConvexPiece *pieces;
    const std::uint32_t *solidPieces;
    const double *planes;                   ///< n_planes x 4: unit outward normal and offset (n . x = d on the face)
    const std::uint32_t *edges;             ///< n_edges x 2: vertex numbers within the piece
    const std::uint32_t *supportCellStart;  ///< per piece with cells, kSupportCells + 1 offsets
    const HullPointNumber *supportCandidates;  ///< hull point numbers within the piece, ascending per cell
    /** \brief Solid s's patch tree is patchNodes[solidPatchNodes[s] .. solidPatchNodes[s + 1]),
        root first; an empty range: the solid has none (it is small, or close to convex). */
    const PatchNode *patchNodes;
    const std::uint32_t *solidPatchNodes;  ///< n_solids + 1
    const ConvexPiece *patchPieces;        ///< n_patches; offsets into the arrays above
    const std::uint32_t *patchTriangles;   ///< n_patch_triangles x 3: vertex numbers within the patch
};

/** \brief One piece as the separation test reads it: pointers into the flat arrays. */
struct ConvexProxy
{
    const double *vertices;
    std::uint32_t numVertices;
    const double *hullPoints;
    std::uint32_t numHullPoints;
    double radius;
    double hullSlack;
    const double *planes;
    std::uint32_t numPlanes;
    Vec3<double> centre;
    bool surfaceVertices;
    const std::uint32_t *edges;
    std::uint32_t numEdges;
    const std::uint32_t *supportCellStart;  ///< null: every hull point is searched
    const HullPointNumber *supportCandidates;
};

RC_HD ConvexProxy convexProxy(const ConvexArrays &arrays, const ConvexPiece &p)
{
    return ConvexProxy{arrays.vertices + 3 * static_cast<std::size_t>(p.firstVertex),
                       p.numVertices,
                       arrays.hullPoints + 3 * static_cast<std::size_t>(p.firstHullPoint),
                       p.numHullPoints,
                       p.radius,
                       p.hullSlack,
                       arrays.planes + 4 * static_cast<std::size_t>(p.firstPlane),
                       p.numPlanes,
                       Vec3<double>{p.centre[0], p.centre[1], p.centre[2]},
                       p.surfaceVertices != 0,
                       arrays.edges + 2 * static_cast<std::size_t>(p.firstEdge),
                       p.numEdges,
                       p.hasSupportCells ? arrays.supportCellStart + p.firstSupportCell : nullptr,
                       arrays.supportCandidates};
}

RC_HD ConvexProxy convexProxy(const ConvexArrays &arrays, std::uint32_t piece)
{
    return convexProxy(arrays, arrays.pieces[piece]);
}

/** \brief Relative rounding slack of the separation proof: a gap must exceed the padding by this
    fraction of the coordinates' magnitudes. It dwarfs the few ulps (1e-16) the projections lose
    and the oracle's own rounding, so a proof never contradicts the oracle. */
constexpr double kSeparationSlack = 1e-12;

/** \brief Relative slack of the overlap proof's plane tests, of the pieces' radii: it covers the
    tilt rounding gives a face's unit normal (under 1e-11 for faces ConvexSolids keeps planes of)
    over the distance from the face to the point tested. */
constexpr double kPlaneSlack = 1e-9;

/** \brief Most vertex x face-plane tests the overlap proof spends scanning every vertex of one piece
    against the other's planes (surfaceVertexInside), and edge x face-plane tests clipping every
    edge (surfaceEdgeInside), when the hulls meet and the cheaper candidates failed. Most vertices fail at the first
   planes, so a scan costs far less than its bound; it replaces an exact narrow phase that walks both BVHs. */
constexpr double kVertexScanBudget = 65536.0;

/** \brief What the hull test settled about a pair of solids. */
enum class HullRelation
{
    Apart,        ///< proven more than the padding apart
    Overlapping,  ///< proven to share a point (relateHulls says how)
    Unknown       ///< neither: the exact narrow phase decides
};

/** \brief max over points p of d . p; points x y z. */
RC_HD double supportValue(const double *points, std::uint32_t count, const Vec3<double> &d,
                          std::uint32_t *argmax = nullptr)
{
    double best = d.x * points[0] + d.y * points[1] + d.z * points[2];
    std::uint32_t bestIndex = 0;
    RC_ROLLED_LOOP
    for (std::uint32_t i = 1; i < count; ++i)
    {
        const double value = d.x * points[3 * i] + d.y * points[3 * i + 1] + d.z * points[3 * i + 2];
        if (value > best)
        {
            best = value;
            bestIndex = i;
        }
    }
    if (argmax)
        *argmax = bestIndex;
    return best;
}

/** \brief R^T v: a world direction in the pose's own frame. */
RC_HD Vec3<double> inverseRotate(const Pose<double> &pose, const Vec3<double> &v)
{
    const double *m = pose.m;
    return {m[0] * v.x + m[4] * v.y + m[8] * v.z, m[1] * v.x + m[5] * v.y + m[9] * v.z,
            m[2] * v.x + m[6] * v.y + m[10] * v.z};
}

RC_HD Vec3<double> translationOf(const Pose<double> &pose)
{
    return {pose.m[3], pose.m[7], pose.m[11]};
}

/** \brief The gap between A and B along direction \a v of A's frame (pointing from B towards A),
    over every vertex, with B placed in A's frame by \a bInA: min over A's vertices of v . x minus
    max over B's, which is |v| times the distance the plane normal to v leaves between them. A gap
    above the padding (plus rounding slack) is the proof: each solid lies in the convex hull of its
    vertices. */
RC_HD double gapAlong(const Vec3<double> &v, const ConvexProxy &a, const ConvexProxy &b, const Pose<double> &bInA)
{
    const double lowestA = -supportValue(a.vertices, a.numVertices, Vec3<double>{-v.x, -v.y, -v.z});
    const double highestB =
        supportValue(b.vertices, b.numVertices, inverseRotate(bInA, v)) + dot(v, translationOf(bInA));
    return lowestA - highestB;
}

namespace detail
{
/** \brief What closestOnSimplex() found. */
enum class SimplexStep
{
    Closer,       ///< \a closest and the sub-simplex are written (NaN coordinates: nothing); the caller
                  ///< checks that it got closer
    OriginInside  ///< the origin lies inside a full tetrahedron (the hulls meet)
};

/** \brief The nearest point to the origin found so far among faces of a simplex: its squared norm,
    the face holding it (\a mask: bit i for simplex point i) and its barycentric weights there, in
    the order of the face's points in the simplex. */
struct FaceNearest
{
    Vec3<double> point{0.0, 0.0, 0.0};
    double norm = HUGE_VAL;
    double weights[3] = {0.0, 0.0, 0.0};
    int mask = 0;

    /** \brief Keeps point \a p of face \a faceMask, with weights \a w0 .. \a w2 of the face's points
        (in simplex order), when it is nearer. */
    RC_HD void keep(const Vec3<double> &p, int faceMask, double w0, double w1 = 0.0, double w2 = 0.0)
    {
        const double pp = dot(p, p);
        if (!(pp < norm))
            return;
        point = p;
        norm = pp;
        weights[0] = w0;
        weights[1] = w1;
        weights[2] = w2;
        mask = faceMask;
    }
};

/** \brief Keeps the nearest point of segment simplex[i] simplex[j] (i < j) in \a best when it is
    nearer. */
RC_HD_CALL void nearestOnSegment(const Vec3<double> *simplex, int i, int j, FaceNearest &best)
{
    const Vec3<double> t = simplex[j] - simplex[i];
    const double tt = dot(t, t);
    const double u = tt > 0.0 ? -dot(simplex[i], t) / tt : 0.0;  // the weight of j
    if (!(u > 0.0))
        best.keep(simplex[i], 1 << i, 1.0);
    else if (!(u < 1.0))
        best.keep(simplex[j], 1 << j, 1.0);
    else
        best.keep(simplex[i] + u * t, (1 << i) | (1 << j), 1.0 - u, u);
}

/** \brief Keeps the nearest point of triangle simplex[i] simplex[j] simplex[k] (i < j < k) in \a best when it is
    nearer: the origin's projection on its plane when that falls inside, else the nearest point of
    the edges opposite the corners whose weight is not positive (the edges whose lines part the
    projection from the triangle); of every edge when the triangle is flat. It and nearestOnSegment
    are calls of their own on the device: inlined at each of closestOnSimplex's call sites they added
    32 registers a thread to the light proof (sm_90, docs/benchmarks.md). */
RC_HD_CALL void nearestOnTriangle(const Vec3<double> *simplex, int i, int j, int k, FaceNearest &best)
{
    const Vec3<double> s0 = simplex[i], e0 = simplex[j] - s0, e1 = simplex[k] - s0;
    const double a00 = dot(e0, e0), a01 = dot(e0, e1), a11 = dot(e1, e1);
    const double det = a00 * a11 - a01 * a01;
    bool opposite[3] = {true, true, true};  // the edges to search: opposite corner i, j, k
    if (det > 1e-12 * a00 * a11)
    {
        const double b0 = -dot(e0, s0), b1 = -dot(e1, s0);
        const double lj = (b0 * a11 - b1 * a01) / det, lk = (a00 * b1 - a01 * b0) / det, li = 1.0 - lj - lk;
        if (li > 0.0 && lj > 0.0 && lk > 0.0)
        {
            best.keep(s0 + lj * e0 + lk * e1, (1 << i) | (1 << j) | (1 << k), li, lj, lk);
            return;
        }
        opposite[0] = !(li > 0.0);
        opposite[1] = !(lj > 0.0);
        opposite[2] = !(lk > 0.0);
    }
    if (opposite[0])
        nearestOnSegment(simplex, j, k, best);
    if (opposite[1])
        nearestOnSegment(simplex, i, k, best);
    if (opposite[2])
        nearestOnSegment(simplex, i, j, best);
}

/** \brief Closest point to the origin of the convex hull of simplex[0..count) (count 1 to 4), and
    the smallest sub-simplex whose hull holds it, written back in place: the signed-volume
    sub-algorithm (Montanari, Petrinic and Barbieri, "Improving the GJK algorithm for faster and more
    robust distance queries between convex objects", ACM TOG 2017). The origin's barycentric
    weights in the full simplex say which faces can hold the nearest point (those opposite a corner
    whose weight is not positive: only they face the origin), and only those are searched, down to
    edges and corners; a flat simplex searches all of its faces. \a companion (optional) is kept in
    step with the simplex; \a weights (optional, 4) receives the barycentric weights of the closest
    point on the kept sub-simplex, or of the origin in the tetrahedron that holds it. Where no face
    gives a number (NaN coordinates) nothing is written: \a closest stays as given, which the
    callers read as no progress. */
RC_HD SimplexStep closestOnSimplex(Vec3<double> *simplex, int &count, Vec3<double> &closest,
                                   Vec3<double> *companion = nullptr, double *weights = nullptr)
{
    FaceNearest best;
    if (count == 1)
        best.keep(simplex[0], 1, 1.0);
    else if (count == 2)
        nearestOnSegment(simplex, 0, 1, best);
    else if (count == 3)
        nearestOnTriangle(simplex, 0, 1, 2, best);
    else
    {
        const Vec3<double> s0 = simplex[0], e0 = simplex[1] - s0, e1 = simplex[2] - s0, e2 = simplex[3] - s0;
        const double det = dot(e0, cross(e1, e2));
        const double scale = sqrt(dot(e0, e0) * dot(e1, e1) * dot(e2, e2));
        bool opposite[4] = {true, true, true, true};  // the faces to search: opposite corner 0 .. 3
        if (det > 1e-9 * scale || -det > 1e-9 * scale)
        {
            const Vec3<double> minusS0 = {-s0.x, -s0.y, -s0.z};
            const double l1 = dot(minusS0, cross(e1, e2)) / det;
            const double l2 = dot(e0, cross(minusS0, e2)) / det;
            const double l3 = dot(e0, cross(e1, minusS0)) / det;
            const double l0 = 1.0 - l1 - l2 - l3;
            if (l0 > 0.0 && l1 > 0.0 && l2 > 0.0 && l3 > 0.0)
            {
                if (weights)
                {
                    weights[0] = l0;
                    weights[1] = l1;
                    weights[2] = l2;
                    weights[3] = l3;
                }
                return SimplexStep::OriginInside;
            }
            opposite[0] = !(l0 > 0.0);
            opposite[1] = !(l1 > 0.0);
            opposite[2] = !(l2 > 0.0);
            opposite[3] = !(l3 > 0.0);
        }
        if (opposite[0])
            nearestOnTriangle(simplex, 1, 2, 3, best);
        if (opposite[1])
            nearestOnTriangle(simplex, 0, 2, 3, best);
        if (opposite[2])
            nearestOnTriangle(simplex, 0, 1, 3, best);
        if (opposite[3])
            nearestOnTriangle(simplex, 0, 1, 2, best);
    }
    if (best.mask == 0)
        return SimplexStep::Closer;  // no face gave a number (NaN coordinates): no progress
    closest = best.point;
    int kept = 0;
    for (int i = 0; i < count; ++i)
        if (best.mask & (1 << i))
        {
            if (companion)
                companion[kept] = companion[i];
            simplex[kept++] = simplex[i];
        }
    if (weights)
        for (int i = 0; i < 4; ++i)
            weights[i] = i < 3 ? best.weights[i] : 0.0;
    count = kept;
    return SimplexStep::Closer;
}

/** \brief The hull point of \a solid extreme along \a d (its own frame): among the points of \a d's
    cell (kSupportCells) when the piece has cells, else among all. The same maximum as a search of
    every hull point, since a cell lists every point that can be extreme in it (test_separation
    checks it); on the Panda MotionBenchMaker
    edges it halved the time of the hull tests' support search (docs/benchmarks.md). */
RC_HD std::uint32_t hullSupportIndex(const ConvexProxy &solid, const Vec3<double> &d)
{
    std::uint32_t index = 0;
    const std::uint32_t cell = solid.supportCellStart ? supportCell(d) : kSupportCells;
    if (cell == kSupportCells)
    {
        supportValue(solid.hullPoints, solid.numHullPoints, d, &index);
        return index;
    }
    const HullPointNumber *candidate = solid.supportCandidates + solid.supportCellStart[cell];
    const HullPointNumber *end = solid.supportCandidates + solid.supportCellStart[cell + 1];
    index = *candidate;
    const double *first = solid.hullPoints + 3 * index;
    double best = d.x * first[0] + d.y * first[1] + d.z * first[2];
    RC_ROLLED_LOOP
    for (++candidate; candidate < end; ++candidate)
    {
        const double *p = solid.hullPoints + 3 * *candidate;
        const double value = d.x * p[0] + d.y * p[1] + d.z * p[2];
        if (value > best)
        {
            best = value;
            index = *candidate;
        }
    }
    return index;
}

/** \brief The hull point of \a solid extreme along \a d, both in the solid's own frame. */
RC_HD Vec3<double> localSupport(const ConvexProxy &solid, const Vec3<double> &d)
{
    const double *p = solid.hullPoints + 3 * hullSupportIndex(solid, d);
    return {p[0], p[1], p[2]};
}

/** \brief The hull point of \a solid extreme along \a d, placed by \a pose (\a d in the frame the pose
    places the solid in: the world's, or another solid's). */
RC_HD Vec3<double> placedSupport(const ConvexProxy &solid, const Pose<double> &pose, const Vec3<double> &d)
{
    return transformPoint(pose, localSupport(solid, inverseRotate(pose, d)));
}

/** \brief True when world point \a x lies behind every face plane of \a piece (placed by \a pose)
    by more than \a margin. Then x is inside the solid: seen from x, every face of the closed,
    outward-oriented surface spans a positive solid angle, so x's winding number is positive, and
    it is an integer, so at least 1 (inside, as the oracle's containment test counts it). The
    margin covers the rounding of x and of the planes. */
RC_HD bool behindAllPlanesLocal(const ConvexProxy &piece, const Vec3<double> &local, double margin)
{
    if (piece.numPlanes == 0)
        return false;
    for (std::uint32_t f = 0; f < piece.numPlanes; ++f)
    {
        const double *plane = piece.planes + 4 * f;
        if (!(plane[0] * local.x + plane[1] * local.y + plane[2] * local.z - plane[3] < -margin))
            return false;
    }
    return true;
}

RC_HD bool behindAllPlanes(const ConvexProxy &piece, const Pose<double> &pose, const Vec3<double> &x, double margin)
{
    return behindAllPlanesLocal(piece, inverseRotate(pose, x - translationOf(pose)), margin);
}

/** \brief True when some vertex of \a p, all of whose vertices are corners of its triangles, lies
    behind every face plane of \a q (placed by their poses) by more than \a margin: p's surface then
    reaches inside q's solid (behindAllPlanes). Every vertex is read when p's vertex count times q's
    plane count is within kVertexScanBudget; most vertices fail at q's first planes. */
RC_HD bool surfaceVertexInside(const ConvexProxy &p, const Pose<double> &poseP, const ConvexProxy &q,
                               const Pose<double> &poseQ, double margin)
{
    if (!p.surfaceVertices || q.numPlanes == 0 || static_cast<double>(p.numVertices) * q.numPlanes > kVertexScanBudget)
        return false;
    const Pose<double> pInQ = relativePose(poseQ, poseP);
    for (std::uint32_t i = 0; i < p.numVertices; ++i)
    {
        const double *v = p.vertices + 3 * static_cast<std::size_t>(i);
        if (behindAllPlanesLocal(q, transformPoint(pInQ, Vec3<double>{v[0], v[1], v[2]}), margin))
            return true;
    }
    return false;
}

/** \brief True when some point of an edge of \a p's triangles lies behind every face plane of \a q
    by more than \a margin (checked again on the point itself): p's surface reaches inside q's solid.
    Each edge is clipped to the region behind q's planes (Cyrus-Beck); most leave it at the first
    planes. Read when p's edge count times q's plane count is within kVertexScanBudget. */
RC_HD bool surfaceEdgeInside(const ConvexProxy &p, const Pose<double> &poseP, const ConvexProxy &q,
                             const Pose<double> &poseQ, double margin)
{
    if (p.numEdges == 0 || q.numPlanes == 0 || static_cast<double>(p.numEdges) * q.numPlanes > kVertexScanBudget)
        return false;
    const Pose<double> pInQ = relativePose(poseQ, poseP);
    const auto vertex = [&](std::uint32_t i)
    {
        const double *v = p.vertices + 3 * static_cast<std::size_t>(i);
        return transformPoint(pInQ, Vec3<double>{v[0], v[1], v[2]});
    };
    for (std::uint32_t e = 0; e < p.numEdges; ++e)
    {
        const Vec3<double> x0 = vertex(p.edges[2 * e]), x1 = vertex(p.edges[2 * e + 1]);
        double from = 0.0, to = 1.0;  // the part of the edge behind the planes seen so far
        for (std::uint32_t f = 0; f < q.numPlanes && from < to; ++f)
        {
            const double *plane = q.planes + 4 * f;
            // Height above the plane plus the margin, at either end: below 0 is far enough behind.
            const double h0 = plane[0] * x0.x + plane[1] * x0.y + plane[2] * x0.z - plane[3] + margin;
            const double h1 = plane[0] * x1.x + plane[1] * x1.y + plane[2] * x1.z - plane[3] + margin;
            if (h0 >= 0.0 && h1 >= 0.0)
                from = to;
            else if (h0 >= 0.0)
                from = from > h0 / (h0 - h1) ? from : h0 / (h0 - h1);
            else if (h1 >= 0.0)
                to = to < h0 / (h0 - h1) ? to : h0 / (h0 - h1);
        }
        if (from < to && behindAllPlanesLocal(q, x0 + (0.5 * (from + to)) * (x1 - x0), margin))
            return true;
    }
    return false;
}

/** \brief relateHulls' overlap proofs, once the origin lies on or in its simplex (\a count points of
    A - B, A's frame, with A's point of each in \a onA and the origin's weights). The same weights
    on A's points give a point of both hulls; it or a point halfway to either piece's centre,
    behind every face of both, proves it. So does a vertex of one (a point of its surface: an open
    mesh too) behind every face of the other: that surface reaches inside the other solid. A call
    of its own on a GPU: the GJK loop's registers are not held through it. It takes no world pose
    (surfacesProvenInside, the scans that follow when asked, does), so where the scans are not
    asked (the light proof) both poses die once B's pose in A's frame is made. */
RC_HD_CALL bool overlapProvenInA(const ConvexProxy &a, const ConvexProxy &b, const Pose<double> &bInA,
                                 const Vec3<double> *onA, const Vec3<double> *simplex, const double *weights, int count,
                                 double planeMargin)
{
    if (a.numPlanes > 0 && b.numPlanes > 0)
    {
        Vec3<double> shared = weights[0] * onA[0];
        for (int i = 1; i < count; ++i)
            shared = shared + weights[i] * onA[i];
        const Vec3<double> candidates[3] = {shared, 0.5 * (shared + a.centre),
                                            0.5 * (shared + transformPoint(bInA, b.centre))};
        for (const Vec3<double> &x : candidates)
            if (behindAllPlanesLocal(a, x, planeMargin) && behindAllPlanes(b, bInA, x, planeMargin))
                return true;
    }
    for (int i = 0; i < count; ++i)
    {
        if (a.surfaceVertices && behindAllPlanes(b, bInA, onA[i], planeMargin))
            return true;
        if (b.surfaceVertices && behindAllPlanesLocal(a, onA[i] - simplex[i], planeMargin))
            return true;
    }
    return false;
}

/** \brief relateHulls' last overlap proofs: every vertex, then every edge, of each piece behind
    every face of the other. */
RC_HD_CALL bool surfacesProvenInside(const ConvexProxy &a, const Pose<double> &poseA, const ConvexProxy &b,
                                     const Pose<double> &poseB, double planeMargin)
{
    return surfaceVertexInside(a, poseA, b, poseB, planeMargin) ||
           surfaceVertexInside(b, poseB, a, poseA, planeMargin) || surfaceEdgeInside(a, poseA, b, poseB, planeMargin) ||
           surfaceEdgeInside(b, poseB, a, poseA, planeMargin);
}
}  // namespace detail

/** \brief An upper bound on the distance from \a x to the convex hull of \a piece's hull points
    (at least one): GJK on the set x - hull, whose point nearest the origin is x less the hull's
    point nearest x. Every v it visits lies in that set, so |v| bounds the distance however early
    it stops: at convergence, at \a enough (the caller keeps a maximum over many points and needs
    no less), or after 64 steps. 0 when the origin is found inside a tetrahedron of hull points: the
    barycentric test rounds, so the caller adds a slack (ConvexSolids: 1e-6 of the piece's radius).
    The support search reads the piece's cells where it has them (hullSupportIndex). For
    ConvexSolids at load time, on the host. */
RC_HD double hullDistanceBound(const Vec3<double> &x, const ConvexProxy &piece, double enough)
{
    const auto pointOfSet = [&](const Vec3<double> &d)  // the point of x - hull extreme along d
    {
        return x - detail::localSupport(piece, Vec3<double>{-d.x, -d.y, -d.z});
    };
    const double *points = piece.hullPoints;
    Vec3<double> v = x - Vec3<double>{points[0], points[1], points[2]};
    Vec3<double> simplex[4] = {v};
    int size = 1;
    for (int iteration = 0; iteration < 64; ++iteration)
    {
        const double vv = dot(v, v);
        if (!(vv > enough * enough))
            break;
        const Vec3<double> w = pointOfSet(Vec3<double>{-v.x, -v.y, -v.z});
        if (vv - dot(v, w) <= 1e-12 * vv)
            break;  // converged
        simplex[size++] = w;
        Vec3<double> next = v;
        const detail::SimplexStep step = detail::closestOnSimplex(simplex, size, next);
        if (step == detail::SimplexStep::OriginInside)
            return 0.0;
        if (!(dot(next, next) < vv))
            break;
        v = next;
    }
    return std::sqrt(dot(v, v));
}

/** \brief Are pieces A and B (placed by their poses, world frame) provably more than \a padding
    apart, or, when \a proveOverlap and both have face planes (ConvexPiece::numPlanes), provably
    overlapping? GJK (van den Bergen's distance loop) over the hull points proposes the direction
    between the solids' nearest points. The hull points' gap along it proves the pair apart when it
    clears the padding plus both pieces' hull slacks (most pairs end there, after a few hundred
    multiply-adds); otherwise gapAlong() tries the proof over every vertex, once along the first
    direction that looks good enough and once along the converged one. Apart or Overlapping only
    with a proof, so the answer is conservative whatever GJK does; Unknown sends the pair on to the
    exact narrow phase. For convex meshes of no more than rastercheck::kConvexHullDirections
    (1024) vertices, every vertex is a hull point and the proof is found whenever the solids are
    apart by more than the padding; finer meshes need a little more (the hull points' direction is
    off by up to the directions' spacing: two unit spheres of 60 000 vertices, 0.0499 apart, are
    proven apart up to a padding of 0.0493). A GJK over every vertex closes that gap but did not
    pay: on the Panda's MotionBenchMaker scenes it settled no more pairs. Meshes without vertices are never
    proven apart (the caller decides those).

    Overlap: when GJK finds the origin in the hull of its simplex of hull-point differences, the
    same weights on A's points give a point of both hulls, often on the surface of one (a small
    solid inside a large one). It and the points halfway from it to either piece's centre are
    tried; one that lies behind every face of both pieces (behindAllPlanes) lies inside both
    solids. The simplex's own points are vertices of A and of B: one behind every face of the
    other piece puts a point of its surface inside that solid, which proves the overlap even for
    an open mesh (the surface and the solid meet, or the whole shell lies inside, which the
    oracle's containment test finds). Failing those, every vertex, then every edge, of each piece
    is looked for behind every face of the other (surfaceVertexInside, surfaceEdgeInside): a bar
    through a box has no vertex inside it, but its edges run through. Most pairs that reach the
    exact narrow phase while planning collide (99 % on a Panda cage problem); the simplex's points
    settled 76 % of them there, and with the scans 98 %. */
RC_HD HullRelation relateHulls(const ConvexProxy &a, const Pose<double> &poseA, const ConvexProxy &b,
                               const Pose<double> &poseB, double padding, bool proveOverlap,
                               Vec3<double> *direction = nullptr, bool scanSurfaces = true)
{
    if (a.numHullPoints == 0 || b.numHullPoints == 0)
        return HullRelation::Unknown;
    constexpr int kMaxIterations = 32;
    const Vec3<double> ta = translationOf(poseA), tb = translationOf(poseB);
    // What the gap must clear: the padding and the rounding of coordinates this large (the world
    // poses' translations: B's pose in A's frame rounds at their scale too).
    const double rounding = kSeparationSlack * (a.radius + b.radius + std::sqrt(dot(ta, ta)) + std::sqrt(dot(tb, tb)));
    const double margin = padding + rounding;
    // Everything below runs in A's frame: A's points as stored, B's placed by one pose. Half the
    // rotations of placing both in the world, and one pose held instead of two (a GPU thread's
    // registers). Directions come in and go out in the world frame.
    const Pose<double> bInA = relativePose(poseA, poseB);
    // v: the closest point to the origin of the simplex's hull, a part of the Minkowski difference
    // A - B. The simplex starts as one point of A - B, so every step's v is no farther than the last.
    Vec3<double> v = Vec3<double>{0.0, 0.0, 0.0} - translationOf(bInA), onA[4];  // onA: A's point of each simplex point
    if (direction && dot(*direction, *direction) > 0.0)
    {
        // The direction that proved this pair apart at a nearby state (the caller's last call):
        // its gap settles most pairs at once; else its support points start GJK.
        const Vec3<double> d = inverseRotate(poseA, *direction);
        onA[0] = detail::localSupport(a, Vec3<double>{-d.x, -d.y, -d.z});
        v = onA[0] - detail::placedSupport(b, bInA, d);
        if (dot(d, v) > (margin + a.hullSlack + b.hullSlack) * std::sqrt(dot(d, d)))
            return HullRelation::Apart;
    }
    else
    {
        if (!(dot(v, v) > 0.0))
            v = {1.0, 0.0, 0.0};
        onA[0] = detail::localSupport(a, v);
        v = onA[0] - detail::placedSupport(b, bInA, Vec3<double>{-v.x, -v.y, -v.z});
    }
    Vec3<double> simplex[4] = {v};
    double weights[4] = {1.0, 0.0, 0.0, 0.0};  // v = sum of weights[i] * simplex[i]
    int count = 1;
    const auto overlapProven = [&]()
    {
        const double planeMargin = rounding + kPlaneSlack * (a.radius + b.radius);
        return proveOverlap && (detail::overlapProvenInA(a, b, bInA, onA, simplex, weights, count, planeMargin) ||
                                (scanSurfaces && detail::surfacesProvenInside(a, poseA, b, poseB, planeMargin)));
    };
    // Reading every vertex is worth it for pieces of a few thousand; a solid finer than that has
    // patches (SolidRelation.h), whose own proofs read only the vertices near the other solid.
    const bool readEveryVertex = static_cast<double>(a.numVertices) + b.numVertices <= kVertexScanBudget;
    // A proof's direction, kept for the caller's next call on the same pair (a nearby state).
    const auto apart = [&](const Vec3<double> &proof)
    {
        if (direction)
            *direction = rotateVector(poseA, proof);
        return HullRelation::Apart;
    };
    bool proofTried = false;
    // The hull points' gap along v (times |v|), infinite until it is measured for the current v: no
    // vertex's gap along v is larger, since the hull points are vertices.
    double gapOfV = HUGE_VAL;
    // The origin on or inside the simplex: the hulls touch or overlap, and only an overlap proof is
    // left to try (after the loop: one copy of its code, not one per exit).
    bool touching = false;
    for (int iteration = 0; iteration < kMaxIterations; ++iteration)
    {
        const double vv = dot(v, v);
        if (!(vv > rounding * rounding))
        {
            touching = true;
            break;
        }
        // |v| bounds the hull points' distance from above, and every gap from below: once it is
        // within the margin no plane can prove the pair apart, and only an overlap proof could still
        // come of going on (a pair within a certified midpoint's sweep: 4 700 -> 2 700 cycles with
        // the other early exits, docs/benchmarks.md "Where a certified midpoint's check goes").
        if (!proveOverlap && !(vv > margin * margin))
            return HullRelation::Unknown;
        const Vec3<double> pointOfA = detail::localSupport(a, Vec3<double>{-v.x, -v.y, -v.z});
        const Vec3<double> w = pointOfA - detail::placedSupport(b, bInA, v);
        const double vw = dot(v, w);
        gapOfV = vw;
        // v . w / |v| is the gap the plane normal to v leaves between the hull points' hulls (it
        // bounds their distance from below). No vertex sticks out of its hull points' hull by more
        // than the piece's hull slack, so a gap that clears the margin plus both slacks is a proof
        // without reading every vertex; one that clears the margin alone is worth that reading.
        const double length = std::sqrt(vv);
        if (vw > (margin + a.hullSlack + b.hullSlack) * length)
            return apart(v);
        if (!proofTried && readEveryVertex && vw > margin * length)
        {
            proofTried = true;
            if (gapAlong(v, a, b, bInA) > margin * length)
                return apart(v);
        }
        if (vv - vw <= 1e-10 * vv)
            break;  // converged: v is the hull points' nearest direction within rounding
        onA[count] = pointOfA;
        simplex[count++] = w;
        Vec3<double> next = v;  // written by closestOnSimplex when it gets closer, with its weights
        const detail::SimplexStep step = detail::closestOnSimplex(simplex, count, next, onA, weights);
        if (step == detail::SimplexStep::OriginInside)
        {
            touching = true;
            break;
        }
        if (!(dot(next, next) < vv))
            break;  // no progress left
        v = next;
        gapOfV = HUGE_VAL;
    }
    if (touching)
        return overlapProven() ? HullRelation::Overlapping : HullRelation::Unknown;
    // Every vertex along v, unless the hull points' gap along it already misses the margin.
    const double needed = margin * std::sqrt(dot(v, v));
    if (!readEveryVertex || !(gapOfV > needed))
        return HullRelation::Unknown;
    return gapAlong(v, a, b, bInA) > needed ? apart(v) : HullRelation::Unknown;
}

}  // namespace rastercheck::device
