// rastercheck check: a states file in, one verdict per state out. A stable interface other tools
// drive: the OUT.csv columns and the final summary line do not change.
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/io/StatesCsv.h"

namespace rastercheck::cli
{
namespace
{
struct CheckOptions
{
    ProblemArguments problem;
    std::string statesPath;
    std::string outPath;
    CheckingArguments checking;
    double pixel = 0.0;
    std::size_t deviceMemoryMiB = 0;
};

void writeVerdicts(std::ostream &out, const Checker &checker, const std::vector<std::uint8_t> &valid,
                   const std::vector<Contact> &contacts)
{
    out << "valid,component,object,triangle,x,y,z\n" << std::setprecision(9);
    const RobotModel &robot = checker.robot();
    for (std::size_t i = 0; i < valid.size(); ++i)
    {
        const Contact &c = contacts[i];
        if (valid[i] || c.kind == Contact::Kind::OutOfBounds)
        {
            out << (valid[i] ? 1 : 0) << ",,,,,,\n";
            continue;
        }
        const std::string other = c.kind == Contact::Kind::Environment ? checker.scene().objects[c.object].name
                                                                       : robot.components[c.otherComponent].name;
        out << "0," << robot.components[c.component].name << ',' << other << ',';
        if (c.triangle >= 0)
            out << c.triangle;
        out << ',' << c.position.x() << ',' << c.position.y() << ',' << c.position.z() << '\n';
    }
}

int runCheck(const CheckOptions &options)
{
    // Before loading anything: CLI11 lets "nan" and "inf" through its range checks.
    if (!(std::isfinite(options.checking.padding) && options.checking.padding >= 0))
        throw ConfigurationError("--padding must be a finite number >= 0");
    if (!(std::isfinite(options.pixel) && options.pixel >= 0))
        throw ConfigurationError("--pixel must be a finite number >= 0");
    const Problem problem = loadProblem(options.problem.source());
    CheckerOptions checkerOptions = options.checking.checker();
    checkerOptions.deviceMemoryLimit = options.deviceMemoryMiB << 20;
    const Checker checker(problem.robot, problem.scene, checkerOptions);
    CollisionRequest request = options.checking.request();
    request.pixelSize = options.pixel;

    const StatesTable states = readStatesCsv(options.statesPath, problem.robot->coordinateNames);
    std::vector<std::uint8_t> valid(states.rows);
    std::vector<Contact> contacts(states.rows);
    const auto start = std::chrono::steady_clock::now();
    checker.check(states.values.data(), states.rows, valid.data(), request, contacts.data());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    if (!options.outPath.empty())
    {
        std::ofstream out(options.outPath);
        if (!out)
            throw InputError(options.outPath, "", "cannot write the verdicts file");
        writeVerdicts(out, checker, valid, contacts);
    }
    std::size_t invalid = 0;
    for (std::uint8_t v : valid)
        invalid += v == 0;
    std::cerr << "rastercheck: backend " << checker.backendName() << ", mode " << options.checking.mode << '\n';
    std::cout << "states=" << states.rows << " invalid=" << invalid << " seconds=" << seconds
              << " states_per_s=" << (seconds > 0 ? static_cast<double>(states.rows) / seconds : 0.0) << std::endl;
    return 0;
}
}  // namespace

void addCheckCommand(CLI::App &app)
{
    auto options = std::make_shared<CheckOptions>();
    CLI::App *command = app.add_subcommand("check", "Decide a batch of states from a CSV file");
    options->problem.addTo(*command);
    command->add_option("--states", options->statesPath,
                        "CSV with a header row: the robot's coordinate names (x,y,z,qx,qy,qz,qw for rigid bodies)")
        ->required();
    command->add_option("--out", options->outPath, "verdicts CSV: valid,component,object,triangle,x,y,z");
    options->checking.addModeAndPadding(*command, "how the states are checked");
    options->checking.addBackendAndThreads(*command, "worker threads");
    command->add_option("--device-memory", options->deviceMemoryMiB,
                        "MiB of GPU memory the batch buffers may take (0 = half the free memory); a batch that "
                        "needs more runs in several passes, with the same verdicts")
        ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 30));
    command->add_option("--pixel", options->pixel, "raster pixel size in scene units (0 = automatic)")
        ->check(CLI::NonNegativeNumber);
    command->callback([options]() { throw CommandResult{runCheck(*options)}; });
}
}  // namespace rastercheck::cli
