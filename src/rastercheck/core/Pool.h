#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace rastercheck
{
/** \brief Objects lent to one caller at a time and kept for later callers (workspaces, executors,
    per-call buffers): borrow() hands out one no other caller holds, made when none is idle, and
    giveBack() returns it with whatever capacity it grew. A steady stream of calls allocates nothing
    after the first; callers that run at the same time each get their own, and the pool holds as
    many as were ever out at once. Thread-safe; lending is logically const for the owner. */
template <class T>
class Pool
{
public:
    explicit Pool(std::function<std::unique_ptr<T>()> make) : make_(std::move(make)) {}

    std::unique_ptr<T> borrow() const
    {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            if (!idle_.empty())
            {
                std::unique_ptr<T> item = std::move(idle_.back());
                idle_.pop_back();
                return item;
            }
        }
        std::unique_ptr<T> item = make_();
        const std::lock_guard<std::mutex> lock(mutex_);
        ++made_;
        return item;
    }

    void giveBack(std::unique_ptr<T> item) const
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        idle_.push_back(std::move(item));
    }

    /** \brief The objects made so far: the most that were out at once. */
    std::size_t made() const
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        return made_;
    }

private:
    std::function<std::unique_ptr<T>()> make_;
    mutable std::mutex mutex_;
    mutable std::vector<std::unique_ptr<T>> idle_;
    mutable std::size_t made_ = 0;
};
}  // namespace rastercheck
