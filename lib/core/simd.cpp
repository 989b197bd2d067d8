// The traversal's instruction set, chosen in one place (simd.h).
#include "core/simd.h"

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/error.h"

namespace rs {

namespace {

bool cpuHas(Isa isa) {
    if (isa == Isa::Sse2) return true;
#if RS_TRAVERSE_AVX512
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f");
#else
    return false;
#endif
}

// RAYSPLAT_SIMD's value: true with `isa` set for a known name, false for none or an unknown one.
bool fromEnvironment(Isa& isa) {
    const char* name = std::getenv("RAYSPLAT_SIMD");
    if (!name) return false;
    for (Isa i : {Isa::Sse2, Isa::Avx512})
        if (std::strcmp(name, isaName(i)) == 0) return isa = i, true;
    return false;
}

Isa initialChoice() {
    Isa isa;
    if (fromEnvironment(isa) && cpuHas(isa)) return isa;
    return cpuHas(Isa::Avx512) ? Isa::Avx512 : Isa::Sse2;
}

std::atomic<Isa>& choice() {
    static std::atomic<Isa> isa{initialChoice()};
    return isa;
}

}  // namespace

const char* isaName(Isa isa) { return isa == Isa::Avx512 ? "avx512" : "sse2"; }

Isa traversalIsa() { return choice().load(std::memory_order_relaxed); }

void checkSimdEnvironment() {
    const char* name = std::getenv("RAYSPLAT_SIMD");
    if (!name) return;
    Isa isa;
    if (!fromEnvironment(isa))
        throw Error(ErrorKind::Config, std::string("RAYSPLAT_SIMD=") + name + " is not an instruction set (sse2, avx512)");
    if (!cpuHas(isa)) throw Error(ErrorKind::Config, std::string("RAYSPLAT_SIMD=") + name + ": this CPU does not have it");
}

bool setTraversalIsa(Isa isa) {
    if (!cpuHas(isa)) return false;
    choice().store(isa, std::memory_order_relaxed);
    return true;
}

}  // namespace rs
