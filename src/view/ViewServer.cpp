#include "view/ViewServer.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/geometric/SimpleSetup.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Text.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/Planners.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateValidityChecker.h"
#include "render/RasterPicture.h"
// After Eigen: httplib.h brings in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace rastercheck::view
{
using nlohmann::json;

namespace
{
namespace fs = std::filesystem;

/** \brief A request the server cannot answer as asked (malformed, too large, or asking for what
    does not exist): answered with \a status and {"error": message}. */
struct RequestError
{
    int status;
    std::string message;
};

void sendJson(httplib::Response &response, const json &body, int status = 200)
{
    response.status = status;
    response.set_header("Cache-Control", "no-store");
    // Invalid UTF-8 in a name from a file is replaced rather than thrown on.
    response.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

void sendError(httplib::Response &response, int status, const std::string &message)
{
    sendJson(response, json{{"error", message}}, status);
}

std::string coordinateList(const RobotModel &robot)
{
    std::string names;
    for (const std::string &name : robot.coordinateNames)
        names += (names.empty() ? "" : ", ") + name;
    return names;
}

/** \brief A configuration from a JSON array: dof finite numbers, else RequestError. */
std::vector<double> configurationFromJson(const json &value, const RobotModel &robot, const std::string &what)
{
    if (!value.is_array())
        throw RequestError{400, what + " must be an array of " + std::to_string(robot.numCoordinates()) + " numbers"};
    if (value.size() != robot.numCoordinates())
        throw RequestError{400, what + " has " + std::to_string(value.size()) + " values; robot '" + robot.name +
                                    "' has " + std::to_string(robot.numCoordinates()) + " coordinates (" +
                                    coordinateList(robot) + ")"};
    std::vector<double> q(value.size());
    for (std::size_t i = 0; i < q.size(); ++i)
    {
        if (!value[i].is_number())
            throw RequestError{
                400, what + "[" + std::to_string(i) + "] ('" + robot.coordinateNames[i] + "') is not a number"};
        q[i] = value[i].get<double>();
        // JSON has neither NaN nor infinity, but a query string ("q=nan,...") has both.
        if (!std::isfinite(q[i]))
            throw RequestError{400,
                               what + "[" + std::to_string(i) + "] ('" + robot.coordinateNames[i] + "') is not finite"};
    }
    return q;
}

/** \brief A configuration from "v1,v2,..." (a query parameter), else RequestError. */
std::vector<double> configurationFromText(const std::string &text, const RobotModel &robot)
{
    json values = json::array();
    std::size_t begin = 0;
    while (begin <= text.size())
    {
        const std::size_t end = std::min(text.find(',', begin), text.size());
        const std::string item = text.substr(begin, end - begin);
        char *stop = nullptr;
        const double value = std::strtod(item.c_str(), &stop);
        if (item.empty() || *stop != '\0')
            throw RequestError{400, "q: '" + item + "' is not a number (expected q=v1,v2,...)"};
        values.push_back(value);
        begin = end + 1;
    }
    return configurationFromJson(values, robot, "q");
}

json vectorJson(const Eigen::Vector3d &v)
{
    return json::array({v.x(), v.y(), v.z()});
}

/** \brief Flat arrays of a mesh for the page: vertices as float (what WebGL draws; 7 digits
    instead of 17 keep the model a third of the size), triangles as vertex indices. */
json meshJson(const Mesh &mesh)
{
    std::vector<float> vertices;
    vertices.reserve(mesh.numVertices() * 3);
    for (const Eigen::Vector3d &v : mesh.vertices)
        for (int k = 0; k < 3; ++k)
            vertices.push_back(static_cast<float>(v[k]));
    std::vector<std::uint32_t> triangles;
    triangles.reserve(mesh.numTriangles() * 3);
    for (const Mesh::Triangle &t : mesh.triangles)
        triangles.insert(triangles.end(), t.begin(), t.end());
    return json{{"vertices", vertices}, {"triangles", triangles}};
}

/** \brief The unit of each coordinate ("m", "rad", or "" for quaternion parts), from its joint. */
std::vector<std::string> coordinateUnits(const RobotModel &robot)
{
    std::vector<std::string> units(robot.numCoordinates());
    for (const Joint &joint : robot.joints)
        for (std::size_t k = 0; joint.firstCoordinate >= 0 && k < joint.coordinateNames.size(); ++k)
        {
            std::string unit = "m";
            if (joint.kind == JointKind::Revolute || (joint.kind == JointKind::Planar && k == 2))
                unit = "rad";
            else if (joint.kind == JointKind::Floating && k >= 3)
                unit = "";
            units[static_cast<std::size_t>(joint.firstCoordinate) + k] = unit;
        }
    return units;
}

json rowsJson(const std::vector<double> &values, std::size_t dof)
{
    json rows = json::array();
    for (std::size_t r = 0; dof > 0 && r + dof <= values.size(); r += dof)
        rows.push_back(std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(r),
                                           values.begin() + static_cast<std::ptrdiff_t>(r + dof)));
    return rows;
}

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/** \brief The first path among \a candidates that holds \a marker, else ConfigurationError naming
    them all and \a hint. */
std::string firstHolding(const std::vector<fs::path> &candidates, const std::string &marker, const std::string &what,
                         const std::string &hint)
{
    std::string tried;
    for (const fs::path &candidate : candidates)
    {
        if (candidate.empty())
            continue;
        std::error_code error;
        if (fs::is_regular_file(candidate / marker, error))
            return fs::absolute(candidate).lexically_normal().string();
        tried += "\n  " + (candidate / marker).string();
    }
    throw ConfigurationError(what + " not found; tried:" + tried + "\n" + hint);
}

fs::path environmentPath(const char *variable)
{
    const char *value = std::getenv(variable);
    return value && *value ? fs::path(value) : fs::path();
}

/** \brief httplib's request handling (parse, route, answer) without its listen(): ConnectionLoop
    reads the requests and calls answer(). */
class HttpServer : public httplib::Server
{
public:
    bool answer(httplib::Stream &stream, bool closeConnection, bool &connectionClosed)
    {
        return process_request(stream, closeConnection, connectionClosed, nullptr);
    }
    /** \brief The bound socket, for ConnectionLoop (which closes it). */
    int takeSocket() { return svr_sock_.exchange(INVALID_SOCKET); }
};

/** \brief At most \a limit holders at once; the others wait. */
class Gate
{
public:
    explicit Gate(int limit) : limit_(std::max(1, limit)) {}

    class Pass
    {
    public:
        explicit Pass(Gate &gate) : gate_(gate)
        {
            std::unique_lock<std::mutex> lock(gate_.mutex_);
            gate_.free_.wait(lock, [&] { return gate_.running_ < gate_.limit_; });
            gate_.peak_ = std::max(gate_.peak_, ++gate_.running_);
        }
        ~Pass()
        {
            {
                std::lock_guard<std::mutex> lock(gate_.mutex_);
                --gate_.running_;
            }
            gate_.free_.notify_one();
        }
        Pass(const Pass &) = delete;
        Pass &operator=(const Pass &) = delete;

    private:
        Gate &gate_;
    };

    int peak() const
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return peak_;
    }

private:
    const int limit_;
    mutable std::mutex mutex_;
    std::condition_variable free_;
    int running_ = 0;
    int peak_ = 0;
};

bool isLoopbackHost(const std::string &host)
{
    return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

bool isWildcardHost(const std::string &host)
{
    return host.empty() || host == "0.0.0.0" || host == "::";
}

/** \brief An IPv4 literal, or an IPv6 one in brackets (as a Host header writes it). */
bool isAddressLiteral(const std::string &name)
{
    if (name.size() > 2 && name.front() == '[' && name.back() == ']')
        return name.find_first_not_of("0123456789abcdef:.", 1) == name.size() - 1;
    return !name.empty() && name.find_first_not_of("0123456789.") == std::string::npos;
}

CheckerOptions checkerOptionsFor(const ViewServerOptions &options)
{
    CheckerOptions checker;
    const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    checker.threads =
        options.checkerThreads > 0 ? options.checkerThreads : std::max(1, cores / std::max(1, options.maxConcurrentBatches));
    return checker;
}
}  // namespace

std::string findWebDir(const std::string &executable)
{
    const fs::path chosen = environmentPath("RASTERCHECK_WEB_DIR");
    std::error_code error;
    fs::path installed;
    const fs::path binary = fs::canonical(executable, error);
    if (!error)
        installed = binary.parent_path() / RASTERCHECK_VIEW_WEB_FROM_BINDIR;
    return firstHolding(chosen.empty() ? std::vector<fs::path>{installed, RASTERCHECK_VIEW_SOURCE_WEB_DIR}
                                       : std::vector<fs::path>{chosen},
                        "index.html", "the viewer's page (index.html)",
                        "set RASTERCHECK_WEB_DIR to the folder that holds it (src/view/web in the source tree)");
}

std::string findThreeDir()
{
    const fs::path chosen = environmentPath("RASTERCHECK_THREE_DIR");
    return firstHolding(
        chosen.empty() ? std::vector<fs::path>{RASTERCHECK_VIEW_THREE_DIR} : std::vector<fs::path>{chosen},
        "build/three.module.js", "three.js",
        "install Debian's libjs-three (scripts/install-deps.sh) or set RASTERCHECK_THREE_DIR to "
        "the folder that holds build/three.module.js");
}

struct ViewServer::Impl
{
    Impl(Problem problemIn, ViewContent contentIn, ViewServerOptions optionsIn)
        : problem(std::move(problemIn)),
          content(std::move(contentIn)),
          options(std::move(optionsIn)),
          checker(problem.robot, problem.scene, checkerOptionsFor(options)),
          batches(options.maxConcurrentBatches)
    {
        const std::size_t dof = robot().numCoordinates();
        const auto checkSize = [&](const std::vector<double> &values, const std::string &what)
        {
            if (!values.empty() && values.size() != dof)
                throw ConfigurationError("viewer: the " + what + " has " + std::to_string(values.size()) +
                                         " values; robot '" + robot().name + "' has " + std::to_string(dof) +
                                         " coordinates");
        };
        checkSize(content.start, "start");
        checkSize(content.goal, "goal");
        if (dof > 0 ? content.path.size() % dof != 0 : !content.path.empty())
            throw ConfigurationError("viewer: the path's " + std::to_string(content.path.size()) +
                                     " values are not rows of the robot's " + std::to_string(dof) + " coordinates");
        validate(options.request);
        modelJson = makeModelJson().dump(-1, ' ', false, json::error_handler_t::replace);
        addRoutes();
    }

    const RobotModel &robot() const { return *problem.robot; }
    const Scene &scene() const { return *problem.scene; }

    json makeModelJson() const
    {
        json components = json::array();
        for (const Component &component : robot().components)
        {
            json entry = meshJson(component.mesh);
            entry["name"] = component.name;
            entry["link"] = robot().links[static_cast<std::size_t>(component.link)].name;
            entry["closed"] = component.topology.closed;
            components.push_back(std::move(entry));
        }
        json objects = json::array();
        for (const SceneObject &object : scene().objects)
        {
            json entry = meshJson(object.mesh);
            entry["name"] = object.name;
            entry["closed"] = object.topology.closed;
            objects.push_back(std::move(entry));
        }
        json coordinates = json::array();
        const std::vector<std::string> units = coordinateUnits(robot());
        for (std::size_t i = 0; i < robot().numCoordinates(); ++i)
            coordinates.push_back({{"name", robot().coordinateNames[i]},
                                   {"lower", robot().lowerBounds[i]},
                                   {"upper", robot().upperBounds[i]},
                                   {"unit", units[i]}});
        const std::size_t dof = robot().numCoordinates();
        return json{{"title", content.title},
                    {"robot", robot().name},
                    {"backend", checker.backendName()},
                    {"mode", toString(options.request.mode)},
                    {"padding", options.request.padding},
                    {"coordinates", std::move(coordinates)},
                    {"neutral", robot().neutralConfiguration()},
                    {"start", content.start.empty() ? json(nullptr) : json(content.start)},
                    {"goal", content.goal.empty() ? json(nullptr) : json(content.goal)},
                    {"path", rowsJson(content.path, dof)},
                    {"components", std::move(components)},
                    {"objects", std::move(objects)}};
    }

    json contactJson(const Contact &contact) const
    {
        json entry{{"kind", toString(contact.kind)}, {"description", checker.describe(contact)}};
        if (contact.kind == Contact::Kind::OutOfBounds && contact.coordinate >= 0)
            entry["coordinate"] = robot().coordinateNames[static_cast<std::size_t>(contact.coordinate)];
        if (contact.kind != Contact::Kind::Environment && contact.kind != Contact::Kind::SelfCollision)
            return entry;
        entry["component"] = robot().components[static_cast<std::size_t>(contact.component)].name;
        entry["object"] = contact.kind == Contact::Kind::Environment
                              ? scene().objects[static_cast<std::size_t>(contact.object)].name
                              : robot().components[static_cast<std::size_t>(contact.otherComponent)].name;
        entry["triangle"] = contact.triangle;
        entry["point"] = vectorJson(contact.position);
        return entry;
    }

    /** \brief The distance at \a q (Checker::distance over the pairs the request checks): the
        value, the pair and the two nearest points; null when there is nothing to measure. */
    json distanceJson(const std::vector<double> &q) const
    {
        DistanceRequest request;
        request.checkEnvironment = options.request.checkEnvironment;
        request.checkSelfCollision = options.request.checkSelfCollision;
        DistanceResult result;
        checker.distance(q.data(), request, &result);
        if (result.kind != Contact::Kind::Environment && result.kind != Contact::Kind::SelfCollision)
            return nullptr;
        const std::string other = result.kind == Contact::Kind::Environment
                                      ? scene().objects[static_cast<std::size_t>(result.object)].name
                                      : robot().components[static_cast<std::size_t>(result.otherComponent)].name;
        return json{{"distance", result.distance},
                    {"kind", toString(result.kind)},
                    {"component", robot().components[static_cast<std::size_t>(result.component)].name},
                    {"other", other},
                    {"points", json::array({vectorJson(result.pointOnComponent), vectorJson(result.pointOnOther)})}};
    }

    /** \brief Pose of every component (world frame) at \a q: position and quaternion x y z w. */
    json componentPoses(const std::vector<double> &q) const
    {
        RobotData data(robot());
        forwardKinematics(robot(), data, q);
        json poses = json::array();
        for (const Component &component : robot().components)
        {
            const Eigen::Isometry3d &pose = data.oMl[static_cast<std::size_t>(component.link)];
            const Eigen::Quaterniond rotation(pose.rotation());
            poses.push_back({{"position", vectorJson(pose.translation())},
                             {"quaternion", json::array({rotation.x(), rotation.y(), rotation.z(), rotation.w()})}});
        }
        return poses;
    }

    json checkOne(const std::vector<double> &q) const
    {
        const auto start = std::chrono::steady_clock::now();
        // The checker's verdict first (culls and proofs: fast for a free state); every contact only
        // for a state that collides.
        const bool valid = checker.isValid(q, options.request);
        std::vector<Contact> contacts;
        if (!valid)
            contacts = checker.contacts(q.data(), options.request);
        // A valid state's clearance: how far, and between which two points, it is from the nearest
        // solid (the pairs the request checks; not padded).
        json distance = nullptr;
        if (valid)
            distance = distanceJson(q);
        const double milliseconds = millisecondsSince(start);
        json contactList = json::array();
        for (const Contact &contact : contacts)
            contactList.push_back(contactJson(contact));
        return json{{"valid", valid},
                    {"contacts", std::move(contactList)},
                    {"distance", std::move(distance)},
                    {"links", componentPoses(q)},
                    {"milliseconds", milliseconds}};
    }

    json checkBatch(const json &states) const
    {
        if (!states.is_array())
            throw RequestError{400, "states must be an array of configurations"};
        if (states.size() > options.maxBatchStates)
            throw RequestError{413, "states has " + std::to_string(states.size()) + " configurations; at most " +
                                        std::to_string(options.maxBatchStates) + " per request"};
        const std::size_t dof = robot().numCoordinates(), n = states.size();
        std::vector<double> q;
        q.reserve(n * dof);
        for (std::size_t i = 0; i < n; ++i)
        {
            const std::vector<double> row =
                configurationFromJson(states[i], robot(), "states[" + std::to_string(i) + "]");
            q.insert(q.end(), row.begin(), row.end());
        }
        std::vector<std::uint8_t> valid(n);
        std::vector<Contact> contacts(n);
        double milliseconds = 0;
        {
            const Gate::Pass pass(batches);
            const auto start = std::chrono::steady_clock::now();
            checker.check(q.data(), n, valid.data(), options.request, contacts.data());
            milliseconds = millisecondsSince(start);
        }
        json verdicts = json::array(), firstContacts = json::array();
        for (std::size_t i = 0; i < n; ++i)
        {
            verdicts.push_back(valid[i] != 0);
            firstContacts.push_back(valid[i] ? json(nullptr) : contactJson(contacts[i]));
        }
        return json{
            {"valid", std::move(verdicts)}, {"contacts", std::move(firstContacts)}, {"milliseconds", milliseconds}};
    }

    static json parseBody(const httplib::Request &request)
    {
        try
        {
            return json::parse(request.body);
        }
        catch (const json::exception &e)  // a syntax error, or a number too large for a double
        {
            throw RequestError{400, std::string("malformed JSON: ") + e.what()};
        }
    }

    void handleCheck(const httplib::Request &request, httplib::Response &response) const
    {
        json body = parseBody(request);
        if (!body.is_object() || body.contains("q") == body.contains("states"))
            throw RequestError{400,
                               "expected an object with either \"q\": [one configuration] or \"states\": "
                               "[[configuration], ...]"};
        sendJson(response, body.contains("q") ? checkOne(configurationFromJson(body["q"], robot(), "q"))
                                              : checkBatch(body["states"]));
    }

    /** \brief POST /api/plan: one plan at a time, on a SimpleSetup made as `rastercheck plan` makes
        it (ompl::makeSimpleSetup: the same options, certified edges by default), built at the first
        plan. */
    void handlePlan(const httplib::Request &request, httplib::Response &response) const
    {
        const json body = parseBody(request);
        if (!body.is_object())
            throw RequestError{400, "expected an object {\"start\", \"goal\", \"planner\", \"time_limit\"} (each "
                                    "optional)"};
        for (const auto &item : body.items())
            if (item.key() != "start" && item.key() != "goal" && item.key() != "planner" && item.key() != "time_limit")
                throw RequestError{400, "unknown field \"" + item.key() +
                                            "\" (expected start, goal, planner, time_limit)"};
        const auto endpoint = [&](const char *name, const std::vector<double> &fallback)
        {
            if (body.contains(name))
                return configurationFromJson(body[name], robot(), name);
            if (fallback.empty())
                throw RequestError{400, std::string("no ") + name + ": the problem has none; give \"" + name + "\""};
            return fallback;
        };
        const std::vector<double> start = endpoint("start", content.start);
        const std::vector<double> goal = endpoint("goal", content.goal);
        if (body.contains("planner") && !body["planner"].is_string())
            throw RequestError{400, "planner must be a name (batchrrtconnect, rrtconnect, ...)"};
        const std::string plannerName = body.value("planner", std::string("batchrrtconnect"));
        double timeLimit = 1.0;
        if (body.contains("time_limit"))
        {
            if (!body["time_limit"].is_number() || !(body["time_limit"].get<double>() > 0) ||
                body["time_limit"].get<double>() > options.maxPlanSeconds)
                throw RequestError{400, "time_limit must be a number of seconds in (0, " +
                                            std::to_string(static_cast<int>(options.maxPlanSeconds)) + "]"};
            timeLimit = body["time_limit"].get<double>();
        }

        std::unique_lock<std::mutex> lock(planMutex, std::try_to_lock);
        if (!lock.owns_lock())
            throw RequestError{409, "a plan is running: one at a time"};
        if (!planSetup)
        {
            ompl::SetupOptions setupOptions;
            setupOptions.checker = checkerOptionsFor(options);
            setupOptions.request = options.request;
            planSetup = ompl::makeSimpleSetup(problem, setupOptions);
        }
        ::ompl::base::PlannerPtr planner;
        try
        {
            planner = ompl::allocatePlanner(plannerName, planSetup->getSpaceInformation());
        }
        catch (const ConfigurationError &e)
        {
            throw RequestError{400, e.what()};
        }
        json answer{{"solved", false}, {"path", json::array()}, {"seconds", 0.0}, {"planner", planner->getName()}};
        // A planner cannot leave an invalid start or reach an invalid goal: say which and why.
        for (const auto &[name, q] : {std::pair<const char *, const std::vector<double> &>{"start", start},
                                      std::pair<const char *, const std::vector<double> &>{"goal", goal}})
        {
            Contact contact;
            if (!checker.isValid(q, options.request, &contact))
            {
                answer["message"] = std::string("the ") + name + " is invalid: " + checker.describe(contact);
                sendJson(response, answer);
                return;
            }
        }
        planSetup->clear();
        ompl::setStartAndGoal(*planSetup, start, goal);
        planSetup->setPlanner(planner);
        const auto begin = std::chrono::steady_clock::now();
        // stop() ends a plan early, so that it never waits for a long time limit.
        const ::ompl::base::PlannerStatus status = planSetup->solve(::ompl::base::plannerOrTerminationCondition(
            ::ompl::base::timedPlannerTerminationCondition(timeLimit),
            ::ompl::base::PlannerTerminationCondition([this] { return cancelPlans.load(); })));
        const bool solved = status == ::ompl::base::PlannerStatus::EXACT_SOLUTION;
        if (solved)
            planSetup->simplifySolution();
        answer["seconds"] = millisecondsSince(begin) / 1000.0;
        answer["solved"] = solved;
        if (!solved)
        {
            answer["message"] = "no path found within " + json(timeLimit).dump() + " s (" + status.asString() + ")";
            sendJson(response, answer);
            return;
        }
        const ompl::StateMapping &mapping = ompl::getStateValidityChecker(*planSetup)->getStateMapping();
        const ::ompl::geometric::PathGeometric &path = planSetup->getSolutionPath();
        for (std::size_t i = 0; i < path.getStateCount(); ++i)
            answer["path"].push_back(mapping.toConfiguration(path.getState(static_cast<unsigned int>(i))));
        sendJson(response, answer);
    }

    void handleRaster(const httplib::Request &request, httplib::Response &response) const
    {
        if (!request.has_param("q"))
            throw RequestError{400, "expected ?q=v1,v2,... (" + coordinateList(robot()) + ")"};
        const std::vector<double> q = configurationFromText(request.get_param_value("q"), robot());
        Contact contact;
        if (checker.isValid(q, options.request, &contact))
            throw RequestError{404, "the state is collision-free: no colliding pair to draw"};
        RasterImage image;
        if (contact.kind == Contact::Kind::OutOfBounds ||
            !checker.rasterImage(q.data(), contact, options.request, image))
            throw RequestError{
                404, "the state is invalid (" + checker.describe(contact) + ") but names no pair of solids to draw"};
        render::RasterPictureOptions picture;
        picture.subtitle = checker.describe(contact);
        picture.componentLabel = robot().components[static_cast<std::size_t>(contact.component)].name;
        picture.objectLabel = contact.kind == Contact::Kind::Environment
                                  ? scene().objects[static_cast<std::size_t>(contact.object)].name
                                  : robot().components[static_cast<std::size_t>(contact.otherComponent)].name;
        std::string png;
        {
            // Cairo's surfaces are independent, but its text goes through fontconfig and FreeType,
            // whose caches older releases do not guard: one picture at a time.
            std::lock_guard<std::mutex> lock(cairoMutex);
            png = render::rasterPicturePng(image, picture);
        }
        response.set_header("Cache-Control", "no-store");
        response.set_content(png, "image/png");
    }

    void log(const std::string &line) const
    {
        if (options.log)
            options.log(line);
        else
            std::cerr << "rastercheck view: " << line << std::endl;
    }

    /** \brief A 500 for an unexpected failure: its detail goes to the log, not to a client (it may
        name files and internals). */
    void answerInternalError(const httplib::Request &request, httplib::Response &response,
                             const std::string &detail) const
    {
        log("internal error answering " + request.method + " " + request.path + ": " + detail);
        sendError(response, 500, "internal error (the server's log has the detail)");
    }

    /** \brief Runs \a handler, answering a RequestError with its status and {"error": message}, and
        any other exception with a generic 500: no request stops the server. */
    httplib::Server::Handler guarded(void (Impl::*handler)(const httplib::Request &, httplib::Response &) const) const
    {
        return [this, handler](const httplib::Request &request, httplib::Response &response)
        {
            try
            {
                (this->*handler)(request, response);
            }
            catch (const RequestError &bad)
            {
                sendError(response, bad.status, bad.message);
            }
            catch (const std::exception &e)
            {
                answerInternalError(request, response, e.what());
            }
        };
    }

    /** \brief The names a Host header may give this server: the bound address, and for a loopback
        or wildcard bind the loopback names. */
    std::vector<std::string> hostNames() const
    {
        std::vector<std::string> names;
        const std::string &host = options.host;
        names.push_back(lowerCase(host.find(':') != std::string::npos ? "[" + host + "]" : host));
        if (isLoopbackHost(host) || isWildcardHost(host))
            for (const char *name : {"localhost", "127.0.0.1", "[::1]"})
                names.emplace_back(name);
        return names;
    }

    /** \brief Why a request may not be served (empty when it may): a Host other than this server's
        (DNS rebinding), a cross-origin call of the API, a POST body that is not JSON. */
    std::pair<int, std::string> refusal(const httplib::Request &request) const
    {
        const std::string host = lowerCase(request.get_header_value("Host"));
        const std::size_t colon = host.rfind(':');
        const bool hasPort = colon != std::string::npos && host.find(']', colon) == std::string::npos;
        const std::string name = hasPort ? host.substr(0, colon) : host;
        const std::string portText = hasPort ? host.substr(colon + 1) : "80";
        const std::vector<std::string> names = hostNames();
        const bool knownName = std::find(names.begin(), names.end(), name) != names.end() ||
                               (isWildcardHost(options.host) && isAddressLiteral(name));
        if (!knownName || portText != std::to_string(port))
            return {403, "Host '" + host + "' is not this server (" + names.front() + ":" + std::to_string(port) +
                             "): requests are served only for the address it listens on"};
        if (request.path.rfind("/api/", 0) != 0)
            return {};
        const std::string origin = lowerCase(request.get_header_value("Origin"));
        if (request.has_header("Origin") && origin != "http://" + host)
            return {403, "cross-origin request from '" + origin + "' refused: the API answers its own page only"};
        const std::string site = lowerCase(request.get_header_value("Sec-Fetch-Site"));
        if (site == "cross-site" || site == "same-site")
            return {403, "request from another site (Sec-Fetch-Site: " + site +
                             ") refused: the API answers its own page only"};
        if (request.method == "POST")
        {
            const std::string type = lowerCase(request.get_header_value("Content-Type"));
            std::string mediaType = type.substr(0, type.find(';'));  // parameters (charset) aside
            mediaType.erase(mediaType.find_last_not_of(" \t") + 1);
            if (mediaType != "application/json")
                return {415, "Content-Type '" + type + "' refused: POST bodies must be application/json"};
        }
        return {};
    }

    void addRoutes()
    {
        // httplib's default sets SO_REUSEPORT, with which a second server binds a port in use and
        // silently takes part of its connections. SO_REUSEADDR alone still lets a stopped viewer
        // be restarted on its port at once.
        server.set_socket_options(
            [](socket_t socket)
            {
                const int yes = 1;
                setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
            });
        server.set_payload_max_length(options.maxBodyBytes);
        server.set_pre_routing_handler(
            [this](const httplib::Request &request, httplib::Response &response)
            {
                const auto [status, message] = refusal(request);
                if (status == 0)
                    return httplib::Server::HandlerResponse::Unhandled;
                sendError(response, status, message);
                return httplib::Server::HandlerResponse::Handled;
            });
        server.set_exception_handler(
            [this](const httplib::Request &request, httplib::Response &response, std::exception_ptr failure)
            {
                std::string detail = "unknown exception";
                try
                {
                    std::rethrow_exception(failure);
                }
                catch (const std::exception &e)
                {
                    detail = e.what();
                }
                catch (...)
                {
                }
                answerInternalError(request, response, detail);
            });
        // Module scripts load only with a JavaScript type.
        server.set_file_extension_and_mimetype_mapping("js", "text/javascript");
        server.set_mount_point("/vendor/three", options.threeDir);
        server.set_mount_point("/", options.webDir);
        server.Get("/api/model",
                   [this](const httplib::Request &, httplib::Response &response)
                   {
                       response.set_header("Cache-Control", "no-store");
                       response.set_content(modelJson, "application/json");
                   });
        server.Post("/api/check", guarded(&Impl::handleCheck));
        server.Post("/api/plan", guarded(&Impl::handlePlan));
        server.Get("/api/raster", guarded(&Impl::handleRaster));
        // Every other failure (no such route or file, a body over the limit, a request httplib
        // cannot parse) gets a message too; answers the handlers wrote are left as they are.
        const std::size_t maxBody = options.maxBodyBytes;
        server.set_error_handler(
            [maxBody](const httplib::Request &request, httplib::Response &response)
            {
                if (!response.body.empty())
                    return;
                std::string message;
                if (response.status == 404)
                    message = "no route " + request.method + " " + request.path +
                              " (routes: GET /api/model, POST /api/check, POST /api/plan, GET /api/raster?q=..., "
                              "and the page)";
                else if (response.status == 413)
                    message = "request body over the limit of " + std::to_string(maxBody) + " bytes";
                else
                    message = "request refused (HTTP " + std::to_string(response.status) + ")";
                sendError(response, response.status, message);
            });
    }

    Problem problem;
    ViewContent content;
    ViewServerOptions options;
    Checker checker;
    mutable Gate batches;
    std::string modelJson;
    HttpServer server;
    mutable std::mutex cairoMutex;
    mutable std::mutex planMutex;
    mutable ::ompl::geometric::SimpleSetupPtr planSetup;  ///< under planMutex
    std::atomic<bool> cancelPlans{false};
    int port = -1;
    std::unique_ptr<ConnectionLoop> loop;
    std::mutex stateMutex;  ///< loop (created once) and stopping
    std::mutex stopMutex;
    std::condition_variable stopped;
    bool stopping = false;
};

ViewServer::ViewServer(Problem problem, ViewContent content, ViewServerOptions options)
    : impl_(std::make_unique<Impl>(std::move(problem), std::move(content), std::move(options)))
{
}

ViewServer::~ViewServer()
{
    stop();
}

int ViewServer::bind()
{
    const ViewServerOptions &options = impl_->options;
    if (options.port < 0 || options.port > 65535)
        throw ConfigurationError("viewer: port " + std::to_string(options.port) + " is not in 0..65535");
    if (options.port == 0)
        impl_->port = impl_->server.bind_to_any_port(options.host);
    else if (impl_->server.bind_to_port(options.host, options.port))
        impl_->port = options.port;
    if (impl_->port <= 0)
        throw ConfigurationError("viewer: cannot listen on " + options.host + ":" + std::to_string(options.port) +
                                 " (address not available, or the port is in use: try --port 0)");
    return impl_->port;
}

void ViewServer::start()
{
    Impl &impl = *impl_;
    std::lock_guard<std::mutex> lock(impl.stateMutex);
    if (impl.loop || impl.stopping || impl.port <= 0)
        return;
    ConnectionLimits limits = impl.options.connections;
    limits.maxBodyBytes = impl.options.maxBodyBytes;
    impl.loop = std::make_unique<ConnectionLoop>(
        impl.server.takeSocket(), limits,
        [&impl](httplib::Stream &stream, bool closeConnection, bool &connectionClosed)
        { return impl.server.answer(stream, closeConnection, connectionClosed); });
    impl.loop->start();
}

bool ViewServer::serve()
{
    start();
    std::unique_lock<std::mutex> lock(impl_->stateMutex);
    if (!impl_->loop)
        return false;
    impl_->stopped.wait(lock, [&] { return impl_->stopping; });
    return true;
}

void ViewServer::stop()
{
    // One stop at a time: the second waits until the threads are joined.
    std::lock_guard<std::mutex> stopping(impl_->stopMutex);
    impl_->cancelPlans = true;
    ConnectionLoop *loop = nullptr;  // made once by start(), never replaced
    {
        std::lock_guard<std::mutex> lock(impl_->stateMutex);
        impl_->stopping = true;
        loop = impl_->loop.get();
    }
    impl_->stopped.notify_all();
    if (loop)
        loop->stop();
}

ViewServerStats ViewServer::stats() const
{
    ViewServerStats stats;
    {
        std::lock_guard<std::mutex> lock(impl_->stateMutex);
        if (impl_->loop)
            stats.connections = impl_->loop->stats();
    }
    stats.peakConcurrentBatches = impl_->batches.peak();
    return stats;
}

std::string ViewServer::url() const
{
    const std::string &host = impl_->options.host;
    // An IPv6 literal goes in brackets in a URL.
    const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host;
    return "http://" + shown + ":" + std::to_string(impl_->port) + "/";
}

std::string ViewServer::backendName() const
{
    return impl_->checker.backendName();
}
}  // namespace rastercheck::view
