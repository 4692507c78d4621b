#include "rastercheck/model/Scene.h"

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"

namespace rastercheck
{
void Scene::addObject(std::string name, Mesh worldMesh, std::vector<PrimitiveShape> shapes)
{
    if (objectIndex(name) >= 0)
        throw ConfigurationError("scene object '" + name + "' is defined twice");
    SceneObject object;
    object.name = std::move(name);
    object.mesh = std::move(worldMesh);
    object.topology = cleanMesh(object.mesh);
    if (object.mesh.empty())
    {
        logWarning("scene object '" + object.name + "' has no triangles; ignored");
        return;
    }
    if (!object.topology.closed)
        logWarning("scene object '" + object.name + "' is " + object.topology.summary() +
                   ": its surface is checked exactly, but a component entirely inside it is not a collision");
    object.bounds = object.mesh.bounds();
    object.shapes = std::move(shapes);
    objects.push_back(std::move(object));
}

std::size_t Scene::numTriangles() const
{
    std::size_t total = 0;
    for (const SceneObject &object : objects)
        total += object.mesh.numTriangles();
    return total;
}

Aabb Scene::bounds() const
{
    Aabb box;
    for (const SceneObject &object : objects)
        box.extend(object.bounds);
    return box;
}

int Scene::objectIndex(const std::string &objectName) const
{
    for (std::size_t i = 0; i < objects.size(); ++i)
        if (objects[i].name == objectName)
            return static_cast<int>(i);
    return -1;
}
}  // namespace rastercheck
