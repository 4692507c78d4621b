// rastercheck render: pictures of a problem and a path (top and side views) and the raster image of
// the first colliding state (the paper's Fig. 6).
#include <filesystem>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/StatesCsv.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateMapping.h"
#include "render/RasterPicture.h"
#include "render/SitePicture.h"

namespace rastercheck::cli
{
namespace
{
struct RenderOptions
{
    ProblemArguments problem;
    std::string statesPath;
    std::string requestPath;
    std::string outDir;
    std::string view = "all";
    std::string trackedLink;
    CheckingArguments checking;
    int interpolate = 0;
    int ghosts = 6;
    double pixel = 0.0;
};

/** \brief \a rows states with \a between states inserted linearly between consecutive ones. */
std::vector<double> interpolate(const std::vector<double> &states, std::size_t dof, int between)
{
    const std::size_t rows = states.size() / dof;
    if (between <= 0 || rows < 2)
        return states;
    std::vector<double> dense;
    dense.reserve((rows - 1) * static_cast<std::size_t>(between + 1) * dof + dof);
    for (std::size_t r = 0; r + 1 < rows; ++r)
        for (int k = 0; k <= between; ++k)
        {
            const double t = static_cast<double>(k) / (between + 1);
            for (std::size_t d = 0; d < dof; ++d)
                dense.push_back((1 - t) * states[r * dof + d] + t * states[(r + 1) * dof + d]);
        }
    dense.insert(dense.end(), states.end() - static_cast<std::ptrdiff_t>(dof), states.end());
    return dense;
}

int runRender(const RenderOptions &options)
{
    if (options.statesPath.empty() == options.requestPath.empty())
        throw ConfigurationError("give the states as exactly one of --states CSV or --request YAML");
    const Problem problem = loadProblem(options.problem.source());
    const RobotModel &robot = *problem.robot;
    const std::size_t dof = robot.numCoordinates();

    std::vector<double> states;
    std::string source;
    if (!options.statesPath.empty())
    {
        states = readStatesCsv(options.statesPath, robot.coordinateNames).values;
        source = options.statesPath;
    }
    else
    {
        // The configurations `plan` and `view` make of the request (StateMapping: quaternions, mimic
        // joints, coordinates the request leaves out at their neutral values).
        const auto [start, goal] =
            ompl::startAndGoal(ompl::StateMapping(problem.robot), loadMoveItRequest(options.requestPath));
        states = start;
        states.insert(states.end(), goal.begin(), goal.end());
        source = options.requestPath;
    }
    if (states.empty())
        throw InputError(source, "", "no states to draw");
    states = interpolate(states, dof, options.interpolate);
    const std::size_t rows = states.size() / dof;

    std::filesystem::create_directories(options.outDir);
    const bool all = options.view == "all";
    const std::string subtitle =
        robot.name + " in " +
        std::filesystem::path(options.problem.scenePath.empty() ? options.problem.cfgPath : options.problem.scenePath)
            .filename()
            .string() +
        ", " + std::to_string(rows) + " state" + (rows == 1 ? "" : "s") + " from " +
        std::filesystem::path(source).filename().string();

    int colliding = -1;
    if (all || options.view == "raster")
    {
        const Checker checker(problem.robot, problem.scene);
        CollisionRequest request = options.checking.request();
        request.pixelSize = options.pixel;
        std::vector<std::uint8_t> valid(rows);
        std::vector<Contact> contacts(rows);
        checker.check(states.data(), rows, valid.data(), request, contacts.data());
        for (std::size_t r = 0; r < rows && colliding < 0; ++r)
            if (!valid[r])
                colliding = static_cast<int>(r);
        if (colliding < 0)
            std::cout << "no state collides (" << rows << " checked, mode " << options.checking.mode
                      << "): no raster picture\n";
        else
        {
            const Contact &contact = contacts[static_cast<std::size_t>(colliding)];
            std::cout << "first colliding state: row " << colliding << " of " << rows << ": "
                      << checker.describe(contact) << '\n';
            RasterImage image;
            if (!checker.rasterImage(states.data() + static_cast<std::size_t>(colliding) * dof, contact, request,
                                     image))
                std::cout << "no raster picture: the contact names no pair of solids\n";
            else
            {
                render::RasterPictureOptions pictureOptions;
                pictureOptions.subtitle = "row " + std::to_string(colliding) + ": " + checker.describe(contact);
                pictureOptions.componentLabel = robot.components[static_cast<std::size_t>(contact.component)].name;
                pictureOptions.objectLabel =
                    contact.kind == Contact::Kind::Environment
                        ? problem.scene->objects[static_cast<std::size_t>(contact.object)].name
                        : robot.components[static_cast<std::size_t>(contact.otherComponent)].name;
                const std::string path = (std::filesystem::path(options.outDir) / "raster.png").string();
                const render::RasterPictureLayout layout = render::writeRasterPicture(path, image, pictureOptions);
                std::cout << "wrote " << path << " (" << layout.width << " x " << layout.height << ")\n";
            }
        }
    }
    for (const char *view : {"top", "side"})
    {
        if (!all && options.view != view)
            continue;
        render::SitePictureOptions pictureOptions;
        pictureOptions.view = render::parseSiteView(view);
        pictureOptions.subtitle = subtitle;
        pictureOptions.trackedLink = options.trackedLink;
        pictureOptions.ghosts = options.ghosts;
        pictureOptions.collidingState = colliding;
        const std::string path = (std::filesystem::path(options.outDir) / (std::string(view) + ".png")).string();
        const render::SitePictureInfo info =
            render::writeSitePicture(path, robot, *problem.scene, states, pictureOptions);
        std::cout << "wrote " << path << " (" << info.width << " x " << info.height << ")\n";
    }
    return 0;
}
}  // namespace

void addRenderCommand(CLI::App &app)
{
    auto options = std::make_shared<RenderOptions>();
    CLI::App *command = app.add_subcommand(
        "render", "Draw a problem and a path (top and side views) and the raster image of the first colliding state");
    options->problem.addTo(*command);
    CLI::Option *states = command->add_option("--states", options->statesPath,
                                              "CSV of states (header: coordinate names); the rows in order are a path");
    CLI::Option *request = command->add_option("--request", options->requestPath,
                                               "MoveIt MotionPlanRequest YAML: its start and goal states");
    states->excludes(request);
    command->add_option("--out-dir", options->outDir, "folder for top.png, side.png and raster.png")->required();
    command->add_option("--view", options->view, "top, side, raster or all (default)")
        ->check(CLI::IsMember({"top", "side", "raster", "all"}));
    command
        ->add_option("--interpolate", options->interpolate,
                     "states inserted linearly between consecutive rows (0 = draw the rows as given)")
        ->check(CLI::NonNegativeNumber);
    command->add_option("--track", options->trackedLink, "link whose path is drawn (default: the last link)");
    command->add_option("--ghosts", options->ghosts, "path states drawn as grey silhouettes (default 6)")
        ->check(CLI::NonNegativeNumber);
    options->checking.addModeAndPadding(*command, "how states are checked for the raster view");
    command->add_option("--pixel", options->pixel, "raster pixel size in scene units (0 = automatic)")
        ->check(CLI::NonNegativeNumber);
    command->callback([options]() { throw CommandResult{runRender(*options)}; });
}
}  // namespace rastercheck::cli
