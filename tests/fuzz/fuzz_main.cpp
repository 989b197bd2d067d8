// libFuzzer's entry for one target, chosen at build time (RAYSPLAT_FUZZ_TARGET).
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const rs::fuzz::Target target = rs::fuzz::targetNamed(RAYSPLAT_FUZZ_TARGET);
    target(data, size);
    return 0;
}
