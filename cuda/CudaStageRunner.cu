// The CUDA executor of the batched pipeline: each stage of device/BatchPipeline.h runs as one
// kernel (forEachKernel instantiated with that stage's per-element function), compaction, scans
// and the fragments' sort are CUB calls, all on the executor's stream. Device buffers and the
// page-locked host mirrors that copies go through live as long as the executor and only grow, so
// a steady stream of batches does not allocate; copies run asynchronously on the stream, and the
// host waits only where the driver asks (a small chunk: once); the model is uploaded once.

#include "CudaStageRunner.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include <cub/block/block_scan.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <cuda_runtime.h>
#include <thrust/iterator/counting_iterator.h>

#include "rastercheck/collision/PassRecorder.h"
#include "rastercheck/collision/StageChunks.h"

namespace rastercheck::cuda
{
namespace
{
void check(cudaError_t status, const char *what)
{
    if (status != cudaSuccess)
    {
        cudaGetLastError();  // a caught failure must not resurface at the next launch check
        throw std::runtime_error(std::string("CUDA: ") + what + " failed: " + cudaGetErrorName(status) + " (" +
                                 cudaGetErrorString(status) + ")");
    }
}

/** \brief The first statement of every stage kernel, for programmatic dependent launch (sm_90 on):
    wait until the kernel before it in the stream has finished and its writes are visible, then
    let the next kernel be launched. A kernel launched with the programmatic-serialization
    attribute (CudaExecutor::launch) may start before its predecessor ends, so its blocks are
    resident and waiting here when the predecessor's last block exits: the launch's latency
    overlaps the predecessor instead of following it. Launched without the attribute, both
    instructions return at once; after a copy, or a CUB kernel (which does not trigger), the kernel
    starts when that ends, as it would without the attribute. The trigger comes after the wait, so
    a kernel's successor is scheduled only once every block of this kernel has started and its own
    predecessor has ended: waiting blocks never take an SM from the kernels before them. */
__device__ __forceinline__ void followPreviousKernel()
{
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    asm volatile("griddepcontrol.wait;" ::: "memory");
    asm volatile("griddepcontrol.launch_dependents;" :::);
#endif
}

template <class F>
__global__ void forEachKernel(std::size_t n, F f)
{
    followPreviousKernel();
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n)
        f(i);
}

/** \brief Threads per block of the register-heavy stage kernels (forEachHeavyKernel). */
constexpr unsigned kHeavyBlockThreads = 256;

/** \brief Threads per block of the other stage kernels, unless RASTERCHECK_CUDA_BLOCK_THREADS says
    otherwise (a multiple of 32 up to 1024: to measure one size against another in the same run,
    scripts/gpu-check.sh). An SM holds whole blocks only, so small blocks leave fewer registers
    unusable: at 64 threads the light proof (141 registers a thread, sm_90) keeps 14 warps an SM
    resident instead of 8, and no stage kernel fewer than at 256 (32 blocks of 2 warps fill an
    SM's 64). */
unsigned blockThreads()
{
    constexpr unsigned kDefault = 64;
    const char *setting = std::getenv("RASTERCHECK_CUDA_BLOCK_THREADS");
    if (!setting || !*setting)
        return kDefault;
    char *end = nullptr;
    const unsigned long threads = std::strtoul(setting, &end, 10);
    if (*end != '\0' || threads == 0 || threads > 1024 || threads % 32 != 0)
        throw std::invalid_argument(std::string("RASTERCHECK_CUDA_BLOCK_THREADS=") + setting +
                                    ": expected a multiple of 32 from 32 to 1024 (threads per block)");
    return static_cast<unsigned>(threads);
}

/** \brief forEachKernel for the stages whose per-element code would take every register it can (the
    full proof, the exact phase: 255 and 246 registers per thread unbounded, 8 warps an SM): held to
    two blocks an SM, so 128 registers, twice the warps. ptxas spills 4 and 92 bytes a thread there
    (`scripts/gpu-check.sh registers`, sm_90, 2026-11-26). */
template <class F>
__global__ void __launch_bounds__(kHeavyBlockThreads, 2) forEachHeavyKernel(std::size_t n, F f)
{
    followPreviousKernel();
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n)
        f(i);
}

/** \brief f(i) for i below the extent's count, which an earlier kernel of the stream wrote. */
template <class F>
__global__ void forEachCountedKernel(device::Extent extent, F f)
{
    followPreviousKernel();
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < extent.size())
        f(i);
}

__global__ void probeKernel(int *out) { *out = 42; }

__global__ void iotaKernel(std::uint32_t *out, std::size_t n)
{
    const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n)
        out[i] = static_cast<std::uint32_t>(i);
}

/** \brief Threads and items a thread of the one-block scan and compaction below: tiles of 8 192
    elements. */
constexpr unsigned kOneBlockThreads = 1024;
constexpr int kOneBlockItems = 8;
/** \brief Up to this many elements a scan or a compaction is one kernel of one block (two tiles).
    CUB's are two kernels (the tiles' look-back states, then the tiles) and, for a scan's total, a
    copy: three steps of a small call's chain, each at least a launch's minimum, for a few thousand
    elements (32 Panda states are 3 136 to 8 064 (state, pair) elements). */
constexpr std::size_t kOneBlockMost = 2 * std::size_t{kOneBlockThreads} * kOneBlockItems;

/** \brief out[i] = sum of in[0..i) for i < n (in and out may alias), *total = out[n - 1]; n >= 1.
    One block, tile after tile, each thread holding kOneBlockItems consecutive elements. */
__global__ void __launch_bounds__(kOneBlockThreads)
    oneBlockExclusiveSumKernel(const unsigned long long *in, unsigned long long *out, std::size_t n,
                               unsigned long long *total)
{
    followPreviousKernel();
    using Scan = cub::BlockScan<unsigned long long, kOneBlockThreads>;
    __shared__ typename Scan::TempStorage scratch;
    unsigned long long carry = 0;  // the sum of the tiles before, the same in every thread
    for (std::size_t base = 0; base < n; base += std::size_t{kOneBlockThreads} * kOneBlockItems)
    {
        const std::size_t first = base + std::size_t{threadIdx.x} * kOneBlockItems;
        unsigned long long items[kOneBlockItems];
        for (int j = 0; j < kOneBlockItems; ++j)
            items[j] = first + j < n ? in[first + j] : 0;
        unsigned long long tileSum = 0;
        Scan(scratch).ExclusiveSum(items, items, tileSum);  // every thread's loads come before its barrier
        for (int j = 0; j < kOneBlockItems; ++j)
            if (first + j < n)
            {
                out[first + j] = carry + items[j];
                if (first + j == n - 1)
                    *total = carry + items[j];
            }
        carry += tileSum;
        __syncthreads();  // the next tile reuses the scan's shared memory
    }
}

/** \brief The indices i < n with flags[i] set into \a selected, in order, and how many into the
    count: one block, as oneBlockExclusiveSumKernel. */
__global__ void __launch_bounds__(kOneBlockThreads)
    oneBlockSelectFlaggedKernel(const std::uint8_t *flags, std::size_t n, std::uint32_t *selected,
                                unsigned long long *count)
{
    followPreviousKernel();
    using Scan = cub::BlockScan<std::uint32_t, kOneBlockThreads>;
    __shared__ typename Scan::TempStorage scratch;
    unsigned long long carry = 0;  // selected in the tiles before, the same in every thread
    for (std::size_t base = 0; base < n; base += std::size_t{kOneBlockThreads} * kOneBlockItems)
    {
        const std::size_t first = base + std::size_t{threadIdx.x} * kOneBlockItems;
        bool kept[kOneBlockItems];
        std::uint32_t place[kOneBlockItems];
        for (int j = 0; j < kOneBlockItems; ++j)
        {
            kept[j] = first + j < n && flags[first + j] != 0;
            place[j] = kept[j] ? 1 : 0;
        }
        std::uint32_t tileCount = 0;
        Scan(scratch).ExclusiveSum(place, place, tileCount);
        for (int j = 0; j < kOneBlockItems; ++j)
            if (kept[j])
                selected[carry + place[j]] = static_cast<std::uint32_t>(first + j);
        carry += tileCount;
        __syncthreads();  // the next tile reuses the scan's shared memory
    }
    if (threadIdx.x == 0)
        *count = carry;
}

/** \brief One allocation that only grows, freed with its owner: device memory, or page-locked
    host memory (\a PageLocked), which copies to and from the device reach asynchronously on a
    stream (a copy from pageable memory makes the host wait). */
template <bool PageLocked>
class Allocation
{
public:
    Allocation() = default;
    Allocation(Allocation &&other) noexcept : pointer_(other.pointer_), bytes_(other.bytes_)
    {
        other.pointer_ = nullptr;
        other.bytes_ = 0;
    }
    Allocation &operator=(Allocation &&) = delete;
    Allocation(const Allocation &) = delete;
    Allocation &operator=(const Allocation &) = delete;
    ~Allocation() { release(); }

    void *pointer() const { return pointer_; }
    std::size_t bytes() const { return bytes_; }

    /** \brief Holds at least \a need bytes after it: a quarter more when \a most allows (fewer
        regrowths as batches vary), else exactly \a need. False when there is no room (the old
        contents are gone either way); any other CUDA failure throws. */
    bool grow(std::size_t need, std::size_t most, const char *what)
    {
        if (need <= bytes_)
            return true;
        release();
        const std::size_t roomy = std::max(need, std::min(need + need / 4, most));
        for (const std::size_t size : {roomy, need})
        {
            const cudaError_t status = PageLocked ? cudaMallocHost(&pointer_, size) : cudaMalloc(&pointer_, size);
            if (status == cudaSuccess)
            {
                bytes_ = size;
                return true;
            }
            pointer_ = nullptr;
            if (status != cudaErrorMemoryAllocation)
                check(status, what);
            cudaGetLastError();  // out of memory is not sticky: clear it
            if (size == need)
                break;  // no smaller size to try
        }
        return false;
    }

    void release()
    {
        if (pointer_)
            PageLocked ? cudaFreeHost(pointer_) : cudaFree(pointer_);
        pointer_ = nullptr;
        bytes_ = 0;
    }

private:
    void *pointer_ = nullptr;
    std::size_t bytes_ = 0;
};
using DeviceAllocation = Allocation<false>;
using PinnedAllocation = Allocation<true>;

/** \brief A pass compiled by PassRecorder: the CUDA graph captured from its operations, or none
    where capturing failed (its operations are then issued one by one, as before). */
class GraphExec
{
public:
    explicit GraphExec(cudaGraphExec_t exec = nullptr) : exec_(exec) {}
    GraphExec(GraphExec &&other) noexcept : exec_(other.exec_) { other.exec_ = nullptr; }
    GraphExec &operator=(GraphExec &&) = delete;
    GraphExec(const GraphExec &) = delete;
    GraphExec &operator=(const GraphExec &) = delete;
    ~GraphExec()
    {
        if (exec_)
            cudaGraphExecDestroy(exec_);  // one still running is freed when it ends
    }

    cudaGraphExec_t get() const { return exec_; }

private:
    cudaGraphExec_t exec_;
};

/** \brief Whether the executor's optimisation named by \a variable is on: yes unless the variable
    is 0 (to measure one against the other in the same run, scripts/gpu-check.sh).
    RASTERCHECK_CUDA_GRAPHS: small passes replayed as CUDA graphs. RASTERCHECK_CUDA_PDL: stage
    kernels launched before the kernel ahead of them ends (programmatic dependent launch, sm_90 on). */
bool allowedUnlessZero(const char *variable)
{
    const char *setting = std::getenv(variable);
    return !(setting && std::strcmp(setting, "0") == 0);
}

/** \brief Whether the stage kernels were compiled with followPreviousKernel's wait: from a virtual
    architecture of 9.0 or later. Code for an earlier one (PTX the driver compiles for a newer
    device) lacks it and must not overlap its predecessor. Every kernel of this file comes from the
    same images, so probeKernel answers for all of them. */
bool kernelsFollowPreviousKernel()
{
    cudaFuncAttributes attributes{};
    const bool known = cudaFuncGetAttributes(&attributes, probeKernel) == cudaSuccess;
    cudaGetLastError();
    return known && attributes.ptxVersion >= 90;
}

class CudaExecutor
{
public:
    explicit CudaExecutor(unsigned blockThreads)
        : graphs_(allowedUnlessZero("RASTERCHECK_CUDA_GRAPHS")),
          programmaticLaunch_(allowedUnlessZero("RASTERCHECK_CUDA_PDL") && kernelsFollowPreviousKernel()),
          threads_(blockThreads)
    {
        check(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "cudaStreamCreate");
    }
    ~CudaExecutor()
    {
        cudaStreamSynchronize(stream_);  // no copy may still use a mirror
        releaseScratch();
        cudaStreamDestroy(stream_);
    }
    CudaExecutor(const CudaExecutor &) = delete;
    CudaExecutor &operator=(const CudaExecutor &) = delete;

    /** \brief StageBudget::maxScratchBytes: the most all scratch buffers may hold together. */
    void limitScratch(std::size_t bytes) { maxScratchBytes_ = bytes; }

    template <class T>
    T *buffer(int slot, std::size_t count)
    {
        return static_cast<T *>(reserve(buffers_[static_cast<std::size_t>(slot)],
                                         std::max<std::size_t>(1, count) * sizeof(T), "cudaMalloc (stage buffer)"));
    }

    /** \brief Buffer \a slot holding a copy of \a count elements at \a source, copied through the
        slot's host mirror: the copy runs on the stream, the host does not wait for it. */
    template <class T>
    T *upload(int slot, const T *source, std::size_t count)
    {
        T *destination = buffer<T>(slot, count);
        if (count == 0)
            return destination;
        T *staged = static_cast<T *>(mirror(slot, count * sizeof(T), true));
        const std::size_t bytes = count * sizeof(T);
        copyInParallel(staged, source, bytes);  // now: the copy to the device may run later
        recorder_.issue(
            [this, destination, staged, bytes] {
                check(cudaMemcpyAsync(destination, staged, bytes, cudaMemcpyHostToDevice, stream_),
                      "cudaMemcpyAsync (upload)");
            },
            kUpload, destination, staged, bytes);
        return destination;
    }

    /** \brief Queues a copy of \a count elements at \a source into the host mirror of \a slot and
        returns the mirror, to be read after wait(). */
    template <class T>
    const T *download(int slot, const T *source, std::size_t count)
    {
        if (count == 0)
            return static_cast<const T *>(mirrors_[static_cast<std::size_t>(slot)].pointer());
        T *host = static_cast<T *>(mirror(slot, count * sizeof(T), false));
        const std::size_t bytes = count * sizeof(T);
        recorder_.issue(
            [this, host, source, bytes] {
                check(cudaMemcpyAsync(host, source, bytes, cudaMemcpyDeviceToHost, stream_),
                      "cudaMemcpyAsync (download)");
            },
            kDownload, host, source, bytes);
        return host;
    }

    /** \brief What is issued until the next wait() may be recorded (PassRecorder): a pass seen
        twice before runs as one CUDA graph. */
    void beginReplayable()
    {
        if (graphs_)
            recorder_.begin();
    }

    /** \brief The host waits for everything queued on the stream (a recorded pass issued first). */
    void wait()
    {
        bool replayed = false;  // as a graph (a pass whose capture failed is issued one by one)
        const auto issued = recorder_.finish([this](std::vector<Operation> &operations) { return compile(operations); },
                                             [&](GraphExec &graph, std::vector<Operation> &operations)
                                             {
                                                 if (!graph.get())
                                                     return Recorder::issueAll(operations);
                                                 check(cudaGraphLaunch(graph.get(), stream_), "cudaGraphLaunch");
                                                 replayed = true;
                                             });
        counts_.compiledPasses += issued == Recorder::Issued::CompiledNow ? 1 : 0;
        counts_.replayedPasses += replayed ? 1 : 0;
        check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
        ++counts_.synchronizations;
        mirrorInUse_.fill(false);
    }

    device::ExecutorCounts &counts() { return counts_; }
    device::CountGuesses &guesses() { return guesses_; }

    template <class F>
    void forEach(std::size_t n, F f)
    {
        if (n == 0)
            return;
        ++counts_.launches;
        recorder_.issue([this, n, f] { launchOver(&forEachKernel<F>, n, n, f); },
                        reinterpret_cast<const void *>(&forEachKernel<F>), n, f);
    }

    /** \brief forEach for a stage whose per-element code is register-heavy (forEachHeavyKernel). */
    template <class F>
    void forEachHeavy(std::size_t n, F f)
    {
        if (n == 0)
            return;
        ++counts_.launches;
        recorder_.issue([this, n, f]
                        { launch(&forEachHeavyKernel<F>, blocksFor(n, kHeavyBlockThreads), kHeavyBlockThreads, n, f); },
                        reinterpret_cast<const void *>(&forEachHeavyKernel<F>), n, f);
    }

    /** \brief f(i) for i below the extent's count, read on the device: a thread per element of its
        bound, so that the host need not wait for the count. */
    template <class F>
    void forEach(device::Extent extent, F f)
    {
        if (extent.bound == 0)
            return;
        ++counts_.launches;
        recorder_.issue([this, extent, f] { launchOver(&forEachCountedKernel<F>, extent.bound, extent, f); },
                        reinterpret_cast<const void *>(&forEachCountedKernel<F>), extent, f);
    }

    /** \brief The indices i < n with flags[i] set into \a selected, their number into *count
        (device memory, not waited for). */
    void selectFlagged(const std::uint8_t *flags, std::size_t n, std::uint32_t *selected, unsigned long long *count)
    {
        if (n == 0)
        {
            recorder_.issue([this, count]
                            { check(cudaMemsetAsync(count, 0, sizeof(*count), stream_), "cudaMemsetAsync (count)"); },
                            kZeroCount, count);
            return;
        }
        ++counts_.launches;
        if (n <= kOneBlockMost)
        {
            recorder_.issue([=]
                            { launch(&oneBlockSelectFlaggedKernel, 1, kOneBlockThreads, flags, n, selected, count); },
                            kOneBlockSelect, flags, n, selected, count);
            return;
        }
        const thrust::counting_iterator<std::uint32_t> indices(0);
        const auto items = static_cast<std::int64_t>(n);
        std::size_t bytes = 0;
        check(cub::DeviceSelect::Flagged(nullptr, bytes, indices, flags, selected, count, items, stream_),
              "cub::DeviceSelect::Flagged (size)");
        void *temp = reserve(temp_, bytes, "cudaMalloc (CUB scratch)");
        recorder_.issue(
            [=]
            {
                std::size_t size = bytes;  // CUB takes it by reference
                check(cub::DeviceSelect::Flagged(temp, size, indices, flags, selected, count, items, stream_),
                      "cub::DeviceSelect::Flagged");
            },
            kSelect, temp, bytes, flags, selected, count, items);
    }

    /** \brief order = 0..n-1 stably sorted by keys[i] (each below numKeys): CUB's radix sort (LSD,
        so stable) over the keys' low bits, the indices as values. The fragment sort's spare
        buffers hold the sorted keys and the indices: that sort comes later in the chunk, on the
        same stream. */
    void orderByKey(const std::uint32_t *keys, std::size_t n, std::uint32_t numKeys, std::uint32_t *order)
    {
        if (n == 0)
            return;
        int bits = 1;
        while (bits < 32 && (std::uint64_t{1} << bits) < numKeys)
            ++bits;
        auto *sortedKeys =
            static_cast<std::uint32_t *>(reserve(keysAlt_, n * sizeof(std::uint32_t), "cudaMalloc (sort keys)"));
        auto *indices =
            static_cast<std::uint32_t *>(reserve(valuesAlt_, n * sizeof(std::uint32_t), "cudaMalloc (sort values)"));
        const auto items = static_cast<std::int64_t>(n);
        std::size_t bytes = 0;
        check(
            cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys, sortedKeys, indices, order, items, 0, bits, stream_),
            "cub::DeviceRadixSort::SortPairs (size)");
        void *temp = reserve(temp_, bytes, "cudaMalloc (CUB scratch)");
        counts_.launches += 2;  // with the iota
        recorder_.issue(
            [=]
            {
                constexpr unsigned threads = 256;
                iotaKernel<<<static_cast<unsigned>((n + threads - 1) / threads), threads, 0, stream_>>>(indices, n);
                check(cudaGetLastError(), "kernel launch (iota)");
                std::size_t size = bytes;
                check(cub::DeviceRadixSort::SortPairs(temp, size, keys, sortedKeys, indices, order, items, 0, bits,
                                                      stream_),
                      "cub::DeviceRadixSort::SortPairs");
            },
            kOrder, temp, bytes, keys, sortedKeys, indices, order, items, bits);
    }

    /** \brief out[i] = sum of in[0..i); the inputs end with a zero, so the last output is the
        total, copied to *total (device memory, not waited for). */
    void exclusiveSum(const unsigned long long *in, unsigned long long *out, std::size_t n, unsigned long long *total)
    {
        ++counts_.launches;  // as the host executor counts, whose scan of nothing writes a total of 0
        if (n == 0)
        {
            recorder_.issue([this, total]
                            { check(cudaMemsetAsync(total, 0, sizeof(*total), stream_), "cudaMemsetAsync (total)"); },
                            kZeroCount, total);
            return;
        }
        if (n <= kOneBlockMost)
        {
            recorder_.issue([=] { launch(&oneBlockExclusiveSumKernel, 1, kOneBlockThreads, in, out, n, total); },
                            kOneBlockScan, in, out, n, total);
            return;
        }
        std::size_t bytes = 0;
        check(cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, out, n, stream_), "cub::DeviceScan::ExclusiveSum (size)");
        void *temp = reserve(temp_, bytes, "cudaMalloc (CUB scratch)");
        recorder_.issue(
            [=]
            {
                std::size_t size = bytes;
                check(cub::DeviceScan::ExclusiveSum(temp, size, in, out, n, stream_), "cub::DeviceScan::ExclusiveSum");
                check(cudaMemcpyAsync(total, out + (n - 1), sizeof(*total), cudaMemcpyDeviceToDevice, stream_),
                      "cudaMemcpyAsync (scan total)");
            },
            kScan, temp, bytes, in, out, n, total);
    }

    /** \brief Stable sort of the \a n (key, value) pairs by key (every key below 2^\a keyBits):
        CUB's radix sort, which does not make the host wait, into the executor's other key and
        value buffers, where \a keys and \a values then point (known when the sort is issued, so
        that a recorded pass needs nothing from it). */
    void sortByKey(unsigned long long *&keys, std::uint32_t *&values, std::size_t n, int keyBits)
    {
        if (n == 0)
            return;
        auto *sortedKeys = static_cast<unsigned long long *>(
            reserve(keysAlt_, n * sizeof(unsigned long long), "cudaMalloc (sort keys)"));
        auto *sortedValues =
            static_cast<std::uint32_t *>(reserve(valuesAlt_, n * sizeof(std::uint32_t), "cudaMalloc (sort values)"));
        const unsigned long long *inKeys = keys;
        const std::uint32_t *inValues = values;
        const auto items = static_cast<std::int64_t>(n);
        std::size_t bytes = 0;
        check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, inKeys, sortedKeys, inValues, sortedValues, items, 0,
                                              keyBits, stream_),
              "cub::DeviceRadixSort::SortPairs (size)");
        void *temp = reserve(temp_, bytes, "cudaMalloc (CUB scratch)");
        ++counts_.launches;
        recorder_.issue(
            [=]
            {
                std::size_t size = bytes;
                check(cub::DeviceRadixSort::SortPairs(temp, size, inKeys, sortedKeys, inValues, sortedValues, items, 0,
                                                      keyBits, stream_),
                      "cub::DeviceRadixSort::SortPairs");
            },
            kSort, temp, bytes, inKeys, sortedKeys, inValues, sortedValues, items, keyBits);
        keys = sortedKeys;
        values = sortedValues;
    }

private:
    /** \brief \a kernel (one that begins with followPreviousKernel) over \a blocks blocks of
        \a threads on the stream; where its wait was compiled in, with programmatic stream
        serialization, so that its launch overlaps the kernel before it. A small call is some
        twenty kernels in a row, most of them a few microseconds long; in a CUDA graph the
        attribute becomes a programmatic edge. */
    template <class... Params, class... Args>
    void launch(void (*kernel)(Params...), unsigned blocks, unsigned threads, Args... args)
    {
        cudaLaunchAttribute overlap{};
        overlap.id = cudaLaunchAttributeProgrammaticStreamSerialization;
        overlap.val.programmaticStreamSerializationAllowed = 1;
        cudaLaunchConfig_t config{};
        config.gridDim = dim3(blocks);
        config.blockDim = dim3(threads);
        config.stream = stream_;
        if (programmaticLaunch_)
        {
            config.attrs = &overlap;
            config.numAttrs = 1;
        }
        cudaError_t status = cudaLaunchKernelEx(&config, kernel, args...);
        if (status != cudaSuccess && config.numAttrs > 0)
        {
            // A driver that refuses the attribute: this executor launches as before from now on
            // (where the launch fails without it too, the attribute was not the cause).
            cudaGetLastError();
            config.attrs = nullptr;
            config.numAttrs = 0;
            status = cudaLaunchKernelEx(&config, kernel, args...);
            programmaticLaunch_ = status != cudaSuccess;
        }
        check(status, "kernel launch");
    }

    /** \brief \a kernel over \a n elements in blocks of threads_, or of as many as its registers
        allow where that is fewer (RASTERCHECK_CUDA_BLOCK_THREADS past what the light proof's registers
        leave room for: a block's threads share an SM's 64 K registers). */
    template <class... Params, class... Args>
    void launchOver(void (*kernel)(Params...), std::size_t n, Args... args)
    {
        const unsigned threads = std::min(threads_, mostThreads(reinterpret_cast<const void *>(kernel)));
        launch(kernel, blocksFor(n, threads), threads, args...);
    }

    /** \brief The most threads a block of \a kernel may have (cudaFuncGetAttributes, once per kernel),
        in whole warps. */
    unsigned mostThreads(const void *kernel)
    {
        const auto known = mostThreads_.find(kernel);
        if (known != mostThreads_.end())
            return known->second;
        cudaFuncAttributes attributes{};
        check(cudaFuncGetAttributes(&attributes, kernel), "cudaFuncGetAttributes");
        const unsigned most = std::max(32u, static_cast<unsigned>(attributes.maxThreadsPerBlock) / 32u * 32u);
        mostThreads_.emplace(kernel, most);
        return most;
    }

    using Recorder = PassRecorder<GraphExec>;
    using Operation = Recorder::Operation;
    /** \brief Tags of the operations that are not kernels of the driver's, in signatures. */
    enum OperationTag : int
    {
        kUpload,
        kDownload,
        kZeroCount,
        kSelect,
        kOneBlockSelect,
        kOrder,
        kScan,
        kOneBlockScan,
        kSort
    };

    /** \brief The graph instantiated from \a operations issued in stream capture, or null where
        capturing or instantiating fails (nothing has run then). */
    cudaGraphExec_t capture(std::vector<Operation> &operations)
    {
        if (cudaStreamBeginCapture(stream_, cudaStreamCaptureModeRelaxed) != cudaSuccess)
        {
            cudaGetLastError();  // a failed capture must not resurface at the next launch check
            return nullptr;
        }
        bool issued = true;
        try
        {
            Recorder::issueAll(operations);
        }
        catch (const std::exception &)
        {
            issued = false;
        }
        cudaGraph_t graph = nullptr;
        cudaGraphExec_t exec = nullptr;
        const bool captured = cudaStreamEndCapture(stream_, &graph) == cudaSuccess && issued && graph;
        if (captured && cudaGraphInstantiate(&exec, graph, 0) != cudaSuccess)
            exec = nullptr;
        if (graph)
            cudaGraphDestroy(graph);
        if (!exec)
            cudaGetLastError();
        return exec;
    }

    /** \brief A pass's operations captured as a CUDA graph, which is launched. Where capturing
        fails, nothing has run: the operations are issued one by one, now and at each replay. */
    GraphExec compile(std::vector<Operation> &operations)
    {
        cudaGraphExec_t exec = capture(operations);
        if (!exec && programmaticLaunch_)
        {
            // A driver that cannot capture programmatic launches: graphs save more than the
            // overlapped launches, so this executor gives those up (unless the pass fails to
            // capture without them as well: then they were not the reason).
            programmaticLaunch_ = false;
            exec = capture(operations);
            programmaticLaunch_ = !exec;
        }
        if (!exec)
        {
            Recorder::issueAll(operations);
            return GraphExec();
        }
        GraphExec compiled(exec);
        check(cudaGraphLaunch(compiled.get(), stream_), "cudaGraphLaunch");
        return compiled;
    }

    static unsigned blocksFor(std::size_t n, unsigned threads)
    {
        return static_cast<unsigned>((n + threads - 1) / threads);
    }

    /** \brief The host mirror of \a slot, at least \a bytes, for a copy that the host fills first
        (\a hostWrites) or that the stream fills. The host writes or frees a mirror only when no
        queued copy uses it, else it waits first (the driver's chunks end with a wait, and use a
        mirror once before it, so that costs nothing in practice). */
    void *mirror(int slot, std::size_t bytes, bool hostWrites)
    {
        const std::size_t i = static_cast<std::size_t>(slot);
        PinnedAllocation &m = mirrors_[i];
        const bool grows = bytes > m.bytes();
        if (mirrorInUse_[i] && (grows || hostWrites))
            wait();
        if (grows)
        {
            recorder_.interrupt();  // what it recorded may copy through this mirror
            if (!m.grow(bytes, SIZE_MAX, "cudaMallocHost (host mirror)"))
                throw std::runtime_error("CUDA: no page-locked host memory for a host mirror of " +
                                         std::to_string(bytes) + " bytes");
            ++counts_.allocations;
        }
        mirrorInUse_[i] = true;
        return m.pointer();
    }

    /** \brief \a a grown to \a need bytes within the scratch limit. When the limit or the device
        says no, every scratch buffer is freed (the chunk is abandoned; cudaFree waits for the
        kernels using them) and StageMemoryExhausted has the chunk split. */
    void *reserve(DeviceAllocation &a, std::size_t need, const char *what)
    {
        if (need <= a.bytes())
            return a.pointer();
        const std::size_t room = scratchRoom(maxScratchBytes_, heldBytes() - a.bytes());
        recorder_.interrupt();  // what it recorded may use this allocation
        if (need > room || !a.grow(need, room, what))
        {
            releaseScratch();
            throw scratchExhausted(what, need, room, maxScratchBytes_);
        }
        ++counts_.allocations;
        return a.pointer();
    }

    std::size_t heldBytes() const
    {
        std::size_t total = temp_.bytes() + keysAlt_.bytes() + valuesAlt_.bytes();
        for (const DeviceAllocation &a : buffers_)
            total += a.bytes();
        return total;
    }

    void releaseScratch()
    {
        recorder_.discard();
        recorder_.forget();  // their graphs use this memory
        for (DeviceAllocation &a : buffers_)
            a.release();
        temp_.release();
        keysAlt_.release();
        valuesAlt_.release();
    }

    cudaStream_t stream_ = nullptr;
    std::size_t maxScratchBytes_ = 0;
    device::ExecutorCounts counts_;
    device::CountGuesses guesses_;
    std::array<DeviceAllocation, device::kNumStageBuffers> buffers_;
    DeviceAllocation temp_, keysAlt_, valuesAlt_;
    std::array<PinnedAllocation, device::kNumStageBuffers> mirrors_;
    std::array<bool, device::kNumStageBuffers> mirrorInUse_{};  // a queued copy reads or writes it
    bool graphs_;
    /// RASTERCHECK_CUDA_PDL not 0 and kernelsFollowPreviousKernel(); off for good once the driver
    /// refuses the attribute at a launch or in a graph (launch, compile)
    bool programmaticLaunch_;
    unsigned threads_;  ///< per block, forEach and forEachCounted (blockThreads())
    std::unordered_map<const void *, unsigned> mostThreads_;  ///< per kernel (mostThreads())
    Recorder recorder_;
};

/** \brief A host array copied to the device once. */
template <class T>
const T *uploadOnce(std::vector<DeviceAllocation> &keep, const T *source, std::size_t count)
{
    keep.emplace_back();
    const std::size_t bytes = std::max<std::size_t>(1, count) * sizeof(T);
    if (!keep.back().grow(bytes, bytes, "cudaMalloc (model)"))
        throw std::runtime_error("CUDA: no device memory for the model (" + std::to_string(bytes) + " bytes)");
    void *p = keep.back().pointer();
    if (count > 0)
        check(cudaMemcpy(p, source, count * sizeof(T), cudaMemcpyHostToDevice), "cudaMemcpy (model)");
    return static_cast<const T *>(p);
}

/** \brief Makes \a device the calling thread's current one for the scope's life, then restores the
    thread's own (each host thread has a current device; a caller's may not be the model's). */
class DeviceScope
{
public:
    explicit DeviceScope(int device)
    {
        check(cudaGetDevice(&previous_), "cudaGetDevice");
        if (previous_ != device)
            check(cudaSetDevice(device), "cudaSetDevice");
        device_ = device;
    }
    ~DeviceScope()
    {
        if (previous_ != device_)
            cudaSetDevice(previous_);
    }
    DeviceScope(const DeviceScope &) = delete;
    DeviceScope &operator=(const DeviceScope &) = delete;

private:
    int previous_ = 0;
    int device_ = 0;
};

/** \brief The stages on the device: the model uploaded once; each concurrent pass has its own
    stream and scratch within budget_ (PooledStageRunner), and a pass that finds the device full
    (another executor holds the memory) splits its chunk (StageMemoryExhausted). */
class CudaStageRunner : public PooledStageRunner<CudaExecutor>
{
public:
    CudaStageRunner(const device::ModelArrays &host, std::string deviceName, std::size_t memoryLimit)
        : PooledStageRunner(
              [this]
              {
                  auto ex = std::make_unique<CudaExecutor>(blockThreads_);
                  ex->limitScratch(budget_.maxScratchBytes);
                  return ex;
              }),
          deviceName_(std::move(deviceName)),
          blockThreads_(blockThreads())
    {
        check(cudaGetDevice(&device_), "cudaGetDevice");
        const std::size_t m = static_cast<std::size_t>(host.numComponents);
        arrays_ = copyModelArrays(
            host, [this](const auto *source, std::size_t count) { return uploadOnce(model_memory_, source, count); });

        // cudaMemcpy from pageable memory may return before its DMA lands, and the stages run on a
        // non-blocking stream that does not wait for the legacy one: wait here.
        check(cudaDeviceSynchronize(), "cudaDeviceSynchronize (model upload)");

        // Budgets: the caller's limit, else half the free memory (the rest is left to others),
        // split between the stages' buffers by bytes per element: fragments 56 (key, value, their
        // sorted copies, the rasterized and the walk's fragment: 40; CUB's own sort scratch), (pair, triangle) items
        // 20, (state, pair) elements 8, states perState; what is left covers the surviving pairs' buffers (in a chunk
        // below StageBudget::waitForCountsFrom sized by their bound, survivorBound, a few hundred bytes each) and CUB's
        // scratch. The scratch limit enforces the sum (StageMemoryExhausted).
        std::size_t freeBytes = 0, totalBytes = 0;
        check(cudaMemGetInfo(&freeBytes, &totalBytes), "cudaMemGetInfo");
        const std::size_t usable = memoryLimit > 0 ? std::min(memoryLimit, freeBytes) : freeBytes / 2;
        const std::size_t perState = 8 * static_cast<std::size_t>(host.numCoordinates) +
                                     96 * static_cast<std::size_t>(host.numJoints + host.numLinks) + 160 * m + 64;
        budget_.maxFragments = std::max<std::size_t>(1, usable / 10 * 4 / 56);
        budget_.maxItems = std::max<std::size_t>(1, usable / 10 * 2 / 20);
        budget_.maxPairElements = std::max<std::size_t>(host.numPairs(), usable / 100 * 15 / 8);
        budget_.maxStates = std::max<std::size_t>(1, usable / 10 / perState);
        budget_.maxScratchBytes = usable;
        // 32-bit indices inside a chunk.
        budget_.maxFragments = std::min<std::size_t>(budget_.maxFragments, 1u << 31);
        budget_.maxItems = std::min<std::size_t>(budget_.maxItems, 1u << 31);
        budget_.maxPairElements = std::min<std::size_t>(budget_.maxPairElements, 1u << 31);
    }

    std::string name() const override { return "cuda (" + deviceName_ + ")"; }

    /** \brief A pass on the model's device, whichever device the calling thread has current (its
        executor, made on first use, lives there too). */
    void run(const double *q, const std::uint8_t *admissible, std::size_t n, const device::StageSettings &settings,
             std::vector<device::PairOutcome> &outcomes) override
    {
        const DeviceScope scope(device_);
        PooledStageRunner::run(q, admissible, n, settings, outcomes);
    }

private:
    int device_ = 0;  ///< the device current when the model was uploaded
    std::string deviceName_;
    unsigned blockThreads_;  ///< threads per block of the executors' light kernels (blockThreads())
    std::vector<DeviceAllocation> model_memory_;  // what arrays_ point into
};
}  // namespace

bool deviceUsable(std::string &description)
{
    int count = 0;
    cudaError_t status = cudaGetDeviceCount(&count);
    // Without a driver the runtime says "CUDA driver version is insufficient for CUDA runtime
    // version", which reads as an outdated driver; the plain fact is that there is none.
    if (status == cudaErrorInsufficientDriver || status == cudaErrorNoDevice || (status == cudaSuccess && count == 0))
    {
        description = "no NVIDIA driver or device found";
        cudaGetLastError();  // clear the sticky error state
        return false;
    }
    if (status != cudaSuccess)
    {
        description = std::string("CUDA unusable: ") + cudaGetErrorString(status);
        cudaGetLastError();
        return false;
    }
    cudaDeviceProp properties{};
    if ((status = cudaGetDeviceProperties(&properties, 0)) != cudaSuccess)
    {
        description = std::string("CUDA device 0 unreadable: ") + cudaGetErrorString(status);
        return false;
    }
    // A device this build has no kernels for (or a broken driver) shows on the first launch.
    int *probe = nullptr;
    int answer = 0;
    status = cudaMalloc(&probe, sizeof(int));
    if (status == cudaSuccess)
    {
        probeKernel<<<1, 1>>>(probe);
        status = cudaGetLastError();
        if (status == cudaSuccess)
            status = cudaMemcpy(&answer, probe, sizeof(int), cudaMemcpyDeviceToHost);
        cudaFree(probe);
    }
    if (status != cudaSuccess || answer != 42)
    {
        description = std::string(properties.name) + " cannot run this build's kernels: " + cudaGetErrorString(status);
        cudaGetLastError();
        return false;
    }
    std::size_t freeBytes = 0, totalBytes = 0;
    cudaMemGetInfo(&freeBytes, &totalBytes);
    description = std::string(properties.name) + ", compute " + std::to_string(properties.major) + "." +
                  std::to_string(properties.minor) + ", " + std::to_string(freeBytes >> 30) + " GiB free";
    return true;
}

std::unique_ptr<StageRunner> makeStageRunner(const device::ModelArrays &model, std::size_t memoryLimit)
{
    cudaDeviceProp properties{};
    check(cudaGetDeviceProperties(&properties, 0), "cudaGetDeviceProperties");
    return std::make_unique<CudaStageRunner>(model, properties.name, memoryLimit);
}
}  // namespace rastercheck::cuda
