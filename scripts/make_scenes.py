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

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_builder import (X, Y, Z, GltfBuilder, box_maker, cross, dot, f32, icosahedron, leaf_png,  # noqa: E402
                          merge, mul, normalize, plant_leaves, quad_node, quat_axis_angle, quat_between, quat_mul, rect, sub,
                          unit_cube, uv_sphere, vec)


# --------------------------------------------------------------------------
# Scenes

WHITE = (0.75, 0.75, 0.75)
LIGHT_RGB, LIGHT_STRENGTH = (1.0, 0.78, 0.5), 25.0


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
    plant_leaves(g, leaf, px, pz, 0.65, 0.16, 0.35, 0.07)
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
