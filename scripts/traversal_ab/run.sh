#!/bin/bash
# The kd-tree benchmark's cylinder traversal of two revisions, compared in one process.
#   scripts/traversal_ab/run.sh REV_A [REV_B [ROUNDS [RADIUS ...]]]
# REV_B "." (the default) is the working tree. ROUNDS pairs a radius and thread count
# (default 15), radii in voxels (default 4 8). Prints each side's median rate and the median of
# the pairwise ratios b/a with their range. Builds in a temporary folder with the release
# build's flags (the dependencies: `scripts/run.sh build` installs them). AB_SECONDS sets a
# measurement's length (default 0.25 s of side a); AB_FLAGS_A and AB_FLAGS_B add compiler
# flags to one side (e.g. AB_FLAGS_B=-march=x86-64-v3: the same code for another target).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
[ $# -ge 1 ] || { echo "usage: $0 REV_A [REV_B [ROUNDS [RADIUS ...]]]" >&2; exit 2; }
revA=$1; revB=${2:-.}; shift $(( $# >= 2 ? 2 : 1 ))
work=$(mktemp -d /tmp/traversal_ab.XXXXXX)
cleanup() {
    for side in a b; do [ -d "$work/$side" ] && git -C "$repo" worktree remove --force "$work/$side" 2>/dev/null || true; done
    rm -rf "$work"
}
trap cleanup EXIT
tree_of() {  # side rev -> the folder holding that revision's sources
    if [ "$2" = "." ]; then echo "$repo"; return; fi
    git -C "$repo" worktree add --detach --quiet "$work/$1" "$2" >&2
    echo "$work/$1"
}
flags="-std=c++17 -O3 -DNDEBUG -D_FILE_OFFSET_BITS=64 -ffp-contract=off -pthread -w -ffunction-sections -fdata-sections"
flags="$flags -I/usr/include/Imath -I/usr/include/OpenEXR"
objects=(); pids=()
for side in a b; do
    rev=$revA; [ $side = b ] && rev=$revB
    tree=$(tree_of $side "$rev")
    if [ -d "$tree/lib/splat" ]; then
        sources=$(cd "$tree" && ls lib/occlusion/*.cpp lib/splat/kdtree*.cpp lib/splat/eye.cpp lib/core/*.cpp lib/grid/occlusion_grid.cpp lib/memory.cpp 2>/dev/null)
        flat=0
    else  # the layout before lib/ had folders
        sources="lib/kdtree.cpp lib/eye.cpp lib/stats.cpp lib/parallel.cpp lib/log.cpp lib/occlusion_grid.cpp lib/error.cpp"
        flat=1
    fi
    extra=${AB_FLAGS_A:-}; [ $side = b ] && extra=${AB_FLAGS_B:-}
    echo "side $side: $rev ($(git -C "$tree" log -1 --format='%h %s' | cut -c1-70))${extra:+, flags $extra}"
    for s in $sources "$here/side.cpp"; do
        src=$s; [ "$s" = "$here/side.cpp" ] || src=$tree/$s
        o=$work/$side-$(basename "$s" .cpp).o
        c++ $flags $extra -Drs=rs_$side -DRS_AB_FLAT=$flat -I"$tree/lib" -I"$tree/tests" -c "$src" -o "$o" &
        objects+=("$o"); pids+=($!)
    done
done
for p in "${pids[@]}"; do wait "$p"; done
c++ $flags -c "$here/driver.cpp" -o "$work/driver.o"
c++ -pthread -Wl,--gc-sections -o "$work/traversal_ab" "$work/driver.o" "${objects[@]}"
"$work/traversal_ab" "$@"
