// Plans a crane lift through an industrial plant (the use of Cai et al., "Collision Detection Using
// Axis Aligned Bounding Boxes"): a 50 t crawler crane picks a 4 x 2 x 2 m skid off a trailer and sets
// it down on a foundation behind a pipe rack. RRT-Connect plans through rastercheck's checker, the
// path is re-checked densely by the exact oracle, and the lift is drawn.
//
//   crane_lift [--robots DIR] [--out DIR] [--time SECONDS] [--seed N] [--padding METRES] [--step METRES]
//
// DIR defaults to the source tree's robots/ folder; pictures go to out/crane_lift/.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/PathCheck.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/planners/BatchRRTConnect.h"
#include "render/RasterPicture.h"
#include "render/SitePicture.h"

namespace rc = rastercheck;
namespace og = ::ompl::geometric;

namespace
{
struct Options
{
    std::string robots = RASTERCHECK_ROBOTS_DIR;
    std::string out = "out/crane_lift";
    double time = 20.0;  // planning time limit, seconds
    unsigned seed = 42;
    // The lift's safety clearance: no part of crane or load may come closer than this to the plant,
    // and no two crane parts closer to each other. The skid is picked and set down 0.3 m above its
    // supports, so the clearance must stay below that.
    double padding = 0.25;
    // Largest motion of any point of the crane between two states the planner checks on an edge.
    double step = 0.25;
};

Options parseArguments(int argc, char **argv)
{
    Options options;
    for (int i = 1; i < argc; ++i)
    {
        const std::string flag = argv[i];
        if (flag == "--help" || flag == "-h")
        {
            std::cout << "usage: crane_lift [--robots DIR] [--out DIR] [--time SECONDS] [--seed N] [--padding METRES] "
                         "[--step METRES]\n";
            std::exit(0);
        }
        if (i + 1 >= argc)
            throw rc::ConfigurationError(flag + " needs a value (see --help)");
        const std::string value = argv[++i];
        if (flag == "--robots")
            options.robots = value;
        else if (flag == "--out")
            options.out = value;
        else if (flag == "--time")
            options.time = std::stod(value);
        else if (flag == "--seed")
            options.seed = static_cast<unsigned>(std::stoul(value));
        else if (flag == "--padding")
            options.padding = std::stod(value);
        else if (flag == "--step")
            options.step = std::stod(value);
        else
            throw rc::ConfigurationError("unknown option " + flag + " (see --help)");
    }
    if (!(options.time > 0) || !(options.padding >= 0) || !(options.step > 0))
        throw rc::ConfigurationError("--time and --step must be > 0, --padding >= 0");
    return options;
}

double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double degrees(double radians)
{
    return radians * 180.0 / M_PI;
}

/** \brief \a value, with anything that would print as -0.00 printed as 0.00. */
double tidy(double value)
{
    return std::abs(value) < 0.005 ? 0.0 : value;
}

/** \brief \a path relative to the working directory when that is shorter. */
std::string shortPath(const std::string &path)
{
    const std::string relative = std::filesystem::proximate(path).string();
    return relative.size() < path.size() ? relative : path;
}

/** \brief Scene objects are one per primitive ("pipe_rack_bent_03/2"); the file's objects are the ids. */
std::size_t countIds(const rc::Scene &scene)
{
    std::vector<std::string> ids;
    for (const rc::SceneObject &object : scene.objects)
        ids.push_back(object.name.substr(0, object.name.find('/')));
    std::sort(ids.begin(), ids.end());
    return static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
}

/** \brief Where the crane's coordinates live in a configuration, and the hook's link. */
struct CraneLayout
{
    int slew, luff, telescope, hoist, hook;
    explicit CraneLayout(const rc::RobotModel &crane)
        : slew(crane.coordinateIndex("slew")),
          luff(crane.coordinateIndex("luff")),
          telescope(crane.coordinateIndex("telescope_1")),
          hoist(crane.coordinateIndex("hoist")),
          hook(crane.linkIndex("hook_block"))
    {
        if (slew < 0 || luff < 0 || telescope < 0 || hoist < 0 || hook < 0)
            throw rc::ConfigurationError("robot '" + crane.name + "' is not the crawler crane of robots/crane");
    }
};

Eigen::Vector3d hookPosition(const rc::RobotModel &crane, const CraneLayout &layout, const std::vector<double> &q)
{
    rc::RobotData data(crane);
    rc::forwardKinematics(crane, data, q);
    return data.oMl[static_cast<std::size_t>(layout.hook)].translation();
}

void printCraneState(const char *label, const rc::RobotModel &crane, const CraneLayout &layout,
                     const std::vector<double> &q, const char *verdict)
{
    const Eigen::Vector3d hook = hookPosition(crane, layout, q);
    std::printf("  %-18s slew %7.1f deg  luff %5.1f deg  boom %4.1f m  hoist %5.2f m  hook (%6.2f, %6.2f, %5.2f)  %s\n",
                label, degrees(q[layout.slew]), degrees(q[layout.luff]), 12.0 + 3.0 * q[layout.telescope],
                q[layout.hoist], tidy(hook.x()), tidy(hook.y()), tidy(hook.z()), verdict);
}

std::vector<double> pathConfigurations(const og::PathGeometric &path, const rc::ompl::StateMapping &mapping)
{
    std::vector<double> rows;
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
    {
        const std::vector<double> q = mapping.toConfiguration(path.getState(i));
        rows.insert(rows.end(), q.begin(), q.end());
    }
    return rows;
}

/** \brief The largest padding (to \a tolerance) at which every one of \a n states is valid in exact
    mode, found by bisection (validity only shrinks as padding grows), and the contact that bounds
    it: the least clearance along the path. */
double minimumClearance(const rc::Checker &checker, const std::vector<double> &rows, std::size_t n, double upper,
                        double tolerance, rc::Contact &binding, std::size_t &bindingState)
{
    rc::CollisionRequest request;
    request.mode = rc::CollisionMode::Exact;
    std::vector<std::uint8_t> valid(n);
    std::vector<rc::Contact> contacts(n);
    double lo = 0.0, hi = upper;
    while (hi - lo > tolerance)
    {
        request.padding = 0.5 * (lo + hi);
        checker.check(rows.data(), n, valid.data(), request, contacts.data());
        std::size_t first = n;
        for (std::size_t i = 0; i < n && first == n; ++i)
            if (!valid[i])
                first = i;
        if (first == n)
            lo = request.padding;
        else
        {
            hi = request.padding;
            binding = contacts[first];
            bindingState = first;
        }
    }
    return lo;
}

int run(const Options &options)
{
    const auto begin = std::chrono::steady_clock::now();
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_WARN);
    // Before any OMPL random number generator exists, so that planning and simplification repeat.
    ::ompl::RNG::setSeed(options.seed);

    const std::filesystem::path robots(options.robots);
    rc::ProblemSource source;
    source.urdfPath = (robots / "crane/crane.urdf").string();
    source.srdfPath = (robots / "crane/crane.srdf").string();
    source.scenePath = (robots / "sites/plant.yaml").string();
    const rc::Problem problem = rc::loadProblem(source);
    const rc::MotionPlanRequest lift = rc::loadMoveItRequest((robots / "sites/plant_lift.yaml").string());
    const rc::RobotModel &crane = *problem.robot;
    const CraneLayout layout(crane);

    // The crawler stands on its mats during the lift: only the superstructure moves.
    rc::ompl::SetupOptions setupOptions;
    setupOptions.request.mode = rc::CollisionMode::Safe;
    setupOptions.request.padding = options.padding;
    setupOptions.heldCoordinates = {{"base_x", 0.0}, {"base_y", 0.0}, {"base_yaw", 0.0}};
    // Certified edges: every point of every edge keeps the clearance, not only states a resolution
    // apart (CertifiedMotionValidator bounds how far each part of the crane swings along an edge).
    setupOptions.edges = rc::ompl::EdgeChecking::Certified;
    const og::SimpleSetupPtr setup = rc::ompl::makeSimpleSetup(problem, setupOptions);
    rc::ompl::setStartAndGoal(*setup, lift);
    // The resolution in metres of crane motion paces the exact re-check below (certified edges do not
    // use it). The state metric adds radians of slew to metres of hoist, and one radian of slew or
    // luff moves the boom tip and the load up to 41 m (the longest boom's reach from the slew axis
    // and the luff pivot), so OMPL's default of 1 % of the space's extent would let the load jump
    // about 15 m between re-checked states. With at most kMetresPerUnit metres per unit of the
    // metric (tests/test_crane.cpp), no point of the crane moves more than options.step between two
    // states a resolution apart; the re-check samples ten times finer.
    constexpr double kMetresPerUnit = 45.0;
    const ::ompl::base::StateSpacePtr &space = setup->getStateSpace();
    space->setLongestValidSegmentFraction(options.step / kMetresPerUnit / space->getMaximumExtent());
    const rc::ompl::StateValidityCheckerPtr validity = rc::ompl::getStateValidityChecker(*setup);
    const rc::ompl::StateMapping &mapping = validity->getStateMapping();
    const rc::Checker &checker = validity->getChecker();
    const std::vector<double> start = rc::ompl::configurationFromJoints(mapping, lift.startJoints, "start");
    const std::vector<double> goal = rc::ompl::configurationFromJoints(mapping, lift.goalJoints, "goal");

    std::printf(
        "rastercheck crane lift: a 4 x 2 x 2 m skid from the trailer, over the pipe rack, onto its "
        "foundation\n\n");
    std::printf("  robot    %s (%s): %zu coordinates, %zu components, %zu triangles\n", crane.name.c_str(),
                shortPath(source.urdfPath).c_str(), crane.numCoordinates(), crane.numComponents(),
                crane.numTriangles());
    std::printf("  site     %s: %zu objects (%zu primitives), %zu triangles\n", shortPath(source.scenePath).c_str(),
                countIds(checker.scene()), checker.scene().numObjects(), checker.scene().numTriangles());
    std::printf("  checker  %s backend, %s mode, %.2f m safety clearance (padding)\n", checker.backendName().c_str(),
                rc::toString(setupOptions.request.mode).c_str(), options.padding);
    std::printf("  planned  slew, luff, telescope_1, hoist (base_x, base_y, base_yaw held at 0)\n");
    std::printf("  edges    certified: the clearance holds at every point of an edge, not only at samples\n");
    std::printf("  recheck  every %.3f m of crane motion (a %.1e fraction of the space's extent)\n\n",
                options.step / 10, space->getLongestValidSegmentFraction() / 10);

    std::printf("start and goal (plant_lift.yaml)\n");
    printCraneState("start: pick", crane, layout, start,
                    checker.isValid(start, setupOptions.request) ? "valid" : "INVALID");
    printCraneState("goal: set-down", crane, layout, goal,
                    checker.isValid(goal, setupOptions.request) ? "valid" : "INVALID");

    // The straight joint-space line swings the low load east into tank_1 (robots/sites/README.md).
    constexpr int kLineStates = 101;
    std::vector<double> line;
    for (int k = 0; k < kLineStates; ++k)
    {
        const double t = static_cast<double>(k) / (kLineStates - 1);
        for (std::size_t d = 0; d < start.size(); ++d)
            line.push_back((1 - t) * start[d] + t * goal[d]);
    }
    rc::CollisionRequest overlap;  // solids overlapping: what the raster picture shows
    std::vector<std::uint8_t> lineValid(kLineStates);
    std::vector<rc::Contact> lineContacts(kLineStates);
    checker.check(line.data(), kLineStates, lineValid.data(), overlap, lineContacts.data());
    int lineHit = -1;
    for (int k = 0; k < kLineStates && lineHit < 0; ++k)
        if (!lineValid[static_cast<std::size_t>(k)])
            lineHit = k;
    if (lineHit < 0)
        std::printf("\nstraight line start -> goal: no collision in %d states\n", kLineStates);
    else
        std::printf("\nstraight line start -> goal (linear in the joints): first collision %d %% of the way:\n  %s\n",
                    lineHit, checker.describe(lineContacts[static_cast<std::size_t>(lineHit)]).c_str());

    // OMPL's RRT-Connect first, for its time; then BatchRRTConnect (planners/), whose path the rest
    // of the program shows. Both on the same checker and certified edges.
    std::printf("\nplanning: %.0f s limit each, seed %u, certified edges\n", options.time, options.seed);
    const auto edges = std::dynamic_pointer_cast<rc::ompl::CertifiedMotionValidator>(
        setup->getSpaceInformation()->getMotionValidator());
    auto planChecks = [&] { return validity->getCallCount() + (edges ? edges->getCheckedStateCount() : 0); };
    auto plan = [&](const ::ompl::base::PlannerPtr &planner, double &seconds)
    {
        setup->clear();
        validity->resetCounters();
        if (edges)
            edges->resetStateCounter();
        setup->setPlanner(planner);
        const auto begin = std::chrono::steady_clock::now();
        const ::ompl::base::PlannerStatus result = rastercheck::ompl::solveWithin(*setup, options.time);
        seconds = secondsSince(begin);
        return result;
    };
    double rrtSeconds = 0.0;
    plan(std::make_shared<og::RRTConnect>(setup->getSpaceInformation()), rrtSeconds);
    std::printf("  RRT-Connect      %s in %.3f s, %llu states checked\n",
                setup->haveExactSolutionPath() ? "solved" : "no solution", rrtSeconds,
                static_cast<unsigned long long>(planChecks()));
    double planSeconds = 0.0;
    const ::ompl::base::PlannerStatus status =
        plan(std::make_shared<rc::planners::BatchRRTConnect>(setup->getSpaceInformation()), planSeconds);
    std::printf("  BatchRRTConnect  %s in %.3f s, %llu states checked (%.1fx RRT-Connect's time)\n",
                setup->haveExactSolutionPath() ? "solved" : "no solution", planSeconds,
                static_cast<unsigned long long>(planChecks()), planSeconds / rrtSeconds);
    const std::uint64_t planStates = planChecks();
    if (!setup->haveExactSolutionPath())
    {
        std::printf("  no solution within %.1f s (%s, %llu state checks)\n", planSeconds, status.asString().c_str(),
                    static_cast<unsigned long long>(planStates));
        return 2;
    }
    og::PathGeometric &path = setup->getSolutionPath();
    const std::size_t rawStates = path.getStateCount();
    auto phase = std::chrono::steady_clock::now();
    setup->simplifySolution(2.0);
    const double simplifySeconds = secondsSince(phase);
    std::printf("  BatchRRTConnect's path: %zu waypoints\n", rawStates);
    std::printf("  simplified in %.2f s to %zu waypoints\n", simplifySeconds, path.getStateCount());

    std::printf("\nplan (hook = hook block's rope end; the load hangs 1.5 m below it)\n");
    std::printf("   #   slew (deg)  luff (deg)  boom (m)  hoist (m)   hook x (m)  hook y (m)  hook z (m)\n");
    const std::vector<double> waypoints = pathConfigurations(path, mapping);
    const std::size_t dof = crane.numCoordinates();
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
    {
        const std::vector<double> q(waypoints.begin() + static_cast<std::ptrdiff_t>(i * dof),
                                    waypoints.begin() + static_cast<std::ptrdiff_t>((i + 1) * dof));
        const Eigen::Vector3d hook = hookPosition(crane, layout, q);
        std::printf("  %2zu  %10.1f  %10.1f  %8.1f  %9.2f   %10.2f  %10.2f  %10.2f\n", i, degrees(q[layout.slew]),
                    degrees(q[layout.luff]), 12.0 + 3.0 * q[layout.telescope], q[layout.hoist], tidy(hook.x()),
                    tidy(hook.y()), tidy(hook.z()));
    }
    std::printf("  path length %.2f (state-space metric: rad + m)\n", path.length());

    // The oracle: every state at ten times the planner's edge resolution, exact narrow phase.
    phase = std::chrono::steady_clock::now();
    rc::CollisionRequest exact;
    exact.mode = rc::CollisionMode::Exact;
    exact.padding = options.padding;
    const rc::ompl::PathCheckResult cleared = rc::ompl::checkPathDensely(path, mapping, checker, exact, 10);
    exact.padding = 0.0;
    const rc::ompl::PathCheckResult touching = rc::ompl::checkPathDensely(path, mapping, checker, exact, 10);
    std::printf("\nexact re-check (oracle), %zu states along the path (10 x the planner's resolution), %.2f s\n",
                cleared.statesChecked, secondsSince(phase));
    auto verdict = [&](const rc::ompl::PathCheckResult &result)
    {
        return result.valid
                   ? std::string("pass")
                   : "FAIL at segment " + std::to_string(result.segment) + ": " + checker.describe(result.contact);
    };
    std::printf("  collision-free (padding 0):               %s\n", verdict(touching).c_str());
    std::printf("  safety clearance %.2f m kept everywhere:  %s\n", options.padding, verdict(cleared).c_str());

    og::PathGeometric dense(path);
    dense.interpolate(static_cast<unsigned>(cleared.statesChecked));
    const std::vector<double> denseRows = pathConfigurations(dense, mapping);
    rc::Contact binding;
    std::size_t bindingState = 0;
    phase = std::chrono::steady_clock::now();
    const double clearance =
        minimumClearance(checker, denseRows, dense.getStateCount(), 2.0, 0.01, binding, bindingState);
    std::printf("  minimum clearance along the path:         %.2f m (+-0.01, bisection on exact padding, %.2f s)\n",
                clearance, secondsSince(phase));
    if (binding.kind != rc::Contact::Kind::None)
        std::printf("    bound by %s, %.0f %% along the path\n", checker.describe(binding).c_str(),
                    100.0 * static_cast<double>(bindingState) / static_cast<double>(dense.getStateCount() - 1));

    // Pictures.
    phase = std::chrono::steady_clock::now();
    const std::filesystem::path out(options.out);
    std::filesystem::create_directories(out);
    std::vector<std::string> written;
    og::PathGeometric drawn(path);
    drawn.interpolate(200);
    const std::vector<double> drawnRows = pathConfigurations(drawn, mapping);
    char subtitle[200];
    std::snprintf(subtitle, sizeof subtitle,
                  "%s at the plant: RRT-Connect (seed %u) through rastercheck, %.2f m clearance, %zu waypoints",
                  crane.name.c_str(), options.seed, options.padding, path.getStateCount());
    for (const rc::render::SiteView view : {rc::render::SiteView::Top, rc::render::SiteView::Side})
    {
        rc::render::SitePictureOptions picture;
        picture.view = view;
        picture.title = view == rc::render::SiteView::Top ? "Crane lift: top view" : "Crane lift: side view";
        picture.subtitle = subtitle;
        picture.trackedLink = "load";
        const std::string file =
            (out / (view == rc::render::SiteView::Top ? "lift_top.png" : "lift_side.png")).string();
        rc::render::writeSitePicture(file, crane, checker.scene(), drawnRows, picture);
        written.push_back(file);
    }
    if (lineHit >= 0)
    {
        rc::render::SitePictureOptions picture;
        picture.title = "Straight line from pick to set-down: top view";
        picture.subtitle = "linear in the joints, " + std::to_string(kLineStates) + " states; first collision: " +
                           checker.describe(lineContacts[static_cast<std::size_t>(lineHit)]);
        picture.trackedLink = "load";
        picture.collidingState = lineHit;
        const std::string file = (out / "straight_line_top.png").string();
        rc::render::writeSitePicture(file, crane, checker.scene(), line, picture);
        written.push_back(file);

        const rc::Contact &contact = lineContacts[static_cast<std::size_t>(lineHit)];
        rc::RasterImage image;
        if (checker.rasterImage(line.data() + static_cast<std::size_t>(lineHit) * dof, contact, overlap, image))
        {
            rc::render::RasterPictureOptions raster;
            raster.title = "Raster image of the first collision on the straight line";
            raster.subtitle = checker.describe(contact);
            raster.componentLabel = crane.components[static_cast<std::size_t>(contact.component)].name;
            raster.objectLabel = contact.kind == rc::Contact::Kind::Environment
                                     ? checker.scene().objects[static_cast<std::size_t>(contact.object)].name
                                     : crane.components[static_cast<std::size_t>(contact.otherComponent)].name;
            const std::string file = (out / "straight_line_raster.png").string();
            rc::render::writeRasterPicture(file, image, raster);
            written.push_back(file);
        }
    }
    std::printf("\npictures (%.2f s)\n", secondsSince(phase));
    for (const std::string &file : written)
        std::printf("  %s\n", shortPath(file).c_str());
    std::printf("\ndone in %.1f s\n", secondsSince(begin));
    return touching.valid && cleared.valid ? 0 : 1;
}
}  // namespace

int main(int argc, char **argv)
{
    try
    {
        return run(parseArguments(argc, argv));
    }
    catch (const std::exception &e)
    {
        std::cerr << "crane_lift: error: " << e.what() << '\n';
        return 1;
    }
}
