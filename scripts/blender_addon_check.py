#!/usr/bin/env python3
"""Checks the Blender add-on (blender/raysplat_addon) headless, with the pinned bpy:

- the zip installs and enables, and raysplat is a render engine;
- a small scene made here (a closed room with an opening, a sun, a point lamp and an area lamp,
  boxes, a camera) renders with it: the Combined pass equals, to the bit, `raysplat render` of the
  .glb the add-on exported, with the same settings; every pass is present with the layer's values;
- the area lamp became an emissive quad of the lamp's power (radiance P / (π A));
- a render stopped after its first progress line leaves no process and no temporary folder;
- a missing binary and a failing command are reported with one line, the command's own;
- "Show occlusion grid" adds a volume lined up with the meshes;
- Render Animation (Ctrl+F12) of a camera walk, frames 1-3 at step 2: the scene is exported once
  (only the camera animated, where Blender puts it), one process renders the range, and frames
  1 and 3 equal `raysplat render --frames 1-3 --frame-step 2` of the exported .glb to the bit;
  the range's process stops on Esc without a frame file, and a job Blender cancels leaves nothing.

Exit status: 0 PASS, 1 FAIL, 77 skipped (no bpy; with RAYSPLAT_REQUIRE_BLENDER=1 a failure).
Needs $RAYSPLAT (the binary)."""

import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blender_check import FAIL, begin_check, exit_without_teardown, reexec_under_bpy_python, world_bounds_of_meshes  # noqa: E402
from addon_zip import make_zip  # noqa: E402

W, H = 64, 48


def say(msg):
    print(f"blender_addon_check: {msg}", flush=True)


def build_scene(bpy):
    scene = bpy.context.scene
    # Lambert in both renderers: a Principled BSDF of roughness 1 without its specular layer.
    white = bpy.data.materials.new("white")
    white.use_nodes = True
    bsdf = white.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1)
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0

    def box(name, loc, size):
        bpy.ops.mesh.primitive_cube_add(location=loc)
        o = bpy.context.object
        o.name = name
        o.scale = [s / 2 for s in size]
        o.data.materials.append(white)
        return o

    # A 4 × 4 × 2.5 m room of 10 cm walls, a 1 × 1 m opening in the +X wall.
    box("floor", (0, 0, -0.05), (4.2, 4.2, 0.1))
    box("ceiling", (0, 0, 2.55), (4.2, 4.2, 0.1))
    box("wall_-x", (-2.05, 0, 1.25), (0.1, 4.2, 2.5))
    box("wall_-y", (0, -2.05, 1.25), (4.2, 0.1, 2.5))
    box("wall_+y", (0, 2.05, 1.25), (4.2, 0.1, 2.5))
    box("wall_+x_low", (2.05, 0, 0.5), (0.1, 4.2, 1.0))
    box("wall_+x_high", (2.05, 0, 2.25), (0.1, 4.2, 0.5))
    box("wall_+x_a", (2.05, -1.3, 1.5), (0.1, 1.6, 1.0))
    box("wall_+x_b", (2.05, 1.3, 1.5), (0.1, 1.6, 1.0))
    box("block", (0.3, 0.4, 0.4), (0.8, 0.8, 0.8))
    box("column", (-0.9, -0.6, 0.75), (0.4, 0.4, 1.5))

    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 3.0
    o = bpy.data.objects.new("sun", sun)
    o.rotation_euler = (0.0, math.radians(60), 0.0)  # from +X, down, through the opening
    scene.collection.objects.link(o)
    point = bpy.data.lights.new("lamp", "POINT")
    point.energy = 40.0
    o = bpy.data.objects.new("lamp", point)
    o.location = (-1.0, 1.0, 2.0)
    scene.collection.objects.link(o)
    area = bpy.data.lights.new("panel", "AREA")
    area.energy = 25.0
    area.size = 0.5
    o = bpy.data.objects.new("panel", area)
    o.location = (0.0, 0.0, 2.45)
    scene.collection.objects.link(o)

    cam = bpy.data.cameras.new("view")
    o = bpy.data.objects.new("view", cam)
    o.location = (-1.8, -1.8, 1.6)
    o.rotation_euler = (math.radians(80), 0, math.radians(-45))
    scene.collection.objects.link(o)
    scene.camera = o
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
    return scene


def glb_json(path):
    data = Path(path).read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20:20 + length])


def exr_channels(path):
    """Every channel of an EXR by its full name, as float32 arrays."""
    import OpenEXR
    import numpy as np
    return {name: np.asarray(ch.pixels) for name, ch in OpenEXR.File(str(path), separate_channels=True).parts[0].channels.items()}


def raysplat_processes(binary):
    """Process ids running `binary render` on a scene the add-on exported (from /proc: no pgrep
    needed; other tests may be rendering at the same time)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if len(argv) > 2 and argv[0] == binary.encode() and argv[1] == b"render" and b"/raysplat-" in argv[2] \
                and argv[2].endswith(b"/scene.glb"):
            found.append(int(pid))
    return found


def check_animation(bpy, c, scene, binary, work):
    """Render Animation (Ctrl+F12) of frames 1-3 at step 2, the camera walking: one export, one
    process for the range, and frames 1 and 3 equal to the CLI's on the exported file. Esc stops
    it. Returns the kept folder."""
    import numpy as np
    import raysplat_addon
    prefs = bpy.context.preferences.addons["raysplat_addon"].preferences
    cam = scene.camera
    scene.frame_set(1)
    cam.keyframe_insert("location", frame=1)
    cam.keyframe_insert("rotation_euler", frame=1)
    cam.location = (cam.location.x + 0.8, cam.location.y + 0.3, cam.location.z - 0.2)
    cam.rotation_euler.z += math.radians(15)
    cam.keyframe_insert("location", frame=3)
    cam.keyframe_insert("rotation_euler", frame=3)
    scene.frame_start, scene.frame_end, scene.frame_step = 1, 3, 2
    s = scene.raysplat
    s.passes, s.photons, s.seed, s.threads = 2, 20000, 3, 2
    prefs.keep_files = True
    scene.render.filepath = str(work / "anim_####")
    tmp_root = Path(tempfile.gettempdir())
    before = set(tmp_root.glob("raysplat-*"))
    bpy.ops.render.render(animation=True)
    kept = sorted(set(tmp_root.glob("raysplat-*")) - before)
    c.check(raysplat_addon.last_error is None, f"Render Animation succeeded ({raysplat_addon.last_error})")
    c.check(raysplat_addon.animation_job is None, "the animation's job ended with its last frame")
    if not c.check(len(kept) == 1 and (kept[0] / "scene.glb").is_file(), "Render Animation exported the scene once, for one process"):
        return kept
    glb = kept[0] / "scene.glb"
    frames = [1, 3]
    written = sorted(p.name for p in work.glob("anim_*.exr"))
    c.check(written == [f"anim_{f:04d}.exr" for f in frames], f"Blender wrote frames 1 and 3 of 1-3 at step 2 (got {written})")

    # The exported walk: only the camera moves (the photons are traced once), and where Blender puts it.
    doc = glb_json(glb)
    cam_node = next(i for i, n in enumerate(doc["nodes"]) if n.get("camera") is not None)
    moved = {ch["target"]["node"] for a in doc.get("animations", []) for ch in a["channels"]}
    c.check(moved == {cam_node}, f"the exported animation moves the camera alone (nodes {sorted(moved)})")
    out = subprocess.run([binary, "info", str(glb), "--frames", "1-3"], capture_output=True, text=True)
    poses = {p["frame"]: p["camera"] for p in map(json.loads, out.stdout.splitlines())} if out.returncode == 0 else {}
    err = 0.0
    for f in (1, 2, 3):
        scene.frame_set(f)
        t = cam.matrix_world.translation
        err = max(err, max(abs(a - b) for a, b in zip((t.x, t.z, -t.y), poses[f]["position"])) if f in poses else 1.0)
    c.check(err < 1e-5, f"the exported camera is Blender's at frames 1-3 (max diff {err:.2g} m)")

    # The CLI on the exported file, with the same settings: the same frames, to the bit.
    cmd = [binary, "render", str(glb), "-o", str(work / "cli_####.exr"), "--frames", "1-3", "--frame-step", "2", "--fps", "24",
           "--width", str(W), "--height", str(H), "--camera", "view", "--passes", "2", "--photons", "20000", "--seed", "3",
           "--threads", "1", "--quiet"]
    c.check(subprocess.run(cmd).returncode == 0, "raysplat render --frames 1-3 --frame-step 2 of the exported .glb")
    layer = scene.view_layers[0].name
    images = {}
    for f in frames:
        got, want = exr_channels(work / f"anim_{f:04d}.exr"), exr_channels(work / f"cli_{f:04d}.exr")
        images[f] = want["R"]
        same = all(np.array_equal(got.get(f"{layer}.Combined.{ch}"), want[ch]) for ch in "RGB") and \
            all(np.array_equal(got.get(f"{layer}.{name}.{ch}"), want[f"{name.lower()}.{ch}"])
                for name in ("Direct", "Indirect") for ch in "RGB")
        c.check(same, f"frame {f}: Combined, Direct and Indirect equal the CLI's frame to the bit")
    c.check(not np.array_equal(images[1], images[3]), "the camera moved: frames 1 and 3 differ")

    # Esc. Blender 4.2 crashes saving a frame that an engine left without a result unless its own
    # break flag is set, which a script cannot set: so the parts, without Blender's frame loop.
    # The range's process stopped while frame 1 renders: no frame file, exit 130.
    from raysplat_addon import runner
    stop_dir = work / "stopped_walk"
    stop_dir.mkdir()
    cmd = [binary, "render", str(glb), "-o", str(stop_dir / "f_####.exr"), "--frames", "1-3", "--width", "200",
           "--passes", "50", "--progress", "json"]
    frames = runner.FrameRun(cmd, lambda f: str(stop_dir / f"f_{f:04d}.exr"))
    events = []
    got = frames.wait_frame(1, events.append, lambda: any(e.get("event") == "progress" for e in events))
    c.check(got is None and frames.run.proc.returncode == 130 and list(stop_dir.iterdir()) == [],
            f"Esc while frame 1 renders: the process ends with 130 and writes no frame (got {frames.run.proc.returncode})")
    # A job Blender ends (render_cancel): its process stopped, its folder removed.
    job_dir = Path(tempfile.mkdtemp(prefix="raysplat-"))
    job = raysplat_addon.AnimationJob(("cancelled",), str(job_dir), False)
    job.frames = runner.FrameRun(cmd[:4] + [str(job_dir / "f_####.exr")] + cmd[5:],
                                 lambda f: str(job_dir / f"f_{f:04d}.exr"))
    raysplat_addon.animation_job = job
    for handler in bpy.app.handlers.render_cancel:
        handler(scene)
    c.check(raysplat_addon.animation_job is None and not job_dir.exists() and job.frames.run.proc.poll() is not None,
            "render_cancel stops the animation's process and removes its folder")
    c.check(not raysplat_processes(binary), "no raysplat process is left running")

    # A failing command stops Render Animation with its own one-line message.
    prefs.keep_files = False
    s.light_samples = 5000
    try:
        bpy.ops.render.render(animation=True)
    except RuntimeError:
        pass
    s.light_samples = 0
    e = raysplat_addon.last_error
    c.check(e is not None and "light-samples" in e and "\n" not in e and raysplat_addon.animation_job is None,
            f"a failing command ends Render Animation with its message in one line: {e}")
    return kept


def main():
    reexec_under_bpy_python(__file__)
    begun = begin_check("blender_addon_check")
    if isinstance(begun, int):
        return begun
    bpy, binary, c, work = begun
    import numpy as np

    # Install from the zip, as a user does; the user folder is a temporary one.
    os.environ["BLENDER_USER_SCRIPTS"] = str(work / "scripts")
    zip_path = make_zip(work / "raysplat_addon.zip")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.preferences.addon_install(filepath=str(zip_path), overwrite=True)
    bpy.ops.preferences.addon_enable(module="raysplat_addon")
    import raysplat_addon
    from raysplat_addon import runner
    c.check("RAYSPLAT" in {getattr(e, "bl_idname", "") for e in bpy.types.RenderEngine.__subclasses__()}, "the add-on installs and registers the engine")

    scene = build_scene(bpy)
    prefs = bpy.context.preferences.addons["raysplat_addon"].preferences
    prefs.binary = binary
    prefs.keep_files = True
    scene.render.engine = "RAYSPLAT"
    s = scene.raysplat
    s.passes, s.photons, s.seed, s.threads = 2, 20000, 3, 2
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = str(work / "blender.exr")
    tmp_root = Path(tempfile.gettempdir())
    before = set(tmp_root.glob("raysplat-*"))
    bpy.ops.render.render(write_still=True)
    kept = sorted(set(tmp_root.glob("raysplat-*")) - before)
    c.check(raysplat_addon.last_error is None, f"the render succeeded ({raysplat_addon.last_error})")
    if not c.check(len(kept) == 1 and (kept[0] / "scene.glb").is_file(), "the kept folder holds the exported scene.glb"):
        return FAIL
    glb = kept[0] / "scene.glb"

    # The same settings by hand.
    ref = work / "cli.exr"
    cmd = [binary, "render", str(glb), "-o", str(ref), "--width", str(W), "--height", str(H), "--camera", "view",
           "--passes", "2", "--photons", "20000", "--seed", "3", "--threads", "1", "--quiet"]
    c.check(subprocess.run(cmd).returncode == 0, "raysplat render of the exported .glb")
    got, want = exr_channels(work / "blender.exr"), exr_channels(ref)
    layer = scene.view_layers[0].name
    for ch in "RGB":
        a, b = got.get(f"{layer}.Combined.{ch}"), want[ch]
        c.check(a is not None and a.shape == b.shape and np.array_equal(a, b), f"Combined.{ch} equals the CLI's beauty to the bit")
    c.check(np.all(got[f"{layer}.Combined.A"] == 1.0), "Combined.A is 1")
    for name in ("Direct", "Indirect", "Caustic", "Emission", "Albedo"):
        for ch in "RGB":
            a = got.get(f"{layer}.{name}.{ch}")
            c.check(a is not None and np.array_equal(a, want[f"{name.lower()}.{ch}"]), f"pass {name}.{ch} holds the layer {name.lower()}")
    n = [want[f"normal.{ch}"] for ch in "RGB"]
    for ch, expect in zip("XYZ", (n[0], -n[2], n[1])):
        a = got.get(f"{layer}.Normal.{ch}")
        c.check(a is not None and np.array_equal(a, expect), f"pass Normal.{ch} holds the normal in Blender's axes")
    c.check(float(want["indirect.R"].mean()) > 0 and float(want["direct.R"].mean()) > 0, "direct and indirect light reach the room")

    # The area lamp: an emissive quad of radiance P / (π A).
    doc = glb_json(glb)
    quads = [m for m in doc.get("materials", []) if m.get("name", "").startswith("raysplat_area_")]
    if c.check(len(quads) == 1, "the area lamp went out as one emissive quad"):
        m = quads[0]
        radiance = max(m.get("emissiveFactor", [0, 0, 0])) * m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        c.check(abs(radiance - 25.0 / (math.pi * 0.25)) < 1e-3 * radiance, f"its radiance {radiance:.5g} is 25 W / (π · 0.25 m²)")
    c.check("raysplat_area_panel" not in bpy.data.objects, "the quad is gone from the Blender scene after the export")
    lamps = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    point = [l for l in lamps if l["type"] == "point"]
    c.check(len(point) == 1 and abs(point[0]["intensity"] - 40.0 / (4 * math.pi)) < 1e-4, "the point lamp exports as P / 4π W/sr")

    # Each lamp alone, its power end to end: Cycles against raysplat's path tracer through the add-on.
    lamps = [o for o in scene.objects if o.type == "LIGHT"]
    s.reference, s.spp, s.passes = True, 256, 1
    prefs.keep_files = False
    scene.cycles.samples, scene.cycles.use_denoising = 256, False
    scene.cycles.sample_clamp_indirect = scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.seed = 1
    # Every bounce: the room is white and closed (Cycles stops at 4 diffuse bounces by default).
    scene.cycles.max_bounces = scene.cycles.diffuse_bounces = 64
    for lamp in lamps:
        for o in lamps:
            o.hide_render = o is not lamp
        means = {}
        for engine in ("CYCLES", "RAYSPLAT"):
            scene.render.engine = engine
            scene.render.filepath = str(work / f"lamp_{lamp.name}_{engine}.exr")
            bpy.ops.render.render(write_still=True)
            px = exr_channels(scene.render.filepath)
            means[engine] = float(np.mean([px[f"{layer}.Combined.{ch}"] for ch in "RGB"]))
        ratio = means["RAYSPLAT"] / max(means["CYCLES"], 1e-12)
        c.check(abs(ratio - 1) < 0.04, f"{lamp.data.type.lower()} lamp '{lamp.name}': raysplat / Cycles image mean {ratio:.4f} (within 4 %)")
    for o in lamps:
        o.hide_render = False
    s.reference, s.spp, s.passes = False, 0, 2
    scene.render.engine = "RAYSPLAT"

    # Stopped after the first progress line: no process left, nothing staged.
    prefs.keep_files = False
    stop_dir = work / "stopped"
    stop_dir.mkdir()
    events = []
    cmd = [binary, "render", str(glb), "-o", str(stop_dir / "x.exr"), "--width", "200", "--passes", "50", "--progress", "json"]
    r = runner.Run(cmd)
    import time
    while r.proc.poll() is None and not any(e.get("event") == "progress" for e in r.take_events(0)):
        time.sleep(0.01)
    r.stop()
    events = r.take_events(0)
    c.check(r.proc.returncode == 128 + 2, f"SIGINT ends the command with 130 (got {r.proc.returncode})")
    c.check(list(stop_dir.iterdir()) == [], "the stopped command left no file")
    # Through the engine: a cancel asked at once.
    before = set(tmp_root.glob("raysplat-*"))
    engine_cls = raysplat_addon.RaysplatRenderEngine
    asked = engine_cls._stop_asked
    engine_cls._stop_asked = lambda self: True
    bpy.ops.render.render()
    engine_cls._stop_asked = asked
    c.check(raysplat_addon.last_stopped, "Esc stopped the render")
    c.check(set(tmp_root.glob("raysplat-*")) == before, "a cancelled render leaves no temporary folder")
    c.check(not raysplat_processes(binary), "no raysplat process is left running")

    # Errors: a missing binary, a failing command; one line each.
    def reported(word, what):
        try:
            bpy.ops.render.render()
        except RuntimeError:
            pass
        e = raysplat_addon.last_error
        c.check(e is not None and word in e and "\n" not in e, f"{what} is reported in one line: {e}")

    prefs.binary = str(work / "no-such-raysplat")
    reported("not found", "a missing binary")
    prefs.binary = binary
    s.light_samples = 5000
    reported("light-samples", "a failing command, with its own message,")
    s.light_samples = 0

    # The occlusion grid, lined up with the meshes.
    bpy.ops.wm.save_as_mainfile(filepath=str(work / "scene.blend"))
    result = bpy.ops.raysplat.show_grid()
    obj = bpy.data.objects.get("raysplat occlusion grid")
    if c.check("FINISHED" in result and obj is not None and obj.data.grids.load(), "Show occlusion grid adds a volume that loads"):
        import mathutils
        bpy.context.view_layer.update()
        meshes = [o for o in scene.objects if o.type == "MESH"]
        lo, hi = world_bounds_of_meshes(meshes)
        corners = np.array([list(obj.matrix_world @ mathutils.Vector(b)) for b in obj.bound_box])
        m = np.array(obj.data.grids["density"].matrix_object)
        voxel = float(np.linalg.norm(m[:3, 0]))
        leaf = 8 * voxel + 0.5 * voxel + 1e-4
        c.check(np.all(np.abs(corners.min(axis=0) - lo) <= leaf) and np.all(np.abs(corners.max(axis=0) - hi) <= leaf),
                f"the grid's bounds meet the meshes' within a leaf ({leaf:.3f} m)")
    kept += check_animation(bpy, c, scene, binary, work)
    for d in kept + [work]:
        shutil.rmtree(d, ignore_errors=True)
    return c.finish("blender_addon_check", "the add-on renders as the command does")


if __name__ == "__main__":
    exit_without_teardown(main())
