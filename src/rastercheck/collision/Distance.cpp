#include "rastercheck/collision/Distance.h"

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/MeshDistance.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
void validate(const DistanceRequest &request)
{
    if (!(request.upperBound > 0.0))
        throw ConfigurationError("DistanceRequest::upperBound must be > 0 (infinity for the exact distance), got " +
                                 std::to_string(request.upperBound));
}

/** \brief Scratch of one query at a time: the link poses, the placed nodes, the pairs in order. */
struct DistanceWorkspace
{
    explicit DistanceWorkspace(const RobotModel &robot) : data(robot) {}

    struct Candidate
    {
        double bound;  // lower bound on the pair's measure (its root boxes' distance, through the metric)
        std::uint32_t pair;
        bool rootsMeet;  // the root boxes may overlap: one solid may hold the other
    };
    /** \brief A solid's root bounding sphere in the world frame, grown by the nodes' rounding. */
    struct Sphere
    {
        Eigen::Vector3d centre;
        double radius;
        bool present;  // false for an empty mesh: no pair of it is measured
    };
    RobotData data;
    ExactWorkspace exact;
    std::vector<Sphere> spheres;  // n_components + n_objects: the solids' spheres at this state
    std::vector<Candidate> candidates;
    std::vector<SurfaceHint> hints;  // n_pairs: each pair's nearest triangles at its last query
};

namespace
{
// As MeshDistance.cpp's slack: the float nodes' rounding, taken off the root bounds.
using device::kNodeRounding;

/** \brief Lower bound on the distance between the solids of \a a and \a b (their root boxes), less
    the float nodes' rounding; 0 when the boxes may overlap. */
double rootBound(const MeshBvh &a, const Eigen::Isometry3d &poseA, const MeshBvh &b, const Eigen::Isometry3d &poseB)
{
    const MeshBvh::Node &ra = a.nodes()[0], &rb = b.nodes()[0];
    const Eigen::Isometry3d bMa = poseB.inverse(Eigen::Isometry) * poseA;
    const Eigen::Vector3d centreA = bMa * nodeCentre(ra);
    const double slack = kNodeRounding * (bMa.translation().norm() + ra.radius + nodeCentre(ra).norm() + rb.radius +
                                          nodeCentre(rb).norm());
    const double bound = nodeDistanceLowerBound(rb, bMa.linear() * nodeAxes(ra), ra, centreA - nodeCentre(rb));
    return std::max(0.0, bound - slack);
}

/** \brief ClearanceMeasure::HullBound's measure of a pair, solids \a a and \a b (ConvexArrays
    numbering), when below \a reach (else a value at least \a reach): their whole hulls' lower bound
    (device::hullDistanceLowerBound). Where the whole hulls meet (a table's legs straddle a door
    frame, a link reaches into a shelf), the solids' parts: each solid is the union of its shells,
    and its surface lies in its patches, so the least bound over the pairs of parts bounds the
    surfaces' distance. A solid with patches is taken by them (device::patchesLowerBound against
    each shell of the other; where both have patches, one's patches against each patch of the
    other that meets the other's shell), a solid without by its shells. 0 when parts meet too.
    \a hullsApart: the whole hulls are apart, so neither solid lies inside the other; otherwise the
    bound is the surfaces' only, and the caller rules out containment. */
double hullLowerBound(const device::ConvexArrays &arrays, std::uint32_t a, const device::Pose<double> &poseA,
                      std::uint32_t b, const device::Pose<double> &poseB, double reach, bool &hullsApart)
{
    const std::uint32_t a0 = arrays.solidPieces[a], a1 = arrays.solidPieces[a + 1];
    const std::uint32_t b0 = arrays.solidPieces[b], b1 = arrays.solidPieces[b + 1];
    const double whole = device::hullDistanceLowerBound(device::convexProxy(arrays, a0), poseA,
                                                        device::convexProxy(arrays, b0), poseB, reach);
    hullsApart = whole > 0.0;
    const bool patchesA = device::hasPatches(arrays, a), patchesB = device::hasPatches(arrays, b);
    if (hullsApart || (!patchesA && !patchesB && a1 - a0 == 1 && b1 - b0 == 1))
        return whole;
    // With patches on one side only, that side is B (the bound is symmetric).
    const bool swap = patchesA && !patchesB;
    const std::uint32_t first = swap ? b0 : a0, last = swap ? b1 : a1;
    const std::uint32_t patched = swap ? a : b;
    const device::Pose<double> &patchedPose = swap ? poseA : poseB, &otherPose = swap ? poseB : poseA;
    const auto meetingNone = [](const device::ConvexProxy &, double) { return 0.0; };
    // Where a shell of the unpatched (or first) solid meets a patch: the first solid's patches, if any.
    const auto meeting = [&](const device::ConvexProxy &patch, double bound) {
        return patchesA && patchesB ? device::patchesLowerBound(arrays, a, poseA, patch, poseB, bound, meetingNone)
                                    : 0.0;
    };
    double bound = reach;
    for (std::uint32_t i = last - first > 1 ? first + 1 : first; i < last && bound > 0.0; ++i)
    {
        const device::ConvexProxy shell = device::convexProxy(arrays, i);
        if (patchesA || patchesB)
        {
            bound = std::min(bound,
                             device::patchesLowerBound(arrays, patched, patchedPose, shell, otherPose, bound, meeting));
            continue;
        }
        for (std::uint32_t j = b1 - b0 > 1 ? b0 + 1 : b0; j < b1 && bound > 0.0; ++j)
            bound = std::min(
                bound, device::hullDistanceLowerBound(shell, poseA, device::convexProxy(arrays, j), poseB, bound));
    }
    return bound;
}

/** \brief Relative slack freeRadius takes off a measured distance, of the coordinates' size: the
    triangle distances are computed in double after one rigid transform (rounding about 1e-16 of the
    coordinates), and a step must never be longer than the exact distance allows. */
constexpr double kRadiusSlack = 1e-9;
}  // namespace

/** \brief What measure() minimises over the pairs: (distance - offset) / rate. The plain distance is
    offset 0 and rate 1 (no rates, no slack); freeRadius gives each pair its padding and its rate. */
struct DistanceQueries::PairMetric
{
    PairPaddings offset;
    const PairPaddings *rate = nullptr;                  // null: 1 for every pair
    bool slack = false;                                  // take kRadiusSlack off each measured distance
    ClearanceMeasure measure = ClearanceMeasure::Exact;  // HullBound: each mesh pair's hull bound

    /** \brief The pair's measure for a distance \a d between points at \a size from the world's
        origin (their norms): infinity for a pair with rate 0 that is apart by more than its offset. */
    double value(std::uint32_t pair, double d, double size) const
    {
        const double o = offset.pair(pair);
        const double excess = d - o - (slack ? kRadiusSlack * (size + d + o) : 0.0);
        if (!rate)
            return excess;
        const double r = rate->pair(pair);
        if (r > 0.0)
            return excess / r;
        return excess > 0.0 ? std::numeric_limits<double>::infinity() : excess;
    }
    /** \brief The distance below which the pair's measure is below \a best: the bound of its walk. */
    double reach(std::uint32_t pair, double best) const
    {
        const double o = offset.pair(pair);
        if (!rate)
            return o + best;
        const double r = rate->pair(pair);
        return r > 0.0 ? o + r * best : o;
    }
};

DistanceQueries::DistanceQueries(CollisionModelConstPtr model)
    : model_(std::move(model)),
      penetration_(*model_),
      workspaces_([this] { return std::make_unique<DistanceWorkspace>(*model_->robot); })
{
}

DistanceQueries::~DistanceQueries() = default;

template <class PerState>
void DistanceQueries::forEachState(std::size_t n, int threads, const PerState &fn) const
{
    const int workers = batchWorkers(n, threads);
    if (workers == 1 || n < 2)  // no thread team for a single query (OMPL's clearance())
    {
        std::unique_ptr<DistanceWorkspace> ws = workspaces_.borrow();
        for (std::size_t i = 0; i < n; ++i)
            fn(i, *ws);
        workspaces_.giveBack(std::move(ws));
        return;
    }
#pragma omp parallel num_threads(workers)
    {
        std::unique_ptr<DistanceWorkspace> ws = workspaces_.borrow();
#pragma omp for schedule(dynamic, 4)
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i)
            fn(static_cast<std::size_t>(i), *ws);
        workspaces_.giveBack(std::move(ws));
    }
}

void DistanceQueries::distance(const double *q, std::size_t n, DistanceResult *results, const DistanceRequest &request,
                               int threads) const
{
    validate(request);
    const std::size_t dof = model_->robot->numCoordinates();
    const PairMetric metric{PairPaddings(*model_, 0.0, nullptr, 0)};
    forEachState(n, threads,
                 [&](std::size_t i, DistanceWorkspace &ws) { measure(q + i * dof, request, metric, ws, results[i]); });
}

void DistanceQueries::freeRadius(const double *q, std::size_t n, const CollisionRequest &request,
                                 const PairPadding &rates, const double *caps, double *radii, int threads,
                                 ClearanceMeasure clearance) const
{
    const std::size_t dof = model_->robot->numCoordinates();
    forEachState(n, threads,
                 [&](std::size_t i, DistanceWorkspace &ws)
                 {
                     if (!(caps[i] > 0.0))
                     {
                         radii[i] = 0.0;
                         return;
                     }
                     const PairPaddings rate(*model_, 0.0, &rates, i);
                     const PairMetric metric{PairPaddings(*model_, request, i), &rate, true, clearance};
                     DistanceRequest bounded;
                     bounded.checkEnvironment = request.checkEnvironment;
                     bounded.checkSelfCollision = request.checkSelfCollision;
                     bounded.upperBound = caps[i];
                     DistanceResult result;
                     measure(q + i * dof, bounded, metric, ws, result);
                     radii[i] = result.kind == Contact::Kind::OutOfBounds ? 0.0 : std::min(result.distance, caps[i]);
                 });
}

void DistanceQueries::measure(const double *q, const DistanceRequest &request, const PairMetric &metric,
                              DistanceWorkspace &ws, DistanceResult &result) const
{
    const CollisionModel &model = *model_;
    result = DistanceResult{};
    if (!model.configurationAdmissible(q))
    {
        result.distance = 0.0;
        result.kind = Contact::Kind::OutOfBounds;
        result.coordinate = model.firstInadmissibleCoordinate(q);
        return;
    }
    forwardKinematics(*model.robot, ws.data, q);
    ws.hints.resize(model.numPairs());
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    const std::size_t m = model.numComponents();
    const std::size_t environmentPairs = model.numObjects() * m;
    // A pair's two solids: its component (A) and the object or other component (B).
    struct Sides
    {
        const MeshBvh *a, *b;
        const Eigen::Isometry3d *poseA, *poseB;
        bool closedA, closedB;
        std::uint32_t solidA, solidB;  // ConvexArrays numbering
    };
    const auto sides = [&](std::uint32_t pair)
    {
        Contact parties;
        model.nameParties(pair, parties);
        const std::size_t c = static_cast<std::size_t>(parties.component);
        const Eigen::Isometry3d *poseA = &ws.data.oMl[model.componentLink[c]];
        if (parties.kind == Contact::Kind::Environment)
        {
            const std::size_t o = static_cast<std::size_t>(parties.object);
            return Sides{model.componentBvhs[c].get(),
                         model.objectBvhs[o].get(),
                         poseA,
                         &identity,
                         model.components[c].closed,
                         model.objects[o].closed,
                         static_cast<std::uint32_t>(c),
                         static_cast<std::uint32_t>(m + o)};
        }
        const std::size_t other = static_cast<std::size_t>(parties.otherComponent);
        return Sides{model.componentBvhs[c].get(),
                     model.componentBvhs[other].get(),
                     poseA,
                     &ws.data.oMl[model.componentLink[other]],
                     model.components[c].closed,
                     model.components[other].closed,
                     static_cast<std::uint32_t>(c),
                     static_cast<std::uint32_t>(other)};
    };

    // Every pair's root bound, nearest first: the best distance shrinks early, and the pairs whose
    // bound reaches it are never walked. The root spheres' distance comes first: with a finite upper
    // bound (freeRadius' cap) it ends most pairs for a few multiply-adds, where the root boxes'
    // bound places one box in the other's frame.
    ws.spheres.resize(m + model.numObjects());
    for (std::size_t solid = 0; solid < ws.spheres.size(); ++solid)
    {
        const MeshBvh &bvh = solid < m ? *model.componentBvhs[solid] : *model.objectBvhs[solid - m];
        DistanceWorkspace::Sphere &sphere = ws.spheres[solid];
        sphere.present = !bvh.empty();
        if (!sphere.present)
            continue;
        const Eigen::Isometry3d &pose = solid < m ? ws.data.oMl[model.componentLink[solid]] : identity;
        const MeshBvh::Node &root = bvh.nodes()[0];
        const Eigen::Vector3d centre = nodeCentre(root);
        const double radius = root.radius;
        sphere.centre = pose * centre;
        sphere.radius = radius + kNodeRounding * (pose.translation().norm() + centre.norm() + radius);
    }
    ws.candidates.clear();
    // Pair \a pair of solids \a a and \a b, which only a distance below \a reach can make a candidate.
    const auto consider = [&](std::uint32_t pair, std::size_t a, std::size_t b, double reach)
    {
        const DistanceWorkspace::Sphere &sa = ws.spheres[a], &sb = ws.spheres[b];
        const double within = reach + sa.radius + sb.radius;
        if (!(sa.present && sb.present && (sa.centre - sb.centre).squaredNorm() < within * within))
            return;
        const Sides s = sides(pair);
        const double bound = rootBound(*s.a, *s.poseA, *s.b, *s.poseB);
        const double measureBound = metric.value(pair, bound, 0.0);
        if (measureBound < request.upperBound)  // a pair that cannot come below the bound is never walked
            ws.candidates.push_back({measureBound, pair, bound <= 0.0});
    };
    const int components = static_cast<int>(m);
    if (request.checkEnvironment)
        for (int c = 0; c < components; ++c)
        {
            // A component's pairs with every object share its padding and rate: one reach.
            const double reach = metric.reach(device::environmentPair(0, c, components), request.upperBound);
            for (int o = 0; o < static_cast<int>(model.numObjects()); ++o)
                consider(device::environmentPair(o, c, components), static_cast<std::size_t>(c), m + o, reach);
        }
    if (request.checkSelfCollision)
        for (std::size_t i = 0; i < model.selfPairs.size(); ++i)
        {
            const std::uint32_t pair = static_cast<std::uint32_t>(environmentPairs + i);
            consider(pair, static_cast<std::size_t>(model.selfPairs[i].first),
                     static_cast<std::size_t>(model.selfPairs[i].second), metric.reach(pair, request.upperBound));
        }
    std::sort(ws.candidates.begin(), ws.candidates.end(),
              [](const DistanceWorkspace::Candidate &x, const DistanceWorkspace::Candidate &y)
              { return x.bound < y.bound || (x.bound == y.bound && x.pair < y.pair); });

    double best = request.upperBound;
    bool found = false;
    std::uint32_t bestPair = 0;
    SurfaceDistance nearest;
    // The measure of a pair found nearer than its reach: below the best so far, save for the slack
    // (of coordinates as large as \a size).
    const auto keep = [&](std::uint32_t pair, const SurfaceDistance &measured, double size)
    {
        const double value = metric.value(pair, measured.distance, size);
        if (value >= best)
            return;
        found = true;
        best = value;
        bestPair = pair;
        nearest = measured;
    };
    // Every candidate's triangle pair of its last query first, one triangle distance each: their
    // smallest is a real distance of this state, at or near the answer where the state is near the
    // workspace's last (a planner's next state) or the pair's relative pose depends on a few joints
    // only (a wrist), so the walks below prune against it from their first node pair. A single
    // pair (a rigid body among meshes) has no other pair to bound: its own walk reads its hint
    // (surfaceDistance). Hull bounds walk no triangles: their hints would be stale.
    const bool hullBound = metric.measure == ClearanceMeasure::HullBound;
    const auto sizeOf = [](const SurfaceDistance &measured)
    { return std::max(measured.pointA.norm(), measured.pointB.norm()); };
    for (std::size_t k = 0; !hullBound && ws.candidates.size() > 1 && k < ws.candidates.size(); ++k)
    {
        const DistanceWorkspace::Candidate &candidate = ws.candidates[k];
        if (candidate.bound >= best)
            break;
        const Sides s = sides(candidate.pair);
        SurfaceDistance measured;
        if (!model.curved.refines(candidate.pair) &&
            hintedDistance(*s.a, *s.poseA, *s.b, *s.poseB, ws.hints[candidate.pair], metric.reach(candidate.pair, best),
                           measured) &&
            measured.distance > 0.0)  // a contact is left to the walks, which name the first pair in order
            keep(candidate.pair, measured, sizeOf(measured));
    }
    for (const DistanceWorkspace::Candidate &candidate : ws.candidates)
    {
        if (candidate.bound >= best)
            break;
        const Sides s = sides(candidate.pair);
        const double reach = metric.reach(candidate.pair, best);
        SurfaceDistance measured;
        bool nearer = false;
        double size = 0.0;
        if (model.curved.refines(candidate.pair))
            nearer = model.curved.distance(model, candidate.pair, toDevicePose(*s.poseA), toDevicePose(*s.poseB), reach,
                                           measured);
        else
        {
            bool hullsApart = false;
            if (hullBound)
            {
                // Where the parts' hulls meet the bound is 0: the state gets no step, and its interval
                // is halved as bisection would (an exact walk there found a contact 9 times in 10 on
                // the Panda's edges, at 15 to 30 us each, where the check bisection makes costs 4).
                const device::ConvexArrays arrays = model.convex.arrays();
                measured = SurfaceDistance{};
                measured.distance = hullLowerBound(arrays, s.solidA, toDevicePose(*s.poseA), s.solidB,
                                                   toDevicePose(*s.poseB), reach, hullsApart);
                nearer = measured.distance < reach;
                // No witnesses: the slack is of the solids' own reach from the world's origin.
                size = s.poseA->translation().norm() + s.poseB->translation().norm() +
                       arrays.pieces[arrays.solidPieces[s.solidA]].radius +
                       arrays.pieces[arrays.solidPieces[s.solidB]].radius;
            }
            else
                nearer = surfaceDistance(*s.a, *s.poseA, *s.b, *s.poseB, reach, measured, &ws.exact,
                                         &ws.hints[candidate.pair]);
            // Surfaces apart but the root boxes overlapping (and the hulls not proven apart): one
            // solid may hold the other, which is a collision however far apart the surfaces are.
            Eigen::Vector3d inside;
            if (!(nearer && measured.distance <= 0.0) && candidate.rootsMeet && !hullsApart &&
                ((s.closedB && solidInside(*s.a, *s.poseA, *s.b, *s.poseB, &inside)) ||
                 (s.closedA && solidInside(*s.b, *s.poseB, *s.a, *s.poseA, &inside))))
            {
                nearer = true;
                measured = SurfaceDistance{};
                measured.distance = 0.0;
                measured.pointA = measured.pointB = inside;
            }
        }
        if (!nearer)
            continue;
        keep(candidate.pair, measured, size > 0.0 ? size : sizeOf(measured));
        if (best <= 0.0)
            break;  // colliding: nothing is nearer
    }

    if (!found)
    {
        result.distance = request.upperBound;
        result.capped = std::isfinite(request.upperBound);
        return;
    }
    Contact parties;
    model.nameParties(bestPair, parties);
    result.distance = std::max(0.0, best);
    result.kind = parties.kind;
    result.component = parties.component;
    result.object = parties.object;
    result.otherComponent = parties.otherComponent;
    result.triangle = nearest.triangleA;
    result.otherTriangle = nearest.triangleB;
    result.pointOnComponent = nearest.pointA;
    result.pointOnOther = nearest.pointB;
    if (request.penetration && result.distance <= 0.0)
    {
        const Sides s = sides(bestPair);
        penetration_.measure(bestPair, *s.poseA, *s.poseB, result.penetration);
    }
}
}  // namespace rastercheck
