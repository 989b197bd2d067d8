#!/usr/bin/env python3
"""Renders a glTF scene with Blender's Cycles, as Blender's own glTF importer reads it, and with
raysplat, and checks that the images agree (docs/testing.md).

usage: blender_cycles_check.py [SCENE.gltf] [--width 128] [--samples 64] [--raysplat BINARY]
                               [--keep DIR]

SCENE defaults to data/textured_room.gltf. Each renderer renders the scene twice, with two
seeds (raysplat its default method, photon ray splatting): the two halves give each one's own
noise. The checks: the image mean of raysplat is within 3 % of Cycles' (every channel and all
together), and the 8×8-pixel block means differ by no more than their noise and a stated bias:
relative MSE of the blocks ≤ AGREE_RATIO (validate_mitsuba.py) × the two renderers' noise +
BLOCK_BIAS², a stated 1 % RMS. Measured at 128×96, 64 samples a half: textured_room's means
0.6 % apart, its blocks 2.1 % RMS apart against 1.8 % noise (ratio 1.40); with Cycles at 256
samples a half, 1.2 % RMS is left besides the noise. Reading the normal maps otherwise than
Cycles does shows here: one normal for both lobes, the geometric one where the mapped normal
faces away from the viewer, leaves the floor near the camera 8–13 % darker (3.2 × noise); glTF's
fresnel_mix in the place of Cycles' albedo scaling makes a floor of roughness 0.3 5–12 %
brighter.

Cycles is set up as raysplat renders: the glTF camera at the image size, a box pixel filter of
one pixel, every bounce up to raysplat's 32 path vertices, no clamping, no glossy filter, no
denoiser, no adaptive sampling; the EXR is linear. Emission is radiance in both (the importer's
strength times colour); punctual lights come in with the importer's "Non-physical" units
(COMPAT: a point light of I W/sr becomes 4π I W, a sun of E W/m² a strength E), raysplat's
radiometric reading of KHR_lights_punctual.
Where the glTF leaves the reading to the renderer, this check makes Cycles read the file as
raysplat does (docs/usage.md's feature table):
- emission leaves the front face only: glTF culls a single-sided material's back faces,
  Cycles' Emission would shine from both; a Backfacing node turns it off behind;
- a material of metallic 0, roughness 1 and no metallic-roughness texture is Lambert in
  raysplat: its Principled BSDF gets a Specular IOR Level of 0 (no specular layer).
- an 8-bit sRGB image (base colour, emissive) is decoded to linear before Cycles filters it, as
  glTF reads it: Cycles filters such an image's encoded texels and decodes after, which darkens
  every edge between texels (the 64×36 colour bars of the screen, four texels a pixel, lost
  2.4 % of their light, and the room 2.4 % with them); it is replaced by a float image of its
  linear values.
Everything else is the importer's Principled BSDF as it makes it: the dielectric specular of
F0 = 0.04 over the diffuse (raysplat layers them as Cycles does, docs/design.md §3), metals, normal maps (tangents by MikkTSpace, green up; Cycles
4.2 shades a bump-mapped diffuse closure with Chiang et al.'s 2019 bump shadowing, as raysplat
does: a Lambert plane under a sun, its normal map tilted 30° towards it, renders at 0.4380,
0.9194 and 0.7648 of plain n·l at three sun elevations, the term's values to 4 digits; its
diffuse closure keeps the mapped normal where it faces away from the viewer and its specular
closures bend it until the viewer's reflection clears the surface, as raysplat does,
docs/design.md §3), the
emissive texture and strength, COLOR_0 times the base colour, alpha MASK by a math node.

Exit status: 0 PASS, 1 FAIL, 77 skipped (bpy cannot be imported; with
RAYSPLAT_REQUIRE_BLENDER=1, as CI sets it, that is a failure too).
"""

import argparse
import json
import os
import struct
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blender_check import FAIL, ROOT, begin_check, exit_without_teardown, reexec_under_bpy_python  # noqa: E402

MEAN_TOLERANCE = 0.03
BLOCK_BIAS = 0.01  # RMS relative difference of the block means allowed besides noise (docstring)
MAX_VERTICES = 32  # raysplat's --max-depth default: its longest path
SEEDS = (1, 2)


def say(msg):
    print(f"blender_cycles_check: {msg}", flush=True)


def gltf_document(path):
    """The JSON of a .gltf or .glb file."""
    data = Path(path).read_bytes()
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        return json.loads(data[20:20 + length])
    return json.loads(data)


def raysplat_lambert(m):
    """Whether raysplat renders glTF material m as Lambert (lib/scene/gltf_materials.cpp)."""
    pbr = m.get("pbrMetallicRoughness", {})
    transmission = m.get("extensions", {}).get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    return (pbr.get("metallicFactor", 1.0) <= 0.0 and pbr.get("roughnessFactor", 1.0) >= 1.0
            and "metallicRoughnessTexture" not in pbr and transmission < 0.5)


def front_emission_only(mat):
    """Multiplies the Principled BSDF's Emission Strength by 1 − Backfacing."""
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    socket = bsdf.inputs["Emission Strength"] if bsdf else None
    if socket is None or socket.is_linked or socket.default_value == 0.0:
        return False
    geometry = nodes.new("ShaderNodeNewGeometry")
    front = nodes.new("ShaderNodeMath")
    front.operation = "SUBTRACT"
    front.inputs[0].default_value = 1.0
    links.new(geometry.outputs["Backfacing"], front.inputs[1])
    strength = nodes.new("ShaderNodeMath")
    strength.operation = "MULTIPLY"
    strength.inputs[0].default_value = socket.default_value
    links.new(front.outputs[0], strength.inputs[1])
    links.new(strength.outputs[0], socket)
    mat.cycles.emission_sampling = "FRONT"
    return True


def linear_float_images(bpy):
    """Every 8-bit sRGB image as a float image of its linear values (the docstring). Returns the
    names of the images converted."""
    import numpy as np
    converted = []
    for image in list(bpy.data.images):
        if image.is_float or image.colorspace_settings.name != "sRGB":
            continue
        w, h = image.size
        if w == 0 or h == 0:
            continue
        px = np.empty(w * h * 4, np.float32)
        image.pixels.foreach_get(px)
        rgb = px.reshape(-1, 4)[:, :3]
        px.reshape(-1, 4)[:, :3] = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
        linear = bpy.data.images.new(image.name + " linear", w, h, alpha=True, float_buffer=True)
        linear.colorspace_settings.name = "Linear Rec.709"
        linear.alpha_mode = image.alpha_mode
        linear.pixels.foreach_set(px)
        image.user_remap(linear)
        converted.append(image.name)
    return converted


def read_as_raysplat(bpy, doc):
    """The two readings of the docstring, on the imported materials. Returns what was changed."""
    by_name = {m.get("name"): m for m in doc.get("materials", [])}
    changed = {"lambert": [], "front emission": []}
    for mat in bpy.data.materials:
        if not mat.use_nodes:
            continue
        gltf = by_name.get(mat.name.split(".")[0])
        bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
        if gltf is not None and bsdf is not None and raysplat_lambert(gltf):
            bsdf.inputs["Specular IOR Level"].default_value = 0.0
            changed["lambert"].append(mat.name)
        if front_emission_only(mat):
            changed["front emission"].append(mat.name)
    return changed


def setup_cycles(bpy, scene, width, height, samples, camera_name):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.sample_clamp_direct = scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.blur_glossy = 0.0
    bounces = MAX_VERTICES - 1
    scene.cycles.max_bounces = scene.cycles.diffuse_bounces = scene.cycles.glossy_bounces = bounces
    scene.cycles.transmission_bounces = scene.cycles.transparent_max_bounces = bounces
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = len(os.sched_getaffinity(0))
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    cameras = [o for o in scene.objects if o.type == "CAMERA"]
    scene.camera = next((o for o in cameras if o.data.name == camera_name), cameras[0] if cameras else None)
    return scene.camera is not None


def render_raysplat(binary, scene_path, out, width, height, seed):
    cmd = [binary, "render", str(scene_path), "-o", str(out), "--width", str(width), "--height", str(height),
           "--seed", str(seed), "--quiet"]
    say("running " + " ".join(cmd))
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stderr.strip()


def compare(c, images, ours, theirs, block):
    """The mean and block checks on two pairs of halves (lists of H×W×3 arrays)."""
    import numpy as np
    from validate_mitsuba import AGREE_RATIO, block_agreement, ratio
    a, b = 0.5 * (ours[0] + ours[1]), 0.5 * (theirs[0] + theirs[1])
    for name, k in (("R", 0), ("G", 1), ("B", 2), ("RGB", slice(None))):
        ma, mb = float(a[..., k].mean()), float(b[..., k].mean())
        c.check(mb > 0 and abs(ma / mb - 1) <= MEAN_TOLERANCE,
                f"mean {name}: raysplat {ma:.5g}, Cycles {mb:.5g}, ratio {ma / max(mb, 1e-12):.4f} (within {MEAN_TOLERANCE:.0%})")
    _, _, err, noise = block_agreement(ours, theirs)
    limit = AGREE_RATIO * noise + BLOCK_BIAS ** 2
    c.check(err <= limit, f"{block}×{block} block means: relMSE {err:.3e} (RMS {np.sqrt(err):.1%}), noise {noise:.3e} "
                          f"(ratio {ratio(err, noise):.2f}), at most {AGREE_RATIO} × noise + {BLOCK_BIAS:.0%}²")
    return a, b


def picture(images, studyutil, a, b, block, path):
    """raysplat | Cycles | block means' relative difference, red where raysplat is brighter and
    blue where darker (full at 10 %)."""
    import numpy as np
    e = images.auto_exposure(b)
    ab, bb = studyutil.block_means(a, block).mean(-1), studyutil.block_means(b, block).mean(-1)
    d = np.clip((ab - bb) / (np.abs(bb) + 1e-2) / 0.1, -1, 1)
    zmap = studyutil.upscale(np.stack([np.maximum(d, 0), np.zeros_like(d), np.maximum(-d, 0)], -1) * 255, block)
    pad = np.full((a.shape[0], 4, 3), 255, np.uint8)
    rgb = np.hstack([images.to_srgb8(a, e), pad, images.to_srgb8(b, e), pad,
                     zmap[:a.shape[0], :a.shape[1]].astype(np.uint8)])
    from gltf_builder import png_rgba  # stdlib only: bpy's Python has no PIL
    path.write_bytes(png_rgba(rgb.shape[1], rgb.shape[0], lambda x, y: tuple(int(v) for v in rgb[y, x]) + (255,)))


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", nargs="?", default=str(ROOT / "data" / "textured_room.gltf"))
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--samples", type=int, default=64, help="Cycles samples a pixel, each half")
    p.add_argument("--raysplat", default=os.environ.get("RAYSPLAT"), help="the raysplat binary (default $RAYSPLAT)")
    p.add_argument("--keep", help="keep the renders and a comparison picture in this directory")
    return p.parse_args()


def main():
    reexec_under_bpy_python(__file__)
    a = parse_args()
    begun = begin_check("blender_cycles_check", a.raysplat, a.keep)
    if isinstance(begun, int):
        return begun
    bpy, a.raysplat, c, work = begun
    import images
    import studyutil
    scene_path = Path(a.scene).resolve()
    doc = gltf_document(scene_path)
    cam = (doc.get("cameras") or [{}])[0]
    aspect = cam.get("perspective", {}).get("aspectRatio", 1.5)
    width, height = a.width, max(1, round(a.width / aspect))
    say(f"Blender {bpy.app.version_string}: {scene_path.name} at {width}×{height}, Cycles {a.samples} samples a half")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=str(scene_path), export_import_convert_lighting_mode="COMPAT")
    c.check("FINISHED" in result, f"Blender's glTF importer reads {scene_path.name}")
    changed = read_as_raysplat(bpy, doc)
    say(f"decoded to linear before filtering: {linear_float_images(bpy)}")
    say(f"read as raysplat does: Lambert {changed['lambert']}, front-only emission {changed['front emission']}")
    scene = bpy.context.scene
    if not c.check(setup_cycles(bpy, scene, width, height, a.samples, cam.get("name")), "the scene has a camera"):
        return FAIL

    ours, theirs = [], []
    for seed in SEEDS:
        scene.cycles.seed = seed
        scene.render.filepath = str(work / f"cycles_{seed}.exr")
        bpy.ops.render.render(write_still=True)
        theirs.append(images.read_layers(scene.render.filepath)["beauty"])
        out = work / f"raysplat_{seed}.exr"
        rc, err = render_raysplat(a.raysplat, scene_path, out, width, height, seed)
        if not c.check(rc == 0, f"raysplat renders with seed {seed} {err[:200]}".rstrip()):
            return c.finish("blender_cycles_check")
        ours.append(images.read_layers(str(out))["beauty"])
    from validate_mitsuba import BLOCK
    mean_ours, mean_theirs = compare(c, images, ours, theirs, BLOCK)
    if a.keep:
        picture(images, studyutil, mean_ours, mean_theirs, BLOCK, work / "raysplat_vs_cycles.png")
        say(f"wrote {work / 'raysplat_vs_cycles.png'} (raysplat | Cycles | block difference, bright ≥ 10 %)")
    return c.finish("blender_cycles_check", f"raysplat renders {scene_path.name} as Cycles does")


if __name__ == "__main__":
    exit_without_teardown(main())
