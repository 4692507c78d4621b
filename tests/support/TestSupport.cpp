#include "TestSupport.h"

#include <cstdlib>
#include <fstream>
#include <cstdio>
#include <stdexcept>
#include <sys/wait.h>

#include "rastercheck/core/Error.h"

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

std::string writeFile(const std::string &path, const std::string &text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out)
        throw std::runtime_error("cannot write " + path);
    return path;
}
}  // namespace rastercheck::test
