// MotionBound: the bounds hold for every vertex (whole robot, per component) and for the distances
// between vertices of two components (per pair) along OMPL's own interpolation (Panda, crane), and
// known answers on small robots.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/base/StateSpace.h>

#include "TestSupport.h"
#include "rastercheck/io/UrdfLoader.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/model/MotionBound.h"
#include "rastercheck/ompl/StateMapping.h"

namespace rc = rastercheck;
namespace ob = ompl::base;

namespace
{
const std::string kBox = "<collision><origin xyz=\"2 0 0\"/><geometry><box size=\"1 1 1\"/></geometry></collision>";

rc::RobotModelPtr robotFrom(const std::string &body)
{
    return rc::loadUrdfString(rc::test::urdfRobot(body), ".");
}

/** \brief A uniform configuration within \a robot's bounds, as a state of \a mapping's space. */
void sampleUniform(const rc::RobotModel &robot, const rc::ompl::StateMapping &mapping, std::mt19937 &rng,
                   ob::State *state)
{
    std::vector<double> q(robot.numCoordinates());
    for (std::size_t i = 0; i < q.size(); ++i)
        q[i] = std::uniform_real_distribution<double>(robot.lowerBounds[i], robot.upperBounds[i])(rng);
    mapping.fromConfiguration(q, state);
}

/** \brief The largest change, from poses \a x to poses \a y, of the distance between a vertex of
    component \a a and one of component \a b (every so many of each, about \a samples, to keep the
    pairs' product small). */
double largestDistanceChange(const rc::RobotModel &robot, std::pair<int, int> pair, const rc::RobotData &x,
                             const rc::RobotData &y, std::size_t samples)
{
    const rc::Component &ca = robot.components[static_cast<std::size_t>(pair.first)];
    const rc::Component &cb = robot.components[static_cast<std::size_t>(pair.second)];
    const auto la = static_cast<std::size_t>(ca.link), lb = static_cast<std::size_t>(cb.link);
    const std::size_t strideA = ca.mesh.vertices.size() / samples + 1, strideB = cb.mesh.vertices.size() / samples + 1;
    double largest = 0.0;
    for (std::size_t i = 0; i < ca.mesh.vertices.size(); i += strideA)
        for (std::size_t j = 0; j < cb.mesh.vertices.size(); j += strideB)
        {
            const Eigen::Vector3d &va = ca.mesh.vertices[i], &vb = cb.mesh.vertices[j];
            const double then = (x.oMl[la] * va - x.oMl[lb] * vb).norm();
            const double now = (y.oMl[la] * va - y.oMl[lb] * vb).norm();
            largest = std::max(largest, std::abs(now - then));
        }
    return largest;
}

/** \brief \a worst: the largest ratio (distance a vertex moved between consecutive samples) / (the bound's share
    of that step) over \a edges random edges of \a robot's planning space, each sampled at \a steps
    + 1 fractions by the space's own interpolate. Fails the test where a vertex moves farther than
    the bound allows, from the edge's start or between samples. */
void measureSweeps(const rc::RobotModelConstPtr &robot, int edges, int steps, double &worst)
{
    const rc::ompl::StateMapping mapping(robot);
    const rc::MotionBound bound(*robot);
    const ob::StateSpacePtr &space = mapping.getStateSpace();
    std::mt19937 rng(7);
    auto sample = [&](ob::State *state) { sampleUniform(*robot, mapping, rng, state); };
    ob::ScopedState<> a(space), b(space), s(space);
    rc::RobotData previous(*robot), current(*robot), start(*robot);
    worst = 0.0;
    for (int e = 0; e < edges; ++e)
    {
        sample(a.get());
        sample(b.get());
        const std::vector<double> qa = mapping.toConfiguration(a.get()), qb = mapping.toConfiguration(b.get());
        const double sweep = bound.sweep(qa.data(), qb.data());
        EXPECT_TRUE(std::isfinite(sweep));
        const std::size_t m = robot->numComponents();
        std::vector<std::pair<int, int>> pairs;
        for (int i = 0; i < static_cast<int>(m); ++i)
            for (int j = i + 1; j < static_cast<int>(m); ++j)
                pairs.emplace_back(i, j);
        std::vector<double> componentSweeps(m), pairSweeps(pairs.size());
        bound.sweeps(qa.data(), qb.data(), pairs, componentSweeps.data(), pairSweeps.data());
        rc::forwardKinematics(*robot, start, qa);
        previous = start;
        for (int k = 1; k <= steps; ++k)
        {
            const double t = static_cast<double>(k) / steps;
            space->interpolate(a.get(), b.get(), t, s.get());
            rc::forwardKinematics(*robot, current, mapping.toConfiguration(s.get()));
            auto slack = [](double bound) { return bound * (1 + 1e-9) + 1e-12; };
            for (std::size_t ci = 0; ci < m; ++ci)
            {
                const rc::Component &c = robot->components[ci];
                for (const Eigen::Vector3d &v : c.mesh.vertices)
                {
                    const auto l = static_cast<std::size_t>(c.link);
                    const Eigen::Vector3d x = current.oMl[l] * v;
                    const double step = (x - previous.oMl[l] * v).norm();
                    const double fromStart = (x - start.oMl[l] * v).norm();
                    ASSERT_LE(step, slack(sweep / steps)) << c.name << " edge " << e << " step " << k;
                    ASSERT_LE(fromStart, slack(componentSweeps[ci] * t)) << c.name << " edge " << e << " step " << k;
                    ASSERT_LE(componentSweeps[ci], sweep);
                    worst = std::max(worst, step / (sweep / steps));
                }
            }
            // Distances between points of two components change by at most the pair's sweep (a
            // sample of vertices of each, to keep the pairs' product small).
            for (std::size_t p = 0; p < pairs.size(); ++p)
                ASSERT_LE(largestDistanceChange(*robot, pairs[p], start, current, 12), slack(pairSweeps[p] * t))
                    << robot->components[static_cast<std::size_t>(pairs[p].first)].name << " / "
                    << robot->components[static_cast<std::size_t>(pairs[p].second)].name << " edge " << e << " step "
                    << k;
            std::swap(previous, current);
        }
    }
}
/** \brief MotionBound::sweeps about a reference: over \a edges random edges of \a robot's planning
    space, a random span of each ([f - h, f + h] within the edge; half of them a whole edge about
    its middle), the sweeps measured about f's link poses, and \a steps + 1 samples of the span by
    the space's own interpolate. Fails the test where a vertex moves, or the distance between
    vertices of two components changes, between any two samples by more than those sweeps allow, or
    where they exceed the chain's. \a tightened: the mean of span sweep / chain sweep over the
    components and the shorter spans. */
void measureSpanSweeps(const rc::RobotModelConstPtr &robot, int edges, int steps, double &tightened)
{
    const rc::ompl::StateMapping mapping(robot);
    const rc::MotionBound bound(*robot);
    const ob::StateSpacePtr &space = mapping.getStateSpace();
    std::mt19937 rng(11);
    auto sample = [&](ob::State *state) { sampleUniform(*robot, mapping, rng, state); };
    const std::size_t m = robot->numComponents();
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < static_cast<int>(m); ++i)
        for (int j = i + 1; j < static_cast<int>(m); ++j)
            pairs.emplace_back(i, j);
    ob::ScopedState<> a(space), b(space), s(space);
    rc::RobotData reference(*robot);
    std::vector<rc::RobotData> samples(static_cast<std::size_t>(steps) + 1, rc::RobotData(*robot));
    double ratioSum = 0.0;
    int ratios = 0;
    for (int e = 0; e < edges; ++e)
    {
        sample(a.get());
        sample(b.get());
        const std::vector<double> qa = mapping.toConfiguration(a.get()), qb = mapping.toConfiguration(b.get());
        const double h = e % 2 == 0 ? 0.5 : std::uniform_real_distribution<double>(0.005, 0.2)(rng);
        const double f = e % 2 == 0 ? 0.5 : std::uniform_real_distribution<double>(h, 1.0 - h)(rng);
        space->interpolate(a.get(), b.get(), f, s.get());
        rc::forwardKinematics(*robot, reference, mapping.toConfiguration(s.get()));
        std::vector<double> chain(m), chainPairs(pairs.size()), span(m), spanPairs(pairs.size());
        bound.sweeps(qa.data(), qb.data(), pairs, chain.data(), chainPairs.data());
        bound.sweeps(qa.data(), qb.data(), reference, h, pairs, span.data(), spanPairs.data());
        for (std::size_t c = 0; c < m; ++c)
        {
            ASSERT_LE(span[c], chain[c]);
            if (chain[c] > 0.0 && e % 2 == 1)
            {
                ratioSum += span[c] / chain[c];
                ++ratios;
            }
        }
        for (std::size_t p = 0; p < pairs.size(); ++p)
            ASSERT_LE(spanPairs[p], chainPairs[p]);
        for (int k = 0; k <= steps; ++k)
        {
            space->interpolate(a.get(), b.get(), f - h + 2.0 * h * k / steps, s.get());
            rc::forwardKinematics(*robot, samples[static_cast<std::size_t>(k)], mapping.toConfiguration(s.get()));
        }
        auto slack = [](double bound) { return bound * (1 + 1e-9) + 1e-12; };
        for (int i = 0; i <= steps; ++i)
            for (int j = i + 1; j <= steps; j += 3)
            {
                const rc::RobotData &x = samples[static_cast<std::size_t>(i)],
                                    &y = samples[static_cast<std::size_t>(j)];
                const double dt = 2.0 * h * (j - i) / steps;
                for (std::size_t c = 0; c < m; ++c)
                {
                    const rc::Component &component = robot->components[c];
                    const auto l = static_cast<std::size_t>(component.link);
                    for (const Eigen::Vector3d &v : component.mesh.vertices)
                        ASSERT_LE((y.oMl[l] * v - x.oMl[l] * v).norm(), slack(span[c] * dt))
                            << component.name << " edge " << e << " samples " << i << ", " << j;
                }
                for (std::size_t p = 0; p < pairs.size(); ++p)
                    ASSERT_LE(largestDistanceChange(*robot, pairs[p], x, y, 8), slack(spanPairs[p] * dt))
                        << robot->components[static_cast<std::size_t>(pairs[p].first)].name << " / "
                        << robot->components[static_cast<std::size_t>(pairs[p].second)].name << " edge " << e
                        << " samples " << i << ", " << j;
            }
    }
    tightened = ratioSum / std::max(1, ratios);
}
}  // namespace

TEST(MotionBound, SweepsAboutAReferenceHoldOverTheirSpanAndAreTighter)
{
    // A span of a Panda, crane or UR5 edge, its sweeps measured about the link poses at its middle:
    // every vertex and vertex pair within them, and on average tighter than the chain's bound
    // (which sweeps() about the middle never exceeds).
    RASTERCHECK_REQUIRE_DATA(root);
    // The samples per span: their pairs' vertex loops are the test's time (a quarter under the
    // sanitizers: RASTERCHECK_SAMPLE_SCALE); the mean ratios depend on the edges alone.
    const int steps = rc::test::scaledCount(24, "RASTERCHECK_SAMPLE_SCALE");
    double panda = 1.0, crane = 1.0;
    measureSpanSweeps(rc::test::pandaProblem(root, "table_pick").robot, 40, steps, panda);
    measureSpanSweeps(rc::test::plant().robot, 40, steps, crane);
    // The UR5's base and upper arm: a pair whose first joint counts from the base's side.
    double ur5 = 1.0;
    measureSpanSweeps(rc::loadUrdf(root + "/mbm/ur5/ur5.urdf"), 8, steps, ur5);
    std::cout << "span sweep / chain sweep, mean over components: Panda " << panda << ", crane " << crane << ", UR5 "
              << ur5 << "\n";
    EXPECT_LT(panda, 0.95);
    EXPECT_LT(crane, 0.8);
}

TEST(MotionBound, EveryPandaVertexMovesLessThanTheBoundAlongOmplsInterpolation)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem panda = rc::test::pandaProblem(root, "table_pick");
    double worst = 0.0;
    measureSweeps(panda.robot, 40, rc::test::scaledCount(32, "RASTERCHECK_SAMPLE_SCALE"), worst);
    // Not loose beyond use: some vertex moves at least a fifth of what the bound allows.
    EXPECT_GT(worst, 0.2);
    std::cout << "Panda: the fastest vertex step is " << worst << " of the bound's\n";
}

TEST(MotionBound, EveryCraneVertexMovesLessThanTheBound)
{
    double worst = 0.0;
    measureSweeps(rc::test::plant().robot, 40, 32, worst);
    EXPECT_GT(worst, 0.2);
    std::cout << "crane: the fastest vertex step is " << worst << " of the bound's\n";
}

TEST(MotionBound, KnownAnswersOnOneLink)
{
    // A 1 m cube centred 2 m along x from a joint: its farthest vertex is sqrt(2.5^2 + 0.5^2 + 0.5^2) away.
    const double reach = std::sqrt(6.75);
    for (const std::string type : {"revolute", "continuous", "prismatic"})
    {
        const auto robot = robotFrom(
            rc::test::urdfLink("base") + rc::test::urdfLink("arm", kBox) +
            rc::test::urdfJoint("j", type, "base", "arm",
                                "<axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>"));
        const rc::MotionBound bound(*robot);
        ASSERT_EQ(bound.jointReach().size(), 1u);
        EXPECT_NEAR(bound.jointReach()[0], reach, 1e-12) << type;
        const double qa[] = {0.25}, qb[] = {0.35};
        const double expected = type == "prismatic" ? 0.1 : 0.1 * reach;  // a slide moves every point alike
        EXPECT_NEAR(bound.sweep(qa, qb), expected, 1e-12) << type;
        EXPECT_NEAR(bound.sweep(qb, qa), expected, 1e-12) << type;
        EXPECT_EQ(bound.sweep(qa, qa), 0.0) << type;
        const double nan[] = {std::numeric_limits<double>::quiet_NaN()};
        EXPECT_EQ(bound.sweep(qa, nan), std::numeric_limits<double>::infinity()) << type;
    }
    // A continuous joint turns the short way across +-pi: 3.0 -> -3.0 is 2 pi - 6 rad.
    const auto wheel = robotFrom(rc::test::urdfLink("base") + rc::test::urdfLink("arm", kBox) +
                                 rc::test::urdfJoint("j", "continuous", "base", "arm", "<axis xyz=\"0 0 1\"/>"));
    const double from[] = {3.0}, to[] = {-3.0};
    EXPECT_NEAR(rc::MotionBound(*wheel).sweep(from, to), (2 * M_PI - 6.0) * reach, 1e-12);
}

TEST(MotionBound, APairsJointCountsFromTheNearerSide)
{
    // A 0.2 m cube on the base around the joint's centre and the 1 m cube 2 m out on the arm: the
    // joint turns the arm at up to sqrt(6.75) m, but it changes a base point's distance to an arm
    // point no faster than the base point's distance from the joint, at most sqrt(0.03) m.
    const auto robot = robotFrom(
        rc::test::urdfLink("base", "<collision><geometry><box size=\"0.2 0.2 0.2\"/></geometry></collision>") +
        rc::test::urdfLink("arm", kBox) +
        rc::test::urdfJoint("j", "revolute", "base", "arm",
                            "<axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>"));
    ASSERT_EQ(robot->numComponents(), 2u);
    const rc::MotionBound bound(*robot);
    const double qa[] = {0.25}, qb[] = {0.35};
    double components[2], pair = 0.0;
    bound.sweeps(qa, qb, {{0, 1}}, components, &pair);
    EXPECT_EQ(components[0], 0.0);
    EXPECT_NEAR(components[1], 0.1 * std::sqrt(6.75), 1e-12);
    EXPECT_NEAR(pair, 0.1 * std::sqrt(0.03), 1e-12);
    // About a reference: the base's sphere (about its centre, on the axis) holds it within
    // sqrt(0.03) m of the axis too.
    rc::RobotData reference(*robot);
    rc::forwardKinematics(*robot, reference, std::vector<double>{0.3});
    bound.sweeps(qa, qb, reference, 0.5, {{0, 1}}, components, &pair);
    EXPECT_NEAR(pair, 0.1 * std::sqrt(0.03), 1e-12);
    // Every base vertex against every arm vertex, in steps of the edge.
    rc::RobotData x(*robot), y(*robot);
    for (int k = 0; k < 10; ++k)
    {
        rc::forwardKinematics(*robot, x, std::vector<double>{0.25 + 0.01 * k});
        rc::forwardKinematics(*robot, y, std::vector<double>{0.25 + 0.01 * (k + 1)});
        for (const Eigen::Vector3d &va : robot->components[0].mesh.vertices)
            for (const Eigen::Vector3d &vb : robot->components[1].mesh.vertices)
            {
                const double then =
                    (x.oMl[robot->components[0].link] * va - x.oMl[robot->components[1].link] * vb).norm();
                const double now =
                    (y.oMl[robot->components[0].link] * va - y.oMl[robot->components[1].link] * vb).norm();
                EXPECT_LE(std::abs(now - then), 0.1 * pair + 1e-12);
            }
    }
}

TEST(MotionBound, AboutAReferenceTheNearerSideCountsWhatTurnsItWithinTheSpan)
{
    // j1 turns about z, j2 about j1's x axis and carries a 1 m cube 2 m up. The base's small cube
    // sits 0.5 m out on x: on j2's axis halfway along the edge (j1 = 0), 0.35 m from it at the ends
    // (j1 = +-pi/4). So j2 counts from the base's side at its distance from the axis there plus
    // what j1 moves the base about that axis within the span; without the latter, the distances
    // between the two cubes' vertices change faster than the pair sweep allows.
    const std::string limit = "<limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>";
    const auto robot = robotFrom(
        rc::test::urdfLink("base",
                           "<collision><origin xyz=\"0.5 0 0\"/><geometry><box size=\"0.02 0.02 0.02\"/></geometry>"
                           "</collision>") +
        rc::test::urdfLink("middle") +
        rc::test::urdfLink("arm",
                           "<collision><origin xyz=\"0 0 2\"/><geometry><box size=\"1 1 1\"/></geometry>"
                           "</collision>") +
        rc::test::urdfJoint("j1", "revolute", "base", "middle", "<axis xyz=\"0 0 1\"/>" + limit) +
        rc::test::urdfJoint("j2", "revolute", "middle", "arm", "<axis xyz=\"1 0 0\"/>" + limit));
    ASSERT_EQ(robot->numComponents(), 2u);
    const rc::MotionBound bound(*robot);
    const double quarter = 0.25 * M_PI;
    const std::vector<double> qa{-quarter, -0.5}, qb{quarter, 0.5};
    rc::RobotData reference(*robot);
    rc::forwardKinematics(*robot, reference, std::vector<double>{0.0, 0.0});
    double components[2], chainPair = 0.0, pair = 0.0;
    bound.sweeps(qa.data(), qb.data(), {{0, 1}}, components, &chainPair);
    bound.sweeps(qa.data(), qb.data(), reference, 0.5, {{0, 1}}, components, &pair);
    EXPECT_LE(pair, chainPair);
    const int steps = 200;
    rc::RobotData x(*robot), y(*robot);
    double fastest = 0.0;  // the largest change of a vertex pair's distance per unit of the edge
    for (int k = 0; k < steps; ++k)
    {
        auto at = [&](int i)
        {
            const double t = static_cast<double>(i) / steps;
            return std::vector<double>{qa[0] + t * (qb[0] - qa[0]), qa[1] + t * (qb[1] - qa[1])};
        };
        rc::forwardKinematics(*robot, x, at(k));
        rc::forwardKinematics(*robot, y, at(k + 1));
        for (const Eigen::Vector3d &va : robot->components[0].mesh.vertices)
            for (const Eigen::Vector3d &vb : robot->components[1].mesh.vertices)
            {
                const auto la = static_cast<std::size_t>(robot->components[0].link);
                const auto lb = static_cast<std::size_t>(robot->components[1].link);
                const double then = (x.oMl[la] * va - x.oMl[lb] * vb).norm();
                const double now = (y.oMl[la] * va - y.oMl[lb] * vb).norm();
                fastest = std::max(fastest, std::abs(now - then) * steps);
            }
    }
    EXPECT_LE(fastest, pair * (1 + 1e-9));
}

TEST(MotionBound, ReachAddsTheOffsetsAndSlidesBelowAJoint)
{
    // shoulder (revolute at the base) -> 1 m offset -> slide of up to 0.5 m -> the cube: every point of
    // the cube lies within 1 + 0.5 + reach(cube) of the shoulder, whatever the slide does.
    const auto robot = robotFrom(
        rc::test::urdfLink("base") + rc::test::urdfLink("upper") + rc::test::urdfLink("arm", kBox) +
        rc::test::urdfJoint("shoulder", "revolute", "base", "upper",
                            "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>") +
        rc::test::urdfJoint("slide", "prismatic", "upper", "arm",
                            "<origin xyz=\"1 0 0\"/><axis xyz=\"1 0 0\"/><limit lower=\"-0.2\" upper=\"0.5\" "
                            "effort=\"1\" velocity=\"1\"/>"));
    const rc::MotionBound bound(*robot);
    const double cube = std::sqrt(6.75);
    ASSERT_EQ(bound.jointReach().size(), 2u);
    EXPECT_NEAR(bound.jointReach()[robot->jointIndex("shoulder")], 1.5 + cube, 1e-12);
    EXPECT_NEAR(bound.jointReach()[robot->jointIndex("slide")], cube, 1e-12);
    EXPECT_NEAR(bound.size(), 1.5 + cube, 1e-12);
    const double qa[] = {0.0, 0.0}, qb[] = {0.2, 0.3};  // shoulder 0.2 rad, slide 0.3 m
    EXPECT_NEAR(bound.sweep(qa, qb), 0.2 * (1.5 + cube) + 0.3, 1e-12);
}

TEST(MotionBound, AMimicFollowerOfAContinuousJointAcrossPiCannotBeBounded)
{
    const auto robot =
        robotFrom(rc::test::urdfLink("base") + rc::test::urdfLink("wheel") + rc::test::urdfLink("arm", kBox) +
                  rc::test::urdfJoint("drive", "continuous", "base", "wheel", "<axis xyz=\"0 0 1\"/>") +
                  rc::test::urdfJoint("follow", "revolute", "base", "arm",
                                      "<axis xyz=\"0 0 1\"/><limit lower=\"-5\" upper=\"5\" effort=\"1\" "
                                      "velocity=\"1\"/><mimic joint=\"drive\" multiplier=\"0.5\"/>"));
    const rc::MotionBound bound(*robot);
    const double qa[] = {3.0}, qb[] = {-3.0}, qc[] = {2.0};
    // Across pi the drive goes the short way, but its follower jumps from 1.57 to -1.57 rad.
    EXPECT_EQ(bound.sweep(qa, qb), std::numeric_limits<double>::infinity());
    // Elsewhere the follower turns half as far as the drive.
    EXPECT_NEAR(bound.sweep(qa, qc), 0.5 * std::sqrt(6.75), 1e-12);
}

TEST(MotionBound, AHeldUnboundedBaseDoesNotMakeEveryEdgeUnbounded)
{
    // A floating base without bounds under a turning joint: its reach is infinite, but an edge that
    // leaves the turning joint alone and moves the base a known distance is bounded.
    const auto robot = robotFrom(
        rc::test::urdfLink("world") + rc::test::urdfLink("mount") + rc::test::urdfLink("body", kBox) +
        rc::test::urdfJoint("yaw", "revolute", "world", "mount",
                            "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>") +
        rc::test::urdfJoint("base", "floating", "mount", "body"));
    const rc::MotionBound bound(*robot);
    EXPECT_EQ(bound.jointReach()[robot->jointIndex("yaw")], std::numeric_limits<double>::infinity());
    // yaw, x y z qx qy qz qw
    const double qa[] = {0.0, 1, 2, 3, 0, 0, 0, 1};
    const double qb[] = {0.0, 4, 6, 3, 0, 0, std::sin(0.05), std::cos(0.05)};  // 5 m and 0.1 rad about z
    EXPECT_NEAR(bound.sweep(qa, qb), 5.0 + 0.1 * std::sqrt(6.75), 1e-9);
    const double qc[] = {0.1, 1, 2, 3, 0, 0, 0, 1};
    EXPECT_EQ(bound.sweep(qa, qc), std::numeric_limits<double>::infinity());
    // About the links' poses on that edge the yaw turns the box at its distance from the yaw axis:
    // its centre (3, 2, 3) is sqrt(13) from it, its corners sqrt(0.75) from the centre.
    rc::RobotData middle(*robot);
    const double qm[] = {0.05, 1, 2, 3, 0, 0, 0, 1};
    rc::forwardKinematics(*robot, middle, qm);
    double componentSweep = 0.0;
    bound.sweeps(qa, qc, middle, 0.5, {}, &componentSweep, nullptr);
    EXPECT_NEAR(componentSweep, 0.1 * (std::sqrt(13.0) + std::sqrt(0.75)), 1e-9);
}
