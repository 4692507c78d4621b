// `rastercheck info`: prints what the loaders make of a robot, a problem or a scene, so a user can
// see the coordinate layout, the collision components and their topology before planning.
#include <fstream>
#include <iostream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "Commands.h"
#include "rastercheck/collision/CollisionModel.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Paths.h"
#include "rastercheck/core/Text.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rastercheck::cli
{
namespace
{
struct InfoOptions
{
    std::string path;
    std::string srdf;
    std::vector<std::string> packagePaths;
    bool visualFallback = false;
};

std::string formatVector(const Eigen::Vector3d &v)
{
    std::ostringstream out;
    out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return out.str();
}

std::string formatBounds(const Aabb &box)
{
    if (box.empty())
        return "empty";
    return formatVector(box.min) + " .. " + formatVector(box.max);
}

const char *kindName(const Joint &joint)
{
    switch (joint.kind)
    {
        case JointKind::Revolute:
            return joint.continuous ? "continuous" : "revolute";
        case JointKind::Prismatic:
            return "prismatic";
        case JointKind::Floating:
            return "floating";
        case JointKind::Planar:
            return "planar";
        default:
            return "fixed";
    }
}

void printRobot(const RobotModel &model, std::ostream &out)
{
    out << "robot '" << model.name << "': " << model.links.size() << " links, " << model.joints.size()
        << " joints, dof " << model.numCoordinates() << ", " << model.numComponents() << " components ("
        << model.numTriangles() << " triangles)\n";
    out << "links:\n";
    for (const Link &link : model.links)
    {
        out << "  " << link.name;
        if (link.component >= 0)
            out << "  [component " << link.component << "]";
        out << '\n';
    }
    out << "joints:\n";
    for (const Joint &joint : model.joints)
    {
        out << "  " << joint.name << "  " << kindName(joint) << "  " << model.links[joint.parentLink].name << " -> "
            << model.links[joint.childLink].name;
        if (joint.mimicOf >= 0)
            out << "  mimic " << model.joints[joint.mimicOf].name << " * " << joint.mimicMultiplier << " + "
                << joint.mimicOffset;
        else
            for (std::size_t k = 0; k < joint.coordinateNames.size(); ++k)
                out << (k == 0 ? "  " : ", ") << joint.coordinateNames[k] << " [" << joint.lower[k] << ", "
                    << joint.upper[k] << "]";
        out << '\n';
    }
    out << "dof: " << model.numCoordinates() << '\n';
    out << "coordinates:";
    for (const std::string &name : model.coordinateNames)
        out << ' ' << name;
    out << '\n';
    out << "components:\n";
    std::size_t closed = 0;
    for (const Component &component : model.components)
    {
        closed += component.topology.closed ? 1 : 0;
        out << "  " << component.name << ": " << component.mesh.numTriangles() << " triangles, "
            << component.topology.summary() << '\n';
    }
    out << "closed components: " << closed << " of " << model.numComponents() << '\n';
    std::size_t allowed = 0;
    const std::size_t n = model.numComponents();
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = a + 1; b < n; ++b)
            allowed += model.isCollisionAllowed(static_cast<int>(a), static_cast<int>(b)) ? 1 : 0;
    out << "allowed collision pairs: " << allowed << " of " << n * (n - (n > 0 ? 1 : 0)) / 2 << '\n';
}

void printScene(const Scene &scene, std::ostream &out)
{
    std::size_t closed = 0;
    out << "scene: " << scene.numObjects() << " objects, " << scene.numTriangles() << " triangles\n";
    for (const SceneObject &object : scene.objects)
    {
        closed += object.topology.closed ? 1 : 0;
        out << "  " << object.name << ": " << object.mesh.numTriangles() << " triangles, " << object.topology.summary()
            << ", bounds " << formatBounds(object.bounds) << '\n';
    }
    out << "closed objects: " << closed << " of " << scene.numObjects() << '\n';
    out << "bounds: " << formatBounds(scene.bounds()) << '\n';
}

void printRequest(const MotionPlanRequest &request, std::ostream &out)
{
    out << "request: group '" << request.groupName << "'\n";
    out << "start:";
    for (const auto &[name, value] : request.startJoints)
        out << ' ' << name << '=' << value;
    out << "\ngoal:";
    for (const auto &[name, value] : request.goalJoints)
        out << ' ' << name << '=' << value;
    out << '\n';
}

void printValues(const char *label, const std::vector<double> &values, std::ostream &out)
{
    out << label << ':';
    for (double v : values)
        out << ' ' << v;
    out << '\n';
}

bool looksLikeRequest(const std::string &path)
{
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    static const std::regex requestKey("(^|\n)(goal_constraints|start_state)[ \t]*:");
    return std::regex_search(text.str(), requestKey);
}

/** \brief What the proofs and the exact phase keep beside the meshes: the patch trees of the
    non-convex solids, the bytes of every proof array and of the exact phase's trees, per triangle. */
void printProofArrays(const CollisionModel &model, std::ostream &out)
{
    const std::size_t triangles = (model.componentTriangles.size() + model.objectTriangles.size()) / 3;
    std::size_t patched = 0;
    for (std::size_t s = 0; s < model.convex.numSolids(); ++s)
        patched += model.convex.numPatchesOf(s) > 0 ? 1 : 0;
    out << "proofs: " << model.convex.numPatches() << " patches in " << patched << " non-convex solids of "
        << model.convex.numSolids() << ", " << model.convex.bytes() << " bytes ("
        << (triangles > 0 ? model.convex.bytes() / triangles : 0) << " per triangle)\n";
    std::size_t treeBytes = 0;
    for (const auto *trees : {&model.componentBvhs, &model.objectBvhs})
        for (const std::shared_ptr<const MeshBvh> &bvh : *trees)
            treeBytes += bvh->bytes();
    out << "triangle trees (exact phase and raster stages): " << treeBytes << " bytes ("
        << (triangles > 0 ? treeBytes / triangles : 0) << " per triangle)\n";
}

void runInfo(const InfoOptions &options)
{
    const std::string extension = lowerCase(extensionOf(options.path));
    std::ostream &out = std::cout;
    if (extension == "urdf" || extension == "xml")
    {
        UrdfOptions urdfOptions;
        urdfOptions.packagePaths = options.packagePaths;
        urdfOptions.visualWhenNoCollision = options.visualFallback;
        RobotModelPtr model = loadUrdf(options.path, urdfOptions);
        if (!options.srdf.empty())
            applySrdf(*model, loadSrdf(options.srdf));
        printRobot(*model, out);
        return;
    }
    if (!options.srdf.empty() || !options.packagePaths.empty() || options.visualFallback)
        throw ConfigurationError("--srdf, --package-path and --visual-fallback apply to URDF files only");
    if (extension == "cfg")
    {
        const OmplAppProblem problem = loadOmplAppProblem(options.path);
        out << "problem '" << problem.name << "': " << (problem.planar ? "SE(2)" : "SE(3)") << '\n';
        out << "robot mesh: " << problem.robotMeshPath << '\n';
        out << "world mesh: " << (problem.worldMeshPath.empty() ? "(none)" : problem.worldMeshPath) << '\n';
        printValues("start", problem.start, out);
        printValues("goal", problem.goal, out);
        out << "planners:";
        for (const auto &planner : problem.planners)
            out << ' ' << planner.first;
        out << '\n';
        printRobot(*problem.robot, out);
        printScene(*problem.scene, out);
        printProofArrays(CollisionModel(problem.robot, problem.scene), out);
        return;
    }
    if (extension == "yaml" || extension == "yml")
    {
        if (looksLikeRequest(options.path))
            printRequest(loadMoveItRequest(options.path), out);
        else
            printScene(*loadMoveItScene(options.path), out);
        return;
    }
    throw ConfigurationError("cannot tell what '" + options.path +
                             "' is from its extension (expected .urdf, .xml, .cfg, .yaml or .yml)");
}
}  // namespace

void addInfoCommand(CLI::App &app)
{
    auto options = std::make_shared<InfoOptions>();
    CLI::App *info = app.add_subcommand(
        "info", "Describe a robot (URDF), an OMPL.app problem (.cfg) or a MoveIt scene/request (.yaml)");
    info->add_option("file", options->path, "URDF, OMPL.app .cfg, or MoveIt scene / request YAML")->required();
    info->add_option("--srdf", options->srdf, "SRDF whose disable_collisions pairs are applied (URDF only)");
    info->add_option("--package-path", options->packagePaths, "folder searched for package:// URIs (repeatable)")
        ->allow_extra_args(false);
    info->add_flag("--visual-fallback", options->visualFallback,
                   "use a link's visual geometry when it has no collision geometry");
    info->callback([options]() { runInfo(*options); });
}
}  // namespace rastercheck::cli
