// The rastercheck command line: one binary, one subcommand per job.
#include <iostream>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "rastercheck/BuildConfig.h"
#include "rastercheck/core/Error.h"

int main(int argc, char **argv)
{
    CLI::App app{"rastercheck: batched collision checking for motion planning (version " RASTERCHECK_VERSION ")"};
    app.require_subcommand(1);
    rastercheck::cli::addInfoCommand(app);
    rastercheck::cli::addCheckCommand(app);
    rastercheck::cli::addPlanCommand(app);
    rastercheck::cli::addRenderCommand(app);
    rastercheck::cli::addViewCommand(app);
    rastercheck::cli::addSweepCommand(app);
    try
    {
        app.parse(argc, argv);
    }
    catch (const CLI::ParseError &e)
    {
        return app.exit(e);
    }
    catch (const rastercheck::cli::CommandResult &result)
    {
        return result.status;
    }
    catch (const rastercheck::Error &e)
    {
        std::cerr << "rastercheck: error: " << e.what() << '\n';
        return 1;
    }
    catch (const std::exception &e)
    {
        // Anything a library below us throws is still reported, never an abort.
        std::cerr << "rastercheck: error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
