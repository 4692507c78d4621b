#include "rastercheck/model/Bounds.h"

#include <cmath>
#include <sstream>

#include "rastercheck/core/Error.h"

namespace rastercheck
{
namespace
{
/** \brief Per coordinate: does it have bounds a configuration must keep (finite, not a continuous
    joint's)? */
std::vector<bool> boundedCoordinates(const RobotModel &robot)
{
    std::vector<bool> bounded(robot.numCoordinates(), false);
    for (std::size_t c = 0; c < bounded.size(); ++c)
        bounded[c] = std::isfinite(robot.lowerBounds[c]) && std::isfinite(robot.upperBounds[c]);
    for (const Joint &joint : robot.joints)
        if (joint.continuous && joint.firstCoordinate >= 0)
            bounded[static_cast<std::size_t>(joint.firstCoordinate)] = false;
    return bounded;
}

double slackAt(const std::vector<double> &slack, std::size_t c)
{
    return c < slack.size() && std::isfinite(slack[c]) ? slack[c] : 0.0;
}
}  // namespace

BoundsFit fitToBounds(const RobotModel &robot, double *q, double tolerance, const std::vector<double> &slackDown,
                      const std::vector<double> &slackUp)
{
    if (!(std::isfinite(tolerance) && tolerance >= 0))
        throw ConfigurationError("the bounds tolerance must be a finite number >= 0");
    BoundsFit fit;
    const std::vector<bool> bounded = boundedCoordinates(robot);
    for (std::size_t c = 0; c < bounded.size(); ++c)
    {
        if (!bounded[c] || !std::isfinite(q[c]))
            continue;
        const bool above = q[c] > robot.upperBounds[c];
        if (!above && !(q[c] < robot.lowerBounds[c]))
            continue;
        const BoundsExcess excess{static_cast<int>(c), q[c], above ? robot.upperBounds[c] : robot.lowerBounds[c]};
        const double allowed = std::max(tolerance, slackAt(above ? slackDown : slackUp, c));
        if (std::abs(q[c] - excess.bound) <= allowed)
        {
            q[c] = excess.bound;
            fit.moved.push_back(excess);
        }
        else if (fit.outside.coordinate < 0)
            fit.outside = excess;
    }
    return fit;
}

std::string describeExcess(const RobotModel &robot, const BoundsExcess &excess)
{
    const bool above = excess.value > excess.bound;
    std::ostringstream text;
    text.precision(10);
    text << "joint '" << robot.coordinateNames.at(static_cast<std::size_t>(excess.coordinate)) << "' at "
         << excess.value;
    text.precision(3);
    text << " is " << std::abs(excess.value - excess.bound);
    text.precision(10);
    text << (above ? " above its upper" : " below its lower") << " bound " << excess.bound;
    return text.str();
}

}  // namespace rastercheck
