#!/usr/bin/env python3
"""Checks with Blender (bpy) that raysplat's environment light (--env, --env-rotation) is
oriented as Blender's world, so that an HDRI looks the same in both (docs/design.md §4).

usage: blender_env_check.py [--raysplat BINARY] [--keep DIR]

In Blender: an equirectangular image whose red is the pixel's column and green its row (as
fractions, from the left and from the top), as the world's Environment Texture (Closest), and
cameras of a narrow view looking in several directions. Each camera's centre pixel is rendered
with Cycles; the scene is exported with Blender's glTF exporter and each camera rendered by
`raysplat render --method path --env IMAGE`: both must read the same pixel of the image. Then
the same with a Mapping node turning the world 30° about Z against `--env-rotation 30`.

Exit status: 0 PASS, 1 FAIL, 77 skipped (bpy cannot be imported; with
RAYSPLAT_REQUIRE_BLENDER=1, as CI sets it, that is a failure too).
"""

import argparse
import math
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_check  # noqa: E402
from blender_check import exit_without_teardown  # noqa: E402

W, H = 64, 32
ROTATION = 30.0  # degrees
# Directions in Blender's frame (Z up), none on a pixel's border.
DIRECTIONS = {"east": (1.0, 0.13, 0.07), "north": (0.11, 1.0, 0.05), "west": (-1.0, -0.21, 0.12),
              "south": (0.17, -1.0, -0.09), "high": (0.3, -0.5, 0.8), "low": (-0.52, 0.34, -0.6)}


def make_image(path):
    import numpy as np
    import OpenEXR

    rgb = np.zeros((H, W, 3), dtype=np.float32)
    rgb[:, :, 0] = (np.arange(W) + 0.5) / W
    rgb[:, :, 1] = ((np.arange(H) + 0.5) / H)[:, None]
    header = {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}
    OpenEXR.File(header, {"RGB": rgb}).write(str(path))


def setup_scene(bpy, image_path):
    import mathutils

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = 4
    scene.render.filter_size = 0.01
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    # Something for the glTF file to hold, out of every camera's view.
    mesh = bpy.data.meshes.new("speck")
    mesh.from_pydata([(0, 0, 0), (0.01, 0, 0), (0, 0.01, 0)], [], [(0, 1, 2)])
    speck = bpy.data.objects.new("speck", mesh)
    scene.collection.objects.link(speck)
    speck.location = (0.0, 0.0, -30.0)
    world = bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    nodes = world.node_tree.nodes
    tex = nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(str(image_path))
    tex.image.colorspace_settings.name = "Non-Color"
    tex.interpolation = "Closest"
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    world.node_tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    world.node_tree.links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    world.node_tree.links.new(tex.outputs["Color"], nodes["Background"].inputs["Color"])
    for name, d in DIRECTIONS.items():
        cam = bpy.data.cameras.new(name)
        cam.lens_unit = "FOV"
        cam.angle = 0.004
        obj = bpy.data.objects.new(name, cam)
        scene.collection.objects.link(obj)
        obj.rotation_euler = mathutils.Vector(d).normalized().to_track_quat("-Z", "Y").to_euler()
    return scene, mapping


def centre_pixel(path):
    """Red and green of pixel (1, 1) of the EXR's beauty (every pixel sees the same image pixel)."""
    import OpenEXR

    channels = OpenEXR.File(str(path)).channels()
    rgb = channels["RGB"].pixels if "RGB" in channels else channels["RGBA"].pixels
    return float(rgb[1, 1, 0]), float(rgb[1, 1, 1])


def main():
    blender_check.reexec_under_bpy_python(__file__)
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--raysplat", default=os.environ.get("RAYSPLAT"), help="the raysplat binary (default $RAYSPLAT)")
    p.add_argument("--keep", help="keep the files in this directory")
    a = p.parse_args()
    begun = blender_check.begin_check("blender_env_check", a.raysplat, a.keep)
    if isinstance(begun, int):
        return begun
    bpy, a.raysplat, c, work = begun
    image_path = work / "uv.exr"
    make_image(image_path)
    scene, mapping = setup_scene(bpy, image_path)
    glb = work / "cameras.glb"
    bpy.ops.export_scene.gltf(filepath=str(glb), export_format="GLB", export_cameras=True)
    for rotation in (0.0, ROTATION):
        mapping.inputs["Rotation"].default_value[2] = math.radians(rotation)
        for name in DIRECTIONS:
            scene.camera = bpy.data.objects[name]
            scene.render.filepath = str(work / f"cycles_{name}_{rotation:g}.exr")
            bpy.ops.render.render(write_still=True)
            want = centre_pixel(scene.render.filepath)
            out = work / f"raysplat_{name}_{rotation:g}.exr"
            cmd = [a.raysplat, "render", str(glb), "-o", str(out), "--camera", name, "--method", "path",
                   "--spp", "1", "--width", "4", "--height", "4", "--env", str(image_path),
                   "--env-rotation", f"{rotation:g}", "--quiet"]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if not c.check(r.returncode == 0, f"raysplat renders camera {name}: {r.stderr.strip()[:200]}"):
                continue
            got = centre_pixel(out)
            c.check(abs(got[0] - want[0]) < 2e-3 and abs(got[1] - want[1]) < 2e-3,
                    f"{name}, turned {rotation:g}°: raysplat reads column/row ({got[0]:.4f}, {got[1]:.4f}), "
                    f"Cycles ({want[0]:.4f}, {want[1]:.4f})")
    return c.finish("blender_env_check", "raysplat's --env and --env-rotation look as Blender's world")


if __name__ == "__main__":
    exit_without_teardown(main())
