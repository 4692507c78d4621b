#include "rastercheck/geometry/MeshDistance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rastercheck/device/Traversal.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/geometry/TriangleTests.h"

namespace rastercheck
{
namespace
{
using Vec = Eigen::Vector3d;
using CornersMap = Eigen::Map<const Vec>;

using device::kNodeRounding;  // ten times the float nodes' rounding, taken off every node bound

double treeScale(const MeshBvh &bvh)
{
    return device::treeScale(bvh.exactTree());
}

// A lower bound on the distance between triangles p and q: how far q's corners all lie on one side
// of p's plane (0 when they do not). It settles most leaf pairs near the best distance for a cross
// product and three dot products, where the exact distance costs the exact intersection test and
// fifteen feature pairs. The margin covers its rounding, so a pair it skips is farther than the
// best by more than rounding.
double planeGap(const Vec p[3], const Vec q[3])
{
    const Vec normal = (p[1] - p[0]).cross(p[2] - p[0]);
    const double length = normal.norm();
    if (!(length > 0.0))
        return 0.0;
    const double s0 = normal.dot(q[0] - p[0]), s1 = normal.dot(q[1] - p[0]), s2 = normal.dot(q[2] - p[0]);
    const double low = std::min(s0, std::min(s1, s2)), high = std::max(s0, std::max(s1, s2));
    const double gap = low > 0.0 ? low : (high < 0.0 ? -high : 0.0);
    const double scale = (p[1] - p[0]).norm() + (p[2] - p[0]).norm() + (q[0] - p[0]).norm() + (q[1] - p[0]).norm() +
                         (q[2] - p[0]).norm();
    return gap / length - 1e-12 * scale;
}

// The distance query for device::walkPairs, in the fixed tree's frame with the moving tree placed
// there by R, T. `best` is the reach: it starts at the caller's bound and shrinks with every nearer
// triangle pair, so the pairs still on the walk's stack are pruned against it when popped.
struct DistanceQuery
{
    const MeshBvh &fixed, &moving;
    const MeshBvh::Node *nodesF, *nodesM;
    Eigen::Matrix3d R;
    Vec T;
    device::Pose<double> nodePlacement;  // R, T as the exact phase places nodes
    double slack;
    device::ExactScratch *scratch;  // the workspace's placed-node cache (shared with the exact phase)
    bool cached;
    double best;
    bool found = false;
    std::uint32_t slotFixed = 0, slotMoving = 0;
    Vec pointFixed = Vec::Zero(), pointMoving = Vec::Zero();  // fixed frame
    device::PlacedNode visit{};

    const device::PlacedNode &placed(std::int32_t index)
    {
        return device::placedNode(nodesM, index, nodePlacement, scratch, cached, visit);
    }

    // The pair's lower bound, or the best distance when the bounding spheres already show that
    // the pair holds nothing nearer.
    double bound(device::NodePair pair)
    {
        const MeshBvh::Node &nf = nodesF[pair.a], &nm = nodesM[pair.b];
        const device::PlacedNode &pm = placed(pair.b);
        const Vec between = Vec(pm.centre.x, pm.centre.y, pm.centre.z) - nodeCentre(nf);
        // Bounding spheres first: one dot product settles most pairs far from the best.
        const double spheres = static_cast<double>(nf.radius) + nm.radius + best + slack;
        if (between.squaredNorm() >= spheres * spheres)
            return best;
        Eigen::Matrix3d axes;
        for (int j = 0; j < 3; ++j)
            axes.col(j) = Vec(pm.axis[j].x, pm.axis[j].y, pm.axis[j].z);
        return nodeDistanceLowerBound(nf, axes, nm, between) - slack;
    }

    // secondFirst() bounds both children; the walk tests the nearer at once and the other later, so
    // the bounds are kept by pair for test() (direct-mapped; a bound only grows stale on the safe
    // side, since the best distance only shrinks).
    struct KeptBound
    {
        std::int32_t a = -1, b = -1;
        double bound = 0.0;
    };
    static constexpr unsigned kKept = 64;
    KeptBound kept[kKept]{};
    static unsigned keptSlot(device::NodePair pair)
    {
        return (static_cast<unsigned>(pair.a) * 2654435761u ^ static_cast<unsigned>(pair.b)) % kKept;
    }
    double keptBound(device::NodePair pair)
    {
        KeptBound &slot = kept[keptSlot(pair)];
        if (slot.a != pair.a || slot.b != pair.b)
            slot = KeptBound{pair.a, pair.b, bound(pair)};
        return slot.bound;
    }

    bool test(device::NodePair pair) { return keptBound(pair) < best; }

    // The moving tree's triangle in slot sm, placed in the fixed frame.
    void place(std::uint32_t sm, Vec placedTriangle[3]) const
    {
        const double *cm = moving.slotCorners(sm);
        for (int k = 0; k < 3; ++k)
            placedTriangle[k] = R * CornersMap(cm + 3 * k) + T;
    }

    // Measures the fixed tree's triangle in slot sf against the placed one from slot sm, keeping the
    // pair when it is nearer than the best; false once the surfaces meet (nothing is nearer).
    bool measure(std::uint32_t sf, std::uint32_t sm, const Vec placedTriangle[3])
    {
        const double *cf = fixed.slotCorners(sf);
        const Vec fixedTriangle[3] = {CornersMap(cf), CornersMap(cf + 3), CornersMap(cf + 6)};
        if (planeGap(fixedTriangle, placedTriangle) >= best || planeGap(placedTriangle, fixedTriangle) >= best)
            return true;
        Vec onFixed, onMoving;
        const double d = triangleDistance(fixedTriangle[0], fixedTriangle[1], fixedTriangle[2], placedTriangle[0],
                                          placedTriangle[1], placedTriangle[2], &onFixed, &onMoving);
        if (d < best)
        {
            best = d;
            found = true;
            slotFixed = sf;
            slotMoving = sm;
            pointFixed = onFixed;
            pointMoving = onMoving;
        }
        return d > 0.0;
    }

    bool leaves(device::NodePair pair)
    {
        const MeshBvh::Node &nf = nodesF[pair.a], &nm = nodesM[pair.b];
        Vec placedTriangle[3];
        for (std::uint32_t sm = nm.firstSlot(); sm < nm.firstSlot() + nm.count; ++sm)
        {
            place(sm, placedTriangle);
            for (std::uint32_t sf = nf.firstSlot(); sf < nf.firstSlot() + nf.count; ++sf)
                if (!measure(sf, sm, placedTriangle))
                    return false;
        }
        return true;
    }

    // Descend into the bigger node, so both trees shrink at a similar pace.
    bool splitA(device::NodePair pair) const { return nodesF[pair.a].radius >= nodesM[pair.b].radius; }

    // The child pair with the lower bound first (as FCL's distanceRecurse): the best distance
    // shrinks sooner, and the walk prunes more of what remains.
    bool secondFirst(device::NodePair first, device::NodePair second)
    {
        const double boundFirst = keptBound(first);  // one at a time: placed() may reuse its scratch
        return keptBound(second) < boundFirst;
    }
};
}  // namespace

double nodeDistanceLowerBound(const MeshBvh::Node &nf, const Eigen::Matrix3d &P, const MeshBvh::Node &nm,
                              const Vec &between)
{
    const double centres = between.norm();
    double bound = centres - (static_cast<double>(nf.radius) + nm.radius);
    const float *f = nf.axes;  // row-major: the fixed box's axis i is (f[i], f[3 + i], f[6 + i])
    const double ea[3] = {nf.halfExtents[0], nf.halfExtents[1], nf.halfExtents[2]};
    const double eb[3] = {nm.halfExtents[0], nm.halfExtents[1], nm.halfExtents[2]};
    double d[3];
    for (int i = 0; i < 3; ++i)
        d[i] = f[i] * between[0] + f[3 + i] * between[1] + f[6 + i] * between[2];
    const double *p = P.data();  // column-major: the moving box's axis j is p[3j .. 3j + 2]
    double R[3][3], Q[3][3];     // R(i, j) = axis i of the fixed box . axis j of the moving box; Q = |R|
    for (int i = 0; i < 3; ++i)
    {
        const double a0 = f[i], a1 = f[3 + i], a2 = f[6 + i];
        for (int j = 0; j < 3; ++j)
        {
            R[i][j] = a0 * p[3 * j] + a1 * p[3 * j + 1] + a2 * p[3 * j + 2];
            Q[i][j] = std::abs(R[i][j]);
        }
        bound = std::max(bound, std::abs(d[i]) - (ea[i] + Q[i][0] * eb[0] + Q[i][1] * eb[1] + Q[i][2] * eb[2]));
    }
    // Each box against the other's centre: no point of the moving node is nearer the fixed box than
    // its centre less its radius, and the other way round. Tight where a node is small against the
    // gap, which the axes' projections are not when the gap runs diagonally to every axis.
    double outsideFixed = 0.0, outsideMoving = 0.0;
    for (int i = 0; i < 3; ++i)
    {
        const double t = std::max(std::abs(d[i]) - ea[i], 0.0);
        outsideFixed += t * t;
    }
    for (int j = 0; j < 3; ++j)
    {
        const double along = std::abs(d[0] * R[0][j] + d[1] * R[1][j] + d[2] * R[2][j]);
        bound = std::max(bound, along - (ea[0] * Q[0][j] + ea[1] * Q[1][j] + ea[2] * Q[2][j] + eb[j]));
        const double t = std::max(along - eb[j], 0.0);
        outsideMoving += t * t;
    }
    bound = std::max(bound, std::sqrt(outsideFixed) - nm.radius);
    bound = std::max(bound, std::sqrt(outsideMoving) - nf.radius);
    for (int i = 0; i < 3; ++i)
    {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j)
        {
            // Axis i of the fixed box cross axis j of the moving one: its length is the sine of their
            // angle, read from the two other rows of R (no cancellation when they are parallel;
            // a near-zero axis is skipped, the face axes cover that case).
            const double length = std::sqrt(R[i1][j] * R[i1][j] + R[i2][j] * R[i2][j]);
            if (length < 1e-6)
                continue;
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const double gap = std::abs(d[i2] * R[i1][j] - d[i1] * R[i2][j]) -
                               (ea[i1] * Q[i2][j] + ea[i2] * Q[i1][j] + eb[j1] * Q[i][j2] + eb[j2] * Q[i][j1]);
            bound = std::max(bound, gap / length);
        }
    }
    return std::max(bound, 0.0);
}

namespace
{
// Widening: the first reach is the roots' lower bound plus this fraction of the smaller root's
// radius, doubled after each walk that finds nothing.
constexpr double kWideningStep = 0.05;

// Walks the trees for query.best (the caller's bound, or the hint's distance below it), which then
// holds the nearest pair below it, if any. A walk without a good bound spends most of its time
// before its best distance gets near the answer (FCL env/rob, 1000 uniform poses: 113-132 us cold,
// 38 us with the answer itself as the bound). So where the caller gave no bound (\a unbounded),
// walks with a reach widened from the roots' lower bound come first, up to the hint's distance:
// the first that finds a pair within its reach has found the nearest (every node pair nearer than
// the reach was visited). bench/distance, FCL env/rob, 300 uniform poses, us per query by first
// step (fraction of the radius): 0.01: 59, 0.02: 54, 0.05: 55-57, 0.1: 63, 0.2: 94; 105 without
// widening, FCL 102. Only without a bound: a pair measured against another pair's distance
// (Checker::distance's pairs after the first) mostly finds nothing nearer, and would walk every
// widened reach in vain (Panda scenes: 10 to 25 % slower when it widened below finite bounds).
device::WalkEnd widenedWalks(DistanceQuery &query, bool unbounded)
{
    const MeshBvh::Node *nodesF = query.nodesF, *nodesM = query.nodesM;
    double step = kWideningStep * std::min<double>(nodesF[0].radius, nodesM[0].radius);
    if (unbounded && step > 0.0)
    {
        // The hint's pair (if any) stands unless a widened walk finds a nearer one.
        const double reach = query.best;
        const bool found = query.found;
        const std::uint32_t slotFixed = query.slotFixed, slotMoving = query.slotMoving;
        const Vec pointFixed = query.pointFixed, pointMoving = query.pointMoving;
        const double lowest = std::max(0.0, query.bound(device::NodePair{0, 0}));
        for (double widened = lowest + step; widened < reach; step *= 2.0, widened = lowest + step)
        {
            query.best = widened;
            query.found = false;
            std::fill(std::begin(query.kept), std::end(query.kept), DistanceQuery::KeptBound{});
            const device::WalkEnd end = device::walkPairs(nodesF, nodesM, query);
            if (end == device::WalkEnd::Overflow || query.found)
                return end;
        }
        query.best = reach;
        query.found = found;
        query.slotFixed = slotFixed;
        query.slotMoving = slotMoving;
        query.pointFixed = pointFixed;
        query.pointMoving = pointMoving;
        std::fill(std::begin(query.kept), std::end(query.kept), DistanceQuery::KeptBound{});
    }
    return device::walkPairs(nodesF, nodesM, query);
}

// surfaceDistance, or with `walk` false only the hint's pair (hintedDistance): one setup and one
// placement arithmetic for both, so a hinted pair measures the same as it does in the walk.
bool measureSurfaces(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                     double bound, SurfaceDistance &result, ExactWorkspace *workspace, SurfaceHint *hint, bool walk)
{
    if (a.empty() || b.empty() || !(bound > 0.0))
        return false;
    // As surfacesWithin: the tree with fewer nodes is the one moved (its nodes placed once per query).
    const bool movingIsA = a.numNodes() <= b.numNodes();
    const MeshBvh &fixed = movingIsA ? b : a, &moving = movingIsA ? a : b;
    const Eigen::Isometry3d &fixedPose = movingIsA ? poseB : poseA, &movingPose = movingIsA ? poseA : poseB;
    const Eigen::Isometry3d fMm = fixedPose.inverse(Eigen::Isometry) * movingPose;
    device::ExactScratch scratch =
        workspace ? workspace->lend(static_cast<std::size_t>(moving.numNodes())) : device::ExactScratch{};
    const bool cached = device::beginPlacing(&scratch, static_cast<std::uint32_t>(moving.numNodes()));
    DistanceQuery query{fixed,
                        moving,
                        fixed.nodes(),
                        moving.nodes(),
                        fMm.linear(),
                        fMm.translation(),
                        toDevicePose(fMm),
                        kNodeRounding * (fMm.translation().norm() + treeScale(a) + treeScale(b)),
                        &scratch,
                        cached,
                        bound};
    // The hint's triangle pair first: at a state near the last one it is at or near the nearest
    // pair, and the walk then prunes against it from its first node pair.
    const std::uint32_t hintFixed = hint ? (movingIsA ? hint->slotB : hint->slotA) : 0;
    const std::uint32_t hintMoving = hint ? (movingIsA ? hint->slotA : hint->slotB) : 0;
    if (hint && hintFixed < fixed.mesh().triangles.size() && hintMoving < moving.mesh().triangles.size())
    {
        Vec placedTriangle[3];
        query.place(hintMoving, placedTriangle);
        query.measure(hintFixed, hintMoving, placedTriangle);
    }
    device::WalkEnd end = device::WalkEnd::Stopped;
    if (walk && !(query.found && query.best <= 0.0))
        end = widenedWalks(query, std::isinf(bound));
    if (end == device::WalkEnd::Overflow)
    {
        // A tree deeper than the walk's stack (the builder rules it out): no bound can be trusted.
        result = SurfaceDistance{};
        result.distance = 0.0;
        result.pointA = result.pointB = fixedPose * nodeCentre(fixed.nodes()[0]);
        return true;
    }
    if (!query.found)
        return false;
    const std::int32_t triangleFixed = static_cast<std::int32_t>(fixed.triangleOrder()[query.slotFixed]);
    const std::int32_t triangleMoving = static_cast<std::int32_t>(moving.triangleOrder()[query.slotMoving]);
    const Vec worldFixed = fixedPose * query.pointFixed, worldMoving = fixedPose * query.pointMoving;
    result.distance = query.best;
    result.pointA = movingIsA ? worldMoving : worldFixed;
    result.pointB = movingIsA ? worldFixed : worldMoving;
    result.triangleA = movingIsA ? triangleMoving : triangleFixed;
    result.triangleB = movingIsA ? triangleFixed : triangleMoving;
    if (hint)
    {
        hint->slotA = movingIsA ? query.slotMoving : query.slotFixed;
        hint->slotB = movingIsA ? query.slotFixed : query.slotMoving;
    }
    return true;
}
}  // namespace

bool surfaceDistance(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                     double bound, SurfaceDistance &result, ExactWorkspace *workspace, SurfaceHint *hint)
{
    return measureSurfaces(a, poseA, b, poseB, bound, result, workspace, hint, true);
}

bool hintedDistance(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB,
                    const SurfaceHint &hint, double bound, SurfaceDistance &result)
{
    SurfaceHint copy = hint;
    return measureSurfaces(a, poseA, b, poseB, bound, result, nullptr, &copy, false);
}

bool solidInside(const MeshBvh &inner, const Eigen::Isometry3d &innerPose, const MeshBvh &outer,
                 const Eigen::Isometry3d &outerPose, Vec *point)
{
    if (inner.empty() || outer.empty())
        return false;
    device::ExactContact contact;
    if (!device::shellInside(inner.exactTree(), toDevicePose(innerPose), outer.exactTree(), toDevicePose(outerPose),
                             point ? &contact : nullptr))
        return false;
    if (point)
        *point = Vec(contact.position.x, contact.position.y, contact.position.z);
    return true;
}
}  // namespace rastercheck
