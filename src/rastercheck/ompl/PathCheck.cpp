#include "rastercheck/ompl/PathCheck.h"

#include <algorithm>

#include <ompl/base/SpaceInformation.h>

#include "rastercheck/core/Error.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
namespace
{
/** \brief A state of the dense path: segment, time on it, whether it satisfies the bounds. */
struct Sample
{
    std::size_t segment;
    double time;
    bool inBounds;
};
}  // namespace

PathCheckResult checkPathDensely(const ::ompl::geometric::PathGeometric &path, const StateMapping &mapping,
                                 const Checker &checker, const CollisionRequest &request, unsigned int resolutionFactor)
{
    if (resolutionFactor == 0)
        throw ConfigurationError("checkPathDensely: the resolution factor must be at least 1");
    const ob::SpaceInformationPtr &si = path.getSpaceInformation();
    const ob::StateSpacePtr &space = si->getStateSpace();
    const std::size_t dof = mapping.numCoordinates();
    PathCheckResult result;
    const std::size_t count = path.getStateCount();
    if (count == 0)
        return result;

    std::vector<Sample> samples;
    std::vector<double> rows;
    ob::State *test = si->allocState();
    auto add = [&](const ob::State *state, std::size_t segment, double time) {
        const bool inBounds = si->satisfiesBounds(state);
        rows.resize(rows.size() + dof);
        mapping.toConfiguration(state, rows.data() + rows.size() - dof);
        samples.push_back({segment, time, inBounds});
    };
    add(path.getState(0), 0, 0.0);
    for (std::size_t i = 0; i + 1 < count; ++i)
    {
        const ob::State *a = path.getState(i), *b = path.getState(i + 1);
        const unsigned int n = std::max(1u, space->validSegmentCount(a, b)) * resolutionFactor;
        for (unsigned int k = 1; k < n; ++k)
        {
            const double t = static_cast<double>(k) / static_cast<double>(n);
            space->interpolate(a, b, t, test);
            add(test, i, t);
        }
        add(b, i, 1.0);
    }
    si->freeState(test);

    std::vector<std::uint8_t> valid(samples.size());
    std::vector<Contact> contacts(samples.size());
    checker.check(rows.data(), samples.size(), valid.data(), request, contacts.data());
    result.statesChecked = samples.size();
    for (std::size_t s = 0; s < samples.size(); ++s)
    {
        if (samples[s].inBounds && valid[s])
            continue;
        result.valid = false;
        result.segment = samples[s].segment;
        result.time = samples[s].time;
        result.configuration.assign(rows.begin() + static_cast<std::ptrdiff_t>(s * dof),
                                    rows.begin() + static_cast<std::ptrdiff_t>((s + 1) * dof));
        result.contact = contacts[s];
        if (!samples[s].inBounds)
        {
            result.contact = Contact{};
            result.contact.kind = Contact::Kind::OutOfBounds;
        }
        break;
    }
    return result;
}
}  // namespace rastercheck::ompl
