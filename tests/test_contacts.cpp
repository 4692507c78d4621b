// Checker::contacts: every colliding pair of a state, each with a triangle the component's surface
// really crosses; empty exactly when the oracle finds the state free.
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "Reference.h"
#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/geometry/TriangleTests.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;

namespace
{
using rastercheck::test::plant;

// The crane slewed to face the pipe rack (+y), boom raised, hook drawn up: free. Luffed down to
// 0.3 rad its boom goes through bent 06 of the rack and the pipes on it (tests/browser too).
const std::vector<double> kFree = {0, 0, 0, 1.570796326795, 0.834431313317, 5, 1};
const std::vector<double> kBoomInRack = {0, 0, 0, 1.570796326795, 0.3, 5, 1};

using Triangle = std::array<Eigen::Vector3d, 3>;

std::vector<Triangle> worldTriangles(const rc::Mesh &mesh, const Eigen::Isometry3d &pose)
{
    std::vector<Triangle> triangles;
    for (const rc::Mesh::Triangle &t : mesh.triangles)
        triangles.push_back({pose * mesh.vertices[t[0]], pose * mesh.vertices[t[1]], pose * mesh.vertices[t[2]]});
    return triangles;
}

bool crosses(const Triangle &a, const Triangle &b)
{
    return rc::trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
}

bool crossesAny(const Triangle &triangle, const std::vector<Triangle> &others)
{
    for (const Triangle &other : others)
        if (crosses(triangle, other))
            return true;
    return false;
}

/** \brief Every (component, object) pair whose surfaces cross, by testing all their triangle pairs:
    an oracle that shares nothing with the checker but the triangle test. */
std::set<std::pair<int, int>> crossingPairsByBruteForce(const rc::Problem &problem, const std::vector<double> &q)
{
    const rc::RobotModel &robot = *problem.robot;
    rc::RobotData data(robot);
    rc::forwardKinematics(robot, data, q);
    std::set<std::pair<int, int>> pairs;
    for (std::size_t c = 0; c < robot.numComponents(); ++c)
    {
        const std::vector<Triangle> component =
            worldTriangles(robot.components[c].mesh, data.oMl[static_cast<std::size_t>(robot.components[c].link)]);
        for (std::size_t o = 0; o < problem.scene->numObjects(); ++o)
            for (const Triangle &t : worldTriangles(problem.scene->objects[o].mesh, Eigen::Isometry3d::Identity()))
                if (crossesAny(t, component))
                {
                    pairs.insert({static_cast<int>(c), static_cast<int>(o)});
                    break;
                }
    }
    return pairs;
}
}  // namespace

TEST(Contacts, FreeStateHasNone)
{
    const rc::Checker checker(plant().robot, plant().scene);
    EXPECT_TRUE(checker.isValid(kFree));
    EXPECT_TRUE(checker.contacts(kFree.data()).empty());
}

TEST(Contacts, BoomInThePipeRackListsEveryCrossingPairWithACrossedTriangle)
{
    const rc::Problem &problem = plant();
    const rc::Checker checker(problem.robot, problem.scene);
    const std::vector<rc::Contact> contacts = checker.contacts(kBoomInRack.data());
    ASSERT_FALSE(checker.isValid(kBoomInRack));

    std::set<std::pair<int, int>> listed;
    rc::RobotData data(*problem.robot);
    rc::forwardKinematics(*problem.robot, data, kBoomInRack);
    for (const rc::Contact &contact : contacts)
    {
        ASSERT_EQ(contact.kind, rc::Contact::Kind::Environment) << checker.describe(contact);
        EXPECT_TRUE(listed.insert({contact.component, contact.object}).second) << "pair listed twice";
        // The named triangle of the object is crossed by the component's surface.
        const rc::Component &component = problem.robot->components[static_cast<std::size_t>(contact.component)];
        const rc::SceneObject &object = problem.scene->objects[static_cast<std::size_t>(contact.object)];
        ASSERT_GE(contact.triangle, 0) << checker.describe(contact);
        ASSERT_LT(static_cast<std::size_t>(contact.triangle), object.mesh.numTriangles());
        const Triangle hit = worldTriangles(object.mesh, Eigen::Isometry3d::Identity())[contact.triangle];
        EXPECT_TRUE(crossesAny(hit, worldTriangles(component.mesh, data.oMl[static_cast<std::size_t>(component.link)])))
            << checker.describe(contact);
        // The point lies on that triangle's plane, within the triangle's reach.
        const Eigen::Vector3d normal = (hit[1] - hit[0]).cross(hit[2] - hit[0]).normalized();
        EXPECT_NEAR(normal.dot(contact.position - hit[0]), 0.0, 1e-6) << checker.describe(contact);
    }
    // Known answer: the boom's three sections against two members of bent 06 and pipes 5 to 7.
    EXPECT_EQ(contacts.size(), 12u);
    std::set<std::string> components, objects;
    for (const rc::Contact &contact : contacts)
    {
        components.insert(problem.robot->components[static_cast<std::size_t>(contact.component)].name);
        objects.insert(problem.scene->objects[static_cast<std::size_t>(contact.object)].name);
    }
    EXPECT_EQ(components, (std::set<std::string>{"boom_section_1", "boom_section_2", "boom_section_3"}));
    EXPECT_EQ(objects,
              (std::set<std::string>{"pipe_rack_bent_06/0", "pipe_rack_bent_06/3", "pipe_5", "pipe_6", "pipe_7"}));
    // Every pair whose triangles cross is listed, and nothing else (no pair here is a containment).
    EXPECT_EQ(listed, crossingPairsByBruteForce(problem, kBoomInRack));
}

TEST(Contacts, OutOfBoundsAndNotFiniteStatesGiveOneOutOfBoundsEntry)
{
    const rc::Checker checker(plant().robot, plant().scene);
    std::vector<double> tooSteep = kFree;
    tooSteep[4] = 2.0;  // luff above its 1.396 rad limit
    std::vector<double> notFinite = kFree;
    notFinite[3] = std::numeric_limits<double>::quiet_NaN();
    rastercheck::test::LogCapture log;  // the NaN is named in one warning
    for (const std::vector<double> &q : {tooSteep, notFinite})
    {
        const std::vector<rc::Contact> contacts = checker.contacts(q.data());
        ASSERT_EQ(contacts.size(), 1u);
        EXPECT_EQ(contacts[0].kind, rc::Contact::Kind::OutOfBounds);
    }
}

TEST(Contacts, RequestChoosesThePairsAndThePaddingWidensThem)
{
    const rc::Checker checker(plant().robot, plant().scene);
    rc::CollisionRequest noEnvironment;
    noEnvironment.checkEnvironment = false;
    EXPECT_TRUE(checker.contacts(kBoomInRack.data(), noEnvironment).empty());
    // Every component of the crane is within 50 m of some object of the plant.
    rc::CollisionRequest padded;
    padded.padding = 50.0;
    const std::vector<rc::Contact> contacts = checker.contacts(kFree.data(), padded);
    EXPECT_FALSE(checker.isValid(kFree, padded));
    EXPECT_GE(contacts.size(), plant().robot->numComponents());
}

TEST(Contacts, EmptyExactlyWhenTheOracleFindsTheStateFree)
{
    // The crane, and the Panda among MotionBenchMaker's shelves when the shared data is there.
    std::vector<rc::Problem> problems = {plant()};
    const std::string data = rastercheck::test::sharedData();
    if (!data.empty())
        problems.push_back(rastercheck::test::pandaProblem(data, "bookshelf_small"));
    else
        std::cout << "[ SKIPPED  ] the Panda part: no shared data (RASTERCHECK_DATA or ../shared/data)\n";
    for (const rc::Problem &problem : problems)
    {
        const rc::Checker checker(problem.robot, problem.scene);
        const rc::RobotModel &robot = *problem.robot;
        std::mt19937 random(21);
        int colliding = 0;
        // 150 states: a second in a Release build, half a minute under AddressSanitizer (the oracle
        // tests every pair with no cull).
        constexpr int kStates = 150;
        for (int i = 0; i < kStates; ++i)
        {
            std::vector<double> q(robot.numCoordinates());
            for (std::size_t k = 0; k < q.size(); ++k)
                q[k] = std::uniform_real_distribution<double>(robot.lowerBounds[k], robot.upperBounds[k])(random);
            const bool collides = rastercheck::test::bruteForceCollides(checker.collisionModel(), q.data(), 0.0);
            const std::vector<rc::Contact> contacts = checker.contacts(q.data());
            ASSERT_EQ(!contacts.empty(), collides) << robot.name << " state " << i;
            ASSERT_EQ(checker.isValid(q), contacts.empty()) << robot.name << " state " << i;
            colliding += collides ? 1 : 0;
        }
        // Both kinds of state were met.
        EXPECT_GT(colliding, kStates / 20) << robot.name;
        EXPECT_LT(colliding, kStates - kStates / 20) << robot.name;
    }
}
