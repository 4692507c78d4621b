#include "rastercheck/collision/Checker.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <thread>

#include "rastercheck/BuildConfig.h"
#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/collision/StagedBackend.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#if RASTERCHECK_WITH_CUDA
#include "CudaStageRunner.h"
#endif

namespace rastercheck
{
BackendChoice parseBackendChoice(const std::string &text)
{
    if (text == "auto")
        return BackendChoice::Auto;
    if (text == "cpu")
        return BackendChoice::Cpu;
    if (text == "cuda")
        return BackendChoice::Cuda;
    if (text == "host-stages")
        return BackendChoice::HostStages;
    throw ConfigurationError("unknown backend '" + text + "' (expected auto, cpu, cuda or host-stages)");
}

namespace
{
/** \brief The CUDA backend when the build has it and a device can run it; null otherwise, with
    the reason in \a why. */
std::unique_ptr<Backend> makeCudaBackend(const CollisionModelConstPtr &model, std::size_t memoryLimit, std::string &why)
{
#if RASTERCHECK_WITH_CUDA
    std::string device;
    if (!cuda::deviceUsable(device))
    {
        why = device;
        return nullptr;
    }
    try
    {
        auto backend =
            std::make_unique<StagedBackend>(model, cuda::makeStageRunner(hostModelArrays(*model), memoryLimit));
        logInfo("using the CUDA backend on " + device);
        return backend;
    }
    catch (const std::exception &e)
    {
        why = e.what();
        return nullptr;
    }
#else
    (void)model;
    (void)memoryLimit;
    why = "this build has no CUDA backend";
    return nullptr;
#endif
}
}  // namespace

Checker::Checker(RobotModelConstPtr robot, SceneConstPtr scene, const CheckerOptions &options)
    : model_(std::make_shared<const CollisionModel>(std::move(robot), std::move(scene))),
      reference_(model_),
      distances_(model_),
      threads_(options.threads),
      minDeviceBatch_(options.minDeviceBatch > 0
                          ? options.minDeviceBatch
                          : kDeviceBatchPerCpuThread * static_cast<std::size_t>(options.threads > 0
                                                                                  ? options.threads
                                                                                  : std::max(1u, std::thread::hardware_concurrency())))
{
    if (options.threads < 0)
        throw ConfigurationError("CheckerOptions::threads must be >= 0 (0 = all cores)");
    if (options.backend == BackendChoice::HostStages)
        backend_ = std::make_unique<StagedBackend>(model_, makeHostStageRunner(model_));
    else if (options.backend != BackendChoice::Cpu)
    {
        std::string why;
        backend_ = makeCudaBackend(model_, options.deviceMemoryLimit, why);
        if (!backend_)
        {
            const std::string notice = why + "; using the CPU backend";
            // Asked for CUDA: warn every time. Auto: say it once per process, not per checker.
            if (options.backend == BackendChoice::Cuda)
                logWarning(notice);
            else
                logOnce(LogLevel::Info, notice);
        }
    }
    usesStages_ = backend_ != nullptr;
    if (!backend_)
        backend_ = std::make_unique<CpuBackend>(model_);
}

Checker::~Checker() = default;

// A NaN usually means a bug upstream (a planner, a CSV column of blanks read as NaN); the verdict
// alone would hide it among real collisions, so the first one is named.
void Checker::warnOnceIfNotFinite(const double *q, std::size_t n) const
{
    if (warnedNotFinite_.load(std::memory_order_relaxed))
        return;
    const std::size_t dof = this->dof();
    for (std::size_t i = 0; i < n * dof; ++i)
        if (!std::isfinite(q[i]))
        {
            if (!warnedNotFinite_.exchange(true))
                logWarning((n > 1 ? "state " + std::to_string(i / dof) + " of " + std::to_string(n) : "a state") +
                           " has coordinate '" + model_->robot->coordinateNames[i % dof] +
                           "' = " + std::to_string(q[i]) +
                           ": a state that is not finite is invalid (reported once per checker)");
            return;
        }
}

void Checker::validateRequest(const CollisionRequest &request, std::size_t states) const
{
    validate(request);
    if (request.pairPadding)
        validateRows(*request.pairPadding, "CollisionRequest::pairPadding", states);
}

void Checker::validateRows(const PairPadding &rows, const std::string &name, std::size_t states) const
{
    if (rows.rows != 1 && rows.rows != states)
        throw ConfigurationError(name + " has " + std::to_string(rows.rows) + " rows for " + std::to_string(states) +
                                 " state(s); give one row for all states or one per state");
    if (rows.environment.size() != rows.rows * model_->numComponents() ||
        rows.self.size() != rows.rows * model_->selfPairs.size())
        throw ConfigurationError(name + " has " + std::to_string(rows.environment.size()) + " component and " +
                                 std::to_string(rows.self.size()) + " self-pair entries in " +
                                 std::to_string(rows.rows) + " row(s); robot '" + robot().name + "' has " +
                                 std::to_string(model_->numComponents()) + " components and " +
                                 std::to_string(model_->selfPairs.size()) + " self pairs per row");
}

void Checker::check(const double *q, std::size_t n, std::uint8_t *valid, const CollisionRequest &request,
                    Contact *contacts) const
{
    validateRequest(request, n);
    warnOnceIfNotFinite(q, n);
    const Backend &backend = n >= minDeviceBatch_ ? *backend_ : static_cast<const Backend &>(reference_);
    backend.check(q, n, valid, contacts, request, threads_);
    nameCoordinatesOutOfBounds(q, n, contacts);
}

void Checker::checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts, const CollisionRequest &request,
                               const PairPadding &wider) const
{
    validateRequest(request, n);
    validateRows(wider, "checkTwoPaddings' wider paddings", n);
    validateEntries(wider, "checkTwoPaddings' wider paddings");
    warnOnceIfNotFinite(q, n);
    const Backend &backend = n >= minDeviceBatch_ ? *backend_ : static_cast<const Backend &>(reference_);
    if (backend.checkTwoPaddings(q, n, verdicts, request, wider, threads_))
        return;

    // Two passes: every state at the wider paddings (the request's pair paddings plus wider's, row
    // by row, as PairPaddings adds them), then the states that missed them at the request's own.
    const std::size_t components = model_->numComponents(), selfPairs = model_->selfPairs.size();
    const PairPadding *own = request.pairPadding.get();
    auto outer = std::make_shared<PairPadding>();
    appendPaddingRows(*model_, own, &wider, wider.rows > 1 || (own && own->rows > 1) ? n : 1, *outer);
    CollisionRequest wide = request;
    wide.pairPadding = std::move(outer);
    check(q, n, verdicts, wide);

    std::vector<std::size_t> missed;
    for (std::size_t i = 0; i < n; ++i)
        if (!verdicts[i])
            missed.push_back(i);
    if (missed.empty())
        return;
    const std::size_t coordinates = dof();
    std::vector<double> rows(missed.size() * coordinates);
    for (std::size_t k = 0; k < missed.size(); ++k)
        std::copy_n(q + missed[k] * coordinates, coordinates,
                    rows.begin() + static_cast<std::ptrdiff_t>(k * coordinates));
    CollisionRequest narrow = request;
    if (own && own->rows > 1)
    {
        auto picked = std::make_shared<PairPadding>();
        picked->rows = missed.size();
        for (const std::size_t i : missed)
        {
            picked->environment.insert(picked->environment.end(),
                                       own->environment.begin() + static_cast<std::ptrdiff_t>(i * components),
                                       own->environment.begin() + static_cast<std::ptrdiff_t>((i + 1) * components));
            picked->self.insert(picked->self.end(), own->self.begin() + static_cast<std::ptrdiff_t>(i * selfPairs),
                                own->self.begin() + static_cast<std::ptrdiff_t>((i + 1) * selfPairs));
        }
        narrow.pairPadding = std::move(picked);
    }
    std::vector<std::uint8_t> valid(missed.size());
    check(rows.data(), missed.size(), valid.data(), narrow);
    for (std::size_t k = 0; k < missed.size(); ++k)
        verdicts[missed[k]] = static_cast<std::uint8_t>(valid[k] ? PaddedVerdict::Near : PaddedVerdict::Collides);
}

// The backends only say that a state is out of bounds; which coordinate is asked of the model here,
// off the hot path (such states are rare, and their verdict needs no more).
void Checker::nameCoordinatesOutOfBounds(const double *q, std::size_t n, Contact *contacts) const
{
    if (!contacts)
        return;
    for (std::size_t i = 0; i < n; ++i)
        if (contacts[i].kind == Contact::Kind::OutOfBounds)
            contacts[i].coordinate = model_->firstInadmissibleCoordinate(q + i * dof());
}

bool Checker::isValid(const double *q, const CollisionRequest &request, Contact *contact) const
{
    validateRequest(request, 1);
    warnOnceIfNotFinite(q, 1);
    std::uint8_t valid = 0;
    const Backend &backend = minDeviceBatch_ <= 1 ? *backend_ : static_cast<const Backend &>(reference_);
    backend.check(q, 1, &valid, contact, request, 1);
    nameCoordinatesOutOfBounds(q, 1, contact);
    return valid != 0;
}

bool Checker::isValid(const std::vector<double> &q, const CollisionRequest &request, Contact *contact) const
{
    if (q.size() != dof())
        throw ConfigurationError("Checker::isValid: the configuration has " + std::to_string(q.size()) +
                                 " values, robot '" + robot().name + "' has " + std::to_string(dof()) + " coordinates");
    return isValid(q.data(), request, contact);
}

std::vector<Contact> Checker::contacts(const double *q, const CollisionRequest &request) const
{
    validateRequest(request, 1);
    warnOnceIfNotFinite(q, 1);
    const CollisionModel &model = *model_;
    if (!model.configurationAdmissible(q))
    {
        Contact outOfBounds;
        outOfBounds.kind = Contact::Kind::OutOfBounds;
        outOfBounds.coordinate = model.firstInadmissibleCoordinate(q);
        return {outOfBounds};
    }
    std::unique_ptr<CpuWorkspace> workspace = reference_.borrow();
    reference_.refitState(q, *workspace);
    CollisionRequest exact = request;
    exact.mode = CollisionMode::Exact;
    const std::size_t environmentPairs = model.numObjects() * model.numComponents();
    std::vector<Contact> found;
    for (std::uint32_t pair = 0; pair < model.numPairs(); ++pair)
    {
        const bool environment = pair < environmentPairs;
        if (environment ? !request.checkEnvironment : !request.checkSelfCollision)
            continue;
        Contact contact;
        if (reference_.decideOpenPair(pair, exact, *workspace, contact))
            found.push_back(contact);
    }
    reference_.giveBack(std::move(workspace));
    return found;
}

void Checker::freeRadius(const double *q, std::size_t n, const CollisionRequest &request, const PairPadding &rates,
                         const double *caps, double *radii, ClearanceMeasure measure) const
{
    validateRequest(request, n);
    validateEntries(rates, "Checker::freeRadius: the rates");
    validateRows(rates, "Checker::freeRadius: the rates", n);
    warnOnceIfNotFinite(q, n);
    distances_.freeRadius(q, n, request, rates, caps, radii, n > 1 ? threads_ : 1, measure);
}

void Checker::distance(const double *q, const DistanceRequest &request, DistanceResult *result) const
{
    distance(q, 1, request, result);
}

void Checker::distance(const double *q, std::size_t n, const DistanceRequest &request, DistanceResult *results) const
{
    warnOnceIfNotFinite(q, n);
    distances_.distance(q, n, results, request, n > 1 ? threads_ : 1);
}

std::string Checker::describe(const DistanceResult &result) const
{
    if (result.kind == Contact::Kind::None || result.kind == Contact::Kind::OutOfBounds)
    {
        Contact contact;
        contact.kind = result.kind;
        contact.coordinate = result.coordinate;
        if (result.kind == Contact::Kind::OutOfBounds)
            return describe(contact);
        std::ostringstream text;
        text << (result.capped ? "at least " : "") << result.distance;
        return text.str();
    }
    const RobotModel &robot = *model_->robot;
    std::ostringstream text;
    text << robot.components[result.component].name << " vs ";
    if (result.kind == Contact::Kind::Environment)
        text << "object '" << model_->scene->objects[result.object].name << "'";
    else
        text << robot.components[result.otherComponent].name;
    const Eigen::Vector3d &a = result.pointOnComponent, &b = result.pointOnOther;
    text << " at " << result.distance << " (" << a.x() << ", " << a.y() << ", " << a.z() << ") - (" << b.x() << ", "
         << b.y() << ", " << b.z() << ")";
    return text.str();
}

bool Checker::rasterImage(const double *q, const Contact &contact, const CollisionRequest &request,
                          RasterImage &image) const
{
    validateRequest(request, 1);
    return reference_.rasterImage(q, contact, request, image);
}

std::string Checker::describe(const Contact &contact) const
{
    std::ostringstream text;
    const RobotModel &robot = *model_->robot;
    auto componentName = [&](int c) { return c >= 0 ? robot.components[c].name : std::string("?"); };
    switch (contact.kind)
    {
        case Contact::Kind::None:
            return "valid";
        case Contact::Kind::OutOfBounds:
            if (contact.coordinate >= 0 && static_cast<std::size_t>(contact.coordinate) < robot.numCoordinates())
                return "coordinate '" + robot.coordinateNames[contact.coordinate] + "' out of bounds or not finite";
            return "out of bounds or not finite";
        case Contact::Kind::Environment:
            text << componentName(contact.component) << " vs object '"
                 << (contact.object >= 0 ? model_->scene->objects[contact.object].name : std::string("?")) << "'";
            break;
        case Contact::Kind::SelfCollision:
            text << componentName(contact.component) << " vs " << componentName(contact.otherComponent);
            break;
    }
    if (contact.triangle >= 0)
        text << " triangle " << contact.triangle;
    else
        text << " (containment)";
    text << " at (" << contact.position.x() << ", " << contact.position.y() << ", " << contact.position.z() << ")";
    return text.str();
}
}  // namespace rastercheck
