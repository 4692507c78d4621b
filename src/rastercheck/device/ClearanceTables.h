#pragma once

// The self pairs' joint-space clearance tables (SelfPairTables builds them) as flat arrays, and
// the one test both backends read them by: the CPU backend's self-pair loop and the stages' pair
// cull, so a pair the tables prove apart skips the hull test on either.

#include <cmath>
#include <cstddef>

#include "rastercheck/device/HostDevice.h"

namespace rastercheck::device
{
/** \brief One coordinate of a table: its nodes from lower, step apart, and the pair sweep per unit
    change of the coordinate (MotionBound's, linear). */
struct ClearanceAxis
{
    int coordinate = -1;
    double lower = 0.0;
    double step = 0.0;  ///< between nodes
    int nodes = 1;
    double rate = 0.0;  ///< the pair sweep per unit change of the coordinate
};

/** \brief A self pair's table over one or two coordinates. */
struct ClearanceTable
{
    ClearanceAxis axes[2];
    int numAxes = 0;
    std::size_t firstClearance = 0;  ///< the table's nodes in ClearanceTableArrays::clearance (axis 0 slowest)
};

/** \brief Every self pair's table (host or device memory). Null \a tableOf: no tables. */
struct ClearanceTableArrays
{
    const int *tableOf = nullptr;  ///< per self pair: its index into tables, or -1
    const ClearanceTable *tables = nullptr;
    const float *clearance =
        nullptr;  ///< per node: a distance the pair provably exceeds; -infinity where no proof held
};

/** \brief True when self pair \a pair (< the number of self pairs) is provably more than \a padding
    apart at \a q (the robot's coordinates): the clearance at the nearest node, less how far the
    pair can move relative to itself between that node and q, exceeds the padding. False when the
    pair has no table, the proof does not reach, or a coordinate is not finite. */
RC_HD bool selfPairApartByTable(const ClearanceTableArrays &arrays, std::size_t pair, const double *q, double padding)
{
    if (!arrays.tableOf || arrays.tableOf[pair] < 0)
        return false;
    const ClearanceTable &table = arrays.tables[arrays.tableOf[pair]];
    double sweep = 0.0;
    std::size_t index = 0;
    for (int k = 0; k < table.numAxes; ++k)
    {
        const ClearanceAxis &axis = table.axes[k];
        const double value = q[axis.coordinate];
        if (!std::isfinite(value))
            return false;
        const double last = static_cast<double>(axis.nodes - 1);
        double node = std::round((value - axis.lower) / axis.step);
        node = node < 0.0 ? 0.0 : (node > last ? last : node);
        sweep += axis.rate * std::fabs(value - (axis.lower + static_cast<int>(node) * axis.step));
        index = index * static_cast<std::size_t>(axis.nodes) + static_cast<std::size_t>(node);
    }
    // The sweep's own rounding: a relative 1e-12 of it.
    return static_cast<double>(arrays.clearance[table.firstClearance + index]) - sweep * (1 + 1e-12) > padding;
}
}  // namespace rastercheck::device
