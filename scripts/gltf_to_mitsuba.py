#!/usr/bin/env python3
"""Convert a glTF 2.0 scene (.gltf or .glb) into a Mitsuba 3 scene.

  python3 scripts/gltf_to_mitsuba.py SCENE.gltf OUTDIR [--width W] [--height H]
                                     [--spp N] [--camera NAME]

Writes OUTDIR/scene.xml and one binary PLY per glTF primitive in OUTDIR/meshes/.
The glTF is read here with numpy, independently of raysplat's loader, and mapped with
the rules of docs/design.md §3 so that both renderers see the same scene:

  glTF material                          Mitsuba 3
  metallic 0, roughness 1                twosided diffuse, reflectance = baseColor
  metallic 1, roughness ≥ 0.05           twosided principled, metallic 1, roughness
                                         (GGX α = roughness², Schlick F0 = baseColor)
  metallic 1, roughness < 0.05           twosided conductor, material none,
                                         specular_reflectance = baseColor
  other metallic / roughness (mix)       twosided principled with the same factors
  KHR_materials_transmission ≥ 0.5       dielectric, int_ior = KHR_materials_ior (1.5)
  emissiveFactor × emissive_strength     area emitter, radiance in W/(m²·sr), front face
  KHR_lights_punctual point / spot       point / spot, intensity in W/sr
  KHR_lights_punctual directional        directional, irradiance in W/m²
  perspective camera                     perspective, fov_axis y, box pixel filter
  baseColorTexture (diffuse materials)   bitmap reflectance, bilinear, sRGB decoded
  alphaMode MASK / BLEND                 mask BSDF whose opacity is the texel's level
                                         (MASK: 0 or 1 by alphaCutoff; BLEND: alpha),
                                         nearest texel, as raysplat's alpha test
  scene extras raysplat_sky              constant emitter
  scene extras raysplat_env (+ strength, envmap, scale = strength, turned about +Y by
    rotation)                            90° − rotation (Blender's orientation)
  node extras raysplat_portal            left out (a portal is not geometry)

Known differences of material model (they matter only where such materials are seen):
the principled BSDF uses the separable Smith masking term where raysplat uses the
height-correlated one, and its diffuse lobe for the mix is Disney's, not Lambert's;
Mitsuba's conductor "none" reflects a constant F0 where raysplat's mirror uses Schlick.
A base colour texture is converted for diffuse materials whose factor is white; other
textured materials keep their factor and the converter says so, as it does for normal,
emissive and metallic-roughness textures, which it leaves out (data/textured_room.gltf, whose
maps Blender's Cycles checks instead: scripts/blender_cycles_check.py), and COLOR_0.
"""

import argparse
import base64
import json
import math
import os
import struct
import sys
from xml.sax.saxutils import quoteattr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import venv_bootstrap  # noqa: E402

if __name__ == "__main__":
    venv_bootstrap.ensure()

import numpy as np  # noqa: E402

COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


class GltfError(Exception):
    pass


# -- Reading ------------------------------------------------------------------------------

def load_gltf(path):
    """(json document, list of buffer bytes) for a .gltf or .glb file."""
    try:
        data = open(path, "rb").read()
    except OSError as e:
        raise GltfError(f"{path}: {e.strerror}")
    binary_chunk = None
    if data[:4] == b"glTF":
        _, _, length = struct.unpack_from("<III", data, 0)
        offset, doc = 12, None
        while offset + 8 <= min(length, len(data)):
            size, kind = struct.unpack_from("<II", data, offset)
            chunk = data[offset + 8: offset + 8 + size]
            if kind == 0x4E4F534A:
                doc = json.loads(chunk)
            elif kind == 0x004E4942:
                binary_chunk = chunk
            offset += 8 + size
        if doc is None:
            raise GltfError(f"{path}: GLB has no JSON chunk")
    else:
        try:
            doc = json.loads(data)
        except ValueError as e:
            raise GltfError(f"{path}: not JSON ({e})")
    buffers = []
    for i, b in enumerate(doc.get("buffers", [])):
        uri = b.get("uri")
        if uri is None:
            if binary_chunk is None:
                raise GltfError(f"{path}: buffer {i} has no uri and there is no GLB chunk")
            buffers.append(binary_chunk)
        elif uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            from urllib.parse import unquote
            with open(os.path.join(os.path.dirname(path), unquote(uri)), "rb") as f:
                buffers.append(f.read())
    return doc, buffers


def read_accessor(doc, buffers, index):
    acc = doc["accessors"][index]
    n, width = acc["count"], COMPONENTS[acc["type"]]
    dtype = np.dtype(DTYPES[acc["componentType"]])
    if "bufferView" not in acc:
        return np.zeros((n, width), dtype)
    view = doc["bufferViews"][acc["bufferView"]]
    buf = buffers[view["buffer"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride") or width * dtype.itemsize
    rows = np.ndarray((n, width), dtype=dtype, buffer=buf, offset=start, strides=(stride, dtype.itemsize))
    out = np.array(rows)
    if acc.get("normalized") and dtype.kind in "iu":
        out = out.astype(np.float32) / float(np.iinfo(dtype).max)
    return out


def node_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # glTF is column-major
    t = np.array(node.get("translation", [0, 0, 0]), dtype=np.float64)
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    s = np.array(node.get("scale", [1, 1, 1]), dtype=np.float64)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * s
    m[:3, 3] = t
    return m


def walk_nodes(doc):
    """(node index, world matrix) for every node of the default scene, parents first."""
    scenes = doc.get("scenes", [])
    roots = scenes[doc.get("scene", 0)]["nodes"] if scenes else range(len(doc.get("nodes", [])))
    stack = [(i, np.eye(4)) for i in reversed(list(roots))]
    while stack:
        i, parent = stack.pop()
        node = doc["nodes"][i]
        world = parent @ node_matrix(node)
        yield i, world
        for c in reversed(node.get("children", [])):
            stack.append((c, world))


def triangle_indices(mode, idx, name):
    if mode == 4:
        return idx.reshape(-1, 3)
    if mode == 5:  # strip: keep the winding of every second triangle
        tris = [(idx[i], idx[i + 1], idx[i + 2]) if i % 2 == 0 else (idx[i + 1], idx[i], idx[i + 2])
                for i in range(len(idx) - 2)]
        return np.array(tris, dtype=np.uint32).reshape(-1, 3)
    if mode == 6:
        return np.array([(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)],
                        dtype=np.uint32).reshape(-1, 3)
    print(f"warning: {name}: primitive mode {mode} is not triangles, skipped", file=sys.stderr)
    return None


# -- Materials ----------------------------------------------------------------------------

def ext_number(mat, ext, key, default):
    return float(mat.get("extensions", {}).get(ext, {}).get(key, default))


def rgb(values):
    return ", ".join(f"{v:.9g}" for v in values[:3])


def image_of_texture(doc, buffers, texture, scene_path):
    """The decoded RGBA image (H × W × 4, uint8) of glTF texture `texture`."""
    from io import BytesIO
    from PIL import Image

    image = doc["images"][doc["textures"][texture]["source"]]
    if "bufferView" in image:
        view = doc["bufferViews"][image["bufferView"]]
        start = view.get("byteOffset", 0)
        data = bytes(buffers[view["buffer"]][start:start + view["byteLength"]])
    elif image.get("uri", "").startswith("data:"):
        data = base64.b64decode(image["uri"].split(",", 1)[1])
    else:
        from urllib.parse import unquote
        with open(os.path.join(os.path.dirname(scene_path), unquote(image["uri"])), "rb") as f:
            data = f.read()
    return np.array(Image.open(BytesIO(data)).convert("RGBA"))


def write_png(path, pixels):
    from PIL import Image

    Image.fromarray(pixels).save(path)


def material_xml(mat, name, texture_file=None, opacity_file=None):
    """(bsdf XML, emitter XML or '') for a glTF material following docs/design.md §3.
    texture_file: the base colour texture as a PNG, opacity_file: the cut-out's opacity (its
    alpha test's outcome per texel) as a PNG, both relative to the scene's folder, or None."""
    pbr = mat.get("pbrMetallicRoughness", {})
    base = pbr.get("baseColorFactor", [1, 1, 1, 1])
    metallic = min(max(float(pbr.get("metallicFactor", 1.0)), 0.0), 1.0)
    roughness = min(max(float(pbr.get("roughnessFactor", 1.0)), 0.0), 1.0)
    textured = texture_file is not None and metallic <= 0.0 and roughness >= 1.0 and all(v == 1 for v in base[:3])
    if "baseColorTexture" in pbr and not textured:
        print(f"warning: {name}: baseColorTexture not converted, baseColorFactor used", file=sys.stderr)
    for slot in ("normalTexture", "emissiveTexture", "metallicRoughnessTexture"):
        if slot in mat or slot in pbr:
            print(f"warning: {name}: {slot} not converted (the Mitsuba scene leaves it out)", file=sys.stderr)
    transmission = ext_number(mat, "KHR_materials_transmission", "transmissionFactor", 0.0)
    ior = ext_number(mat, "KHR_materials_ior", "ior", 1.5)
    if transmission >= 0.5:
        bsdf = (f'<bsdf type="dielectric"><float name="int_ior" value="{ior:.9g}"/>'
                f'<float name="ext_ior" value="1"/>'
                f'<rgb name="specular_transmittance" value="{rgb(base)}"/></bsdf>')
    elif metallic >= 1.0 and roughness < 0.05:
        bsdf = (f'<bsdf type="twosided"><bsdf type="conductor"><string name="material" value="none"/>'
                f'<rgb name="specular_reflectance" value="{rgb(base)}"/></bsdf></bsdf>')
    elif textured:
        bsdf = (f'<bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                f'<string name="filename" value="{texture_file}"/><string name="filter_type" value="bilinear"/>'
                f'</texture></bsdf></bsdf>')
    elif metallic <= 0.0 and roughness >= 1.0:
        bsdf = (f'<bsdf type="twosided"><bsdf type="diffuse">'
                f'<rgb name="reflectance" value="{rgb(base)}"/></bsdf></bsdf>')
    else:
        bsdf = (f'<bsdf type="twosided"><bsdf type="principled">'
                f'<rgb name="base_color" value="{rgb(base)}"/>'
                f'<float name="metallic" value="{metallic:.9g}"/>'
                f'<float name="roughness" value="{roughness:.9g}"/></bsdf></bsdf>')
    mode = mat.get("alphaMode", "OPAQUE")
    if mode in ("MASK", "BLEND"):
        opacity = (f'<texture type="bitmap" name="opacity"><string name="filename" value="{opacity_file}"/>'
                   f'<string name="filter_type" value="nearest"/><boolean name="raw" value="true"/></texture>'
                   if opacity_file else f'<float name="opacity" value="{cut_level(mat, 1.0):.9g}"/>')
        bsdf = f'<bsdf type="mask">{opacity}{bsdf}</bsdf>'
    strength = ext_number(mat, "KHR_materials_emissive_strength", "emissiveStrength", 1.0)
    emission = [float(v) * strength for v in mat.get("emissiveFactor", [0, 0, 0])]
    emitter = ""
    if any(v > 0 for v in emission):
        emitter = f'<emitter type="area"><rgb name="radiance" value="{rgb(emission)}"/></emitter>'
    return bsdf, emitter


def cut_level(mat, alpha):
    """raysplat's alpha test as an opacity: MASK 0 or 1 by alphaCutoff, BLEND the alpha."""
    factor = float(mat.get("pbrMetallicRoughness", {}).get("baseColorFactor", [1, 1, 1, 1])[3])
    a = factor * alpha
    if mat.get("alphaMode") == "MASK":
        return np.where(a >= float(mat.get("alphaCutoff", 0.5)), 1.0, 0.0)
    return a


def material_textures(doc, buffers, mi, mat, scene_path, outdir):
    """(texture PNG, opacity PNG) of material mi, written under OUTDIR/textures/, or Nones."""
    texture = mat.get("pbrMetallicRoughness", {}).get("baseColorTexture", {}).get("index")
    if texture is None:
        return None, None
    os.makedirs(os.path.join(outdir, "textures"), exist_ok=True)
    rgba = image_of_texture(doc, buffers, texture, scene_path)
    colour = f"textures/material{mi}_colour.png"
    write_png(os.path.join(outdir, colour), np.ascontiguousarray(rgba[:, :, :3]))
    opacity = None
    if mat.get("alphaMode") in ("MASK", "BLEND"):
        level = cut_level(mat, rgba[:, :, 3].astype(np.float64) / 255.0)
        opacity = f"textures/material{mi}_opacity.png"
        write_png(os.path.join(outdir, opacity), np.round(level * 255.0).astype(np.uint8))
    return colour, opacity


DEFAULT_MATERIAL = {"name": "default", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                                               "metallicFactor": 0, "roughnessFactor": 1}}


# -- Writing ------------------------------------------------------------------------------

def write_ply(path, positions, normals, faces, uvs=None):
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(positions)}",
              "property float x", "property float y", "property float z"]
    columns = [positions]
    if normals is not None:
        header += ["property float nx", "property float ny", "property float nz"]
        columns.append(normals)
    if uvs is not None:  # glTF's v runs down the image, as Mitsuba's bitmap reads it
        header += ["property float u", "property float v"]
        columns.append(uvs)
    header += [f"element face {len(faces)}", "property list uchar uint vertex_indices", "end_header"]
    vert = np.hstack(columns).astype("<f4")
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<u4", 3)])
    face["n"] = 3
    face["i"] = faces
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode())
        f.write(vert.tobytes())
        f.write(face.tobytes())


def look_at(world):
    """glTF camera (looks down local −Z, +Y up) → Mitsuba lookat origin, target, up."""
    origin = world[:3, 3]
    forward = -world[:3, 2] / np.linalg.norm(world[:3, 2])
    up = world[:3, 1] / np.linalg.norm(world[:3, 1])
    return origin, origin + forward, up


def vec(v):
    return ", ".join(f"{x:.9g}" for x in v)


def convert(scene_path, outdir, width=256, height=256, spp=256, camera_name=None, max_depth=32):
    """Write OUTDIR/scene.xml (+ meshes/). Returns the path of scene.xml."""
    doc, buffers = load_gltf(scene_path)
    os.makedirs(os.path.join(outdir, "meshes"), exist_ok=True)
    materials = doc.get("materials", [])
    body, camera = [], None
    lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    mesh_count = 0
    textures = {}
    for ni, world in walk_nodes(doc):
        node = doc["nodes"][ni]
        node_name = f"node {ni} '{node.get('name', '')}'"
        if node.get("extras", {}).get("raysplat_portal") in (True, 1):
            continue  # a light portal: not geometry
        if "camera" in node and camera is None:
            cam = doc["cameras"][node["camera"]]
            if cam.get("type") == "perspective" and (camera_name is None or node.get("name") == camera_name):
                camera = (world, cam["perspective"]["yfov"])
        light_ref = node.get("extensions", {}).get("KHR_lights_punctual")
        if light_ref is not None:
            body.append(light_xml(lights[light_ref["light"]], world))
        if "mesh" not in node:
            continue
        normal_matrix = np.linalg.inv(world[:3, :3]).T
        flip = np.linalg.det(world[:3, :3]) < 0
        for pi, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"]):
            name = f"{node_name} mesh {node['mesh']} primitive {pi}"
            if "COLOR_0" in prim["attributes"]:
                print(f"warning: {name}: COLOR_0 not converted (white)", file=sys.stderr)
            pos = read_accessor(doc, buffers, prim["attributes"]["POSITION"]).astype(np.float64)
            if not np.isfinite(pos).all():
                raise GltfError(f"{scene_path}: {name} has a non-finite vertex")
            idx = (read_accessor(doc, buffers, prim["indices"]).reshape(-1).astype(np.uint32)
                   if "indices" in prim else np.arange(len(pos), dtype=np.uint32))
            faces = triangle_indices(prim.get("mode", 4), idx, name)
            if faces is None or len(faces) == 0:
                continue
            if flip:
                faces = faces[:, ::-1]
            wpos = pos @ world[:3, :3].T + world[:3, 3]
            normals = None
            if "NORMAL" in prim["attributes"]:
                n = read_accessor(doc, buffers, prim["attributes"]["NORMAL"]).astype(np.float64) @ normal_matrix.T
                normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)
            mi = prim.get("material")
            mat = materials[mi] if mi is not None else DEFAULT_MATERIAL
            if mi is not None and mi not in textures:
                textures[mi] = material_textures(doc, buffers, mi, mat, scene_path, outdir)
            texture_file, opacity_file = textures.get(mi, (None, None))
            uvs = None
            if texture_file is not None and "TEXCOORD_0" in prim["attributes"]:
                uvs = read_accessor(doc, buffers, prim["attributes"]["TEXCOORD_0"]).astype(np.float64)
            ply = f"meshes/mesh{mesh_count:03d}.ply"
            mesh_count += 1
            write_ply(os.path.join(outdir, ply), wpos, normals, np.ascontiguousarray(faces), uvs)
            bsdf, emitter = material_xml(mat, f"{scene_path}: material {mi} '{mat.get('name', '')}'",
                                         texture_file, opacity_file)
            face_normals = "" if normals is not None else '<boolean name="face_normals" value="true"/>'
            body.append(f'<shape type="ply" id={quoteattr(f"mesh{mesh_count - 1:03d}")}>'
                        f'<string name="filename" value="{ply}"/>{face_normals}{bsdf}{emitter}</shape>'
                        f'<!-- {name}, material {mat.get("name", "")} -->')
    body += environment_xml(doc, scene_path)
    if camera is None:
        raise GltfError(f"{scene_path}: no perspective camera" +
                        (f" named '{camera_name}'" if camera_name else ""))
    world, yfov = camera
    origin, target, up = look_at(world)
    sensor = (f'<sensor type="perspective"><string name="fov_axis" value="y"/>'
              f'<float name="fov" value="{math.degrees(yfov):.9g}"/>'
              f'<float name="near_clip" value="0.001"/><float name="far_clip" value="1e6"/>'
              f'<transform name="to_world"><lookat origin="{vec(origin)}" target="{vec(target)}" '
              f'up="{vec(up)}"/></transform>'
              f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
              f'<film type="hdrfilm"><integer name="width" value="{width}"/>'
              f'<integer name="height" value="{height}"/><string name="pixel_format" value="rgb"/>'
              f'<rfilter type="box"/></film></sensor>')
    # raysplat's max depth counts path segments; Mitsuba's counts vertices, emitter included.
    # Mitsuba's `path` lets no shadow ray through a cut-out (mask) surface, `volpath` does.
    kind = "volpath" if any(m.get("alphaMode") in ("MASK", "BLEND") for m in materials) else "path"
    integrator = (f'<integrator type="{kind}"><integer name="max_depth" value="{max_depth + 1}"/>'
                  f'<integer name="rr_depth" value="5"/></integrator>')
    xml = ('<?xml version="1.0" encoding="utf-8"?>\n'
           f'<!-- Converted from {os.path.basename(scene_path)} by raysplat scripts/gltf_to_mitsuba.py -->\n'
           '<scene version="3.0.0">\n' + integrator + "\n" + sensor + "\n" + "\n".join(body) + "\n</scene>\n")
    path = os.path.join(outdir, "scene.xml")
    with open(path + ".tmp", "w") as f:
        f.write(xml)
    os.replace(path + ".tmp", path)
    return path


def environment_xml(doc, scene_path):
    """The scene's extras raysplat_sky or raysplat_env as Mitsuba emitters (docs/design.md §4).
    Mitsuba's envmap puts the image's centre column along its local +Z and a quarter from the
    left along +X; raysplat (Blender) along +X and −Z: turned 90° about +Y, less the rotation."""
    scenes = doc.get("scenes", [])
    extras = scenes[doc.get("scene", 0)].get("extras", {}) if scenes else {}
    out = []
    if "raysplat_sky" in extras:
        out.append(f'<emitter type="constant"><rgb name="radiance" value="{rgb(extras["raysplat_sky"])}"/></emitter>')
    if "raysplat_env" in extras:
        path = os.path.abspath(os.path.join(os.path.dirname(scene_path), extras["raysplat_env"]))
        turn = 90.0 - float(extras.get("raysplat_env_rotation", 0.0))
        out.append(f'<emitter type="envmap"><string name="filename" value={quoteattr(path)}/>'
                   f'<float name="scale" value="{float(extras.get("raysplat_env_strength", 1.0)):.9g}"/>'
                   f'<transform name="to_world"><rotate y="1" angle="{turn:.9g}"/></transform></emitter>')
    return out


def light_xml(light, world):
    colour = np.array(light.get("color", [1, 1, 1]), dtype=np.float64) * float(light.get("intensity", 1.0))
    position = world[:3, 3]
    direction = -world[:3, 2] / np.linalg.norm(world[:3, 2])  # lights point down local −Z
    kind = light.get("type")
    if kind == "point":
        return (f'<emitter type="point"><point name="position" value="{vec(position)}"/>'
                f'<rgb name="intensity" value="{rgb(colour)}"/></emitter>')
    if kind == "directional":
        return (f'<emitter type="directional"><vector name="direction" value="{vec(direction)}"/>'
                f'<rgb name="irradiance" value="{rgb(colour)}"/></emitter>')
    if kind == "spot":
        # glTF fades smoothly between inner and outer cone; Mitsuba's spot fades linearly in
        # angle from beam_width to cutoff_angle: close but not identical.
        spot = light.get("spot", {})
        inner = math.degrees(spot.get("innerConeAngle", 0.0))
        outer = math.degrees(spot.get("outerConeAngle", math.pi / 4))
        up = world[:3, 1] / np.linalg.norm(world[:3, 1])
        return (f'<emitter type="spot"><rgb name="intensity" value="{rgb(colour)}"/>'
                f'<float name="cutoff_angle" value="{outer:.9g}"/>'
                f'<float name="beam_width" value="{inner:.9g}"/>'
                f'<transform name="to_world"><lookat origin="{vec(position)}" '
                f'target="{vec(position + direction)}" up="{vec(up)}"/></transform></emitter>')
    raise GltfError(f"light '{light.get('name', '')}' has unknown type '{kind}'")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="glTF 2.0 scene (.gltf or .glb)")
    ap.add_argument("outdir", help="directory for scene.xml and meshes/")
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=256)
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of the sensor")
    ap.add_argument("--camera", help="name of the camera node (default: the first perspective camera)")
    args = ap.parse_args()
    try:
        print(convert(args.scene, args.outdir, args.width, args.height, args.spp, args.camera))
    except (GltfError, KeyError, IndexError, ValueError) as e:
        sys.exit(f"error: {e}")


if __name__ == "__main__":
    main()
