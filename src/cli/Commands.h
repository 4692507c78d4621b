// Registration of the rastercheck subcommands; each lives in its own file.
#pragma once

#include <CLI/CLI.hpp>

namespace rastercheck::cli
{
/** \brief `rastercheck info <urdf | problem.cfg | scene.yaml | request.yaml>`: what the loaders
    make of a file (robot, joints, coordinates, components, allowed pairs; scene objects). */
void addInfoCommand(CLI::App &app);
}  // namespace rastercheck::cli
