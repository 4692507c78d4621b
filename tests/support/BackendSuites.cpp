#include "BackendSuites.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "BlindSpots.h"
#include "TestSupport.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rastercheck::test
{
std::vector<double> randomStates(const RobotModel &robot, std::size_t n, unsigned seed)
{
    std::mt19937_64 rng(seed);
    const std::size_t dof = robot.numCoordinates();
    std::vector<double> q(n * dof);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < dof; ++k)
        {
            const double lo = std::isfinite(robot.lowerBounds[k]) ? robot.lowerBounds[k] : -M_PI;
            const double hi = std::isfinite(robot.upperBounds[k]) ? robot.upperBounds[k] : M_PI;
            q[i * dof + k] = std::uniform_real_distribution<double>(lo, hi)(rng);
        }
    return q;
}

Eigen::Isometry3d randomPose(std::mt19937_64 &rng, double spread)
{
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Quaterniond rotation(u(rng), u(rng), u(rng), u(rng));
    rotation.normalize();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation.toRotationMatrix();
    pose.translation() = spread * Eigen::Vector3d(u(rng), u(rng), u(rng));
    return pose;
}

std::vector<StateSuite> accuracySuites(std::size_t statesPerSuite)
{
    std::vector<StateSuite> suites;
    for (const BlindSpotSuite &blind : blindSpotSuites(statesPerSuite))
    {
        suites.push_back(StateSuite{blind.name, blind.robot, blind.scene, blind.states});
        const BlindSpotSuite far = movedBy(blind, Eigen::Vector3d(1e6, -2e6, 3e5));
        suites.push_back(StateSuite{far.name, far.robot, far.scene, far.states});
    }
    const std::string root = sharedData();
    if (root.empty())
        return suites;
    RobotModelPtr panda = loadUrdf(root + "/mbm/panda/panda.urdf");
    applySrdf(*panda, loadSrdf(root + "/mbm/panda/panda.srdf"));
    unsigned seed = 1;
    for (const char *scenario : {"bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "cage", "table_pick",
                                 "table_under_pick"})
        suites.push_back(StateSuite{std::string("panda ") + scenario, panda,
                                    loadMoveItScene(root + "/mbm/panda/problems/" + scenario + "_panda/scene0001.yaml"),
                                    randomStates(*panda, statesPerSuite, seed++)});
    const Problem &crane = plant();
    suites.push_back(StateSuite{"crane in the plant", crane.robot, crane.scene,
                                randomStates(*crane.robot, statesPerSuite, seed++)});
    return suites;
}

Agreement expectSameDecisions(const Backend &candidate, const Backend &reference, const CollisionModel &model,
                              const std::vector<double> &states, const CollisionRequest &request,
                              const std::string &label)
{
    const std::size_t n = states.size() / model.robot->numCoordinates();
    std::vector<std::uint8_t> expected(n), actual(n), actualWithContacts(n);
    std::vector<Contact> expectedContacts(n), actualContacts(n);
    reference.check(states.data(), n, expected.data(), expectedContacts.data(), request, 0);
    candidate.check(states.data(), n, actual.data(), nullptr, request, 0);
    candidate.check(states.data(), n, actualWithContacts.data(), actualContacts.data(), request, 0);
    Agreement agreement;
    for (std::size_t i = 0; i < n; ++i)
    {
        (expected[i] ? agreement.valid : agreement.invalid) += 1;
        EXPECT_EQ(actual[i], expected[i]) << label << " state " << i << " (no contacts asked)";
        EXPECT_EQ(actualWithContacts[i], expected[i]) << label << " state " << i;
        const Contact &a = actualContacts[i], &e = expectedContacts[i];
        EXPECT_TRUE(a.kind == e.kind && a.component == e.component && a.object == e.object &&
                    a.otherComponent == e.otherComponent && a.triangle == e.triangle && a.position == e.position)
            << label << " state " << i << ": first contacts differ (kind " << int(a.kind) << "/" << int(e.kind)
            << ", component " << a.component << "/" << e.component << ", object " << a.object << "/" << e.object
            << ", other " << a.otherComponent << "/" << e.otherComponent << ", triangle " << a.triangle << "/"
            << e.triangle << ")";
    }
    return agreement;
}
std::shared_ptr<PairPadding> randomPairPaddings(const CollisionModel &model, std::size_t rows, unsigned seed)
{
    std::mt19937 random(seed);
    const double choices[] = {0.0, 0.002, 0.01, 0.05};
    auto extra = std::make_shared<PairPadding>();
    extra->rows = rows;
    extra->environment.resize(rows * model.numComponents());
    extra->self.resize(rows * model.selfPairs.size());
    for (double &p : extra->environment)
        p = choices[random() % 4];
    for (double &p : extra->self)
        p = choices[random() % 4];
    return extra;
}
}  // namespace rastercheck::test
