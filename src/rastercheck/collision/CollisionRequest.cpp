#include "rastercheck/collision/CollisionRequest.h"

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
    }
    return "unknown";
}

CollisionMode parseCollisionMode(const std::string &text)
{
    if (text == "safe")
        return CollisionMode::Safe;
    if (text == "raster")
        return CollisionMode::Raster;
    if (text == "exact")
        return CollisionMode::Exact;
    throw ConfigurationError("unknown collision mode '" + text + "' (expected safe, raster or exact)");
}
}  // namespace rastercheck
