#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/ompl/BatchMotionValidator.h"
#include "rastercheck/ompl/StateValidityChecker.h"

namespace rastercheck::planners
{
/** \brief How the batch planners decide many edges at once on a space information: its motion
    validator when that is a BatchMotionValidator (rastercheck's batched or certified validator, as
    makeSimpleSetup chose); else, when its validity checker is rastercheck's, a
    CertifiedMotionValidator of its own (collision-free edges at every point; in raster mode, which
    cannot certify, the batched validator at the space's resolution); else (a foreign checker) one
    edge at a time through SpaceInformation::checkMotion. Thread safe as the validators are. */
class EdgeChecker
{
public:
    explicit EdgeChecker(const ::ompl::base::SpaceInformationPtr &si);

    /** \brief Decides \a edges: valid[i] = 1 when edge i is accepted. */
    void check(const std::vector<ompl::Edge> &edges, std::vector<std::uint8_t> &valid) const;

    /** \brief Decides \a states alone (not the motions between them): valid[i] = 1 when
        SpaceInformation::isValid accepts states[i]. One Checker::check call when the validity
        checker is rastercheck's, else one isValid call per state. */
    void checkStates(const std::vector<const ::ompl::base::State *> &states, std::vector<std::uint8_t> &valid) const;

    /** \brief Checks the states at \a points (edge index, fraction of the edge; 1 = its end) in one
        batch (checkStates); valid[e] = 0 for every edge with a rejected state, the others are left
        as they are. Returns the number of states checked. */
    std::size_t checkAlong(const std::vector<ompl::Edge> &edges,
                           const std::vector<std::pair<std::size_t, double>> &points,
                           std::vector<std::uint8_t> &valid) const;

    /** \brief States along \a edges at rising density (the midpoints, then the quarter points, ...)
        down to the space's longest valid segment, one batch per level: most edges that cross an
        obstacle are rejected at a few states, for a fraction of what check() costs. valid[e] = 0
        for the edges where a state was rejected, 1 for the others. levels[e]: the levels edge e
        passed before (skipped), and on return the levels it has passed now. \a paths (candidate
        paths, each the indices of its edges; an edge may lie on several): a path is rejected with
        its first rejected edge, the rake goes on only with the edges of paths not rejected, and it
        stops after the level that leaves none; null: every edge is a path of its own. A state check,
        not a decision: an edge the rake passes is decided only by check(). Returns the number of
        states checked. */
    std::size_t rake(const std::vector<ompl::Edge> &edges, std::vector<unsigned int> &levels,
                     std::vector<std::uint8_t> &valid, const std::vector<std::vector<std::size_t>> *paths) const;

    /** \brief The smallest batch of states that runs on the validity checker's GPU backend (or its
        host stages): Checker::deviceBatch(); 0 when its batches run on the CPU, or the validity
        checker is not rastercheck's. */
    std::size_t deviceBatch() const { return states_ ? states_->getChecker().deviceBatch() : 0; }
    /** \brief Whether a batch of \a states runs there (Checker::reachesDevice); false for a foreign
        validity checker. */
    bool reachesDevice(std::size_t states) const { return states_ && states_->getChecker().reachesDevice(states); }

    /** \brief "certified", "batched" or "one at a time": what check() runs. */
    const std::string &description() const { return description_; }
    /** \brief Whether check() certifies edges (collision-free at every point): then a rake before it
        saves work; batched edges check the rake's states themselves. */
    bool certifies() const { return description_ == "certified"; }

private:
    ::ompl::base::SpaceInformationPtr si_;
    const ompl::StateValidityChecker *states_ = nullptr;  ///< rastercheck's, or null
    const ompl::BatchMotionValidator *batch_ = nullptr;
    std::shared_ptr<ompl::BatchMotionValidator> owned_;
    std::string description_;
};
}  // namespace rastercheck::planners
