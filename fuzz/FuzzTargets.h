#pragma once

// One entry point per loader, shared by the libFuzzer harnesses (fuzz/fuzz_*.cpp) and the
// regression test that replays every input that once failed (tests/test_fuzz_regressions.cpp), so
// both run exactly the same code on a given input.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace rastercheck::fuzz
{
/** \brief What a loader did with one input: accepted it, or rejected it with an InputError (the
    documented outcome for bad input; its message is kept). Anything else a loader throws escapes
    the entry points, so the fuzzer reports it as a crash and the regression test fails. */
struct Outcome
{
    bool accepted = false;
    std::string error;  ///< InputError::what() when rejected
};

/** \brief A loader broke its contract without crashing: an InputError that does not name the input,
    or a result that violates the loader's documented guarantees (a triangle index past the
    vertices, a non-finite vertex, a row of the wrong width). Deliberately not a rastercheck::Error,
    so nothing that catches loader errors swallows it. */
class ContractViolation : public std::logic_error
{
public:
    using std::logic_error::logic_error;
};

using Target = Outcome (*)(const std::uint8_t *data, std::size_t size);

/** \brief loadUrdfString; relative mesh paths resolve in a scratch folder holding `mesh.stl` (a
    box), so seeds whose mesh file names are rewritten to it build complete models. */
Outcome urdf(const std::uint8_t *data, std::size_t size);
/** \brief loadSrdfString, then applySrdf onto a copy of a small fixed robot whose link names are
    the Panda's (panda_link0..3, panda_hand), so real SRDF seeds reach the matrix updates. */
Outcome srdf(const std::uint8_t *data, std::size_t size);
/** \brief loadMoveItSceneString. */
Outcome scene(const std::uint8_t *data, std::size_t size);
/** \brief loadMoveItRequestString. */
Outcome request(const std::uint8_t *data, std::size_t size);
/** \brief loadOmplAppProblemString; meshes resolve in the scratch folder, which holds `robot.stl`
    (a tetrahedron) and `world.stl` (two boxes). */
Outcome cfg(const std::uint8_t *data, std::size_t size);
/** \brief parseStatesCsv with the Panda arm's coordinate names panda_joint1..7. */
Outcome csv(const std::uint8_t *data, std::size_t size);
/** \brief loadMeshNodesFromMemory: the first byte picks the format hint (low two bits: obj, stl,
    dae, ply) and the COLLADA up-axis handling (bit 2); the rest is the file. */
Outcome mesh(const std::uint8_t *data, std::size_t size);

/** \brief The harness names ("urdf", "srdf", "scene", "request", "cfg", "csv", "mesh"): each is
    the fuzzer fuzz_<name> and the folder tests/data/fuzz-regressions/<name>/. */
const std::vector<std::string> &targetNames();
/** \brief The entry point named \a name; throws std::invalid_argument for an unknown name. */
Target findTarget(const std::string &name);

/** \brief Silences rastercheck's log (loaders warn about fallbacks; printing them for every
    fuzzer execution would cost more than the parsing). */
void silenceLog();
}  // namespace rastercheck::fuzz
