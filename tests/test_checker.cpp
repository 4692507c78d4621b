// The collision engine end to end on the CPU backend: known answers, every mode against the exact
// oracle on the blind-spot suites and the Panda MotionBenchMaker scenes, determinism across threads.
#include <cmath>
#include <cstring>
#include <functional>
#include <cstdlib>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "BackendSuites.h"
#include "BlindSpots.h"
#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/BuildConfig.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/RigidBody.h"

namespace rc = rastercheck;

namespace
{
rc::Mesh boxAt(const Eigen::Vector3d &size, const Eigen::Vector3d &center)
{
    rc::Mesh mesh = rc::makeBox(size);
    mesh.transform(Eigen::Isometry3d(Eigen::Translation3d(center)));
    return mesh;
}

rc::RobotModelConstPtr cubeRobot(double side)
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d::Constant(-5);
    bounds.max = Eigen::Vector3d::Constant(5);
    return rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d::Constant(side)), bounds);
}

// A unit-ish table (object 0) and a post (object 1).
rc::SceneConstPtr tableScene()
{
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("table", boxAt({1.0, 1.0, 0.1}, {0, 0, -0.05}));
    scene->addObject("post", boxAt({0.1, 0.1, 1.0}, {2.0, 0, 0.5}));
    return scene;
}

std::vector<double> at(double x, double y, double z)
{
    return {x, y, z, 0, 0, 0, 1};
}

const rc::CollisionMode kModes[] = {rc::CollisionMode::Safe, rc::CollisionMode::Raster, rc::CollisionMode::Exact,
                                    rc::CollisionMode::Conservative};
}  // namespace

TEST(Checker, KnownAnswersInEveryMode)
{
    const rc::Checker checker(cubeRobot(0.2), tableScene());
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        rc::Contact contact;
        // Resting 5 cm into the table top: collision with object 0 near z = 0.
        EXPECT_FALSE(checker.isValid(at(0.2, 0.1, 0.05), request, &contact)) << rc::toString(mode);
        EXPECT_EQ(contact.kind, rc::Contact::Kind::Environment);
        EXPECT_EQ(contact.object, 0);
        EXPECT_EQ(contact.component, 0);
        EXPECT_NEAR(contact.position.z(), 0.0, 0.06);
        EXPECT_NEAR(contact.position.x(), 0.2, 0.11);
        // 1 cm above the table and far from the post: free.
        EXPECT_TRUE(checker.isValid(at(0.2, 0.1, 0.11), request, &contact)) << rc::toString(mode);
        EXPECT_EQ(contact.kind, rc::Contact::Kind::None);
        // Hitting the post.
        EXPECT_FALSE(checker.isValid(at(2.1, 0.05, 0.5), request, &contact));
        EXPECT_EQ(contact.object, 1);
    }
}

TEST(Checker, PaddingIsHonouredExactly)
{
    const rc::Checker checker(cubeRobot(0.2), tableScene());
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        const std::vector<double> gap1cm = at(0.2, 0.1, 0.11);
        request.padding = 0.009;
        EXPECT_TRUE(checker.isValid(gap1cm, request)) << rc::toString(mode);
        request.padding = 0.011;
        EXPECT_FALSE(checker.isValid(gap1cm, request)) << rc::toString(mode);
    }
}

TEST(Checker, PairPaddingActsLikeThePaddingOnItsPairs)
{
    const rc::Checker checker(cubeRobot(0.2), tableScene());
    ASSERT_EQ(checker.collisionModel().numComponents(), 1u);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        request.padding = 0.004;
        auto extra = std::make_shared<rc::PairPadding>();
        const std::vector<double> gap1cm = at(0.2, 0.1, 0.11);
        extra->environment = {0.005};  // 0.009 in all
        request.pairPadding = extra;
        EXPECT_TRUE(checker.isValid(gap1cm, request)) << rc::toString(mode);
        extra->environment = {0.007};  // 0.011 in all
        EXPECT_FALSE(checker.isValid(gap1cm, request)) << rc::toString(mode);
        // The same as the plain padding, state for state, on a batch.
        std::vector<double> q;
        for (int i = 0; i < 40; ++i)
        {
            const std::vector<double> state = at(0.1 * i - 1.0, 0.05 * (i % 7), 0.09 + 0.002 * (i % 13));
            q.insert(q.end(), state.begin(), state.end());
        }
        std::vector<std::uint8_t> byPair(40), byPadding(40);
        checker.check(q.data(), 40, byPair.data(), request);
        rc::CollisionRequest plain;
        plain.mode = mode;
        plain.padding = 0.011;
        checker.check(q.data(), 40, byPadding.data(), plain);
        EXPECT_EQ(byPair, byPadding) << rc::toString(mode);
        // One row per state: the gap of 1 cm is clear at 0.009 (row 0), not at 0.011 (row 1).
        auto rows = std::make_shared<rc::PairPadding>();
        rows->rows = 2;
        rows->environment = {0.005, 0.007};
        rc::CollisionRequest perState = request;
        perState.pairPadding = rows;
        std::vector<double> twice = gap1cm;
        twice.insert(twice.end(), gap1cm.begin(), gap1cm.end());
        std::vector<std::uint8_t> verdicts(2);
        checker.check(twice.data(), 2, verdicts.data(), perState);
        EXPECT_EQ(verdicts, (std::vector<std::uint8_t>{1, 0})) << rc::toString(mode);
        // Rows must match the batch: two rows for one state are a configuration error.
        EXPECT_THROW(checker.isValid(gap1cm, perState), rc::ConfigurationError);
    }
    // Entries must fit the model and be finite and >= 0.
    rc::CollisionRequest request;
    auto extra = std::make_shared<rc::PairPadding>();
    request.pairPadding = extra;
    EXPECT_THROW(checker.isValid(at(0, 0, 1), request), rc::ConfigurationError);  // no entry for the component
    extra->environment = {-0.1};
    EXPECT_THROW(checker.isValid(at(0, 0, 1), request), rc::ConfigurationError);
    extra->environment = {0.0};
    extra->self = {0.0};  // the cube has no self pair
    EXPECT_THROW(checker.isValid(at(0, 0, 1), request), rc::ConfigurationError);
}

TEST(Checker, AnOpenPairIsDecidedWithItsOwnPadding)
{
    // The staged backends finish open pairs with decideOpenPair: it must read the pair's padding
    // from the state's pairPadding row, as the CPU backend's own pass does.
    const auto model = std::make_shared<const rc::CollisionModel>(cubeRobot(0.2), tableScene());
    const rc::CpuBackend backend(model);
    std::unique_ptr<rc::CpuWorkspace> ws = backend.makeWorkspace();
    backend.refitState(at(0.2, 0.1, 0.11).data(), *ws);  // 1 cm above the table top (object 0)
    rc::CollisionRequest request;
    request.padding = 0.004;
    auto rows = std::make_shared<rc::PairPadding>();
    rows->rows = 2;
    rows->environment = {0.005, 0.007};  // 0.009 and 0.011 in all
    request.pairPadding = rows;
    const std::uint32_t table = 0;  // object 0 against component 0
    for (rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact})
    {
        request.mode = mode;
        rc::Contact contact;
        EXPECT_FALSE(backend.decideOpenPair(table, request, *ws, contact, 0)) << rc::toString(mode);
        EXPECT_TRUE(backend.decideOpenPair(table, request, *ws, contact, 1)) << rc::toString(mode);
        EXPECT_EQ(contact.object, 0);
    }
}

TEST(Checker, SelfCollisionRespectsTheAllowedCollisionMatrix)
{
    // base (cube at origin) -j1-> middle (small cube, adjacent) -j2-> tip (cube 0.6 along its x).
    rc::RobotModel model;
    model.name = "folding";
    model.links = {{"base", -1, 0}, {"middle", -1, 1}, {"tip", -1, 2}};
    auto joint = [](const std::string &name, int parent, int child)
    {
        rc::Joint j;
        j.name = name;
        j.kind = rc::JointKind::Revolute;
        j.parentLink = parent;
        j.childLink = child;
        j.origin.translation() = Eigen::Vector3d(0.3, 0, 0);
        j.axis = Eigen::Vector3d::UnitZ();
        j.coordinateNames = {name};
        j.lower = {-4};
        j.upper = {4};
        return j;
    };
    model.joints = {joint("j1", 0, 1), joint("j2", 1, 2)};
    auto component = [](const std::string &name, int link, rc::Mesh mesh)
    {
        rc::Component c;
        c.name = name;
        c.link = link;
        c.mesh = std::move(mesh);
        c.topology = rc::cleanMesh(c.mesh);
        c.localAabb = c.mesh.bounds();
        c.localObb = rc::Obb::fit(c.mesh);
        return c;
    };
    model.components = {component("base", 0, boxAt({0.1, 0.1, 0.1}, {0, 0, 0})),
                        component("middle", 1, boxAt({0.05, 0.05, 0.05}, {0, 0, 0})),
                        component("tip", 2, boxAt({0.1, 0.1, 0.1}, {0.6, 0, 0}))};
    model.finalize();
    auto shared = std::make_shared<rc::RobotModel>(model);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        const rc::Checker checker(shared, nullptr);
        rc::Contact contact;
        EXPECT_TRUE(checker.isValid(std::vector<double>{0.0, 0.0}, request));
        // Folded back: the tip lands on the base.
        EXPECT_FALSE(checker.isValid(std::vector<double>{0.0, M_PI}, request, &contact)) << rc::toString(mode);
        EXPECT_EQ(contact.kind, rc::Contact::Kind::SelfCollision);
        EXPECT_EQ(model.components[contact.component].name, "base");
        EXPECT_EQ(model.components[contact.otherComponent].name, "tip");
        request.checkSelfCollision = false;
        EXPECT_TRUE(checker.isValid(std::vector<double>{0.0, M_PI}, request));
        // A self pair's pairPadding entry acts like the padding on it (base vs tip is the only pair).
        ASSERT_EQ(checker.collisionModel().selfPairs.size(), 1u);
        request.checkSelfCollision = true;
        rc::CollisionRequest byPair = request;
        auto extra = std::make_shared<rc::PairPadding>();
        extra->environment = {0.0, 0.0, 0.0};
        extra->self = {0.05};
        byPair.pairPadding = extra;
        request.padding = 0.05;
        int differing = 0, invalid = 0;
        for (double angle = 2.0; angle <= M_PI; angle += 0.01)
        {
            const std::vector<double> q{0.0, angle};
            differing += checker.isValid(q, byPair) != checker.isValid(q, request);
            invalid += !checker.isValid(q, request);
        }
        EXPECT_EQ(differing, 0) << rc::toString(mode);
        EXPECT_GT(invalid, 10) << rc::toString(mode);
        EXPECT_LT(invalid, 100) << rc::toString(mode);
    }
    // Allowing the pair silences it.
    shared->setCollisionAllowed(0, 2, true);
    EXPECT_TRUE(rc::Checker(shared, nullptr).isValid(std::vector<double>{0.0, M_PI}));
}

TEST(RobotParts, ModelsOfRobotsWithEqualContentShareTheRobotsTrees)
{
    // Two robots loaded apart with the same content: the second model's component trees are the
    // first's. A cube of another size gets trees of its own, and its verdicts.
    const rc::CollisionModel first(cubeRobot(0.2), tableScene());
    const rc::CollisionModel second(cubeRobot(0.2), nullptr);
    const rc::CollisionModel larger(cubeRobot(0.3), tableScene());
    ASSERT_EQ(first.componentBvhs.size(), 1u);
    EXPECT_EQ(first.componentBvhs[0].get(), second.componentBvhs[0].get());
    EXPECT_NE(first.componentBvhs[0].get(), larger.componentBvhs[0].get());
    EXPECT_EQ(first.componentTrees.nodes.size(), second.componentTrees.nodes.size());
    // The copied arrays are the shared tree's own.
    EXPECT_EQ(0, std::memcmp(first.componentTrees.nodes.data(), first.componentBvhs[0]->nodes(),
                             first.componentTrees.nodes.size() * sizeof(rc::MeshBvh::Node)));
    // 12 cm above the table top: the 0.2 m cube is clear of it, the 0.3 m cube is in it.
    EXPECT_TRUE(rc::Checker(cubeRobot(0.2), tableScene()).isValid(at(0, 0, 0.12)));
    EXPECT_FALSE(rc::Checker(cubeRobot(0.3), tableScene()).isValid(at(0, 0, 0.12)));
}

TEST(RobotParts, ARobotChangedAfterAModelWasBuiltGetsPartsOfItsOwn)
{
    // The caller's robot changes in place after a checker was built from it (the parts were built
    // for a copy): the next checker sees the change, the first keeps its own verdicts.
    auto robot = std::make_shared<rc::RobotModel>(*cubeRobot(0.2));
    const rc::Checker before(robot, tableScene());
    for (Eigen::Vector3d &v : robot->components[0].mesh.vertices)
        v *= 1.5;  // a 0.3 m cube
    robot->components[0].localObb.halfExtents *= 1.5;
    robot->components[0].localAabb = robot->components[0].mesh.bounds();
    const rc::Checker after(robot, tableScene());
    EXPECT_TRUE(before.isValid(at(0, 0, 0.12)));
    EXPECT_FALSE(after.isValid(at(0, 0, 0.12)));
    EXPECT_NE(before.collisionModel().componentBvhs[0].get(), after.collisionModel().componentBvhs[0].get());
}

TEST(RobotParts, TheLastUsedPartsStayBuiltAndOthersAreFreed)
{
    std::weak_ptr<const rc::MeshBvh> tree;
    const rc::MeshBvh *address = nullptr;
    {
        const rc::CollisionModel model(cubeRobot(0.25), nullptr);
        tree = model.componentBvhs[0];
        address = model.componentBvhs[0].get();
    }
    // Dropped by every model, kept: the next model of that robot reuses it.
    ASSERT_FALSE(tree.expired());
    EXPECT_EQ(rc::CollisionModel(cubeRobot(0.25), nullptr).componentBvhs[0].get(), address);
    // Once kKeptRobotParts other robots were used since, it is freed.
    for (std::size_t k = 0; k < rc::CollisionModel::kKeptRobotParts; ++k)
        rc::CollisionModel(cubeRobot(0.26 + 0.01 * static_cast<double>(k)), nullptr);
    EXPECT_TRUE(tree.expired());
}

TEST(RobotParts, AMalformedComponentMeshIsAnErrorFromTheParallelBuild)
{
    // The trees are built on OpenMP's threads: an error in one (a triangle naming a vertex the mesh
    // does not have, from a model edited by hand) reaches the caller as a ConfigurationError.
    auto robot = std::make_shared<rc::RobotModel>(*rc::test::plant().robot);
    robot->components[1].mesh.triangles[0][2] = static_cast<std::uint32_t>(robot->components[1].mesh.numVertices());
    try
    {
        const rc::Checker checker(robot, nullptr);
        FAIL() << "a mesh with a missing vertex was accepted";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_NE(std::string(e.what()).find("component '" + robot->components[1].name +
                                             "': MeshBvh: triangle 0 names vertex"),
                  std::string::npos)
            << e.what();
    }
}

TEST(RobotParts, EveryFieldOfTheRobotCountsTowardsItsContent)
{
    // Each change below, however small, must give the robot other parts (contentBytes differs);
    // a copy must not.
    const rc::RobotModel &crane = *rc::test::plant().robot;
    const std::string original = rc::contentBytes(crane);
    EXPECT_TRUE(rc::contentBytes(rc::RobotModel(crane)) == original);
    ASSERT_GE(crane.components.size(), 2u);
    ASSERT_GE(crane.joints.size(), 2u);
    const std::vector<std::pair<std::string, std::function<void(rc::RobotModel &)>>> changes = {
        {"name", [](rc::RobotModel &r) { r.name += "x"; }},
        {"link name", [](rc::RobotModel &r) { r.links[1].name += "x"; }},
        {"link component", [](rc::RobotModel &r) { r.links[0].component = -2; }},
        {"joint origin", [](rc::RobotModel &r) { r.joints[1].origin.translation().x() += 1e-12; }},
        {"joint axis", [](rc::RobotModel &r) { r.joints[1].axis.z() = -r.joints[1].axis.z(); }},
        {"joint lower bound", [](rc::RobotModel &r) { r.joints[1].lower.push_back(0.0); }},
        {"joint kind", [](rc::RobotModel &r) { r.joints[0].kind = rc::JointKind::Revolute; }},
        {"joint continuity", [](rc::RobotModel &r) { r.joints[0].continuous = !r.joints[0].continuous; }},
        {"mimic", [](rc::RobotModel &r) { r.joints[1].mimicOffset += 1.0; }},
        {"component vertex", [](rc::RobotModel &r) { r.components[1].mesh.vertices[0].y() += 1e-12; }},
        {"component triangle", [](rc::RobotModel &r)
         { std::swap(r.components[1].mesh.triangles[0][0], r.components[1].mesh.triangles[0][1]); }},
        {"component closed",
         [](rc::RobotModel &r) { r.components[0].topology.closed = !r.components[0].topology.closed; }},
        {"component box", [](rc::RobotModel &r) { r.components[0].localObb.halfExtents.x() *= 2.0; }},
        {"component bounds", [](rc::RobotModel &r) { r.components[0].localAabb.max.x() += 1.0; }},
        {"component shapes", [](rc::RobotModel &r) { r.components[0].shapes.emplace_back(); }},
        {"component link", [](rc::RobotModel &r) { r.components[0].link += 1; }},
        {"subtree ends", [](rc::RobotModel &r) { r.componentSubtreeEnd[0] += 1; }},
        {"coordinate bound", [](rc::RobotModel &r) { r.upperBounds[0] = std::nextafter(r.upperBounds[0], 1e9); }},
        {"coordinate name", [](rc::RobotModel &r) { r.coordinateNames[0] += "x"; }},
        {"allowed collisions", [](rc::RobotModel &r) { r.setCollisionAllowed(0, 1, !r.isCollisionAllowed(0, 1)); }},
        {"kinematic joint", [](rc::RobotModel &r) { r.kinematicJoints[1].axis.x += 1e-9; }},
    };
    for (const auto &[what, change] : changes)
    {
        rc::RobotModel changed = crane;
        change(changed);
        EXPECT_TRUE(rc::contentBytes(changed) != original) << what;
    }
}

TEST(Checker, ComponentOfOverlappingShellsContainsWhatEitherShellContains)
{
    // Two 0.4 m cubes overlapping in x in [-0.1, 0.1] form one component; a 2 cm pebble sits in the
    // overlap. Parity would count two shells around it and call it outside.
    rc::RobotModel model;
    model.name = "twin_cubes";
    model.links = {{"world", -1, -1}, {"body", -1, 0}};
    rc::Joint slide;
    slide.name = "slide";
    slide.kind = rc::JointKind::Prismatic;
    slide.parentLink = 0;
    slide.childLink = 1;
    slide.axis = Eigen::Vector3d::UnitX();
    slide.coordinateNames = {"slide"};
    slide.lower = {-2};
    slide.upper = {2};
    model.joints = {slide};
    model.components = {
        rc::makeComponent("body", {boxAt({0.4, 0.4, 0.4}, {-0.1, 0, 0}), boxAt({0.4, 0.4, 0.4}, {0.1, 0, 0})})};
    model.finalize();
    ASSERT_TRUE(model.components[0].topology.closed);
    ASSERT_EQ(model.components[0].topology.shells, 2u);
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("pebble", boxAt({0.02, 0.02, 0.02}, {0, 0, 0}));
    const rc::Checker checker(std::make_shared<rc::RobotModel>(model), scene);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        rc::Contact contact;
        EXPECT_FALSE(checker.isValid(std::vector<double>{0.0}, request, &contact)) << rc::toString(mode);
        EXPECT_TRUE(checker.isValid(std::vector<double>{1.0}, request)) << rc::toString(mode);
    }
}

TEST(Checker, EveryModeAgainstTheOracleOnBlindSpots)
{
    for (const rc::test::BlindSpotSuite &suite : rc::test::blindSpotSuites(400))
    {
        const rc::Checker checker(suite.robot, suite.scene);
        const std::size_t n = suite.numStates();
        std::vector<std::uint8_t> truth(n);
        std::size_t colliding = 0;
        for (std::size_t i = 0; i < n; ++i)
        {
            truth[i] = rc::test::bruteForceCollides(checker.collisionModel(), suite.states.data() + 7 * i, 0.0) ? 0 : 1;
            colliding += !truth[i];
        }
        // Each suite must really straddle the boundary, or it tests nothing.
        EXPECT_GT(colliding, n / 10) << suite.name;
        EXPECT_LT(colliding, n - n / 10) << suite.name;
        for (rc::CollisionMode mode : kModes)
        {
            rc::CollisionRequest request;
            request.mode = mode;
            std::vector<std::uint8_t> valid(n);
            checker.check(suite.states.data(), n, valid.data(), request);
            std::size_t falseNegatives = 0, falsePositives = 0;
            for (std::size_t i = 0; i < n; ++i)
            {
                falseNegatives += valid[i] && !truth[i];
                falsePositives += !valid[i] && truth[i];
            }
            // Conservative mode may call free states invalid (hulls within the padding), never the reverse.
            if (mode != rc::CollisionMode::Raster)
            {
                EXPECT_EQ(falseNegatives, 0u) << suite.name << " " << rc::toString(mode);
            }
            if (mode == rc::CollisionMode::Safe || mode == rc::CollisionMode::Exact)
            {
                EXPECT_EQ(falsePositives, 0u) << suite.name << " " << rc::toString(mode);
            }
            // The paper's method alone is allowed blind spots, but never false alarms.
            if (mode == rc::CollisionMode::Raster)
            {
                EXPECT_EQ(falsePositives, 0u) << suite.name;
            }
        }
    }
}

TEST(Checker, SafeModeMatchesTheOracleOnPandaScenes)
{
    RASTERCHECK_REQUIRE_DATA(root);
    rc::RobotModelPtr panda = rc::loadUrdf(root + "/mbm/panda/panda.urdf");
    rc::applySrdf(*panda, rc::loadSrdf(root + "/mbm/panda/panda.srdf"));
    for (const char *scenario :
         {"bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "cage", "table_pick", "table_under_pick"})
    {
        const rc::SceneConstPtr scene =
            rc::loadMoveItScene(root + "/mbm/panda/problems/" + scenario + "_panda/scene0001.yaml");
        const rc::Checker checker(panda, scene);
        std::mt19937_64 rng(11);
        const std::size_t n = 150, dof = panda->numCoordinates();
        std::vector<double> q(n * dof);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t k = 0; k < dof; ++k)
                q[i * dof + k] =
                    std::uniform_real_distribution<double>(panda->lowerBounds[k], panda->upperBounds[k])(rng);
        std::vector<std::uint8_t> valid(n), exact(n), conservative(n);
        checker.check(q.data(), n, valid.data());
        rc::CollisionRequest exactRequest, conservativeRequest;
        exactRequest.mode = rc::CollisionMode::Exact;
        conservativeRequest.mode = rc::CollisionMode::Conservative;
        checker.check(q.data(), n, exact.data(), exactRequest);
        checker.check(q.data(), n, conservative.data(), conservativeRequest);
        rc::test::FclReference fcl(checker.collisionModel());
        std::size_t colliding = 0, falseAlarms = 0;
        for (std::size_t i = 0; i < n; ++i)
        {
            const bool truth = !rc::test::bruteForceCollides(checker.collisionModel(), q.data() + i * dof, 0.0);
            colliding += !truth;
            EXPECT_EQ(valid[i] != 0, truth) << scenario << " state " << i;
            EXPECT_EQ(exact[i] != 0, truth) << scenario << " state " << i;
            if (conservative[i])
            {
                EXPECT_TRUE(truth) << scenario << " state " << i << ": conservative mode missed a collision";
            }
            falseAlarms += truth && !conservative[i];
            // FCL sees surfaces only: it may miss a buried link, never report a free state as colliding.
            if (fcl.collides(q.data() + i * dof))
            {
                EXPECT_FALSE(truth) << scenario << " state " << i;
            }
        }
        EXPECT_GT(colliding, 0u) << scenario;
        // The proofs settle almost every free Panda state (docs/accuracy.md): false alarms stay rare.
        EXPECT_LE(falseAlarms, (n - colliding) / 10) << scenario;
    }
}

TEST(Checker, TwoPaddingsInOnePassGiveTheVerdictsOfTwoChecks)
{
    // checkTwoPaddings must say what check() says at the wider paddings and then at the request's
    // own: the blind spots (meshes, primitives, non-convex shapes), the Panda's scenes and the
    // crane, every mode that can certify (one pass on the CPU backend) and raster mode (two
    // passes), with and without pair paddings of the request's own, per state.
    std::size_t kinds[3] = {0, 0, 0};
    for (const rc::test::StateSuite &suite : rc::test::accuracySuites(120))
    {
        const rc::Checker checker(suite.robot, suite.scene, rc::CheckerOptions{rc::BackendChoice::Cpu, 1});
        const rc::CollisionModel &model = checker.collisionModel();
        const std::size_t n = suite.numStates();
        const std::shared_ptr<rc::PairPadding> wider = rc::test::randomPairPaddings(model, n, 5);
        for (const rc::CollisionMode mode : {rc::CollisionMode::Safe, rc::CollisionMode::Exact,
                                             rc::CollisionMode::Conservative, rc::CollisionMode::Raster})
            for (const bool ownPairPaddings : {false, true})
            {
                rc::CollisionRequest request;
                request.mode = mode;
                request.padding = 0.002;
                if (ownPairPaddings)
                    request.pairPadding = rc::test::randomPairPaddings(model, n, 9);
                // The wider paddings as one request: the request's own plus wider's, per state.
                rc::CollisionRequest wide = request;
                auto sum = std::make_shared<rc::PairPadding>(*wider);
                if (ownPairPaddings)
                {
                    for (std::size_t k = 0; k < sum->environment.size(); ++k)
                        sum->environment[k] += request.pairPadding->environment[k];
                    for (std::size_t k = 0; k < sum->self.size(); ++k)
                        sum->self[k] += request.pairPadding->self[k];
                }
                wide.pairPadding = sum;
                std::vector<std::uint8_t> verdicts(n), clear(n), valid(n);
                checker.checkTwoPaddings(suite.states.data(), n, verdicts.data(), request, *wider);
                checker.check(suite.states.data(), n, clear.data(), wide);
                checker.check(suite.states.data(), n, valid.data(), request);
                for (std::size_t i = 0; i < n; ++i)
                {
                    const rc::PaddedVerdict expected = clear[i]   ? rc::PaddedVerdict::Clear
                                                       : valid[i] ? rc::PaddedVerdict::Near
                                                                  : rc::PaddedVerdict::Collides;
                    EXPECT_EQ(verdicts[i], static_cast<std::uint8_t>(expected))
                        << suite.name << ", mode " << rc::toString(mode)
                        << (ownPairPaddings ? ", own pair paddings" : "") << ", state " << i;
                    ++kinds[verdicts[i] < 3 ? verdicts[i] : 0];
                }
            }
    }
    // Every verdict occurs, or the comparison above proves little.
    EXPECT_GT(kinds[0], 100u);
    EXPECT_GT(kinds[1], 100u);
    EXPECT_GT(kinds[2], 100u);
}

TEST(Checker, TwoPaddingsRefuseWiderPaddingsThatDoNotFit)
{
    const rc::Checker checker(cubeRobot(0.2), tableScene());
    const rc::CollisionModel &model = checker.collisionModel();
    std::vector<double> q(3 * checker.dof(), 0.0);
    std::vector<std::uint8_t> verdicts(3);
    rc::PairPadding wider;
    wider.rows = 2;  // neither 1 nor the batch's 3
    wider.environment.assign(2 * model.numComponents(), 0.0);
    wider.self.assign(2 * model.selfPairs.size(), 0.0);
    EXPECT_THROW(checker.checkTwoPaddings(q.data(), 3, verdicts.data(), {}, wider), rc::ConfigurationError);
    wider.rows = 1;
    wider.environment.assign(model.numComponents(), -0.1);  // a negative padding
    wider.self.assign(model.selfPairs.size(), 0.0);
    EXPECT_THROW(checker.checkTwoPaddings(q.data(), 3, verdicts.data(), {}, wider), rc::ConfigurationError);
    wider.environment.assign(model.numComponents(), std::numeric_limits<double>::quiet_NaN());
    EXPECT_THROW(checker.checkTwoPaddings(q.data(), 3, verdicts.data(), {}, wider), rc::ConfigurationError);
}

TEST(Checker, VerdictsAndContactsAreIdenticalAcrossThreadCounts)
{
    const rc::test::BlindSpotSuite suite = rc::test::blindSpotSuites(500)[0];
    std::vector<std::vector<std::uint8_t>> verdicts;
    std::vector<std::vector<rc::Contact>> contacts;
    for (int threads : {1, 2, 4})
    {
        const rc::Checker checker(suite.robot, suite.scene, rc::CheckerOptions{rc::BackendChoice::Cpu, threads});
        verdicts.emplace_back(suite.numStates());
        contacts.emplace_back(suite.numStates());
        checker.check(suite.states.data(), suite.numStates(), verdicts.back().data(), {}, contacts.back().data());
    }
    for (std::size_t t = 1; t < verdicts.size(); ++t)
    {
        EXPECT_EQ(verdicts[t], verdicts[0]);
        for (std::size_t i = 0; i < suite.numStates(); ++i)
        {
            EXPECT_EQ(contacts[t][i].triangle, contacts[0][i].triangle);
            EXPECT_EQ(contacts[t][i].position, contacts[0][i].position);
        }
    }
}

TEST(Checker, ObjectBoxesHoldEveryVertexAndHugRotatedWalls)
{
    // A wall turned 30 degrees about z, in site coordinates far from the world origin: its
    // axis-aligned box is mostly air, its oriented box (the OBB-vs-OBB cull) is not.
    const Eigen::Vector3d wallCentre(1000.0, -500.0, 3.0);
    rc::Mesh wall = rc::makeBox(Eigen::Vector3d(2.0, 0.04, 1.0));
    wall.transform(Eigen::Translation3d(wallCentre) * Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()));
    auto scene = std::make_shared<rc::Scene>();
    scene->addObject("wall", wall);
    scene->addObject("crate", boxAt({0.3, 0.3, 0.3}, wallCentre + Eigen::Vector3d(3.0, 2.0, 0.0)));
    rc::Aabb bounds;
    bounds.min = wallCentre - Eigen::Vector3d::Constant(5);
    bounds.max = wallCentre + Eigen::Vector3d::Constant(5);
    const rc::RobotModelConstPtr robot =
        rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d::Constant(0.2)), bounds);

    const rc::CollisionModel model(robot, scene);
    for (std::size_t o = 0; o < scene->objects.size(); ++o)
    {
        const rc::device::OrientedBox &box = model.objectOrientedBoxes[o];
        for (const Eigen::Vector3d &vertex : scene->objects[o].mesh.vertices)
        {
            const Eigen::Vector3d p = vertex - model.origin;
            for (int axis = 0; axis < 3; ++axis)
            {
                double local = 0.0;
                for (int r = 0; r < 3; ++r)
                    local += static_cast<double>(box.axes[3 * r + axis]) * (p[r] - static_cast<double>(box.center[r]));
                EXPECT_LE(std::abs(local), static_cast<double>(box.half[axis])) << "object " << o << " axis " << axis;
            }
        }
    }
    const rc::device::OrientedBox &wallBox = model.objectOrientedBoxes[0];
    const rc::device::Box &wallBounds = model.objectBoxes[0];
    const double orientedVolume = 8.0 * wallBox.half[0] * wallBox.half[1] * wallBox.half[2];
    double boundsVolume = 1.0;
    for (int k = 0; k < 3; ++k)
        boundsVolume *= wallBounds.max[k] - wallBounds.min[k];
    EXPECT_LT(orientedVolume, 0.1 * boundsVolume);

    // The cube 5 cm off the wall's face, well inside the wall's axis-aligned box: free, unless the
    // padding reaches the wall; 5 cm into it: a collision.
    const Eigen::Vector3d normal(-std::sin(M_PI / 6), std::cos(M_PI / 6), 0.0);  // the wall's thin axis
    const auto cubeAt = [&](double offFace)
    {
        const Eigen::Vector3d c = wallCentre + (0.02 + 0.1 + offFace) * normal;
        return at(c.x(), c.y(), c.z());
    };
    const rc::Checker checker(robot, scene);
    for (rc::CollisionMode mode : kModes)
    {
        rc::CollisionRequest request;
        request.mode = mode;
        // The cube is not turned with the wall: its corner reaches 0.1 * (sqrt(2) cos 15deg - 1)
        // = 0.0366 closer than its centre's offset.
        EXPECT_TRUE(checker.isValid(cubeAt(0.05 + 0.0366), request)) << rc::toString(mode);
        EXPECT_FALSE(checker.isValid(cubeAt(-0.05), request)) << rc::toString(mode);
        request.padding = 0.04;
        EXPECT_TRUE(checker.isValid(cubeAt(0.05 + 0.0366), request)) << rc::toString(mode);
        request.padding = 0.06;
        EXPECT_FALSE(checker.isValid(cubeAt(0.05 + 0.0366), request)) << rc::toString(mode);
    }
}

TEST(Checker, RasterImageMarksTheCollisionPixels)
{
    const rc::Checker checker(cubeRobot(0.2), tableScene());
    rc::CollisionRequest request;
    request.mode = rc::CollisionMode::Raster;
    rc::Contact contact;
    const std::vector<double> q = at(0.2, 0.1, 0.05);
    ASSERT_FALSE(checker.isValid(q, request, &contact));
    rc::RasterImage image;
    ASSERT_TRUE(checker.rasterImage(q.data(), contact, request, image));
    const std::size_t pixels = static_cast<std::size_t>(image.grid.width * image.grid.height);
    ASSERT_EQ(image.hits.size(), pixels);
    std::size_t hits = 0, both = 0;
    for (std::size_t p = 0; p < pixels; ++p)
    {
        hits += image.hits[p];
        both += image.coverage[p] == 3;
        if (image.hits[p])
        {
            EXPECT_EQ(image.coverage[p], 3);  // an overlap needs fragments of both solids
        }
    }
    // The cube's 0.2 x 0.2 footprint sinks into the table top: rays along z (the window's thinnest
    // extent, 5 cm) see the overlap over the whole footprint.
    EXPECT_EQ(image.grid.axis, 2);
    EXPECT_GT(hits, pixels / 2);
    EXPECT_EQ(hits, both);
    EXPECT_FALSE(checker.rasterImage(q.data(), rc::Contact{}, request, image));
}

TEST(Checker, WithoutAUsableDeviceTheCudaChoiceFallsBackToTheCpuWithAWarning)
{
    std::vector<std::string> warnings;
    rc::setLogHandler(
        [&](rc::LogLevel level, const std::string &message)
        {
            if (level == rc::LogLevel::Warning)
                warnings.push_back(message);
        });
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cuda;
    const rc::Checker checker(cubeRobot(0.2), tableScene(), options);
    rc::setLogHandler(nullptr);
    if (checker.backendName() != "cpu")
        GTEST_SKIP() << "a CUDA device is usable here (" << checker.backendName() << "): nothing falls back";
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("using the CPU backend"), std::string::npos) << warnings[0];
    // Said plainly: not the CUDA runtime's "driver version is insufficient" for a missing driver.
    EXPECT_EQ(warnings[0], RASTERCHECK_WITH_CUDA ? "no NVIDIA driver or device found; using the CPU backend"
                                                 : "this build has no CUDA backend; using the CPU backend");
    // Decisions still come, from the CPU backend.
    EXPECT_FALSE(checker.isValid(at(0, 0, 0)));
    EXPECT_TRUE(checker.isValid(at(0, 0, 1)));
}

TEST(Checker, HostStagesRunTheDevicePathFromTheirDeviceBatchOn)
{
    // BackendChoice::HostStages: the GPU's staged pipeline on the host executor, batches of at
    // least minDeviceBatch states on it, smaller ones on the CPU backend; deviceBatch() says where
    // that line is (0: every batch on the CPU), which planners size their batches by.
    EXPECT_EQ(rc::parseBackendChoice("host-stages"), rc::BackendChoice::HostStages);
    const rc::Checker cpu(cubeRobot(0.2), tableScene(), rc::CheckerOptions{rc::BackendChoice::Cpu, 1});
    EXPECT_EQ(cpu.deviceBatch(), 0u);
    rc::CheckerOptions options{rc::BackendChoice::HostStages, 2};
    const rc::Checker automatic(cubeRobot(0.2), tableScene(), options);
    EXPECT_EQ(automatic.deviceBatch(), 2 * rc::kDeviceBatchPerCpuThread);
    options.minDeviceBatch = 4;
    const rc::Checker staged(cubeRobot(0.2), tableScene(), options);
    EXPECT_EQ(staged.deviceBatch(), 4u);
    EXPECT_EQ(staged.backendName(), "cpu-staged");
    const auto *stages = dynamic_cast<const rc::StagedBackend *>(&staged.backend());
    ASSERT_NE(stages, nullptr);
    // Three states go to the CPU backend, four to the stages; the verdicts are the CPU's.
    std::vector<double> q;
    for (const std::vector<double> &state : {at(0, 0, 0), at(0, 0, 1), at(2, 0, 0.5), at(3, 3, 3)})
        q.insert(q.end(), state.begin(), state.end());
    for (const std::size_t n : {std::size_t{3}, std::size_t{4}})
    {
        const unsigned long long callsBefore = stages->executorCounts().calls;
        std::vector<std::uint8_t> valid(n), expected(n);
        staged.check(q.data(), n, valid.data());
        cpu.check(q.data(), n, expected.data());
        EXPECT_EQ(valid, expected) << n;
        std::vector<std::uint8_t> known = {0, 1, 0, 1};
        known.resize(n);
        EXPECT_EQ(valid, known) << n;
        EXPECT_EQ(stages->executorCounts().calls - callsBefore, n >= 4 ? 1u : 0u) << n;
    }
}

TEST(LongRunning, CheckersBuiltAndDroppedKeepMemoryFlat)
{
    // A system that rebuilds its checker (a scene update, a reconfigured robot) for hours. One build
    // for the crane in the plant takes about 0.13 s here (its robot's part shared: much less): ctest builds 30,
    // RASTERCHECK_SOAK_CHECKERS sets the count (1000 in docs/benchmarks.md), RASTERCHECK_SOAK_SCALE shrinks it
    // (scripts/sanitize.sh).
    const rc::Problem &plant = rc::test::plant();
    const std::vector<double> boomInRack = {0, 0, 0, 1.570796326795, 0.3, 5, 1};
    rc::CheckerOptions options;
    options.backend = rc::BackendChoice::Cpu;
    const char *count = std::getenv("RASTERCHECK_SOAK_CHECKERS");
    const int checkers = rc::test::scaledCount(count && *count ? std::atoi(count) : 30, "RASTERCHECK_SOAK_SCALE");
    // Every other checker is of a reconfigured crane (a robot of new content: its parts built anew,
    // the parts of earlier ones freed), the others share the crane's parts.
    int right = 0, built = 0;
    EXPECT_TRUE(rc::test::footprintFlatOver(checkers, "checkers built and dropped",
                                            [&]
                                            {
                                                rc::RobotModelConstPtr robot = plant.robot;
                                                if (built++ % 2 == 1)
                                                {
                                                    auto renamed = std::make_shared<rc::RobotModel>(*plant.robot);
                                                    renamed->name += " " + std::to_string(built);
                                                    robot = renamed;
                                                }
                                                const rc::Checker checker(robot, plant.scene, options);
                                                right += !checker.isValid(boomInRack);
                                            }));
    EXPECT_EQ(right, checkers);
}
