#pragma once

#include <cstdlib>
#include <string>
#include <sys/stat.h>

namespace rastercheck
{
/** \brief Root of the shared benchmark data (robots, MotionBenchMaker problems): the environment
    variable RASTERCHECK_DATA when set, else \a fallback (tests and benches pass
    "<source>/../shared/data"). Returns "" when the folder does not exist, so callers can skip. */
inline std::string dataRoot(const std::string &fallback)
{
    const char *fromEnvironment = std::getenv("RASTERCHECK_DATA");
    const std::string root = fromEnvironment && *fromEnvironment ? fromEnvironment : fallback;
    struct stat info;
    return stat(root.c_str(), &info) == 0 && S_ISDIR(info.st_mode) ? root : std::string();
}
}  // namespace rastercheck
