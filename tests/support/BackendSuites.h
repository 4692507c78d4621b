#pragma once

#include <cstddef>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "rastercheck/collision/Backend.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck::test
{
/** \brief A robot, a scene and states to decide: the accuracy suites the backends are compared on. */
struct StateSuite
{
    std::string name;
    RobotModelConstPtr robot;
    SceneConstPtr scene;
    std::vector<double> states;  // row-major, robot->numCoordinates() per state
    std::size_t numStates() const { return states.size() / robot->numCoordinates(); }
};

/** \brief The blind-spot suites (also moved 1e6 m from the origin), the seven Panda MotionBenchMaker scenes (random states within
    bounds) and the crane in the plant, \a statesPerSuite each (fixed seeds). The Panda and crane
    suites need the shared data; without it only the blind-spot suites come back. */
std::vector<StateSuite> accuracySuites(std::size_t statesPerSuite);

/** \brief \a n uniform random states within \a robot's bounds (continuous joints in [-pi, pi]). */
std::vector<double> randomStates(const RobotModel &robot, std::size_t n, unsigned seed);

/** \brief A random pose: a rotation from a normalised random quaternion, a translation with each
    coordinate uniform in [-spread, spread]. */
Eigen::Isometry3d randomPose(std::mt19937_64 &rng, double spread);

/** \brief Extra paddings (CollisionRequest::pairPadding) for \a rows rows of \a model's pairs: 0, 2 mm,
    1 cm or 5 cm at random (fixed \a seed), the range a certified midpoint's sweeps take on the Panda. */
std::shared_ptr<PairPadding> randomPairPaddings(const CollisionModel &model, std::size_t rows, unsigned seed);

/** \brief How many of a batch each backend called valid. */
struct Agreement
{
    std::size_t valid = 0;
    std::size_t invalid = 0;
};

/** \brief Decides \a states with both backends and expects identical verdicts, and with contacts
    asked, identical first contacts (kind, pair, triangle, position). Returns the reference's counts. */
Agreement expectSameDecisions(const Backend &candidate, const Backend &reference, const CollisionModel &model,
                              const std::vector<double> &states, const CollisionRequest &request,
                              const std::string &label);
}  // namespace rastercheck::test
