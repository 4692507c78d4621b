// The libFuzzer harness of one loader: compiled once per target with RASTERCHECK_FUZZ_TARGET set
// to the entry point's name (fuzz/CMakeLists.txt). Documented errors are the expected outcome and
// are handled inside the entry point; a crash, sanitizer report, leak, hang or any other exception
// (ContractViolation included: uncaught, it aborts) is what libFuzzer reports.
#include <cstddef>
#include <cstdint>

#include "FuzzTargets.h"

extern "C" int LLVMFuzzerInitialize(int *, char ***)
{
    rastercheck::fuzz::silenceLog();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size)
{
    rastercheck::fuzz::RASTERCHECK_FUZZ_TARGET(data, size);
    return 0;
}
