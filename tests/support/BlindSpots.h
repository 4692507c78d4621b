#pragma once

#include <string>
#include <vector>

#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck::test
{
/** \brief A scene built to hit one blind spot of image-space collision detection (DESIGN.md), with
    a free-flying box robot and states concentrated where the answer is hard. */
struct BlindSpotSuite
{
    std::string name;
    RobotModelConstPtr robot;
    SceneConstPtr scene;
    std::vector<double> states;  // n x 7 (x y z qx qy qz qw)
    std::size_t numStates() const { return states.size() / 7; }
};

/** \brief The four suites: "thin plate" (a 0.2 mm plate, thinner than any pixel), "parallel walls"
    (axis-aligned walls and an axis-aligned robot, faces parallel to every ray), "buried" (the robot
    wholly inside or around an obstacle, surfaces apart) and "grazing" (penetrations and gaps of
    1e-5 to 1e-3 m). \a statesPerSuite states each, fixed seed. */
std::vector<BlindSpotSuite> blindSpotSuites(std::size_t statesPerSuite, unsigned seed = 1);

/** \brief \a suite moved by \a offset: scene, robot bounds and states (a plant in site coordinates,
    where a float resolves centimetres). */
BlindSpotSuite movedBy(const BlindSpotSuite &suite, const Eigen::Vector3d &offset);
}  // namespace rastercheck::test
