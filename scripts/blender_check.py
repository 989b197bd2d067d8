#!/usr/bin/env python3
"""Checks with Blender (bpy, Blender as a Python module) that a raysplat .vdb loads and
overlays the glTF scene it was made from (docs/design.md §5).

usage: blender_check.py SCENE.gltf GRID.vdb
       blender_check.py --scene SCENE.gltf [--vdb OUT.vdb] [--grid N]
           voxelizes first: $RAYSPLAT voxelize SCENE -o OUT.vdb --voxelizer cpu [--grid N]

Checks: the glTF imports; every grid (density, normal, occ_px … occ_nz) loads with its type
(FLOAT / VECTOR_FLOAT); the density grid's index → world matrix is voxelSize × the rotation
(x, y, z) → (x, −z, y) of Blender's glTF importer; and the density grid's world bounds
match the imported meshes' world bounds within one voxel per axis. Blender's object
bound_box is computed from whole 8³ leaf nodes, so the precise bounds come from Blender's
own Volume to Mesh of the density grid at a tiny threshold: its surface lies one voxel
(minus threshold/density) outside the active voxel centres, i.e. half a voxel outside the
active voxel cells (after undoing the half-voxel shift Blender adds to that mesh). The
coarse bound_box is checked too (within one leaf).

Exit status: 0 PASS, 1 FAIL, 77 skipped (bpy cannot be imported: machines without it; with
RAYSPLAT_REQUIRE_BLENDER=1, as CI sets it, that is a failure too).

Interpreter: $RAYSPLAT_BPY_PYTHON if set, else <source>/.venv-blender/bin/python if it
exists, else the Python running this script; the script re-executes itself under it.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
REEXEC_MARK = "RAYSPLAT_BPY_REEXECUTED"
EXPECTED_GRIDS = {
    "density": "FLOAT",
    "normal": "VECTOR_FLOAT",
    "occ_px": "FLOAT",
    "occ_nx": "FLOAT",
    "occ_py": "FLOAT",
    "occ_ny": "FLOAT",
    "occ_pz": "FLOAT",
    "occ_nz": "FLOAT",
}
SKIP, FAIL = 77, 1


def say(msg):
    print(f"blender_check: {msg}", flush=True)


def reexec_under_bpy_python(script=__file__):
    """Runs `script` again under the bpy interpreter, with this process's arguments."""
    if os.environ.get(REEXEC_MARK):
        return
    chosen = os.environ.get("RAYSPLAT_BPY_PYTHON")
    explicit = bool(chosen)
    if not chosen:
        venv = ROOT / ".venv-blender" / "bin" / "python"
        chosen = str(venv) if venv.exists() else None
    if not chosen or os.path.abspath(chosen) == os.path.abspath(sys.executable):
        return
    os.environ[REEXEC_MARK] = "1"
    try:
        os.execv(chosen, [chosen, str(Path(script).resolve())] + sys.argv[1:])
    except OSError as e:
        say(f"cannot run {chosen}: {e}")
        sys.exit(FAIL if explicit or os.environ.get("RAYSPLAT_REQUIRE_BLENDER") == "1" else SKIP)


_temporary = []  # begin_check's work folders, removed by exit_without_teardown


def begin_check(name, binary=None, keep=None):
    """What a check of raysplat through bpy starts with, run under the bpy interpreter: bpy
    imported (SKIP where it cannot be, FAIL with RAYSPLAT_REQUIRE_BLENDER=1), the binary
    (`binary`, else $RAYSPLAT), a Checks and a work folder (`keep`, else a temporary one).
    Returns (bpy, binary, checks, work), or the exit code where the check cannot run."""
    required = os.environ.get("RAYSPLAT_REQUIRE_BLENDER") == "1"
    try:
        import bpy
    except Exception as e:  # ImportError, or a bpy built for another Python
        print(f"{name}: {'FAIL' if required else 'SKIP'}: cannot import bpy with {sys.executable} ({e})", flush=True)
        return FAIL if required else SKIP
    binary = binary or os.environ.get("RAYSPLAT")
    if not binary:
        print(f"{name}: FAIL: set $RAYSPLAT to the raysplat binary", flush=True)
        return FAIL
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
    else:
        keep = tempfile.mkdtemp(prefix=name + "-")
        _temporary.append(keep)
    return bpy, binary, Checks(), Path(keep)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="*", help="SCENE.gltf GRID.vdb")
    p.add_argument("--scene", help="voxelize this scene first (with $RAYSPLAT or --raysplat)")
    p.add_argument("--vdb", help="with --scene: the .vdb to write (default: beside the scene's name in the cwd)")
    p.add_argument("--grid", type=int, help="with --scene: --grid N for raysplat voxelize")
    p.add_argument("--raysplat", default=os.environ.get("RAYSPLAT"), help="the raysplat binary (default $RAYSPLAT)")
    a = p.parse_args()
    if a.scene:
        if a.files:
            p.error("give either SCENE GRID.vdb or --scene SCENE")
        a.vdb = a.vdb or (Path(a.scene).stem + ".vdb")
    elif len(a.files) == 2:
        a.scene, a.vdb = a.files
    else:
        p.error("give SCENE.gltf GRID.vdb, or --scene SCENE.gltf")
    return a


class Checks:
    def __init__(self):
        self.failed = []
        self.count = 0

    def check(self, ok, what):
        self.count += 1
        say(f"{'ok  ' if ok else 'FAIL'} {what}")
        if not ok:
            self.failed.append(what)
        return ok

    def finish(self, name, what=""):
        """Prints the verdict as `name`; the exit status. `what`: what a pass shows."""
        if self.failed:
            print(f"{name}: FAIL: {len(self.failed)} of {self.count} checks failed", flush=True)
            return FAIL
        print(f"{name}: PASS: {self.count} checks" + (f" ({what})" if what else ""), flush=True)
        return 0


def exit_without_teardown(status):
    """Exits with `status` at once: bpy 4.2 segfaults while the interpreter shuts down after a
    glTF import (exit 139 after a PASS), so the teardown is skipped; begin_check's temporary
    work folders are removed first."""
    for folder in _temporary:
        shutil.rmtree(folder, ignore_errors=True)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


def world_bounds_of_meshes(objects):
    import numpy as np

    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for o in objects:
        n = len(o.data.vertices)
        if n == 0:
            continue
        co = np.empty(n * 3, dtype=np.float64)
        o.data.vertices.foreach_get("co", co)
        co = co.reshape(n, 3)
        m = np.array(o.matrix_world, dtype=np.float64)
        w = co @ m[:3, :3].T + m[:3, 3]
        lo = np.minimum(lo, w.min(axis=0))
        hi = np.maximum(hi, w.max(axis=0))
    return lo, hi


def fmt3(v):
    return "(" + ", ".join(f"{x:.4f}" for x in v) + ")"


def main():
    reexec_under_bpy_python()
    args = parse_args()
    try:
        import bpy
        import mathutils
        import numpy as np
    except Exception as e:  # ImportError, or a bpy built for another Python
        required = os.environ.get("RAYSPLAT_REQUIRE_BLENDER") == "1"
        say(f"{'FAIL' if required else 'SKIP'}: cannot import bpy with {sys.executable} ({e.__class__.__name__}: {e})")
        return FAIL if required else SKIP

    say(f"Blender {bpy.app.version_string} (bpy) under {sys.executable}")
    scene_path = str(Path(args.scene).resolve())
    vdb_path = str(Path(args.vdb).resolve())

    if args.files == []:  # --scene: voxelize first
        if not args.raysplat:
            say("FAIL: --scene needs the raysplat binary: set $RAYSPLAT or give --raysplat")
            return FAIL
        cmd = [args.raysplat, "voxelize", scene_path, "-o", vdb_path, "--voxelizer", "cpu"]
        if args.grid:
            cmd += ["--grid", str(args.grid)]
        say("running " + " ".join(cmd))
        r = subprocess.run(cmd)
        if r.returncode != 0:
            say(f"FAIL: raysplat voxelize exited with {r.returncode}")
            return FAIL

    c = Checks()
    if not c.check(Path(vdb_path).is_file(), f"{vdb_path} exists"):
        return FAIL

    # The scene, as Blender's glTF importer places it (+Y up → +Z up).
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=scene_path)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    c.check("FINISHED" in result and bool(meshes), f"glTF import of {scene_path}: {len(meshes)} mesh objects")
    if not meshes:
        return FAIL
    bpy.context.view_layer.update()
    mesh_lo, mesh_hi = world_bounds_of_meshes(meshes)
    say(f"meshes' world bounds      {fmt3(mesh_lo)} to {fmt3(mesh_hi)}")

    # The grids.
    vol = bpy.data.volumes.new("raysplat_grid")
    vol.filepath = vdb_path
    if not c.check(vol.grids.load(), f"{vdb_path} opens as a volume ({vol.grids.error_message or 'no error'})"):
        return FAIL
    vol_obj = bpy.data.objects.new("raysplat_grid", vol)
    bpy.context.scene.collection.objects.link(vol_obj)
    grids = {g.name: g for g in vol.grids}
    for name, expected_type in EXPECTED_GRIDS.items():
        g = grids.get(name)
        if not c.check(g is not None, f"grid '{name}' is in the file"):
            continue
        loaded = g.load()  # in 5.x is_loaded stays False: the return value is what counts
        c.check(loaded and g.data_type == expected_type, f"grid '{name}' loads as {g.data_type} (expected {expected_type})")
    extra = sorted(set(grids) - set(EXPECTED_GRIDS))
    c.check(not extra, f"no unexpected grids {extra if extra else ''}".rstrip())
    if "density" not in grids:
        return FAIL

    # Index → world: voxelSize × rotation (x, y, z) → (x, −z, y), the importer's axis change.
    m = np.array(grids["density"].matrix_object, dtype=np.float64)
    voxel = float(np.linalg.norm(m[:3, 0]))
    rotation = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=np.float64)
    c.check(voxel > 0 and np.allclose(m[:3, :3], voxel * rotation, atol=1e-6 * max(voxel, 1e-9) + 1e-9),
            f"density index → world is {voxel:.5g} m × the glTF +Y-up → Blender +Z-up rotation")

    # Coarse: Blender's object bounds (whole 8³ leaves, half-voxel padded).
    bpy.context.view_layer.update()
    corners = np.array([list(vol_obj.matrix_world @ mathutils.Vector(b)) for b in vol_obj.bound_box])
    bb_lo, bb_hi = corners.min(axis=0), corners.max(axis=0)
    say(f"volume bound_box (leaves) {fmt3(bb_lo)} to {fmt3(bb_hi)}")
    leaf = 8 * voxel + 0.5 * voxel + 1e-4
    c.check(bool(np.all(bb_lo <= mesh_lo + 1e-4) and np.all(bb_hi >= mesh_hi - 1e-4) and
                 np.all(mesh_lo - bb_lo <= leaf) and np.all(bb_hi - mesh_hi <= leaf)),
            "volume bound_box contains the meshes, within one 8-voxel leaf")

    # Precise: the density grid's active cells, via Blender's Volume to Mesh.
    threshold = 1e-4
    surf_mesh = bpy.data.meshes.new("density_surface")
    surf_obj = bpy.data.objects.new("density_surface", surf_mesh)
    bpy.context.scene.collection.objects.link(surf_obj)
    mod = surf_obj.modifiers.new("density_to_mesh", "VOLUME_TO_MESH")
    mod.object = vol_obj
    mod.grid_name = "density"
    mod.threshold = threshold
    mod.resolution_mode = "GRID"
    mod.adaptivity = 0.0
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = surf_obj.evaluated_get(depsgraph)
    surf_lo, surf_hi = world_bounds_of_meshes([evaluated])
    if not c.check(len(evaluated.data.vertices) > 0, f"Volume to Mesh of density: {len(evaluated.data.vertices)} vertices"):
        return FAIL
    # Blender adds voxelSize/2 to every vertex of Volume to Mesh, along the world axes ("better
    # align generated mesh with volume", T85312, volume_to_mesh.cc): undo it. Then the surface
    # lies one voxel outside the active centres, half a voxel outside the active cells.
    surf_lo, surf_hi = surf_lo - 0.5 * voxel, surf_hi - 0.5 * voxel
    cells_lo, cells_hi = surf_lo + 0.5 * voxel, surf_hi - 0.5 * voxel
    say(f"density active cells      {fmt3(cells_lo)} to {fmt3(cells_hi)}")
    tol = voxel * (1.0 + 0.02)  # 2 %: the surface's threshold/density offset and float rounding
    for a, axis in enumerate("xyz"):
        d_lo, d_hi = mesh_lo[a] - cells_lo[a], cells_hi[a] - mesh_hi[a]
        c.check(abs(d_lo) <= tol and abs(d_hi) <= tol,
                f"{axis}: density cells extend the meshes by {d_lo / voxel:+.3f} / {d_hi / voxel:+.3f} voxels (limit ±1)")

    return c.finish("blender_check", f"{Path(vdb_path).name} overlays {Path(scene_path).name} in Blender")


if __name__ == "__main__":
    exit_without_teardown(main())
