#include "TestSupport.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"

namespace rastercheck::test
{
std::string makeTempDir(const std::string &tag)
{
    std::string pattern = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/rastercheck-" + tag + "-XXXXXX";
    if (!mkdtemp(pattern.data()))
        throw std::runtime_error("cannot create a temporary directory " + pattern);
    return pattern;
}

const Problem &plant()
{
    static const Problem problem = [] {
        ProblemSource source;
        source.urdfPath = sourcePath("robots/crane/crane.urdf");
        source.srdfPath = sourcePath("robots/crane/crane.srdf");
        source.scenePath = sourcePath("robots/sites/plant.yaml");
        return loadProblem(source);
    }();
    return problem;
}

Problem pandaProblem(const std::string &root, const std::string &scenario)
{
    ProblemSource source;
    source.urdfPath = root + "/mbm/panda/panda.urdf";
    source.srdfPath = root + "/mbm/panda/panda.srdf";
    source.scenePath = root + "/mbm/panda/problems/" + scenario + "_panda/scene0001.yaml";
    return loadProblem(source);
}

CommandRun runCommand(const std::string &command)
{
    CommandRun run;
    FILE *pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe)
        return run;
    char buffer[4096];
    std::size_t read = 0;
    while ((read = fread(buffer, 1, sizeof buffer, pipe)) > 0)
        run.output.append(buffer, read);
    const int status = pclose(pipe);
    run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return run;
}

void expectInputError(const std::function<void()> &load, const std::string &file, const std::string &element,
                      const std::string &what)
{
    try
    {
        load();
        ADD_FAILURE() << "expected an InputError (" << element << ": " << what << ")";
    }
    catch (const InputError &e)
    {
        EXPECT_EQ(e.file(), file) << e.what();
        EXPECT_NE(e.element().find(element), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
}

void seedOmpl(std::uint_fast32_t value)
{
    const ::ompl::msg::LogLevel level = ::ompl::msg::getLogLevel();
    ::ompl::msg::setLogLevel(::ompl::msg::LOG_NONE);  // OMPL warns when the seed changes after RNGs exist
    ::ompl::RNG::setSeed(value);
    ::ompl::msg::setLogLevel(level);
}

std::string writeFile(const std::string &path, const std::string &text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out)
        throw std::runtime_error("cannot write " + path);
    return path;
}

std::string objText(const Mesh &mesh)
{
    std::ostringstream obj;
    obj << std::setprecision(17);
    for (const Eigen::Vector3d &v : mesh.vertices)
        obj << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    for (const Mesh::Triangle &t : mesh.triangles)
        obj << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    return obj.str();
}

std::string objBox(const std::string &name, double x0, double y0, double z0, double x1, double y1, double z1, int base)
{
    char text[1024];
    std::snprintf(text, sizeof text,
                  "o %s\nv %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g "
                  "%g\n",
                  name.c_str(), x0, y0, z0, x1, y0, z0, x1, y1, z0, x0, y1, z0, x0, y0, z1, x1, y0, z1, x1, y1, z1, x0,
                  y1, z1);
    std::string obj = text;
    const int faces[12][3] = {{1, 4, 3}, {1, 3, 2}, {5, 6, 7}, {5, 7, 8}, {1, 2, 6}, {1, 6, 5},
                              {4, 8, 7}, {4, 7, 3}, {1, 5, 8}, {1, 8, 4}, {2, 3, 7}, {2, 7, 6}};
    for (const auto &f : faces)
        obj += "f " + std::to_string(base + f[0]) + " " + std::to_string(base + f[1]) + " " +
               std::to_string(base + f[2]) + "\n";
    return obj;
}

LogCapture::LogCapture()
{
    setLogHandler(
        [this](LogLevel level, const std::string &message)
        { (level == LogLevel::Warning ? warnings : notices).push_back(message); });
}

LogCapture::~LogCapture() { setLogHandler(nullptr); }

namespace
{
bool anyContains(const std::vector<std::string> &messages, const std::string &text)
{
    for (const std::string &message : messages)
        if (message.find(text) != std::string::npos)
            return true;
    return false;
}
}  // namespace

bool LogCapture::warned(const std::string &text) const { return anyContains(warnings, text); }
bool LogCapture::noticed(const std::string &text) const { return anyContains(notices, text); }

const char *const kCubeObj =
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";

std::string urdfRobot(const std::string &body)
{
    return "<?xml version=\"1.0\"?>\n<robot name=\"test\">\n" + body + "</robot>\n";
}

std::string urdfLink(const std::string &name, const std::string &collision)
{
    return "<link name=\"" + name + "\">" + collision + "</link>\n";
}

std::string urdfJoint(const std::string &name, const std::string &type, const std::string &parent,
                      const std::string &child, const std::string &extra)
{
    return "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent + "\"/><child link=\"" +
           child + "\"/>" + extra + "</joint>\n";
}

std::string urdfCollisionMesh(const std::string &file, const std::string &extra)
{
    return "<collision><geometry><mesh filename=\"" + file + "\"" + extra + "/></geometry></collision>";
}
double scaleFromEnvironment(const char *variable)
{
    const char *text = std::getenv(variable);
    const double scale = text && *text ? std::atof(text) : 1.0;
    return scale > 0 && std::isfinite(scale) ? scale : 1.0;
}

int scaledCount(int count, const char *variable)
{
    return std::max(1, static_cast<int>(count * scaleFromEnvironment(variable) + 0.5));
}

// AddressSanitizer (GCC defines the first macro, clang answers __has_feature) keeps freed memory
// in quarantine, ThreadSanitizer in its own allocator: resident memory grows there by design.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define RASTERCHECK_SANITIZED_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define RASTERCHECK_SANITIZED_ALLOCATOR 1
#endif
#endif

namespace
{
std::size_t entriesIn(const char *folder)
{
    std::size_t count = 0;
    for ([[maybe_unused]] const auto &entry : std::filesystem::directory_iterator(folder))
        ++count;
    return count;
}
}  // namespace

ProcessFootprint ProcessFootprint::now()
{
    ProcessFootprint footprint;
    std::ifstream statm("/proc/self/statm");
    std::size_t pages = 0, resident = 0;
    statm >> pages >> resident;
    footprint.residentBytes = resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
    footprint.threads = entriesIn("/proc/self/task");
    footprint.descriptors = entriesIn("/proc/self/fd");
    return footprint;
}

::testing::AssertionResult footprintFlat(const ProcessFootprint &warm, const ProcessFootprint &after)
{
    std::ostringstream why;
    if (after.threads != warm.threads)
        why << "threads " << warm.threads << " -> " << after.threads << "; ";
    if (after.descriptors != warm.descriptors)
        why << "descriptors " << warm.descriptors << " -> " << after.descriptors << "; ";
#ifndef RASTERCHECK_SANITIZED_ALLOCATOR
    if (static_cast<double>(after.residentBytes) > 1.1 * static_cast<double>(warm.residentBytes))
        why << "resident memory " << warm.residentBytes / 1048576.0 << " -> " << after.residentBytes / 1048576.0
            << " MiB (more than 10 % above)";
#endif
    if (why.str().empty())
        return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << why.str();
}
::testing::AssertionResult footprintFlatOver(int count, const std::string &what, const std::function<void()> &step)
{
    const int warmUp = std::max(1, count / 10);
    const auto begin = std::chrono::steady_clock::now();
    for (int i = 0; i < std::min(warmUp, count); ++i)
        step();
    const ProcessFootprint warm = ProcessFootprint::now();
    for (int i = warmUp; i < count; ++i)
        step();
    const ProcessFootprint after = ProcessFootprint::now();
    std::cout << count << " " << what << " in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count() << " s; resident "
              << warm.residentBytes / 1048576.0 << " MiB after " << warmUp << ", " << after.residentBytes / 1048576.0
              << " MiB after all" << std::endl;
    return footprintFlat(warm, after);
}
}  // namespace rastercheck::test
