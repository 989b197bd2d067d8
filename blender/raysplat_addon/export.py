"""The open scene as the raysplat command takes it: a .glb from Blender's own glTF exporter,
with area lamps turned into emissive quads of the same power (the exporter drops them), and
the world's sky as command-line options."""

import math
import os

import bpy

# Blender's exporter writes lamps in these units with this mode: a point or spot lamp of P W as
# P / 4π W/sr, a sun of S W/m² as S, which is how raysplat reads KHR_lights_punctual.
LIGHTING_MODE = "COMPAT"
# A walkthrough's export: the objects' active actions as one glTF animation, sampled at every
# frame of the scene's range (so that frame n of the file is Blender's frame n, whatever the
# keys' interpolation, Euler rotations included); objects without an action stay unanimated, so
# that a camera walk keeps raysplat's photons from frame to frame. (The exporter's SCENE mode,
# which would bake every object, fails on scenes with lamps in Blender 4.2.)
ANIMATION = dict(export_animations=True, export_animation_mode="ACTIVE_ACTIONS", export_force_sampling=True,
                 export_frame_range=True, export_frame_step=1)


def _area_lamp_quad(obj, collection):
    """An emissive rectangle for an area lamp: radiance P / (π A) × colour (a Lambertian emitter
    of power P), facing the lamp's −Z as the lamp does."""
    lamp = obj.data
    sx = lamp.size
    sy = lamp.size_y if lamp.shape in ("RECTANGLE", "ELLIPSE") else lamp.size
    area = sx * sy * (math.pi / 4 if lamp.shape in ("DISK", "ELLIPSE") else 1.0)
    if lamp.shape in ("DISK", "ELLIPSE"):  # a rectangle of the same area and aspect
        sx, sy = sx * math.sqrt(math.pi) / 2, sy * math.sqrt(math.pi) / 2
    radiance = lamp.energy / (math.pi * area) if area > 0 else 0.0
    mesh = bpy.data.meshes.new(f"raysplat_area_{obj.name}")
    h = (sx / 2, sy / 2)
    # Counter-clockwise seen from −Z, so the face's normal is the lamp's −Z.
    mesh.from_pydata([(-h[0], -h[1], 0), (-h[0], h[1], 0), (h[0], h[1], 0), (h[0], -h[1], 0)], [], [(0, 1, 2, 3)])
    mat = bpy.data.materials.new(f"raysplat_area_{obj.name}")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1)
    bsdf.inputs["Emission Color"].default_value = (*lamp.color, 1)
    bsdf.inputs["Emission Strength"].default_value = radiance
    mesh.materials.append(mat)
    quad = bpy.data.objects.new(mesh.name, mesh)
    quad.matrix_world = obj.matrix_world.copy()
    collection.objects.link(quad)
    return quad, mesh, mat


def world_options(scene, report):
    """--env/--sky options for the world: an Environment Texture (OpenEXR or .hdr; through a Mapping node's Z
    rotation, if any) into a Background's Color, times its Strength; or a plain colour."""
    world = scene.world
    if world is None or not world.use_nodes or world.node_tree is None:
        return []
    nodes = world.node_tree.nodes
    output = next((n for n in nodes if n.type == "OUTPUT_WORLD" and n.is_active_output), None)
    surface = output.inputs["Surface"].links if output else []
    if not surface or surface[0].from_node.type != "BACKGROUND":
        return []
    bg = surface[0].from_node
    strength = bg.inputs["Strength"].default_value
    color = bg.inputs["Color"]
    if not color.links:
        rgb = [c * strength for c in color.default_value[:3]]
        return ["--sky", ",".join(f"{c:.9g}" for c in rgb)] if any(c > 0 for c in rgb) else []
    tex = color.links[0].from_node
    if tex.type != "TEX_ENVIRONMENT" or tex.image is None:
        report({"WARNING"}, f"raysplat: the world's colour comes from a {tex.type} node; only an Environment Texture is read")
        return []
    path = bpy.path.abspath(tex.image.filepath)
    if not path.lower().endswith((".exr", ".hdr")):
        report({"WARNING"}, f"raysplat: the world's image {os.path.basename(path)} is neither OpenEXR nor Radiance .hdr, "
                             "the skies raysplat reads")
        return []
    rotation = 0.0
    vector = tex.inputs["Vector"].links
    if vector and vector[0].from_node.type == "MAPPING":
        rotation = math.degrees(vector[0].from_node.inputs["Rotation"].default_value[2])
    return ["--env", path, "--env-strength", f"{strength:.9g}", "--env-rotation", f"{rotation:.9g}"]


def export_glb(context, path, animation=False):
    """Writes the scene to `path` with the glTF exporter: renderable objects, cameras, lamps and
    custom properties (raysplat_portal). Area lamps go as emissive quads, removed afterwards.
    With `animation`, the scene as it plays: every object's action sampled at each frame of the
    scene's range into one glTF animation, frame n at time n / (fps × fps_base)."""
    scene = context.scene
    temporary = []
    try:
        for obj in scene.objects:
            if obj.type == "LIGHT" and obj.data.type == "AREA" and not obj.hide_render:
                temporary.append(_area_lamp_quad(obj, scene.collection))
        with context.temp_override(scene=scene):
            bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", use_renderable=True, export_cameras=True,
                                      export_lights=True, export_extras=True, export_apply=True, export_yup=True,
                                      export_import_convert_lighting_mode=LIGHTING_MODE,
                                      **(ANIMATION if animation else {}))
    finally:
        for quad, mesh, mat in temporary:
            bpy.data.objects.remove(quad)
            bpy.data.meshes.remove(mesh)
            bpy.data.materials.remove(mat)


def resolution(scene):
    r = scene.render
    return max(1, r.resolution_x * r.resolution_percentage // 100), max(1, r.resolution_y * r.resolution_percentage // 100)
