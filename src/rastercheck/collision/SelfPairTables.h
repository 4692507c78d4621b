#pragma once

#include <cstddef>
#include <vector>

#include "rastercheck/device/ClearanceTables.h"

namespace rastercheck
{
class CollisionModel;

/** \brief Clearance tables for the self pairs whose relative pose depends on one or two joint
    coordinates, such as an arm's wrist links: the Panda's panda_link5 against panda_link7 and
    against panda_hand pass the box culls in most states and only the hull test (GJK) tells them
    apart, a quarter of a certified state's check and two fifths of a free one's (docs/benchmarks.md).

    Over a grid of the pair's coordinates (at most 64 nodes each), every node holds a distance the
    two solids provably exceed there: the largest padding on a ladder that relateSolids (the hull
    and shell proofs every backend uses) proves them apart at, from one canonical configuration
    (the other coordinates do not move the pair relative to each other). MotionBound's pair sweep,
    linear in the coordinates' changes and the same in every configuration, bounds how far any
    point of one solid moves relative to the other between the nearest node and a state. So the
    pair is more than padding apart at the state when node clearance - sweep > padding: every
    point pair's distance is at least the hulls' distance at the node less the sweep, and hulls hold
    their meshes. The proof is never wrong; where it does not hold, the pair goes through the
    usual tests.

    A pair qualifies when every joint that moves its two components relative to each other (those
    above exactly one of them, as MotionBound::pairJoints names them) is a revolute (not
    continuous) or prismatic joint with finite bounds that mimics none and that no other joint
    mimics, and at most two of them move. Built once with the model (each node a few
    proofs: about 11 ms per table for the Panda's); immutable, thread-safe. */
class SelfPairTables
{
public:
    SelfPairTables() = default;
    explicit SelfPairTables(const CollisionModel &model);

    /** \brief True when self pair \a pair (an index into CollisionModel::selfPairs) is provably more
        than \a padding apart at \a q (the robot's coordinates). False when the pair has no table,
        the proof does not reach, or a coordinate is not finite. */
    bool apart(std::size_t pair, const double *q, double padding) const;

    /** \brief Whether self pair \a pair has a table. */
    bool hasTable(std::size_t pair) const { return pair < tableOf_.size() && tableOf_[pair] >= 0; }
    /** \brief How many self pairs have a table. */
    std::size_t numTables() const { return tables_.size(); }
    /** \brief Bytes the tables hold. */
    std::size_t memoryBytes() const;

    /** \brief The tables as flat arrays (device::selfPairApartByTable reads them), valid while this
        object lives. */
    device::ClearanceTableArrays arrays() const
    {
        return tableOf_.empty() ? device::ClearanceTableArrays{}
                                : device::ClearanceTableArrays{tableOf_.data(), tables_.data(), clearance_.data()};
    }
    /** \brief The number of nodes of all tables (the size of arrays().clearance). */
    std::size_t numNodes() const { return clearance_.size(); }

private:
    std::vector<int> tableOf_;      ///< per self pair: index into tables_, or -1
    std::vector<device::ClearanceTable> tables_;  ///< n_tables
    std::vector<float> clearance_;  ///< per table, per node (axis 0 slowest); -infinity where no proof held
};
}  // namespace rastercheck
