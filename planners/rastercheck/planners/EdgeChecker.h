#pragma once

#include <cstdint>
#include <memory>
#include <string>
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

    /** \brief "certified", "batched" or "one at a time": what check() runs. */
    const std::string &description() const { return description_; }

private:
    ::ompl::base::SpaceInformationPtr si_;
    const ompl::StateValidityChecker *states_ = nullptr;  ///< rastercheck's, or null
    const ompl::BatchMotionValidator *batch_ = nullptr;
    std::shared_ptr<ompl::BatchMotionValidator> owned_;
    std::string description_;
};
}  // namespace rastercheck::planners
