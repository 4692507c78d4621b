#pragma once

#include <string>

#include "rastercheck/geometry/Aabb.h"
#include "rastercheck/geometry/Mesh.h"
#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
/** \brief A free-flying rigid body as a RobotModel: root link "world", one joint "body" moving link
    "body" that carries \a mesh (cleaned, topology checked). 3D: a floating joint with coordinates
    x y z qx qy qz qw, positions bounded by \a positionBounds, quaternion components by [-1, 1].
    Planar: x y yaw in the world xy plane (yaw in [-pi, pi]; z of positionBounds unused). This is how
    OMPL.app problems and synthetic test bodies become robots. */
RobotModelPtr makeRigidBodyModel(const std::string &name, Mesh mesh, const Aabb &positionBounds, bool planar = false);
}  // namespace rastercheck
