#include "TestSupport.h"

#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace rastercheck::test
{
std::string makeTempDir(const std::string &tag)
{
    std::string pattern = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/rastercheck-" + tag + "-XXXXXX";
    if (!mkdtemp(pattern.data()))
        throw std::runtime_error("cannot create a temporary directory " + pattern);
    return pattern;
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
