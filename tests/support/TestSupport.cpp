#include "TestSupport.h"

#include <cstdlib>
#include <fstream>
#include <cstdio>
#include <stdexcept>
#include <sys/wait.h>

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
}  // namespace rastercheck::test
