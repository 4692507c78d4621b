// Every input that once made a fuzzer fail (bench/fuzz.sh), replayed through the same entry point
// (fuzz/FuzzTargets.h) in the regular build: each file in tests/data/fuzz-regressions/<harness>/
// must now give the outcome listed below — a clean InputError naming the input, or success — and
// never a crash, a sanitizer report (CI's sanitizer build runs this too) or another exception.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "FuzzTargets.h"
#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MeshLoader.h"

namespace fs = std::filesystem;
namespace fz = rastercheck::fuzz;

namespace
{
struct Expected
{
    bool accepted;        ///< the loader accepts the input (else: InputError)
    const char *message;  ///< a part of the InputError's message ("" when accepted)
    const char *bug;      ///< what went wrong before the fix
};

// "<harness>/<file>" -> expected outcome. A file without an entry, or an entry without its file,
// fails the test: every regression input is documented here.
const std::map<std::string, Expected> &expectations()
{
    static const std::map<std::string, Expected> table{
        {"urdf/link-with-two-parents.urdf",
         {false, "joint 'j3' child: link 'b' is already the child of joint 'j1'",
          "urdfdom linked the loop b -> c -> b with shared_ptrs and leaked it"}},
        {"urdf/joint-cycle.urdf",
         {false, "the joints form a cycle through link 'b'", "urdfdom leaked the cycle a -> b -> a"}},
        {"urdf/joint-own-parent.urdf",
         {false, "joint 'loop': the joints form a cycle through link 'a'",
          "urdfdom leaked a link that is its own child"}},
        {"urdf/link-name-bare-ampersand.urdf",
         {false, "link '&': urdfdom reads this name differently",
          "the pre-scan (TinyXML 2) read the link as '&', urdfdom (TinyXML 1) as '': null dereference"}},
        {"urdf/joint-name-bare-ampersand.urdf",
         {false, "joint 'j&': urdfdom reads this name differently", "the same for a joint name"}},
        {"scene/quaternion-map-missing-component.yaml",
         {false, "primitive_poses[3].orientation.y: expected a number",
          "Eigen's comma initializer asserted (abort) while the InputError unwound through it"}},
        {"scene/weld-hash-object-6km-away.yaml",
         {true, "", "vertex welding hashed cell coordinates with signed products: overflow (UB)"}},
        {"scene/weld-cell-beyond-int64.yaml",
         {true, "", "vertex welding converted a cell coordinate of 1e21 to int64 (UB)"}},
        {"scene/sphere-of-605-m.yaml",
         {true, "", "a sphere of 605 m at 1 mm made a million triangles: 9.3 s, 855 MB (kMaxSphereBands)"}},
        {"mesh/stl-ascii-truncated-facet.bin",
         {false, "STL: unexpected EOF", "assimp leaks the mesh it had built; suppressed (fuzz/FuzzTargets.cpp)"}},
        {"mesh/ply-no-end-header.bin",
         {false, "PLY header: no end_header line", "assimp's PLY importer never returned (timeout)"}},
        {"mesh/ply-ascii-huge-element-count.bin",
         {false, "declares 4000000000 instances", "assimp allocated 48 GB for the declared vertices"}},
        {"mesh/ply-binary-huge-element-count.bin",
         {false, "declares 400000000 instances", "assimp allocated 4.8 GB for the declared vertices"}},
        {"mesh/ply-face-index-out-of-range.bin",
         {false, "PLY header line 2: expected 'format",
          "assimp's post-processing crashed (SEGV) on a face index past the vertices"}},
        {"mesh/ply-ascii-face-index-out-of-range.bin",
         {false, "names vertex", "as above, with a header the PLY check accepts: the face check rejects it"}},
        {"mesh/ply-face-without-vertices.bin",
         {false, "PLY header line 2: expected 'format", "assimp's Triangulate step aborted on an assertion"}},
        {"mesh/ply-ascii-face-without-vertices.bin",
         {false, "face 0 has no vertices", "as above, with a header the PLY check accepts"}},
        {"mesh/obj-texture-line-before-newmtl.bin",
         {false, "", "assimp's MTL parser (fed the OBJ's own bytes as the fallback .mtl) crashed (SEGV)"}},
        {"mesh/ply-end-header-skipped-after-cr-cr.bin",
         {false, "PLY header: no end_header line",
          "the first header check saw an end_header assimp skips (after \\r\\r): assimp hung (and crashes here)"}},
        {"mesh/ply-cr-line-ends.bin",
         {false, "mesh has no triangles",
          "not a failure: assimp reads \\r-only line ends, so the check must pass them"}},
        {"mesh/ply-signed-list-count-fuzzer.bin",
         {false, "PLY header line 2: expected 'format",
          "assimp read a list length of -1 (signed char) as 4294967295 and allocated 34 GB"}},
        {"mesh/ply-binary-list-length-minus-one.bin",
         {false, "list of -1 values runs past the end of the file", "as above, well-formed header"}},
        {"mesh/ply-ascii-list-length-4294967295.bin",
         {false, "list of 4294967295 values has 3 on its line", "the same allocation from an ASCII file"}},
    };
    return table;
}

std::string folder()
{
    return rastercheck::test::sourcePath("tests/data/fuzz-regressions");
}

std::string readBytes(const fs::path &path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
}  // namespace

TEST(FuzzRegressions, EveryInputGivesItsDocumentedOutcome)
{
    fz::silenceLog();
    std::set<std::string> seen;
    for (const std::string &harness : fz::targetNames())
    {
        const fs::path directory = fs::path(folder()) / harness;
        if (!fs::is_directory(directory))
            continue;
        std::vector<fs::path> files;
        for (const fs::directory_entry &entry : fs::directory_iterator(directory))
            if (entry.is_regular_file())
                files.push_back(entry.path());
        std::sort(files.begin(), files.end());
        for (const fs::path &file : files)
        {
            const std::string key = harness + "/" + file.filename().string();
            SCOPED_TRACE(key);
            seen.insert(key);
            const std::string bytes = readBytes(file);
            fz::Outcome outcome;
            try
            {
                outcome = fz::findTarget(harness)(reinterpret_cast<const std::uint8_t *>(bytes.data()), bytes.size());
            }
            catch (const std::exception &e)
            {
                ADD_FAILURE() << "unexpected exception: " << e.what();
                continue;
            }
            auto expected = expectations().find(key);
            if (expected == expectations().end())
            {
                ADD_FAILURE() << "no expected outcome listed (loader " << (outcome.accepted ? "accepts it" : "says: ")
                              << outcome.error << ")";
                continue;
            }
            EXPECT_EQ(outcome.accepted, expected->second.accepted) << outcome.error;
            EXPECT_NE(outcome.error.find(expected->second.message), std::string::npos)
                << "message: " << outcome.error << "\nexpected to contain: " << expected->second.message;
        }
    }
    for (const auto &[key, expected] : expectations())
        EXPECT_TRUE(seen.count(key)) << key << " is listed but its file is missing (" << expected.bug << ")";
}

// OMPL.app's import (loadOmplAppVertices: .cfg robot centres and world bounds) runs more assimp
// steps (GenNormals, OptimizeGraph) after the same checks: the mesh inputs, written as files with the
// extension their first byte selects, get their documented outcome through it too.
TEST(FuzzRegressions, MeshInputsGiveTheSameOutcomeThroughOmplAppsImport)
{
    fz::silenceLog();
    static const char *const hints[] = {"obj", "stl", "dae", "ply"};
    const std::string scratch = rastercheck::test::makeTempDir("fuzz-omplapp");
    for (const auto &[key, expected] : expectations())
    {
        if (key.rfind("mesh/", 0) != 0)
            continue;
        SCOPED_TRACE(key);
        const std::string bytes = readBytes(fs::path(folder()) / key);
        ASSERT_FALSE(bytes.empty());
        const std::string file = rastercheck::test::writeFile(
            scratch + "/" + fs::path(key).stem().string() + "." + hints[bytes[0] & 3], bytes.substr(1));
        try
        {
            rastercheck::loadOmplAppVertices(file);
            EXPECT_TRUE(expected.accepted);
        }
        catch (const rastercheck::InputError &e)
        {
            EXPECT_FALSE(expected.accepted) << e.what();
            EXPECT_EQ(e.file(), file);
            EXPECT_NE(std::string(e.what()).find(expected.message), std::string::npos)
                << "message: " << e.what() << "\nexpected to contain: " << expected.message;
        }
    }
}

TEST(FuzzRegressions, EveryHarnessHasAnEntryPoint)
{
    for (const std::string &harness : fz::targetNames())
        EXPECT_NE(fz::findTarget(harness), nullptr) << harness;
    EXPECT_THROW(fz::findTarget("no-such-harness"), std::invalid_argument);
}

// The committed seeds are valid input: each harness must accept its own (else the fuzzer would
// start from inputs that fail early, and a broken scratch fixture would go unnoticed).
TEST(FuzzRegressions, CommittedSeedsAreAccepted)
{
    fz::silenceLog();
    const std::map<std::string, char> meshSelector{{".obj", 0}, {".stl", 1}, {".dae", 2}, {".ply", 3}};
    for (const std::string &harness : fz::targetNames())
    {
        const fs::path directory = fs::path(rastercheck::test::sourcePath("fuzz/seeds")) / harness;
        if (!fs::is_directory(directory))
            continue;
        for (const fs::directory_entry &entry : fs::directory_iterator(directory))
        {
            SCOPED_TRACE(entry.path().string());
            std::string bytes = readBytes(entry.path());
            if (harness == "mesh")  // as bench/fuzz.sh: the first byte picks the format hint
                bytes.insert(bytes.begin(), meshSelector.at(entry.path().extension().string()));
            const fz::Outcome outcome =
                fz::findTarget(harness)(reinterpret_cast<const std::uint8_t *>(bytes.data()), bytes.size());
            EXPECT_TRUE(outcome.accepted) << outcome.error;
        }
    }
}
