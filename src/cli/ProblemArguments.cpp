#include "Commands.h"

namespace rastercheck::cli
{
void ProblemArguments::addTo(CLI::App &command)
{
    command.add_option("problem", cfgPath, "OMPL.app problem (.cfg)");
    command.add_option("--robot", urdfPath, "robot URDF");
    command.add_option("--srdf", srdfPath, "SRDF with disable_collisions pairs");
    command.add_option("--scene", scenePath, "MoveIt scene YAML or a mesh file (one object per node)");
    command.add_option("--package-path", packagePaths, "folder searched for package:// URIs (repeatable)");
    command.add_flag("--visual-fallback", visualFallback, "use visual geometry for links without collision geometry");
}

ProblemSource ProblemArguments::source() const
{
    ProblemSource source;
    source.cfgPath = cfgPath;
    source.urdfPath = urdfPath;
    source.srdfPath = srdfPath;
    source.scenePath = scenePath;
    source.urdfOptions.packagePaths = packagePaths;
    source.urdfOptions.visualWhenNoCollision = visualFallback;
    return source;
}
}  // namespace rastercheck::cli
