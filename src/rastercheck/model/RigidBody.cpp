#include "rastercheck/model/RigidBody.h"

#include <cmath>

#include "rastercheck/core/Error.h"

namespace rastercheck
{
RobotModelPtr makeRigidBodyModel(const std::string &name, Mesh mesh, const Aabb &positionBounds, bool planar)
{
    if (positionBounds.empty())
        throw ConfigurationError("rigid body '" + name + "': position bounds are empty (min > max)");
    auto model = std::make_shared<RobotModel>();
    model->name = name;
    model->links = {{"world", -1, -1}, {"body", -1, 0}};

    Joint joint;
    joint.name = "body";
    joint.parentLink = 0;
    joint.childLink = 1;
    const Eigen::Vector3d &lo = positionBounds.min, &hi = positionBounds.max;
    if (planar)
    {
        joint.kind = JointKind::Planar;
        joint.coordinateNames = {"x", "y", "yaw"};
        joint.lower = {lo.x(), lo.y(), -M_PI};
        joint.upper = {hi.x(), hi.y(), M_PI};
    }
    else
    {
        joint.kind = JointKind::Floating;
        joint.coordinateNames = {"x", "y", "z", "qx", "qy", "qz", "qw"};
        joint.lower = {lo.x(), lo.y(), lo.z(), -1, -1, -1, -1};
        joint.upper = {hi.x(), hi.y(), hi.z(), 1, 1, 1, 1};
    }
    model->joints = {joint};

    Component component = makeComponent("body", {std::move(mesh)});
    if (component.mesh.empty())
        throw ConfigurationError("rigid body '" + name + "' has no triangles");
    model->components = {std::move(component)};
    model->finalize();
    return model;
}
}  // namespace rastercheck
