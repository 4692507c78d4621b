#include "rastercheck/collision/CollisionRequest.h"

#include <cmath>

#include "rastercheck/core/Error.h"

namespace rastercheck
{
std::string toString(CollisionMode mode)
{
    switch (mode)
    {
        case CollisionMode::Safe:
            return "safe";
        case CollisionMode::Raster:
            return "raster";
        case CollisionMode::Exact:
            return "exact";
        case CollisionMode::Conservative:
            return "conservative";
    }
    return "unknown";
}

std::string toString(Contact::Kind kind)
{
    switch (kind)
    {
        case Contact::Kind::None:
            return "none";
        case Contact::Kind::OutOfBounds:
            return "out_of_bounds";
        case Contact::Kind::Environment:
            return "environment";
        case Contact::Kind::SelfCollision:
            return "self";
    }
    return "none";
}

CollisionMode parseCollisionMode(const std::string &text)
{
    if (text == "safe")
        return CollisionMode::Safe;
    if (text == "raster")
        return CollisionMode::Raster;
    if (text == "exact")
        return CollisionMode::Exact;
    if (text == "conservative")
        return CollisionMode::Conservative;
    throw ConfigurationError("unknown collision mode '" + text + "' (expected safe, raster, exact or conservative)");
}

void validateEntries(const PairPadding &rows, const std::string &name)
{
    for (const std::vector<double> *entries : {&rows.environment, &rows.self})
        for (const double entry : *entries)
            if (!std::isfinite(entry) || entry < 0)
                throw ConfigurationError(name + " entries must be finite and >= 0, got " + std::to_string(entry));
}

void validate(const CollisionRequest &request)
{
    if (!std::isfinite(request.padding) || request.padding < 0)
        throw ConfigurationError("CollisionRequest::padding must be finite and >= 0, got " +
                                 std::to_string(request.padding));
    if (!std::isfinite(request.pixelSize) || request.pixelSize < 0)
        throw ConfigurationError("CollisionRequest::pixelSize must be finite and >= 0 (0 = automatic), got " +
                                 std::to_string(request.pixelSize));
    if (request.pairPadding)
        validateEntries(*request.pairPadding, "CollisionRequest::pairPadding");
    if (request.maxImageSide < 1 || request.maxImageSide > 4096)
        throw ConfigurationError("CollisionRequest::maxImageSide must be in [1, 4096], got " +
                                 std::to_string(request.maxImageSide));
}
}  // namespace rastercheck
