"""The textured interior of scripts/make_scenes.py (data/textured_room.gltf): a closed
4 x 2.6 x 4 m room lit by a ceiling panel and an emissive screen, whose materials use every
texture of the glTF metallic-roughness model, for the comparison with Blender's Cycles
(scripts/blender_cycles_check.py).

  floor    tiles of four planks: a normal map of bevelled planks (a sawtooth along the
           image's +X), a base colour texture (two tones of wood), a metallic-roughness
           texture (roughness 0.3 and 0.8 by plank, no metal)
  walls    a normal map of horizontal ridges (a sawtooth along the image's +Y, so that
           a normal map read upside down is darker under the ceiling light), a
           metallic-roughness texture with a band of brushed metal at 0.9-1.1 m
  screen   an emissive texture of colour bars over a grey ramp, emissiveFactor times
           KHR_materials_emissive_strength
  ball     a sphere whose COLOR_0 vertex colours run through the hues
  plant    alpha-MASK leaves (a cut-out texture) under the ceiling panel: their shadow
           falls on the floor

No TANGENTs are written: both renderers compute them (MikkTSpace's conventions). Textures
are 64-128 px PNGs in the .bin; the file stays under 100 kB.
"""

import math

from gltf_builder import (X, Y, Z, GltfBuilder, box_maker, leaf_png, mul, normalize,
                          png_rgba, plant_leaves, quad_node, rect, uv_sphere)

ROOM_X, ROOM_H, ROOM_Z = 2.0, 2.6, 2.0  # x, z in [-ROOM_X, ROOM_X] x [-ROOM_Z, ROOM_Z]


def byte(x):
    return max(0, min(255, int(round(x * 255.0))))


def normal_rgb(n):
    """A unit tangent-space normal (x towards +u, y towards the image's top, z out) as bytes."""
    n = normalize(n)
    return tuple(byte(0.5 * c + 0.5) for c in n)


def srgb_byte(linear):
    c = linear * 12.92 if linear <= 0.0031308 else 1.055 * linear ** (1 / 2.4) - 0.055
    return byte(c)


def floor_normal_png(size=128):
    """Four planks across the image (along x), each bevelled: 70 % of it rises gently towards
    +x and the rest falls steeply (a sawtooth height field), and a groove along the image's
    top and bottom rows."""
    def pixel(x, y):
        f = (x + 0.5) / size * 4.0 % 1.0
        n = (-0.35, 0.0, 1.0) if f < 0.7 else (0.8, 0.0, 1.0)
        if y < 3:
            n = (0.0, -0.9, 1.0)
        elif y >= size - 3:
            n = (0.0, 0.9, 1.0)
        return normal_rgb(n) + (255,)
    return png_rgba(size, size, pixel)


def floor_colour_png(size=64):
    """Two tones of wood, plank by plank (sRGB)."""
    tones = [(0.55, 0.38, 0.22), (0.42, 0.27, 0.15), (0.5, 0.34, 0.2), (0.38, 0.25, 0.14)]

    def pixel(x, y):
        t = tones[int((x + 0.5) / size * 4.0) % 4]
        return tuple(srgb_byte(c) for c in t) + (255,)
    return png_rgba(size, size, pixel)


def floor_mr_png(size=64):
    """Roughness (G) 0.3 on planks 0 and 2, 0.8 on 1 and 3; metal (B) 0."""
    def pixel(x, y):
        rough = 0.3 if int((x + 0.5) / size * 4.0) % 2 == 0 else 0.8
        return (255, byte(rough), 0, 255)
    return png_rgba(size, size, pixel)


def wall_normal_png(size=128, ridges=16):
    """Horizontal ridges, `ridges` over the image's height: 75 % of each faces up (towards the
    image's top) at 27°, 25 % faces down at 56°."""
    def pixel(x, y):
        f = (y + 0.5) / size * ridges % 1.0  # 0 at a ridge's top edge, growing downwards
        n = (0.0, -1.5, 1.0) if f < 0.25 else (0.0, 0.5, 1.0)
        return normal_rgb(n) + (255,)
    return png_rgba(8, size, pixel)


def wall_mr_png(size=128):
    """Roughness 0.6, no metal, but for a band of metal of roughness 0.35 from 0.9 to 1.1 m
    (the image spans the wall's height, its top row at the ceiling)."""
    def pixel(x, y):
        height = ROOM_H * (1.0 - (y + 0.5) / size)
        metal = 0.9 <= height <= 1.1
        return (255, byte(0.35 if metal else 0.6), 255 if metal else 0, 255)
    return png_rgba(8, size, pixel)


def screen_png(width=64, height=36):
    """Seven colour bars over a grey ramp (sRGB), black at the image's right edge column."""
    bars = [(1, 1, 1), (1, 1, 0), (0, 1, 1), (0, 1, 0), (1, 0, 1), (1, 0, 0), (0, 0, 1)]

    def pixel(x, y):
        if y < height * 2 // 3:
            c = bars[x * len(bars) // width]
            return tuple(255 * k for k in c) + (255,)
        v = srgb_byte(x / (width - 1))
        return (v, v, v, 255)
    return png_rgba(width, height, pixel)


def hue(t):
    """A saturated colour of hue t in [0, 1) (linear RGB)."""
    r = 0.5 + 0.5 * math.cos(2 * math.pi * t)
    g = 0.5 + 0.5 * math.cos(2 * math.pi * (t - 1 / 3))
    b = 0.5 + 0.5 * math.cos(2 * math.pi * (t - 2 / 3))
    return (0.1 + 0.8 * r, 0.1 + 0.8 * g, 0.1 + 0.8 * b)


def textured(g, name, base, metallic, roughness, normal=None, mr=None, colour=None):
    """A material with textures (PNG bytes) in the normal, metallic-roughness and base colour
    slots."""
    m = g.doc["materials"][g.material(name, base, metallic, roughness)]
    if normal is not None:
        m["normalTexture"] = {"index": g.png_texture(name + "_normal", normal), "scale": 1.0}
    if mr is not None:
        m["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {"index": g.png_texture(name + "_mr", mr)}
    if colour is not None:
        m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": g.png_texture(name + "_colour", colour)}
    return g.doc["materials"].index(m)


def room_shell(g):
    """Floor, ceiling and four walls, normals into the room. The floor's UVs repeat its texture
    once a metre; a wall's u runs 1 a metre along it (left to right, seen from the room) and
    its v from 0 at the ceiling to 1 at the floor, so the image's top is up."""
    floor = textured(g, "floor", (1.0, 1.0, 1.0), 1.0, 1.0, normal=floor_normal_png(),
                     mr=floor_mr_png(), colour=floor_colour_png())
    wall = textured(g, "wall", (0.72, 0.7, 0.64), 1.0, 1.0, normal=wall_normal_png(), mr=wall_mr_png())
    ceiling = g.material("ceiling", (0.8, 0.8, 0.8))

    def uvs_of(pos, u_axis, v_of):
        return [(sum(p[k] * u_axis[k] for k in range(3)), v_of(p)) for p in pos]

    geom = rect((0, 0, 0), mul(X, ROOM_X), mul(Z, ROOM_Z), Y)
    g.node("floor", mesh=g.mesh("floor", geom, floor, uvs=uvs_of(geom[0], X, lambda p: p[2])))
    quad_node(g, "ceiling", rect((0, ROOM_H, 0), mul(X, ROOM_X), mul(Z, ROOM_Z), mul(Y, -1)), ceiling)
    half = ROOM_H / 2
    for name, centre, along, inward in (
            ("back_wall", (0, half, -ROOM_Z), X, Z),
            ("front_wall", (0, half, ROOM_Z), mul(X, -1), mul(Z, -1)),
            ("left_wall", (-ROOM_X, half, 0), mul(Z, -1), X),
            ("right_wall", (ROOM_X, half, 0), Z, mul(X, -1))):
        geom = rect(centre, mul(along, ROOM_X), mul(Y, half), inward)
        g.node(name, mesh=g.mesh(name, geom, wall,
                                 uvs=uvs_of(geom[0], along, lambda p: (ROOM_H - p[1]) / ROOM_H)))


def plant(g, box, x, z):
    """A pot, a stem and ten alpha-masked leaves, 0.75-1.2 m up."""
    clay = g.material("pot", (0.55, 0.3, 0.2))
    stem = g.material("stem", (0.3, 0.22, 0.1))
    leaf = g.material("leaf", (1.0, 1.0, 1.0))
    m = g.doc["materials"][leaf]
    m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": g.png_texture("leaf", leaf_png())}
    m["alphaMode"] = "MASK"
    m["alphaCutoff"] = 0.5
    m["doubleSided"] = True
    box("pot", clay, (x - 0.14, 0, z - 0.14), (x + 0.14, 0.3, z + 0.14))
    box("stem", stem, (x - 0.01, 0.3, z - 0.01), (x + 0.01, 1.25, z + 0.01))
    plant_leaves(g, leaf, x, z, 0.75, 0.2, 0.3, 0.09)


def textured_room(path):
    g = GltfBuilder("textured_room")
    room_shell(g)
    box = box_maker(g)
    # The ceiling panel, 1 cm below the ceiling, and the screen, 2 cm off the left wall in
    # a dark bezel.
    panel = g.material("panel", (0.0, 0.0, 0.0), emissive=(1.0, 0.9, 0.75), strength=40.0)
    quad_node(g, "panel", rect((0.3, ROOM_H - 0.01, 0.3), mul(X, 0.25), mul(Z, 0.25), mul(Y, -1)), panel)
    screen = g.material("screen", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), strength=6.0)
    g.doc["materials"][screen]["emissiveTexture"] = {"index": g.png_texture("screen", screen_png())}
    bezel = g.material("bezel", (0.05, 0.05, 0.05), roughness=0.4)
    sx, sy, sz, hw, hh = -ROOM_X + 0.04, 1.35, -0.6, 0.6, 0.34
    box("bezel", bezel, (-ROOM_X, sy - hh - 0.03, sz - hw - 0.03), (sx, sy + hh + 0.03, sz + hw + 0.03))
    geom = rect((sx + 0.001, sy, sz), mul(Z, -hw), mul(Y, hh), X)
    uvs = [(1.0 - (p[2] - sz + hw) / (2 * hw), (sy + hh - p[1]) / (2 * hh)) for p in geom[0]]
    g.node("screen", mesh=g.mesh("screen", geom, screen, uvs=uvs))
    # The vertex-coloured ball on a plinth.
    plinth = g.material("plinth", (0.7, 0.7, 0.7))
    box("plinth", plinth, (0.55, 0, -1.05), (1.05, 0.4, -0.55))
    white = g.material("ball", (1.0, 1.0, 1.0))
    geom = uv_sphere(0.22, segments=32, rings=16)
    colours = [hue(math.atan2(n[2], n[0]) / (2 * math.pi) % 1.0) for n in geom[1]]
    g.node("ball", mesh=g.mesh("ball", geom, white, colors=colours), t=(0.8, 0.62, -0.8))
    plant(g, box, -0.4, 0.1)
    g.camera("camera", eye=(1.75, 1.55, 1.8), target=(-0.9, 0.75, -0.9), yfov=1.1, aspect=4 / 3)
    g.write_gltf(path)
    return g
