// libFuzzer entry point of one target (tests/fuzz/CMakeLists.txt builds one executable per target, with
// TERRAIN_FUZZ_ENTRY naming the function of FuzzTargets.h).
#include "FuzzTargets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    TERRAIN_FUZZ_ENTRY(std::span<const std::uint8_t>(data, size));
    return 0;
}
