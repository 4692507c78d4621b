#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/collision/ModeRules.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <omp.h>

#include "rastercheck/device/Raster.h"
#include "rastercheck/device/Kinematics.h"
#include "rastercheck/device/MeshTree.h"
#include "rastercheck/device/Stages.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
namespace
{
using device::Vec3;

/** \brief One solid of a pair as the stages see it. */
struct Solid
{
    const CollisionModel::MeshSlice *slice;
    const float *vertices;            // slice's vertices, local frame, x y z
    const std::uint32_t *triangles;   // slice's triangles
    const device::Pose<float> *pose;  // null: vertices are already in the world frame
    int component;                    // index for the per-state vertex cache; -1 for objects
    device::Box bounds;               // world
    const MeshBvh *bvh;
    device::ConvexArrays convex;               // the separation cull's arrays
    std::uint32_t convexSolid;                 // this solid's number there
    const device::Pose<double> *pose64;        // the double pose of the hull test and the exact phase
    const device::Pose<float> *treePlacement;  // bvh's frame -> the float frame (relative to the model's origin)
};

const device::Pose<double> &identityDevicePose()
{
    static const device::Pose<double> identity = device::Pose<double>::identity();
    return identity;
}

// Stage: vertices of a solid in the world frame, and its triangles whose projection meets the
// image rectangle grown by `margin` (every triangle a ray of the image can cross: parity stays
// exact), found through its tree as the batched stages find them.
const Vec3<float> *worldVertices(const Solid &solid, CpuWorkspace &ws)
{
    const Vec3<float> *local = reinterpret_cast<const Vec3<float> *>(solid.vertices);
    if (!solid.pose)
        return local;
    std::vector<Vec3<float>> &buffer = ws.componentWorld[solid.component];
    if (ws.componentWorldState[solid.component] != ws.state)
    {
        buffer.resize(solid.slice->numVertices);
        for (std::uint32_t i = 0; i < solid.slice->numVertices; ++i)
            buffer[i] = device::transformPoint(*solid.pose, local[i]);
        ws.componentWorldState[solid.component] = ws.state;
    }
    return buffer.data();
}

void cullToImage(const Solid &solid, const Vec3<float> *world, const device::RasterGrid &grid, float margin,
                 std::vector<std::uint32_t> &candidates)
{
    candidates.clear();
    device::forEachTriangleNearImage(
        solid.bvh->view(), *solid.treePlacement, grid, margin,
        [&](std::uint32_t t)
        {
            const std::uint32_t *tri = solid.triangles + 3 * t;
            if (device::triangleMeetsImage(world[tri[0]], world[tri[1]], world[tri[2]], grid, margin))
                candidates.push_back(t);
        });
}

// Stages: pre-rasterization count, scan, rasterization, per-pixel sort, Sort_Search_Pair. With an
// image, every pixel is walked and recorded (pictures); without, the first hit ends the pair.
bool rasterHit(const Solid &a, const Vec3<float> *worldA, const std::vector<std::uint32_t> &candidatesA, const Solid &b,
               const Vec3<float> *worldB, const std::vector<std::uint32_t> &candidatesB, const device::RasterGrid &grid,
               CpuWorkspace &ws, Contact &contact, RasterImage *image = nullptr)
{
    const int pixels = grid.width * grid.height;
    ws.pixelCount.assign(static_cast<std::size_t>(pixels), 0);
    auto forEachTriangle = [&](auto &&emitFor)
    {
        for (std::uint32_t t : candidatesA)
        {
            const std::uint32_t *tri = a.triangles + 3 * t;
            device::rasterizeTriangle(grid, worldA[tri[0]], worldA[tri[1]], worldA[tri[2]], emitFor(t));
        }
        for (std::uint32_t t : candidatesB)
        {
            const std::uint32_t *tri = b.triangles + 3 * t;
            device::rasterizeTriangle(grid, worldB[tri[0]], worldB[tri[1]], worldB[tri[2]],
                                      emitFor(t | device::kPartyB));
        }
    };
    forEachTriangle([&](std::uint32_t) { return [&](int pixel, float, bool) { ++ws.pixelCount[pixel]; }; });

    ws.pixelStart.resize(static_cast<std::size_t>(pixels) + 1);
    ws.pixelStart[0] = 0;
    for (int p = 0; p < pixels; ++p)
        ws.pixelStart[p + 1] = ws.pixelStart[p] + ws.pixelCount[p];
    ws.fragments.resize(static_cast<std::size_t>(ws.pixelStart[pixels]));
    std::copy(ws.pixelStart.begin(), ws.pixelStart.end() - 1, ws.pixelCount.begin());  // write cursors
    forEachTriangle(
        [&](std::uint32_t code)
        {
            return [&, code](int pixel, float depth, bool entering) {
                ws.fragments[ws.pixelCount[pixel]++] = {depth, entering ? code | device::kEntering : code};
            };
        });

    if (image)
    {
        image->grid = grid;
        image->coverage.assign(static_cast<std::size_t>(pixels), 0);
        image->hits.assign(static_cast<std::size_t>(pixels), 0);
    }
    bool found = false;
    for (int p = 0; p < pixels; ++p)
    {
        const int start = ws.pixelStart[p], count = ws.pixelStart[p + 1] - start;
        device::Fragment *fragments = ws.fragments.data() + start;
        if (image)
            for (int k = 0; k < count; ++k)
                image->coverage[p] |= device::isPartyB(fragments[k]) ? 2 : 1;
        if (count < 2)
            continue;
        device::sortFragments(fragments, count);
        const int hit = device::sortSearchPair(fragments, count, a.slice->closed, b.slice->closed);
        if (hit < 0)
            continue;
        if (image)
            image->hits[p] = 1;
        if (found)
            continue;
        found = true;
        float position[3];
        device::hitContact(fragments, hit, grid, p, contact.triangle, position);
        contact.position = Eigen::Vector3d(position[0], position[1], position[2]);
        if (!image)
            return true;
    }
    return found;
}

/** \brief The hull test (the stages run the same test per surviving pair): Apart when a plane
    between the solids' hulls keeps them more than \a padding apart, Overlapping (only with
    \a proveOverlap) when a point provably lies inside both. Most pairs the box culls pass are
    still apart, and this settles them for a few thousand multiply-adds where the oracle walks both
    BVHs (measured on the Panda MBM scenes: 164 node pairs and 367 triangle pairs per pair that
    turned out apart); most of the rest collide, and the overlap proof settles most of those. */
device::HullRelation hullRelation(const Solid &a, const Solid &b, double padding, bool proveOverlap,
                                  device::Vec3<double> *warmStart, bool patchAgainstPatch)
{
    return device::relateSolids(a.convex, a.convexSolid, *a.pose64, b.convexSolid, *b.pose64, std::max(0.0, padding),
                                proveOverlap, warmStart, patchAgainstPatch);
}

/** \brief The exact narrow phase (the oracle): triangle pairs and containment. Without
    \a wantContact the contact is left unset, and the traversal may start from the leaf pair its
    thread last met for these two trees (surfacesWithin()), which changes which contact is found
    first but never the verdict; with it, the first contact is the traversal's own, the same on
    every backend and every chunking of a batch. */
bool exactOverlap(const Solid &a, const Solid &b, double padding, bool wantContact, CpuWorkspace &ws,
                  Contact &contact)
{
    MeshContact meshContact;
    if (!solidsOverlap(*a.bvh, fromDevicePose(*a.pose64), a.slice->closed, *b.bvh, fromDevicePose(*b.pose64),
                       b.slice->closed, padding, wantContact ? &meshContact : nullptr, &ws.exact))
        return false;
    contact.triangle = meshContact.triangleB;
    contact.position = meshContact.position;
    return true;
}

/** \brief Is \a solid a scene object with patches: a non-convex mesh (a room, a plant exported from
    CAD, a terrain)? Objects made of primitives (the MotionBenchMaker scenes, the crane's plant)
    are not, and keep the proofs, which settle most of their pairs. */
bool isMeshObstacle(const Solid &solid)
{
    return solid.component < 0 && device::hasPatches(solid.convex, solid.convexSolid);
}

/** \brief The image plane of a pair and its candidate triangles: the stages before rasterization. */
struct PreparedPair
{
    device::RasterGrid grid;
    float margin;  // padding plus the float pipeline's rounding allowance
    const Vec3<float> *worldA;
    const Vec3<float> *worldB;
};

bool preparePair(const Solid &a, const Solid &b, const CollisionRequest &request, double pairPadding, double pixel,
                 CpuWorkspace &ws, PreparedPair &pair)
{
    const float padding = device::floatPadding(pairPadding);
    const device::Box window = device::pairWindow(a.bounds, b.bounds, padding);
    if (device::isEmpty(window))
        return false;
    pair.grid = device::makeGrid(window, static_cast<float>(pixel), request.maxImageSide);
    pair.margin = device::pairMargin(window, pair.grid, padding);
    pair.worldA = worldVertices(a, ws);
    pair.worldB = worldVertices(b, ws);
    cullToImage(a, pair.worldA, pair.grid, pair.margin, ws.candidatesA);
    cullToImage(b, pair.worldB, pair.grid, pair.margin, ws.candidatesB);
    return true;
}

/** \brief Conservative mode's verdict on a pair the box culls pass and no proof settles: colliding,
    placed at the centre of \a window (the region where the pair's boxes, grown by the padding,
    meet; relative to \a origin, CollisionModel::origin) with no triangle. */
bool unprovenCollides(const device::Box &window, const Eigen::Vector3d &origin, Contact &contact)
{
    contact.triangle = -1;
    contact.position = origin + 0.5 * Eigen::Vector3d(window.min[0] + window.max[0], window.min[1] + window.max[1],
                                                      window.min[2] + window.max[2]);
    return true;
}

/** \brief Decides one pair of solids (closer than \a padding counts as colliding); fills
    contact.triangle and contact.position on collision when \a wantContact (without it, in safe
    and exact mode, a pair the hull test proves overlapping is decided there and the contact's
    place is left unset).
    Only raster mode rasterizes here: on the CPU the exact narrow phase decides a pair faster than
    the raster stages (measured on the Panda MBM scenes: rasterizing a pair cost about 5x an exact
    BVH query, and the depth-range proof settled only a quarter of the pairs), so safe mode on this
    backend is the exact phase behind the paper's culls. */
bool meshPairCollides(const Solid &a, const Solid &b, std::uint32_t pairNumber, const CollisionRequest &request,
                      const ModeRules &rules, double padding, double pixel, const Eigen::Vector3d &origin,
                      bool wantContact, CpuWorkspace &ws, Contact &contact)
{
    // The box culls already passed; the window test and the hull test are the last cheap exits.
    const device::Box window = device::pairWindow(a.bounds, b.bounds, device::floatPadding(padding));
    if (device::isEmpty(window))
        return false;
    // A non-convex mesh obstacle goes straight to the exact phase in every mode but raster (whose
    // verdicts are the raster's): its oriented-box trees cull as well as the patch walk and decide
    // in the same pass, where the proofs, when they fail, are paid on top (4000 uniform OMPL.app
    // states, A/B in one build: safe mode over the exact traversal's own rate 0.31 -> 0.73 on
    // Home, 0.63 -> 0.88 on Easy, 0.67 -> 0.91 on cubicles). In conservative mode that makes the
    // pair exact, not just bounded: no false alarms among meshes (6 % of Abstract's free states
    // before), at safe mode's speed (alpha-1.5: 0.21x -> 1.7x FCL).
    if (rules.meshObstaclesExact && isMeshObstacle(b))
        return exactOverlap(a, b, padding, wantContact, ws, contact);
    // A self pair's direction is kept in A's frame: the joints above both links turn them together,
    // and a direction that proved them apart still points between them after such a turn (an
    // object stays put, so an environment pair's is kept in the world frame). Panda MBM problems
    // (bench/edges, one A/B run): 2.78 -> 2.48 us per free state, 6.0 -> 5.6 per certified one.
    device::Vec3<double> *warmStart = nullptr, selfDirection{};
    const bool selfPair = b.component >= 0;
    if (rules.warmStart)
    {
        warmStart = &ws.proofDirection[pairNumber];
        if (selfPair)
        {
            selfDirection = device::rotateVector(*a.pose64, *warmStart);
            warmStart = &selfDirection;
        }
    }
    const device::HullRelation relation =
        hullRelation(a, b, padding, rules.proveOverlaps, warmStart, rules.patchAgainstPatch);
    if (selfPair && warmStart && relation == device::HullRelation::Apart)
        ws.proofDirection[pairNumber] = device::inverseRotate(*a.pose64, selfDirection);
    if (relation != device::HullRelation::Unknown)
        return relation == device::HullRelation::Overlapping;
    if (rules.unprovenCollides)
        return unprovenCollides(window, origin, contact);
    if (!rules.rasterOnHost ||
        !device::rasterUsable(a.slice->closed, b.slice->closed, window, static_cast<float>(pixel)))
        return exactOverlap(a, b, padding, wantContact, ws, contact);
    PreparedPair pair;
    if (!preparePair(a, b, request, padding, pixel, ws, pair))
        return false;
    if (rasterHit(a, pair.worldA, ws.candidatesA, b, pair.worldB, ws.candidatesB, pair.grid, ws, contact))
    {
        contact.position += origin;  // the raster works relative to CollisionModel::origin
        return true;
    }
    // Padding is always honoured exactly: the raster sees overlaps, not distances.
    return (rules.confirmRasterMisses || padding > 0) && exactOverlap(a, b, padding, wantContact, ws, contact);
}

/** \brief Safe and exact mode's last word on a pair whose meshes collide: where a side is made of
    primitives and one is curved, the exact shapes decide (CurvedSolids), since those meshes lie
    outside the shapes they stand for. Conservative and raster verdicts stay their tests' own. */
bool curvedShapesConfirm(const CollisionModel &model, std::uint32_t pairNumber, const Solid &a, const Solid &b,
                         const CollisionRequest &request, double padding)
{
    if ((request.mode != CollisionMode::Safe && request.mode != CollisionMode::Exact) ||
        !model.curved.refines(pairNumber))
        return true;
    return model.curved.collide(model, pairNumber, *a.pose64, *b.pose64, padding);
}

/** \brief meshPairCollides, with a collision of curved primitives confirmed on their exact shapes. */
bool pairCollides(const Solid &a, const Solid &b, std::uint32_t pairNumber, const CollisionRequest &request,
                  const ModeRules &rules, double padding, double pixel, const CollisionModel &model,
                  bool wantContact, CpuWorkspace &ws, Contact &contact)
{
    return meshPairCollides(a, b, pairNumber, request, rules, padding, pixel, model.origin, wantContact, ws,
                            contact) &&
           curvedShapesConfirm(model, pairNumber, a, b, request, padding);
}

// Stages: forward kinematics and the hybrid BVH refit (component OBBs, layer AABBs).
void refit(const CollisionModel &model, const double *q, CpuWorkspace &ws)
{
    ++ws.state;
    const RobotModel &robot = *model.robot;
    device::linkPoses(robot.kinematicJoints.data(), static_cast<int>(robot.kinematicJoints.size()), q,
                      ws.jointValues.data(), ws.linkPoses.data());
    const std::size_t m = model.numComponents();
    for (std::size_t c = 0; c < m; ++c)
    {
        ws.componentPose[c] = device::toFloatPose(ws.linkPoses[model.componentLink[c]], model.origin.data());
        ws.componentBox[c] = device::transformBox(ws.componentPose[c], model.componentLocalBoxes[c]);
        ws.componentBounds[c] = device::boundsOf(ws.componentBox[c]);
    }
    device::computeLayerBounds(ws.componentBounds.data(), model.componentSubtreeEnd.data(), static_cast<int>(m),
                               ws.layerBounds.data());
}

Solid componentSolid(const CollisionModel &model, CpuWorkspace &ws, std::size_t c)
{
    return Solid{&model.components[c],
                 model.componentVertices.data() + 3 * model.components[c].firstVertex,
                 model.componentTriangles.data() + 3 * model.components[c].firstTriangle,
                 &ws.componentPose[c],
                 static_cast<int>(c),
                 ws.componentBounds[c],
                 model.componentBvhs[c].get(),
                 model.convex.arrays(),
                 static_cast<std::uint32_t>(c),
                 &ws.linkPoses[model.componentLink[c]],
                 &ws.componentPose[c]};
}

Solid objectSolid(const CollisionModel &model, std::size_t o)
{
    return Solid{&model.objects[o],
                 model.objectVertices.data() + 3 * model.objects[o].firstVertex,
                 model.objectTriangles.data() + 3 * model.objects[o].firstTriangle,
                 nullptr,
                 -1,
                 model.objectBoxes[o],
                 model.objectBvhs[o].get(),
                 model.convex.arrays(),
                 static_cast<std::uint32_t>(model.numComponents() + o),
                 &identityDevicePose(),
                 &model.objectTreePlacement};
}
}  // namespace

int batchWorkers(std::size_t n, int requested)
{
    const std::size_t cap = std::max<std::size_t>(1, n / 16);
    const std::size_t wanted = static_cast<std::size_t>(requested > 0 ? requested : omp_get_max_threads());
    return static_cast<int>(std::min(wanted, cap));
}

CpuBackend::CpuBackend(CollisionModelConstPtr model)
    : model_(std::move(model)), workspaces_([this] { return makeWorkspace(); })
{
}

CpuBackend::~CpuBackend() = default;

std::unique_ptr<CpuWorkspace> CpuBackend::makeWorkspace() const
{
    return std::make_unique<CpuWorkspace>(*model_);
}

std::unique_ptr<CpuWorkspace> CpuBackend::borrow() const
{
    return workspaces_.borrow();
}

void CpuBackend::giveBack(std::unique_ptr<CpuWorkspace> workspace) const
{
    workspaces_.giveBack(std::move(workspace));
}

void CpuBackend::refitState(const double *q, CpuWorkspace &ws) const
{
    refit(*model_, q, ws);
}

bool CpuBackend::decideOpenPair(std::uint32_t pair, const CollisionRequest &request, CpuWorkspace &ws,
                                Contact &contact, std::size_t paddingRow) const
{
    const CollisionModel &model = *model_;
    model.nameParties(pair, contact);
    const Solid a = componentSolid(model, ws, static_cast<std::size_t>(contact.component));
    const Solid b = contact.kind == Contact::Kind::Environment
                        ? objectSolid(model, static_cast<std::size_t>(contact.object))
                        : componentSolid(model, ws, static_cast<std::size_t>(contact.otherComponent));
    const double padding = PairPaddings(model, request, paddingRow).pair(pair);
    // As pairCollides: a non-convex mesh obstacle is decided exactly in conservative mode too.
    const ModeRules rules = modeRules(request.mode, true);
    if (rules.unprovenCollides && !(rules.meshObstaclesExact && isMeshObstacle(b)))
        return unprovenCollides(device::pairWindow(a.bounds, b.bounds, device::floatPadding(padding)), model.origin,
                                contact);
    return exactOverlap(a, b, padding, true, ws, contact) && curvedShapesConfirm(model, pair, a, b, request, padding);
}

std::uint8_t CpuBackend::isValid(const double *q, const CollisionRequest &request, CpuWorkspace &ws,
                                 Contact *contactOut, std::size_t paddingRow, const PairPadding *wider) const
{
    const CollisionModel &model = *model_;
    Contact contact;
    auto invalid = [&](Contact::Kind kind)
    {
        contact.kind = kind;
        if (contactOut)
            *contactOut = contact;
        return static_cast<std::uint8_t>(PaddedVerdict::Collides);
    };

    if (!model.configurationAdmissible(q))
        return invalid(Contact::Kind::OutOfBounds);

    refit(model, q, ws);
    const std::size_t m = model.numComponents();

    const double pixel = request.pixelSize > 0 ? request.pixelSize : model.defaultPixelSize;
    const bool wantContact = contactOut != nullptr;
    const ModeRules rules = modeRules(request.mode, wantContact);
    // Paddings: the request's, plus its pairPadding entry per pair (plus wider's: the outer
    // paddings of two). The distance set and the layer culls take the largest padding they stand
    // for, the outer one.
    const PairPaddings own(model, request, paddingRow);
    const PairPaddings outer(model, request.padding, request.pairPadding.get(), paddingRow, wider);
    // With two paddings, the first pair nearer than its outer padding but clear at its own makes the
    // state Near; from then on only the request's own paddings matter.
    bool near = false;
    auto padding = [&](double outerPadding, double ownPadding) { return near ? ownPadding : outerPadding; };
    // A pair tried at a wider padding than its own is tried at its own next if it meets (collidesAtOwn),
    // with the overlap proofs: at the wider one they would only tell what the hull test's Unknown and
    // the exact phase tell too, and GJK stops sooner without them.
    ModeRules widerRules = rules;
    widerRules.proveOverlaps = false;
    auto rulesAt = [&](double paddingUsed, double ownPadding) -> const ModeRules &
    { return paddingUsed > ownPadding ? widerRules : rules; };
    // A pair that meets at \a paddingUsed: whether the state collides (else it is now Near).
    auto collidesAtOwn =
        [&](const Solid &a, const Solid &b, std::uint32_t pairNumber, double paddingUsed, double ownPadding)
    {
        if (!wider || near || paddingUsed <= ownPadding)
            return true;
        if (pairCollides(a, b, pairNumber, request, rules, ownPadding, pixel, model, wantContact, ws, contact))
            return true;
        near = true;
        return false;
    };
    double reachPadding = request.padding;
    if (outer.uniform())
        std::fill(ws.layerPadding.begin(), ws.layerPadding.end(), device::floatPadding(request.padding));
    else
    {
        // A layer's padding is the largest in its subtree (the layer boxes' own walk).
        device::joinLayers(
            model.componentSubtreeEnd.data(), static_cast<int>(m), ws.layerLargest.data(),
            [&](int k) { return std::max(request.padding, outer.component(static_cast<std::size_t>(k))); },
            [](double &layer, double child) { layer = std::max(layer, child); });
        for (std::size_t k = 0; k < m; ++k)
        {
            ws.layerPadding[k] = device::floatPadding(ws.layerLargest[k]);
            reachPadding = std::max(reachPadding, ws.layerLargest[k]);
        }
    }
    // Stage: distance set and the Alg. 1 box culls, then the pair pipeline.
    if (request.checkEnvironment && model.numObjects() > 0 && m > 0)
    {
        device::Box robotBounds = device::emptyBox();
        for (std::size_t c = 0; c < m; ++c)
            device::extend(robotBounds, ws.componentBounds[c]);
        const device::Sphere robotSphere = device::boundingSphere(robotBounds);
        for (std::size_t o = 0; o < model.numObjects(); ++o)
        {
            const device::Box &objectBox = model.objectBoxes[o];
            if (!device::objectWithinReach(robotSphere, model.objectSpheres[o], device::floatPadding(reachPadding)))
                continue;
            const Solid object = objectSolid(model, o);
            for (std::size_t k = 0; k < m;)
            {
                if (!device::boxesOverlap(ws.layerBounds[k], objectBox, ws.layerPadding[k]))
                {
                    k = static_cast<std::size_t>(model.componentSubtreeEnd[k]);
                    continue;
                }
                const double pairPadding = padding(outer.component(k), own.component(k));
                const Solid component = componentSolid(model, ws, k);
                const std::uint32_t pairNumber =
                    device::environmentPair(static_cast<int>(o), static_cast<int>(k), static_cast<int>(m));
                if (device::solidsMayMeet(ws.componentBounds[k], ws.componentBox[k], objectBox,
                                          model.objectOrientedBoxes[o], device::floatPadding(pairPadding)) &&
                    pairCollides(component, object, pairNumber, request, rulesAt(pairPadding, own.component(k)),
                                 pairPadding, pixel, model, wantContact, ws, contact) &&
                    collidesAtOwn(component, object, pairNumber, pairPadding, own.component(k)))
                {
                    contact.component = static_cast<int>(k);
                    contact.object = static_cast<int>(o);
                    return invalid(Contact::Kind::Environment);
                }
                ++k;
            }
        }
    }

    if (request.checkSelfCollision)
        for (std::size_t i = 0; i < model.selfPairs.size(); ++i)
        {
            const auto [a, b] = model.selfPairs[i];
            const double pairPadding = padding(outer.self(i), own.self(i));
            if (!device::solidsMayMeet(ws.componentBounds[a], ws.componentBox[a], ws.componentBounds[b],
                                       ws.componentBox[b], device::floatPadding(pairPadding)))
                continue;
            // The pair's clearance table: a proof of "apart" without a hull test. Safe and exact mode
            // only, whose verdicts are the meshes' own (conservative and raster verdicts are their
            // tests' outcomes, which the table must not change).
            if (rules.clearanceTables && model.selfPairTables.apart(i, q, pairPadding))
                continue;
            const Solid solidA = componentSolid(model, ws, a), solidB = componentSolid(model, ws, b);
            const std::uint32_t pairNumber =
                device::selfPair(static_cast<int>(i), static_cast<int>(model.numObjects()), static_cast<int>(m));
            if (pairCollides(solidA, solidB, pairNumber, request, rulesAt(pairPadding, own.self(i)), pairPadding, pixel,
                             model, wantContact, ws, contact) &&
                collidesAtOwn(solidA, solidB, pairNumber, pairPadding, own.self(i)))
            {
                contact.component = a;
                contact.otherComponent = b;
                return invalid(Contact::Kind::SelfCollision);
            }
        }

    if (contactOut)
        *contactOut = Contact{};
    return static_cast<std::uint8_t>(near ? PaddedVerdict::Near : PaddedVerdict::Clear);
}

bool CpuBackend::rasterImage(const double *q, const Contact &contact, const CollisionRequest &request,
                             RasterImage &image) const
{
    const CollisionModel &model = *model_;
    const bool environment = contact.kind == Contact::Kind::Environment;
    if ((!environment && contact.kind != Contact::Kind::SelfCollision) || !model.configurationAdmissible(q))
        return false;
    std::unique_ptr<CpuWorkspace> ws = borrow();
    refit(model, q, *ws);
    const Solid a = componentSolid(model, *ws, static_cast<std::size_t>(contact.component));
    const Solid b = environment ? objectSolid(model, static_cast<std::size_t>(contact.object))
                                : componentSolid(model, *ws, static_cast<std::size_t>(contact.otherComponent));
    const double pixel = request.pixelSize > 0 ? request.pixelSize : model.defaultPixelSize;
    PreparedPair pair;
    Contact scratch;
    const bool made = preparePair(a, b, request, request.padding, pixel, *ws, pair);
    if (made)
    {
        rasterHit(a, pair.worldA, ws->candidatesA, b, pair.worldB, ws->candidatesB, pair.grid, *ws, scratch, &image);
        // Pictures label world coordinates.
        image.grid.origin[0] += static_cast<float>(model.origin[(pair.grid.axis + 1) % 3]);
        image.grid.origin[1] += static_cast<float>(model.origin[(pair.grid.axis + 2) % 3]);
    }
    giveBack(std::move(ws));
    return made;
}

void CpuBackend::check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts,
                       const CollisionRequest &request, int threads) const
{
    decide(q, n, valid, contacts, request, nullptr, threads);
}

bool CpuBackend::checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts,
                                  const CollisionRequest &request, const PairPadding &wider, int threads) const
{
    // One pass relies on a pair clear at a padding being clear at every smaller one; raster
    // verdicts (pixels) need not be.
    if (request.mode == CollisionMode::Raster)
        return false;
    decide(q, n, verdicts, nullptr, request, &wider, threads);
    return true;
}

void CpuBackend::decide(const double *q, std::size_t n, std::uint8_t *verdicts, Contact *contacts,
                        const CollisionRequest &request, const PairPadding *wider, int threads) const
{
    const std::size_t dof = model_->robot->numCoordinates();
    const int workers = batchWorkers(n, threads);
    // State i reads row i of the pair paddings (PairPaddings reads row 0 of a single row).
    if (workers == 1 || n < 2)
    {
        std::unique_ptr<CpuWorkspace> ws = borrow();
        for (std::size_t i = 0; i < n; ++i)
            verdicts[i] = isValid(q + i * dof, request, *ws, contacts ? contacts + i : nullptr, i, wider);
        giveBack(std::move(ws));
        return;
    }
#pragma omp parallel num_threads(workers)
    {
        std::unique_ptr<CpuWorkspace> ws = borrow();
#pragma omp for schedule(dynamic, 16)
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i)
            verdicts[i] = isValid(q + static_cast<std::size_t>(i) * dof, request, *ws,
                                  contacts ? contacts + i : nullptr, static_cast<std::size_t>(i), wider);
        giveBack(std::move(ws));
    }
}
}  // namespace rastercheck
