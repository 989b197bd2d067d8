"""Writing glTF 2.0 scenes from Python, standard library only: small vector and quaternion
helpers, meshes (rectangles, cubes, spheres), GltfBuilder (nodes, meshes, materials,
lights, cameras, animations; .gltf + .bin or .glb) and embedded PNG images. The scenes of
data/ are made with it by make_scenes.py and textured_room.py."""

import base64
import json
import math
import os
import re
import struct

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


X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


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


def plant_leaves(g, leaf, x, z, y0, reach, lift, width):
    """Ten quads of material `leaf` around a stem at (x, z), a golden angle apart, from y0 up
    by 5 cm each: each reaches `reach` out from the stem, tilted up by `lift`, `width` wide."""
    uvs = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]
    for i in range(10):
        angle = i * 2.399963  # golden angle
        y = y0 + 0.05 * i
        out = (math.cos(angle), 0.0, math.sin(angle))
        side = (-math.sin(angle), 0.0, math.cos(angle))
        tilt = normalize(add(out, (0.0, lift, 0.0)))
        centre = (x + reach * out[0], y, z + reach * out[2])
        geom = rect(centre, mul(tilt, reach), mul(side, width), cross(tilt, side))
        g.node("leaf_%d" % i, mesh=g.mesh("leaf_%d" % i, geom, leaf, uvs=uvs))


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
