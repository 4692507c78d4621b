// Forward kinematics against poses computed by hand, mimic joints, and the model's derived layout.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/device/Pose.h"
#include "rastercheck/device/SinCos.h"
#include "rastercheck/model/Kinematics.h"

namespace rc = rastercheck;

namespace
{
rc::Joint oneCoordinateJoint(const std::string &name, rc::JointKind kind, int parent, int child,
                             const Eigen::Vector3d &offset, const Eigen::Vector3d &axis, double lo, double hi)
{
    rc::Joint joint;
    joint.name = name;
    joint.kind = kind;
    joint.parentLink = parent;
    joint.childLink = child;
    joint.origin.translation() = offset;
    joint.axis = axis;
    joint.coordinateNames = {name};
    joint.lower = {lo};
    joint.upper = {hi};
    return joint;
}

// base --(revolute z at (0,0,1))--> upper --(prismatic x at (2,0,0))--> fore
//                                         \--(mimic of slide, x2, +0.1)--> twin
rc::RobotModel planarArm()
{
    rc::RobotModel model;
    model.name = "arm";
    model.links = {{"base", -1, -1}, {"upper", -1, -1}, {"fore", -1, -1}, {"twin", -1, -1}};
    model.joints.push_back(oneCoordinateJoint("swing", rc::JointKind::Revolute, 0, 1, {0, 0, 1}, {0, 0, 1}, -3, 3));
    model.joints.push_back(oneCoordinateJoint("slide", rc::JointKind::Prismatic, 1, 2, {2, 0, 0}, {1, 0, 0}, 0, 1));
    rc::Joint twin = oneCoordinateJoint("twin_slide", rc::JointKind::Prismatic, 1, 3, {0, 1, 0}, {1, 0, 0}, 0, 1);
    twin.mimicOf = 1;
    twin.mimicMultiplier = 2.0;
    twin.mimicOffset = 0.1;
    twin.coordinateNames.clear();
    twin.lower.clear();
    twin.upper.clear();
    model.joints.push_back(twin);
    model.finalize();
    return model;
}

/** \brief Distance in units in the last place between two finite doubles. */
std::int64_t ulpsApart(double a, double b)
{
    std::int64_t x = 0, y = 0;
    std::memcpy(&x, &a, sizeof x);
    std::memcpy(&y, &b, sizeof y);
    // Map the sign-magnitude bit patterns onto a line where neighbouring doubles are 1 apart.
    x = x < 0 ? INT64_MIN - x : x;
    y = y < 0 ? INT64_MIN - y : y;
    return x > y ? x - y : y - x;
}
}  // namespace

// The kinematics' sine and cosine are our own (device/SinCos.h) so the CUDA kernels place links
// to the same bits as the CPU; they must still be as good as the C library's.
TEST(Kinematics, SinCosIsWithinOneUlpOfTheCLibrary)
{
    std::mt19937_64 random(3);
    for (double range : {0.8, 7.0, 1000.0, rc::device::kSinCosExactRange})
    {
        std::uniform_real_distribution<double> angles(-range, range);
        std::int64_t worstSine = 0, worstCosine = 0;
        for (int i = 0; i < 200000; ++i)
        {
            const double angle = angles(random);
            double sine = 0, cosine = 0;
            rc::device::sinCos(angle, sine, cosine);
            worstSine = std::max(worstSine, ulpsApart(sine, std::sin(angle)));
            worstCosine = std::max(worstCosine, ulpsApart(cosine, std::cos(angle)));
        }
        EXPECT_LE(worstSine, 1) << "angles within +-" << range;
        EXPECT_LE(worstCosine, 1) << "angles within +-" << range;
    }
    // Quadrant boundaries and odd symmetry, exactly.
    const double quarter = std::acos(-1.0) / 2;
    for (int k = -8; k <= 8; ++k)
    {
        double sine = 0, cosine = 0, sineOfOpposite = 0, cosineOfOpposite = 0;
        rc::device::sinCos(k * quarter, sine, cosine);
        EXPECT_LE(ulpsApart(sine, std::sin(k * quarter)), 1) << k;
        EXPECT_LE(ulpsApart(cosine, std::cos(k * quarter)), 1) << k;
        rc::device::sinCos(-k * quarter, sineOfOpposite, cosineOfOpposite);
        EXPECT_EQ(sineOfOpposite, -sine) << k;
        EXPECT_EQ(cosineOfOpposite, cosine) << k;
    }
    double sine = 0, cosine = 0;
    rc::device::sinCos(0.0, sine, cosine);
    EXPECT_EQ(sine, 0.0);
    EXPECT_EQ(cosine, 1.0);
    // Beyond the exact range: reduced modulo 2 pi first, still a point on the unit circle.
    rc::device::sinCos(1e300, sine, cosine);
    EXPECT_NEAR(sine * sine + cosine * cosine, 1.0, 1e-15);
    rc::device::sinCos(std::nan(""), sine, cosine);
    EXPECT_TRUE(std::isnan(sine) && std::isnan(cosine));
    rc::device::sinCos(-INFINITY, sine, cosine);
    EXPECT_TRUE(std::isnan(sine) && std::isnan(cosine));
}

// A revolute joint about a coordinate axis turns two columns of its origin (device::rotateAbout)
// instead of composing a rotation matrix: the same pose, every axis and sign, within rounding.
TEST(Kinematics, ATurnAboutACoordinateAxisEqualsComposingItsRotation)
{
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const double norm = std::sqrt(0.3 * 0.3 + 0.5 * 0.5 + 0.8 * 0.8);
    const rc::device::Vec3<double> general{0.3 / norm, -0.5 / norm, 0.8 / norm};
    const rc::device::Vec3<double> axes[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0},
                                             {0, 0, 1}, {0, 0, -1}, general};
    for (int trial = 0; trial < 200; ++trial)
    {
        const rc::device::Pose<double> pose =
            rc::device::compose(rc::device::axisAngle(general, 3.0 * unit(random)),
                                rc::device::fromQuaternion(unit(random), unit(random), unit(random), unit(random),
                                                           unit(random), unit(random), 1.0));
        for (const rc::device::Vec3<double> &axis : axes)
        {
            const double angle = 4.0 * unit(random);
            const rc::device::Pose<double> expected = rc::device::compose(pose, rc::device::axisAngle(axis, angle));
            const rc::device::Pose<double> turned = rc::device::rotateAbout(pose, axis, angle);
            for (int k = 0; k < 12; ++k)
                ASSERT_NEAR(turned.m[k], expected.m[k], 1e-14)
                    << "axis (" << axis.x << ", " << axis.y << ", " << axis.z << "), entry " << k;
        }
    }
}

TEST(Kinematics, RevoluteAndPrismaticMatchHandComputedPoses)
{
    const rc::RobotModel model = planarArm();
    ASSERT_EQ(model.numCoordinates(), 2u);
    EXPECT_EQ(model.coordinateNames[0], "swing");
    EXPECT_EQ(model.coordinateNames[1], "slide");
    rc::RobotData data(model);
    rc::forwardKinematics(model, data, std::vector<double>{M_PI / 2, 0.5});

    const int upper = model.linkIndex("upper"), fore = model.linkIndex("fore");
    // Swing by 90 degrees about z: upper's x axis points along world y.
    EXPECT_TRUE(data.oMl[upper].translation().isApprox(Eigen::Vector3d(0, 0, 1)));
    EXPECT_TRUE(data.oMl[upper].linear().col(0).isApprox(Eigen::Vector3d(0, 1, 0)));
    // The fore link sits 2 m along upper's x plus the 0.5 m slide: world (0, 2.5, 1).
    EXPECT_TRUE(data.oMl[fore].translation().isApprox(Eigen::Vector3d(0, 2.5, 1), 1e-12));
}

TEST(Kinematics, MimicJointFollowsItsSource)
{
    const rc::RobotModel model = planarArm();
    rc::RobotData data(model);
    rc::forwardKinematics(model, data, std::vector<double>{0.0, 0.3});
    const int twin = model.linkIndex("twin");
    // twin = 2 * 0.3 + 0.1 = 0.7 along x from (0, 1, 1).
    EXPECT_TRUE(data.oMl[twin].translation().isApprox(Eigen::Vector3d(0.7, 1, 1), 1e-12));
    EXPECT_EQ(model.activeJointNames(), (std::vector<std::string>{"swing", "slide"}));
}

TEST(Kinematics, FloatingJointTakesPositionAndQuaternion)
{
    rc::RobotModel model;
    model.name = "body";
    model.links = {{"world", -1, -1}, {"body", -1, -1}};
    rc::Joint joint;
    joint.name = "free";
    joint.kind = rc::JointKind::Floating;
    joint.parentLink = 0;
    joint.childLink = 1;
    joint.coordinateNames = {"x", "y", "z", "qx", "qy", "qz", "qw"};
    joint.lower = {-10, -10, -10, -1, -1, -1, -1};
    joint.upper = {10, 10, 10, 1, 1, 1, 1};
    model.joints = {joint};
    model.finalize();
    rc::RobotData data(model);
    // 90 degrees about x: (qx, qw) = (sin 45, cos 45).
    const double h = std::sqrt(0.5);
    rc::forwardKinematics(model, data, std::vector<double>{1, 2, 3, h, 0, 0, h});
    EXPECT_TRUE(data.oMl[1].translation().isApprox(Eigen::Vector3d(1, 2, 3)));
    EXPECT_TRUE((data.oMl[1].linear() * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
}

TEST(Kinematics, FinalizeRejectsInvertedBoundsAndCycles)
{
    rc::RobotModel model = planarArm();
    model.joints[0].lower = {1.0};
    model.joints[0].upper = {-1.0};
    EXPECT_THROW(model.finalize(), rc::ConfigurationError);

    rc::RobotModel cyclic;
    cyclic.name = "cyclic";
    cyclic.links = {{"a", -1, -1}, {"b", -1, -1}};
    cyclic.joints = {oneCoordinateJoint("ab", rc::JointKind::Revolute, 0, 1, {0, 0, 0}, {0, 0, 1}, -1, 1),
                     oneCoordinateJoint("ba", rc::JointKind::Revolute, 1, 0, {0, 0, 0}, {0, 0, 1}, -1, 1)};
    EXPECT_THROW(cyclic.finalize(), rc::ConfigurationError);
}
