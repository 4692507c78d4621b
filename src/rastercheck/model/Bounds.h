#pragma once

#include <string>
#include <vector>

#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
/** \brief Default of how far outside a joint limit a requested start or goal may lie and still be
    moved onto it (joint units: rad or m). MoveIt's start-state bounds adapter uses a small tolerance
    like this, and its goal joint constraints carry their own; a URDF that limits a roll joint to
    +-3.14159 then accepts a request at +-pi (2.65e-6 outside). */
constexpr double kDefaultBoundsTolerance = 1e-4;

/** \brief A coordinate outside its finite bounds. */
struct BoundsExcess
{
    int coordinate = -1;  ///< RobotModel::coordinateNames index
    double value = 0.0;   ///< the coordinate as given
    double bound = 0.0;   ///< the bound it lies beyond (lower or upper)
};

/** \brief What fitToBounds did to a configuration: the coordinates it moved onto a bound, and the
    first coordinate farther outside than allowed (coordinate -1: none). */
struct BoundsFit
{
    std::vector<BoundsExcess> moved;
    BoundsExcess outside;
};

/** \brief Moves every coordinate of \a q (RobotModel order) that lies outside its bounds by at most
    the allowance onto that bound, and reports the first one beyond it, which it leaves as it is.
    The allowance is \a tolerance, or, where larger, \a slackDown[c] for a value above the upper
    bound (how far it may move down) and \a slackUp[c] for one below the lower bound (empty vectors:
    none; a goal joint constraint's tolerance_below and tolerance_above). Continuous joints and
    coordinates without finite bounds are left alone; non-finite values are not bounds questions
    (the checker calls them invalid). Throws ConfigurationError when \a tolerance is negative or not
    finite. */
BoundsFit fitToBounds(const RobotModel &robot, double *q, double tolerance, const std::vector<double> &slackDown = {},
                      const std::vector<double> &slackUp = {});

/** \brief "joint 'name' at VALUE is D above its upper bound B" (below / lower): the words every
    bounds message uses. */
std::string describeExcess(const RobotModel &robot, const BoundsExcess &excess);

}  // namespace rastercheck
