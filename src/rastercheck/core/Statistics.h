#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace rastercheck
{
/** \brief Median of \a values (mean of the two middle ones for an even count); NaN when empty.
    Used by the planning summaries of the command line and the benches. */
inline double median(std::vector<double> values)
{
    if (values.empty())
        return std::nan("");
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/** \brief The \a q quantile of \a values, q in [0, 1], by the nearest rank below (no interpolation:
    a reported p95 is a time some run took); NaN when empty. */
inline double quantile(std::vector<double> values, double q)
{
    if (values.empty())
        return std::nan("");
    std::sort(values.begin(), values.end());
    const double rank = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size());
    return values[std::min(values.size() - 1, static_cast<std::size_t>(rank))];
}
}  // namespace rastercheck
