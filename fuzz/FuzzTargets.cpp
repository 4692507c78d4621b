#include "FuzzTargets.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <fstream>
#include <memory>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/geometry/Primitives.h"
#include "rastercheck/io/MeshLoader.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/OmplAppProblem.h"
#include "rastercheck/io/SrdfLoader.h"
#include "rastercheck/io/StatesCsv.h"
#include "rastercheck/io/UrdfLoader.h"

namespace rastercheck::fuzz
{
namespace
{
// Names the input in errors; an InputError naming anything else is a contract violation (a nested
// loader's error passed on without saying which input it came from).
const char *const kUrdfName = "fuzz.urdf";
const char *const kSrdfName = "fuzz.srdf";
const char *const kSceneName = "fuzz-scene.yaml";
const char *const kRequestName = "fuzz-request.yaml";
const char *const kCfgName = "fuzz.cfg";
const char *const kCsvName = "fuzz.csv";
const char *const kMeshName = "fuzz-mesh";

// The scratch meshes are written as ASCII STL: assimp's OBJ reader sets up a 16 MB line buffer per
// file, which made loading them the larger part of every URDF and .cfg execution.
std::string asciiStl(const std::vector<std::pair<std::string, Mesh>> &solids)
{
    std::ostringstream out;
    for (const auto &[name, mesh] : solids)
    {
        out << "solid " << name << "\n";
        for (const Mesh::Triangle &t : mesh.triangles)
        {
            out << "facet normal 0 0 0\nouter loop\n";
            for (std::uint32_t i : t)
                out << "vertex " << mesh.vertices[i].x() << " " << mesh.vertices[i].y() << " " << mesh.vertices[i].z()
                    << "\n";
            out << "endloop\nendfacet\n";
        }
        out << "endsolid " << name << "\n";
    }
    return out.str();
}

Mesh boxAt(const Eigen::Vector3d &min, const Eigen::Vector3d &max)
{
    Mesh box = makeBox(max - min);
    box.transform(Eigen::Isometry3d(Eigen::Translation3d((min + max) / 2)));
    return box;
}

// Tetrahedron with corners (5,5,5) + {0, e_x, e_y, e_z}, as in tests/test_omplapp.cpp.
Mesh tetrahedron()
{
    Mesh mesh;
    mesh.vertices = {{5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {5, 5, 6}};
    mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return mesh;
}

// The robot the SRDF harness applies its input to: Panda link names, one link without geometry.
const char *const kSrdfRobot = R"(<robot name="panda">
  <link name="panda_link0"><collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="panda_link1"><collision><geometry><cylinder radius="0.05" length="0.3"/></geometry></collision></link>
  <link name="panda_link2"><collision><geometry><sphere radius="0.06"/></geometry></collision></link>
  <link name="panda_link3"/>
  <link name="panda_hand"><collision><geometry><box size="0.05 0.2 0.05"/></geometry></collision></link>
  <joint name="panda_joint1" type="revolute"><parent link="panda_link0"/><child link="panda_link1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9" effort="1" velocity="1"/></joint>
  <joint name="panda_joint2" type="revolute"><parent link="panda_link1"/><child link="panda_link2"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-1.7" upper="1.7" effort="1" velocity="1"/></joint>
  <joint name="panda_joint3" type="fixed"><parent link="panda_link2"/><child link="panda_link3"/></joint>
  <joint name="panda_joint4" type="prismatic"><parent link="panda_link3"/><child link="panda_hand"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>
</robot>
)";

std::string text(const std::uint8_t *data, std::size_t size)
{
    return std::string(reinterpret_cast<const char *>(data), size);
}

// The folder with the mesh files the URDF and .cfg inputs may name. Its name follows from the user
// and the files' contents, and it is never removed: a per-process folder removed at exit was left
// behind by every process that ended without running destructors (a crash, a fuzzer's child), by
// the hundred. Files are written under a temporary name and renamed, so processes that start
// together see whole files.
const std::string &scratchFolder()
{
    static const std::string folder = []
    {
        const std::pair<const char *, std::string> files[] = {
            {"mesh.stl", asciiStl({{"box", boxAt({0, 0, 0}, {1, 1, 1})}})},
            {"robot.stl", asciiStl({{"tetrahedron", tetrahedron()}})},
            {"world.stl",
             asciiStl({{"wallA", boxAt({0, 0, 0}, {1, 1, 1})}, {"wallB", boxAt({10, 0, 0}, {11, 1, 2})}})}};
        std::string all;
        for (const auto &[name, contents] : files)
            all += std::string(name) + '\0' + contents + '\0';
        std::ostringstream path;
        const char *tmp = std::getenv("TMPDIR");
        path << (tmp && *tmp ? tmp : "/tmp") << "/rastercheck-fuzz-" << getuid() << "-" << std::hex
             << std::hash<std::string>{}(all);
        const std::string folder = path.str();
        struct stat info;
        if (mkdir(folder.c_str(), 0700) != 0 &&
            (lstat(folder.c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != getuid()))
            throw std::runtime_error("cannot use " + folder + " as the fuzz harnesses' scratch folder");
        for (const auto &[name, contents] : files)
        {
            const std::string file = folder + "/" + name, part = file + "." + std::to_string(getpid());
            std::ofstream(part, std::ios::binary) << contents;
            if (std::rename(part.c_str(), file.c_str()) != 0)
                throw std::runtime_error("cannot write " + file);
        }
        return folder;
    }();
    return folder;
}

void violated(const std::string &source, const std::string &what)
{
    throw ContractViolation(source + ": " + what);
}

void checkMesh(const Mesh &mesh, const std::string &source, const std::string &where)
{
    for (const Eigen::Vector3d &v : mesh.vertices)
        if (!v.allFinite())
            violated(source, where + ": vertex is not finite");
    for (const Mesh::Triangle &t : mesh.triangles)
        for (std::uint32_t i : t)
            if (i >= mesh.vertices.size())
                violated(source, where + ": triangle index " + std::to_string(i) + " past " +
                                     std::to_string(mesh.vertices.size()) + " vertices");
}

void checkModel(const RobotModel &model, const std::string &source)
{
    if (model.links.empty())
        violated(source, "model has no links");
    if (model.lowerBounds.size() != model.numCoordinates() || model.upperBounds.size() != model.numCoordinates())
        violated(source, "bounds do not match the coordinates");
    for (std::size_t i = 0; i < model.numCoordinates(); ++i)
        if (!(model.lowerBounds[i] <= model.upperBounds[i]))
            violated(source, "coordinate '" + model.coordinateNames[i] + "' has lower bound above upper bound");
    if (model.allowedCollisions.size() != model.numComponents() * model.numComponents())
        violated(source, "allowed-collision matrix has the wrong size");
    for (const Component &component : model.components)
        checkMesh(component.mesh, source, "component");
}

void checkScene(const Scene &scene, const std::string &source)
{
    for (const SceneObject &object : scene.objects)
        checkMesh(object.mesh, source, "object '" + object.name + "'");
}

void checkFinite(const std::vector<double> &values, const std::string &source, const std::string &where)
{
    for (double v : values)
        if (!std::isfinite(v))
            violated(source, where + " is not finite");
}

// Runs one load: success and InputError naming the input are the documented outcomes.
template <class Load>
Outcome run(const char *source, Load load)
{
    Outcome outcome;
    try
    {
        load();
        outcome.accepted = true;
    }
    catch (const InputError &e)
    {
        if (e.file() != source)
            violated(source, "InputError names '" + e.file() + "' instead of the input: " + e.what());
        outcome.error = e.what();
    }
    return outcome;
}
}  // namespace

Outcome urdf(const std::uint8_t *data, std::size_t size)
{
    const std::string folder = scratchFolder();
    return run(kUrdfName,
               [&]
               {
                   UrdfOptions options;
                   options.visualWhenNoCollision = size % 2 == 1;  // both branches, chosen by the input
                   checkModel(*loadUrdfString(text(data, size), folder, options, kUrdfName), kUrdfName);
               });
}

Outcome srdf(const std::uint8_t *data, std::size_t size)
{
    static const RobotModelConstPtr robot = loadUrdfString(kSrdfRobot, scratchFolder(), {}, "srdf-fixture.urdf");
    return run(kSrdfName,
               [&]
               {
                   const Srdf parsed = loadSrdfString(text(data, size), kSrdfName);
                   RobotModel model = *robot;
                   applySrdf(model, parsed);
                   checkModel(model, kSrdfName);
               });
}

Outcome scene(const std::uint8_t *data, std::size_t size)
{
    return run(kSceneName, [&] { checkScene(*loadMoveItSceneString(text(data, size), kSceneName), kSceneName); });
}

Outcome request(const std::uint8_t *data, std::size_t size)
{
    return run(kRequestName,
               [&]
               {
                   const MotionPlanRequest parsed = loadMoveItRequestString(text(data, size), kRequestName);
                   for (const auto *joints : {&parsed.startJoints, &parsed.goalJoints, &parsed.goalToleranceAbove,
                                              &parsed.goalToleranceBelow})
                       for (const auto &[name, value] : *joints)
                           if (!std::isfinite(value))
                               violated(kRequestName, "joint '" + name + "' value is not finite");
               });
}

Outcome cfg(const std::uint8_t *data, std::size_t size)
{
    const std::string folder = scratchFolder();
    return run(kCfgName,
               [&]
               {
                   const OmplAppProblem problem = loadOmplAppProblemString(text(data, size), folder, kCfgName);
                   const std::size_t width = problem.planar ? 3 : 7;
                   if (problem.start.size() != width || problem.goal.size() != width)
                       violated(kCfgName, "start or goal has the wrong number of coordinates");
                   checkFinite(problem.start, kCfgName, "start");
                   checkFinite(problem.goal, kCfgName, "goal");
                   if (!problem.robot || !problem.scene)
                       violated(kCfgName, "no robot or scene");
                   checkModel(*problem.robot, kCfgName);
                   checkScene(*problem.scene, kCfgName);
               });
}

Outcome csv(const std::uint8_t *data, std::size_t size)
{
    static const std::vector<std::string> names{"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                                "panda_joint5", "panda_joint6", "panda_joint7"};
    return run(kCsvName,
               [&]
               {
                   const StatesTable table = parseStatesCsv(text(data, size), names, kCsvName);
                   if (table.dof != names.size() || table.values.size() != table.rows * table.dof)
                       violated(kCsvName, "table size does not match rows x dof");
               });
}

Outcome mesh(const std::uint8_t *data, std::size_t size)
{
    static const char *const hints[] = {"obj", "stl", "dae", "ply"};
    const std::uint8_t selector = size > 0 ? data[0] : 0;
    const ColladaUpAxis upAxis = selector & 4 ? ColladaUpAxis::ConvertToYUp : ColladaUpAxis::Keep;
    return run(kMeshName,
               [&]
               {
                   // loadMeshNodesFromMemory rejects empty data itself; pass a null pointer then.
                   const std::uint8_t *bytes = size > 1 ? data + 1 : nullptr;
                   for (const MeshNode &node :
                        loadMeshNodesFromMemory(bytes, size > 1 ? size - 1 : 0, hints[selector & 3], kMeshName, upAxis))
                       checkMesh(node.mesh, kMeshName, "node '" + node.name + "'");
               });
}

const std::vector<std::string> &targetNames()
{
    static const std::vector<std::string> names{"urdf", "srdf", "scene", "request", "cfg", "csv", "mesh"};
    return names;
}

Target findTarget(const std::string &name)
{
    static const Target targets[] = {urdf, srdf, scene, request, cfg, csv, mesh};
    for (std::size_t i = 0; i < targetNames().size(); ++i)
        if (targetNames()[i] == name)
            return targets[i];
    throw std::invalid_argument("unknown fuzz target '" + name + "'");
}

void silenceLog()
{
    setLogHandler([](LogLevel, const std::string &) {});
}
}  // namespace rastercheck::fuzz

// LeakSanitizer suppression, compiled into the fuzzers and the regression test (LSan reads it at
// start-up): assimp 5.2.5 leaks the aiMesh and aiNode objects an importer had built when it throws
// on malformed input (seen with a truncated ASCII STL, tests/data/fuzz-regressions/mesh/); the
// Importer that owns our import is freed correctly and assimp exports no symbols to name the
// importer by, so the suppression names the library. Our own allocations never pass through it.
extern "C" const char *__lsan_default_suppressions()
{
    return "leak:libassimp.so\n";
}
