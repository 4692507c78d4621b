#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace rastercheck
{
/** \brief Records what an executor issues between the driver's beginReplayable() and its next
    wait(): each operation (a kernel, a CUB call, a copy) as a closure, and a signature of
    everything it hands the device (which kernel, how many elements, the bytes of its per-element
    function with every pointer and value it captured, the copies' addresses and sizes). A pass
    whose signature equals an earlier pass's issues exactly the same work on the same memory, so the
    CUDA executor captures such a pass once as a CUDA graph and from then on launches the graph: one
    launch instead of about twenty, and no capture. A pass seen for the first time is issued as
    recorded; the second time it is compiled (captured), the third time on replayed. The host
    executor runs the same recorder, compiling nothing, so that the tests see on any machine which
    calls a GPU would replay.

    The closures run later than the driver asked for them, so nothing they use may change before
    they run: an executor interrupts the recording (issuing what it holds) before it grows or frees
    memory. The signature holds values only (trivially copyable parts: a pointer, never what it
    points to, which is data the replay reads as the pass would), their padding zeroed where the
    compiler can (else padding that differs between calls makes a pass look new: it then runs as
    recorded, slower, never wrong). \a Compiled is what a compiled pass
    keeps (a CUDA graph; for the host executor nothing). */
template <class Compiled>
class PassRecorder
{
public:
    using Operation = std::function<void()>;

    /** \brief At most this many signatures are remembered (least recently used go first). */
    static constexpr std::size_t kMaxPasses = 16;

    bool recording() const { return recording_; }

    void begin()
    {
        recording_ = true;
        operations_.clear();
        signature_.clear();
    }

    /** \brief Records \a operation (its signature: \a parts) while recording, else issues it. */
    template <class... Parts>
    void issue(Operation operation, const Parts &...parts)
    {
        if (recording_)
            record(std::move(operation), parts...);
        else
            operation();
    }

    static void issueAll(std::vector<Operation> &operations)
    {
        for (Operation &operation : operations)
            operation();
    }

    /** \brief Issues what was recorded as it was recorded and ends the recording; nothing is
        remembered of it. */
    void interrupt()
    {
        if (!recording_)
            return;
        recording_ = false;
        issueAll(operations_);
        operations_.clear();
    }

    /** \brief Ends the recording without issuing it: the pass is abandoned (its memory freed). */
    void discard()
    {
        recording_ = false;
        operations_.clear();
    }

    /** \brief How finish() issued a pass. */
    enum class Issued
    {
        AsRecorded,   ///< a new signature (or none recorded): the operations one by one
        CompiledNow,  ///< seen once before: compiled (and so issued) now
        Replayed      ///< compiled before: replayed
    };

    /** \brief Ends the recording. A signature compiled before: replay(compiled, operations); seen
        once: compile(operations) (which issues them), kept; new: the operations issued as
        recorded, the signature remembered. */
    template <class Compile, class Replay>
    Issued finish(Compile &&compile, Replay &&replay)
    {
        if (!recording_)
            return Issued::AsRecorded;
        recording_ = false;
        ++clock_;
        const std::uint64_t hash = hashOf(signature_);
        for (Pass &pass : passes_)
        {
            if (pass.hash != hash || pass.signature != signature_)
                continue;
            pass.lastUse = clock_;
            if (pass.compiled)
            {
                replay(*pass.compiled, operations_);
                operations_.clear();
                return Issued::Replayed;
            }
            pass.compiled = std::make_unique<Compiled>(compile(operations_));
            operations_.clear();
            return Issued::CompiledNow;
        }
        issueAll(operations_);
        operations_.clear();
        Pass *slot = nullptr;
        if (passes_.size() < kMaxPasses)
            slot = &passes_.emplace_back();
        else
            for (Pass &pass : passes_)
                if (!slot || pass.lastUse < slot->lastUse)
                    slot = &pass;
        slot->hash = hash;
        slot->signature.swap(signature_);
        slot->compiled.reset();
        slot->lastUse = clock_;
        return Issued::AsRecorded;
    }

    /** \brief Forgets every remembered pass (their memory is about to go). */
    void forget() { passes_.clear(); }

private:
    /** \brief Records \a operation, with the bytes of each of \a parts in the signature. */
    template <class... Parts>
    void record(Operation operation, const Parts &...parts)
    {
        (appendValue(parts), ...);
        operations_.push_back(std::move(operation));
    }

    struct Pass
    {
        std::uint64_t hash = 0;
        std::vector<unsigned char> signature;
        std::unique_ptr<Compiled> compiled;
        unsigned long long lastUse = 0;
    };

    /** \brief The bytes of \a value with its padding zeroed: a closure's padding holds whatever
        the stack held, which would make every pass look new. */
    template <class T>
    void appendValue(const T &value)
    {
        static_assert(std::is_trivially_copyable_v<T>, "a signature holds values, not what they own elsewhere");
        alignas(T) unsigned char bytes[sizeof(T)];
        std::memcpy(bytes, static_cast<const void *>(&value), sizeof(T));
#if defined(__has_builtin)
#if __has_builtin(__builtin_clear_padding)
        __builtin_clear_padding(reinterpret_cast<T *>(bytes));
#endif
#endif
        append(bytes, sizeof(T));
    }

    void append(const void *bytes, std::size_t size)
    {
        const auto *p = static_cast<const unsigned char *>(bytes);
        signature_.insert(signature_.end(), p, p + size);
    }

    /** \brief FNV-1a over 8-byte words (a signature is a few kilobytes). */
    static std::uint64_t hashOf(const std::vector<unsigned char> &bytes)
    {
        std::uint64_t hash = 1469598103934665603ull;
        std::size_t i = 0;
        for (; i + 8 <= bytes.size(); i += 8)
        {
            std::uint64_t word;
            std::memcpy(&word, bytes.data() + i, 8);
            hash = (hash ^ word) * 1099511628211ull;
        }
        for (; i < bytes.size(); ++i)
            hash = (hash ^ bytes[i]) * 1099511628211ull;
        return hash;
    }

    bool recording_ = false;
    std::vector<Operation> operations_;
    std::vector<unsigned char> signature_;
    std::vector<Pass> passes_;
    unsigned long long clock_ = 0;
};
}  // namespace rastercheck
