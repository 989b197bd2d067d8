#!/usr/bin/env bash
# raysplat on a fresh Debian 12 machine, from a clean clone:
#
#   scripts/run.sh render   install what is missing, build, render data/cornell_box.gltf
#                           to out/cornell_box.exr and out/cornell_box.png
#   scripts/run.sh test     install what is missing, build, run the whole test suite
#   scripts/run.sh build    install what is missing and build (build/raysplat)
#   scripts/run.sh study    also install python3-venv and libLLVM 19 (for Mitsuba's LLVM
#                           variant), build, and run the quality study (scripts/study.py),
#                           which writes docs/results/ and the README's Results section
#
# Packages are installed with apt-get only when one is missing (needs root or sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(g++ pkg-config meson ninja-build python3 zlib1g-dev
  libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libglm-dev
  libembree-dev libopenvdb-dev libboost-dev libopenexr-dev libtinygltf-dev
  libtbb-dev libgtest-dev libbenchmark-dev)

install_missing() {
  local missing=()
  [ "${1:-}" = study ] && packages+=(python3-venv python3-pip libllvm19)
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

build() {
  [ -f build/build.ninja ] || meson setup build --buildtype=release
  ninja -C build
}

case "${1:-}" in
  render)
    install_missing; build
    mkdir -p out
    build/raysplat render data/cornell_box.gltf -o out/cornell_box.exr --png out/cornell_box.png
    ;;
  test)
    install_missing; build
    meson test -C build --print-errorlogs --num-processes 2
    ;;
  build)
    install_missing; build ;;
  study)
    install_missing study; build
    python3 scripts/study.py
    ;;
  *)
    echo "usage: scripts/run.sh render|test|build|study" >&2; exit 2 ;;
esac
