#include "rastercheck/geometry/MeshDistance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rastercheck/device/Traversal.h"
#include "rastercheck/device/TriangleTests.h"
#include "rastercheck/geometry/EigenDevice.h"
#include "rastercheck/geometry/TriangleTests.h"
#include "rastercheck/model/Kinematics.h"

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

// What each triangle's plane tells of triangles p and q, before triangleDistance() (which costs the
// exact intersection test and up to fifteen feature pairs) is asked.
enum class PlanesShow
{
    Beyond,      // one triangle lies at least the reach beyond the other's plane: nothing nearer
    CornerOver,  // one lies wholly on one side of the other's plane, and its corner nearest that plane
                 // projects into the other: that corner and its foot are a closest pair (the slab
                 // between the plane and the parallel one through the corner holds nothing of either)
    Nothing
};

// Each normal's gap is a lower bound on the distance (exact where the nearest points are a corner
// over a face), which settles a good share of the leaf pairs near the best distance for two cross
// products, and a corner over a face (the nearest pair of most pairs of large triangles, as in
// OMPL.app's Easy and Twistycool) is measured by one corner/face distance, so neither the
// intersection test nor an edge pair is. (The nine axes across an edge of each settle more pairs, but
// cost more than they save: bench/distance, FCL env/rob 28.8 -> 29.9 us, alpha-1.5 167 -> 194 us.)
// Every corner is projected (about p's first corner), so a normal may carry any rounding (a
// sliver's): the margin covers the projections' rounding. A gap is compared squared against the
// reach times the normal's squared length, so no root is taken. On CornerOver, `distance`, `onP` and
// `onQ` are set as triangleDistance() would set them for that pair of features.
PlanesShow whatPlanesShow(const Vec p[3], const Vec q[3], double reach, double &distance, Vec &onP, Vec &onQ)
{
    const Vec pe[3] = {Vec::Zero(), p[1] - p[0], p[2] - p[0]};
    const Vec qe[3] = {q[0] - p[0], q[1] - p[0], q[2] - p[0]};
    const double rounding =
        1e-12 * (pe[1].lpNorm<1>() + pe[2].lpNorm<1>() + qe[0].lpNorm<1>() + qe[1].lpNorm<1>() + qe[2].lpNorm<1>());
    const double reach2 = (reach + rounding) * (reach + rounding);
    // One triangle against the other's plane: `gap` (0 unless it lies wholly beyond the plane, by more
    // than rounding), the normal's squared length and the triangle's corner nearest the plane.
    struct Side
    {
        double gap = 0.0, length2 = 1.0;
        int nearest = 0;
    };
    const auto against = [&](const Vec &normal, const Vec *own, const Vec *other)
    {
        Side side;
        side.length2 = normal.squaredNorm();
        const double o0 = normal.dot(own[0]), o1 = normal.dot(own[1]), o2 = normal.dot(own[2]);
        const double h[3] = {normal.dot(other[0]), normal.dot(other[1]), normal.dot(other[2])};
        const double above = std::min(h[0], std::min(h[1], h[2])) - std::max(o0, std::max(o1, o2));
        const double below = std::min(o0, std::min(o1, o2)) - std::max(h[0], std::max(h[1], h[2]));
        const double gap = std::max(above, below);
        if (gap > 0.0 && gap * gap > rounding * rounding * side.length2)
        {
            side.gap = gap;
            const double sign = above > below ? 1.0 : -1.0;
            side.nearest = sign * h[1] < sign * h[0] ? 1 : 0;
            side.nearest = sign * h[2] < sign * h[side.nearest] ? 2 : side.nearest;
        }
        return side;
    };
    const auto beyond = [&](const Side &side) { return side.gap * side.gap >= reach2 * side.length2; };
    const Side overP = against(pe[1].cross(pe[2]), pe, qe);
    if (beyond(overP))
        return PlanesShow::Beyond;
    const Side overQ = against((qe[1] - qe[0]).cross(qe[2] - qe[0]), qe, pe);
    if (beyond(overQ))
        return PlanesShow::Beyond;
    // A corner over a face is nearest only across the wider of the two gaps (the distance is at least
    // both), so one corner/face distance is tried at most.
    if (overP.gap <= 0.0 && overQ.gap <= 0.0)
        return PlanesShow::Nothing;
    const bool acrossP = overP.gap * overP.gap * overQ.length2 >= overQ.gap * overQ.gap * overP.length2;
    const Vec *face = acrossP ? p : q;
    const Vec &corner = acrossP ? q[overP.nearest] : p[overQ.nearest];
    device::Vec3<double> foot;
    const double d =
        device::triangles::vertexFace(toDevice(corner), toDevice(face[0]), toDevice(face[1]), toDevice(face[2]), foot);
    if (!(d < HUGE_VAL))
        return PlanesShow::Nothing;
    distance = std::sqrt(d);
    (acrossP ? onP : onQ) = Vec(foot.x, foot.y, foot.z);
    (acrossP ? onQ : onP) = corner;
    return PlanesShow::CornerOver;
}

// Are triangles p and q at least `reach` apart along the unit axis u? Projected about `origin` (a
// point near both, so the projections are small), with a margin for their rounding.
bool apartAlong(const Vec &u, const Vec &origin, const Vec p[3], const Vec q[3], double reach)
{
    double lowP = HUGE_VAL, highP = -HUGE_VAL, lowQ = HUGE_VAL, highQ = -HUGE_VAL, scale = 0.0;
    for (int k = 0; k < 3; ++k)
    {
        const Vec fromP = p[k] - origin, fromQ = q[k] - origin;
        const double sp = fromP.dot(u), sq = fromQ.dot(u);
        lowP = std::min(lowP, sp);
        highP = std::max(highP, sp);
        lowQ = std::min(lowQ, sq);
        highQ = std::max(highQ, sq);
        scale += fromP.lpNorm<1>() + fromQ.lpNorm<1>();
    }
    return std::max(lowQ - highP, lowP - highQ) >= reach + 1e-12 * scale;
}

// nodeDistanceLowerBound(), inlined into the walk: the moving node's axes as placed (axesM[j] its
// axis j in the fixed frame). The nine axes across an edge of each box are left out: they kept about
// a tenth fewer node pairs but cost as much as the rest of the bound (bench/distance, same machine, in
// turn: 4-6 % faster without them on OMPL.app Easy, Twistycool, bugtrap and alpha-1.5).
inline double boxesLowerBound(const MeshBvh::Node &nf, const device::Vec3<double> axesM[3], const MeshBvh::Node &nm,
                              const device::Vec3<double> &between, double reach)
{
    const double centres = std::sqrt(dot(between, between));
    double bound = centres - (static_cast<double>(nf.radius) + nm.radius);
    const float *f = nf.axes;  // row-major: the fixed box's axis i is (f[i], f[3 + i], f[6 + i])
    const double ea[3] = {nf.halfExtents[0], nf.halfExtents[1], nf.halfExtents[2]};
    const double eb[3] = {nm.halfExtents[0], nm.halfExtents[1], nm.halfExtents[2]};
    double d[3];
    for (int i = 0; i < 3; ++i)
        d[i] = f[i] * between.x + f[3 + i] * between.y + f[6 + i] * between.z;
    double R[3][3], Q[3][3];  // R(i, j) = axis i of the fixed box . axis j of the moving box; Q = |R|
    for (int i = 0; i < 3; ++i)
    {
        const double a0 = f[i], a1 = f[3 + i], a2 = f[6 + i];
        for (int j = 0; j < 3; ++j)
        {
            R[i][j] = a0 * axesM[j].x + a1 * axesM[j].y + a2 * axesM[j].z;
            Q[i][j] = std::abs(R[i][j]);
        }
        bound = std::max(bound, std::abs(d[i]) - (ea[i] + Q[i][0] * eb[0] + Q[i][1] * eb[1] + Q[i][2] * eb[2]));
    }
    if (bound >= reach)
        return bound;
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
    return std::max(bound, 0.0);
}

// The distance query, in the fixed tree's frame with the moving tree placed there by R, T. `best` is
// the reach: it starts at the caller's bound and shrinks with every nearer triangle pair.
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
    // The unit direction from pointFixed to pointMoving while the best pair is apart: near the
    // answer, the pairs that hold nothing nearer lie mostly at about the best distance along it
    // too (the surfaces run alongside), which one more separating axis, shared by every pair, shows.
    Vec witness = Vec::Zero();
    bool hasWitness = false;
    device::PlacedNode visit{};

    const device::PlacedNode &placed(std::int32_t index)
    {
        return device::placedNode(nodesM, index, nodePlacement, scratch, cached, visit);
    }

    // The pair's lower bound; at least the best distance when the pair holds nothing nearer (then
    // not necessarily the tightest bound: the bounding spheres alone, or the first axis that shows it).
    double bound(std::int32_t indexF, std::int32_t indexM)
    {
        const MeshBvh::Node &nf = nodesF[indexF], &nm = nodesM[indexM];
        const device::PlacedNode &pm = placed(indexM);
        const device::Vec3<double> between{pm.centre.x - nf.centre[0], pm.centre.y - nf.centre[1],
                                           pm.centre.z - nf.centre[2]};
        // Bounding spheres first: one dot product settles most pairs far from the best.
        const double spheres = static_cast<double>(nf.radius) + nm.radius + best + slack;
        if (dot(between, between) >= spheres * spheres)
            return best;
        // Then the witness's axis: seven dot products, where the boxes' six axes cost about thirty.
        double alongWitness = 0.0;
        if (hasWitness)
        {
            const device::Vec3<double> u = toDevice(witness);
            const float *f = nf.axes;           // row-major: the fixed box's axis i is (f[i], f[3 + i], f[6 + i])
            double reachF = 0.0, reachM = 0.0;  // each box's half extent along the axis
            for (int i = 0; i < 3; ++i)
            {
                reachF += nf.halfExtents[i] * std::abs(f[i] * u.x + f[3 + i] * u.y + f[6 + i] * u.z);
                reachM += nm.halfExtents[i] * std::abs(dot(pm.axis[i], u));
            }
            alongWitness = std::abs(dot(between, u)) - reachF - reachM;
            if (alongWitness - slack >= best)
                return alongWitness - slack;
        }
        return std::max(alongWitness, boxesLowerBound(nf, pm.axis, nm, between, best + slack)) - slack;
    }

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
        if (hasWitness && apartAlong(witness, pointFixed, fixedTriangle, placedTriangle, best))
            return true;
        double d;
        Vec onFixed, onMoving;
        const PlanesShow shown = whatPlanesShow(fixedTriangle, placedTriangle, best, d, onFixed, onMoving);
        if (shown == PlanesShow::Beyond)
            return true;
        if (shown == PlanesShow::Nothing)
            d = triangleDistance(fixedTriangle[0], fixedTriangle[1], fixedTriangle[2], placedTriangle[0],
                                 placedTriangle[1], placedTriangle[2], &onFixed, &onMoving);
        if (d < best)
        {
            best = d;
            found = true;
            slotFixed = sf;
            slotMoving = sm;
            pointFixed = onFixed;
            pointMoving = onMoving;
            hasWitness = d > 0.0;
            if (hasWitness)
                witness = (onMoving - onFixed) / (onMoving - onFixed).norm();
        }
        return d > 0.0;
    }

    // Every triangle pair of two leaves; false once the surfaces meet.
    bool leaves(std::int32_t indexF, std::int32_t indexM)
    {
        const MeshBvh::Node &nf = nodesF[indexF], &nm = nodesM[indexM];
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
};

// A node pair waiting in the best-first walk, with its lower bound.
struct PendingPair
{
    double bound;
    std::int32_t fixed, moving;
};

// The waiting pairs, nearest on top (a binary heap): on the stack up to kInline pairs, beyond that
// in a vector (large trees whose nearest regions hold many pairs at nearly the best distance).
class PendingPairs
{
public:
    PendingPairs() = default;
    PendingPairs(const PendingPairs &) = delete;
    PendingPairs &operator=(const PendingPairs &) = delete;

    bool empty() const { return size_ == 0; }
    const PendingPair &top() const { return data_[0]; }
    void push(const PendingPair &pair)
    {
        if (size_ == capacity_)
        {
            std::vector<PendingPair> grown(data_, data_ + size_);
            grown.resize(2 * capacity_);
            spilled_.swap(grown);
            data_ = spilled_.data();
            capacity_ = spilled_.size();
        }
        data_[size_++] = pair;
        std::push_heap(data_, data_ + size_, Farther{});
    }
    PendingPair pop()
    {
        std::pop_heap(data_, data_ + size_, Farther{});
        return data_[--size_];
    }

private:
    struct Farther
    {
        bool operator()(const PendingPair &x, const PendingPair &y) const { return x.bound > y.bound; }
    };
    static constexpr std::size_t kInline = 256;
    PendingPair inline_[kInline];
    std::vector<PendingPair> spilled_;
    PendingPair *data_ = inline_;
    std::size_t size_ = 0, capacity_ = kInline;
};

// Node pairs whose radii are within this ratio are split together (walkNearestFirst).
constexpr float kSplitBothRatio = 1.5f;

// Walks the trees for query.best (the caller's bound, or the hint's distance below it), which then
// holds the nearest pair below it, if any: best first (as FCL's distance traversal with a queue,
// qsize > 2), each node pair in the order of its lower bound, so the walk ends when the nearest
// waiting pair's bound reaches the best distance found. It visits only the node pairs whose bound is
// below the answer (a depth-first walk also visits those below the best distance it had when it got
// there, which early on is far above the answer): on FCL's env/rob, 1000 uniform poses, 142 node
// bounds and 30 triangle pairs per query, against 243 and 59 for the depth-first walk it replaced
// (device::walkPairs with a reach widened from below), and 633 and 116 for a plain depth-first one.
// The nearer child is walked on at once when it is still the nearest pair, so most steps never
// touch the heap.
void walkNearestFirst(DistanceQuery &query)
{
    const MeshBvh::Node *nodesF = query.nodesF, *nodesM = query.nodesM;
    PendingPairs pending;
    PendingPair current{query.bound(0, 0), 0, 0};
    for (;;)
    {
        if (current.bound < query.best)
        {
            const MeshBvh::Node &nf = nodesF[current.fixed], &nm = nodesM[current.moving];
            const bool leafF = device::isLeafNode(nf), leafM = device::isLeafNode(nm);
            if (leafF && leafM)
            {
                if (!query.leaves(current.fixed, current.moving))
                    return;  // the surfaces meet
            }
            else
            {
                // Descend into the bigger node, so both trees shrink at a similar pace, or into both
                // at once where they are of a size (radii within kSplitBothRatio): one step and one
                // heap visit for what two steps would bound, and the grandchildren's bounds prune
                // pairs that the children's would have kept (OMPL.app alpha-1.5, two trees of 1 008
                // triangles: 98 -> 90 us per query; bugtrap and Easy, a small tree against a large
                // one, unchanged).
                const bool similar = !leafF && !leafM &&
                                     std::max(nf.radius, nm.radius) < kSplitBothRatio * std::min(nf.radius, nm.radius);
                const bool splitF = !leafF && (leafM || similar || nf.radius >= nm.radius);
                const bool splitM = !leafM && (leafF || similar || nm.radius > nf.radius);
                PendingPair children[4];
                int count = 0;
                for (int i = 0; i < (splitF ? 2 : 1); ++i)
                    for (int j = 0; j < (splitM ? 2 : 1); ++j)
                    {
                        PendingPair &child = children[count++];
                        child.fixed = splitF ? nf.first + i : current.fixed;
                        child.moving = splitM ? nm.first + j : current.moving;
                        // One bound at a time: placed() may reuse its scratch.
                        child.bound = query.bound(child.fixed, child.moving);
                    }
                int nearest = 0;
                for (int k = 1; k < count; ++k)
                    if (children[k].bound < children[nearest].bound)
                        nearest = k;
                for (int k = 0; k < count; ++k)
                    if (k != nearest && children[k].bound < query.best)
                        pending.push(children[k]);
                const PendingPair &near = children[nearest];
                if (near.bound < query.best && (pending.empty() || near.bound <= pending.top().bound))
                {
                    current = near;
                    continue;
                }
                if (near.bound < query.best)
                    pending.push(near);
            }
        }
        if (pending.empty() || pending.top().bound >= query.best)
            return;
        current = pending.pop();
    }
}
}  // namespace

double nodeDistanceLowerBound(const MeshBvh::Node &nf, const Eigen::Matrix3d &axesM, const MeshBvh::Node &nm,
                              const Vec &between, double reach)
{
    device::Vec3<double> axes[3];
    for (int j = 0; j < 3; ++j)
        axes[j] = {axesM(0, j), axesM(1, j), axesM(2, j)};
    return boxesLowerBound(nf, axes, nm, toDevice(between), reach);
}

namespace
{
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
    if (walk && !(query.found && query.best <= 0.0))
        walkNearestFirst(query);
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
