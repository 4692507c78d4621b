#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rastercheck/geometry/Aabb.h"
#include "rastercheck/geometry/Mesh.h"
#include "rastercheck/geometry/MeshTopology.h"
#include "rastercheck/geometry/Primitives.h"

namespace rastercheck
{
/** \brief One Party-2 object: a static triangle mesh in the world frame. */
struct SceneObject
{
    std::string name;
    Mesh mesh;  ///< world frame, metres (or model units for OMPL.app problems)
    MeshTopology topology;
    Aabb bounds;  ///< world frame
    /** \brief The exact shapes (world frame) when the object is made of primitives only; empty
        otherwise. */
    std::vector<PrimitiveShape> shapes;
};

/** \brief The environment (Party-2): immutable once built, shared as SceneConstPtr. */
class Scene
{
public:
    std::vector<SceneObject> objects;

    /** \brief Adds an object: cleans its mesh (cleanMesh), computes bounds. Empty meshes are skipped
        with a warning naming \a name (an empty object can never collide). An open mesh (holes after
        cleaning) is kept with a warning: it is a surface without an inside, so a component entirely
        inside it is not a collision. Throws ConfigurationError when an object named \a name exists
        (contacts name objects; two of one name would make a contact ambiguous). \a shapes: the
        exact primitives \a worldMesh stands for (world frame), when it is made of them only. */
    void addObject(std::string name, Mesh worldMesh, std::vector<PrimitiveShape> shapes = {});

    std::size_t numObjects() const { return objects.size(); }
    std::size_t numTriangles() const;
    Aabb bounds() const;
    int objectIndex(const std::string &objectName) const;
};

using ScenePtr = std::shared_ptr<Scene>;
using SceneConstPtr = std::shared_ptr<const Scene>;
}  // namespace rastercheck
