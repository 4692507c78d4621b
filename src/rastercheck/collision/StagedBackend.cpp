#include "rastercheck/collision/StagedBackend.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <deque>
#include <mutex>
#include <new>
#include <numeric>
#include <string>
#include <type_traits>

#include <sys/mman.h>
#include <unistd.h>

#include "rastercheck/collision/ModeRules.h"
#include "rastercheck/collision/PassRecorder.h"
#include "rastercheck/collision/StageChunks.h"

namespace rastercheck
{
device::ModelArrays hostModelArrays(const CollisionModel &model)
{
    static_assert(sizeof(std::pair<int, int>) == 2 * sizeof(int), "self pairs are read as int[2]");
    const RobotModel &robot = *model.robot;
    return device::ModelArrays{robot.kinematicJoints.data(),
                               static_cast<int>(robot.kinematicJoints.size()),
                               static_cast<int>(robot.links.size()),
                               static_cast<int>(robot.numCoordinates()),
                               model.componentVertices.data(),
                               model.componentVertices.size(),
                               model.componentTriangles.data(),
                               model.componentTriangles.size(),
                               model.components.data(),
                               model.componentLocalBoxes.data(),
                               model.componentLink.data(),
                               model.componentSubtreeEnd.data(),
                               static_cast<int>(model.numComponents()),
                               model.objectVertices.data(),
                               model.objectVertices.size(),
                               model.objectTriangles.data(),
                               model.objectTriangles.size(),
                               model.objects.data(),
                               model.objectBoxes.data(),
                               model.objectOrientedBoxes.data(),
                               static_cast<int>(model.numObjects()),
                               reinterpret_cast<const int *>(model.selfPairs.data()),
                               static_cast<int>(model.selfPairs.size()),
                               {model.origin.x(), model.origin.y(), model.origin.z()},
                               model.convex.arrays(),
                               model.convex.numVertexDoubles(),
                               model.convex.numHullPointDoubles(),
                               model.convex.numAllPieces(),
                               model.convex.numPlaneDoubles(),
                               model.convex.numEdgeIndices(),
                               model.convex.numSupportCellOffsets(),
                               model.convex.numSupportCandidates(),
                               model.convex.numPatchNodes(),
                               model.convex.numPatches(),
                               model.convex.numPatchTriangleIndices(),
                               model.componentTrees.nodes.data(),
                               model.componentTrees.nodes.size(),
                               model.componentTrees.triangleOrder.data(),
                               model.objectTrees.nodes.data(),
                               model.objectTrees.nodes.size(),
                               model.objectTrees.triangleOrder.data(),
                               model.componentTrees.exactArrays(),
                               model.objectTrees.exactArrays(),
                               model.componentTrees.gridCells.size(),
                               model.componentTrees.probePoints.size(),
                               model.componentTrees.shellProbeStart.size(),
                               model.objectTrees.gridCells.size(),
                               model.objectTrees.probePoints.size(),
                               model.objectTrees.shellProbeStart.size(),
                               model.curved.refinedPairs().data(),
                               model.curved.refinedPairs().size(),
                               model.curved.arrays(),
                               model.curved.shapes().size(),
                               model.objectTreePlacement,
                               model.selfPairTables.arrays(),
                               model.selfPairTables.numTables(),
                               model.selfPairTables.numNodes()};
}

void copyInParallel(void *to, const void *from, std::size_t bytes)
{
    constexpr std::size_t kPiece = std::size_t(1) << 18;
    if (bytes == 0)
        return;  // memcpy may not be handed a null pointer, even for no bytes
    if (bytes < 4 * kPiece)
    {
        std::memcpy(to, from, bytes);
        return;
    }
    const auto pieces = static_cast<std::ptrdiff_t>((bytes + kPiece - 1) / kPiece);
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t k = 0; k < pieces; ++k)
    {
        const std::size_t start = static_cast<std::size_t>(k) * kPiece;
        std::memcpy(static_cast<char *>(to) + start, static_cast<const char *>(from) + start,
                    std::min(kPiece, bytes - start));
    }
}

device::StageSettings stageSettings(const CollisionModel &model, const CollisionRequest &request, bool contactsAsked)
{
    device::StageSettings settings{};
    settings.padding = std::max(0.0, request.padding);
    if (const PairPadding *extra = request.pairPadding.get())
        settings.extraPadding = device::PairPaddingRows{extra->environment.data(), extra->self.data(), extra->rows > 1};
    settings.pixel = static_cast<float>(request.pixelSize > 0 ? request.pixelSize : model.defaultPixelSize);
    settings.maxImageSide = request.maxImageSide;
    settings.checkEnvironment = request.checkEnvironment;
    settings.checkSelfCollision = request.checkSelfCollision;
    const ModeRules rules = modeRules(request.mode, contactsAsked);
    settings.rasterize = rules.rasterInStages;
    settings.confirmMisses = rules.confirmRasterMisses;
    settings.proveOverlaps = rules.proveOverlaps;
    settings.meshObstaclesUnproven = rules.meshObstaclesExact;
    settings.unprovenCollides = rules.unprovenCollides;
    settings.clearanceTables = rules.clearanceTables;
    settings.confirmCurvedOverlaps = request.mode == CollisionMode::Safe || request.mode == CollisionMode::Exact;
    settings.firstContacts = contactsAsked;
    return settings;
}

namespace
{
/** \brief What the host executor compiles of a pass: nothing (its operations run again). */
struct NoGraph
{
};

/** \brief Pages that only the host executor's operations may touch (HostScratch::Guarded): one
    reserved range of address space, handed out page by page and kept PROT_NONE except while some
    operation runs (an Open scope; nested and concurrent scopes are counted, and the last to close
    shuts the range again). One range, so that opening and closing is one mprotect each. Released
    pages go back to the system but not to the range (a test's few hundred megabytes at most). */
class GuardedPages
{
public:
    static void *allocate(std::size_t bytes)
    {
        State &state = instance();
        const std::lock_guard<std::mutex> lock(state.mutex);
        const std::size_t size = pageRound(bytes);
        if (!state.base || size > kReserved - state.used)
            throw std::bad_alloc();
        unsigned char *pages = state.base + state.used;
        state.used += size;
        mprotect(pages, size, state.open > 0 ? PROT_READ | PROT_WRITE : PROT_NONE);
        return pages;
    }

    static void release(void *pages, std::size_t bytes)
    {
        State &state = instance();
        const std::lock_guard<std::mutex> lock(state.mutex);
        madvise(pages, pageRound(bytes), MADV_DONTNEED);
    }

    /** \brief Every guarded page readable and writable while it lives (where \a on). */
    class Open
    {
    public:
        explicit Open(bool on) : on_(on)
        {
            if (on_)
                shift(+1);
        }
        ~Open()
        {
            if (on_)
                shift(-1);
        }
        Open(const Open &) = delete;
        Open &operator=(const Open &) = delete;

    private:
        static void shift(int by)
        {
            State &state = instance();
            const std::lock_guard<std::mutex> lock(state.mutex);
            const bool wasOpen = state.open > 0;
            state.open += by;
            if (wasOpen != (state.open > 0) && state.used > 0)
                mprotect(state.base, state.used, state.open > 0 ? PROT_READ | PROT_WRITE : PROT_NONE);
        }
        bool on_;
    };

private:
    static constexpr std::size_t kReserved = std::size_t{1} << 32;  // address space, not memory

    struct State
    {
        State()
        {
            void *range = mmap(nullptr, kReserved, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
            base = range == MAP_FAILED ? nullptr : static_cast<unsigned char *>(range);
        }
        std::mutex mutex;
        unsigned char *base = nullptr;
        std::size_t used = 0;
        int open = 0;
    };
    static State &instance()
    {
        static State state;
        return state;
    }
    static std::size_t pageRound(std::size_t bytes)
    {
        const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
        return std::max(page, (bytes + page - 1) / page * page);
    }
};

/** \brief A scratch buffer of the host executor: plain memory, or guarded pages. Its contents do
    not survive growth (a stage writes what it reads; HostScratch::Poisoned tests that). */
class ScratchBytes
{
public:
    ScratchBytes() = default;
    ~ScratchBytes() { release(); }
    ScratchBytes(const ScratchBytes &) = delete;
    ScratchBytes &operator=(const ScratchBytes &) = delete;

    unsigned char *data() const { return data_; }
    std::size_t size() const { return size_; }
    /** \brief \a bytes of zeros, in guarded pages where \a guarded. */
    void allocate(std::size_t bytes, bool guarded)
    {
        release();
        data_ = guarded ? static_cast<unsigned char *>(GuardedPages::allocate(bytes)) : new unsigned char[bytes]();
        size_ = bytes;
        guarded_ = guarded;
    }
    void release()
    {
        if (!data_)
            return;
        if (guarded_)
            GuardedPages::release(data_, size_);
        else
            delete[] data_;
        data_ = nullptr;
        size_ = 0;
    }

private:
    unsigned char *data_ = nullptr;
    std::size_t size_ = 0;
    bool guarded_ = false;
};

/** \brief The stages' primitives as host loops (OpenMP), for running the GPU's driver on the CPU.
    Its memory is the host's, so copies need no mirrors and waits wait for nothing, but it counts
    launches and waits where the CUDA executor makes them. */
class HostExecutor
{
public:
    HostExecutor(HostScratch scratch, std::size_t maxScratchBytes, HostLoop loop)
        : scratch_(scratch), maxScratchBytes_(maxScratchBytes), loop_(loop)
    {
    }

    template <class T>
    T *buffer(int slot, std::size_t count)
    {
        ScratchBytes &storage = buffers_[static_cast<std::size_t>(slot)];
        const std::size_t need = count * sizeof(T);
        if (storage.size() < need || !storage.data())
        {
            const std::size_t room = scratchRoom(maxScratchBytes_, heldBytes() - storage.size());
            if (need > room)
            {
                recorder_.discard();  // the chunk is abandoned
                for (ScratchBytes &b : buffers_)
                    b.release();
                throw scratchExhausted("stage buffer " + std::to_string(slot), need, room, maxScratchBytes_);
            }
            recorder_.interrupt();  // what it recorded may use this buffer's storage
            storage.allocate(std::max<std::size_t>(need, 1), guarded());
            ++counts_.allocations;
        }
        if (scratch_ != HostScratch::Reused)
        {
            const GuardedPages::Open open(guarded());
            std::memset(storage.data(), 0xFF, need);
        }
        return reinterpret_cast<T *>(storage.data());
    }

    /** \brief Buffer \a slot holding a copy of \a count elements at \a source. */
    template <class T>
    T *upload(int slot, const T *source, std::size_t count)
    {
        T *destination = buffer<T>(slot, std::max<std::size_t>(count, 1));
        if (count > 0)
        {
            const GuardedPages::Open open(guarded());
            copyInParallel(destination, source, count * sizeof(T));
        }
        return destination;
    }

    /** \brief \a source itself (executor memory is host memory); with HostScratch::Guarded a host
        mirror that an issued copy fills, as on a GPU (junk until the wait). */
    template <class T>
    const T *download(int slot, const T *source, std::size_t count)
    {
        if (!guarded())
            return source;
        std::vector<unsigned char> &mirror = mirrors_[static_cast<std::size_t>(slot)];
        const std::size_t bytes = count * sizeof(T);
        if (mirror.size() < std::max<std::size_t>(bytes, 1))
        {
            recorder_.interrupt();  // what it recorded may copy into this mirror
            mirror.resize(std::max<std::size_t>(bytes, 1));
        }
        unsigned char *host = mirror.data();
        std::memset(host, 0xA5, bytes);
        if (bytes > 0)
            issue([host, source, bytes] { std::memcpy(host, source, bytes); }, host, source, bytes);
        return reinterpret_cast<const T *>(host);
    }

    /** \brief The launches until the next wait() may be recorded and issued there (PassRecorder):
        on the GPU, as one CUDA graph from a pass's third time on; here, the same recording and
        signatures, each pass's operations run at its wait, and counts of what a GPU would replay. */
    void beginReplayable() { recorder_.begin(); }

    void wait()
    {
        const auto issued = recorder_.finish(
            [](std::vector<Operation> &operations)
            {
                Recorder::issueAll(operations);
                return NoGraph{};
            },
            [](NoGraph &, std::vector<Operation> &operations) { Recorder::issueAll(operations); });
        counts_.compiledPasses += issued == Recorder::Issued::CompiledNow ? 1 : 0;
        counts_.replayedPasses += issued == Recorder::Issued::Replayed ? 1 : 0;
        ++counts_.synchronizations;
    }

    device::ExecutorCounts &counts() { return counts_; }
    device::CountGuesses &guesses() { return guesses_; }

    template <class F>
    void forEach(std::size_t n, F f)
    {
        if (n == 0)
            return;
        ++counts_.launches;
        issue([this, n, f] { loop(n, f); }, kernelId<F>(), n, f);
    }

    /** \brief The GPU holds these kernels to fewer registers; here the same loop. */
    template <class F>
    void forEachHeavy(std::size_t n, F f)
    {
        forEach(n, f);
    }

    /** \brief f(i) for i below the extent's count: one launch over its bound, as on the GPU. */
    template <class F>
    void forEach(device::Extent extent, F f)
    {
        if (extent.bound == 0)
            return;
        ++counts_.launches;
        issue([this, extent, f] { loop(extent.size(), f); }, kernelId<F>(), extent, f);  // the count as it is then
    }

    void selectFlagged(const std::uint8_t *flags, std::size_t n, std::uint32_t *selected, unsigned long long *count)
    {
        if (n > 0)
            ++counts_.launches;
        issue(
            [=]
            {
                *count = 0;
                for (std::size_t i = 0; i < n; ++i)
                    if (flags[i])
                        selected[(*count)++] = static_cast<std::uint32_t>(i);
            },
            flags, n, selected, count);
    }

    /** \brief order = 0..n-1 stably sorted by keys[i] (each below numKeys): a counting sort. */
    void orderByKey(const std::uint32_t *keys, std::size_t n, std::uint32_t numKeys, std::uint32_t *order)
    {
        if (n == 0)
            return;
        counts_.launches += 2;  // the GPU's iota and radix sort
        issue(
            [=]
            {
                std::vector<std::size_t> next(static_cast<std::size_t>(numKeys) + 1, 0);
                for (std::size_t i = 0; i < n; ++i)
                    ++next[keys[i] + 1];
                for (std::uint32_t k = 0; k < numKeys; ++k)
                    next[k + 1] += next[k];
                for (std::size_t i = 0; i < n; ++i)
                    order[next[keys[i]]++] = static_cast<std::uint32_t>(i);
            },
            keys, n, numKeys, order);
    }

    /** \brief out[i] = sum of in[0..i) (in and out may alias); the inputs end with a zero, so the
        total, written to \a total, is out[n - 1]. */
    void exclusiveSum(const unsigned long long *in, unsigned long long *out, std::size_t n, unsigned long long *total)
    {
        ++counts_.launches;
        issue(
            [=]
            {
                unsigned long long sum = 0;
                for (std::size_t i = 0; i < n; ++i)
                {
                    const unsigned long long value = in[i];
                    out[i] = sum;
                    sum += value;
                }
                *total = n > 0 ? out[n - 1] : 0;
            },
            in, out, n, total);
    }

    /** \brief Stable sort of the \a n (key, value) pairs by key (every key below 2^\a keyBits), in
        place (the GPU's sorts into other buffers and moves \a keys and \a values there): an LSD
        radix sort, as the GPU's. */
    void sortByKey(unsigned long long *&keys, std::uint32_t *&values, std::size_t n, int keyBits)
    {
        if (n == 0)
            return;
        ++counts_.launches;
        issue([this, keys, values, n, keyBits] { radixSort(keys, values, n, keyBits); }, keys, values, n, keyBits);
    }

private:
    using Recorder = PassRecorder<NoGraph>;
    using Operation = Recorder::Operation;

    void radixSort(unsigned long long *keys, std::uint32_t *values, std::size_t n, int keyBits)
    {
        constexpr int kDigitBits = 8;
        constexpr std::size_t kDigits = std::size_t{1} << kDigitBits;
        if (sortKeys_.size() < n)
        {
            sortKeys_.resize(n);
            sortValues_.resize(n);
        }
        unsigned long long *fromKeys = keys, *toKeys = sortKeys_.data();
        std::uint32_t *fromValues = values, *toValues = sortValues_.data();
        for (int shift = 0; shift < keyBits; shift += kDigitBits)
        {
            std::array<std::size_t, kDigits + 1> next{};
            for (std::size_t i = 0; i < n; ++i)
                ++next[((fromKeys[i] >> shift) & (kDigits - 1)) + 1];
            for (std::size_t d = 0; d < kDigits; ++d)
                next[d + 1] += next[d];
            for (std::size_t i = 0; i < n; ++i)
            {
                const std::size_t slot = next[(fromKeys[i] >> shift) & (kDigits - 1)]++;
                toKeys[slot] = fromKeys[i];
                toValues[slot] = fromValues[i];
            }
            std::swap(fromKeys, toKeys);
            std::swap(fromValues, toValues);
        }
        if (fromKeys != keys)
        {
            std::copy(fromKeys, fromKeys + n, keys);
            std::copy(fromValues, fromValues + n, values);
        }
    }

    bool guarded() const { return scratch_ == HostScratch::Guarded; }

    /** \brief The recorder's issue, the guarded pages open while \a operation runs. */
    template <class Operation, class... Parts>
    void issue(Operation operation, const Parts &...parts)
    {
        recorder_.issue(
            [this, operation]
            {
                const GuardedPages::Open open(guarded());
                operation();
            },
            parts...);
    }

    template <class F>
    void loop(std::size_t n, const F &f)
    {
        if (loop_ == HostLoop::Reversed)
        {
            for (std::size_t i = n; i-- > 0;)
                f(i);
            return;
        }
        if (loop_ == HostLoop::Timed)
        {
            // An element over a microsecond runs again and the lower time counts: a timer interrupt
            // inside one would otherwise count whole (a call timed element by element lasts
            // milliseconds). A second run writes what the first did: elements write their own
            // slots and lower minima (atomicMinimum), nothing they add to.
            const auto timed = [&f](std::size_t i)
            {
                const auto start = std::chrono::steady_clock::now();
                f(i);
                return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            };
            double slowest = 0.0;
            for (std::size_t i = 0; i < n; ++i)
            {
                double seconds = timed(i);
                if (seconds > 1e-6)
                    seconds = std::min(seconds, timed(i));
                slowest = std::max(slowest, seconds);
            }
            counts_.criticalPathSeconds += slowest;
            return;
        }
#pragma omp parallel for schedule(static)
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i)
            f(static_cast<std::size_t>(i));
    }

    /** \brief One value per per-element function type, as a kernel's address on the GPU. */
    template <class F>
    static const void *kernelId()
    {
        static const char id = 0;
        return &id;
    }

    std::size_t heldBytes() const
    {
        std::size_t total = 0;
        for (const ScratchBytes &b : buffers_)
            total += b.size();
        return total;
    }

    HostScratch scratch_;
    std::size_t maxScratchBytes_;
    HostLoop loop_;
    device::ExecutorCounts counts_;
    device::CountGuesses guesses_;
    std::array<ScratchBytes, device::kNumStageBuffers> buffers_;
    std::array<std::vector<unsigned char>, device::kNumStageBuffers> mirrors_;  // HostScratch::Guarded
    std::vector<unsigned long long> sortKeys_;  // sortByKey's other buffers
    std::vector<std::uint32_t> sortValues_;
    Recorder recorder_;
};

class HostStageRunner : public PooledStageRunner<HostExecutor>
{
public:
    HostStageRunner(CollisionModelConstPtr model, const device::StageBudget &budget, HostScratch scratch, HostLoop loop)
        : PooledStageRunner([scratch, budget, loop]
                            { return std::make_unique<HostExecutor>(scratch, budget.maxScratchBytes, loop); }),
          model_(std::move(model))
    {
        arrays_ = hostModelArrays(*model_);
        budget_ = budget;
        if (scratch == HostScratch::Guarded)
            arrays_ = copyModelArrays(arrays_,
                                      [this](const auto *source, std::size_t count)
                                      {
                                          using T = std::remove_const_t<std::remove_pointer_t<decltype(source)>>;
                                          const std::size_t bytes = std::max<std::size_t>(1, count) * sizeof(T);
                                          auto &pages = guardedModel_.emplace_back();
                                          pages.allocate(bytes, true);
                                          if (count > 0)
                                          {
                                              const GuardedPages::Open open(true);
                                              std::memcpy(pages.data(), source, count * sizeof(T));
                                          }
                                          return reinterpret_cast<const T *>(pages.data());
                                      });
    }

    std::string name() const override { return "cpu-staged"; }

private:
    CollisionModelConstPtr model_;           // what arrays_ point into
    std::deque<ScratchBytes> guardedModel_;  // or these, with HostScratch::Guarded
};
}  // namespace

std::unique_ptr<StageRunner> makeHostStageRunner(CollisionModelConstPtr model, const device::StageBudget &budget,
                                                 HostScratch scratch, HostLoop loop)
{
    return std::make_unique<HostStageRunner>(std::move(model), budget, scratch, loop);
}

/** \brief What one check() keeps on the host besides the executor's buffers: the states' bounds
    verdicts, the outcomes that came back and where each state's begin and end (both 0 for a state
    without any). Pooled, so that a steady stream of calls allocates nothing on the host either. */
struct StagedBackend::CallBuffers
{
    std::vector<std::uint8_t> admissible;
    std::vector<device::PairOutcome> outcomes;
    std::vector<std::size_t> outcomesBegin, outcomesEnd;
};

StagedBackend::StagedBackend(CollisionModelConstPtr model, std::unique_ptr<StageRunner> runner)
    : model_(std::move(model)),
      exact_(model_),
      runner_(std::move(runner)),
      callBuffers_([] { return std::make_unique<CallBuffers>(); })
{
}

StagedBackend::~StagedBackend() = default;

void StagedBackend::countStages(bool on) const
{
    runner_->countStages(on);
}

device::StageCounts StagedBackend::stageCounts() const
{
    return runner_->counts();
}

device::ExecutorCounts StagedBackend::executorCounts() const
{
    return runner_->executorCounts();
}

bool StagedBackend::checkTwoPaddings(const double *q, std::size_t n, std::uint8_t *verdicts,
                                     const CollisionRequest &request, const PairPadding &wider, int threads) const
{
    if (n > kTwoPaddingsInOnePassMost)
        return false;
    // States 0..n-1 at the wider paddings (the request's pair paddings plus wider's), states n..2n-1
    // the same configurations at the request's own.
    const std::size_t dof = model_->robot->numCoordinates();
    std::vector<double> twice(2 * n * dof);
    std::copy_n(q, n * dof, twice.begin());
    std::copy_n(q, n * dof, twice.begin() + static_cast<std::ptrdiff_t>(n * dof));
    auto rows = std::make_shared<PairPadding>();
    appendPaddingRows(*model_, request.pairPadding.get(), &wider, n, *rows);
    appendPaddingRows(*model_, request.pairPadding.get(), nullptr, n, *rows);
    CollisionRequest both = request;
    both.pairPadding = std::move(rows);
    std::vector<std::uint8_t> valid(2 * n);
    check(twice.data(), 2 * n, valid.data(), nullptr, both, threads);
    for (std::size_t i = 0; i < n; ++i)
        verdicts[i] = static_cast<std::uint8_t>(valid[i]       ? PaddedVerdict::Clear
                                                : valid[n + i] ? PaddedVerdict::Near
                                                               : PaddedVerdict::Collides);
    return true;
}

void StagedBackend::check(const double *q, std::size_t n, std::uint8_t *valid, Contact *contacts,
                          const CollisionRequest &request, int threads) const
{
    const CollisionModel &model = *model_;
    const std::size_t dof = model.robot->numCoordinates();
    const int workers = batchWorkers(n, threads);

    std::unique_ptr<CallBuffers> buffers = callBuffers_.borrow();
    std::vector<std::uint8_t> &admissible = buffers->admissible;
    admissible.resize(n);
#pragma omp parallel for num_threads(workers) schedule(static)
    for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i)
        admissible[i] = model.configurationAdmissible(q + static_cast<std::size_t>(i) * dof) ? 1 : 0;

    device::StageSettings settings = stageSettings(model, request, contacts != nullptr);
    settings.onlyDecisive = true;  // the reduction below reads no pair settled apart

    std::vector<device::PairOutcome> &outcomes = buffers->outcomes;
    outcomes.clear();
    try
    {
        runner_->run(q, admissible.data(), n, settings, outcomes);
    }
    catch (...)
    {
        callBuffers_.giveBack(std::move(buffers));
        throw;
    }
    std::vector<std::size_t> &outcomesBegin = buffers->outcomesBegin, &outcomesEnd = buffers->outcomesEnd;
    outcomesBegin.resize(n);
    outcomesEnd.resize(n);
    const auto numOutcomes = static_cast<std::ptrdiff_t>(outcomes.size());

    // Per-state reduction: the first pair (in the CPU's order) that collides. An open pair is decided
    // with its own padding (the state's pairPadding row). First each state's outcomes, which come in
    // (state, pair) order: every boundary between two states' runs marked in parallel (a serial
    // pass over 10^5 states took 130 us, a part of what a device's large call may take).
    const bool rowPerState = request.pairPadding && request.pairPadding->rows > 1;
#pragma omp parallel num_threads(workers)
    {
#pragma omp for schedule(static)
        for (std::ptrdiff_t si = 0; si < static_cast<std::ptrdiff_t>(n); ++si)
            outcomesBegin[static_cast<std::size_t>(si)] = outcomesEnd[static_cast<std::size_t>(si)] = 0;
#pragma omp for schedule(static)
        for (std::ptrdiff_t k = 0; k < numOutcomes; ++k)
        {
            const std::uint32_t state = outcomes[static_cast<std::size_t>(k)].state;
            if (k == 0 || outcomes[static_cast<std::size_t>(k - 1)].state != state)
                outcomesBegin[state] = static_cast<std::size_t>(k);
            if (k + 1 == numOutcomes || outcomes[static_cast<std::size_t>(k + 1)].state != state)
                outcomesEnd[state] = static_cast<std::size_t>(k + 1);
        }
        std::unique_ptr<CpuWorkspace> ws = exact_.borrow();
#pragma omp for schedule(dynamic, 16)
        for (std::ptrdiff_t si = 0; si < static_cast<std::ptrdiff_t>(n); ++si)
        {
            const std::size_t i = static_cast<std::size_t>(si);
            Contact contact;
            bool collides = false;
            if (!admissible[i])
            {
                contact.kind = Contact::Kind::OutOfBounds;
                collides = true;
            }
            const device::PairOutcome *begin = outcomes.data() + outcomesBegin[i];
            const device::PairOutcome *end = outcomes.data() + outcomesEnd[i];
            auto overlapSettled = [](const device::PairOutcome &o) { return o.status == device::PairOverlaps; };
            if (!collides && !contacts)
                collides = std::any_of(begin, end, overlapSettled);
            bool refitted = false;
            for (const device::PairOutcome *o = begin; !collides && o != end; ++o)
            {
                if (overlapSettled(*o))
                {
                    model.nameParties(o->pair, contact);
                    contact.triangle = o->triangle;
                    contact.position = Eigen::Vector3d(o->position[0], o->position[1], o->position[2]);
                    collides = true;
                }
                else if (o->status != device::PairApart)
                {
                    if (!refitted)
                        exact_.refitState(q + i * dof, *ws);
                    refitted = true;
                    collides = exact_.decideOpenPair(o->pair, request, *ws, contact, rowPerState ? i : 0);
                }
            }
            valid[i] = collides ? 0 : 1;
            if (contacts)
                contacts[i] = collides ? contact : Contact{};
        }
        exact_.giveBack(std::move(ws));
    }
    callBuffers_.giveBack(std::move(buffers));
}
}  // namespace rastercheck
