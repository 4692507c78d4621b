#include "rastercheck/io/UrdfLoader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <sys/stat.h>

#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/io/MeshLoader.h"

namespace rastercheck
{
namespace
{
constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string joinPath(const std::string &folder, const std::string &rest)
{
    if (folder.empty() || (!rest.empty() && rest[0] == '/'))
        return rest;
    return folder.back() == '/' ? folder + rest : folder + "/" + rest;
}

// ---- pre-scan: urdfdom reports malformed input only on its console, so the checks that must name
// the element (XML syntax, joint types, numbers, link references) run on the XML first. ----------

struct XmlScan
{
    std::vector<std::string> linkNames;   // document order
    std::vector<std::string> jointNames;  // document order
};

// Checks that attribute `attribute` of `element` (when present) holds `count` finite numbers.
void checkNumbers(const tinyxml2::XMLElement *element, const char *attribute, int count, const std::string &file,
                  const std::string &where)
{
    if (!element)
        return;
    const char *text = element->Attribute(attribute);
    if (!text)
        return;
    std::istringstream tokens(text);
    std::string token;
    int found = 0;
    while (tokens >> token)
    {
        char *end = nullptr;
        errno = 0;
        const double value = std::strtod(token.c_str(), &end);
        if (end == token.c_str() || *end != '\0' || !std::isfinite(value) || errno == ERANGE)
            throw InputError(file, where + " '" + attribute + "'", "'" + token + "' is not a finite number");
        ++found;
    }
    if (found != count)
        throw InputError(file, where + " '" + attribute + "'",
                         "expected " + std::to_string(count) + " numbers, got '" + std::string(text) + "'");
}

void checkOrigin(const tinyxml2::XMLElement *parent, const std::string &file, const std::string &where)
{
    const tinyxml2::XMLElement *origin = parent->FirstChildElement("origin");
    checkNumbers(origin, "xyz", 3, file, where + " origin");
    checkNumbers(origin, "rpy", 3, file, where + " origin");
}

void checkGeometryElements(const tinyxml2::XMLElement *link, const char *tag, const std::string &file,
                           const std::string &linkWhere)
{
    int k = 0;
    for (const tinyxml2::XMLElement *e = link->FirstChildElement(tag); e; e = e->NextSiblingElement(tag), ++k)
    {
        const std::string where = linkWhere + " " + tag + " " + std::to_string(k);
        checkOrigin(e, file, where);
        const tinyxml2::XMLElement *geometry = e->FirstChildElement("geometry");
        if (!geometry)
            throw InputError(file, where, "has no <geometry>");
        const tinyxml2::XMLElement *shape = geometry->FirstChildElement();
        if (!shape)
            throw InputError(file, where, "<geometry> is empty");
        checkNumbers(geometry->FirstChildElement("box"), "size", 3, file, where + " box");
        checkNumbers(geometry->FirstChildElement("cylinder"), "radius", 1, file, where + " cylinder");
        checkNumbers(geometry->FirstChildElement("cylinder"), "length", 1, file, where + " cylinder");
        checkNumbers(geometry->FirstChildElement("sphere"), "radius", 1, file, where + " sphere");
        checkNumbers(geometry->FirstChildElement("mesh"), "scale", 3, file, where + " mesh");
    }
}

XmlScan prescan(const std::string &xml, const std::string &file)
{
    tinyxml2::XMLDocument document;
    if (document.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS)
        throw InputError(file, "line " + std::to_string(document.ErrorLineNum()),
                         std::string("malformed XML: ") + document.ErrorStr());
    const tinyxml2::XMLElement *robot = document.FirstChildElement("robot");
    if (!robot)
        throw InputError(file, "", "no <robot> root element");
    if (!robot->Attribute("name"))
        throw InputError(file, "robot", "missing attribute 'name'");

    XmlScan scan;
    std::set<std::string> links;
    int k = 0;
    for (const tinyxml2::XMLElement *link = robot->FirstChildElement("link"); link;
         link = link->NextSiblingElement("link"), ++k)
    {
        const char *name = link->Attribute("name");
        if (!name)
            throw InputError(file, "link #" + std::to_string(k), "missing attribute 'name'");
        if (!links.insert(name).second)
            throw InputError(file, "link '" + std::string(name) + "'", "defined twice");
        scan.linkNames.push_back(name);
        checkGeometryElements(link, "collision", file, "link '" + std::string(name) + "'");
        checkGeometryElements(link, "visual", file, "link '" + std::string(name) + "'");
    }
    if (scan.linkNames.empty())
        throw InputError(file, "robot", "has no links");

    static const std::set<std::string> knownTypes{"revolute", "continuous", "prismatic", "fixed", "floating", "planar"};
    std::set<std::string> joints;
    std::map<std::string, std::string> parentLink, parentJoint;  // child link -> its parent link, joint
    k = 0;
    for (const tinyxml2::XMLElement *joint = robot->FirstChildElement("joint"); joint;
         joint = joint->NextSiblingElement("joint"), ++k)
    {
        const char *name = joint->Attribute("name");
        if (!name)
            throw InputError(file, "joint #" + std::to_string(k), "missing attribute 'name'");
        const std::string where = "joint '" + std::string(name) + "'";
        if (!joints.insert(name).second)
            throw InputError(file, where, "defined twice");
        const char *type = joint->Attribute("type");
        if (!type)
            throw InputError(file, where, "missing attribute 'type'");
        if (!knownTypes.count(type))
            throw InputError(file, where,
                             "unknown joint type '" + std::string(type) +
                                 "' (expected revolute, continuous, prismatic, fixed, floating or planar)");
        for (const char *end : {"parent", "child"})
        {
            const tinyxml2::XMLElement *e = joint->FirstChildElement(end);
            const char *link = e ? e->Attribute("link") : nullptr;
            if (!link)
                throw InputError(file, where + " " + end, "missing <" + std::string(end) + " link=\"...\"/>");
            if (!links.count(link))
                throw InputError(file, where + " " + end, "link '" + std::string(link) + "' does not exist");
        }
        const std::string parent = joint->FirstChildElement("parent")->Attribute("link");
        const std::string child = joint->FirstChildElement("child")->Attribute("link");
        if (parentJoint.count(child))
            throw InputError(file, where + " child",
                             "link '" + child + "' is already the child of joint '" + parentJoint[child] + "'");
        parentLink[child] = parent;
        parentJoint[child] = name;
        if ((std::string(type) == "revolute" || std::string(type) == "prismatic") && !joint->FirstChildElement("limit"))
            throw InputError(file, where, "a " + std::string(type) + " joint needs <limit lower=... upper=...>");
        checkOrigin(joint, file, where);
        checkNumbers(joint->FirstChildElement("axis"), "xyz", 3, file, where + " axis");
        for (const char *attribute : {"lower", "upper", "effort", "velocity"})
            checkNumbers(joint->FirstChildElement("limit"), attribute, 1, file, where + " limit");
        for (const char *attribute : {"multiplier", "offset"})
            checkNumbers(joint->FirstChildElement("mimic"), attribute, 1, file, where + " mimic");
        scan.jointNames.push_back(name);
    }
    // The links must form a tree before urdfdom sees them: it links a cycle into shared_ptr loops
    // that are never freed (found by fuzz_urdf), and a cycle has no root to hang a model from.
    std::set<std::string> rooted;  // links whose chain of parents ends at a root
    for (const std::string &start : scan.linkNames)
    {
        std::vector<std::string> chain;
        std::string link = start;
        while (!rooted.count(link) && parentLink.count(link))
        {
            chain.push_back(link);
            if (chain.size() > scan.linkNames.size())  // longer than any path to a root: `link` is on a cycle
                throw InputError(file, "joint '" + parentJoint[link] + "'",
                                 "the joints form a cycle through link '" + link + "'");
            link = parentLink[link];
        }
        rooted.insert(chain.begin(), chain.end());
        rooted.insert(link);
    }
    return scan;
}

// urdfdom writes its errors to console_bridge; they are captured so the exception can carry them.
class CapturingHandler : public console_bridge::OutputHandler
{
public:
    explicit CapturingHandler(std::string file) : file_(std::move(file)) {}

    void log(const std::string &text, console_bridge::LogLevel level, const char *, int) override
    {
        if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR)
            errors_ += (errors_.empty() ? "" : "; ") + text;
        else if (level == console_bridge::CONSOLE_BRIDGE_LOG_WARN)
            logOnce(LogLevel::Warning, file_ + ": " + text);
    }

    const std::string &errors() const { return errors_; }

private:
    std::string file_;
    std::string errors_;
};

urdf::ModelInterfaceSharedPtr parseWithUrdfdom(const std::string &xml, const std::string &file)
{
    static std::mutex consoleMutex;  // console_bridge's handler is process-global
    std::lock_guard<std::mutex> lock(consoleMutex);
    CapturingHandler handler(file);
    console_bridge::useOutputHandler(&handler);
    urdf::ModelInterfaceSharedPtr model;
    try
    {
        model = urdf::parseURDF(xml);
    }
    catch (const std::exception &e)
    {
        console_bridge::restorePreviousOutputHandler();
        throw InputError(file, "robot", std::string("urdfdom: ") + e.what());
    }
    console_bridge::restorePreviousOutputHandler();
    if (!model)
        throw InputError(
            file, "robot",
            "urdfdom rejected the robot: " + (handler.errors().empty() ? "no reason given" : handler.errors()));
    return model;
}

// ---- building the model ----------------------------------------------------------------------

Eigen::Isometry3d toIsometry(const urdf::Pose &pose)
{
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
    out.linear() = q.normalized().toRotationMatrix();
    out.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
    return out;
}

class Builder
{
public:
    Builder(std::string file, std::string baseDirectory, const UrdfOptions &options)
        : file_(std::move(file)), baseDirectory_(std::move(baseDirectory)), options_(options)
    {
    }

    RobotModelPtr build(const std::string &xml)
    {
        const XmlScan scan = prescan(xml, file_);
        urdf_ = parseWithUrdfdom(xml, file_);
        // urdfdom (TinyXML 1) and the pre-scan (TinyXML 2) can read a name differently: a bare '&'
        // is "&" to one and "" to the other (found by fuzz_urdf). The model is built from both, so
        // their names must agree.
        const char *differently = "urdfdom reads this name differently (an '&' that starts no XML entity?)";
        const std::set<std::string> scannedLinks(scan.linkNames.begin(), scan.linkNames.end());
        for (const std::string &name : scan.linkNames)
            if (!urdf_->getLink(name))
                throw InputError(file_, "link '" + name + "'", differently);
        for (const std::string &name : scan.jointNames)
        {
            const urdf::JointConstSharedPtr joint = urdf_->getJoint(name);
            if (!joint)
                throw InputError(file_, "joint '" + name + "'", differently);
            for (const std::string &link : {joint->parent_link_name, joint->child_link_name})
                if (!scannedLinks.count(link))
                    throw InputError(file_, "joint '" + name + "' link '" + link + "'", differently);
        }
        auto model = std::make_shared<RobotModel>();
        model->name = urdf_->getName();
        for (std::size_t i = 0; i < scan.linkNames.size(); ++i)
        {
            linkIndex_[scan.linkNames[i]] = static_cast<int>(i);
            model->links.push_back(Link{scan.linkNames[i], -1, -1});
        }
        for (const std::string &name : scan.jointNames)
        {
            jointIndex_[name] = static_cast<int>(model->joints.size());
            model->joints.push_back(makeJoint(name));
        }
        resolveMimics(*model);
        for (Link &link : model->links)
            addComponent(*model, link);
        try
        {
            model->finalize();
        }
        catch (const ConfigurationError &e)
        {
            throw InputError(file_, "robot '" + model->name + "'", e.what());
        }
        return model;
    }

private:
    Joint makeJoint(const std::string &name)
    {
        const urdf::JointConstSharedPtr source = urdf_->getJoint(name);
        const std::string where = "joint '" + name + "'";
        Joint joint;
        joint.name = name;
        joint.parentLink = linkIndex_.at(source->parent_link_name);
        joint.childLink = linkIndex_.at(source->child_link_name);
        joint.origin = toIsometry(source->parent_to_joint_origin_transform);
        const Eigen::Vector3d axis(source->axis.x, source->axis.y, source->axis.z);

        auto limits = [&](double &lower, double &upper)
        {
            if (!source->limits)
                throw InputError(file_, where, "missing <limit>");
            lower = source->limits->lower;
            upper = source->limits->upper;
            if (lower > upper)
            {
                logWarning(file_ + ": " + where + ": lower limit " + std::to_string(lower) + " is above upper limit " +
                           std::to_string(upper) + "; the limits are swapped");
                std::swap(lower, upper);
            }
        };
        auto unitAxis = [&]()
        {
            if (!(axis.norm() > 0.0))
                throw InputError(file_, where + " axis", "axis has zero length");
            return Eigen::Vector3d(axis.normalized());
        };

        switch (source->type)
        {
            case urdf::Joint::REVOLUTE:
            case urdf::Joint::PRISMATIC:
            {
                joint.kind = source->type == urdf::Joint::REVOLUTE ? JointKind::Revolute : JointKind::Prismatic;
                joint.axis = unitAxis();
                double lower = 0.0, upper = 0.0;
                limits(lower, upper);
                joint.coordinateNames = {name};
                joint.lower = {lower};
                joint.upper = {upper};
                break;
            }
            case urdf::Joint::CONTINUOUS:
                joint.kind = JointKind::Revolute;
                joint.continuous = true;
                joint.axis = unitAxis();
                joint.coordinateNames = {name};
                joint.lower = {-M_PI};
                joint.upper = {M_PI};
                break;
            case urdf::Joint::FLOATING:
                joint.kind = JointKind::Floating;
                for (const char *c : {"x", "y", "z", "qx", "qy", "qz", "qw"})
                    joint.coordinateNames.push_back(name + "/" + c);
                joint.lower = {-kInfinity, -kInfinity, -kInfinity, -1.0, -1.0, -1.0, -1.0};
                joint.upper = {kInfinity, kInfinity, kInfinity, 1.0, 1.0, 1.0, 1.0};
                break;
            case urdf::Joint::PLANAR:
                joint.kind = JointKind::Planar;
                if (!unitAxis().isApprox(Eigen::Vector3d::UnitZ(), 1e-9))
                    throw InputError(file_, where + " axis", "planar joints are supported only with axis 0 0 1");
                joint.coordinateNames = {name + "/x", name + "/y", name + "/theta"};
                joint.lower = {-kInfinity, -kInfinity, -M_PI};
                joint.upper = {kInfinity, kInfinity, M_PI};
                break;
            case urdf::Joint::FIXED:
                joint.kind = JointKind::Fixed;
                break;
            default:
                throw InputError(file_, where, "unknown joint type");
        }
        if (source->mimic && joint.kind != JointKind::Fixed)
        {
            mimicSource_[name] = Mimic{source->mimic->joint_name, source->mimic->multiplier, source->mimic->offset};
        }
        return joint;
    }

    // Points every mimic joint at the joint that moves on its own, composing the linear maps:
    // v = m1 (m2 v0 + o2) + o1 = (m1 m2) v0 + (m1 o2 + o1).
    void resolveMimics(RobotModel &model)
    {
        for (Joint &joint : model.joints)
        {
            if (!mimicSource_.count(joint.name))
                continue;
            const std::string where = "joint '" + joint.name + "' mimic";
            if (device::coordinateCount(joint.kind) != 1)
                throw InputError(file_, where, "only revolute, continuous and prismatic joints can mimic");
            const Mimic &first = mimicSource_.at(joint.name);
            double multiplier = first.multiplier, offset = first.offset;
            std::vector<std::string> chain{joint.name};
            std::string current = first.source;
            while (true)
            {
                if (!jointIndex_.count(current))
                    throw InputError(file_, where, "joint '" + current + "' does not exist");
                for (const std::string &seen : chain)
                    if (seen == current)
                    {
                        std::string cycle;
                        for (const std::string &c : chain)
                            cycle += c + " -> ";
                        throw InputError(file_, where, "mimic cycle: " + cycle + current);
                    }
                chain.push_back(current);
                auto next = mimicSource_.find(current);
                if (next == mimicSource_.end())
                    break;
                offset = multiplier * next->second.offset + offset;
                multiplier *= next->second.multiplier;
                current = next->second.source;
            }
            const Joint &root = model.joints[jointIndex_.at(current)];
            if (device::coordinateCount(root.kind) != 1)
                throw InputError(file_, where,
                                 "mimicked joint '" + current + "' is not revolute, continuous or prismatic");
            joint.mimicOf = jointIndex_.at(current);
            joint.mimicMultiplier = multiplier;
            joint.mimicOffset = offset;
            joint.coordinateNames.clear();
            joint.lower.clear();
            joint.upper.clear();
        }
    }

    template <class Element>
    void appendElements(const std::vector<std::shared_ptr<Element>> &elements, const std::string &linkName,
                        const char *kind, std::vector<Mesh> &parts, std::vector<PrimitiveShape> &shapes,
                        bool &onlyPrimitives)
    {
        for (std::size_t k = 0; k < elements.size(); ++k)
        {
            const Element &element = *elements[k];
            const std::string where = "link '" + linkName + "' " + kind + " " + std::to_string(k);
            if (!element.geometry)
                throw InputError(file_, where, "has no geometry");
            parts.push_back(geometryMesh(*element.geometry, linkName, kind, where));
            parts.back().transform(toIsometry(element.origin));
            PrimitiveShape shape;
            shape.pose = toIsometry(element.origin);
            switch (element.geometry->type)
            {
                case urdf::Geometry::BOX:
                {
                    const auto &box = static_cast<const urdf::Box &>(*element.geometry);
                    shape.size = Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z);
                    break;
                }
                case urdf::Geometry::CYLINDER:
                {
                    const auto &cylinder = static_cast<const urdf::Cylinder &>(*element.geometry);
                    shape.kind = PrimitiveShape::Kind::Cylinder;
                    shape.size = Eigen::Vector3d(cylinder.radius, cylinder.length, 0.0);
                    break;
                }
                case urdf::Geometry::SPHERE:
                    shape.kind = PrimitiveShape::Kind::Sphere;
                    shape.size.x() = static_cast<const urdf::Sphere &>(*element.geometry).radius;
                    break;
                default:
                    onlyPrimitives = false;
                    continue;
            }
            shapes.push_back(shape);
        }
    }

    void addComponent(RobotModel &model, Link &link)
    {
        const urdf::LinkConstSharedPtr source = urdf_->getLink(link.name);
        std::vector<Mesh> parts;
        std::vector<PrimitiveShape> shapes;
        bool onlyPrimitives = true;
        const char *kind = "collision";
        if (!source->collision_array.empty())
            appendElements(source->collision_array, link.name, kind, parts, shapes, onlyPrimitives);
        else if (options_.visualWhenNoCollision && !source->visual_array.empty())
        {
            kind = "visual";
            logOnce(LogLevel::Warning,
                    file_ + ": link '" + link.name + "' has no collision geometry; its visual geometry is used");
            appendElements(source->visual_array, link.name, kind, parts, shapes, onlyPrimitives);
        }
        else
            return;

        // Elements stay separate shells: two touching boxes of one link must not weld into a
        // non-manifold surface (see cleanAndMerge).
        Component component = makeComponent(link.name, std::move(parts));
        if (onlyPrimitives)
            component.shapes = std::move(shapes);
        if (component.mesh.empty())
            throw InputError(file_, "link '" + link.name + "' " + kind, "geometry has no triangles after cleaning");
        if (!component.topology.closed)
            logOnce(LogLevel::Info, file_ + ": link '" + link.name + "' " + kind + " geometry is " +
                                        component.topology.summary() + "; the exact narrow phase checks it");
        link.component = static_cast<int>(model.components.size());
        model.components.push_back(std::move(component));
    }

    Mesh geometryMesh(const urdf::Geometry &geometry, const std::string &linkName, const char *kind,
                      const std::string &where)
    {
        auto positive = [&](double value, const char *what)
        {
            if (!std::isfinite(value) || value <= 0.0)
                throw InputError(file_, where, std::string(what) + " must be positive, got " + std::to_string(value));
        };
        switch (geometry.type)
        {
            case urdf::Geometry::BOX:
            {
                const auto &box = static_cast<const urdf::Box &>(geometry);
                positive(box.dim.x, "box size x");
                positive(box.dim.y, "box size y");
                positive(box.dim.z, "box size z");
                return makeBox(Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z));
            }
            case urdf::Geometry::CYLINDER:
            {
                const auto &cylinder = static_cast<const urdf::Cylinder &>(geometry);
                positive(cylinder.radius, "cylinder radius");
                positive(cylinder.length, "cylinder length");
                return makeCylinder(cylinder.radius, cylinder.length, options_.primitiveError);
            }
            case urdf::Geometry::SPHERE:
            {
                const auto &sphere = static_cast<const urdf::Sphere &>(geometry);
                positive(sphere.radius, "sphere radius");
                return makeSphere(sphere.radius, options_.primitiveError);
            }
            case urdf::Geometry::MESH:
            {
                const auto &meshGeometry = static_cast<const urdf::Mesh &>(geometry);
                const std::string meshWhere =
                    "link '" + linkName + "' " + kind + " mesh '" + meshGeometry.filename + "'";
                Mesh mesh = loadCached(resolve(meshGeometry.filename, meshWhere), meshWhere);
                const Eigen::Vector3d scale(meshGeometry.scale.x, meshGeometry.scale.y, meshGeometry.scale.z);
                if (!scale.allFinite() || (scale.array() == 0.0).any())
                    throw InputError(file_, meshWhere, "scale must be finite and non-zero");
                mesh.scale(scale);
                return mesh;
            }
        }
        throw InputError(file_, where, "unknown geometry type");
    }

    Mesh loadCached(const std::string &path, const std::string &where)
    {
        auto cached = meshCache_.find(path);
        if (cached != meshCache_.end())
            return cached->second;
        try
        {
            return meshCache_[path] = loadMesh(path);
        }
        catch (const InputError &e)
        {
            throw InputError(file_, where, e.what());
        }
    }

    std::vector<std::string> packageFolders() const
    {
        std::vector<std::string> folders = options_.packagePaths;
        if (const char *environment = std::getenv("RASTERCHECK_PACKAGE_PATH"))
        {
            std::istringstream parts(environment);
            std::string part;
            while (std::getline(parts, part, ':'))
                if (!part.empty())
                    folders.push_back(part);
        }
        std::string folder = baseDirectory_.empty() ? "." : baseDirectory_;
        while (true)
        {
            folders.push_back(folder);
            const std::string parent = folderOf(folder);
            if (parent == folder || folder == "." || folder == "/")
                break;
            folder = parent;
        }
        return folders;
    }

    std::string resolve(const std::string &uri, const std::string &where) const
    {
        static const std::string packageScheme = "package://", fileScheme = "file://";
        if (uri.compare(0, packageScheme.size(), packageScheme) == 0)
        {
            const std::string rest = uri.substr(packageScheme.size());
            const std::size_t slash = rest.find('/');
            if (slash == std::string::npos || slash == 0)
                throw InputError(file_, where, "malformed package URI (expected package://NAME/path)");
            const std::string package = rest.substr(0, slash), inside = rest.substr(slash + 1);
            std::string tried;
            for (const std::string &folder : packageFolders())
                for (const std::string &candidate :
                     {joinPath(joinPath(folder, package), inside), joinPath(folder, inside)})
                {
                    if (isFile(candidate))
                        return candidate;
                    tried += (tried.empty() ? "" : ", ") + candidate;
                }
            throw InputError(file_, where, "file not found (tried " + tried + ")");
        }
        std::string path = uri;
        if (uri.compare(0, fileScheme.size(), fileScheme) == 0)
            path = uri.substr(fileScheme.size());
        else if (uri.find("://") != std::string::npos)
            throw InputError(file_, where, "unsupported URI scheme (expected package://, file:// or a path)");
        path = joinPath(baseDirectory_, path);
        if (!isFile(path))
            throw InputError(file_, where, "file not found (resolved to " + path + ")");
        return path;
    }

    std::string file_;
    std::string baseDirectory_;
    const UrdfOptions &options_;
    urdf::ModelInterfaceSharedPtr urdf_;
    std::map<std::string, int> linkIndex_;
    std::map<std::string, int> jointIndex_;
    struct Mimic
    {
        std::string source;
        double multiplier;
        double offset;
    };
    std::map<std::string, Mimic> mimicSource_;  // as written in the file, before chains are resolved
    std::map<std::string, Mesh> meshCache_;
};
}  // namespace

RobotModelPtr loadUrdf(const std::string &path, const UrdfOptions &options)
{
    std::ifstream in(path, std::ios::binary);
    if (!in || !isFile(path))
        throw InputError(path, "", "file not found");
    std::ostringstream text;
    text << in.rdbuf();
    return Builder(path, folderOf(path), options).build(text.str());
}

RobotModelPtr loadUrdfString(const std::string &xml, const std::string &baseDirectory, const UrdfOptions &options,
                             const std::string &sourceName)
{
    return Builder(sourceName, baseDirectory, options).build(xml);
}

RobotModelPtr RobotModel::fromUrdf(const std::string &path)
{
    return loadUrdf(path);
}

RobotModelPtr RobotModel::fromUrdf(const std::string &path, const UrdfOptions &options)
{
    return loadUrdf(path, options);
}
}  // namespace rastercheck
