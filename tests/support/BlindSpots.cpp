#include "BlindSpots.h"

#include <cmath>
#include <random>

#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/model/RigidBody.h"

namespace rastercheck::test
{
namespace
{
Mesh boxAt(const Eigen::Vector3d &size, const Eigen::Vector3d &center)
{
    Mesh mesh = makeBox(size);
    mesh.transform(Eigen::Isometry3d(Eigen::Translation3d(center)));
    return mesh;
}

RobotModelConstPtr boxRobot(const Eigen::Vector3d &size)
{
    Aabb bounds;
    bounds.min = Eigen::Vector3d::Constant(-2);
    bounds.max = Eigen::Vector3d::Constant(2);
    return makeRigidBodyModel("box_robot", makeBox(size), bounds);
}

void pushState(std::vector<double> &states, const Eigen::Vector3d &p, const Eigen::Quaterniond &q)
{
    states.insert(states.end(), {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()});
}

Eigen::Quaterniond randomRotation(std::mt19937_64 &rng)
{
    std::normal_distribution<double> normal;
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    return q.normalized();
}
}  // namespace

std::vector<BlindSpotSuite> blindSpotSuites(std::size_t n, unsigned seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<BlindSpotSuite> suites;

    {  // A 0.2 mm plate: overlaps are always thinner than a pixel in one direction.
        BlindSpotSuite suite{"thin plate", boxRobot({0.1, 0.1, 0.1}), nullptr, {}};
        auto scene = std::make_shared<Scene>();
        scene->addObject("plate", boxAt({0.6, 0.6, 0.0002}, {0, 0, 0}));
        suite.scene = scene;
        for (std::size_t i = 0; i < n; ++i)
            pushState(suite.states, {0.35 * unit(rng), 0.35 * unit(rng), 0.09 * unit(rng)}, randomRotation(rng));
        suites.push_back(std::move(suite));
    }
    {  // Axis-aligned walls and robot: every face is parallel to two of the three ray directions.
        BlindSpotSuite suite{"parallel walls", boxRobot({0.2, 0.05, 0.1}), nullptr, {}};
        auto scene = std::make_shared<Scene>();
        scene->addObject("wall_x", boxAt({0.01, 1.0, 1.0}, {0.3, 0, 0}));
        scene->addObject("wall_y", boxAt({1.0, 0.01, 1.0}, {0, 0.3, 0}));
        scene->addObject("floor", boxAt({1.0, 1.0, 0.01}, {0, 0, -0.3}));
        suite.scene = scene;
        // Each state faces one wall with a gap or overlap of up to 2 mm, away from the other walls.
        const Eigen::Vector3d half(0.1, 0.025, 0.05);
        const Eigen::Quaterniond turned(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
        for (std::size_t i = 0; i < n; ++i)
        {
            const bool isTurned = (i / 3) % 2 == 1;
            const Eigen::Vector3d extent = isTurned ? Eigen::Vector3d(half.y(), half.x(), half.z()) : half;
            const double gap = 0.002 * unit(rng);
            Eigen::Vector3d p(-0.1 + 0.1 * unit(rng), -0.1 + 0.1 * unit(rng), 0.05 + 0.1 * unit(rng));
            switch (i % 3)
            {
                case 0:
                    p.x() = 0.3 - 0.005 - extent.x() - gap;
                    break;
                case 1:
                    p.y() = 0.3 - 0.005 - extent.y() - gap;
                    break;
                default:
                    p.z() = -0.3 + 0.005 + extent.z() + gap;
                    break;
            }
            pushState(suite.states, p, isTurned ? turned : Eigen::Quaterniond::Identity());
        }
        suites.push_back(std::move(suite));
    }
    {  // Buried: the robot inside a big block, or a small block inside a hollow-free robot.
        BlindSpotSuite suite{"buried", boxRobot({0.1, 0.1, 0.1}), nullptr, {}};
        auto scene = std::make_shared<Scene>();
        scene->addObject("block", boxAt({0.5, 0.5, 0.5}, {0, 0, 0}));
        scene->addObject("pebble", boxAt({0.01, 0.01, 0.01}, {1.0, 0, 0}));
        suite.scene = scene;
        for (std::size_t i = 0; i < n; ++i)
        {
            const Eigen::Vector3d center = i % 2 ? Eigen::Vector3d(0.25 * unit(rng), 0.25 * unit(rng), 0.25 * unit(rng))
                                                 : Eigen::Vector3d(1.0 + 0.06 * unit(rng), 0.06 * unit(rng), 0.06 * unit(rng));
            pushState(suite.states, center, randomRotation(rng));
        }
        suites.push_back(std::move(suite));
    }
    {  // Grazing: the robot's bottom face 1e-5..1e-3 m above or below a table top.
        BlindSpotSuite suite{"grazing", boxRobot({0.1, 0.1, 0.1}), nullptr, {}};
        auto scene = std::make_shared<Scene>();
        scene->addObject("table", boxAt({0.8, 0.8, 0.05}, {0, 0, -0.025}));
        suite.scene = scene;
        std::uniform_real_distribution<double> exponent(-5.0, -3.0);
        for (std::size_t i = 0; i < n; ++i)
        {
            const double depth = (i % 2 ? 1.0 : -1.0) * std::pow(10.0, exponent(rng));
            const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.01 * unit(rng), Eigen::Vector3d::UnitX()) *
                                          Eigen::AngleAxisd(M_PI * unit(rng), Eigen::Vector3d::UnitZ()));
            // Lowest corner of the tilted box is about 0.05 * (1 + |tilt| * sqrt 2) below its centre.
            const Eigen::Matrix3d r = tilt.toRotationMatrix();
            double lowest = 0;
            for (int corner = 0; corner < 8; ++corner)
            {
                const Eigen::Vector3d c(corner & 1 ? 0.05 : -0.05, corner & 2 ? 0.05 : -0.05, corner & 4 ? 0.05 : -0.05);
                lowest = std::min(lowest, (r * c).z());
            }
            pushState(suite.states, {0.3 * unit(rng), 0.3 * unit(rng), -lowest + depth}, tilt);
        }
        suites.push_back(std::move(suite));
    }
    return suites;
}

BlindSpotSuite movedBy(const BlindSpotSuite &suite, const Eigen::Vector3d &offset)
{
    auto robot = std::make_shared<RobotModel>(*suite.robot);
    for (int k = 0; k < 3; ++k)
    {
        robot->joints[0].lower[k] += offset[k];
        robot->joints[0].upper[k] += offset[k];
    }
    robot->finalize();
    auto scene = std::make_shared<Scene>();
    for (const SceneObject &object : suite.scene->objects)
    {
        Mesh mesh = object.mesh;
        mesh.transform(Eigen::Isometry3d(Eigen::Translation3d(offset)));
        scene->addObject(object.name, std::move(mesh));
    }
    std::vector<double> states = suite.states;
    for (std::size_t i = 0; i < suite.numStates(); ++i)
        for (int k = 0; k < 3; ++k)
            states[7 * i + k] += offset[k];
    return BlindSpotSuite{suite.name + " at 1e6 m", robot, scene, states};
}
}  // namespace rastercheck::test
