#!/usr/bin/env bash
# Fuzzes one input reader with libFuzzer:  scripts/fuzz.sh TARGET SECONDS
#   TARGET  gltf (the glTF loader: .gltf with data-URI buffers, and .glb), vdb (the voxel
#           cache's .vdb reader) or cli (the render and voxelize commands' option parser, with
#           tests/fuzz/cli.dict of their flags)
# Builds build-fuzz/ with clang 14, AddressSanitizer and UndefinedBehaviorSanitizer (installing
# clang-14 and libfuzzer-14-dev from Debian when missing and run as root), seeds the corpus
# with tests/fuzz/regressions/TARGET/ (and data/'s scenes for gltf), and runs the fuzzer for
# SECONDS on one core. Each crash, hang (> 10 s) or out-of-memory (> 2 GiB) is written to
# build-fuzz/findings/TARGET/; fix it, then keep the input in tests/fuzz/regressions/TARGET/ so
# that `meson test` (fuzz_replay) replays it from then on.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${1:?usage: scripts/fuzz.sh gltf|vdb|cli SECONDS}"
seconds="${2:?usage: scripts/fuzz.sh gltf|vdb|cli SECONDS}"
case "$target" in gltf|vdb|cli) ;; *) echo "fuzz.sh: unknown target '$target' (gltf, vdb, cli)" >&2; exit 2 ;; esac

if ! command -v clang++-14 >/dev/null || ! ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ]; then
        apt-get update -qq && apt-get install -y -qq --no-install-recommends clang-14 libfuzzer-14-dev libclang-rt-14-dev
    else
        echo "fuzz.sh: needs clang-14 and libfuzzer-14-dev (apt-get install clang-14 libfuzzer-14-dev libclang-rt-14-dev)" >&2
        exit 1
    fi
fi
if [ ! -d build-fuzz ]; then
    CC=clang-14 CXX=clang++-14 meson setup build-fuzz -Dbuildtype=debugoptimized -Db_sanitize=address,undefined \
        -Db_lundef=false -Dfuzz=true -Degl=disabled -Dbench=false >/dev/null
fi
ninja -C build-fuzz "tests/fuzz/fuzz_$target"

corpus="build-fuzz/corpus/$target"
findings="build-fuzz/findings/$target"
mkdir -p "$corpus" "$findings"
cp -n tests/fuzz/regressions/"$target"/* "$corpus"/ 2>/dev/null || true
if [ "$target" = gltf ]; then
    for f in data/*.gltf; do printf '\000' | cat - "$f" > "$corpus/data_$(basename "$f").bin"; done
    for f in data/*.glb; do printf '\001' | cat - "$f" > "$corpus/data_$(basename "$f").bin"; done
fi
dict=()
[ -f "tests/fuzz/$target.dict" ] && dict=(-dict="tests/fuzz/$target.dict")
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# An absurd length read from a corrupt file makes OpenVDB ask for exabytes: in a normal build
# `new` throws std::bad_alloc, which the reader turns into a clean Error; here too, instead of
# ASan aborting (allocator_may_return_null) or libFuzzer calling it a leak of memory
# (-malloc_limit_mb=0). Memory actually used is still bounded by -rss_limit_mb.
export ASAN_OPTIONS=allocator_may_return_null=1
exec "build-fuzz/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -malloc_limit_mb=0 -max_len=262144 -artifact_prefix="$findings/" -print_final_stats=1 "${dict[@]}"
