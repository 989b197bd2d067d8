#!/usr/bin/env bash
# The GPU check, for a machine with a GPU: builds, reports the EGL device
# the voxelizer gets, checks the GPU voxelizer exactly against the CPU voxelizer on every data/
# scene (grid 96) and on the teapot (grid 256), and times both voxelizers on the glossy box
# (192³) and the teapot (256³), medians of 3.
#
#   scripts/device_check.sh [EXTRA_SCENES_DIR]
#
# EXTRA_SCENES_DIR holds bitterli-teapot/teapot.glb (default: $RAYSPLAT_EXTRA_SCENES); without
# it the teapot is skipped. Where the NVIDIA EGL vendor file is installed, it is selected
# (__EGL_VENDOR_LIBRARY_FILENAMES), so the check fails rather than quietly using llvmpipe
# when the GPU is not usable. Runs anywhere EGL does (on llvmpipe it checks the same things).
set -euo pipefail
cd "$(dirname "$0")/.."
export RAYSPLAT_EXTRA_SCENES="${1:-${RAYSPLAT_EXTRA_SCENES:-}}"
for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json /usr/share/glvnd/egl_vendor.d/10_nvidia.json; do
    if [ -f "$f" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$f"; break; fi
done

[ -d build-device ] || meson setup build-device -Dbuildtype=release -Degl=enabled >/dev/null
ninja -C build-device raysplat tests/voxelize_test tests/voxelize_bench
build-device/raysplat info data/cornell_box.gltf --gpu | grep '^gpu'
RAYSPLAT_DATA="$PWD/data" build-device/tests/voxelize_test --gtest_filter='VoxelizeGpu.*' --gtest_brief=1
RAYSPLAT_DATA="$PWD/data" build-device/tests/voxelize_bench
