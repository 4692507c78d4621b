#include "rastercheck/collision/CpuBackend.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <omp.h>

#include "rastercheck/device/Raster.h"
#include "rastercheck/model/Kinematics.h"

namespace rastercheck
{
/** \brief Scratch of one thread: every buffer the stages write, sized on first use and reused. */
struct CpuWorkspace
{
    explicit CpuWorkspace(const CollisionModel &model)
      : data(*model.robot)
      , componentPose(model.numComponents())
      , componentExactPose(model.numComponents())
      , componentBox(model.numComponents())
      , componentBounds(model.numComponents())
      , layerBounds(model.numComponents())
      , componentWorld(model.numComponents())
      , componentWorldState(model.numComponents(), 0)
    {
    }

    RobotData data;
    std::vector<device::Pose<float>> componentPose;        // n_components
    std::vector<Eigen::Isometry3d> componentExactPose;     // n_components
    std::vector<device::OrientedBox> componentBox;         // n_components, world
    std::vector<device::Box> componentBounds;              // n_components, world
    std::vector<device::Box> layerBounds;                  // n_components: bounds of layer k's subtree

    // World vertices of each component, transformed once per state on first use (a component
    // meets several objects); componentWorldState says for which state they are current.
    std::vector<std::vector<device::Vec3<float>>> componentWorld;  // n_components x n_vertices
    std::vector<std::uint64_t> componentWorldState;                // n_components
    std::uint64_t state = 0;
    std::vector<std::uint32_t> candidatesA, candidatesB;
    std::vector<int> pixelCount;                       // n_pixels
    std::vector<int> pixelStart;                       // n_pixels + 1
    std::vector<device::Fragment> fragments;           // total fragments
};

namespace
{
using device::Vec3;

/** \brief One solid of a pair as the stages see it. */
struct Solid
{
    const CollisionModel::MeshSlice *slice;
    const float *vertices;           // slice's vertices, local frame, x y z
    const std::uint32_t *triangles;  // slice's triangles
    const device::Pose<float> *pose;  // null: vertices are already in the world frame
    int component;                    // index for the per-state vertex cache; -1 for objects
    device::Box bounds;              // world
    const MeshBvh *bvh;
    const Eigen::Isometry3d *exactPose;
};

const Eigen::Isometry3d &identityPose()
{
    static const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    return identity;
}

// Stage: vertices of a solid in the world frame, and its triangles whose projection meets the
// image rectangle grown by `margin` (every triangle a ray of the image can cross: parity stays exact).
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
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    const float uLo = grid.origin[0] - margin, uHi = grid.origin[0] + grid.width * grid.pixel + margin;
    const float vLo = grid.origin[1] - margin, vHi = grid.origin[1] + grid.height * grid.pixel + margin;
    candidates.clear();
    for (std::uint32_t t = 0; t < solid.slice->numTriangles; ++t)
    {
        const std::uint32_t *tri = solid.triangles + 3 * t;
        const Vec3<float> &a = world[tri[0]], &b = world[tri[1]], &c = world[tri[2]];
        const float au = device::coordinate(a, u), bu = device::coordinate(b, u), cu = device::coordinate(c, u);
        const float av = device::coordinate(a, v), bv = device::coordinate(b, v), cv = device::coordinate(c, v);
        if (device::maxOf(au, device::maxOf(bu, cu)) < uLo || device::minOf(au, device::minOf(bu, cu)) > uHi || device::maxOf(av, device::maxOf(bv, cv)) < vLo ||
            device::minOf(av, device::minOf(bv, cv)) > vHi)
            continue;
        candidates.push_back(t);
    }
}

// Stages: pre-rasterization count, scan, rasterization, per-pixel sort, Sort_Search_Pair. With an
// image, every pixel is walked and recorded (pictures); without, the first hit ends the pair.
bool rasterHit(const Solid &a, const Vec3<float> *worldA, const std::vector<std::uint32_t> &candidatesA,
               const Solid &b, const Vec3<float> *worldB, const std::vector<std::uint32_t> &candidatesB,
               const device::RasterGrid &grid, CpuWorkspace &ws, Contact &contact, RasterImage *image = nullptr)
{
    const int pixels = grid.width * grid.height;
    ws.pixelCount.assign(static_cast<std::size_t>(pixels), 0);
    auto forEachTriangle = [&](auto &&emitFor) {
        for (std::uint32_t t : candidatesA)
        {
            const std::uint32_t *tri = a.triangles + 3 * t;
            device::rasterizeTriangle(grid, worldA[tri[0]], worldA[tri[1]], worldA[tri[2]], emitFor(t));
        }
        for (std::uint32_t t : candidatesB)
        {
            const std::uint32_t *tri = b.triangles + 3 * t;
            device::rasterizeTriangle(grid, worldB[tri[0]], worldB[tri[1]], worldB[tri[2]], emitFor(t | device::kPartyB));
        }
    };
    forEachTriangle([&](std::uint32_t) { return [&](int pixel, float, bool) { ++ws.pixelCount[pixel]; }; });

    ws.pixelStart.resize(static_cast<std::size_t>(pixels) + 1);
    ws.pixelStart[0] = 0;
    for (int p = 0; p < pixels; ++p)
        ws.pixelStart[p + 1] = ws.pixelStart[p] + ws.pixelCount[p];
    ws.fragments.resize(static_cast<std::size_t>(ws.pixelStart[pixels]));
    std::copy(ws.pixelStart.begin(), ws.pixelStart.end() - 1, ws.pixelCount.begin());  // write cursors
    forEachTriangle([&](std::uint32_t code) {
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
        int objectFragment = hit;
        while (objectFragment > 0 && !device::isPartyB(fragments[objectFragment]))
            --objectFragment;
        contact.triangle = static_cast<int>(device::triangleOf(fragments[objectFragment]));
        const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
        contact.position[grid.axis] = fragments[hit].depth;
        contact.position[u] = grid.origin[0] + (static_cast<float>(p % grid.width) + 0.5f) * grid.pixel;
        contact.position[v] = grid.origin[1] + (static_cast<float>(p / grid.width) + 0.5f) * grid.pixel;
        if (!image)
            return true;
    }
    return found;
}

bool exactOverlap(const Solid &a, const Solid &b, double padding, Contact &contact)
{
    MeshContact meshContact;
    if (!solidsOverlap(*a.bvh, *a.exactPose, a.slice->closed, *b.bvh, *b.exactPose, b.slice->closed, padding,
                       &meshContact))
        return false;
    contact.triangle = meshContact.triangleB;
    contact.position = meshContact.position;
    return true;
}

/** \brief The image plane of a pair and its candidate triangles: the stages before rasterization. */
struct PreparedPair
{
    device::RasterGrid grid;
    float margin;  // padding plus the float pipeline's rounding allowance
    const Vec3<float> *worldA;
    const Vec3<float> *worldB;
};

/** \brief Where the pair can meet: A's bounds grown by the padding, cut by B's (may be empty). */
device::Box pairWindow(const Solid &a, const Solid &b, float padding)
{
    device::Box grownA = a.bounds;
    for (int k = 0; k < 3; ++k)
    {
        grownA.min[k] -= padding;
        grownA.max[k] += padding;
    }
    return device::intersection(grownA, b.bounds);
}

/** \brief The padding for the float culls: a double beyond float's range (a padding of 1e300 m is
    allowed: everything collides) saturates instead of overflowing the conversion. */
float floatPadding(const CollisionRequest &request)
{
    return static_cast<float>(std::min(request.padding, static_cast<double>(std::numeric_limits<float>::max())));
}

/** \brief Largest coordinate magnitude of a box: float rounding there is about 6e-8 of it. */
float magnitudeOf(const device::Box &box)
{
    float magnitude = 0;
    for (int k = 0; k < 3; ++k)
        magnitude = device::maxOf(magnitude, device::maxOf(fabsf(box.min[k]), fabsf(box.max[k])));
    return magnitude;
}

bool preparePair(const Solid &a, const Solid &b, const CollisionRequest &request, double pixel, CpuWorkspace &ws,
                 PreparedPair &pair)
{
    const float padding = floatPadding(request);
    const device::Box window = pairWindow(a, b, padding);
    if (device::isEmpty(window))
        return false;
    pair.grid = device::makeGrid(window, static_cast<float>(pixel), request.maxImageSide);
    // Rounding allowance of the float pipeline: a few ulps of the largest coordinate in play.
    pair.margin = padding + 1e-6f * magnitudeOf(window) + 1e-6f * pair.grid.pixel;
    pair.worldA = worldVertices(a, ws);
    pair.worldB = worldVertices(b, ws);
    cullToImage(a, pair.worldA, pair.grid, pair.margin, ws.candidatesA);
    cullToImage(b, pair.worldB, pair.grid, pair.margin, ws.candidatesB);
    return true;
}

/** \brief Decides one pair of solids; fills contact.triangle and contact.position on collision.
    Only raster mode rasterizes here: on the CPU the exact narrow phase decides a pair faster than
    the raster stages (measured on the Panda MBM scenes: rasterizing a pair cost about 5x an exact
    BVH query, and the depth-range proof settled only a quarter of the pairs), so safe mode on this
    backend is the exact phase behind the paper's culls. */
bool pairCollides(const Solid &a, const Solid &b, const CollisionRequest &request, double pixel,
                  const Eigen::Vector3d &origin, CpuWorkspace &ws, Contact &contact)
{
    // The box culls already passed; the window test is the last cheap exit before the oracle.
    const device::Box window = pairWindow(a, b, floatPadding(request));
    if (device::isEmpty(window))
        return false;
    // Parity needs a closed solid, and fragments placed well within a pixel: far from
    // CollisionModel::origin (a robot 1e6 m from its scene's centre) float rounding is not, and
    // the raster would see overlaps that are not there. Such pairs are decided exactly.
    const bool rasterUsable =
        (a.slice->closed || b.slice->closed) && 1e-6f * magnitudeOf(window) < 0.1f * static_cast<float>(pixel);
    if (request.mode != CollisionMode::Raster || !rasterUsable)
        return exactOverlap(a, b, request.padding, contact);
    PreparedPair pair;
    if (!preparePair(a, b, request, pixel, ws, pair))
        return false;
    if (rasterHit(a, pair.worldA, ws.candidatesA, b, pair.worldB, ws.candidatesB, pair.grid, ws, contact))
    {
        contact.position += origin;  // the raster works relative to CollisionModel::origin
        return true;
    }
    // Padding is always honoured exactly: the raster sees overlaps, not distances.
    return request.padding > 0 && exactOverlap(a, b, request.padding, contact);
}

// Stages: forward kinematics and the hybrid BVH refit (component OBBs, layer AABBs).
void refit(const CollisionModel &model, const double *q, CpuWorkspace &ws)
{
    ++ws.state;
    forwardKinematics(*model.robot, ws.data, q);
    const std::size_t m = model.numComponents();
    for (std::size_t c = 0; c < m; ++c)
    {
        ws.componentExactPose[c] = ws.data.oMl[model.componentLink[c]];
        ws.componentPose[c] = model.devicePose(ws.componentExactPose[c]);
        ws.componentBox[c] = device::transformBox(ws.componentPose[c], model.componentLocalBoxes[c]);
        ws.componentBounds[c] = device::boundsOf(ws.componentBox[c]);
    }
    for (std::size_t k = m; k-- > 0;)
    {
        ws.layerBounds[k] = ws.componentBounds[k];
        for (int j = static_cast<int>(k) + 1; j < model.componentSubtreeEnd[k]; ++j)
            device::extend(ws.layerBounds[k], ws.componentBounds[j]);
    }
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
                 &ws.componentExactPose[c]};
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
                 &identityPose()};
}
}  // namespace

CpuBackend::CpuBackend(CollisionModelConstPtr model) : model_(std::move(model)) {}

CpuBackend::~CpuBackend() = default;

std::unique_ptr<CpuWorkspace> CpuBackend::makeWorkspace() const { return std::make_unique<CpuWorkspace>(*model_); }

std::unique_ptr<CpuWorkspace> CpuBackend::acquire() const
{
    {
        std::lock_guard<std::mutex> lock(poolMutex_);
        if (!pool_.empty())
        {
            std::unique_ptr<CpuWorkspace> workspace = std::move(pool_.back());
            pool_.pop_back();
            return workspace;
        }
    }
    return makeWorkspace();
}

void CpuBackend::release(std::unique_ptr<CpuWorkspace> workspace) const
{
    std::lock_guard<std::mutex> lock(poolMutex_);
    pool_.push_back(std::move(workspace));
}

bool CpuBackend::isValid(const double *q, const CollisionRequest &request, CpuWorkspace &ws, Contact *contactOut) const
{
    const CollisionModel &model = *model_;
    Contact contact;
    auto invalid = [&](Contact::Kind kind) {
        contact.kind = kind;
        if (contactOut)
            *contactOut = contact;
        return false;
    };

    if (!model.configurationAdmissible(q))
        return invalid(Contact::Kind::OutOfBounds);

    refit(model, q, ws);
    const std::size_t m = model.numComponents();

    const double pixel = request.pixelSize > 0 ? request.pixelSize : model.defaultPixelSize;
    const float padding = floatPadding(request);
    // Stage: distance set and the Alg. 1 box culls, then the pair pipeline.
    if (request.checkEnvironment && model.numObjects() > 0 && m > 0)
    {
        device::Box robotBounds = device::emptyBox();
        for (std::size_t c = 0; c < m; ++c)
            device::extend(robotBounds, ws.componentBounds[c]);
        float robotCenter[3], robotRadius = 0;
        for (int k = 0; k < 3; ++k)
        {
            robotCenter[k] = 0.5f * (robotBounds.min[k] + robotBounds.max[k]);
            const float half = 0.5f * (robotBounds.max[k] - robotBounds.min[k]);
            robotRadius += half * half;
        }
        robotRadius = std::sqrt(robotRadius);
        for (std::size_t o = 0; o < model.numObjects(); ++o)
        {
            const device::Box &objectBox = model.objectBoxes[o];
            float distance = 0, objectRadius = 0;
            for (int k = 0; k < 3; ++k)
            {
                const float d = 0.5f * (objectBox.min[k] + objectBox.max[k]) - robotCenter[k];
                const float half = 0.5f * (objectBox.max[k] - objectBox.min[k]);
                distance += d * d;
                objectRadius += half * half;
            }
            if (std::sqrt(distance) > robotRadius + std::sqrt(objectRadius) + padding)
                continue;
            const Solid object = objectSolid(model, o);
            for (std::size_t k = 0; k < m;)
            {
                if (!device::boxesOverlap(ws.layerBounds[k], objectBox, padding))
                {
                    k = static_cast<std::size_t>(model.componentSubtreeEnd[k]);
                    continue;
                }
                if (device::orientedBoxOverlapsBox(ws.componentBox[k], objectBox, padding) &&
                    pairCollides(componentSolid(model, ws, k), object, request, pixel, model.origin, ws, contact))
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
        for (const auto &[a, b] : model.selfPairs)
        {
            if (!device::orientedBoxesOverlap(ws.componentBox[a], ws.componentBox[b], padding))
                continue;
            if (pairCollides(componentSolid(model, ws, a), componentSolid(model, ws, b), request, pixel,
                             model.origin, ws, contact))
            {
                contact.component = a;
                contact.otherComponent = b;
                return invalid(Contact::Kind::SelfCollision);
            }
        }

    if (contactOut)
        *contactOut = Contact{};
    return true;
}

bool CpuBackend::rasterImage(const double *q, const Contact &contact, const CollisionRequest &request,
                             RasterImage &image) const
{
    const CollisionModel &model = *model_;
    const bool environment = contact.kind == Contact::Kind::Environment;
    if ((!environment && contact.kind != Contact::Kind::SelfCollision) || !model.configurationAdmissible(q))
        return false;
    std::unique_ptr<CpuWorkspace> ws = acquire();
    refit(model, q, *ws);
    const Solid a = componentSolid(model, *ws, static_cast<std::size_t>(contact.component));
    const Solid b = environment ? objectSolid(model, static_cast<std::size_t>(contact.object))
                                : componentSolid(model, *ws, static_cast<std::size_t>(contact.otherComponent));
    const double pixel = request.pixelSize > 0 ? request.pixelSize : model.defaultPixelSize;
    PreparedPair pair;
    Contact scratch;
    const bool made = preparePair(a, b, request, pixel, *ws, pair);
    if (made)
    {
        rasterHit(a, pair.worldA, ws->candidatesA, b, pair.worldB, ws->candidatesB, pair.grid, *ws, scratch, &image);
        // Pictures label world coordinates.
        image.grid.origin[0] += static_cast<float>(model.origin[(pair.grid.axis + 1) % 3]);
        image.grid.origin[1] += static_cast<float>(model.origin[(pair.grid.axis + 2) % 3]);
    }
    release(std::move(ws));
    return made;
}

void CpuBackend::check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts,
                       const CollisionRequest &request, int threads) const
{
    const std::size_t dof = model_->robot->numCoordinates();
    const int workers = threads > 0 ? threads : omp_get_max_threads();
    if (workers == 1 || n < 2)
    {
        std::unique_ptr<CpuWorkspace> ws = acquire();
        for (std::size_t i = 0; i < n; ++i)
            valid[i] = isValid(q + i * dof, request, *ws, contacts ? contacts + i : nullptr) ? 1 : 0;
        release(std::move(ws));
        return;
    }
#pragma omp parallel num_threads(workers)
    {
        std::unique_ptr<CpuWorkspace> ws = acquire();
#pragma omp for schedule(dynamic, 16)
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i)
            valid[i] = isValid(q + static_cast<std::size_t>(i) * dof, request, *ws, contacts ? contacts + i : nullptr)
                           ? 1
                           : 0;
        release(std::move(ws));
    }
}
}  // namespace rastercheck
