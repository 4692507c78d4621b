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
}  // namespace rastercheck
