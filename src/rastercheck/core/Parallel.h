#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>

namespace rastercheck
{
/** \brief Calls body(i) for every i in [0, n) on OpenMP's threads, one index at a time to whichever
    thread is free (the items of a model's build differ in cost by 100x), and rethrows the first
    exception a call threw once all are done (an exception must not leave an OpenMP region). For
    independent items whose results do not depend on the order they run in. */
template <class Body>
void parallelFor(std::size_t n, const Body &body)
{
    std::exception_ptr failure;
    std::mutex mutex;
    const auto count = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t i = 0; i < count; ++i)
    {
        try
        {
            body(static_cast<std::size_t>(i));
        }
        catch (...)
        {
            const std::lock_guard<std::mutex> lock(mutex);
            if (!failure)
                failure = std::current_exception();
        }
    }
    if (failure)
        std::rethrow_exception(failure);
}
}  // namespace rastercheck
