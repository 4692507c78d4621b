// rastercheck view: the problem in a browser (three.js), its joints on sliders, collisions and
// contacts shown live, a path played back; served by a local HTTP server (src/view).
#include <filesystem>
#include <iostream>
#include <memory>
#include <tuple>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/StatesCsv.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateMapping.h"
#include "view/ViewServer.h"

namespace rastercheck::cli
{
namespace
{
struct ViewCommandOptions
{
    ProblemArguments problem;
    std::string statesPath;
    std::string requestPath;
    std::string host = "127.0.0.1";
    int port = 8080;
    CheckingArguments checking;
};

bool isLoopback(const std::string &host)
{
    return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

int runView(const ViewCommandOptions &options)
{
    const Problem problem = loadProblem(options.problem.source());
    const RobotModel &robot = *problem.robot;

    view::ViewContent content;
    const std::string &problemPath =
        options.problem.cfgPath.empty() ? options.problem.scenePath : options.problem.cfgPath;
    content.title =
        robot.name + (problemPath.empty() ? "" : " in " + std::filesystem::path(problemPath).filename().string());
    if (problem.omplApp)
    {
        content.start = problem.omplApp->start;
        content.goal = problem.omplApp->goal;
    }
    if (!options.requestPath.empty())
    {
        // Start and goal of a MoveIt request, and the straight line between them as the path (as
        // `rastercheck render --request` draws it) unless --path gives one (a planned path: Plan
        // can plan again from the request's start to its goal).
        std::tie(content.start, content.goal) =
            ompl::startAndGoal(ompl::StateMapping(problem.robot), loadMoveItRequest(options.requestPath));
        content.path = content.start;
        content.path.insert(content.path.end(), content.goal.begin(), content.goal.end());
    }
    if (!options.statesPath.empty())
    {
        content.path = readStatesCsv(options.statesPath, robot.coordinateNames).values;
        if (content.path.empty())
            throw InputError(options.statesPath, "", "no states to play back");
    }

    view::ViewServerOptions serverOptions;
    serverOptions.host = options.host;
    serverOptions.port = options.port;
    // The running binary, not argv[0] (which may be relative or found through PATH).
    serverOptions.webDir = view::findWebDir("/proc/self/exe");
    serverOptions.threeDir = view::findThreeDir();
    serverOptions.request = options.checking.request();
    view::ViewServer server(problem, std::move(content), serverOptions);
    server.bind();
    if (!isLoopback(options.host))
        std::cerr << "rastercheck view: warning: listening on " << options.host
                  << ": anyone who can reach this address can use the viewer and its API\n";
    // The URL is the line a user (or a test) waits for: flushed at once.
    std::cout << "rastercheck view: " << robot.name << ", " << robot.numCoordinates() << " coordinates, "
              << problem.scene->numObjects() << " scene objects, " << server.backendName() << " backend\n"
              << "open " << server.url() << " (Ctrl+C stops the server)" << std::endl;
    if (!server.serve())
        throw ConfigurationError("viewer: the server stopped: could not listen on " + server.url());
    return 0;
}
}  // namespace

void addViewCommand(CLI::App &app)
{
    auto options = std::make_shared<ViewCommandOptions>();
    CLI::App *command = app.add_subcommand(
        "view", "Live 3D viewer in the browser: joints on sliders, collisions and contacts shown as they happen");
    options->problem.addTo(*command);
    command->add_option("--path", options->statesPath,
                        "CSV of states to play back (as `check --states`: header row of coordinate names; "
                        "`plan --path-out` writes them)");
    command->add_option("--request", options->requestPath,
                        "MoveIt MotionPlanRequest YAML: start and goal (Plan's), and the line between them "
                        "unless --path is given");
    command->add_option("--host", options->host, "address to listen on (default 127.0.0.1: this machine only)");
    command->add_option("--port", options->port, "port (default 8080; 0 picks a free one)")
        ->check(CLI::Range(0, 65535));
    options->checking.addModeAndPadding(*command, "how states are checked");
    command->callback([options]() { throw CommandResult{runView(*options)}; });
}
}  // namespace rastercheck::cli
