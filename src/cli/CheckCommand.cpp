// rastercheck check: a states file in, one verdict per state out. A stable interface other tools
// drive: the OUT.csv columns and the final summary line's keys only grow, at the end of the row and
// after invalid=.
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>

#include <CLI/CLI.hpp>

#include "Commands.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/model/Bounds.h"
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
    double boundsTolerance = kDefaultBoundsTolerance;
    std::size_t deviceMemoryMiB = 0;
    bool distance = false;
    bool penetration = false;
};

/** \brief Why a state is invalid, for the verdicts file: "bounds:<coordinate>", "environment" or
    "self"; empty for a valid state. */
std::string reason(const Checker &checker, bool valid, const Contact &c)
{
    if (valid)
        return "";
    switch (c.kind)
    {
        case Contact::Kind::OutOfBounds:
            return "bounds:" + (c.coordinate >= 0 ? checker.robot().coordinateNames[c.coordinate] : std::string());
        case Contact::Kind::Environment:
            return "environment";
        case Contact::Kind::SelfCollision:
            return "self";
        case Contact::Kind::None:
            break;
    }
    return "";
}

/** \brief The --distance columns of one state: the distance, the pair and a closest point on each
    side (world frame); empty for a state outside the bounds or with nothing to measure. */
void writeDistance(std::ostream &out, const Checker &checker, const DistanceResult &d)
{
    if (d.kind != Contact::Kind::Environment && d.kind != Contact::Kind::SelfCollision)
    {
        out << ",,,,,,,,";
        return;
    }
    const RobotModel &robot = checker.robot();
    const std::string other = d.kind == Contact::Kind::Environment ? checker.scene().objects[d.object].name
                                                                   : robot.components[d.otherComponent].name;
    const Eigen::Vector3d &a = d.pointOnComponent, &b = d.pointOnOther;
    out << ',' << d.distance << ',' << robot.components[d.component].name << ',' << other << ',' << a.x() << ','
        << a.y() << ',' << a.z() << ',' << b.x() << ',' << b.y() << ',' << b.z();
}

/** \brief The --penetration columns of one state: the named pair's penetration depth (an upper
    bound), its lower bound, whether the two meet (exact), and the way out (unit, world frame);
    empty for a state that does not collide. */
void writePenetration(std::ostream &out, const DistanceResult &d)
{
    const Penetration &p = d.penetration;
    if (!d.colliding() || std::isnan(p.depth))
    {
        out << ",,,,,,";
        return;
    }
    out << ',' << p.depth << ',' << p.lowerBound << ',' << (p.exact ? 1 : 0) << ',' << p.direction.x() << ','
        << p.direction.y() << ',' << p.direction.z();
}

/** \brief The verdicts file; with \a distances (one per state), the --distance columns at the end
    of each row, and with \a penetration the --penetration columns after them. */
void writeVerdicts(std::ostream &out, const Checker &checker, const std::vector<std::uint8_t> &valid,
                   const std::vector<Contact> &contacts, const std::vector<DistanceResult> &distances,
                   bool penetration)
{
    out << "valid,component,object,triangle,x,y,z,reason";
    if (!distances.empty())
        out << ",distance,distance_component,distance_other,ax,ay,az,bx,by,bz";
    if (!distances.empty() && penetration)
        out << ",penetration,penetration_lower,penetration_exact,px,py,pz";
    out << '\n' << std::setprecision(9);
    const RobotModel &robot = checker.robot();
    for (std::size_t i = 0; i < valid.size(); ++i)
    {
        const Contact &c = contacts[i];
        if (valid[i] || c.kind == Contact::Kind::OutOfBounds)
            out << (valid[i] ? 1 : 0) << ",,,,,,," << reason(checker, valid[i], c);
        else
        {
            const std::string other = c.kind == Contact::Kind::Environment ? checker.scene().objects[c.object].name
                                                                           : robot.components[c.otherComponent].name;
            out << "0," << robot.components[c.component].name << ',' << other << ',';
            if (c.triangle >= 0)
                out << c.triangle;
            out << ',' << c.position.x() << ',' << c.position.y() << ',' << c.position.z() << ','
                << reason(checker, false, c);
        }
        if (!distances.empty())
            writeDistance(out, checker, distances[i]);
        if (!distances.empty() && penetration)
            writePenetration(out, distances[i]);
        out << '\n';
    }
}

/** \brief Moves the coordinates of every state that lie within \a tolerance outside a joint limit
    onto it (as `plan` does with a request's start and goal), with one warning per coordinate: the
    number of states moved and the first of them. States farther outside stay invalid. */
void fitStatesToBounds(const RobotModel &robot, StatesTable &states, double tolerance)
{
    std::vector<std::size_t> count(robot.numCoordinates(), 0);
    std::vector<BoundsExcess> first(robot.numCoordinates());
    for (std::size_t i = 0; i < states.rows; ++i)
        for (const BoundsExcess &moved :
             fitToBounds(robot, states.values.data() + i * robot.numCoordinates(), tolerance).moved)
            if (count[static_cast<std::size_t>(moved.coordinate)]++ == 0)
                first[static_cast<std::size_t>(moved.coordinate)] = moved;
    for (std::size_t c = 0; c < count.size(); ++c)
        if (count[c] > 0)
            logWarning(std::to_string(count[c]) + " state(s) within the bounds tolerance of a limit moved onto it; " +
                       "the first: " + describeExcess(robot, first[c]));
}

int runCheck(const CheckOptions &options)
{
    // Before loading anything: CLI11 lets "nan" and "inf" through its range checks.
    if (!(std::isfinite(options.checking.padding) && options.checking.padding >= 0))
        throw ConfigurationError("--padding must be a finite number >= 0");
    if (!(std::isfinite(options.pixel) && options.pixel >= 0))
        throw ConfigurationError("--pixel must be a finite number >= 0");
    if (!(std::isfinite(options.boundsTolerance) && options.boundsTolerance >= 0))
        throw ConfigurationError("--bounds-tolerance must be a finite number >= 0");
    const Problem problem = loadProblem(options.problem.source());
    CheckerOptions checkerOptions = options.checking.checker();
    checkerOptions.deviceMemoryLimit = options.deviceMemoryMiB << 20;
    const Checker checker(problem.robot, problem.scene, checkerOptions);
    CollisionRequest request = options.checking.request();
    request.pixelSize = options.pixel;

    StatesTable states = readStatesCsv(options.statesPath, problem.robot->coordinateNames);
    fitStatesToBounds(*problem.robot, states, options.boundsTolerance);
    std::vector<std::uint8_t> valid(states.rows);
    std::vector<Contact> contacts(states.rows);
    const auto start = std::chrono::steady_clock::now();
    checker.check(states.values.data(), states.rows, valid.data(), request, contacts.data());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::vector<DistanceResult> distances;
    double distanceSeconds = 0.0;
    if (options.distance || options.penetration)
    {
        distances.resize(states.rows);
        DistanceRequest distanceRequest;
        distanceRequest.checkEnvironment = request.checkEnvironment;
        distanceRequest.checkSelfCollision = request.checkSelfCollision;
        distanceRequest.penetration = options.penetration;
        const auto distanceStart = std::chrono::steady_clock::now();
        checker.distance(states.values.data(), states.rows, distanceRequest, distances.data());
        distanceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - distanceStart).count();
    }

    if (!options.outPath.empty())
    {
        std::ofstream out(options.outPath);
        if (!out)
            throw InputError(options.outPath, "", "cannot write the verdicts file");
        writeVerdicts(out, checker, valid, contacts, distances, options.penetration);
    }
    std::size_t invalid = 0, bounds = 0, environment = 0, self = 0;
    for (std::size_t i = 0; i < states.rows; ++i)
    {
        if (valid[i])
            continue;
        ++invalid;
        bounds += contacts[i].kind == Contact::Kind::OutOfBounds;
        environment += contacts[i].kind == Contact::Kind::Environment;
        self += contacts[i].kind == Contact::Kind::SelfCollision;
    }
    std::cerr << "rastercheck: backend " << checker.backendName() << ", mode " << options.checking.mode << '\n';
    std::cout << "states=" << states.rows << " invalid=" << invalid << " bounds=" << bounds
              << " environment=" << environment << " self=" << self << " seconds=" << seconds
              << " states_per_s=" << (seconds > 0 ? static_cast<double>(states.rows) / seconds : 0.0);
    if (!distances.empty())
    {
        double smallest = std::numeric_limits<double>::infinity();
        for (const DistanceResult &d : distances)
            if (d.kind == Contact::Kind::Environment || d.kind == Contact::Kind::SelfCollision)
                smallest = std::min(smallest, d.distance);
        std::cout << " min_distance=" << smallest;
        if (options.penetration)
        {
            double deepest = 0.0;  // the largest proven depth: each colliding state's lower bound
            for (const DistanceResult &d : distances)
                if (d.colliding() && !std::isnan(d.penetration.lowerBound))
                    deepest = std::max(deepest, d.penetration.lowerBound);
            std::cout << " max_penetration=" << deepest;
        }
        std::cout << " distance_seconds=" << distanceSeconds;
    }
    std::cout << std::endl;
    return 0;
}
}  // namespace

void addCheckCommand(CLI::App &app)
{
    auto options = std::make_shared<CheckOptions>();
    CLI::App *command = app.add_subcommand("check", "Decide a batch of states from a CSV file");
    options->problem.addTo(*command);
    command
        ->add_option("--states", options->statesPath,
                     "CSV with a header row: the robot's coordinate names (x,y,z,qx,qy,qz,qw for rigid bodies)")
        ->required();
    command->add_option("--out", options->outPath,
                        "verdicts CSV: valid,component,object,triangle,x,y,z,reason (reason: bounds:COORDINATE, "
                        "environment or self), then the --distance and --penetration columns");
    options->checking.addModeAndPadding(*command, "how the states are checked");
    options->checking.addBackendAndThreads(*command, "worker threads");
    command
        ->add_option("--device-memory", options->deviceMemoryMiB,
                     "MiB of GPU memory the batch buffers may take (0 = half the free memory); a batch that "
                     "needs more runs in several passes, with the same verdicts")
        ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 30));
    command
        ->add_option("--bounds-tolerance", options->boundsTolerance,
                     "a coordinate this far outside a joint limit (rad or m) is moved onto it with a warning "
                     "(default 1e-4); farther outside, the state is invalid (reason bounds)")
        ->check(CLI::NonNegativeNumber);
    command->add_option("--pixel", options->pixel, "raster pixel size in scene units (0 = automatic)")
        ->check(CLI::NonNegativeNumber);
    command->add_flag("--distance", options->distance,
                      "also measure each state's exact distance (robot to scene and non-exempt self pairs, "
                      "not padded): --out gains the columns distance,distance_component,distance_other,ax,ay,az,"
                      "bx,by,bz (a closest point on the component and on the other solid, world frame; 0 and the "
                      "contact for a colliding state), the summary min_distance= and distance_seconds=");
    command->add_flag("--penetration", options->penetration,
                      "--distance, and for each colliding state how deep the pair it names overlaps: --out gains "
                      "penetration,penetration_lower,penetration_exact,px,py,pz (an upper bound on the depth, a "
                      "proven lower bound, 1 when they meet, the way out as a unit vector in the world frame; "
                      "empty for a free state), the summary max_penetration= (the largest lower bound)");
    command->callback([options]() { throw CommandResult{runCheck(*options)}; });
}
}  // namespace rastercheck::cli
