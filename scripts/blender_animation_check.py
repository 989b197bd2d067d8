#!/usr/bin/env python3
"""Checks raysplat's glTF animation against Blender (the pinned bpy) as the independent answer, to
1e-5 (metres, and unit vectors' components), at frames between keys as well as on them. raysplat's
side is `raysplat info FILE --frames A-B`: the camera and every node's world matrix at frame n,
time n / fps, placed as `render --frames` places them.

1. Cameras from Blender's own exporter. A scene built here in bpy has cameras keyed on location
   and rotation_quaternion with CONSTANT, LINEAR and BEZIER keys (exported, without sampling, as
   STEP, LINEAR and CUBICSPLINE samplers: checked in the file), and a camera parented to an empty
   keyed with LINEAR location and BEZIER rotation. At every frame from before the first key to
   past the last, raysplat's camera position, forward, up and vertical field of view equal
   Blender's (scene.frame_set(f), camera.matrix_world, Blender's Z up turned into glTF's Y up as
   the exporter turns it: (x, y, z) → (x, z, −y)).
   Where Blender and glTF differ by definition: Blender interpolates a LINEAR quaternion
   component by component (a normalized lerp), glTF by slerp. The two agree on the keys and
   half-way between them (by symmetry) and nowhere else, so the LINEAR camera's orientation is
   compared with Blender there, and between them with mathutils' slerp of Blender's key
   orientations; its position is compared with Blender at every frame. Blender's BEZIER keys
   become exact CUBICSPLINE keys because its automatic handles on evenly spaced keys sit a third
   of the way along the interval (checked), which is glTF's Hermite form. Blender 4.2's exporter
   writes a rotation's CUBICSPLINE tangent from the normalized quaternion (key + one frame of the
   handle's slope), which is Blender's curve only where that slope is orthogonal to the key (off
   by up to 1e-4 rad on the parented rig otherwise), so the BEZIER rotation keys here have flat
   handles, exported exactly; the locations keep Blender's automatic, sloped handles.

2. An interpolation scene like Khronos's InterpolationTest, written here as .gltf: nine cubes, one
   each for STEP, LINEAR and CUBICSPLINE on translation, rotation and scale. Blender's importer
   reads it into an empty scene; each cube's world matrix (turned into glTF's axes) at each frame
   equals raysplat's node matrix, and the cube's corners placed by it bound the triangles raysplat
   renders at that frame (info's "objects", flattened at the pose). Where Blender's importer
   cannot be the answer by definition: LINEAR rotations are its normalized lerp (compared on keys and half-way, and elsewhere with
   mathutils' slerp of the keys), and Blender 4.2's importer drops CUBICSPLINE tangents (its
   keys get automatic handles), so CUBICSPLINE cubes are compared with Blender on the keys and
   between them with glTF 2.0 Appendix C's Hermite spline evaluated here in Python.

3. The add-on's export for Render Animation (every object's action sampled at each frame) of a
   camera keyed on location and Euler rotation at 30 / 1.001 fps: with --fps fps × fps_base, the
   time the exporter gives frame n, raysplat's camera is Blender's at every frame.

Exit status: 0 PASS, 1 FAIL, 77 skipped (no bpy; with RAYSPLAT_REQUIRE_BLENDER=1 a failure).
Needs $RAYSPLAT (the binary)."""

import base64
import json
import math
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blender_check import begin_check, exit_without_teardown, reexec_under_bpy_python  # noqa: E402

TOL = 1e-5
FPS = 24
W, H = 64, 48


def say(msg):
    print(f"blender_animation_check: {msg}", flush=True)


def to_gltf(v):
    """A Blender (Z up) vector in glTF's axes (Y up), as the exporter with export_yup turns it."""
    return [v[0], v[2], -v[1]]


def glb_json(path):
    data = Path(path).read_bytes()
    return json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])


def poses(binary, scene_file, first, last, camera=None):
    """raysplat's poses: {frame: the JSON object info --frames prints}."""
    cmd = [binary, "info", str(scene_file), "--frames", f"{first}-{last}", "--fps", str(FPS)]
    if camera:
        cmd += ["--camera", camera]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: {r.stderr.strip()}")
    return {p["frame"]: p for p in map(json.loads, r.stdout.splitlines())}


def max_diff(a, b):
    return max(abs(x - y) for x, y in zip(a, b))


# 1. Cameras through Blender's exporter --------------------------------------------------------

CAMERA_KEYS = [  # frame, location, rotation (axis, degrees) applied after a tilt (axis, degrees)
    (1, (4.0, -3.0, 1.5), ((0, 0, 1), 0.0), ((1, 0, 0), 80.0)),
    (9, (2.0, -5.0, 2.5), ((0.3, 0.2, 1.0), 60.0), ((1, 0, 0), 80.0)),
    (17, (-1.0, -4.0, 1.0), ((0.1, -0.3, 1.0), -40.0), ((1, 0, 0), 70.0)),
]
FIRST, LAST = 0, 19  # before the first key to past the last


def build_cameras(bpy):
    from mathutils import Quaternion
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
    bpy.ops.mesh.primitive_cube_add(location=(0, 0, 0))  # something to render

    def keyed(obj, keys, interpolation):
        obj.rotation_mode = "QUATERNION"
        for frame, loc, (axis, angle), (tilt_axis, tilt) in keys:
            obj.location = loc
            obj.rotation_quaternion = Quaternion(axis, math.radians(angle)) @ Quaternion(tilt_axis, math.radians(tilt))
            obj.keyframe_insert("location", frame=frame)
            obj.keyframe_insert("rotation_quaternion", frame=frame)
        step = (keys[1][0] - keys[0][0]) / 3.0  # evenly spaced keys: handles a third of the interval along
        for fc in obj.animation_data.action.fcurves:
            for k in fc.keyframe_points:
                k.interpolation = interpolation(fc.data_path) if callable(interpolation) else interpolation
                if k.interpolation == "BEZIER" and fc.data_path == "rotation_quaternion":
                    # Flat: the exporter writes a rotation's tangent from a normalized control point,
                    # Blender's curve only where the slope is orthogonal to the key (a zero slope is).
                    k.handle_left_type = k.handle_right_type = "FREE"
                    k.handle_left = (k.co[0] - step, k.co[1])
                    k.handle_right = (k.co[0] + step, k.co[1])

    cameras = {}
    for name, interpolation in (("step", "CONSTANT"), ("linear", "LINEAR"), ("bezier", "BEZIER")):
        cam = bpy.data.objects.new(name, bpy.data.cameras.new(name))
        scene.collection.objects.link(cam)
        keyed(cam, CAMERA_KEYS, interpolation)
        cameras[name] = cam
    # A camera on an animated empty: the rig moves LINEAR and turns BEZIER; the camera sits still on it.
    rig = bpy.data.objects.new("rig", None)
    scene.collection.objects.link(rig)
    keyed(rig, [(f, (0.5 * l[0], 0.5 * l[1], l[2]), r, ((1, 0, 0), 0.0)) for f, l, r, _ in CAMERA_KEYS],
          lambda path: "LINEAR" if path == "location" else "BEZIER")
    child = bpy.data.objects.new("child", bpy.data.cameras.new("child"))
    scene.collection.objects.link(child)
    child.parent = rig
    child.matrix_parent_inverse.identity()
    child.location = (1.0, -2.0, 0.5)
    child.rotation_mode = "QUATERNION"
    child.rotation_quaternion = Quaternion((1, 0.2, 0), math.radians(75))
    cameras["child"] = child
    scene.camera = cameras["step"]
    return scene, cameras


def export(bpy, path):
    # Keys as keys: no sampling (sampling bakes a key a frame, LINEAR between them, and would not
    # test the interpolation); every object's action merged into one glTF animation.
    bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", export_cameras=True, export_yup=True,
                              export_animations=True, export_force_sampling=False,
                              export_animation_mode="ACTIVE_ACTIONS")


def check_cameras(bpy, c, binary, work):
    scene, cameras = build_cameras(bpy)
    handles = [(k.handle_right[0] - k.co[0], k.handle_right[1] - k.co[1]) for fc in cameras["bezier"].animation_data.action.fcurves
               for k in fc.keyframe_points if fc.data_path == "location"]
    c.check(all(abs(h[0] - 8.0 / 3.0) < 1e-4 for h in handles) and any(abs(h[1]) > 0.1 for h in handles),
            "Blender's automatic BEZIER location handles sit a third of the key interval along (glTF's Hermite form), not flat")
    glb = work / "cameras.glb"
    export(bpy, glb)
    doc = glb_json(glb)
    node_of = {n.get("name"): i for i, n in enumerate(doc["nodes"])}
    kinds = {}
    for anim in doc.get("animations", []):
        for ch in anim["channels"]:
            kinds[(ch["target"]["node"], ch["target"]["path"])] = anim["samplers"][ch["sampler"]]["interpolation"]
    for name, want in (("step", "STEP"), ("linear", "LINEAR"), ("bezier", "CUBICSPLINE")):
        got = {kinds.get((node_of.get(name), p)) for p in ("translation", "rotation")}
        c.check(got == {want}, f"camera '{name}': the exporter kept its keys as {want} samplers (got {sorted(map(str, got))})")
    c.check(doc["nodes"][node_of["rig"]].get("children") == [node_of["child"]] and
            kinds.get((node_of["rig"], "rotation")) == "CUBICSPLINE", "camera 'child' is the rig's child; the rig turns by CUBICSPLINE")

    keys = [k[0] for k in CAMERA_KEYS]
    halves = [(a + b) // 2 for a, b in zip(keys, keys[1:])]
    for name, cam in cameras.items():
        got = poses(binary, glb, FIRST, LAST, camera=name)
        # Blender's orientation at the keys, for the slerp between them.
        key_rot = {}
        for f in keys:
            scene.frame_set(f)
            key_rot[f] = cam.matrix_world.to_quaternion()
        err_pos = err_dir = err_fov = 0.0
        compared = []
        for f in range(FIRST, LAST + 1):
            scene.frame_set(f)
            m = cam.matrix_world.copy()
            p = got[f]["camera"]
            err_pos = max(err_pos, max_diff(to_gltf(m.translation), p["position"]))
            rot = m.to_3x3().normalized()
            if name == "linear" and keys[0] < f < keys[-1] and f not in keys + halves:
                # Between keys and off the middle: glTF's slerp of Blender's key orientations.
                a = max(k for k in keys if k <= f)
                b = min(k for k in keys if k > f)
                rot = key_rot[a].slerp(key_rot[b], (f - a) / (b - a)).to_matrix()
            else:
                compared.append(f)
            forward, up = -rot.col[2], rot.col[1]
            err_dir = max(err_dir, max_diff(to_gltf(forward), p["forward"]), max_diff(to_gltf(up), p["up"]))
            # Blender's vertical field of view: its angle spans the render's width (sensor fit AUTO, W > H).
            yfov = 2 * math.atan(math.tan(cam.data.angle / 2) * H / W)
            err_fov = max(err_fov, abs(yfov - p["yfov"]))
        c.check(err_pos < TOL, f"camera '{name}': position equals Blender's at frames {FIRST}-{LAST} (max diff {err_pos:.2g} m)")
        where = f"frames {FIRST}-{LAST}" if len(compared) == LAST - FIRST + 1 else \
            f"frames {', '.join(map(str, compared))} (slerp of Blender's keys elsewhere)"
        c.check(err_dir < TOL, f"camera '{name}': forward and up equal Blender's at {where} (max diff {err_dir:.2g})")
        c.check(err_fov < TOL, f"camera '{name}': yfov equals Blender's (max diff {err_fov:.2g} rad)")


# 2. An InterpolationTest-like file through Blender's importer ---------------------------------

KEY_TIMES = [0.0, 0.5, 1.0, 1.5]  # frames 0, 12, 24, 36 at 24 fps


def axis_angle(axis, degrees):
    n = math.sqrt(sum(a * a for a in axis))
    s = math.sin(math.radians(degrees) / 2)
    return [axis[0] / n * s, axis[1] / n * s, axis[2] / n * s, math.cos(math.radians(degrees) / 2)]


KEY_VALUES = {  # glTF's components: translation and scale xyz, rotation a quaternion's xyzw
    "translation": [[0, 0, 0], [0, 1.0, 0.2], [0.4, 0.3, -0.5], [-0.2, 1.2, 0.1]],
    "rotation": [axis_angle((0, 1, 0), 0), axis_angle((0, 1, 0), 90), axis_angle((1, 1, 0), 160), axis_angle((0.2, 1, -0.5), 40)],
    "scale": [[1, 1, 1], [2.0, 0.5, 1.0], [0.7, 1.5, 2.2], [1.2, 1.2, 0.4]],
}
TANGENTS = {  # CUBICSPLINE: each key's in- and out-tangent (units a second)
    "translation": [([0, 0, 0], [1.0, 2.0, 0.5]), ([0.5, -1.0, 0.2], [0.3, 1.0, -0.4]),
                    ([-1.0, 0.2, 0.3], [0.4, -0.2, 1.0]), ([1.0, 0.5, -0.5], [0, 0, 0])],
    "rotation": [([0, 0, 0, 0], [0.1, 0.8, 0.0, -0.2]), ([0.2, 0.3, -0.1, 0.1], [0.0, -0.5, 0.3, 0.2]),
                 ([0.4, 0.1, 0.2, -0.3], [-0.2, 0.2, 0.1, 0.0]), ([0.1, -0.3, 0.2, 0.1], [0, 0, 0, 0])],
    "scale": [([0, 0, 0], [2.0, -1.0, 0.5]), ([1.0, 0.5, -1.0], [-0.5, 1.0, 2.0]),
              ([0.3, -0.6, 0.2], [1.0, 0.2, -1.5]), ([0.5, 0.5, 0.5], [0, 0, 0])],
}
INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")
PATHS = ("translation", "rotation", "scale")


def cube_mesh():
    """A unit cube's 8 corners and 12 triangles."""
    corners = [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return corners, [i for a, b, c_, d in quads for i in (a, b, c_, a, c_, d)]


def write_interpolation_gltf(path):
    """Nine cubes in a row of threes; cube (path, interpolation) named e.g. 'rotation_LINEAR'."""
    blob = bytearray()
    accessors, views = [], []

    def add(values, kind, component=5126, fmt="f", extra=None):
        offset = len(blob)
        flat = [v for item in values for v in (item if isinstance(item, list) else [item])]
        blob.extend(struct.pack(f"<{len(flat)}{fmt}", *flat))
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(flat) * 4})
        acc = {"bufferView": len(views) - 1, "componentType": component, "count": len(values), "type": kind}
        accessors.append(dict(acc, **(extra or {})))
        return len(accessors) - 1

    corners, indices = cube_mesh()
    pos = add(corners, "VEC3", extra={"min": [-0.5] * 3, "max": [0.5] * 3})
    idx = add(indices, "SCALAR", component=5125, fmt="I")
    times = add(KEY_TIMES, "SCALAR", extra={"min": [KEY_TIMES[0]], "max": [KEY_TIMES[-1]]})
    nodes, samplers, channels = [], [], []
    for row, p in enumerate(PATHS):
        for col, interp in enumerate(INTERPOLATIONS):
            base = [3.0 * col, 0.0, -3.0 * row]
            node = {"name": f"{p}_{interp}", "mesh": 0, "translation": base}
            values = KEY_VALUES[p]
            if p == "translation":
                values = [[b + v for b, v in zip(base, key)] for key in values]
            if interp == "CUBICSPLINE":
                values = [x for (tin, tout), v in zip(TANGENTS[p], values) for x in (tin, v, tout)]
            kind = "VEC4" if p == "rotation" else "VEC3"
            samplers.append({"input": times, "output": add(values, kind), "interpolation": interp})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": len(nodes), "path": p}})
            nodes.append(node)
    doc = {
        "asset": {"version": "2.0", "generator": "raysplat blender_animation_check.py"},
        "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
        "animations": [{"name": "interpolation", "samplers": samplers, "channels": channels}],
    }
    Path(path).write_text(json.dumps(doc))
    return doc


def hermite(path, t):
    """glTF 2.0 Appendix C's cubic spline at time t, from the keys above; rotations normalized."""
    if t <= KEY_TIMES[0] or t >= KEY_TIMES[-1]:
        v = KEY_VALUES[path][0 if t <= KEY_TIMES[0] else -1]
    else:
        k = max(i for i, kt in enumerate(KEY_TIMES) if kt <= t)
        td = KEY_TIMES[k + 1] - KEY_TIMES[k]
        s = (t - KEY_TIMES[k]) / td
        p0, p1 = KEY_VALUES[path][k], KEY_VALUES[path][k + 1]
        b0, a1 = TANGENTS[path][k][1], TANGENTS[path][k + 1][0]
        v = [(2 * s**3 - 3 * s**2 + 1) * p0[i] + td * (s**3 - 2 * s**2 + s) * b0[i] + (-2 * s**3 + 3 * s**2) * p1[i]
             + td * (s**3 - s**2) * a1[i] for i in range(len(p0))]
    if path == "rotation":
        n = math.sqrt(sum(x * x for x in v))
        v = [x / n for x in v]
    return v


def trs_matrix(t, q, s):
    """A glTF node's matrix from translation, quaternion xyzw and scale (mathutils, row-major)."""
    from mathutils import Matrix, Quaternion, Vector
    return Matrix.Translation(Vector(t)) @ Quaternion((q[3], q[0], q[1], q[2])).to_matrix().to_4x4() @ \
        Matrix.Diagonal(Vector((*s, 1.0)))


def check_interpolation(bpy, c, binary, work):
    from mathutils import Matrix, Vector
    gltf = work / "interpolation.gltf"
    doc = write_interpolation_gltf(gltf)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    bpy.ops.import_scene.gltf(filepath=str(gltf))
    last = round(KEY_TIMES[-1] * FPS) + 3
    got = poses(binary, gltf, 0, last)
    # glTF's axes from Blender's: the importer's change of basis, (x, y, z)_glTF = (x, z, −y)_Blender.
    to_g = Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0), (0, 0, 0, 1)))
    key_frames = [round(t * FPS) for t in KEY_TIMES]
    halves = [(a + b) // 2 for a, b in zip(key_frames, key_frames[1:])]
    for i, node in enumerate(doc["nodes"]):
        path, interp = node["name"].split("_")
        obj = bpy.data.objects.get(node["name"])
        if not c.check(obj is not None, f"Blender imported cube '{node['name']}'"):
            continue
        key_rot = {}
        for f in key_frames:
            scene.frame_set(f)
            key_rot[f] = obj.matrix_world.to_quaternion()
        err, err_box, with_blender, other = 0.0, 0.0, [], []
        for f in range(0, last + 1):
            scene.frame_set(f)
            want = to_g @ obj.matrix_world @ to_g.inverted()
            between = key_frames[0] < f < key_frames[-1] and f not in key_frames
            if interp == "CUBICSPLINE" and between:
                # Blender's importer drops the tangents: glTF's own Hermite, evaluated here.
                t = f / FPS
                trs = {"translation": node["translation"], "rotation": [0, 0, 0, 1], "scale": [1, 1, 1]}
                trs[path] = hermite(path, t) if path != "translation" else \
                    [b + v for b, v in zip(node["translation"], hermite(path, t))]
                want = trs_matrix(trs["translation"], trs["rotation"], trs["scale"])
                other.append(f)
            elif interp == "LINEAR" and path == "rotation" and between and f not in halves:
                # Blender lerps quaternion components; glTF slerps: mathutils' slerp of the keys.
                a = max(k for k in key_frames if k <= f)
                b = min(k for k in key_frames if k > f)
                q = key_rot[a].slerp(key_rot[b], (f - a) / (b - a))
                want = to_g @ (Matrix.Translation(obj.matrix_world.translation) @ q.to_matrix().to_4x4()) @ to_g.inverted()
                other.append(f)
            else:
                with_blender.append(f)
            m = got[f]["nodes"][i]["world"]  # column-major
            err = max(err, max(abs(want[r][col] - m[4 * col + r]) for r in range(4) for col in range(4)))
            # The triangles a render of the frame uses: the cube's corners placed by `want`.
            corners = [want @ Vector((*v, 1.0)) for v in cube_mesh()[0]]
            box = next(o for o in got[f]["objects"] if f"(node {i} " in o["name"])
            lo = [min(v[k] for v in corners) for k in range(3)]
            hi = [max(v[k] for v in corners) for k in range(3)]
            err_box = max(err_box, max_diff(lo, box["lo"]), max_diff(hi, box["hi"]))
        how = f"Blender's importer at frames {with_blender[0]}-{with_blender[-1]}" if not other else \
            f"Blender's importer at frames {', '.join(map(str, with_blender))}, " + \
            ("glTF's Hermite" if interp == "CUBICSPLINE" else "slerp of Blender's keys") + " between"
        c.check(err < TOL and err_box < TOL, f"cube '{node['name']}': raysplat's world matrix and its triangles' bounds equal "
                                             f"{how} (max diff {err:.2g}, bounds {err_box:.2g} m)")


# 3. The add-on's export for Render Animation --------------------------------------------------

def check_addon_export(bpy, c, binary, work):
    """The add-on's walkthrough export (export.ANIMATION: the actions sampled at every frame) of a
    camera keyed on location and Euler rotation at 30 / 1.001 fps: at --fps fps × fps_base, the
    exporter's timing, raysplat's camera is Blender's at every frame; at fps / fps_base, the
    scene's real rate, it is not (so the check can tell)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "blender"))
    from raysplat_addon import export as addon_export
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 30, 1.001
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
    bpy.ops.mesh.primitive_cube_add()
    cam = bpy.data.objects.new("walker", bpy.data.cameras.new("walker"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    for frame, loc, rot in ((1, (3, -4, 1.6), (80, 0, 30)), (6, (2, -2, 1.7), (85, 5, 60)), (12, (0, -1, 1.5), (75, -5, 100))):
        cam.location, cam.rotation_euler = loc, [math.radians(a) for a in rot]
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    scene.frame_start, scene.frame_end = 1, 12
    glb = work / "addon_walk.glb"
    bpy.ops.export_scene.gltf(filepath=str(glb), export_format="GLB", export_cameras=True, export_yup=True,
                              **addon_export.ANIMATION)

    def worst(fps):
        r = subprocess.run([binary, "info", str(glb), "--frames", "1-12", "--fps", f"{fps:.9g}"], capture_output=True, text=True)
        if r.returncode != 0:
            return float("inf")
        got = {p["frame"]: p["camera"] for p in map(json.loads, r.stdout.splitlines())}
        err = 0.0
        for f in range(1, 13):
            scene.frame_set(f)
            m = cam.matrix_world
            err = max(err, max_diff(to_gltf(m.translation), got[f]["position"]),
                      max_diff(to_gltf(-m.col[2].xyz.normalized()), got[f]["forward"]))
        return err

    r = scene.render
    right, naive = worst(r.fps * r.fps_base), worst(r.fps / r.fps_base)
    c.check(right < TOL, f"the add-on's export at 30 / 1.001 fps: --fps fps × fps_base places the camera as Blender at "
                         f"frames 1-12 (max diff {right:.2g})")
    c.check(naive > 100 * TOL, f"... and --fps fps / fps_base would not (max diff {naive:.2g})")


def main():
    reexec_under_bpy_python(__file__)
    begun = begin_check("blender_animation_check")
    if isinstance(begun, int):
        return begun
    bpy, binary, c, work = begun
    try:
        check_cameras(bpy, c, binary, work)
        check_interpolation(bpy, c, binary, work)
        check_addon_export(bpy, c, binary, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return c.finish("blender_animation_check", f"cameras and nodes equal Blender's to {TOL:g}")


if __name__ == "__main__":
    exit_without_teardown(main())
