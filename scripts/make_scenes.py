#!/usr/bin/env python3
"""Generate the raysplat test scenes (glTF 2.0) into OUTDIR.

  cornell_box.gltf + .bin  Cornell box, ceiling area light; external .bin
                           buffer (the renderer's default scene)
  glossy_box.glb           same room with a glass sphere and a glossy gold
                           icosahedron; single binary GLB file
  direct_light.gltf        ground plane, three occluders, one point light;
                           buffer embedded as a base64 data URI
  two_rooms_sealed.gltf    two 4 x 2.5 x 3 m rooms sharing an 8 cm wall, a
                           ceiling light in one, the camera in the other:
                           nothing connects them, so the image is black
  two_rooms_gap.gltf       the same rooms joined by a 25 cm wide opening in
                           the shared wall: light reaches the camera's room
                           only through it
  caustic_pool.gltf        a closed room split at mid-height by a sheet of
                           wavy glass (a pool's surface), a small light above
                           it, the camera below: everything it sees is lit
                           through the glass (caustics)
  daylight.gltf + .bin     a furnished room lit by the sun and a uniform sky
                           (the scene's extras) through a 1 m² window with a
                           blind, the opening marked as a light portal, and a
                           potted plant of alpha-masked leaves in the sun
  textured_room.gltf + .bin  a closed room whose floor and walls carry normal,
                           metallic-roughness and base colour textures, an
                           emissive screen showing an image, a vertex-coloured
                           ball and alpha-masked leaves (scripts/textured_room.py)

Usage:  python3 scripts/make_scenes.py [outdir]

OUTDIR defaults to data/ in the repository root, resolved from this script's
location (the working directory does not matter). Stdlib only. The output is
deterministic -- same bytes on every run (fixed object order, sorted JSON
keys, no timestamps) -- so regenerating gives no spurious diffs.

Conventions (design doc): metres, right-handed, +Y up; counter-clockwise
winding is the front face; wall normals point into the room; emitters emit
from their front face only; cameras look down their node's local -Z.
"""

import base64
import json
import math
import os
import re
import struct
import sys

GENERATOR = "raysplat make_scenes.py"
FLOAT, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
TRIANGLES = 4

# --------------------------------------------------------------------------
# Small vector / quaternion helpers (tuples of floats)


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def mul(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def normalize(a):
    return mul(a, 1.0 / math.sqrt(dot(a, a)))


def f32(x):
    """Shortest decimal that rounds to the same float32 as x (tidy JSON)."""
    want = struct.pack("<f", x)
    for digits in range(6, 10):
        y = float("%.*g" % (digits, struct.unpack("<f", want)[0]))
        if struct.pack("<f", y) == want:
            return y + 0.0  # turns -0.0 into 0.0
    return struct.unpack("<f", want)[0]


def vec(v):
    return [f32(x) for x in v]


def quat_axis_angle(axis, angle):
    s = math.sin(angle / 2.0)
    return tuple(c * s for c in normalize(axis)) + (math.cos(angle / 2.0),)


def quat_between(a, b):
    """Rotation taking unit vector a onto unit vector b (not antiparallel)."""
    angle = math.acos(max(-1.0, min(1.0, dot(a, b))))
    return quat_axis_angle(cross(a, b), angle)


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def look_at(eye, target):
    """Node rotation pointing a glTF camera (looks down -Z, +Y up) from eye
    at target without roll: yaw about +Y applied after pitch about +X."""
    dx, dy, dz = sub(target, eye)
    yaw = math.atan2(-dx, -dz)
    pitch = math.atan2(dy, math.hypot(dx, dz))
    return quat_mul(quat_axis_angle((0.0, 1.0, 0.0), yaw),
                    quat_axis_angle((1.0, 0.0, 0.0), pitch))


# --------------------------------------------------------------------------
# Geometry: (positions, normals, indices) triples


def rect(center, u, v, normal):
    """Flat quad center +- u +- v, wound counter-clockwise around normal."""
    if dot(cross(u, v), normal) < 0:
        u, v = v, u
    n = normalize(normal)
    pos = [sub(sub(center, u), v), sub(add(center, u), v),
           add(add(center, u), v), add(sub(center, u), v)]
    return pos, [n] * 4, [0, 1, 2, 0, 2, 3]


def merge(*parts):
    pos, nrm, idx = [], [], []
    for p, n, i in parts:
        idx += [len(pos) + k for k in i]
        pos += p
        nrm += n
    return pos, nrm, idx


def unit_cube():
    """Cube [-0.5, 0.5]^3, outward flat normals, 24 vertices."""
    faces = []
    for axis in range(3):
        e = [tuple(float(k == (axis + j) % 3) for k in range(3))
             for j in range(3)]
        for sign in (1.0, -1.0):
            faces.append(rect(mul(e[0], 0.5 * sign), mul(e[1], 0.5),
                              mul(e[2], 0.5), mul(e[0], sign)))
    return merge(*faces)


def uv_sphere(radius, segments=40, rings=20):
    """UV sphere with smooth outward normals (seam vertices duplicated)."""
    pos, nrm, idx = [], [], []
    for r in range(rings + 1):
        th = math.pi * r / rings
        for s in range(segments + 1):
            ph = 2.0 * math.pi * s / segments
            n = (math.sin(th) * math.cos(ph), math.cos(th),
                 -math.sin(th) * math.sin(ph))
            n = normalize(tuple(0.0 if abs(c) < 1e-12 else c for c in n))
            nrm.append(n)
            pos.append(mul(n, radius))
    row = segments + 1
    for r in range(rings):
        for s in range(segments):
            a, d = r * row + s, r * row + s + 1
            b, c = a + row, d + row
            if r != rings - 1:
                idx += [a, b, c]      # skipped at the south pole (degenerate)
            if r != 0:
                idx += [a, c, d]      # skipped at the north pole (degenerate)
    return pos, nrm, idx


def icosahedron():
    """Unit-circumradius icosahedron, flat shaded (3 vertices per face)."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [normalize(v) for v in [
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0),
        (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
        (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
             (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
             (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
             (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    pos, nrm = [], []
    for f in faces:
        a, b, c = (verts[i] for i in f)
        n = normalize(cross(sub(b, a), sub(c, a)))
        if dot(n, a) < 0:  # keep counter-clockwise seen from outside
            b, c, n = c, b, mul(n, -1.0)
        pos += [a, b, c]
        nrm += [n] * 3
    return pos, nrm, list(range(len(pos)))


# --------------------------------------------------------------------------
# glTF document builder


class GltfBuilder:
    """Accumulates one binary buffer plus the glTF objects that refer to it."""

    def __init__(self, scene_name):
        self.doc = {
            "asset": {"version": "2.0", "generator": GENERATOR},
            "scene": 0,
            "scenes": [{"name": scene_name, "nodes": []}],
            "nodes": [], "meshes": [], "materials": [], "cameras": [],
            "accessors": [], "bufferViews": [], "buffers": [],
        }
        self.bin = bytearray()
        self.extensions = set()
        self.lights = []

    def _append(self, key, obj):
        self.doc[key].append(obj)
        return len(self.doc[key]) - 1

    def _view(self, data, target):
        self.bin += b"\0" * (-len(self.bin) % 4)  # 4-byte aligned views
        view = {"buffer": 0, "byteOffset": len(self.bin),
                "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.bin += data
        return self._append("bufferViews", view)

    def _vec3_accessor(self, values, with_bounds):
        flat = [c + 0.0 for v in values for c in v]
        data = struct.pack("<%df" % len(flat), *flat)
        acc = {"bufferView": self._view(data, ARRAY_BUFFER),
               "componentType": FLOAT, "count": len(values), "type": "VEC3"}
        if with_bounds:  # bounds of the float32 values actually stored
            stored = struct.unpack("<%df" % len(flat), data)
            acc["min"] = [f32(min(stored[k::3])) for k in range(3)]
            acc["max"] = [f32(max(stored[k::3])) for k in range(3)]
        return self._append("accessors", acc)

    def _index_accessor(self, indices, vertex_count):
        comp, fmt = ((UNSIGNED_SHORT, "H") if vertex_count <= 65535
                     else (UNSIGNED_INT, "I"))
        data = struct.pack("<%d%s" % (len(indices), fmt), *indices)
        acc = {"bufferView": self._view(data, ELEMENT_ARRAY_BUFFER),
               "componentType": comp, "count": len(indices), "type": "SCALAR"}
        return self._append("accessors", acc)

    def material(self, name, base, metallic=0.0, roughness=1.0, emissive=None,
                 strength=None, transmission=None, ior=None):
        mat = {"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": vec(tuple(base) + (1.0,)),
            "metallicFactor": f32(metallic),
            "roughnessFactor": f32(roughness)}}
        ext = {}
        if emissive is not None:
            mat["emissiveFactor"] = vec(emissive)
            if strength is not None:
                ext["KHR_materials_emissive_strength"] = {
                    "emissiveStrength": f32(strength)}
        if transmission is not None:
            ext["KHR_materials_transmission"] = {
                "transmissionFactor": f32(transmission)}
        if ior is not None:
            ext["KHR_materials_ior"] = {"ior": f32(ior)}
        if ext:
            mat["extensions"] = ext
            self.extensions.update(ext)
        return self._append("materials", mat)

    def mesh(self, name, geom, material, uvs=None, colors=None):
        """A mesh of one primitive; `colors`: linear RGB a vertex (COLOR_0)."""
        pos, nrm, idx = geom
        prim = {"attributes": {"POSITION": self._vec3_accessor(pos, True),
                               "NORMAL": self._vec3_accessor(nrm, False)},
                "indices": self._index_accessor(idx, len(pos)),
                "material": material, "mode": TRIANGLES}
        if colors is not None:
            prim["attributes"]["COLOR_0"] = self._vec3_accessor(colors, False)
        if uvs is not None:
            flat = [c + 0.0 for uv in uvs for c in uv]
            data = struct.pack("<%df" % len(flat), *flat)
            prim["attributes"]["TEXCOORD_0"] = self._append("accessors", {
                "bufferView": self._view(data, ARRAY_BUFFER),
                "componentType": FLOAT, "count": len(uvs), "type": "VEC2"})
        return self._append("meshes", {"name": name, "primitives": [prim]})

    def png_texture(self, name, png):
        """A texture of a PNG held in the buffer."""
        self.bin += b"\0" * (-len(self.bin) % 4)
        view = self._append("bufferViews", {"buffer": 0, "byteOffset": len(self.bin),
                                            "byteLength": len(png)})
        self.bin += png
        image = self._append_list("images", {"name": name, "bufferView": view,
                                             "mimeType": "image/png"})
        return self._append_list("textures", {"name": name, "source": image})

    def animation(self, name, channels):
        """An animation of (node, path, times, values) channels, LINEAR, one key a
        frame as Blender's exporter bakes them; values are xyz or xyzw tuples."""
        samplers, targets = [], []
        for node, path, times, values in channels:
            t = struct.pack("<%df" % len(times), *times)
            time_acc = self._append("accessors", {
                "bufferView": self._view(t, None), "componentType": FLOAT,
                "count": len(times), "type": "SCALAR",
                "min": [f32(min(times))], "max": [f32(max(times))]})
            flat = [c + 0.0 for v in values for c in v]
            out = self._append("accessors", {
                "bufferView": self._view(struct.pack("<%df" % len(flat), *flat), None),
                "componentType": FLOAT, "count": len(values),
                "type": "VEC%d" % len(values[0])})
            samplers.append({"input": time_acc, "output": out, "interpolation": "LINEAR"})
            targets.append({"sampler": len(samplers) - 1,
                            "target": {"node": node, "path": path}})
        return self._append_list("animations", {"name": name, "channels": targets,
                                                "samplers": samplers})

    def _append_list(self, key, obj):
        self.doc.setdefault(key, []).append(obj)
        return len(self.doc[key]) - 1

    def directional_light(self, name, direction, intensity, color=(1.0, 1.0, 1.0)):
        """A sun shining along `direction` (glTF lights shine down their node's -Z)."""
        self.extensions.add("KHR_lights_punctual")
        self.lights.append({"name": name, "type": "directional",
                            "color": vec(color), "intensity": f32(intensity)})
        d = normalize(direction)
        return self.node(name, r=quat_between((0.0, 0.0, -1.0), d), extensions={
            "KHR_lights_punctual": {"light": len(self.lights) - 1}})

    def node(self, name, parent=None, mesh=None, t=None, r=None, s=None,
             **fields):
        node = {"name": name}
        if mesh is not None:
            node["mesh"] = mesh
        if t is not None:
            node["translation"] = vec(t)
        if r is not None:
            node["rotation"] = vec(r)
        if s is not None:
            node["scale"] = vec(s)
        node.update(fields)
        index = self._append("nodes", node)
        if parent is None:
            self.doc["scenes"][0]["nodes"].append(index)
        else:
            self.doc["nodes"][parent].setdefault("children", []).append(index)
        return index

    def camera(self, name, eye, target, yfov, aspect, znear=0.05, zfar=100.0):
        persp = {"yfov": f32(yfov), "znear": f32(znear), "zfar": f32(zfar),
                 "aspectRatio": f32(aspect)}
        cam = self._append("cameras", {"name": name, "type": "perspective",
                                       "perspective": persp})
        return self.node(name, camera=cam, t=eye, r=look_at(eye, target))

    def point_light(self, name, position, intensity, color=(1.0, 1.0, 1.0)):
        self.extensions.add("KHR_lights_punctual")
        self.lights.append({"name": name, "type": "point",
                            "color": vec(color), "intensity": f32(intensity)})
        return self.node(name, t=position, extensions={
            "KHR_lights_punctual": {"light": len(self.lights) - 1}})

    def _finish(self, uri):
        self.bin += b"\0" * (-len(self.bin) % 4)
        doc = dict(self.doc)
        buf = {"byteLength": len(self.bin)}
        if uri is not None:
            buf["uri"] = uri
        doc["buffers"] = [buf]
        if self.lights:
            doc["extensions"] = {
                "KHR_lights_punctual": {"lights": self.lights}}
        if self.extensions:
            doc["extensionsUsed"] = sorted(self.extensions)
        return {k: v for k, v in doc.items() if v != []}

    def write_gltf(self, path, embed=False):
        if embed:
            uri = ("data:application/octet-stream;base64,"
                   + base64.b64encode(bytes(self.bin)).decode("ascii"))
        else:
            uri = os.path.splitext(os.path.basename(path))[0] + ".bin"
        text = json.dumps(self._finish(uri), indent=1, sort_keys=True)
        # Put lists of plain numbers / strings on one line.
        text = re.sub(r"\[\s+([^][{}]*?)\s+\]",
                      lambda m: "[" + re.sub(r",\s+", ", ", m.group(1)) + "]",
                      text)
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write(text + "\n")
        if not embed:
            with open(os.path.join(os.path.dirname(path), uri), "wb") as f:
                f.write(self.bin)

    def write_glb(self, path):
        js = json.dumps(self._finish(None), separators=(",", ":"),
                        sort_keys=True).encode("utf-8")
        js += b" " * (-len(js) % 4)
        chunks = (struct.pack("<II", len(js), 0x4E4F534A) + js
                  + struct.pack("<II", len(self.bin), 0x004E4942) + self.bin)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)))
            f.write(chunks)


# --------------------------------------------------------------------------
# Scenes

WHITE = (0.75, 0.75, 0.75)
LIGHT_RGB, LIGHT_STRENGTH = (1.0, 0.78, 0.5), 25.0
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def build_room(g, left_rgb, right_rgb):
    """2 x 2 x 2 m room (x,z in [-1,1], y in [0,2]) open towards +z, with a
    0.5 x 0.4 m ceiling light; adds the box camera at (0, 1, 3.4)."""
    white = g.material("white", WHITE)
    left = g.material("left_wall", left_rgb)
    right = g.material("right_wall", right_rgb)
    light = g.material("light", (0.0, 0.0, 0.0), emissive=LIGHT_RGB,
                       strength=LIGHT_STRENGTH)
    walls = [  # name, center, u, v, normal (pointing into the room), material
        ("floor", (0, 0, 0), X, Z, Y, white),
        ("ceiling", (0, 2, 0), X, Z, mul(Y, -1), white),
        ("back_wall", (0, 1, -1), X, Y, Z, white),
        ("left_wall", (-1, 1, 0), Y, Z, X, left),
        ("right_wall", (1, 1, 0), Y, Z, mul(X, -1), right),
        ("light", (0, 1.98, 0), mul(X, 0.25), mul(Z, 0.2), mul(Y, -1), light),
    ]
    for name, c, u, v, n, m in walls:
        g.node(name, mesh=g.mesh(name, rect(c, u, v, n), m))
    g.camera("camera", eye=(0.0, 1.0, 3.4), target=(0.0, 1.0, 0.0),
             yfov=0.69, aspect=1.0)
    return white


def cornell_box(outdir):
    g = GltfBuilder("cornell_box")
    white = build_room(g, (0.63, 0.065, 0.05), (0.14, 0.45, 0.09))
    cube = g.mesh("unit_cube", unit_cube(), white)
    # The parent's translation composes with the children's TRS: world
    # centres are short box (0.35, 0.3, 0.35), tall box (-0.35, 0.6, -0.3).
    boxes = g.node("boxes", t=(0.0, 0.0, -0.1))
    g.node("tall_box", parent=boxes, mesh=cube, t=(-0.35, 0.6, -0.2),
           r=quat_axis_angle(Y, math.radians(17.0)), s=(0.6, 1.2, 0.6))
    g.node("short_box", parent=boxes, mesh=cube, t=(0.35, 0.3, 0.45),
           r=quat_axis_angle(Y, math.radians(-18.0)), s=(0.6, 0.6, 0.6))
    g.write_gltf(os.path.join(outdir, "cornell_box.gltf"))
    return g


def glossy_box(outdir):
    g = GltfBuilder("glossy_box")
    build_room(g, (0.1, 0.2, 0.6), (0.14, 0.45, 0.09))
    glass = g.material("glass", (1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.5)
    gold = g.material("gold", (1.0, 0.78, 0.34), metallic=1.0, roughness=0.3)
    radius = 0.35
    g.node("glass_sphere", t=(-0.42, radius, 0.3),
           mesh=g.mesh("glass_sphere", uv_sphere(radius), glass))
    # Unit icosahedron scaled to radius 0.35 and rotated so that one face
    # rests flat on the floor (its centre then sits at the inradius).
    ico = icosahedron()
    n0 = ico[1][0]
    inradius = radius * abs(dot(n0, ico[0][0]))
    g.node("gold_icosahedron", t=(0.4, inradius, -0.35),
           r=quat_between(n0, (0.0, -1.0, 0.0)), s=(radius, radius, radius),
           mesh=g.mesh("gold_icosahedron", ico, gold))
    g.write_glb(os.path.join(outdir, "glossy_box.glb"))
    return g


def direct_light(outdir):
    g = GltfBuilder("direct_light")
    ground = g.material("ground", (0.6, 0.6, 0.6))
    g.node("ground", mesh=g.mesh("ground", rect((0, 0, 0), mul(X, 3.0),
                                                 mul(Z, 3.0), Y), ground))
    cube = unit_cube()
    box = g.mesh("box", cube, g.material("box_white", (0.8, 0.8, 0.78)))
    slab = g.mesh("slab", cube, g.material("slab_white", (0.7, 0.7, 0.7)))
    pole = g.mesh("pole", cube, g.material("pole_white", (0.75, 0.74, 0.72)))
    g.node("box", mesh=box, t=(-1.0, 0.3, 0.6),
           r=quat_axis_angle(Y, math.radians(30.0)), s=(0.6, 0.6, 0.6))
    g.node("slab", mesh=slab, t=(1.4, 0.5, -0.6),
           r=quat_axis_angle(Y, math.radians(-35.0)), s=(1.2, 1.0, 0.05))
    # A small cap raised on a thin column (hierarchy: parent + 2 children).
    stand = g.node("raised_block", t=(-0.4, 0.0, -1.2),
                   r=quat_axis_angle(Y, math.radians(20.0)))
    g.node("column", parent=stand, mesh=pole, t=(0.0, 0.6, 0.0),
           s=(0.08, 1.2, 0.08))
    g.node("cap", parent=stand, mesh=pole, t=(0.0, 1.25, 0.0),
           s=(0.45, 0.1, 0.45))
    g.point_light("point_light", position=(0.5, 3.0, 0.5), intensity=40.0)
    # Looks down 40 degrees (target chosen so atan(4 / 4.77) = 40 deg).
    g.camera("camera", eye=(0.0, 4.0, 6.0),
             target=(0.0, 0.0, 6.0 - 4.0 / math.tan(math.radians(40.0))),
             yfov=0.75, aspect=1.333)
    g.write_gltf(os.path.join(outdir, "direct_light.gltf"), embed=True)
    return g


# Two rooms side by side along z, sharing one wall (the camera's room at
# z < 0, the lit room at z > 0). Each room is a closed box of inward-facing
# quads; the shared wall is the two rooms' facing quads, WALL apart, so it is
# a solid 8 cm wall as far as either room can tell.
ROOM_X, ROOM_H, ROOM_D, WALL = 2.0, 2.5, 3.0, 0.08
ROOM_LIGHT_STRENGTH = 150.0  # the dark room is lit only through the opening
GAP_X, GAP_W, GAP_H = 0.6, 0.25, 2.0  # the opening: x in [GAP_X, GAP_X + GAP_W]


def wall_with_hole(z, normal, hole):
    """The shared wall's face at depth z (normal +-Z), full width and height,
    less the opening when `hole`."""
    parts = []
    def piece(x0, x1, y0, y1):
        parts.append(rect(((x0 + x1) / 2, (y0 + y1) / 2, z),
                          mul(X, (x1 - x0) / 2), mul(Y, (y1 - y0) / 2),
                          normal))
    if not hole:
        piece(-ROOM_X, ROOM_X, 0.0, ROOM_H)
    else:
        piece(-ROOM_X, GAP_X, 0.0, ROOM_H)
        piece(GAP_X + GAP_W, ROOM_X, 0.0, ROOM_H)
        piece(GAP_X, GAP_X + GAP_W, GAP_H, ROOM_H)
    return merge(*parts)


def two_rooms(outdir, gap):
    name = "two_rooms_gap" if gap else "two_rooms_sealed"
    g = GltfBuilder(name)
    white = g.material("white", WHITE)
    floor = g.material("floor", (0.55, 0.42, 0.3))
    light = g.material("light", (0.0, 0.0, 0.0), emissive=LIGHT_RGB,
                       strength=ROOM_LIGHT_STRENGTH)
    half = WALL / 2
    for room, (z0, z1) in (("dark", (-half - ROOM_D, -half)),
                           ("lit", (half, half + ROOM_D))):
        zc, zh = (z0 + z1) / 2, (z1 - z0) / 2
        shared_z, shared_n = (z1, mul(Z, -1)) if room == "dark" else (z0, Z)
        outer_z, outer_n = (z0, Z) if room == "dark" else (z1, mul(Z, -1))
        walls = [  # normals point into the room
            ("floor", rect((0, 0, zc), mul(X, ROOM_X), mul(Z, zh), Y), floor),
            ("ceiling", rect((0, ROOM_H, zc), mul(X, ROOM_X), mul(Z, zh),
                             mul(Y, -1)), white),
            ("left_wall", rect((-ROOM_X, ROOM_H / 2, zc), mul(Y, ROOM_H / 2),
                               mul(Z, zh), X), white),
            ("right_wall", rect((ROOM_X, ROOM_H / 2, zc), mul(Y, ROOM_H / 2),
                                mul(Z, zh), mul(X, -1)), white),
            ("outer_wall", rect((0, ROOM_H / 2, outer_z), mul(X, ROOM_X),
                                mul(Y, ROOM_H / 2), outer_n), white),
            ("shared_wall", wall_with_hole(shared_z, shared_n, gap), white),
        ]
        for wall, geom, m in walls:
            g.node(room + "_" + wall, mesh=g.mesh(room + "_" + wall, geom, m))
    if gap:  # the opening's sides, top and floor, facing into it
        x0, x1 = GAP_X, GAP_X + GAP_W
        jambs = merge(
            rect((x0, GAP_H / 2, 0), mul(Y, GAP_H / 2), mul(Z, half), X),
            rect((x1, GAP_H / 2, 0), mul(Y, GAP_H / 2), mul(Z, half),
                 mul(X, -1)),
            rect(((x0 + x1) / 2, GAP_H, 0), mul(X, GAP_W / 2), mul(Z, half),
                 mul(Y, -1)))
        g.node("opening_jambs", mesh=g.mesh("opening_jambs", jambs, white))
        g.node("opening_floor", mesh=g.mesh("opening_floor", rect(
            ((x0 + x1) / 2, 0, 0), mul(X, GAP_W / 2), mul(Z, half), Y),
            floor))
    # A glass ball in the lit room near the shared wall: caustic photons land
    # right beside the wall.
    glass = g.material("glass", (1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.5)
    g.node("glass_ball", t=(-0.9, 0.3, half + 0.6),
           mesh=g.mesh("glass_ball", uv_sphere(0.3, 24, 12), glass))
    g.node("ceiling_light", mesh=g.mesh("ceiling_light", rect(
        (0, ROOM_H - 0.01, half + ROOM_D / 2), mul(X, 0.3), mul(Z, 0.3),
        mul(Y, -1)), light))
    # The first camera looks at the shared wall from the dark room; the
    # second shows the lit room (tests compare the two).
    g.camera("camera", eye=(-1.4, 1.5, -half - ROOM_D + 0.2),
             target=(0.4, 0.6, 0.0), yfov=1.1, aspect=1.333)
    g.camera("lit_camera", eye=(1.4, 1.5, half + ROOM_D - 0.2),
             target=(-0.4, 0.9, 0.0), yfov=1.0, aspect=1.333)
    g.write_gltf(os.path.join(outdir, name + ".gltf"))
    return g


def wavy_sheet(half, y0, thickness, amplitude, waves, n):
    """Closed glass sheet over [-half, half]^2: flat bottom at y0, wavy top
    around y0 + thickness (sum of two sine waves), sides; smooth normals on
    the top, outward everywhere."""
    def height(x, z):
        return (y0 + thickness + amplitude * (
            math.sin(waves * x + 0.4) * math.cos(0.8 * waves * z)
            + 0.5 * math.sin(1.7 * waves * (x + z))))

    def normal(x, z):
        e = 1e-4
        dx = (height(x + e, z) - height(x - e, z)) / (2 * e)
        dz = (height(x, z + e) - height(x, z - e)) / (2 * e)
        return normalize((-dx, 1.0, -dz))

    step = 2.0 * half / n
    pos, nrm, idx = [], [], []
    for i in range(n + 1):
        for j in range(n + 1):
            x, z = -half + i * step, -half + j * step
            pos.append((x, height(x, z), z))
            nrm.append(normal(x, z))
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            idx += [a, a + 1, b + 1, a, b + 1, b]  # counter-clockwise seen from +y
    top = (pos, nrm, idx)
    bottom = rect((0, y0, 0), mul(X, half), mul(Z, half), mul(Y, -1))
    sides = []
    for axis, sign in ((0, 1.0), (0, -1.0), (2, 1.0), (2, -1.0)):
        # A strip from the flat bottom up to the wavy edge, outward normal.
        spos, snrm, sidx = [], [], []
        outward = tuple(sign if k == axis else 0.0 for k in range(3))
        for k in range(n + 1):
            t = -half + k * step
            x, z = (sign * half, t) if axis == 0 else (t, sign * half)
            spos += [(x, y0, z), (x, height(x, z), z)]
            snrm += [outward, outward]
        for k in range(n):
            a = 2 * k
            quad = [a, a + 2, a + 3, a, a + 3, a + 1]
            # Wind counter-clockwise around the outward normal.
            p0, p1, p2 = spos[quad[0]], spos[quad[1]], spos[quad[2]]
            if dot(cross(sub(p1, p0), sub(p2, p0)), outward) < 0:
                quad = [a, a + 3, a + 2, a, a + 1, a + 3]
            sidx += quad
        sides.append((spos, snrm, sidx))
    return merge(top, bottom, *sides)


def caustic_pool(outdir):
    g = GltfBuilder("caustic_pool")
    white = g.material("white", WHITE)
    tiles = g.material("pool_floor", (0.35, 0.6, 0.7))
    light = g.material("light", (0.0, 0.0, 0.0), emissive=(1.0, 0.95, 0.85),
                       strength=200.0)
    water = g.material("water", (1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.33)
    walls = [  # a closed 2 x 2 x 2 m room, normals inwards
        ("floor", (0, 0, 0), X, Z, Y, tiles),
        ("ceiling", (0, 2, 0), X, Z, mul(Y, -1), white),
        ("back_wall", (0, 1, -1), X, Y, Z, white),
        ("front_wall", (0, 1, 1), X, Y, mul(Z, -1), white),
        ("left_wall", (-1, 1, 0), Y, Z, X, white),
        ("right_wall", (1, 1, 0), Y, Z, mul(X, -1), white),
    ]
    for name, c, u, v, n, m in walls:
        g.node(name, mesh=g.mesh(name, rect(c, mul(u, 1.0), mul(v, 1.0), n),
                                 m))
    # The sheet spans the room wall to wall: the light sees nothing below it
    # but through the glass.
    g.node("water_sheet", mesh=g.mesh(
        "water_sheet", wavy_sheet(1.0, 1.2, 0.05, 0.012, 16.0, 64), water))
    g.node("light", mesh=g.mesh("light", rect(
        (0.2, 1.98, -0.1), mul(X, 0.08), mul(Z, 0.08), mul(Y, -1)), light))
    g.camera("camera", eye=(0.0, 1.0, 0.95), target=(0.0, 0.0, -0.2),
             yfov=1.1, aspect=1.0)
    g.write_gltf(os.path.join(outdir, "caustic_pool.gltf"))
    return g


def point_shadows(outdir):
    """Boxes casting hard shadows under a point light, on dark ground in the
    open: little indirect light, so the image is direct light and its edges."""
    g = GltfBuilder("point_shadows")
    ground = g.material("ground", (0.25, 0.25, 0.25))
    grey = g.material("box_grey", (0.5, 0.5, 0.48))
    g.node("ground", mesh=g.mesh("ground", rect((0, 0, 0), mul(X, 4.0),
                                                 mul(Z, 4.0), Y), ground))
    cube = g.mesh("box", unit_cube(), grey)
    for name, t, angle, size in (
            ("box_tall", (-0.8, 0.6, -0.4), 25.0, (0.4, 1.2, 0.4)),
            ("box_wide", (0.6, 0.25, 0.3), -15.0, (0.9, 0.5, 0.5)),
            ("box_small", (-0.2, 0.15, 0.9), 40.0, (0.3, 0.3, 0.3)),
            ("plank", (0.9, 0.9, -0.9), 10.0, (1.0, 0.04, 0.3))):
        g.node(name, mesh=cube, t=t, r=quat_axis_angle(Y, math.radians(angle)),
               s=size)
    g.node("plank_post", mesh=cube, t=(0.9, 0.44, -0.9),
           s=(0.04, 0.88, 0.04))
    g.point_light("point_light", position=(1.2, 2.6, 1.0), intensity=30.0)
    g.camera("camera", eye=(0.0, 3.2, 3.6), target=(0.0, 0.2, 0.0),
             yfov=0.8, aspect=1.0)
    g.write_gltf(os.path.join(outdir, "point_shadows.gltf"), embed=True)
    return g


# A furnished room lit through a window and by a ceiling lamp, with the fine
# geometry real interiors have and boxes lack: skirting boards and a crown
# moulding 2-6 cm deep, picture frames of 3 cm bars, a table and chairs on
# 3-5 cm legs, chair backs of 3 cm slats, a banister of 3 cm balusters 12 cm
# apart, shelves of 2 cm boards. At the default grid (192 voxels over the
# room's 5 m) a voxel is 2.7 cm: these parts are one to three voxels wide.
IN_X, IN_H, IN_Z = 2.0, 2.6, 2.5          # room: x, z in [-IN_X, IN_X] x [-IN_Z, IN_Z]
WIN_Z0, WIN_Z1, WIN_Y0, WIN_Y1 = -1.6, -0.4, 0.9, 2.1  # window in the left wall
WIN_DEPTH = 0.2                            # the wall's thickness at the window


def box_maker(g):
    """box(name, material, lo, hi): an axis-aligned box node from corner lo to corner hi, one
    unit-cube mesh a material, instanced."""
    cube = unit_cube()
    meshes = {}

    def box(name, material, lo, hi):
        if material not in meshes:
            meshes[material] = g.mesh("cube_%d" % material, cube, material)
        g.node(name, mesh=meshes[material],
               t=tuple((a + b) / 2 for a, b in zip(lo, hi)),
               s=tuple(b - a for a, b in zip(lo, hi)))
    return box


def quad_node(g, name, geom, material, **fields):
    return g.node(name, mesh=g.mesh(name, geom, material), **fields)


def windowed_room(g, half_x, height, half_z, window, depth, floor, ceiling, wall, trim):
    """The shell of a room x in [-half_x, half_x], z in [-half_z, half_z], y in [0, height],
    normals into the room; the left wall (x = -half_x) less a window (z0, z1, y0, y1) whose
    reveal is a tunnel `depth` deep. Returns the window's centre (y, z) and half sizes (y, z)."""
    z0, z1, y0, y1 = window
    quad_node(g, "floor", rect((0, 0, 0), mul(X, half_x), mul(Z, half_z), Y), floor)
    quad_node(g, "ceiling", rect((0, height, 0), mul(X, half_x), mul(Z, half_z),
                                 mul(Y, -1)), ceiling)
    quad_node(g, "back_wall", rect((0, height / 2, -half_z), mul(X, half_x),
                                   mul(Y, height / 2), Z), wall)
    quad_node(g, "front_wall", rect((0, height / 2, half_z), mul(X, half_x),
                                    mul(Y, height / 2), mul(Z, -1)), wall)
    quad_node(g, "right_wall", rect((half_x, height / 2, 0), mul(Y, height / 2),
                                    mul(Z, half_z), mul(X, -1)), wall)

    def left_piece(za, zb, ya, yb):
        return rect((-half_x, (ya + yb) / 2, (za + zb) / 2),
                    mul(Y, (yb - ya) / 2), mul(Z, (zb - za) / 2), X)
    quad_node(g, "left_wall", merge(
        left_piece(-half_z, z0, 0, height), left_piece(z1, half_z, 0, height),
        left_piece(z0, z1, 0, y0), left_piece(z0, z1, y1, height)), wall)
    xr = -half_x - depth / 2
    hz, hy, hd = (z1 - z0) / 2, (y1 - y0) / 2, depth / 2
    zc, yc = (z0 + z1) / 2, (y0 + y1) / 2
    quad_node(g, "window_reveal", merge(
        rect((xr, y0, zc), mul(X, hd), mul(Z, hz), Y),
        rect((xr, y1, zc), mul(X, hd), mul(Z, hz), mul(Y, -1)),
        rect((xr, yc, z0), mul(X, hd), mul(Y, hy), Z),
        rect((xr, yc, z1), mul(X, hd), mul(Y, hy), mul(Z, -1))), trim)
    return (yc, zc), (hy, hz)


def interior(outdir):
    g = interior_room("interior")
    g.camera("camera", eye=(0.9, 1.55, 2.3), target=(-0.5, 0.9, -1.2),
             yfov=1.05, aspect=1.333)
    g.write_gltf(os.path.join(outdir, "interior.gltf"))
    return g


WALK_FPS, WALK_FRAMES = 24, 48


def interior_walk(outdir):
    """interior.gltf with a walk: a rig carries the camera 1.6 m into the room
    in 2 s while the camera, its child, turns 35 degrees to the left; baked one
    key a frame at 24 fps, frames 0-48, as Blender's exporter writes them."""
    g = interior_room("interior_walk")
    start, end = (0.9, 1.55, 2.3), (0.3, 1.5, 0.8)
    yaw0 = math.atan2(1.4, 3.5)  # towards (-0.5, 0.9, -1.2), as interior.gltf's camera
    pitch = -0.18
    rig = g.node("camera_rig", t=start)
    persp = {"yfov": f32(1.05), "znear": f32(0.05), "zfar": f32(100.0), "aspectRatio": f32(1.333)}
    cam = g._append("cameras", {"name": "camera", "type": "perspective", "perspective": persp})
    camera = g.node("camera", parent=rig, camera=cam)
    times, moves, turns = [], [], []
    for f in range(WALK_FRAMES + 1):
        u = f / WALK_FRAMES
        ease = u * u * (3.0 - 2.0 * u)  # starts and stops walking
        times.append(f / WALK_FPS)
        moves.append(tuple(a + (b - a) * ease for a, b in zip(start, end)))
        turns.append(quat_mul(quat_axis_angle(Y, yaw0 + math.radians(35.0) * ease),
                              quat_axis_angle(X, pitch)))
    g.animation("walk", [(rig, "translation", times, moves),
                         (camera, "rotation", times, turns)])
    g.write_gltf(os.path.join(outdir, "interior_walk.gltf"))
    return g


def interior_room(scene_name):
    g = GltfBuilder(scene_name)
    wall = g.material("wall", (0.7, 0.68, 0.62))
    ceiling = g.material("ceiling", (0.8, 0.8, 0.8))
    floor = g.material("floor", (0.45, 0.3, 0.2))
    trim = g.material("trim", (0.82, 0.8, 0.76))
    wood = g.material("wood", (0.35, 0.22, 0.12))
    gilt = g.material("frame", (0.6, 0.48, 0.28))
    canvas = [g.material("canvas_blue", (0.15, 0.3, 0.55)),
              g.material("canvas_red", (0.6, 0.15, 0.1))]
    sky = g.material("sky", (0.0, 0.0, 0.0), emissive=(0.75, 0.85, 1.0),
                     strength=12.0)
    lamp = g.material("lamp", (0.0, 0.0, 0.0), emissive=LIGHT_RGB,
                      strength=30.0)
    box = box_maker(g)

    def quad(name, geom, material):
        quad_node(g, name, geom, material)

    # The shell, normals into the room; the left wall less the window, whose
    # reveal is a short tunnel ending in the sky.
    (yc, zc), (hy, hz) = windowed_room(g, IN_X, IN_H, IN_Z, (WIN_Z0, WIN_Z1, WIN_Y0, WIN_Y1),
                                       WIN_DEPTH, floor, ceiling, wall, trim)
    quad("sky", rect((-IN_X - WIN_DEPTH, yc, zc), mul(Y, hy), mul(Z, hz), X),
         sky)
    # Window bars: a mullion and a transom, 4 cm.
    box("mullion", trim, (-IN_X - 0.12, WIN_Y0, zc - 0.02),
        (-IN_X - 0.08, WIN_Y1, zc + 0.02))
    box("transom", trim, (-IN_X - 0.12, yc - 0.02, WIN_Z0),
        (-IN_X - 0.08, yc + 0.02, WIN_Z1))
    quad("lamp", rect((0.3, IN_H - 0.01, 0.2), mul(X, 0.2), mul(Z, 0.2),
                      mul(Y, -1)), lamp)

    # Mouldings: skirting boards 2 cm deep, a crown moulding 6 cm.
    for name, lo, hi in (
            ("skirting_back", (-IN_X, 0, -IN_Z), (IN_X, 0.12, -IN_Z + 0.02)),
            ("skirting_right", (IN_X - 0.02, 0, -IN_Z), (IN_X, 0.12, IN_Z)),
            ("skirting_left", (-IN_X, 0, -IN_Z), (-IN_X + 0.02, 0.12, IN_Z)),
            ("crown_back", (-IN_X, IN_H - 0.08, -IN_Z),
             (IN_X, IN_H, -IN_Z + 0.06)),
            ("crown_right", (IN_X - 0.06, IN_H - 0.08, -IN_Z),
             (IN_X, IN_H, IN_Z))):
        box(name, trim, lo, hi)
    # Two framed pictures on the back wall: 3 cm bars standing 3 cm off it.
    for k, (x0, y0, w, h) in enumerate(((-1.3, 1.2, 0.8, 0.6),
                                        (0.4, 1.1, 0.6, 0.8))):
        z0, z1 = -IN_Z, -IN_Z + 0.03
        quad("canvas_%d" % k, rect((x0 + w / 2, y0 + h / 2, z0 + 0.01),
                                   mul(X, w / 2), mul(Y, h / 2), Z), canvas[k])
        for side, lo, hi in (("bottom", (x0, y0, z0), (x0 + w, y0 + 0.03, z1)),
                             ("top", (x0, y0 + h - 0.03, z0),
                              (x0 + w, y0 + h, z1)),
                             ("left", (x0, y0, z0), (x0 + 0.03, y0 + h, z1)),
                             ("right", (x0 + w - 0.03, y0, z0),
                              (x0 + w, y0 + h, z1))):
            box("frame_%d_%s" % (k, side), gilt, lo, hi)
    # A table on 5 cm legs, two chairs on 3 cm legs with slatted backs.
    tx, tz = -0.2, -0.6
    box("table_top", wood, (tx - 0.6, 0.72, tz - 0.35), (tx + 0.6, 0.76, tz + 0.35))
    for i, (dx, dz) in enumerate(((-0.55, -0.3), (0.5, -0.3), (-0.55, 0.25),
                                  (0.5, 0.25))):
        box("table_leg_%d" % i, wood, (tx + dx, 0, tz + dz),
            (tx + dx + 0.05, 0.72, tz + dz + 0.05))
    for c, (cx, cz, facing) in enumerate(((tx - 0.3, tz + 0.6, 1.0),
                                          (tx + 0.35, tz - 0.62, -1.0))):
        box("chair_%d_seat" % c, wood, (cx - 0.21, 0.43, cz - 0.21),
            (cx + 0.21, 0.46, cz + 0.21))
        for i, (dx, dz) in enumerate(((-0.2, -0.2), (0.17, -0.2),
                                      (-0.2, 0.17), (0.17, 0.17))):
            box("chair_%d_leg_%d" % (c, i), wood, (cx + dx, 0, cz + dz),
                (cx + dx + 0.03, 0.43, cz + dz + 0.03))
        bz = cz + facing * 0.19
        box("chair_%d_rail" % c, wood, (cx - 0.21, 0.88, bz - 0.015),
            (cx + 0.21, 0.92, bz + 0.015))
        for i in range(4):
            x = cx - 0.165 + i * 0.11
            box("chair_%d_slat_%d" % (c, i), wood, (x, 0.46, bz - 0.015),
                (x + 0.03, 0.88, bz + 0.015))
    # A banister along the right of the room: 3 cm balusters 12 cm apart
    # under a 5 cm rail.
    bx = 1.2
    box("banister_rail", wood, (bx - 0.025, 0.9, -1.8), (bx + 0.025, 0.95, 1.0))
    box("banister_base", wood, (bx - 0.04, 0, -1.8), (bx + 0.04, 0.06, 1.0))
    for i in range(24):
        z = -1.76 + i * 0.12
        box("baluster_%d" % i, trim, (bx - 0.015, 0.06, z),
            (bx + 0.015, 0.9, z + 0.03))
    # Shelves of 2 cm boards against the right wall, behind the banister.
    for i in range(5):
        y = 0.1 + i * 0.45
        box("shelf_%d" % i, wood, (IN_X - 0.3, y, -2.3), (IN_X - 0.02, y + 0.02, -1.3))
    for side, z in (("a", -2.32), ("b", -1.3)):
        box("shelf_side_" + side, wood, (IN_X - 0.3, 0.1, z),
            (IN_X - 0.02, 1.92, z + 0.02))
    return g


def png_rgba(width, height, pixel):
    """PNG bytes of an 8-bit RGBA image; pixel(x, y) gives (r, g, b, a) in 0..255."""
    import zlib
    raw = b"".join(b"\0" + bytes(c for x in range(width) for c in pixel(x, y))
                   for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def leaf_png(size=32):
    """A leaf: opaque inside a pointed oval along the image's v axis, clear outside."""
    def pixel(x, y):
        u = (x + 0.5) / size * 2.0 - 1.0
        v = (y + 0.5) / size * 2.0 - 1.0
        half_width = 0.55 * (1.0 - v * v) ** 1.5  # pointed at both ends
        inside = abs(u) <= half_width or (abs(u) < 0.04 and v > 0.7)  # and a stalk
        shade = 120 + int(60 * (1.0 - abs(u)))
        return (40, shade, 30, 255 if inside else 0)
    return png_rgba(size, size, pixel)


# The daylight room: x in [-DAY_X, DAY_X], z in [-DAY_Z, DAY_Z], a window of 1 m² in the left
# wall (a tenth of its 10.8 m²) with a blind, lit by the sun and a uniform sky through it.
DAY_X, DAY_H, DAY_Z = 2.5, 2.7, 2.0
DAY_WIN_Z0, DAY_WIN_Z1, DAY_WIN_Y0, DAY_WIN_Y1 = -0.9, 0.1, 0.9, 1.9
DAY_WIN_DEPTH = 0.25


def daylight(outdir):
    g = GltfBuilder("daylight")
    g.doc["scenes"][0]["extras"] = {"raysplat_sky": vec((1.0, 1.25, 1.75))}
    wall = g.material("wall", (0.72, 0.7, 0.66))
    ceiling = g.material("ceiling", (0.8, 0.8, 0.8))
    floor = g.material("floor", (0.5, 0.36, 0.24))
    trim = g.material("trim", (0.85, 0.84, 0.8))
    wood = g.material("wood", (0.38, 0.24, 0.13))
    fabric = g.material("sofa", (0.25, 0.32, 0.45))
    rug = g.material("rug", (0.55, 0.2, 0.15))
    clay = g.material("pot", (0.55, 0.3, 0.2))
    leaf = g.material("leaf", (1.0, 1.0, 1.0))
    leaf_tex = g.png_texture("leaf", leaf_png())
    m = g.doc["materials"][leaf]
    m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": leaf_tex}
    m["alphaMode"] = "MASK"
    m["alphaCutoff"] = 0.5
    m["doubleSided"] = True
    box = box_maker(g)
    (yc, zc), (hy, hz) = windowed_room(g, DAY_X, DAY_H, DAY_Z, (DAY_WIN_Z0, DAY_WIN_Z1, DAY_WIN_Y0, DAY_WIN_Y1),
                                       DAY_WIN_DEPTH, floor, ceiling, wall, trim)
    # The opening's outer face is the light portal: the sun's and the sky's photons enter there.
    quad_node(g, "window_portal", rect((-DAY_X - DAY_WIN_DEPTH, yc, zc), mul(Y, hy), mul(Z, hz), X), trim,
              extras={"raysplat_portal": True})
    # A blind of 9 slats, 1 cm thick and 5 cm deep, 11 cm apart: the sun comes in stripes.
    for i in range(9):
        y = DAY_WIN_Y0 + 0.06 + i * 0.11
        box("blind_slat_%d" % i, trim, (-DAY_X - 0.08, y, DAY_WIN_Z0), (-DAY_X - 0.03, y + 0.01, DAY_WIN_Z1))
    # Mouldings and furniture: enough to make the indirect light matter.
    box("skirting_back", trim, (-DAY_X, 0, -DAY_Z), (DAY_X, 0.1, -DAY_Z + 0.02))
    box("skirting_right", trim, (DAY_X - 0.02, 0, -DAY_Z), (DAY_X, 0.1, DAY_Z))
    box("rug", rug, (-0.6, 0, -0.9), (1.2, 0.01, 0.6))
    box("sofa_seat", fabric, (1.6, 0.0, -1.2), (2.4, 0.42, 0.8))
    box("sofa_back", fabric, (2.2, 0.42, -1.2), (2.4, 0.85, 0.8))
    for side, z0 in (("a", -1.35), ("b", 0.8)):
        box("sofa_arm_" + side, fabric, (1.6, 0.0, z0), (2.4, 0.6, z0 + 0.15))
    tx, tz = 0.3, -0.15
    box("table_top", wood, (tx - 0.45, 0.42, tz - 0.3), (tx + 0.45, 0.45, tz + 0.3))
    for i, (dx, dz) in enumerate(((-0.42, -0.27), (0.39, -0.27), (-0.42, 0.24), (0.39, 0.24))):
        box("table_leg_%d" % i, wood, (tx + dx, 0, tz + dz), (tx + dx + 0.03, 0.42, tz + dz + 0.03))
    for i in range(4):
        y = 0.3 + i * 0.4
        box("shelf_%d" % i, wood, (-1.4, y, -DAY_Z + 0.02), (-0.4, y + 0.02, -DAY_Z + 0.3))
    # A potted plant in the sun's path: alpha-masked leaves on a stem.
    px, pz = -1.55, -1.05
    box("pot", clay, (px - 0.14, 0, pz - 0.14), (px + 0.14, 0.3, pz + 0.14))
    box("stem", wood, (px - 0.01, 0.3, pz - 0.01), (px + 0.01, 1.15, pz + 0.01))
    leaf_uvs = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]
    for i in range(10):
        angle = i * 2.399963  # golden angle
        y = 0.65 + 0.05 * i
        out = (math.cos(angle), 0.0, math.sin(angle))
        side = (-math.sin(angle), 0.0, math.cos(angle))
        tilt = normalize(add(out, (0.0, 0.35, 0.0)))
        centre = (px + 0.16 * out[0], y, pz + 0.16 * out[2])
        geom = rect(centre, mul(tilt, 0.16), mul(side, 0.07), cross(tilt, side))
        g.node("leaf_%d" % i, mesh=g.mesh("leaf_%d" % i, geom, leaf, uvs=leaf_uvs))
    g.directional_light("sun", (0.8, -0.5, -0.25), 30.0, color=(1.0, 0.93, 0.82))
    g.camera("camera", eye=(2.1, 1.45, 1.75), target=(-1.2, 0.7, -1.0), yfov=1.0, aspect=1.333)
    g.write_gltf(os.path.join(outdir, "daylight.gltf"))
    return g


def main(argv):
    import textured_room
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    outdir = argv[1] if len(argv) > 1 else os.path.join(repo, "data")
    os.makedirs(outdir, exist_ok=True)
    for build in (cornell_box, glossy_box, direct_light,
                  lambda d: two_rooms(d, gap=False),
                  lambda d: two_rooms(d, gap=True), caustic_pool, point_shadows,
                  interior, interior_walk, daylight,
                  lambda d: textured_room.textured_room(os.path.join(d, "textured_room.gltf"))):
        g = build(outdir)
        tris = sum(g.doc["accessors"][p["indices"]]["count"] // 3
                   for n in g.doc["nodes"] if "mesh" in n
                   for p in g.doc["meshes"][n["mesh"]]["primitives"])
        print("%-16s %2d nodes, %4d triangles (instanced)" % (
            g.doc["scenes"][0]["name"], len(g.doc["nodes"]), tris))
    print("wrote scenes to", outdir)


if __name__ == "__main__":
    main(sys.argv)
