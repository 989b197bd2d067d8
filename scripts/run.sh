#!/usr/bin/env bash
# raysplat on a fresh Debian 12 machine, from a clean clone:
#
#   scripts/run.sh render   install what is missing, build, render data/cornell_box.gltf
#                           to out/cornell_box.exr and out/cornell_box.png
#   scripts/run.sh test     install what is missing (Blender's bpy, pinned, in .venv-blender/),
#                           build, run the whole test suite
#   scripts/run.sh build    install what is missing and build (build/raysplat)
#   scripts/run.sh study    also install python3-venv and libLLVM 19 (for Mitsuba's LLVM
#                           variant), build, and run the quality study (scripts/study.py)
#                           and the walkthrough study (scripts/walkthrough_study.py), which
#                           write docs/results/ and docs/results.md
#   scripts/run.sh sanitize also install clang 14, build build-san/ with AddressSanitizer and
#                           UndefinedBehaviorSanitizer, and run the test suite there (CI runs
#                           it after `test`). tests/sanitizers/ubsan.supp lists what is
#                           suppressed in third-party headers, and why. Without EGL: Mesa's
#                           llvmpipe keeps allocations made from its JIT code to the end, which
#                           LeakSanitizer reports and cannot attribute; without MPI: Open MPI's
#                           own allocations are reported the same way
#
# Packages are installed with apt-get only when one is missing (needs root or sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(g++ pkg-config meson ninja-build python3 python3-venv zlib1g-dev
  libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libglm-dev
  libembree-dev libopenvdb-dev libboost-dev libopenexr-dev libtinygltf-dev
  libtbb-dev libgtest-dev libbenchmark-dev libopenmpi-dev openmpi-bin libstb-dev)

install_missing() {
  local missing=()
  [ "${1:-}" = study ] && packages+=(python3-venv python3-pip libllvm19)
  [ "${1:-}" = sanitize ] && packages+=(clang-14 libclang-rt-14-dev)
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "raysplat: installing ${#missing[@]} missing packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# Blender as a Python module for the Blender checks: bpy 4.2.0 (the LTS for Python 3.11,
# Debian 12's), pinned, in its own virtual environment, with OpenEXR's Python module to read
# raysplat's layered EXR files (Blender reads only their first layer). Without network it is
# skipped (the checks then skip), unless RAYSPLAT_REQUIRE_BLENDER=1 (CI) makes that a failure.
readonly BPY_VERSION=4.2.0 BPY_OPENEXR_VERSION=3.5.3
blender_venv() {
  local python=.venv-blender/bin/python
  if [ -x "$python" ] && "$python" -c "import importlib.metadata as m; assert m.version('bpy') == '$BPY_VERSION'; assert m.version('OpenEXR') == '$BPY_OPENEXR_VERSION'" 2>/dev/null; then
    return 0
  fi
  echo "raysplat: installing Blender's bpy $BPY_VERSION into .venv-blender/ (about 500 MB)"
  if /usr/bin/python3 -m venv --clear .venv-blender &&
     .venv-blender/bin/pip install -q "bpy==$BPY_VERSION" "OpenEXR==$BPY_OPENEXR_VERSION"; then
    return 0
  fi
  rm -rf .venv-blender
  if [ "${RAYSPLAT_REQUIRE_BLENDER:-}" = 1 ]; then
    echo "raysplat: could not install bpy $BPY_VERSION, and RAYSPLAT_REQUIRE_BLENDER=1" >&2
    exit 1
  fi
  echo "raysplat: could not install bpy $BPY_VERSION: the Blender check will skip" >&2
}

build() {
  [ -f build/build.ninja ] || meson setup build --buildtype=release
  ninja -C build
}

# Under the sanitizers the suite runs the code, not the statistics: these comparisons of whole
# renders with the path tracer at sizes that resolve a per cent (half the sanitized suite's
# time) run in the normal build's suite only; their code runs sanitized in smaller tests (the
# kernel-scale probe in ReplayedPhotonsAddUpUnderTheKernelScaleProbe, portals in
# Portals.*, sparse receivers in every default render). So does the Blender suite's:
# Blender drives the same CLI that cli_test runs sanitized.
readonly sanitize_skips="KernelScale.ChosenByTheSceneAgainstThePathTracer:GapRooms.LayersMatchThePathTracerThroughTheOpening:\
IndirectBias.*:SparseReceivers.KeepTheFullDensitySplatsLightOnThinPartsAndCorners:Passes.ErrorFallsWithEveryQuadrupling"

case "${1:-}" in
  render)
    install_missing; build
    mkdir -p out
    build/raysplat render data/cornell_box.gltf -o out/cornell_box.exr --png out/cornell_box.png
    ;;
  test)
    install_missing; build; blender_venv
    meson test -C build --print-errorlogs --num-processes 2
    ;;
  build)
    install_missing; build ;;
  study)
    install_missing study; build
    python3 scripts/study.py
    python3 scripts/walkthrough_study.py --readme docs/results.md
    ;;
  sanitize)
    install_missing sanitize
    [ -f build-san/build.ninja ] || CC=clang-14 CXX=clang++-14 meson setup build-san --buildtype=debugoptimized \
      -Db_sanitize=address,undefined -Db_lundef=false -Dbench=false -Degl=disabled -Dmpi=disabled
    ninja -C build-san
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/sanitizers/ubsan.supp" \
      GTEST_FILTER="-$sanitize_skips" \
      meson test -C build-san --print-errorlogs --num-processes 2 --timeout-multiplier 4 --no-suite blender
    ;;
  *)
    echo "usage: scripts/run.sh render|test|build|study|sanitize" >&2; exit 2 ;;
esac
