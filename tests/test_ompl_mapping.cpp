// StateMapping: which OMPL space each joint kind becomes, configuration <-> state round trips
// (real vector, SO2, SE3 with normalised quaternions, compound), held coordinates.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/SE2StateSpace.h>
#include <ompl/base/spaces/SE3StateSpace.h>
#include <ompl/base/spaces/SO2StateSpace.h>
#include <ompl/base/spaces/SO3StateSpace.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/RigidBody.h"
#include "rastercheck/ompl/StateMapping.h"

namespace rc = rastercheck;
namespace rco = rastercheck::ompl;
namespace ob = ::ompl::base;

namespace
{
rc::Joint makeJoint(const std::string &name, rc::JointKind kind, int parent, int child,
                    std::vector<std::string> coordinates, std::vector<double> lower, std::vector<double> upper)
{
    rc::Joint joint;
    joint.name = name;
    joint.kind = kind;
    joint.parentLink = parent;
    joint.childLink = child;
    joint.axis = Eigen::Vector3d::UnitZ();
    joint.coordinateNames = std::move(coordinates);
    joint.lower = std::move(lower);
    joint.upper = std::move(upper);
    return joint;
}

// world -base(planar)-> a -j1(revolute)-> b -wrist(continuous)-> c -slide(prismatic)-> d -free(floating)-> e
rc::RobotModelConstPtr mixedRobot()
{
    auto model = std::make_shared<rc::RobotModel>();
    model->name = "mixed";
    model->links = {{"world", -1, -1}, {"a", -1, -1}, {"b", -1, -1}, {"c", -1, -1}, {"d", -1, -1}, {"e", -1, -1}};
    rc::Joint wrist = makeJoint("wrist", rc::JointKind::Revolute, 2, 3, {"wrist"}, {-M_PI}, {M_PI});
    wrist.continuous = true;
    model->joints = {
        makeJoint("base", rc::JointKind::Planar, 0, 1, {"base/x", "base/y", "base/theta"}, {-3, -4, -M_PI}, {3, 4, M_PI}),
        makeJoint("j1", rc::JointKind::Revolute, 1, 2, {"j1"}, {-2}, {2}),
        wrist,
        makeJoint("slide", rc::JointKind::Prismatic, 3, 4, {"slide"}, {0}, {0.5}),
        makeJoint("free", rc::JointKind::Floating, 4, 5,
                  {"free/x", "free/y", "free/z", "free/qx", "free/qy", "free/qz", "free/qw"},
                  {-5, -6, -7, -1, -1, -1, -1}, {5, 6, 7, 1, 1, 1, 1}),
    };
    model->finalize();
    return model;
}

std::vector<double> randomConfiguration(const rc::RobotModel &robot, std::mt19937_64 &rng)
{
    std::vector<double> q(robot.numCoordinates());
    for (std::size_t k = 0; k < q.size(); ++k)
        q[k] = std::uniform_real_distribution<double>(robot.lowerBounds[k], robot.upperBounds[k])(rng);
    return q;
}

// Makes every floating joint's quaternion unit length (random ones are not).
void normaliseQuaternions(const rc::RobotModel &robot, std::vector<double> &q)
{
    for (const rc::Joint &joint : robot.joints)
        if (joint.kind == rc::JointKind::Floating && joint.firstCoordinate >= 0)
        {
            double *r = q.data() + joint.firstCoordinate + 3;
            const double norm = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
            for (int k = 0; k < 4; ++k)
                r[k] /= norm;
        }
}

// configuration -> state -> configuration is the identity (up to rounding of the normalisation), the
// state satisfies the bounds, and state -> configuration -> state gives an equal state.
void expectRoundTrips(const rco::StateMapping &mapping, int samples)
{
    auto si = std::make_shared<ob::SpaceInformation>(mapping.getStateSpace());
    si->setStateValidityChecker([](const ob::State *) { return true; });
    si->setup();
    std::mt19937_64 rng(3);
    ob::ScopedState<> state(si), back(si);
    for (int i = 0; i < samples; ++i)
    {
        std::vector<double> q = randomConfiguration(mapping.robot(), rng);
        normaliseQuaternions(mapping.robot(), q);
        for (std::size_t c = 0; c < q.size(); ++c)
            if (mapping.isHeld(static_cast<int>(c)))
                q[c] = mapping.baseConfiguration()[c];
        mapping.fromConfiguration(q, state.get());
        EXPECT_TRUE(si->satisfiesBounds(state.get()));
        const std::vector<double> again = mapping.toConfiguration(state.get());
        ASSERT_EQ(again.size(), q.size());
        for (std::size_t c = 0; c < q.size(); ++c)
            EXPECT_NEAR(again[c], q[c], 1e-12) << mapping.robot().coordinateNames[c];

        ob::ScopedState<> sampled(si);
        sampled.random();
        mapping.fromConfiguration(mapping.toConfiguration(sampled.get()), back.get());
        EXPECT_TRUE(si->getStateSpace()->equalStates(sampled.get(), back.get()));
    }
}
}  // namespace

TEST(OmplMapping, ArmJointsShareOneRealVectorSpace)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::RobotModelConstPtr panda = rc::loadUrdf(root + "/mbm/panda/panda.urdf");
    const rco::StateMapping mapping(panda);
    auto space = std::dynamic_pointer_cast<ob::RealVectorStateSpace>(mapping.getStateSpace());
    ASSERT_TRUE(space);
    ASSERT_EQ(space->getDimension(), 7u);
    for (unsigned int k = 0; k < 7; ++k)
    {
        EXPECT_EQ(space->getDimensionName(k), panda->coordinateNames[k]);
        EXPECT_EQ(space->getBounds().low[k], panda->lowerBounds[k]);
        EXPECT_EQ(space->getBounds().high[k], panda->upperBounds[k]);
    }
    std::vector<int> expected{0, 1, 2, 3, 4, 5, 6};
    EXPECT_EQ(mapping.plannedCoordinates(), expected);
    expectRoundTrips(mapping, 50);
    // Exact copies for real coordinates.
    ob::ScopedState<> state(mapping.getStateSpace());
    const std::vector<double> q{0.1, -0.2, 0.3, -1.4, 0.5, 1.6, 0.7};
    mapping.fromConfiguration(q, state.get());
    EXPECT_EQ(mapping.toConfiguration(state.get()), q);
}

TEST(OmplMapping, ContinuousJointIsSO2AndWraps)
{
    auto model = std::make_shared<rc::RobotModel>();
    model->name = "spinner";
    model->links = {{"world", -1, -1}, {"rotor", -1, -1}};
    rc::Joint spin = makeJoint("spin", rc::JointKind::Revolute, 0, 1, {"spin"}, {-M_PI}, {M_PI});
    spin.continuous = true;
    model->joints = {spin};
    model->finalize();
    const rco::StateMapping mapping(model);
    ASSERT_TRUE(std::dynamic_pointer_cast<ob::SO2StateSpace>(mapping.getStateSpace()));
    ob::ScopedState<> state(mapping.getStateSpace());
    mapping.fromConfiguration(std::vector<double>{3.5}, state.get());
    EXPECT_NEAR(state->as<ob::SO2StateSpace::StateType>()->value, 3.5 - 2 * M_PI, 1e-12);
    EXPECT_NEAR(mapping.toConfiguration(state.get())[0], 3.5 - 2 * M_PI, 1e-12);
    mapping.fromConfiguration(std::vector<double>{-7.0}, state.get());
    EXPECT_NEAR(mapping.toConfiguration(state.get())[0], -7.0 + 2 * M_PI, 1e-12);
    expectRoundTrips(mapping, 30);
}

TEST(OmplMapping, FloatingJointIsSE3WithNormalisedQuaternion)
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d(-1, -2, -3);
    bounds.max = Eigen::Vector3d(1, 2, 3);
    const rc::RobotModelConstPtr body = rc::makeRigidBodyModel("cube", rc::makeBox(Eigen::Vector3d::Constant(0.1)), bounds);
    const rco::StateMapping mapping(body);
    auto space = std::dynamic_pointer_cast<ob::SE3StateSpace>(mapping.getStateSpace());
    ASSERT_TRUE(space);
    EXPECT_EQ(space->getBounds().low, (std::vector<double>{-1, -2, -3}));
    EXPECT_EQ(space->getBounds().high, (std::vector<double>{1, 2, 3}));

    ob::ScopedState<ob::SE3StateSpace> state(mapping.getStateSpace());
    // Not unit length: normalised on the way in (OMPL 1.5 asserts unit quaternions).
    mapping.fromConfiguration(std::vector<double>{0.5, -1, 2, 0, 0, 1, 1}, state.get());
    const auto &r = state->rotation();
    EXPECT_NEAR(r.x * r.x + r.y * r.y + r.z * r.z + r.w * r.w, 1.0, 1e-15);
    EXPECT_NEAR(r.z, std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(r.w, std::sqrt(0.5), 1e-15);
    EXPECT_EQ(state->getX(), 0.5);
    EXPECT_EQ(state->getY(), -1.0);
    EXPECT_EQ(state->getZ(), 2.0);
    const std::vector<double> q = mapping.toConfiguration(state.get());
    EXPECT_NEAR(q[5], std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(q[6], std::sqrt(0.5), 1e-15);
    // A zero quaternion becomes the identity rather than an assertion failure.
    mapping.fromConfiguration(std::vector<double>{0, 0, 0, 0, 0, 0, 0}, state.get());
    EXPECT_EQ(state->rotation().w, 1.0);
    expectRoundTrips(mapping, 50);
}

TEST(OmplMapping, PlanarJointIsSE2)
{
    rc::Aabb bounds;
    bounds.min = Eigen::Vector3d(-1, -2, 0);
    bounds.max = Eigen::Vector3d(1, 2, 0);
    const rc::RobotModelConstPtr body =
        rc::makeRigidBodyModel("square", rc::makeBox(Eigen::Vector3d::Constant(0.1)), bounds, true);
    const rco::StateMapping mapping(body);
    ASSERT_TRUE(std::dynamic_pointer_cast<ob::SE2StateSpace>(mapping.getStateSpace()));
    expectRoundTrips(mapping, 30);
}

TEST(OmplMapping, MixedJointsFormACompoundInJointOrder)
{
    const rc::RobotModelConstPtr robot = mixedRobot();
    const rco::StateMapping mapping(robot);
    auto compound = std::dynamic_pointer_cast<ob::CompoundStateSpace>(mapping.getStateSpace());
    ASSERT_TRUE(compound);
    ASSERT_EQ(compound->getSubspaceCount(), 5u);
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SE2StateSpace>(compound->getSubspace(0)));
    EXPECT_EQ(compound->getSubspace(1)->getDimension(), 1u);  // j1
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SO2StateSpace>(compound->getSubspace(2)));
    EXPECT_EQ(compound->getSubspace(3)->getDimension(), 1u);  // slide
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SE3StateSpace>(compound->getSubspace(4)));
    EXPECT_EQ(mapping.plannedCoordinates().size(), robot->numCoordinates());
    expectRoundTrips(mapping, 50);
    // Projection-based planners need a default projection on the compound.
    mapping.getStateSpace()->setup();
    EXPECT_TRUE(mapping.getStateSpace()->hasDefaultProjection());
}

TEST(OmplMapping, HeldCoordinatesAreNotPlanned)
{
    const rc::RobotModelConstPtr robot = mixedRobot();
    rco::StateMappingOptions options;
    options.heldCoordinates = {{"base/x", 1.5}, {"base/y", -2.5}, {"free/qx", 0.0}, {"free/qy", 0.0},
                               {"free/qz", 0.0}, {"free/qw", 1.0}};
    const rco::StateMapping mapping(robot, options);
    auto compound = std::dynamic_pointer_cast<ob::CompoundStateSpace>(mapping.getStateSpace());
    ASSERT_TRUE(compound);
    // theta (SO2), j1 (real), wrist (SO2), slide + free/x y z (real).
    ASSERT_EQ(compound->getSubspaceCount(), 4u);
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SO2StateSpace>(compound->getSubspace(0)));
    EXPECT_EQ(compound->getSubspace(1)->getDimension(), 1u);
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SO2StateSpace>(compound->getSubspace(2)));
    auto tail = std::dynamic_pointer_cast<ob::RealVectorStateSpace>(compound->getSubspace(3));
    ASSERT_TRUE(tail);
    EXPECT_EQ(tail->getDimension(), 4u);
    EXPECT_EQ(tail->getDimensionName(0), "slide");
    EXPECT_EQ(tail->getDimensionName(3), "free/z");
    EXPECT_EQ(mapping.plannedCoordinates(), (std::vector<int>{2, 3, 4, 5, 6, 7, 8}));

    ob::ScopedState<> state(mapping.getStateSpace());
    state.random();
    const std::vector<double> q = mapping.toConfiguration(state.get());
    EXPECT_EQ(q[0], 1.5);
    EXPECT_EQ(q[1], -2.5);
    EXPECT_EQ(q[12], 1.0);
    expectRoundTrips(mapping, 50);

    // Orientation planned, position held: SO3.
    rco::StateMappingOptions rotationOnly;
    rotationOnly.heldCoordinates = {{"free/x", 0}, {"free/y", 0}, {"free/z", 0}};
    const rco::StateMapping spinning(robot, rotationOnly);
    auto last = std::dynamic_pointer_cast<ob::CompoundStateSpace>(spinning.getStateSpace());
    ASSERT_TRUE(last);
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SO3StateSpace>(last->getSubspace(last->getSubspaceCount() - 1)));
    expectRoundTrips(spinning, 30);
}

TEST(OmplMapping, CraneWithHeldBase)
{
    rc::RobotModelPtr crane = rc::loadUrdf(rc::test::sourcePath("robots/crane/crane.urdf"));
    rco::StateMappingOptions options;
    options.heldCoordinates = {{"base_x", 0.25}, {"base_y", -0.5}, {"base_yaw", 0.1}};
    const rco::StateMapping mapping(crane, options);
    auto compound = std::dynamic_pointer_cast<ob::CompoundStateSpace>(mapping.getStateSpace());
    ASSERT_TRUE(compound);
    ASSERT_EQ(compound->getSubspaceCount(), 2u);
    EXPECT_TRUE(std::dynamic_pointer_cast<ob::SO2StateSpace>(compound->getSubspace(0)));  // slew
    EXPECT_EQ(compound->getSubspace(1)->getDimension(), 3u);                                // luff, telescope_1, hoist
    expectRoundTrips(mapping, 30);
    ob::ScopedState<> state(mapping.getStateSpace());
    state.random();
    const std::vector<double> q = mapping.toConfiguration(state.get());
    EXPECT_EQ(q[0], 0.25);
    EXPECT_EQ(q[1], -0.5);
    EXPECT_EQ(q[2], 0.1);
}

TEST(OmplMapping, BadOptionsAreConfigurationErrors)
{
    const rc::RobotModelConstPtr robot = mixedRobot();
    rco::StateMappingOptions unknown;
    unknown.heldCoordinates = {{"elbow", 0.0}};
    EXPECT_THROW(rco::StateMapping(robot, unknown), rc::ConfigurationError);
    rco::StateMappingOptions partial;
    partial.heldCoordinates = {{"free/qw", 1.0}};
    try
    {
        rco::StateMapping mapping(robot, partial);
        ADD_FAILURE() << "a partly held quaternion must be refused";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_NE(std::string(e.what()).find("free"), std::string::npos) << e.what();
    }
    rco::StateMappingOptions everything;
    for (const std::string &name : robot->coordinateNames)
        everything.heldCoordinates[name] = 0.0;
    everything.heldCoordinates["free/qw"] = 1.0;
    EXPECT_THROW(rco::StateMapping(robot, everything), rc::ConfigurationError);
}
