// libFuzzer's entry for one target, chosen at build time (RAYSPLAT_FUZZ_TARGET).
#include <cstdio>

#include "targets.h"

// libFuzzer reports on stderr; what the targets print (the cli target's --help) would only
// fill the log.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    return std::freopen("/dev/null", "w", stdout) ? 0 : 1;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const rs::fuzz::Target target = rs::fuzz::targetNamed(RAYSPLAT_FUZZ_TARGET);
    target(data, size);
    return 0;
}
