#include "rastercheck/ompl/StateMapping.h"

#include <cmath>

#include <ompl/base/ProjectionEvaluator.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/SE2StateSpace.h>
#include <ompl/base/spaces/SE3StateSpace.h>
#include <ompl/base/spaces/SO2StateSpace.h>
#include <ompl/base/spaces/SO3StateSpace.h>

#include "rastercheck/core/Error.h"

namespace ob = ::ompl::base;

namespace rastercheck::ompl
{
namespace
{
/** \brief Writes a unit quaternion (x y z w) from \a q into \a rotation; zero or non-finite: identity. */
void setNormalisedRotation(const double *q, ob::SO3StateSpace::StateType &rotation)
{
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm > 0.0) || !std::isfinite(norm))
    {
        rotation.setIdentity();
        return;
    }
    rotation.x = q[0] / norm;
    rotation.y = q[1] / norm;
    rotation.z = q[2] / norm;
    rotation.w = q[3] / norm;
}

double wrapAngle(double angle)
{
    if (!std::isfinite(angle))
        return angle;
    double wrapped = std::remainder(angle, 2.0 * M_PI);
    if (wrapped >= M_PI)
        wrapped -= 2.0 * M_PI;
    return wrapped;
}

ob::RealVectorBounds boundsOf(const RobotModel &robot, const std::vector<int> &coordinates)
{
    ob::RealVectorBounds bounds(static_cast<unsigned int>(coordinates.size()));
    for (std::size_t k = 0; k < coordinates.size(); ++k)
    {
        const int c = coordinates[k];
        const double lo = robot.lowerBounds[c], hi = robot.upperBounds[c];
        if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
            throw ConfigurationError("coordinate '" + robot.coordinateNames[c] +
                                     "' has no finite bounds [lower <= upper]; it cannot be planned (hold it)");
        bounds.setLow(static_cast<unsigned int>(k), lo);
        bounds.setHigh(static_cast<unsigned int>(k), hi);
    }
    return bounds;
}
}  // namespace

StateMapping::StateMapping(RobotModelConstPtr robot, const StateMappingOptions &options)
    : robot_(std::move(robot)), boundsTolerance_(options.boundsTolerance)
{
    if (!robot_)
        throw ConfigurationError("StateMapping: no robot model");
    if (!(std::isfinite(boundsTolerance_) && boundsTolerance_ >= 0))
        throw ConfigurationError("the bounds tolerance must be a finite number >= 0");
    const RobotModel &model = *robot_;
    const std::size_t n = model.numCoordinates();
    held_.assign(n, false);
    base_ = model.neutralConfiguration();
    for (const auto &[name, value] : options.heldCoordinates)
    {
        const int c = model.coordinateIndex(name);
        if (c < 0)
            throw ConfigurationError("held coordinate '" + name + "' is not a coordinate of robot '" + model.name +
                                     "'");
        if (!std::isfinite(value))
            throw ConfigurationError("held coordinate '" + name + "' has a non-finite value");
        held_[c] = true;
        base_[c] = value;
    }

    auto addReal = [this](int c)
    {
        if (blocks_.empty() || blocks_.back().kind != BlockKind::RealVector)
            blocks_.push_back({BlockKind::RealVector, {}});
        blocks_.back().coordinates.push_back(c);
    };
    for (const Joint &joint : model.joints)
    {
        if (joint.firstCoordinate < 0)
            continue;
        const int first = joint.firstCoordinate;
        const int count = static_cast<int>(joint.coordinateNames.size());
        int planned = 0;
        for (int k = 0; k < count; ++k)
            planned += held_[first + k] ? 0 : 1;
        if (planned == 0)
            continue;
        switch (joint.kind)
        {
            case JointKind::Revolute:
                if (joint.continuous)
                    blocks_.push_back({BlockKind::SO2, {first}});
                else
                    addReal(first);
                break;
            case JointKind::Prismatic:
                addReal(first);
                break;
            case JointKind::Planar:
                if (planned == 3)
                {
                    blocks_.push_back({BlockKind::SE2, {first, first + 1, first + 2}});
                    break;
                }
                for (int k = 0; k < 2; ++k)
                    if (!held_[first + k])
                        addReal(first + k);
                if (!held_[first + 2])
                    blocks_.push_back({BlockKind::SO2, {first + 2}});
                break;
            case JointKind::Floating:
            {
                int rotationPlanned = 0;
                for (int k = 3; k < 7; ++k)
                    rotationPlanned += held_[first + k] ? 0 : 1;
                if (rotationPlanned != 0 && rotationPlanned != 4)
                    throw ConfigurationError("floating joint '" + joint.name +
                                             "': hold all of its quaternion coordinates or none");
                if (planned == 7)
                {
                    blocks_.push_back(
                        {BlockKind::SE3, {first, first + 1, first + 2, first + 3, first + 4, first + 5, first + 6}});
                    break;
                }
                for (int k = 0; k < 3; ++k)
                    if (!held_[first + k])
                        addReal(first + k);
                if (rotationPlanned == 4)
                    blocks_.push_back({BlockKind::SO3, {first + 3, first + 4, first + 5, first + 6}});
                break;
            }
            default:
                throw ConfigurationError("joint '" + joint.name + "' consumes coordinates but has no movable kind");
        }
    }
    if (blocks_.empty())
        throw ConfigurationError("robot '" + model.name + "': every coordinate is held, nothing to plan");

    std::vector<ob::StateSpacePtr> spaces;
    for (const Block &block : blocks_)
    {
        planned_.insert(planned_.end(), block.coordinates.begin(), block.coordinates.end());
        switch (block.kind)
        {
            case BlockKind::RealVector:
            {
                auto space =
                    std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned int>(block.coordinates.size()));
                space->setBounds(boundsOf(model, block.coordinates));
                for (std::size_t k = 0; k < block.coordinates.size(); ++k)
                    space->setDimensionName(static_cast<unsigned int>(k), model.coordinateNames[block.coordinates[k]]);
                spaces.push_back(space);
                break;
            }
            case BlockKind::SO2:
                spaces.push_back(std::make_shared<ob::SO2StateSpace>());
                break;
            case BlockKind::SO3:
                spaces.push_back(std::make_shared<ob::SO3StateSpace>());
                break;
            case BlockKind::SE2:
            {
                auto space = std::make_shared<ob::SE2StateSpace>();
                space->setBounds(boundsOf(model, {block.coordinates[0], block.coordinates[1]}));
                spaces.push_back(space);
                break;
            }
            case BlockKind::SE3:
            {
                auto space = std::make_shared<ob::SE3StateSpace>();
                space->setBounds(boundsOf(model, {block.coordinates[0], block.coordinates[1], block.coordinates[2]}));
                spaces.push_back(space);
                break;
            }
        }
    }
    if (spaces.size() == 1)
    {
        space_ = spaces.front();
        return;
    }
    compound_ = true;
    auto compound = std::make_shared<ob::CompoundStateSpace>();
    unsigned int largest = 0;
    for (std::size_t b = 0; b < spaces.size(); ++b)
    {
        compound->addSubspace(spaces[b], 1.0);
        if (spaces[b]->getDimension() > spaces[largest]->getDimension())
            largest = static_cast<unsigned int>(b);
    }
    compound->lock();
    compound->registerDefaultProjection(std::make_shared<ob::SubspaceProjectionEvaluator>(compound.get(), largest));
    space_ = compound;
}

const ob::State *StateMapping::blockState(const ob::State *state, std::size_t block) const
{
    return compound_ ? state->as<ob::CompoundState>()->components[block] : state;
}

ob::State *StateMapping::blockState(ob::State *state, std::size_t block) const
{
    return compound_ ? state->as<ob::CompoundState>()->components[block] : state;
}

void StateMapping::toConfiguration(const ob::State *state, double *q) const
{
    for (std::size_t c = 0; c < base_.size(); ++c)
        if (held_[c])
            q[c] = base_[c];
    for (std::size_t b = 0; b < blocks_.size(); ++b)
    {
        const Block &block = blocks_[b];
        const int *c = block.coordinates.data();
        const ob::State *s = blockState(state, b);
        switch (block.kind)
        {
            case BlockKind::RealVector:
            {
                const double *values = s->as<ob::RealVectorStateSpace::StateType>()->values;
                for (std::size_t k = 0; k < block.coordinates.size(); ++k)
                    q[c[k]] = values[k];
                break;
            }
            case BlockKind::SO2:
                q[c[0]] = s->as<ob::SO2StateSpace::StateType>()->value;
                break;
            case BlockKind::SO3:
            {
                const auto *r = s->as<ob::SO3StateSpace::StateType>();
                q[c[0]] = r->x;
                q[c[1]] = r->y;
                q[c[2]] = r->z;
                q[c[3]] = r->w;
                break;
            }
            case BlockKind::SE2:
            {
                const auto *se2 = s->as<ob::SE2StateSpace::StateType>();
                q[c[0]] = se2->getX();
                q[c[1]] = se2->getY();
                q[c[2]] = se2->getYaw();
                break;
            }
            case BlockKind::SE3:
            {
                const auto *se3 = s->as<ob::SE3StateSpace::StateType>();
                const auto &r = se3->rotation();
                q[c[0]] = se3->getX();
                q[c[1]] = se3->getY();
                q[c[2]] = se3->getZ();
                q[c[3]] = r.x;
                q[c[4]] = r.y;
                q[c[5]] = r.z;
                q[c[6]] = r.w;
                break;
            }
        }
    }
}

std::vector<double> StateMapping::toConfiguration(const ob::State *state) const
{
    std::vector<double> q(base_);
    toConfiguration(state, q.data());
    return q;
}

void StateMapping::fromConfiguration(const double *q, ob::State *state) const
{
    for (std::size_t b = 0; b < blocks_.size(); ++b)
    {
        const Block &block = blocks_[b];
        const int *c = block.coordinates.data();
        ob::State *s = blockState(state, b);
        switch (block.kind)
        {
            case BlockKind::RealVector:
            {
                double *values = s->as<ob::RealVectorStateSpace::StateType>()->values;
                for (std::size_t k = 0; k < block.coordinates.size(); ++k)
                    values[k] = q[c[k]];
                break;
            }
            case BlockKind::SO2:
                s->as<ob::SO2StateSpace::StateType>()->value = wrapAngle(q[c[0]]);
                break;
            case BlockKind::SO3:
            {
                const double quaternion[4] = {q[c[0]], q[c[1]], q[c[2]], q[c[3]]};
                setNormalisedRotation(quaternion, *s->as<ob::SO3StateSpace::StateType>());
                break;
            }
            case BlockKind::SE2:
            {
                auto *se2 = s->as<ob::SE2StateSpace::StateType>();
                se2->setXY(q[c[0]], q[c[1]]);
                se2->setYaw(wrapAngle(q[c[2]]));
                break;
            }
            case BlockKind::SE3:
            {
                auto *se3 = s->as<ob::SE3StateSpace::StateType>();
                se3->setXYZ(q[c[0]], q[c[1]], q[c[2]]);
                const double quaternion[4] = {q[c[3]], q[c[4]], q[c[5]], q[c[6]]};
                setNormalisedRotation(quaternion, se3->rotation());
                break;
            }
        }
    }
}

void StateMapping::fromConfiguration(const std::vector<double> &q, ob::State *state) const
{
    if (q.size() != base_.size())
        throw ConfigurationError("configuration has " + std::to_string(q.size()) + " values, robot '" + robot_->name +
                                 "' has " + std::to_string(base_.size()) + " coordinates");
    fromConfiguration(q.data(), state);
}
}  // namespace rastercheck::ompl
