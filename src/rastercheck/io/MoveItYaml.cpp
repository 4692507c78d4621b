#include "rastercheck/io/MoveItYaml.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/core/Text.h"

namespace rastercheck
{
namespace
{
// Every access goes through these helpers so that a wrong type or a bad number becomes an
// InputError naming the file and the element instead of a yaml-cpp exception.
class Reader
{
public:
    explicit Reader(std::string file) : file_(std::move(file)) {}

    YAML::Node parse(const std::string &text) const
    {
        try
        {
            return YAML::Load(text);
        }
        catch (const YAML::Exception &e)
        {
            throw InputError(file_, "line " + std::to_string(e.mark.line + 1), "malformed YAML: " + e.msg);
        }
    }

    double number(const YAML::Node &node, const std::string &where) const
    {
        if (!node || !node.IsScalar())
            throw InputError(file_, where, "expected a number");
        double value = 0.0;
        try
        {
            value = node.as<double>();
        }
        catch (const YAML::Exception &)
        {
            throw InputError(file_, where, "'" + node.Scalar() + "' is not a number");
        }
        if (!std::isfinite(value))
            throw InputError(file_, where, "'" + node.Scalar() + "' is not a finite number");
        return value;
    }

    std::string text(const YAML::Node &node, const std::string &where) const
    {
        if (!node || !node.IsScalar())
            throw InputError(file_, where, "expected a string");
        return node.Scalar();
    }

    std::vector<double> numbers(const YAML::Node &node, const std::string &where) const
    {
        if (!node || !node.IsSequence())
            throw InputError(file_, where, "expected a list of numbers");
        std::vector<double> values;
        for (std::size_t i = 0; i < node.size(); ++i)
            values.push_back(number(node[i], where + "[" + std::to_string(i) + "]"));
        return values;
    }

    std::vector<std::string> texts(const YAML::Node &node, const std::string &where) const
    {
        if (!node || !node.IsSequence())
            throw InputError(file_, where, "expected a list of strings");
        std::vector<std::string> values;
        for (std::size_t i = 0; i < node.size(); ++i)
            values.push_back(text(node[i], where + "[" + std::to_string(i) + "]"));
        return values;
    }

    const YAML::Node sequence(const YAML::Node &node, const std::string &where) const
    {
        if (node && !node.IsSequence() && !node.IsNull())
            throw InputError(file_, where, "expected a list");
        return node;
    }

    // A point as [x, y, z] (MotionBenchMaker) or {x:, y:, z:} (ROS message YAML).
    Eigen::Vector3d vector3(const YAML::Node &node, const std::string &where) const
    {
        if (node && node.IsMap())
            return Eigen::Vector3d(number(node["x"], where + ".x"), number(node["y"], where + ".y"),
                                   number(node["z"], where + ".z"));
        const std::vector<double> v = numbers(node, where);
        if (v.size() != 3)
            throw InputError(file_, where, "expected 3 numbers, got " + std::to_string(v.size()));
        return Eigen::Vector3d(v[0], v[1], v[2]);
    }

    // A quaternion as [x, y, z, w] or {x:, y:, z:, w:}, normalised.
    Eigen::Quaterniond quaternion(const YAML::Node &node, const std::string &where) const
    {
        Eigen::Vector4d q;
        if (node && node.IsMap())
        {
            // One by one, not through Eigen's comma initializer: a component that throws would leave
            // the initializer incomplete, which Eigen asserts on while the exception unwinds.
            for (int i = 0; i < 4; ++i)
            {
                const std::string key(1, "xyzw"[i]);
                q[i] = number(node[key], where + "." + key);
            }
        }
        else
        {
            const std::vector<double> v = numbers(node, where);
            if (v.size() != 4)
                throw InputError(file_, where, "expected 4 numbers (x y z w), got " + std::to_string(v.size()));
            q << v[0], v[1], v[2], v[3];
        }
        if (!(q.norm() > 0.0))
            throw InputError(file_, where, "quaternion has zero length");
        q.normalize();
        return Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
    }

    // geometry_msgs/Pose; an absent orientation is the identity (MoveIt does the same).
    Eigen::Isometry3d pose(const YAML::Node &node, const std::string &where) const
    {
        if (!node || !node.IsMap())
            throw InputError(file_, where, "expected a pose with position and orientation");
        Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
        if (node["position"])
            out.translation() = vector3(node["position"], where + ".position");
        if (node["orientation"])
            out.linear() = quaternion(node["orientation"], where + ".orientation").toRotationMatrix();
        return out;
    }

    const std::string &file() const { return file_; }

private:
    std::string file_;
};

std::string readFile(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path, "", "file not found");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// shape_msgs/SolidPrimitive: type as a name or its message constant, dimensions per type.
Mesh primitiveMesh(const Reader &reader, const YAML::Node &node, const std::string &where, double primitiveError,
                   PrimitiveShape &exact)
{
    if (!node || !node.IsMap())
        throw InputError(reader.file(), where, "expected a primitive with type and dimensions");
    std::string type = lowerCase(reader.text(node["type"], where + ".type"));
    static const std::map<std::string, std::string> byNumber{
        {"1", "box"}, {"2", "sphere"}, {"3", "cylinder"}, {"4", "cone"}};
    if (byNumber.count(type))
        type = byNumber.at(type);
    const std::vector<double> d = reader.numbers(node["dimensions"], where + ".dimensions");
    auto require = [&](std::size_t count, const char *meaning)
    {
        if (d.size() < count)
            throw InputError(reader.file(), where + ".dimensions",
                             type + " needs " + std::to_string(count) + " dimensions (" + meaning + "), got " +
                                 std::to_string(d.size()));
        for (std::size_t i = 0; i < count; ++i)
            if (!(d[i] > 0.0))
                throw InputError(reader.file(), where + ".dimensions", type + " dimensions must be positive");
    };
    if (type == "box")
    {
        require(3, "x y z");
        exact.size = Eigen::Vector3d(d[0], d[1], d[2]);
        return makeBox(Eigen::Vector3d(d[0], d[1], d[2]));
    }
    if (type == "sphere")
    {
        require(1, "radius");
        exact.kind = PrimitiveShape::Kind::Sphere;
        exact.size.x() = d[0];
        return makeSphere(d[0], primitiveError);
    }
    if (type == "cylinder")
    {
        require(2, "height radius");
        exact.kind = PrimitiveShape::Kind::Cylinder;
        exact.size = Eigen::Vector3d(d[1], d[0], 0.0);
        return makeCylinder(d[1], d[0], primitiveError);
    }
    if (type == "cone")
    {
        require(2, "height radius");
        exact.kind = PrimitiveShape::Kind::Cone;
        exact.size = Eigen::Vector3d(d[1], d[0], 0.0);
        return makeCone(d[1], d[0], primitiveError);
    }
    throw InputError(reader.file(), where + ".type",
                     "unknown primitive type '" + type + "' (expected box, sphere, cylinder or cone)");
}

// shape_msgs/Mesh: triangles[].vertex_indices and vertices[] as points.
Mesh messageMesh(const Reader &reader, const YAML::Node &node, const std::string &where)
{
    if (!node || !node.IsMap())
        throw InputError(reader.file(), where, "expected a mesh with triangles and vertices");
    Mesh mesh;
    const YAML::Node vertices = reader.sequence(node["vertices"], where + ".vertices");
    for (std::size_t i = 0; vertices && i < vertices.size(); ++i)
        mesh.vertices.push_back(reader.vector3(vertices[i], where + ".vertices[" + std::to_string(i) + "]"));
    const YAML::Node triangles = reader.sequence(node["triangles"], where + ".triangles");
    for (std::size_t i = 0; triangles && i < triangles.size(); ++i)
    {
        const std::string at = where + ".triangles[" + std::to_string(i) + "]";
        const YAML::Node indices = triangles[i].IsMap() ? triangles[i]["vertex_indices"] : triangles[i];
        const std::vector<double> v = reader.numbers(indices, at);
        if (v.size() != 3)
            throw InputError(reader.file(), at, "expected 3 vertex indices");
        Mesh::Triangle t;
        for (int k = 0; k < 3; ++k)
        {
            if (v[k] < 0 || v[k] >= static_cast<double>(mesh.vertices.size()) || v[k] != std::floor(v[k]))
                throw InputError(reader.file(), at, "vertex index " + std::to_string(v[k]) + " out of range");
            t[k] = static_cast<std::uint32_t>(v[k]);
        }
        mesh.triangles.push_back(t);
    }
    if (mesh.triangles.empty())
        throw InputError(reader.file(), where, "mesh has no triangles");
    return mesh;
}

struct Shape
{
    Mesh mesh;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    bool primitive = false;
    PrimitiveShape exact;  ///< when primitive (pose: the primitive's own, identity)
};

Shape primitiveShape(const Reader &reader, const YAML::Node &node, const std::string &where, double primitiveError)
{
    Shape shape;
    shape.mesh = primitiveMesh(reader, node, where, primitiveError, shape.exact);
    shape.primitive = true;
    return shape;
}

template <class MakeMesh>
void collectShapes(const Reader &reader, const YAML::Node &object, const char *shapesKey, const char *posesKey,
                   const std::string &where, MakeMesh makeMesh, std::vector<Shape> &shapes)
{
    const YAML::Node list = reader.sequence(object[shapesKey], where + " " + shapesKey);
    if (!list || list.size() == 0)
        return;
    const YAML::Node poses = reader.sequence(object[posesKey], where + " " + posesKey);
    if (!poses || poses.size() != list.size())
        throw InputError(reader.file(), where + " " + posesKey,
                         std::to_string(list.size()) + " " + shapesKey + " need as many " + posesKey + ", got " +
                             std::to_string(poses ? poses.size() : 0));
    for (std::size_t i = 0; i < list.size(); ++i)
    {
        const std::string at = where + " " + shapesKey + "[" + std::to_string(i) + "]";
        Shape shape = makeMesh(list[i], at);
        shape.pose = reader.pose(poses[i], where + " " + posesKey + "[" + std::to_string(i) + "]");
        shapes.push_back(std::move(shape));
    }
}
}  // namespace

namespace
{
ScenePtr readScene(const std::string &yaml, const std::string &sourceName, double primitiveError)
{
    const Reader reader(sourceName);
    const YAML::Node root = reader.parse(yaml);
    if (!root.IsMap())
        throw InputError(sourceName, "", "expected a MoveIt PlanningScene (a map at the top level)");
    auto scene = std::make_shared<Scene>();
    const YAML::Node world = root["world"];
    if (!world)
        return scene;
    if (!world.IsMap())
        throw InputError(sourceName, "world", "expected a map");
    const YAML::Node objects = reader.sequence(world["collision_objects"], "world.collision_objects");
    std::set<std::string> ids;
    for (std::size_t k = 0; objects && k < objects.size(); ++k)
    {
        const YAML::Node object = objects[k];
        if (!object.IsMap())
            throw InputError(sourceName, "collision object #" + std::to_string(k), "expected a map");
        const std::string id = reader.text(object["id"], "collision object #" + std::to_string(k) + " id");
        const std::string where = "collision object '" + id + "'";
        // MoveIt would let the second ADD replace the first: an obstacle of the file silently gone.
        if (!ids.insert(id).second)
            throw InputError(sourceName, where + " (#" + std::to_string(k) + ")", "id defined twice");
        // Only additions describe geometry; MotionBenchMaker scenes carry no operation field.
        if (object["operation"] && object["operation"].IsScalar())
        {
            const std::string operation = object["operation"].Scalar();
            if (operation != "0" && operation != "add" && operation != "ADD" && operation != "append" &&
                operation != "APPEND" && operation != "2")
                throw InputError(sourceName, where + " operation", "only ADD/APPEND objects can be loaded");
        }
        const Eigen::Isometry3d objectPose =
            object["pose"] ? reader.pose(object["pose"], where + " pose") : Eigen::Isometry3d::Identity();
        std::vector<Shape> shapes;
        collectShapes(
            reader, object, "primitives", "primitive_poses", where,
            [&](const YAML::Node &node, const std::string &at)
            { return primitiveShape(reader, node, at, primitiveError); },
            shapes);
        collectShapes(
            reader, object, "meshes", "mesh_poses", where,
            [&](const YAML::Node &node, const std::string &at)
            {
                Shape shape;
                shape.mesh = messageMesh(reader, node, at);
                return shape;
            },
            shapes);
        for (std::size_t i = 0; i < shapes.size(); ++i)
        {
            Mesh worldMesh;
            worldMesh.append(shapes[i].mesh, objectPose * shapes[i].pose);
            try
            {
                std::vector<PrimitiveShape> exact;
                if (shapes[i].primitive)
                {
                    exact.push_back(shapes[i].exact);
                    exact.back().pose = objectPose * shapes[i].pose;
                }
                scene->addObject(shapes.size() == 1 ? id : id + "/" + std::to_string(i), std::move(worldMesh),
                                 std::move(exact));
            }
            catch (const ConfigurationError &e)  // "a/0" from object a's shapes met an object called "a/0"
            {
                throw InputError(sourceName, where, e.what());
            }
        }
    }
    return scene;
}

}  // namespace

// yaml-cpp throws on access that the helpers do not guard (a subscript into a scalar); such input
// is malformed too, and reported with the position yaml-cpp knows.
ScenePtr loadMoveItSceneString(const std::string &yaml, const std::string &sourceName, double primitiveError)
{
    try
    {
        ScenePtr scene = readScene(yaml, sourceName, primitiveError);
        if (scene->objects.empty())
            logWarning(sourceName + ": the scene has no collision objects: only self-collision is checked");
        return scene;
    }
    catch (const YAML::Exception &e)
    {
        throw InputError(sourceName, "line " + std::to_string(e.mark.line + 1), "unexpected YAML structure: " + e.msg);
    }
}

ScenePtr loadMoveItScene(const std::string &path, double primitiveError)
{
    return loadMoveItSceneString(readFile(path), path, primitiveError);
}

namespace
{
MotionPlanRequest readRequest(const std::string &yaml, const std::string &sourceName)
{
    const Reader reader(sourceName);
    const YAML::Node root = reader.parse(yaml);
    if (!root.IsMap())
        throw InputError(sourceName, "", "expected a MoveIt MotionPlanRequest (a map at the top level)");
    MotionPlanRequest request;
    if (root["group_name"])
        request.groupName = reader.text(root["group_name"], "group_name");

    const YAML::Node startState = root["start_state"];
    if (startState && !startState.IsMap() && !startState.IsNull())
        throw InputError(sourceName, "start_state", "expected a map");
    if (startState && startState.IsMap() && startState["joint_state"])
    {
        const YAML::Node jointState = startState["joint_state"];
        const std::vector<std::string> names = reader.texts(jointState["name"], "start_state.joint_state.name");
        const std::vector<double> positions =
            reader.numbers(jointState["position"], "start_state.joint_state.position");
        if (names.size() != positions.size())
            throw InputError(
                sourceName, "start_state.joint_state",
                std::to_string(names.size()) + " names but " + std::to_string(positions.size()) + " positions");
        for (std::size_t i = 0; i < names.size(); ++i)
            if (!request.startJoints.emplace(names[i], positions[i]).second)
                throw InputError(sourceName, "start_state.joint_state.name[" + std::to_string(i) + "]",
                                 "joint '" + names[i] + "' appears twice");
    }

    const YAML::Node goals = reader.sequence(root["goal_constraints"], "goal_constraints");
    if (goals && goals.size() > 0)
    {
        const YAML::Node constraints =
            reader.sequence(goals[0]["joint_constraints"], "goal_constraints[0].joint_constraints");
        for (std::size_t i = 0; constraints && i < constraints.size(); ++i)
        {
            const std::string where = "goal_constraints[0].joint_constraints[" + std::to_string(i) + "]";
            const YAML::Node c = constraints[i];
            if (!c.IsMap())
                throw InputError(sourceName, where, "expected a map");
            const std::string name = reader.text(c["joint_name"], where + ".joint_name");
            if (request.goalJoints.count(name))
                throw InputError(sourceName, where + ".joint_name", "joint '" + name + "' is constrained twice");
            request.goalJoints[name] = reader.number(c["position"], where + ".position");
            if (c["tolerance_above"])
                request.goalToleranceAbove[name] = reader.number(c["tolerance_above"], where + ".tolerance_above");
            if (c["tolerance_below"])
                request.goalToleranceBelow[name] = reader.number(c["tolerance_below"], where + ".tolerance_below");
        }
    }
    return request;
}

}  // namespace

MotionPlanRequest loadMoveItRequestString(const std::string &yaml, const std::string &sourceName)
{
    try
    {
        return readRequest(yaml, sourceName);
    }
    catch (const YAML::Exception &e)
    {
        throw InputError(sourceName, "line " + std::to_string(e.mark.line + 1), "unexpected YAML structure: " + e.msg);
    }
}

MotionPlanRequest loadMoveItRequest(const std::string &path)
{
    return loadMoveItRequestString(readFile(path), path);
}
}  // namespace rastercheck
