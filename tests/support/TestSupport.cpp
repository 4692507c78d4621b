#include "TestSupport.h"

#include <cstdlib>
#include <fstream>
#include <stdexcept>

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
