// Non-convex scenes, where a solid's hull contains the robot almost everywhere: a room with a
// doorway, a U and a bookshelf (each one closed shell), a maze (twelve overlapping boxes in one
// mesh), a sphere of 20k triangles, FCL's env.obj / rob.obj (open meshes, an OMPL.app problem) and
// the Panda before a bookshelf. Robots: an L-shaped bar (one non-convex shell), rob.obj and the
// Panda. States: uniform within bounds, plus pairs on either side of a contact found by bisecting
// with the oracle. Known answers first; then every state: safe and exact equal the exact oracle
// (with and without padding), conservative never misses (its false-alarm rate is printed), raster
// is only counted; the oracle against FCL where surfaces cross; batches against single states; the
// staged (GPU) pipeline on the host against the CPU backend.
//
// RASTERCHECK_SAMPLE_SCALE multiplies the number of states (default 1; the sanitizer runs may
// lower it, a soak run raise it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "BackendSuites.h"
#include "NonConvex.h"
#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/geometry/MeshBvh.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/model/RigidBody.h"

namespace rc = rastercheck;
using Eigen::Vector3d;

namespace
{
const rc::CollisionMode kModes[] = {rc::CollisionMode::Safe, rc::CollisionMode::Raster, rc::CollisionMode::Exact,
                                    rc::CollisionMode::Conservative};

std::size_t scaled(std::size_t n)
{
    return std::max<std::size_t>(
        8, std::size_t(std::lround(double(n) * rc::test::scaleFromEnvironment("RASTERCHECK_SAMPLE_SCALE"))));
}

/** \brief The U's pose in the world: turned about a skew axis, so no face is parallel to a ray. */
Eigen::Isometry3d uPose()
{
    return Eigen::Translation3d(0.3, -0.2, 0.5) * Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized());
}

/** \brief The sphere: radius 1 about (0, 0, 1), 20 000 triangles or more. */
rc::Mesh fineSphere()
{
    rc::Mesh sphere = rc::makeSphere(1.0, 5e-4);
    sphere.transform(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1)));
    return sphere;
}

/** \brief A rigid body's configuration x y z qx qy qz qw for \a pose. */
std::vector<double> configuration(const Eigen::Isometry3d &pose)
{
    const Eigen::Quaterniond q(pose.linear());
    const Vector3d &p = pose.translation();
    return {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()};
}

std::vector<double> at(double x, double y, double z)
{
    return {x, y, z, 0, 0, 0, 1};
}

bool isRigidBody(const rc::CollisionModel &model)
{
    return model.robot->numCoordinates() == 7 && model.quaternionStarts.size() == 1 && model.quaternionStarts[0] == 3;
}

/** \brief A robot, a scene and its states, with the oracle's verdicts. */
struct Scenario
{
    std::string name;
    rc::CollisionModelConstPtr model;
    double padding = 0.0;  // about 1 % of the robot's size
    double extent = 0.0;   // diagonal of the scene's bounds
    /** \brief No robot point moves farther than reach times the rotation angle (rigid body) or
        times the sum of the coordinates' changes (arm). */
    double reach = 0.0;
    std::vector<double> states;  // uniform, then near pairs at padding 0, then near pairs at `padding`
    std::size_t uniform = 0, near = 0, nearPadded = 0;
    std::vector<std::uint8_t> collides;  // the oracle at padding 0

    std::size_t dof() const { return model->robot->numCoordinates(); }
    std::size_t numStates() const { return states.size() / dof(); }
    const double *state(std::size_t i) const { return states.data() + i * dof(); }
    bool oracle(const double *q, double pad) const { return rc::test::bruteForceCollides(*model, q, pad); }
};

/** \brief The configuration at \a t on the segment a -> b: coordinates linear, quaternions along
    the shorter great arc. */
std::vector<double> between(const rc::CollisionModel &model, const double *a, const double *b, double t)
{
    std::vector<double> q(model.robot->numCoordinates());
    for (std::size_t k = 0; k < q.size(); ++k)
        q[k] = a[k] + t * (b[k] - a[k]);
    for (int s : model.quaternionStarts)
    {
        const Eigen::Quaterniond qa = Eigen::Quaterniond(a[s + 3], a[s], a[s + 1], a[s + 2]).normalized();
        const Eigen::Quaterniond qb = Eigen::Quaterniond(b[s + 3], b[s], b[s + 1], b[s + 2]).normalized();
        const Eigen::Quaterniond r = qa.slerp(t, qb);
        q[s] = r.x();
        q[s + 1] = r.y();
        q[s + 2] = r.z();
        q[s + 3] = r.w();
    }
    return q;
}

/** \brief A bound on how far a robot point moves along the segment a -> b. */
double travel(const Scenario &s, const double *a, const double *b)
{
    if (isRigidBody(*s.model))
    {
        const Eigen::Quaterniond qa = Eigen::Quaterniond(a[6], a[3], a[4], a[5]).normalized();
        const Eigen::Quaterniond qb = Eigen::Quaterniond(b[6], b[3], b[4], b[5]).normalized();
        const double angle = 2.0 * std::acos(std::min(1.0, std::abs(qa.dot(qb))));
        return (Vector3d(b[0], b[1], b[2]) - Vector3d(a[0], a[1], a[2])).norm() + s.reach * angle;
    }
    double sum = 0.0;
    for (std::size_t k = 0; k < s.dof(); ++k)
        sum += std::abs(b[k] - a[k]);
    return s.reach * sum;
}

/** \brief Bisects between \a free and \a colliding (by the oracle at \a padding) until the robot
    moves less than 1e-5 of the scene's extent across the interval, and appends a state on each
    side: the free one where the oracle finds it more than 2e-6 of the extent clear of the padding
    (DESIGN.md: contacts within about 1e-6 of the extent may go either way), the colliding one an
    interval further in when that still collides. False when no free side clears the grey zone. */
bool appendNearPair(const Scenario &s, const double *free, const double *colliding, double padding,
                    std::vector<double> &out)
{
    const double length = travel(s, free, colliding), tolerance = 1e-5 * s.extent;
    double lo = 0.0, hi = 1.0;
    while ((hi - lo) * length > tolerance)
    {
        const double mid = 0.5 * (lo + hi);
        (s.oracle(between(*s.model, free, colliding, mid).data(), padding) ? hi : lo) = mid;
    }
    const double step = hi - lo;
    std::vector<double> freeSide;
    for (int j = 0; j < 8 && lo - j * step >= 0.0; ++j)
    {
        std::vector<double> q = between(*s.model, free, colliding, lo - j * step);
        if (!s.oracle(q.data(), padding + 2e-6 * s.extent))
        {
            freeSide = std::move(q);
            break;
        }
    }
    if (freeSide.empty())
        return false;
    std::vector<double> collidingSide = between(*s.model, free, colliding, std::min(1.0, hi + step));
    if (!s.oracle(collidingSide.data(), padding))
        collidingSide = between(*s.model, free, colliding, hi);
    out.insert(out.end(), freeSide.begin(), freeSide.end());
    out.insert(out.end(), collidingSide.begin(), collidingSide.end());
    return true;
}

/** \brief \a n states within the robot's bounds: rigid bodies get uniform positions and uniformly
    random orientations, arms uniform coordinates. */
std::vector<double> uniformStates(const rc::CollisionModel &model, std::size_t n, unsigned seed)
{
    if (!isRigidBody(model))
        return rc::test::randomStates(*model.robot, n, seed);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    const rc::RobotModel &robot = *model.robot;
    std::vector<double> q;
    for (std::size_t i = 0; i < n; ++i)
    {
        for (int k = 0; k < 3; ++k)
            q.push_back(std::uniform_real_distribution<double>(robot.lowerBounds[k], robot.upperBounds[k])(rng));
        const Eigen::Quaterniond r =
            Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
        q.insert(q.end(), {r.x(), r.y(), r.z(), r.w()});
    }
    return q;
}

/** \brief Fills the states of \a s: \a uniform uniform ones, then \a near pairs across the contact
    boundary at padding 0 and \a nearPadded pairs across the boundary at s.padding. */
void addStates(Scenario &s, std::size_t uniform, std::size_t near, std::size_t nearPadded, unsigned seed)
{
    s.extent = (s.model->scene->bounds().max - s.model->scene->bounds().min).norm();
    s.states = uniformStates(*s.model, uniform, seed);
    s.uniform = uniform;
    std::vector<std::size_t> free, freePadded, colliding;
    for (std::size_t i = 0; i < uniform; ++i)
        (s.oracle(s.state(i), 0.0) ? colliding : free).push_back(i);
    // The padded boundary lies between states free with the padding and states colliding without.
    for (std::size_t i : free)
        if (freePadded.size() < 40 && !s.oracle(s.state(i), s.padding))
            freePadded.push_back(i);
    const auto decideAll = [&s]
    {
        s.collides.resize(s.numStates());
        for (std::size_t i = 0; i < s.numStates(); ++i)
            s.collides[i] = s.oracle(s.state(i), 0.0) ? 1 : 0;
    };
    if (free.empty() || colliding.empty() || freePadded.empty())
        return decideAll();  // the test that the states straddle the boundary fails
    std::mt19937_64 rng(seed + 1);
    const auto pick = [&rng](const std::vector<std::size_t> &from)
    { return from[std::uniform_int_distribution<std::size_t>(0, from.size() - 1)(rng)]; };
    const std::vector<double> pool(s.states.begin(), s.states.end());
    std::vector<double> pairs;
    for (std::size_t attempt = 0; s.near < near && attempt < 2 * near; ++attempt)
        s.near += 2 * appendNearPair(s, &pool[pick(free) * s.dof()], &pool[pick(colliding) * s.dof()], 0.0, pairs);
    for (std::size_t attempt = 0; s.nearPadded < nearPadded && attempt < 2 * nearPadded; ++attempt)
        s.nearPadded += 2 * appendNearPair(s, &pool[pick(freePadded) * s.dof()], &pool[pick(colliding) * s.dof()],
                                           s.padding, pairs);
    s.states.insert(s.states.end(), pairs.begin(), pairs.end());
    decideAll();
}

rc::SceneConstPtr sceneOf(const std::string &name, rc::Mesh mesh)
{
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject(name, std::move(mesh));
    return scene;
}

double farthestVertex(const rc::Mesh &mesh)
{
    double r = 0.0;
    for (const Vector3d &v : mesh.vertices)
        r = std::max(r, v.norm());
    return r;
}

/** \brief One of the generated scenes ("room", "u_shape", "maze", "sphere") and the bounds of the
    robot's position in it. */
struct Generated
{
    rc::SceneConstPtr scene;
    rc::Aabb bounds;
};

Generated generated(const std::string &name)
{
    if (name == "room")
        return {sceneOf("room", rc::test::roomWithDoorway()),
                rc::test::box(Vector3d(-0.5, -0.5, -0.3), Vector3d(4.5, 3.5, 2.7))};
    if (name == "u_shape")
    {
        rc::Mesh u = rc::test::uShape();
        u.transform(uPose());
        const rc::Aabb bounds = u.bounds().inflated(0.4);
        return {sceneOf("u", std::move(u)), bounds};
    }
    if (name == "maze")
        return {sceneOf("maze", rc::test::mazeOnSlab()),
                rc::test::box(Vector3d(-0.2, -0.2, 0.1), Vector3d(4.2, 4.2, 1.4))};
    return {sceneOf("sphere", fineSphere()), rc::test::box(Vector3d(-1.6, -1.6, -0.6), Vector3d(1.6, 1.6, 2.6))};
}

/** \brief A checker of the L-bar, scaled by \a scale, in generated scene \a name. */
rc::Checker lBarChecker(const std::string &name, double scale = 1.0)
{
    const Generated g = generated(name);
    return rc::Checker(rc::makeRigidBodyModel("l_bar", rc::test::lBar(scale), g.bounds), g.scene);
}

/** \brief The L-bar robot in generated scene \a name, 1 % of its size as padding. */
std::unique_ptr<Scenario> lBarScenario(const std::string &name, unsigned seed)
{
    auto s = std::make_unique<Scenario>();
    s->name = name;
    const rc::Mesh bar = rc::test::lBar();
    const Generated g = generated(name);
    s->model = std::make_shared<const rc::CollisionModel>(rc::makeRigidBodyModel("l_bar", bar, g.bounds), g.scene);
    s->padding = 0.01 * (bar.bounds().max - bar.bounds().min).norm();
    s->reach = farthestVertex(bar);
    addStates(*s, scaled(400), scaled(300), scaled(100), seed);
    return s;
}

/** \brief An OMPL.app problem (.cfg in a temporary folder) of FCL's rob.obj in env.obj; without
    `volume` keys the position bounds are the world's. */
std::string fclProblemCfg(const std::string &root)
{
    std::string text = "[problem]\nname = fcl_env_rob\n";
    text += "robot = " + root + "/meshes/fcl/rob.obj\n";
    text += "world = " + root + "/meshes/fcl/env.obj\n";
    for (const char *end : {"start", "goal"})
        for (const char *key :
             {".x = 0", ".y = 0", ".z = 0", ".theta = 0", ".axis.x = 1", ".axis.y = 0", ".axis.z = 0"})
            text += std::string(end) + key + "\n";
    return rc::test::writeFile(rc::test::makeTempDir("nonconvex") + "/fcl_env_rob.cfg", text);
}

std::unique_ptr<Scenario> buildScenario(const std::string &name)
{
    const char *const generatedNames[] = {"room", "u_shape", "maze", "sphere"};
    for (unsigned k = 0; k < 4; ++k)
        if (name == generatedNames[k])
            return lBarScenario(name, 11 + k);
    const std::string root = rc::test::sharedData();
    if (root.empty())
        return nullptr;
    if (name == "fcl_env_rob")
    {
        // FCL's test pair: both meshes open, so only their surfaces count.
        const rc::OmplAppProblem problem = rc::loadOmplAppProblem(fclProblemCfg(root));
        auto s = std::make_unique<Scenario>();
        s->name = name;
        s->model = std::make_shared<const rc::CollisionModel>(problem.robot, problem.scene);
        const rc::Mesh &rob = problem.robot->components[0].mesh;
        s->padding = 0.01 * (rob.bounds().max - rob.bounds().min).norm();
        s->reach = farthestVertex(rob);
        addStates(*s, scaled(400), scaled(300), scaled(100), 15);
        return s;
    }
    if (name == "panda_shelf")
    {
        rc::RobotModelPtr panda = rc::loadUrdf(root + "/mbm/panda/panda.urdf");
        rc::applySrdf(*panda, rc::loadSrdf(root + "/mbm/panda/panda.srdf"));
        auto scene = std::make_shared<rc::Scene>();
        scene->addObject("bookshelf", rc::test::bookshelf());
        // An arch behind the robot (one shell): two legs and a top beam.
        scene->addObject("arch",
                         rc::test::blockSolid({rc::test::box(Vector3d(-0.75, -0.7, 0), Vector3d(-0.6, -0.55, 1)),
                                               rc::test::box(Vector3d(-0.75, 0.55, 0), Vector3d(-0.6, 0.7, 1)),
                                               rc::test::box(Vector3d(-0.75, -0.55, 0.9), Vector3d(-0.6, 0.55, 1))},
                                              0.1));
        auto s = std::make_unique<Scenario>();
        s->name = name;
        s->model = std::make_shared<const rc::CollisionModel>(panda, scene);
        s->padding = 0.01;
        s->reach = 1.2;  // no Panda point is farther than 1.2 m from a joint axis
        addStates(*s, scaled(150), scaled(60), scaled(20), 16);
        return s;
    }
    return nullptr;
}

/** \brief Scenario \a name, built once per test program; null when it needs the shared data and
    that is absent. */
const Scenario *scenario(const std::string &name)
{
    static std::map<std::string, std::unique_ptr<Scenario>> built;
    auto found = built.find(name);
    if (found == built.end())
        found = built.emplace(name, buildScenario(name)).first;
    return found->second.get();
}

/** \brief Does a surface of the robot cross one of the scene or another link (no containment)? */
bool surfacesCross(const rc::CollisionModel &model, const double *q)
{
    rc::RobotData data(*model.robot);
    rc::forwardKinematics(*model.robot, data, q);
    for (std::size_t c = 0; c < model.numComponents(); ++c)
        for (std::size_t o = 0; o < model.numObjects(); ++o)
            if (rc::surfacesWithin(*model.componentBvhs[c], data.oMl[model.componentLink[c]], *model.objectBvhs[o],
                                   Eigen::Isometry3d::Identity(), 0.0))
                return true;
    for (const auto &[a, b] : model.selfPairs)
        if (rc::surfacesWithin(*model.componentBvhs[a], data.oMl[model.componentLink[a]], *model.componentBvhs[b],
                               data.oMl[model.componentLink[b]], 0.0))
            return true;
    return false;
}

/** \brief Expects \a valid from the oracle and from every mode (raster never raises false alarms
    far from contact; conservative's patches prove these free states apart, where the whole hulls
    of the room, the U and the maze hold the robot), or invalid from the oracle, safe, exact and
    conservative mode; prints what raster mode says of an invalid state, which it may get wrong. */
void expectKnown(const rc::Checker &checker, const std::vector<double> &q, bool valid, const std::string &what)
{
    EXPECT_EQ(!rc::test::bruteForceCollides(checker.collisionModel(), q.data(), 0.0), valid) << what << ": oracle";
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        const bool verdict = checker.isValid(q, request);
        const bool blind = mode == rc::CollisionMode::Raster;
        if (valid || !blind)
        {
            EXPECT_EQ(verdict, valid) << what << ": " << rc::toString(mode);
        }
        else if (verdict != valid)
        {
            std::printf("  %s: %s mode says %s\n", what.c_str(), rc::toString(mode).c_str(),
                        verdict ? "valid" : "invalid");
        }
    }
}

/** \brief Counts of one mode against the oracle. */
struct Tally
{
    std::size_t falseNegatives = 0, falsePositives = 0, free = 0, colliding = 0;
    double falsePositiveRate() const { return free ? double(falsePositives) / double(free) : 0.0; }
};

Tally tally(const std::vector<std::uint8_t> &valid, const std::vector<std::uint8_t> &collides, std::size_t begin,
            std::size_t end)
{
    Tally t;
    for (std::size_t i = begin; i < end; ++i)
    {
        (collides[i] ? t.colliding : t.free) += 1;
        t.falseNegatives += valid[i] && collides[i];
        t.falsePositives += !valid[i] && !collides[i];
    }
    return t;
}

/** \brief The share of free states (padding 0) conservative mode may call invalid here: what the
    code measured when these scenes were added (this test prints it), with room for
    other seeds and RASTERCHECK_SAMPLE_SCALE. Hulls hold the robot almost everywhere in these
    scenes and the convex proofs count every pair they cannot separate as colliding, so the rates
    are high; tighten these as the proofs learn to see into the hulls. */
double conservativeFalseAlarmBound(const std::string &scenario)
{
    // Before patches (whole hulls and shells only): 58 %, 24 %, 92 %, 31 %, 94 % and 35 %; with
    // them 0 % on the generated scenes and 11 % on env/rob. Now a non-convex mesh obstacle is
    // decided by the exact phase in conservative mode too, so those scenes allow no false alarm;
    // the Panda's links are proven by their hulls, which near contact still reach the shelf.
    const std::map<std::string, double> bounds{{"room", 0.0},   {"u_shape", 0.0},     {"maze", 0.0},
                                               {"sphere", 0.0}, {"fcl_env_rob", 0.0}, {"panda_shelf", 0.10}};
    return bounds.at(scenario);
}

const char *const kScenarios[] = {"room", "u_shape", "maze", "sphere", "fcl_env_rob", "panda_shelf"};

class NonConvexScene : public ::testing::TestWithParam<const char *>
{
protected:
    void SetUp() override
    {
        scenario_ = scenario(GetParam());
        if (!scenario_)
            GTEST_SKIP() << "shared data not found (set RASTERCHECK_DATA or place ../shared/data beside the checkout): "
                         << GetParam() << " needs it";
    }
    const Scenario *scenario_ = nullptr;
};
}  // namespace

TEST(NonConvexMeshes, GeneratedSolidsAreClosedOutwardAndHaveTheirVolumes)
{
    struct Expected
    {
        const char *name;
        rc::Mesh mesh;
        std::size_t shells;
        double volume;
    };
    const double shelf = 0.05 * 1.2 * 1.2 + 2 * 0.35 * 0.04 * 1.2 + 4 * 0.35 * 1.12 * 0.03;
    // The maze's signed volume adds its twelve boxes, overlaps counted twice: the slab, the walls
    // along y (1 m tall) and along x (0.98 m).
    const double maze = 4.1 * 4.1 * 0.2 + 0.1 * 1.0 * (2 * 3.96 + 2.95 + 2.95 + 2.95) +
                        0.1 * 0.98 * (2 * 3.9 + 0.45 + 0.5 + 0.5 + 0.55);
    Expected solids[] = {
        {"room", rc::test::roomWithDoorway(), 1, 4 * 3 * 2.4 - 3.6 * 2.6 * 2.0 - 0.2 * 1.0 * 1.8},
        {"u", rc::test::uShape(), 1, 2 * 0.4 * 1 + 2 * 0.4 * 1.6 * 1},
        {"l_bar", rc::test::lBar(), 1, 0.6 * 0.1 * 0.1 + 0.1 * 0.3 * 0.1},
        {"bookshelf", rc::test::bookshelf(), 1, shelf},
        {"maze", rc::test::mazeOnSlab(), 12, maze},
    };
    for (Expected &e : solids)
    {
        const rc::MeshTopology topology = rc::cleanMesh(e.mesh);
        EXPECT_TRUE(topology.closed) << e.name << ": " << topology.summary();
        EXPECT_EQ(topology.nonManifoldEdges, 0u) << e.name;
        EXPECT_EQ(topology.shells, e.shells) << e.name;
        EXPECT_NEAR(rc::signedVolume(e.mesh), e.volume, 1e-9 * e.volume) << e.name;
        std::printf("%s: %zu triangles\n", e.name, e.mesh.numTriangles());
    }
    // Large meshes, so that a triangle hierarchy has something to split.
    EXPECT_GT(solids[0].mesh.numTriangles(), 2000u);
    rc::Mesh sphere = fineSphere();
    const rc::MeshTopology topology = rc::cleanMesh(sphere);
    EXPECT_TRUE(topology.closed);
    EXPECT_EQ(topology.shells, 1u);
    EXPECT_GE(sphere.numTriangles(), 20000u);
    // It contains the exact sphere and stays within 5e-4 of it.
    EXPECT_GE(rc::signedVolume(sphere), 4.0 / 3.0 * M_PI);
    EXPECT_LE(rc::signedVolume(sphere), 4.0 / 3.0 * M_PI * std::pow(1 + 5e-4, 3));
    std::printf("sphere: %zu triangles\n", sphere.numTriangles());
}

TEST(NonConvexKnownAnswers, RoomWithDoorway)
{
    // The bar lies along x: x in [-0.3, 0.3], y in [-0.05, 0.35], z in [-0.05, 0.05] about its origin.
    const rc::Checker checker = lBarChecker("room");
    expectKnown(checker, at(3.9, 1.4, 1.0), true, "through the doorway, clear of the frame");
    expectKnown(checker, at(2.0, 1.5, 1.0), true, "inside the room, touching nothing");
    expectKnown(checker, at(0.6, 0.5, 0.5), true, "in a corner of the room, touching nothing");
    expectKnown(checker, at(3.9, 0.5, 1.0), false, "through the wall beside the doorway");
    expectKnown(checker, at(3.9, 1.4, 1.98), false, "through the lintel");
    expectKnown(checker, at(2.0, 1.5, 0.22), false, "sunk 3 cm into the floor");
    // The bar at 0.15 scale: 9 x 6 x 1.5 cm, fits inside the 20 cm walls.
    const rc::Checker small = lBarChecker("room", 0.15);
    expectKnown(small, at(0.1, 1.5, 1.2), false, "small bar buried in the -x wall");
    expectKnown(small, at(2.0, 1.5, 0.1), false, "small bar buried in the floor");
    expectKnown(small, at(3.9, 1.5, 2.1), false, "small bar buried in the lintel");
    expectKnown(small, at(2.0, 1.5, 2.3), false, "small bar buried in the ceiling");
    expectKnown(small, at(3.9, 1.5, 1.9), true, "small bar in the doorway under the lintel");
}

TEST(NonConvexKnownAnswers, UShape)
{
    // States in the U's own frame: the bar turned with the U.
    const Eigen::Isometry3d u = uPose();
    const auto local = [&u](double x, double y, double z) { return configuration(u * Eigen::Translation3d(x, y, z)); };
    const rc::Checker checker = lBarChecker("u_shape");
    expectKnown(checker, local(1.0, 1.0, 0.5), true, "in the U's notch");
    expectKnown(checker, local(1.0, 1.8, 0.5), true, "at the notch's mouth");
    expectKnown(checker, local(1.0, 1.0, 1.3), true, "above the notch");
    expectKnown(checker, local(1.0, 2.3, 0.5), true, "beyond the arms' ends");
    expectKnown(checker, local(0.4, 1.0, 0.5), false, "across an arm's inner face");
    expectKnown(checker, local(1.0, 0.2, 0.5), false, "across the base");
    const rc::Checker small = lBarChecker("u_shape", 0.15);
    expectKnown(small, local(1.0, 0.2, 0.5), false, "small bar buried in the base");
    expectKnown(small, local(0.2, 1.2, 0.5), false, "small bar buried in an arm");
    expectKnown(small, local(1.0, 0.5, 0.5), true, "small bar on the notch's floor");
}

TEST(NonConvexKnownAnswers, Maze)
{
    const rc::Checker checker = lBarChecker("maze");
    expectKnown(checker, at(1.5, 1.0, 0.6), true, "in the corridor between the first two inner walls");
    expectKnown(checker, at(2.5, 2.0, 0.6), true, "in the corridor between the second and third");
    expectKnown(checker, at(1.5, 1.0, 1.3), true, "above the walls");
    expectKnown(checker, at(2.0, 2.0, 0.6), false, "through the second inner wall");
    expectKnown(checker, at(1.5, 1.0, 0.22), false, "3 cm into the slab");
    const rc::Checker small = lBarChecker("maze", 0.15);
    expectKnown(small, at(1.0, 1.5, 0.6), false, "small bar buried in the first inner wall");
    expectKnown(small, at(2.5, 0.5, 0.1), false, "small bar buried in the slab");
    // Inside two boxes at once, where a parity count sees an even number of surfaces.
    expectKnown(small, at(1.0, 1.5, 0.17), false, "small bar buried where a wall and the slab overlap");
    const double h = std::sqrt(0.5);  // a quarter turn about x: 9 x 1.5 x 6 cm
    expectKnown(small, {1.0, 0.075, 0.6, h, 0, 0, h}, false, "small bar buried where two walls overlap");
    expectKnown(small, at(1.5, 1.0, 0.6), true, "small bar in a corridor");
}

TEST(NonConvexKnownAnswers, Sphere)
{
    const rc::Checker checker = lBarChecker("sphere");
    // Every point of the bar is within 0.47 of its origin; its -x end is 0.3 behind it.
    expectKnown(checker, at(0, 0, 1), false, "buried at the centre");
    expectKnown(checker, at(0.3, -0.2, 1.1), false, "buried off centre");
    expectKnown(checker, at(1.0, 0, 1), false, "through the surface");
    expectKnown(checker, at(1.28, 0, 1), false, "2 cm into it");
    expectKnown(checker, at(1.31, 0, 1), true, "1 cm outside");
    expectKnown(checker, at(0, 0, 2.6), true, "above");
}

TEST_P(NonConvexScene, SafeAndExactAgreeWithTheOracleConservativeNeverMisses)
{
    const Scenario &s = *scenario_;
    const std::size_t n = s.numStates();
    const Tally all = tally(std::vector<std::uint8_t>(n, 0), s.collides, 0, n);
    // The states straddle the boundary, or they test nothing.
    EXPECT_GT(all.colliding, n / 10) << s.name;
    EXPECT_GT(all.free, n / 10) << s.name;
    EXPECT_GE(s.near, scaled(s.name == "panda_shelf" ? 60 : 300)) << s.name;  // most bisections found a pair
    const rc::Checker checker(s.model->robot, s.model->scene);
    std::printf("%s: %zu states (%zu uniform, %zu near contact, %zu near the padding), %zu colliding\n", s.name.c_str(),
                n, s.uniform, s.near, s.nearPadded, all.colliding);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        std::vector<std::uint8_t> valid(n);
        checker.check(s.states.data(), n, valid.data(), request);
        const Tally whole = tally(valid, s.collides, 0, n), uniform = tally(valid, s.collides, 0, s.uniform),
                    near = tally(valid, s.collides, s.uniform, s.uniform + s.near);
        std::printf("  %-12s FN %zu, FP %zu of %zu free (%.1f %%; uniform %.1f %%, near contact %.1f %%)\n",
                    rc::toString(mode).c_str(), whole.falseNegatives, whole.falsePositives, whole.free,
                    100.0 * whole.falsePositiveRate(), 100.0 * uniform.falsePositiveRate(),
                    100.0 * near.falsePositiveRate());
        if (mode == rc::CollisionMode::Raster)
            continue;  // the paper's method is not required sound: only counted
        EXPECT_EQ(whole.falseNegatives, 0u) << s.name << " " << rc::toString(mode);
        if (mode != rc::CollisionMode::Conservative)
        {
            EXPECT_EQ(whole.falsePositives, 0u) << s.name << " " << rc::toString(mode);
        }
        else
        {
            EXPECT_LE(whole.falsePositiveRate(), conservativeFalseAlarmBound(s.name)) << s.name;
        }
        for (std::size_t i = 0; i < n; ++i)
        {
            if (valid[i] && s.collides[i])
            {
                ADD_FAILURE() << s.name << " state " << i << ": " << rc::toString(mode) << " mode missed a collision";
            }
            else if (mode != rc::CollisionMode::Conservative && !valid[i] && !s.collides[i])
            {
                ADD_FAILURE() << s.name << " state " << i << ": " << rc::toString(mode) << " mode raised a false alarm";
            }
        }
    }
}

TEST_P(NonConvexScene, PaddedSafeAndExactAgreeWithThePaddedOracle)
{
    const Scenario &s = *scenario_;
    const std::size_t n = s.numStates();
    std::vector<std::uint8_t> collides(n);
    for (std::size_t i = 0; i < n; ++i)
        collides[i] = s.oracle(s.state(i), s.padding) ? 1 : 0;
    const rc::Checker checker(s.model->robot, s.model->scene);
    std::printf("%s, padding %g: %zu of %zu states collide\n", s.name.c_str(), s.padding,
                std::size_t(std::count(collides.begin(), collides.end(), 1)), n);
    // The pairs across the padded boundary: each side as the padded oracle says.
    const std::size_t paddedBegin = s.uniform + s.near;
    for (std::size_t i = paddedBegin; i < n; i += 2)
    {
        EXPECT_FALSE(collides[i]) << s.name << " state " << i;
        EXPECT_TRUE(collides[i + 1]) << s.name << " state " << i + 1;
    }
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        request.padding = s.padding;
        std::vector<std::uint8_t> valid(n);
        checker.check(s.states.data(), n, valid.data(), request);
        const Tally whole = tally(valid, collides, 0, n), padded = tally(valid, collides, paddedBegin, n);
        std::printf("  %-12s FN %zu, FP %zu of %zu free (%.1f %%; near the padding %.1f %%)\n",
                    rc::toString(mode).c_str(), whole.falseNegatives, whole.falsePositives, whole.free,
                    100.0 * whole.falsePositiveRate(), 100.0 * padded.falsePositiveRate());
        if (mode == rc::CollisionMode::Raster)
            continue;  // raster mode sends padding to the exact phase, but it is not required sound
        EXPECT_EQ(whole.falseNegatives, 0u) << s.name << " " << rc::toString(mode);
        if (mode != rc::CollisionMode::Conservative)
        {
            EXPECT_EQ(whole.falsePositives, 0u) << s.name << " " << rc::toString(mode);
        }
    }
}

TEST_P(NonConvexScene, OracleAgreesWithFclWhereSurfacesCross)
{
    // FCL sees surfaces only: where it reports a contact the oracle must too, and where surfaces
    // cross FCL must report it; a state the oracle calls colliding with no surface crossing (a
    // buried robot) is one FCL misses.
    const Scenario &s = *scenario_;
    rc::test::FclReference fcl(*s.model);
    std::size_t crossing = 0, buried = 0;
    for (std::size_t i = 0; i < s.numStates(); ++i)
    {
        const bool fclSays = fcl.collides(s.state(i)), cross = surfacesCross(*s.model, s.state(i));
        crossing += cross;
        buried += s.collides[i] && !cross;
        if (fclSays)
        {
            EXPECT_TRUE(s.collides[i]) << s.name << " state " << i << ": FCL reports a contact the oracle does not";
        }
        if (cross)
        {
            EXPECT_TRUE(s.collides[i]) << s.name << " state " << i;
            EXPECT_TRUE(fclSays) << s.name << " state " << i << ": surfaces cross, FCL reports no contact";
        }
    }
    std::printf("%s: %zu states with crossing surfaces, %zu colliding with none (buried: FCL misses them)\n",
                s.name.c_str(), crossing, buried);
    EXPECT_GT(crossing, s.numStates() / 10) << s.name;
    if (s.name == "sphere")
    {
        EXPECT_GT(buried, 0u) << "some uniform states bury the bar in the sphere";
    }
}

TEST_P(NonConvexScene, BatchesDecideAsSingleStates)
{
    const Scenario &s = *scenario_;
    const std::size_t n = s.numStates();
    const rc::Checker checker(s.model->robot, s.model->scene);
    for (rc::CollisionMode mode : kModes)
        for (double padding : {0.0, s.padding})
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.padding = padding;
            std::vector<std::uint8_t> valid(n), validWithContacts(n);
            std::vector<rc::Contact> contacts(n);
            checker.check(s.states.data(), n, valid.data(), request);
            checker.check(s.states.data(), n, validWithContacts.data(), request, contacts.data());
            for (std::size_t i = 0; i < n; ++i)
            {
                rc::Contact contact;
                const bool single = checker.isValid(s.state(i), request, &contact);
                const std::string what = s.name + " " + rc::toString(mode) + " padding " + std::to_string(padding) +
                                         " state " + std::to_string(i);
                EXPECT_EQ(valid[i] != 0, single) << what;
                EXPECT_EQ(validWithContacts[i] != 0, single) << what;
                EXPECT_TRUE(contacts[i].kind == contact.kind && contacts[i].component == contact.component &&
                            contacts[i].object == contact.object &&
                            contacts[i].otherComponent == contact.otherComponent &&
                            contacts[i].triangle == contact.triangle)
                    << what << ": first contacts differ";
            }
        }
}

TEST_P(NonConvexScene, StagedPipelineDecidesAsTheCpuBackend)
{
    const Scenario &s = *scenario_;
    const rc::CpuBackend cpu(s.model);
    const rc::StagedBackend staged(s.model, rc::makeHostStageRunner(s.model, {}, rc::HostScratch::Poisoned));
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Conservative})
        for (double padding : {0.0, s.padding})
        {
            rc::CollisionRequest request;
            request.mode = mode;
            request.padding = padding;
            const rc::test::Agreement counts = rc::test::expectSameDecisions(
                staged, cpu, *s.model, s.states, request,
                s.name + " (" + rc::toString(mode) + ", padding " + std::to_string(padding) + ")");
            EXPECT_GT(counts.valid, 0u) << s.name;
            EXPECT_GT(counts.invalid, 0u) << s.name;
        }
}

TEST_P(NonConvexScene, TheStagesRasterizeOnlyTheTrianglesNearAPair)
{
    // The batched stages take a pair's candidate triangles from both trees' node culls: a pair's
    // image covers a robot-sized window, so only the part of the scene mesh under it is read (the
    // stages read both meshes whole before). Raster mode's verdicts stay the CPU backend's.
    const Scenario &s = *scenario_;
    const rc::CpuBackend cpu(s.model);
    const rc::StagedBackend staged(s.model, rc::makeHostStageRunner(s.model, {}, rc::HostScratch::Poisoned));
    staged.countStages(true);
    rc::CollisionRequest request;
    request.mode = rc::CollisionMode::Raster;
    rc::test::expectSameDecisions(staged, cpu, *s.model, s.states, request, s.name + " (raster)");
    const rc::device::StageCounts counts = staged.stageCounts();
    const std::size_t meshTriangles = (s.model->componentTriangles.size() + s.model->objectTriangles.size()) / 3;
    std::printf("%s: %llu pairs rasterized, %.1f candidate triangles each of %zu in the two meshes\n", s.name.c_str(),
                counts.rasterizedPairs,
                double(counts.candidateTriangles) / double(std::max(1ull, counts.rasterizedPairs)), meshTriangles);
    if (s.model->objects[0].closed || s.model->components[0].closed)
    {
        ASSERT_GE(counts.rasterizedPairs, 20u)
            << s.name;  // 262 to 868 at full scale, 50 to 218 at the sanitizers quarter
        EXPECT_LT(counts.candidateTriangles, counts.rasterizedPairs * meshTriangles / 4) << s.name;
    }
    else
        EXPECT_EQ(counts.rasterizedPairs, 0u) << s.name << ": two open meshes are decided exactly";
}

INSTANTIATE_TEST_SUITE_P(Scenes, NonConvexScene, ::testing::ValuesIn(kScenarios),
                         [](const ::testing::TestParamInfo<const char *> &info) { return std::string(info.param); });
