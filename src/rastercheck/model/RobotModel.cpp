#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Kinematics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <type_traits>

#include "rastercheck/core/Error.h"
#include "rastercheck/geometry/EigenDevice.h"

namespace rastercheck
{
Component makeComponent(const std::string &name, std::vector<Mesh> parts)
{
    Component component;
    component.name = name;
    component.topology = cleanAndMerge(std::move(parts), component.mesh);
    component.localObb = Obb::fit(component.mesh);
    component.localAabb = component.mesh.bounds();
    return component;
}

namespace
{
/** \brief Appends fields one by one (never a struct whole: padding bytes are not content). */
class ContentWriter
{
public:
    template <class T>
    void value(const T &field)
    {
        static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "write a struct's fields one by one");
        bytes.append(reinterpret_cast<const char *>(&field), sizeof(T));
    }
    template <class Derived>
    void matrix(const Eigen::DenseBase<Derived> &m)
    {
        for (Eigen::Index i = 0; i < m.size(); ++i)
            value(static_cast<double>(m.derived().data()[i]));
    }
    void text(const std::string &s)
    {
        value(s.size());
        bytes.append(s);
    }
    template <class T>
    void values(const std::vector<T> &fields)
    {
        value(fields.size());
        for (const T &field : fields)
            value(field);
    }
    void texts(const std::vector<std::string> &fields)
    {
        value(fields.size());
        for (const std::string &field : fields)
            text(field);
    }
    std::string bytes;
};

#if defined(__x86_64__) && defined(__GLIBCXX__) && !defined(_GLIBCXX_DEBUG)
// A field added to one of these types must be written by contentBytes too: else two robots that
// differ only in it would share collision parts built for one of them.
static_assert(sizeof(Joint) == 304, "a new Joint field: write it in contentBytes");
static_assert(sizeof(Link) == 40, "a new Link field: write it in contentBytes");
static_assert(sizeof(Component) == 344, "a new Component field: write it in contentBytes");
static_assert(sizeof(Mesh) == 48, "a new Mesh field: write it in contentBytes");
static_assert(sizeof(MeshTopology) == 64, "a new MeshTopology field: write it in contentBytes");
static_assert(sizeof(PrimitiveShape) == 160, "a new PrimitiveShape field: write it in contentBytes");
static_assert(sizeof(device::KinematicJoint) == 160, "a new KinematicJoint field: write it in contentBytes");
static_assert(sizeof(RobotModel) == 264, "a new RobotModel field: write it in contentBytes");
#endif
}  // namespace

std::string contentBytes(const RobotModel &robot)
{
    ContentWriter out;
    out.text(robot.name);
    out.value(robot.links.size());
    for (const Link &link : robot.links)
    {
        out.text(link.name);
        out.value(link.parentJoint);
        out.value(link.component);
    }
    out.value(robot.joints.size());
    for (const Joint &joint : robot.joints)
    {
        out.text(joint.name);
        out.value(joint.kind);
        out.value(joint.parentLink);
        out.value(joint.childLink);
        out.matrix(joint.origin.matrix());
        out.matrix(joint.axis);
        out.value(joint.continuous);
        out.texts(joint.coordinateNames);
        out.values(joint.lower);
        out.values(joint.upper);
        out.value(joint.firstCoordinate);
        out.value(joint.mimicOf);
        out.value(joint.mimicMultiplier);
        out.value(joint.mimicOffset);
    }
    out.value(robot.components.size());
    for (const Component &component : robot.components)
    {
        out.text(component.name);
        out.value(component.link);
        out.value(component.mesh.vertices.size());
        for (const Eigen::Vector3d &v : component.mesh.vertices)
            out.matrix(v);
        out.value(component.mesh.triangles.size());
        for (const Mesh::Triangle &t : component.mesh.triangles)
            for (std::uint32_t corner : t)
                out.value(corner);
        const MeshTopology &topology = component.topology;
        for (std::size_t count :
             {topology.boundaryEdges, topology.nonManifoldEdges, topology.misorientedEdges,
              topology.degenerateTriangles, topology.mergedVertices, topology.removedDuplicateFaces, topology.shells})
            out.value(count);
        out.value(topology.closed);
        out.matrix(component.localObb.center);
        out.matrix(component.localObb.axes);
        out.matrix(component.localObb.halfExtents);
        out.matrix(component.localAabb.min);
        out.matrix(component.localAabb.max);
        out.value(component.shapes.size());
        for (const PrimitiveShape &shape : component.shapes)
        {
            out.value(shape.kind);
            out.matrix(shape.size);
            out.matrix(shape.pose.matrix());
        }
    }
    out.values(robot.componentSubtreeEnd);
    out.texts(robot.coordinateNames);
    out.values(robot.lowerBounds);
    out.values(robot.upperBounds);
    out.value(robot.allowedCollisions.size());
    for (bool allowed : robot.allowedCollisions)
        out.value(allowed);
    out.value(robot.kinematicJoints.size());
    for (const device::KinematicJoint &joint : robot.kinematicJoints)
    {
        out.value(joint.kind);
        out.value(joint.parentLink);
        out.value(joint.childLink);
        out.value(joint.firstCoordinate);
        out.value(joint.mimicOf);
        out.value(joint.mimicMultiplier);
        out.value(joint.mimicOffset);
        for (double entry : joint.origin.m)
            out.value(entry);
        out.value(joint.axis.x);
        out.value(joint.axis.y);
        out.value(joint.axis.z);
    }
    return std::move(out.bytes);
}

void RobotModel::setCollisionAllowed(int a, int b, bool allowed)
{
    const std::size_t n = components.size();
    allowedCollisions[static_cast<std::size_t>(a) * n + static_cast<std::size_t>(b)] = allowed;
    allowedCollisions[static_cast<std::size_t>(b) * n + static_cast<std::size_t>(a)] = allowed;
}

int RobotModel::linkIndex(const std::string &linkName) const
{
    for (std::size_t i = 0; i < links.size(); ++i)
        if (links[i].name == linkName)
            return static_cast<int>(i);
    return -1;
}

int RobotModel::jointIndex(const std::string &jointName) const
{
    for (std::size_t i = 0; i < joints.size(); ++i)
        if (joints[i].name == jointName)
            return static_cast<int>(i);
    return -1;
}

int RobotModel::coordinateIndex(const std::string &coordinateName) const
{
    auto it = std::find(coordinateNames.begin(), coordinateNames.end(), coordinateName);
    return it == coordinateNames.end() ? -1 : static_cast<int>(it - coordinateNames.begin());
}

std::vector<std::string> RobotModel::activeJointNames() const
{
    std::vector<std::string> names;
    for (const Joint &joint : joints)
        if (joint.firstCoordinate >= 0)
            names.push_back(joint.name);
    return names;
}

std::size_t RobotModel::numTriangles() const
{
    std::size_t total = 0;
    for (const Component &component : components)
        total += component.mesh.numTriangles();
    return total;
}

void RobotModel::finalize()
{
    const int numLinks = static_cast<int>(links.size());
    if (numLinks == 0)
        throw ConfigurationError("robot '" + name + "' has no links");

    // Children of each link, and the single root.
    std::vector<std::vector<int>> childJoints(links.size());
    std::vector<int> parentCount(links.size(), 0);
    for (std::size_t j = 0; j < joints.size(); ++j)
    {
        const Joint &joint = joints[j];
        if (joint.parentLink < 0 || joint.parentLink >= numLinks || joint.childLink < 0 || joint.childLink >= numLinks)
            throw ConfigurationError("joint '" + joint.name + "' refers to a link that does not exist");
        childJoints[joint.parentLink].push_back(static_cast<int>(j));
        ++parentCount[joint.childLink];
    }
    int root = -1;
    for (int l = 0; l < numLinks; ++l)
    {
        if (parentCount[l] > 1)
            throw ConfigurationError("link '" + links[l].name + "' has more than one parent joint");
        if (parentCount[l] == 0)
        {
            if (root >= 0)
                throw ConfigurationError("robot '" + name + "' has several root links ('" + links[root].name +
                                         "', '" + links[l].name + "')");
            root = l;
        }
    }
    if (root < 0)
        throw ConfigurationError("robot '" + name + "' has no root link (the joints form a cycle)");

    // Depth-first order: links, joints (topological), components with their subtree ranges.
    std::vector<int> linkOrder, jointOrder;
    std::vector<int> linkSubtreeEndInOrder;
    std::function<void(int)> visit = [&](int l) {
        linkOrder.push_back(l);
        const std::size_t slot = linkSubtreeEndInOrder.size();
        linkSubtreeEndInOrder.push_back(0);
        for (int j : childJoints[l])
        {
            jointOrder.push_back(j);
            visit(joints[j].childLink);
        }
        linkSubtreeEndInOrder[slot] = static_cast<int>(linkOrder.size());
    };
    visit(root);
    if (static_cast<int>(linkOrder.size()) != numLinks)
        throw ConfigurationError("robot '" + name + "' has links that the root does not reach (a joint cycle)");

    std::vector<int> newLinkIndex(links.size());
    for (int i = 0; i < numLinks; ++i)
        newLinkIndex[linkOrder[i]] = i;
    std::vector<int> newJointIndex(joints.size());
    for (std::size_t i = 0; i < jointOrder.size(); ++i)
        newJointIndex[jointOrder[i]] = static_cast<int>(i);

    std::vector<Link> orderedLinks;
    for (int l : linkOrder)
        orderedLinks.push_back(links[l]);
    std::vector<Joint> orderedJoints;
    for (int j : jointOrder)
    {
        Joint joint = joints[j];
        joint.parentLink = newLinkIndex[joint.parentLink];
        joint.childLink = newLinkIndex[joint.childLink];
        if (joint.mimicOf >= 0)
            joint.mimicOf = newJointIndex[joint.mimicOf];
        orderedJoints.push_back(std::move(joint));
    }
    for (std::size_t j = 0; j < orderedJoints.size(); ++j)
        orderedLinks[orderedJoints[j].childLink].parentJoint = static_cast<int>(j);
    orderedLinks[0].parentJoint = -1;

    // Components follow their links' depth-first order.
    std::vector<Component> orderedComponents;
    std::vector<int> componentOfLinkInOrder(links.size(), -1);
    for (int i = 0; i < numLinks; ++i)
    {
        const int oldComponent = orderedLinks[i].component;
        if (oldComponent < 0)
            continue;
        if (oldComponent >= static_cast<int>(components.size()))
            throw ConfigurationError("link '" + orderedLinks[i].name + "' refers to a component that does not exist");
        componentOfLinkInOrder[i] = static_cast<int>(orderedComponents.size());
        orderedComponents.push_back(std::move(components[oldComponent]));
        orderedComponents.back().link = i;
    }
    for (int i = 0; i < numLinks; ++i)
        orderedLinks[i].component = componentOfLinkInOrder[i];
    componentSubtreeEnd.assign(orderedComponents.size(), 0);
    for (int i = 0; i < numLinks; ++i)
    {
        const int c = componentOfLinkInOrder[i];
        if (c < 0)
            continue;
        int end = c + 1;
        for (int k = i; k < linkSubtreeEndInOrder[i]; ++k)
            if (componentOfLinkInOrder[k] >= 0)
                end = componentOfLinkInOrder[k] + 1;
        componentSubtreeEnd[c] = end;
    }
    links = std::move(orderedLinks);
    joints = std::move(orderedJoints);
    components = std::move(orderedComponents);

    // Configuration layout.
    coordinateNames.clear();
    lowerBounds.clear();
    upperBounds.clear();
    for (Joint &joint : joints)
    {
        joint.firstCoordinate = -1;
        if (joint.mimicOf >= 0)
        {
            const Joint &source = joints[joint.mimicOf];
            if (source.mimicOf >= 0 || device::coordinateCount(source.kind) != 1)
                throw ConfigurationError("joint '" + joint.name + "' mimics '" + source.name +
                                         "', which is not a one-coordinate joint that moves on its own");
            if (device::coordinateCount(joint.kind) != 1)
                throw ConfigurationError("mimic joint '" + joint.name + "' must be revolute or prismatic");
            continue;
        }
        const int count = device::coordinateCount(joint.kind);
        if (count == 0)
            continue;
        if (static_cast<int>(joint.coordinateNames.size()) != count || static_cast<int>(joint.lower.size()) != count ||
            static_cast<int>(joint.upper.size()) != count)
            throw ConfigurationError("joint '" + joint.name + "' needs " + std::to_string(count) +
                                     " coordinate names and bounds");
        joint.firstCoordinate = static_cast<int>(coordinateNames.size());
        for (int k = 0; k < count; ++k)
        {
            if (!(joint.lower[k] <= joint.upper[k]))
                throw ConfigurationError("joint '" + joint.name + "' coordinate '" + joint.coordinateNames[k] +
                                         "' has lower bound above upper bound");
            coordinateNames.push_back(joint.coordinateNames[k]);
            lowerBounds.push_back(joint.lower[k]);
            upperBounds.push_back(joint.upper[k]);
        }
    }
    for (std::size_t i = 0; i < coordinateNames.size(); ++i)
        for (std::size_t k = i + 1; k < coordinateNames.size(); ++k)
            if (coordinateNames[i] == coordinateNames[k])
                throw ConfigurationError("robot '" + name + "' has two coordinates named '" + coordinateNames[i] + "'");

    // Adjacent links may always touch.
    allowedCollisions.assign(components.size() * components.size(), false);
    for (std::size_t c = 0; c < components.size(); ++c)
        setCollisionAllowed(static_cast<int>(c), static_cast<int>(c), true);
    for (const Joint &joint : joints)
    {
        const int a = links[joint.parentLink].component, b = links[joint.childLink].component;
        if (a >= 0 && b >= 0)
            setCollisionAllowed(a, b, true);
    }

    kinematicJoints.clear();
    for (const Joint &joint : joints)
        kinematicJoints.push_back(device::KinematicJoint{
            joint.kind, joint.parentLink, joint.childLink, joint.firstCoordinate, joint.mimicOf, joint.mimicMultiplier,
            joint.mimicOffset, toDevicePose(joint.origin), toDevice(joint.axis)});
}

std::vector<double> RobotModel::neutralConfiguration() const
{
    std::vector<double> q(coordinateNames.size(), 0.0);
    for (const Joint &joint : joints)
    {
        if (joint.firstCoordinate < 0)
            continue;
        for (std::size_t k = 0; k < joint.lower.size(); ++k)
        {
            const double lo = joint.lower[k], hi = joint.upper[k];
            q[joint.firstCoordinate + k] = std::isfinite(lo) && std::isfinite(hi) ? 0.5 * (lo + hi) : 0.0;
        }
        if (joint.kind == JointKind::Floating)
        {
            q[joint.firstCoordinate + 3] = q[joint.firstCoordinate + 4] = q[joint.firstCoordinate + 5] = 0.0;
            q[joint.firstCoordinate + 6] = 1.0;
        }
    }
    return q;
}
}  // namespace rastercheck
