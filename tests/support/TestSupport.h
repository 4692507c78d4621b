#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rastercheck/geometry/Mesh.h"
#include "rastercheck/io/DataPath.h"
#include "rastercheck/io/Problem.h"

namespace rastercheck::test
{
/** \brief The shared data root (RASTERCHECK_DATA, else ../shared/data beside the source tree), or ""
    when absent. */
inline std::string sharedData() { return dataRoot(RASTERCHECK_DEFAULT_DATA); }

/** \brief Path of a file inside the source tree: RASTERCHECK_SOURCE when set (a copy of the tree on
    another machine, such as the GPU machine), else the tree this build came from. */
inline std::string sourcePath(const std::string &relative)
{
    const char *moved = std::getenv("RASTERCHECK_SOURCE");
    return std::string(moved && *moved ? moved : RASTERCHECK_SOURCE_DIR) + "/" + relative;
}

/** \brief The crawler crane (robots/crane, URDF + SRDF) in the plant (robots/sites/plant.yaml),
    loaded once per test program. */
const Problem &plant();

/** \brief The MotionBenchMaker Panda (URDF + SRDF) in scene0001 of \a scenario ("bookshelf_small",
    "table_pick", ...) under the shared data root \a root. */
Problem pandaProblem(const std::string &root, const std::string &scenario);

/** \brief A fresh temporary directory for one test (removed at exit of the process is not
    guaranteed; it lives under the system temp folder). */
std::string makeTempDir(const std::string &tag);

/** \brief What a command printed (stdout and stderr) and its exit status (-1 when it did not exit). */
struct CommandRun
{
    int status = -1;
    std::string output;
};

/** \brief Runs a shell command and collects its output. */
CommandRun runCommand(const std::string &command);
/** \brief Runs the rastercheck command line with \a arguments. */
inline CommandRun runCli(const std::string &arguments) { return runCommand(std::string(RASTERCHECK_CLI) + " " + arguments); }

/** \brief Expects \a load to throw InputError naming \a file, an element containing \a element,
    and a message containing \a what. */
void expectInputError(const std::function<void()> &load, const std::string &file, const std::string &element,
                      const std::string &what);

/** \brief Seeds OMPL's random numbers, so samplers and planners made afterwards draw the same
    numbers on every run. OMPL's RNGs are seeded from one global generator when made: without this
    every test process draws differently (a test counting random edges' verdicts failed in CI that
    way). Silences OMPL's warning that RNGs already exist (other tests in the same program). */
void seedOmpl(std::uint_fast32_t value);

/** \brief $\a variable as a factor that shrinks a long test (scripts/sanitize.sh sets it: the
    sanitizers slow the checker 10 to 50 times), else 1. */
double scaleFromEnvironment(const char *variable);
/** \brief \a count times scaleFromEnvironment(\a variable), at least 1. */
int scaledCount(int count, const char *variable);

/** \brief What a long run could leak, as this process stands now: resident memory (bytes, from
    /proc/self/statm), threads (/proc/self/task) and open descriptors (/proc/self/fd). */
struct ProcessFootprint
{
    std::size_t residentBytes = 0;
    std::size_t threads = 0;
    std::size_t descriptors = 0;
    static ProcessFootprint now();
};

/** \brief Whether \a after keeps resident memory within 10 % of \a warm (skipped under
    AddressSanitizer and ThreadSanitizer, whose allocators keep freed memory by design) and as many
    threads and descriptors. */
::testing::AssertionResult footprintFlat(const ProcessFootprint &warm, const ProcessFootprint &after);

/** \brief Calls \a step \a count times (a long-running use: solves, checkers built and dropped),
    prints what it took, and returns footprintFlat between the end of a warm-up (a tenth of the
    calls, at least one) and the end. \a what names the calls in the printout ("solves"). */
::testing::AssertionResult footprintFlatOver(int count, const std::string &what, const std::function<void()> &step);

/** \brief Writes \a text to \a path (creating it) and returns the path. */
std::string writeFile(const std::string &path, const std::string &text);

/** \brief \a mesh as OBJ text, its coordinates at full precision. */
std::string objText(const Mesh &mesh);

/** \brief An axis-aligned box as OBJ text (object \a name), outward faces, vertex indices starting at
    \a base + 1 (the vertices written before it in the same file). */
std::string objBox(const std::string &name, double x0, double y0, double z0, double x1, double y1, double z1,
                   int base);

/** \brief Collects the library's warnings and notices while it lives (setLogHandler), then restores
    the default handler. */
struct LogCapture
{
    std::vector<std::string> warnings;
    std::vector<std::string> notices;  // LogLevel::Info
    LogCapture();
    ~LogCapture();
    LogCapture(const LogCapture &) = delete;
    LogCapture &operator=(const LogCapture &) = delete;
    /** \brief Whether some warning contains \a text. */
    bool warned(const std::string &text) const;
    /** \brief Whether some notice contains \a text. */
    bool noticed(const std::string &text) const;
};

/** \brief A closed, outward unit cube centred on the origin, as OBJ text. */
extern const char *const kCubeObj;

/** \brief Small URDF texts: a robot named "test" around \a body, a link with optional collision XML,
    a joint (\a extra: origin, axis, limit, mimic XML), a collision element with a mesh. */
std::string urdfRobot(const std::string &body);
std::string urdfLink(const std::string &name, const std::string &collision = "");
std::string urdfJoint(const std::string &name, const std::string &type, const std::string &parent,
                      const std::string &child, const std::string &extra = "");
std::string urdfCollisionMesh(const std::string &file, const std::string &extra = "");
}  // namespace rastercheck::test

/** \brief Skips the current test with a clear message when the shared data is absent. */
#define RASTERCHECK_REQUIRE_DATA(root)                                                                        \
    const std::string root = ::rastercheck::test::sharedData();                                               \
    if (root.empty())                                                                                         \
    GTEST_SKIP() << "shared data not found: set RASTERCHECK_DATA or place ../shared/data beside the checkout"
