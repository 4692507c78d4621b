// The Python module `rastercheck` (pybind11 + numpy): problems, a Checker over row-major (N, dof)
// arrays, straight edges, and planning. Every call goes to the same C++ code as the command line
// (loadProblem, Checker, makeSimpleSetup, the motion validators, allocatePlanner); this file only
// converts arrays and errors, and releases the GIL while C++ runs.
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <ompl/base/PlannerStatus.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "rastercheck/ompl/BatchMotionValidator.h"
#include "rastercheck/ompl/CertifiedMotionValidator.h"
#include "rastercheck/ompl/MotionValidator.h"
#include "rastercheck/ompl/Planners.h"
#include "rastercheck/ompl/Setup.h"

namespace py = pybind11;
namespace rc = rastercheck;
namespace ob = ::ompl::base;
namespace og = ::ompl::geometric;

namespace
{
/** \brief A loaded problem: what loadProblem gives, with a start and goal where the source has them
    (an OMPL.app .cfg, a MoveIt request). Immutable once built. */
struct PyProblem
{
    rc::Problem problem;
    std::string name;
    std::vector<double> start;  ///< empty when the source gives none
    std::vector<double> goal;

    const rc::RobotModel &robot() const { return *problem.robot; }
    std::size_t dof() const { return problem.robot->numCoordinates(); }
};
using PyProblemPtr = std::shared_ptr<PyProblem>;

py::array_t<double> vectorArray(const std::vector<double> &values)
{
    py::array_t<double> array(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), array.mutable_data());
    return array;
}

/** \brief "(3, 7)", "(7,)": an array's shape as Python writes it. */
std::string shapeText(const py::array &array)
{
    std::string text = "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d)
        text += (d ? ", " : "") + std::to_string(array.shape(d));
    return text + (array.ndim() == 1 ? ",)" : ")");
}

/** \brief Configurations a caller passed, as a C-contiguous float64 block: the caller's own memory
    when it already is one (no copy), else a converted copy that \a array keeps alive. */
struct StatesArgument
{
    py::array array;
    const double *data = nullptr;
    std::size_t rows = 0;
};

/** \brief \a q as (N, dof) or (dof,) rows of \a problem's coordinates. Throws py::value_error for
    another shape, a dtype that is not a real number, or a value that is not finite (naming the
    row and coordinate): the checker would call such a state invalid, but from Python it is more
    likely a bug than a question. */
StatesArgument statesArgument(const py::handle &q, const PyProblem &problem, const char *what)
{
    using Float64 = py::array_t<double, py::array::c_style>;
    StatesArgument states;
    states.array = py::isinstance<py::array>(q) ? py::reinterpret_borrow<py::array>(q) : py::array::ensure(q);
    if (!states.array)
        throw py::value_error(std::string(what) + " must be an array of configurations");
    const char kind = states.array.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::value_error(std::string(what) +
                              " must hold real numbers (float64, or float32 converted), not dtype " +
                              py::str(states.array.dtype()).cast<std::string>());
    const std::size_t dof = problem.dof();
    const py::ssize_t ndim = states.array.ndim();
    if ((ndim != 1 && ndim != 2) || static_cast<std::size_t>(states.array.shape(ndim - 1)) != dof)
        throw py::value_error(std::string(what) + " must have shape (N, " + std::to_string(dof) + ") or (" +
                              std::to_string(dof) + ",), not " + shapeText(states.array));
    states.rows = ndim == 1 ? 1 : static_cast<std::size_t>(states.array.shape(0));
    if (!py::isinstance<Float64>(states.array) || !(states.array.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_))
        states.array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(states.array);
    if (!states.array)
        throw py::value_error(std::string(what) + " cannot be converted to float64");
    states.data = static_cast<const double *>(states.array.data());
    for (std::size_t i = 0; i < states.rows * dof; ++i)
        if (!std::isfinite(states.data[i]))
        {
            std::ostringstream message;
            message << what << " row " << i / dof << ": coordinate " << i % dof << " ('"
                    << problem.robot().coordinateNames[i % dof] << "') is " << states.data[i] << ", not finite";
            throw py::value_error(message.str());
        }
    return states;
}

/** \brief One configuration (dof values), for a start or goal. */
std::vector<double> configurationArgument(const py::handle &q, const PyProblem &problem, const char *what)
{
    const StatesArgument states = statesArgument(q, problem, what);
    if (states.array.ndim() != 1)
        throw py::value_error(std::string(what) + " must be one configuration, of shape (" +
                              std::to_string(problem.dof()) + ",)");
    return std::vector<double>(states.data, states.data + problem.dof());
}

PyProblemPtr loadRobotProblem(const std::string &urdf, const std::string &srdf, const std::string &scene,
                              const std::string &request, const std::vector<std::string> &packagePaths)
{
    rc::ProblemSource source;
    source.urdfPath = urdf;
    source.srdfPath = srdf;
    source.scenePath = scene;
    source.urdfOptions.packagePaths = packagePaths;
    auto loaded = std::make_shared<PyProblem>();
    loaded->problem = rc::loadProblem(source);
    loaded->name = loaded->problem.robot->name + (scene.empty() ? "" : "_" + rc::stemOf(scene));
    if (!request.empty())
    {
        // The start and goal makeSimpleSetup's mapping gives the request (rastercheck plan --request).
        const rc::ompl::StateMapping mapping(loaded->problem.robot);
        const rc::MotionPlanRequest motion = rc::loadMoveItRequest(request);
        loaded->start =
            rc::ompl::configurationFromJoints(mapping, motion.startJoints, "start", rc::ompl::UnknownJoints::Skip);
        loaded->goal = rc::ompl::configurationFromJoints(mapping, motion.goalJoints, "goal");
        loaded->name += "_" + rc::stemOf(request);
    }
    return loaded;
}

PyProblemPtr loadCfgProblem(const std::string &path)
{
    rc::ProblemSource source;
    source.cfgPath = path;
    auto loaded = std::make_shared<PyProblem>();
    loaded->problem = rc::loadProblem(source);
    const rc::OmplAppProblem &app = *loaded->problem.omplApp;
    loaded->name = app.name.empty() ? rc::stemOf(path) : app.name;
    loaded->start = app.start;
    loaded->goal = app.goal;
    return loaded;
}

py::dict contactDict(const rc::Checker &checker, const rc::Contact &contact)
{
    py::dict entry;
    entry["kind"] = rc::toString(contact.kind);
    entry["description"] = checker.describe(contact);
    const bool pair =
        contact.kind == rc::Contact::Kind::Environment || contact.kind == rc::Contact::Kind::SelfCollision;
    entry["component"] =
        pair ? py::cast(checker.robot().components[static_cast<std::size_t>(contact.component)].name) : py::none();
    if (!pair)
        entry["object"] = py::none();
    else if (contact.kind == rc::Contact::Kind::Environment)
        entry["object"] = checker.scene().objects[static_cast<std::size_t>(contact.object)].name;
    else
        entry["object"] = checker.robot().components[static_cast<std::size_t>(contact.otherComponent)].name;
    entry["triangle"] = contact.triangle;
    entry["point"] = pair ? py::make_tuple(contact.position.x(), contact.position.y(), contact.position.z())
                          : py::object(py::none());
    return entry;
}

/** \brief OMPL states of the rows of a configuration block, freed with the object. */
class StateBlock
{
public:
    StateBlock(const ob::SpaceInformationPtr &si, const rc::ompl::StateMapping &mapping, const double *rows,
               std::size_t n)
        : si_(si), states_(n, nullptr)
    {
        si_->allocStates(states_);
        for (std::size_t i = 0; i < n; ++i)
            mapping.fromConfiguration(rows + i * mapping.numCoordinates(), states_[i]);
    }
    ~StateBlock() { si_->freeStates(states_); }
    StateBlock(const StateBlock &) = delete;
    StateBlock &operator=(const StateBlock &) = delete;

    const ob::State *operator[](std::size_t i) const { return states_[i]; }

private:
    ob::SpaceInformationPtr si_;
    std::vector<ob::State *> states_;
};

/** \brief The Python Checker: a rastercheck::Checker, the request of every call, and (built on the
    first check_motions call) the planning context of makeSimpleSetup over that same checker for
    each kind of edge. Thread safe like Checker. */
class PyChecker
{
public:
    PyChecker(PyProblemPtr problem, const std::string &mode, double padding, const std::string &backend, int threads)
        : problem_(std::move(problem))
    {
        if (threads < 0)
            throw py::value_error("threads must be >= 0 (0 = all cores), not " + std::to_string(threads));
        request_.mode = rc::parseCollisionMode(mode);
        request_.padding = padding;
        rc::validate(request_);
        options_.backend = rc::parseBackendChoice(backend);
        options_.threads = threads;
        py::gil_scoped_release release;
        checker_ = std::make_shared<const rc::Checker>(problem_->problem.robot, problem_->problem.scene, options_);
    }

    py::array_t<bool> check(const py::handle &q) const
    {
        const StatesArgument states = statesArgument(q, *problem_, "q");
        py::array_t<bool> valid(static_cast<py::ssize_t>(states.rows));
        auto *out = reinterpret_cast<std::uint8_t *>(valid.mutable_data());
        {
            py::gil_scoped_release release;
            checker_->check(states.data, states.rows, out, request_);
        }
        return valid;
    }

    py::list contacts(const py::handle &q) const
    {
        const StatesArgument states = statesArgument(q, *problem_, "q");
        std::vector<std::vector<rc::Contact>> found(states.rows);
        {
            py::gil_scoped_release release;
            for (std::size_t i = 0; i < states.rows; ++i)
                found[i] = checker_->contacts(states.data + i * problem_->dof(), request_);
        }
        py::list perState;
        for (const std::vector<rc::Contact> &contacts : found)
        {
            py::list list;
            for (const rc::Contact &contact : contacts)
                list.append(contactDict(*checker_, contact));
            perState.append(std::move(list));
        }
        return states.array.ndim() == 1 ? py::reinterpret_borrow<py::list>(perState[0]) : perState;
    }

    py::dict distance(const py::handle &q, double upperBound, bool penetration) const
    {
        const StatesArgument states = statesArgument(q, *problem_, "q");
        rc::DistanceRequest request;
        request.checkEnvironment = request_.checkEnvironment;
        request.checkSelfCollision = request_.checkSelfCollision;
        request.upperBound = upperBound;
        request.penetration = penetration;
        try
        {
            rc::validate(request);
        }
        catch (const rc::ConfigurationError &error)
        {
            throw py::value_error(error.what());
        }
        std::vector<rc::DistanceResult> results(states.rows);
        {
            py::gil_scoped_release release;
            checker_->distance(states.data, states.rows, request, results.data());
        }
        const py::ssize_t n = static_cast<py::ssize_t>(states.rows);
        py::array_t<double> distances(n);
        py::array_t<double> points({n, py::ssize_t{2}, py::ssize_t{3}});
        py::list components, others;
        auto d = distances.mutable_unchecked<1>();
        auto p = points.mutable_unchecked<3>();
        const rc::RobotModel &robot = checker_->robot();
        for (py::ssize_t i = 0; i < n; ++i)
        {
            const rc::DistanceResult &r = results[static_cast<std::size_t>(i)];
            d(i) = r.distance;
            const bool pair = r.kind == rc::Contact::Kind::Environment || r.kind == rc::Contact::Kind::SelfCollision;
            for (int k = 0; k < 3; ++k)
            {
                p(i, 0, k) = pair ? r.pointOnComponent[k] : std::nan("");
                p(i, 1, k) = pair ? r.pointOnOther[k] : std::nan("");
            }
            components.append(pair ? py::cast(robot.components[static_cast<std::size_t>(r.component)].name)
                                   : py::object(py::none()));
            if (!pair)
                others.append(py::none());
            else if (r.kind == rc::Contact::Kind::Environment)
                others.append(checker_->scene().objects[static_cast<std::size_t>(r.object)].name);
            else
                others.append(robot.components[static_cast<std::size_t>(r.otherComponent)].name);
        }
        py::dict answer;
        answer["distance"] = distances;
        answer["points"] = points;
        answer["component"] = components;
        answer["other"] = others;
        if (penetration)
        {
            py::array_t<double> depths(n), lowerBounds(n), directions({n, py::ssize_t{3}});
            auto depth = depths.mutable_unchecked<1>(), lower = lowerBounds.mutable_unchecked<1>();
            auto direction = directions.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < n; ++i)
            {
                const rc::Penetration &p = results[static_cast<std::size_t>(i)].penetration;
                depth(i) = p.depth;
                lower(i) = p.lowerBound;
                for (int k = 0; k < 3; ++k)
                    direction(i, k) = std::isnan(p.depth) ? std::nan("") : p.direction[k];
            }
            answer["penetration_depth"] = depths;
            answer["penetration_lower_bound"] = lowerBounds;
            answer["penetration_direction"] = directions;
        }
        return answer;
    }

    py::object checkMotions(const py::handle &a, const py::handle &b, bool certified) const
    {
        const StatesArgument from = statesArgument(a, *problem_, "a");
        const StatesArgument to = statesArgument(b, *problem_, "b");
        if (from.array.ndim() != to.array.ndim() || from.rows != to.rows)
            throw py::value_error("a and b must have the same shape, not " + shapeText(from.array) + " and " +
                                  shapeText(to.array));
        const std::size_t n = from.rows;
        py::array_t<bool> valid(static_cast<py::ssize_t>(n));
        py::array_t<double> lastValid(static_cast<py::ssize_t>(n));
        auto *verdicts = reinterpret_cast<std::uint8_t *>(valid.mutable_data());
        double *fractions = lastValid.mutable_data();
        {
            py::gil_scoped_release release;
            const og::SimpleSetup &setup = edgeSetup(certified);
            const ob::SpaceInformationPtr &si = setup.getSpaceInformation();
            const rc::ompl::StateMapping &mapping = rc::ompl::getStateValidityChecker(setup)->getStateMapping();
            const StateBlock starts(si, mapping, from.data, n), ends(si, mapping, to.data, n);
            std::vector<rc::ompl::Edge> edges(n);
            for (std::size_t i = 0; i < n; ++i)
                edges[i] = {starts[i], ends[i]};
            const auto &validator = static_cast<const rc::ompl::BatchMotionValidator &>(*si->getMotionValidator());
            validator.checkMotions(edges.data(), n, verdicts, certified ? nullptr : fractions);
        }
        if (certified)
            return std::move(valid);
        return py::make_tuple(valid, lastValid);
    }

    /** \brief Seconds per call of the C++ Checker::check on \a q, timed in C++ over \a repeats calls:
        the baseline of bench/python_overhead.py. */
    double cppSeconds(const py::handle &q, int repeats) const
    {
        const StatesArgument states = statesArgument(q, *problem_, "q");
        std::vector<std::uint8_t> valid(states.rows);
        py::gil_scoped_release release;
        const auto start = std::chrono::steady_clock::now();
        for (int r = 0; r < repeats; ++r)
            checker_->check(states.data, states.rows, valid.data(), request_);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / std::max(repeats, 1);
    }

    const PyProblemPtr &problem() const { return problem_; }
    const rc::Checker &checker() const { return *checker_; }
    const rc::CollisionRequest &request() const { return request_; }

private:
    /** \brief The planning context whose motion validator checks edges: certified, or batched (OMPL's
        discrete states at the space's resolution). Built once per kind; the GIL is not held. */
    const og::SimpleSetup &edgeSetup(bool certified) const
    {
        std::lock_guard<std::mutex> lock(edgesMutex_);
        og::SimpleSetupPtr &setup = certified ? certifiedSetup_ : batchedSetup_;
        if (!setup)
        {
            rc::ompl::SetupOptions options;
            options.existingChecker = checker_;
            options.request = request_;
            options.edges = certified ? rc::ompl::EdgeChecking::Certified : rc::ompl::EdgeChecking::Batched;
            setup = rc::ompl::makeSimpleSetup(problem_->problem, options);
            setup->getSpaceInformation()->setup();
        }
        return *setup;
    }

    PyProblemPtr problem_;
    rc::CollisionRequest request_;
    rc::CheckerOptions options_;
    std::shared_ptr<const rc::Checker> checker_;
    mutable std::mutex edgesMutex_;
    mutable og::SimpleSetupPtr certifiedSetup_;
    mutable og::SimpleSetupPtr batchedSetup_;
};

/** \brief What rastercheck.plan tells besides the path. */
struct PlanResult
{
    bool solved = false;
    std::string status;
    std::string planner;
    double time = 0.0;
    double simplifyTime = 0.0;
    std::uint64_t statesChecked = 0;
    double length = 0.0;
};

std::pair<py::array_t<double>, PlanResult> plan(const PyProblemPtr &problem, const py::object &start,
                                                const py::object &goal, const std::string &planner, double timeLimit,
                                                std::optional<long long> seed, bool simplify, const std::string &mode,
                                                double padding, const std::string &backend, int threads,
                                                const std::map<std::string, py::object> &parameters)
{
    if (!(timeLimit > 0.0) || !std::isfinite(timeLimit))
        throw py::value_error("time_limit must be a positive number of seconds");
    if (threads < 0)
        throw py::value_error("threads must be >= 0 (0 = all cores), not " + std::to_string(threads));
    const std::vector<double> from = start.is_none() ? problem->start : configurationArgument(start, *problem, "start");
    const std::vector<double> to = goal.is_none() ? problem->goal : configurationArgument(goal, *problem, "goal");
    if (from.empty() || to.empty())
        throw py::value_error("problem '" + problem->name + "' has no " + (from.empty() ? "start" : "goal") +
                              ": pass start= and goal= (load a MoveIt request with request=)");
    std::vector<std::pair<std::string, std::string>> plannerParameters;
    for (const auto &[name, value] : parameters)
        plannerParameters.emplace_back(name, py::isinstance<py::bool_>(value) ? (value.cast<bool>() ? "1" : "0")
                                                                              : py::str(value).cast<std::string>());
    if (seed)
    {
        if (*seed < 0)
            throw py::value_error("seed must be >= 0");
        // OMPL warns that a seed set after its first random numbers cannot make earlier ones
        // repeat; the planner made below draws all of its numbers after this.
        const ::ompl::msg::LogLevel level = ::ompl::msg::getLogLevel();
        ::ompl::msg::setLogLevel(::ompl::msg::LOG_NONE);
        ::ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(*seed));
        ::ompl::msg::setLogLevel(level);
    }

    // rastercheck plan's setup: makeSimpleSetup, the start and goal, the .cfg's objective, a planner by name.
    rc::ompl::SetupOptions options;
    options.checker.backend = rc::parseBackendChoice(backend);
    options.checker.threads = threads;
    options.request.mode = rc::parseCollisionMode(mode);
    options.request.padding = padding;
    rc::validate(options.request);
    PlanResult result;
    og::PathGeometric path(nullptr);
    rc::ompl::StateMappingConstPtr mapping;
    {
        py::gil_scoped_release release;
        og::SimpleSetupPtr setup = rc::ompl::makeSimpleSetup(problem->problem, options);
        const rc::ompl::StateValidityCheckerPtr validity = rc::ompl::getStateValidityChecker(*setup);
        mapping = validity->getStateMappingPtr();
        rc::ompl::setStartAndGoal(*setup, from, to);
        if (problem->problem.omplApp)
            rc::ompl::setObjective(*setup, *problem->problem.omplApp);
        ob::PlannerPtr algorithm = rc::ompl::allocatePlanner(planner, setup->getSpaceInformation());
        rc::ompl::setPlannerParameters(*algorithm, plannerParameters);
        setup->setPlanner(algorithm);
        const ob::PlannerStatus status = rc::ompl::solveWithin(*setup, timeLimit);
        result.solved = status == ob::PlannerStatus::EXACT_SOLUTION;
        result.status = status.asString();
        result.planner = algorithm->getName();
        result.time = setup->getLastPlanComputationTime();
        if (result.solved)
        {
            if (simplify)
            {
                setup->simplifySolution();
                result.simplifyTime = setup->getLastSimplificationTime();
            }
            path = setup->getSolutionPath();
            result.length = path.length();
        }
        result.statesChecked = validity->getCallCount();
        const ob::MotionValidatorPtr &edges = setup->getSpaceInformation()->getMotionValidator();
        if (auto certifiedEdges = std::dynamic_pointer_cast<rc::ompl::CertifiedMotionValidator>(edges))
            result.statesChecked += certifiedEdges->getCheckedStateCount();
        else if (auto batchedEdges = std::dynamic_pointer_cast<rc::ompl::MotionValidator>(edges))
            result.statesChecked += batchedEdges->getCheckedStateCount();
    }
    const std::size_t dof = problem->dof();
    py::array_t<double> rows({static_cast<py::ssize_t>(path.getStateCount()), static_cast<py::ssize_t>(dof)});
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
        mapping->toConfiguration(path.getState(i), rows.mutable_data(static_cast<py::ssize_t>(i)));
    return {rows, result};
}

/** \brief A str or os.PathLike argument as a path ("" for None); TypeError for anything else. */
std::string pathArgument(const py::object &path)
{
    if (path.is_none())
        return std::string();
    return py::module_::import("os").attr("fspath")(path).cast<std::string>();
}

bool fileExists(const std::string &path)
{
    struct stat info;
    return stat(path.c_str(), &info) == 0;
}
}  // namespace

PYBIND11_MODULE(rastercheck, m)
{
    m.doc() = R"doc(Collision checking for motion planning, many states at a time.

Load a problem (``load`` for a URDF robot with an SRDF, a MoveIt scene and
request, ``load_cfg`` for an OMPL.app .cfg), build a ``Checker`` over it and
hand it row-major ``(N, dof)`` float64 arrays of configurations in the
problem's ``coordinate_names`` order (radians and metres); ``plan`` runs an
OMPL planner (or rastercheck's BatchRRTConnect) on the problem. Every call
runs the C++ library with the GIL released.

Errors: a file that cannot be found raises FileNotFoundError, any other bad
input (a malformed file, an unknown option, a wrong shape, dtype or a
non-finite value) ValueError with the loader's message.)doc";

    m.attr("__version__") = RASTERCHECK_VERSION;

    py::register_exception_translator(
        [](std::exception_ptr thrown)
        {
            try
            {
                if (thrown)
                    std::rethrow_exception(thrown);
            }
            catch (const rc::InputError &e)
            {
                PyErr_SetString(!e.file().empty() && !fileExists(e.file()) ? PyExc_FileNotFoundError : PyExc_ValueError,
                                e.what());
            }
            catch (const rc::ConfigurationError &e)
            {
                PyErr_SetString(PyExc_ValueError, e.what());
            }
        });

    py::class_<PyProblem, std::shared_ptr<PyProblem>>(m, "Problem", R"doc(A loaded problem: a robot, a scene and,
where the source gives them, a start and a goal. Made by ``load`` and ``load_cfg``.)doc")
        .def_property_readonly(
            "name", [](const PyProblem &p) { return p.name; }, "Name: the .cfg's, or robot_scene_request.")
        .def_property_readonly(
            "dof", [](const PyProblem &p) { return p.dof(); }, "Number of coordinates of a configuration.")
        .def_property_readonly(
            "coordinate_names", [](const PyProblem &p) { return p.robot().coordinateNames; },
            "The coordinates of a configuration, in order (joint names; x y z qx qy qz qw for a floating "
            "joint, x y yaw for a planar one).")
        .def_property_readonly(
            "lower", [](const PyProblem &p) { return vectorArray(p.robot().lowerBounds); },
            "Lower limits of the coordinates, shape (dof,) (rad or m; -inf where unbounded).")
        .def_property_readonly(
            "upper", [](const PyProblem &p) { return vectorArray(p.robot().upperBounds); },
            "Upper limits of the coordinates, shape (dof,).")
        .def_property_readonly(
            "start", [](const PyProblem &p) { return p.start.empty() ? py::object(py::none()) : vectorArray(p.start); },
            "Start configuration, shape (dof,), or None when the problem has none.")
        .def_property_readonly(
            "goal", [](const PyProblem &p) { return p.goal.empty() ? py::object(py::none()) : vectorArray(p.goal); },
            "Goal configuration, shape (dof,), or None.")
        .def_property_readonly(
            "neutral", [](const PyProblem &p) { return vectorArray(p.robot().neutralConfiguration()); },
            "The robot's neutral configuration (zeros clamped into the limits; identity orientations).")
        .def_property_readonly(
            "components",
            [](const PyProblem &p)
            {
                std::vector<std::string> names;
                for (const rc::Component &component : p.robot().components)
                    names.push_back(component.name);
                return names;
            },
            "Names of the robot's collision components (links with collision geometry).")
        .def_property_readonly(
            "objects",
            [](const PyProblem &p)
            {
                std::vector<std::string> names;
                for (const auto &object : p.problem.scene->objects)
                    names.push_back(object.name);
                return names;
            },
            "Names of the scene's objects.")
        .def("__repr__",
             [](const PyProblem &p)
             {
                 return "<rastercheck.Problem '" + p.name + "': " + std::to_string(p.dof()) + " coordinates, " +
                        std::to_string(p.robot().components.size()) + " components, " +
                        std::to_string(p.problem.scene->objects.size()) + " objects>";
             });

    m.def(
        "load",
        [](const py::object &urdf, const py::object &srdf, const py::object &scene, const py::object &request,
           const std::vector<std::string> &packagePaths)
        {
            const std::string urdfPath = pathArgument(urdf), srdfPath = pathArgument(srdf),
                              scenePath = pathArgument(scene), requestPath = pathArgument(request);
            py::gil_scoped_release release;
            return loadRobotProblem(urdfPath, srdfPath, scenePath, requestPath, packagePaths);
        },
        py::arg("urdf"), py::arg("srdf") = py::none(), py::arg("scene") = py::none(), py::arg("request") = py::none(),
        py::arg("package_paths") = std::vector<std::string>(),
        R"doc(Loads a robot problem, as ``rastercheck plan --robot URDF --srdf SRDF --scene SCENE --request REQUEST``.

urdf: the robot. srdf: its disable_collisions pairs (optional). scene: a MoveIt
scene YAML or a mesh file, one object per node (optional: no obstacles).
request: a MoveIt MotionPlanRequest YAML whose start state and joint goal
become ``problem.start`` and ``problem.goal`` (optional). package_paths:
folders searched for package:// URIs. Raises FileNotFoundError or ValueError.)doc");

    m.def(
        "load_cfg",
        [](const py::object &path)
        {
            const std::string cfgPath = pathArgument(path);
            py::gil_scoped_release release;
            return loadCfgProblem(cfgPath);
        },
        py::arg("path"),
        R"doc(Loads an OMPL.app problem (.cfg): a rigid body (x y z qx qy qz qw, or x y yaw in 2D) in a mesh
world, with its start and goal. Raises FileNotFoundError or ValueError.)doc");

    py::class_<PyChecker>(m, "Checker", R"doc(Decides whether configurations of a problem's robot collide with its scene
or with itself. Thread safe: several Python threads may call one checker at
once (the GIL is released while it works).)doc")
        .def(py::init<PyProblemPtr, const std::string &, double, const std::string &, int>(),
             py::arg("problem").none(false), py::arg("mode") = "safe", py::arg("padding") = 0.0,
             py::arg("backend") = "auto", py::arg("threads") = 0,
             R"doc(mode: "safe" (default: never calls a colliding state valid), "exact",
"conservative" (may call a free state near an obstacle invalid) or "raster"
(the paper's method alone: may miss overlaps thinner than a pixel).
padding: solids closer than this (scene units, metres for URDF robots) collide.
backend: "auto" (CUDA when compiled in and a device is usable, else CPU),
"cpu" or "cuda". threads: worker threads of batch checks, 0 = all cores.)doc")
        .def("check", &PyChecker::check, py::arg("q"),
             R"doc(Verdicts of configurations: q of shape (N, dof) or (dof,), float64 (read in
place when C-contiguous) or another real dtype (converted). Returns a bool
array of shape (N,) (N = 1 for one configuration): True where the state is
within the limits and collision-free. Raises ValueError for another shape or
dtype and for a value that is not finite (naming its row).)doc")
        .def("contacts", &PyChecker::contacts, py::arg("q"),
             R"doc(Every colliding pair of solids at configuration q (shape (dof,)): a list of
dicts with "kind" ("environment", "self" or "out_of_bounds"), "component"
(the robot link), "object" (the scene object, or the other link), "triangle"
(of the object that the link's surface crosses, -1 when one solid contains
the other), "point" (x, y, z, world frame) and "description". Decided exactly
whatever the mode; empty for a valid state. For q of shape (N, dof), one such
list per row.)doc")
        .def("distance", &PyChecker::distance, py::arg("q"),
             py::arg("upper_bound") = std::numeric_limits<double>::infinity(), py::arg("penetration") = false,
             R"doc(Exact distances of configurations q (shape (N, dof) or (dof,)): the smallest
distance between the robot and the scene and between its self pairs that the
SRDF does not exempt (those the mode's request checks), not padded. Returns a
dict of "distance" (float array (N,): 0 where the state collides, the
upper bound where it is at least upper_bound), "points" ((N, 2, 3): a nearest
point on the component and on the other solid, world frame; NaN where no pair
is named), "component" and "other" (lists of N names, None where no pair is
named). upper_bound (> 0): stop as soon as the distance is known to reach it.
penetration=True adds how deep the pair named overlaps where a state collides
(NaN elsewhere; rastercheck::Penetration says what is measured):
"penetration_depth" ((N,): moving the component that far along
"penetration_direction" ((N, 3), world frame) frees the pair; exact for convex
solids, the convex hulls' depth otherwise) and "penetration_lower_bound" ((N,):
no shorter move frees it; equal to the depth for convex solids).
A state outside the limits has distance 0 and no pair; a value that is not
finite is a ValueError, as for check.)doc")
        .def("check_motions", &PyChecker::checkMotions, py::arg("a"), py::arg("b"), py::arg("certified") = true,
             R"doc(Straight edges from a[i] to b[i] (shapes (N, dof), or (dof,) for one edge), straight
in the planners' state space: a continuous joint turns the shorter way round.

certified=True (default): an edge is valid only when every point of it is
collision-free (rastercheck's CertifiedMotionValidator, the planners'
default; not in raster mode); returns a bool array of shape (N,).
certified=False: OMPL's discrete check, states at the space's resolution
(1 % of its extent); returns (valid, last_valid), last_valid[i] the
fraction of edge i known valid (1.0 for a valid edge).)doc")
        .def("_cpp_seconds", &PyChecker::cppSeconds, py::arg("q"), py::arg("repeats") = 1,
             "Seconds per call of the C++ Checker::check on q, timed in C++ (the baseline of "
             "examples/python/bench_overhead.py).")
        .def_property_readonly(
            "problem", [](const PyChecker &c) { return c.problem(); }, "The problem checked.")
        .def_property_readonly(
            "backend", [](const PyChecker &c) { return c.checker().backendName(); },
            "\"cpu\" or \"cuda (<device>)\": where batches run.")
        .def_property_readonly(
            "mode", [](const PyChecker &c) { return rc::toString(c.request().mode); }, "The collision mode.")
        .def_property_readonly(
            "padding", [](const PyChecker &c) { return c.request().padding; }, "The padding.")
        .def_property_readonly(
            "dof", [](const PyChecker &c) { return c.problem()->dof(); }, "Coordinates per configuration.")
        .def("__repr__",
             [](const PyChecker &c)
             {
                 std::ostringstream text;
                 text << "<rastercheck.Checker of '" << c.problem()->name << "': mode "
                      << rc::toString(c.request().mode) << ", padding " << c.request().padding << ", backend "
                      << c.checker().backendName() << ">";
                 return text.str();
             });

    py::class_<PlanResult>(m, "PlanResult", "What plan() reports besides the path.")
        .def_readonly("solved", &PlanResult::solved, "True when the path reaches the goal (an exact solution).")
        .def_readonly("status", &PlanResult::status, "OMPL's planner status, as text.")
        .def_readonly("planner", &PlanResult::planner, "The planner's name.")
        .def_readonly("time", &PlanResult::time, "Seconds spent planning (without simplification).")
        .def_readonly("simplify_time", &PlanResult::simplifyTime, "Seconds spent simplifying the path.")
        .def_readonly("states_checked", &PlanResult::statesChecked,
                      "States decided: by the state validity checker and by the edge checker.")
        .def_readonly("length", &PlanResult::length, "Length of the path in the state space's metric.")
        .def("__repr__",
             [](const PlanResult &r)
             {
                 std::ostringstream text;
                 text << "PlanResult(solved=" << (r.solved ? "True" : "False") << ", planner='" << r.planner
                      << "', time=" << r.time << ", simplify_time=" << r.simplifyTime
                      << ", states_checked=" << r.statesChecked << ", length=" << r.length << ")";
                 return text.str();
             });

    m.def("plan", &plan, py::arg("problem").none(false), py::arg("start") = py::none(), py::arg("goal") = py::none(),
          py::arg("planner") = "batchrrtconnect", py::arg("time_limit") = 1.0, py::arg("seed") = py::none(),
          py::arg("simplify") = true, py::arg("mode") = "safe", py::arg("padding") = 0.0, py::arg("backend") = "auto",
          py::arg("threads") = 0, py::arg("params") = std::map<std::string, py::object>(),
          R"doc(Plans from start to goal (default: the problem's) as ``rastercheck plan`` does
one run: certified edges (collision-free at every point), the given planner
by its OMPL.app name ("batchrrtconnect", "rrtconnect", "rrt", "prm",
"kpiece", ...; ``planners()`` lists them) with ``params`` (name -> value)
and, for a .cfg, its objective. seed: OMPL's random seed (repeatable runs).
mode, padding, backend, threads: as Checker.

Returns (path, result): path of shape (M, dof) from start to goal (simplified
unless simplify=False; shape (0, dof) when unsolved) and a PlanResult
(solved, time, states_checked, ...).)doc");

    m.def(
        "planners", []() { return rc::ompl::knownPlannerNames(); }, "Names plan() accepts.");
}
