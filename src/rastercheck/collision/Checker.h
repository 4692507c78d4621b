#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rastercheck/collision/Backend.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/collision/CollisionRequest.h"
#include "rastercheck/collision/CpuBackend.h"
#include "rastercheck/collision/Distance.h"

namespace rastercheck
{
/** \brief Which backend runs the pipeline; chosen once at construction, never mid-planning. */
enum class BackendChoice
{
    Auto,  ///< CUDA when compiled in and a device is usable, else CPU (with a one-line notice)
    Cpu,
    Cuda,  ///< like Auto, but warns when it has to fall back to the CPU
    /** \brief The GPU's batched stages on the host executor: the device's code path, batch sizes and
        calls on any machine, for tests and for debugging a device setup without a device. Slower
        than Cpu; never chosen by Auto. */
    HostStages
};

/** \brief "auto", "cpu", "cuda" or "host-stages"; throws ConfigurationError otherwise. */
BackendChoice parseBackendChoice(const std::string &text);

/** \brief CheckerOptions::minDeviceBatch's automatic value per CPU thread. */
constexpr std::size_t kDeviceBatchPerCpuThread = 4096;

struct CheckerOptions
{
    BackendChoice backend = BackendChoice::Auto;
    /** \brief Worker threads of batch calls on the CPU backend; 0 = all cores. Batches run on
        OpenMP, whose threads spin at each batch's end (libgomp's default): processes that share
        cores should each take fewer threads, or run with OMP_WAIT_POLICY=passive (two programs of
        all cores each on two cores decided small batches up to 15x slower, spinning for threads
        the other held). */
    int threads = 0;
    /** \brief Smallest batch sent to the GPU backend (or the host stages): a smaller one (a single
        isValid, a short motion, a planner's round) runs on the CPU backend, where it does not pay
        the GPU pass's fixed latency. 0 = kDeviceBatchPerCpuThread times the CPU threads batches
        would use (threads, or every core): where the device starts to beat those threads (an H100
        against 16 cores, 2026-11-26: a pass costs 4.5 ms from 1 000 to 10 000 Panda states, the two
        are even near 10^5; docs/benchmarks.md "GPU"). */
    std::size_t minDeviceBatch = 0;
    /** \brief Most device memory, in bytes, the GPU backend's batch buffers may take (the model
        comes on top); 0 = half the memory free when the checker is built. A batch that needs more
        is split into passes that fit, with the same verdicts; so is one that meets a device
        filled by other programs. */
    std::size_t deviceMemoryLimit = 0;
};

/** \brief Decides whether robot configurations collide with the scene or themselves, one state or
    a batch at a time. Immutable after construction; every method is thread-safe (each call uses
    its own pooled scratch). Checkers of one robot (or of robots loaded apart with the same content)
    share what depends on the robot alone, built with the first of them: a checker per scene costs
    about the scene's part (CollisionModel). */
class Checker
{
public:
    Checker(RobotModelConstPtr robot, SceneConstPtr scene, const CheckerOptions &options = {});
    ~Checker();

    /** \brief Decides \a n states. \a q: n x dof values in the robot's coordinate order (row-major).
        \a valid[i] = 1 when state i is valid. \a contacts (optional, n entries) receives each
        invalid state's first contact. Never throws for bad states: they are invalid (a state with a
        NaN or infinite coordinate is Contact::Kind::OutOfBounds, and the first such state a checker
        sees is named in one warning). Throws ConfigurationError for a malformed \a request
        (validate(), or a pairPadding whose sizes do not fit the model). With an empty scene only
        self-collision is checked. */
    void check(const double *q, std::size_t n, std::uint8_t *valid, const CollisionRequest &request = {},
               Contact *contacts = nullptr) const;

    /** \brief Decides \a n states at two paddings at once: the request's own, and wider ones, the
        request's plus row i of \a wider for state i (PairPadding: one row for all states or one per
        state; entries finite and >= 0). \a verdicts[i] is a PaddedVerdict: Clear (clear at the wider
        paddings), Near (clear at the request's, not at the wider ones) or Collides (at the
        request's). The same verdicts as check() at the wider paddings and then at the request's for
        the states that missed them, in about one check's time on the CPU backend: a pair nearer
        than its wider padding is tried at its own at once, and the pairs after it only at theirs
        (in raster mode it is those two checks; on the GPU stages one pass of twice the states, up to
        StagedBackend::kTwoPaddingsInOnePassMost). Certified edges ask
        it of every midpoint: clear by its interval's sweep, or at least valid. Throws as check(),
        and for a \a wider that does not fit the model or the batch. */
    void checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts, const CollisionRequest &request,
                          const PairPadding &wider) const;

    /** \brief One state. */
    bool isValid(const double *q, const CollisionRequest &request = {}, Contact *contact = nullptr) const;
    /** \brief One state; throws ConfigurationError when \a q does not have dof() values (reading past
        a short vector would decide garbage). */
    bool isValid(const std::vector<double> &q, const CollisionRequest &request = {}, Contact *contact = nullptr) const;

    /** \brief "cpu" or "cuda (<device>)". */
    std::string backendName() const { return backend_->name(); }
    /** \brief The backend batches of at least minDeviceBatch states run on. */
    const Backend &backend() const { return *backend_; }
    /** \brief The smallest batch that runs on the GPU backend (or the host stages): the options'
        minDeviceBatch, or its automatic value; 0 when every batch runs on the CPU backend. What a
        caller that can choose its batch sizes (BatchRRTConnect) sizes them by. */
    std::size_t deviceBatch() const { return usesStages_ ? minDeviceBatch_ : 0; }
    /** \brief Whether a batch of \a states runs on the GPU backend (or the host stages): at least
        deviceBatch() states, where that is not 0. */
    bool reachesDevice(std::size_t states) const { return usesStages_ && states >= minDeviceBatch_; }
    const CollisionModel &collisionModel() const { return *model_; }
    /** \brief The same model, shared (to build another backend over it without rebuilding it). */
    CollisionModelConstPtr collisionModelPtr() const { return model_; }
    const RobotModel &robot() const { return *model_->robot; }
    const Scene &scene() const { return *model_->scene; }
    std::size_t dof() const { return model_->robot->numCoordinates(); }

    /** \brief Every contact of state \a q, for viewers and diagnostics: one per pair of solids that
        collides (components against scene objects, then self pairs, in CollisionModel's pair
        order), each that pair's first contact by the exact narrow phase with the request's padding
        (and its pairPadding entry): the component, the object (or other component), the triangle
        of the object (or other component) that the component's surface crosses, -1 when one solid
        contains the other, and a point of the contact in the world frame. check() stops at a
        state's first contact; this decides every pair the request covers (checkEnvironment,
        checkSelfCollision), exactly whatever the request's mode: the list is not empty exactly
        when safe and exact mode call the state invalid (conservative mode may also call a free
        state invalid, raster mode may miss a thin overlap). Empty for a free state; a single
        Contact::Kind::OutOfBounds entry for a state outside the bounds or not finite. Costs one
        exact query per pair: about 0.4 ms for a colliding state of the crane in the plant (909
        component-object pairs), 0.1 to 0.2 ms for the Panda in a MotionBenchMaker bookshelf
        (docs/viewer.md). Thread-safe. */
    std::vector<Contact> contacts(const double *q, const CollisionRequest &request = {}) const;

    /** \brief The smallest distance at state \a q between the robot and the scene and between its
        non-exempt self pairs (\a request says which), with the pair, a closest pair of points and
        the triangles they lie on: exact for meshes, primitives and mixed pairs (DistanceQueries);
        0 and a contact when the state collides. With a finite DistanceRequest::upperBound the query
        stops as soon as it knows the distance reaches it (\a result capped). A state outside the
        bounds or not finite is OutOfBounds (named in the checker's one warning). Throws
        ConfigurationError for a bad request. Thread-safe. */
    void distance(const double *q, const DistanceRequest &request, DistanceResult *result) const;
    /** \brief \a n states (n x dof, row-major) into \a results (n entries), over the checker's CPU
        threads (CheckerOptions::threads). */
    void distance(const double *q, std::size_t n, const DistanceRequest &request, DistanceResult *results) const;

    /** \brief Conservative advancement's step at \a n states (DistanceQueries::freeRadius): per
        state the largest t up to caps[i] for which every pair the request checks, closing in at its
        rate (\a rates, laid out as a PairPadding: one row or one per state) for t, stays farther
        apart than its padding; 0 for a state within its padding or outside the bounds. Exact
        (\a measure Exact), or a step no longer sized by the hulls' lower bounds (HullBound), over
        the checker's CPU threads. Throws ConfigurationError for a bad request or rates (negative,
        not finite, or not one row or n rows of the model's components and self pairs). */
    void freeRadius(const double *q, std::size_t n, const CollisionRequest &request, const PairPadding &rates,
                    const double *caps, double *radii, ClearanceMeasure measure = ClearanceMeasure::Exact) const;

    /** \brief "panda_link5 vs object 'box_3' at 0.0421 (0.41, 0.02, 0.33) - (0.43, 0.05, 0.33)". */
    std::string describe(const DistanceResult &result) const;

    /** \brief The raster image of the pair named by \a contact at state \a q (CPU pipeline; for
        pictures such as the paper's Fig. 6). False when the contact names no pair. */
    bool rasterImage(const double *q, const Contact &contact, const CollisionRequest &request,
                     RasterImage &image) const;

    /** \brief Human-readable description of a contact: "panda_link5 vs object 'box_3' triangle 7 at
        (0.41, 0.02, 0.33)". */
    std::string describe(const Contact &contact) const;

private:
    /** \brief validate(), and a pairPadding that fits this checker's model and a batch of \a states. */
    void validateRequest(const CollisionRequest &request, std::size_t states) const;
    /** \brief Throws ConfigurationError, naming \a name, unless \a rows has one row or \a states rows
        of this model's components and self pairs. */
    void validateRows(const PairPadding &rows, const std::string &name, std::size_t states) const;
    void warnOnceIfNotFinite(const double *q, std::size_t n) const;
    void nameCoordinatesOutOfBounds(const double *q, std::size_t n, Contact *contacts) const;

    CollisionModelConstPtr model_;
    std::unique_ptr<Backend> backend_;
    CpuBackend reference_;  // pictures and diagnostics run the CPU pipeline whatever the backend
    DistanceQueries distances_;
    int threads_;
    std::size_t minDeviceBatch_;
    bool usesStages_ = false;  // backend_ is the batched stages (GPU or host), not the CPU backend
    mutable std::atomic<bool> warnedNotFinite_{false};  // one warning per checker, not one per state
};
}  // namespace rastercheck
