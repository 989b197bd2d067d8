#!/usr/bin/env python3
"""Memory and load time of a textured interior: 16 base colour textures of 4096 x 4096.

    python3 scripts/texture_bench.py [--binary build/raysplat] [--binary LABEL=PATH ...]
                                     [--runs 3] [--threads 1] [--dir /tmp/raysplat_texture_bench]
                                     [--size 4096] [--count 16]

Writes (once; later runs reuse it) a room of 8 x 3 x 8 m whose four walls are cut into 16
panels, each with its own material and its own PNG base colour texture (8-bit RGB, a coarse
pattern with random low bits: about as hard for zlib as a photograph), lit by a point light,
seen by a camera in a corner. Renders it with each binary, `--passes 1 --width 300`, under
`/usr/bin/time -v`, and prints medians of --runs: peak resident memory, the load time
(`--stats-json`'s "load"), and the whole command's wall time. Run it under `taskset -c 0` to
pin it to one core, as docs/performance.md's figures are. Stdlib only.
"""
import argparse
import json
import os
import random
import re
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def write_texture(path, size, seed):
    """An RGB PNG: 64 bands of a per-image pattern (high 5 bits), XOR random low 3 bits per byte."""
    rng = random.Random(seed)
    k = [rng.randrange(1, 97) for _ in range(6)]
    bands = []
    for b in range(64):
        row = bytearray(3 * size)
        for x in range(size):
            for c in range(3):
                row[3 * x + c] = ((x * k[c] // 16 + b * k[c + 3] * 8) & 0xF8)
        bands.append(int.from_bytes(row, "little"))
    low = bytes(v & 7 for v in range(256))
    rows = []
    for y in range(size):
        noise = int.from_bytes(rng.randbytes(3 * size).translate(low), "little")
        rows.append(b"\x00" + (bands[(y * 64) // size] ^ noise).to_bytes(3 * size, "little"))
    ihdr = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    data = PNG_SIGNATURE + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", zlib.compress(b"".join(rows), 6))
    with open(path, "wb") as f:
        f.write(data + png_chunk(b"IEND", b""))


def write_room(folder, size, count):
    """room.gltf and its textures; the walls' panels in a ring, count of them (a multiple of 4)."""
    os.makedirs(folder, exist_ok=True)
    positions, uvs, indices, primitives, materials, images = [], [], [], [], [], []
    W, H = 8.0, 3.0
    per_wall = count // 4
    # Walls inward-facing: corners of the floor's square in counter-clockwise order seen from above.
    corners = [(-W / 2, -W / 2), (W / 2, -W / 2), (W / 2, W / 2), (-W / 2, W / 2)]
    for p in range(count):
        wall, part = divmod(p, per_wall)
        (x0, z0), (x1, z1) = corners[wall], corners[(wall + 1) % 4]
        a = (x0 + (x1 - x0) * part / per_wall, z0 + (z1 - z0) * part / per_wall)
        b = (x0 + (x1 - x0) * (part + 1) / per_wall, z0 + (z1 - z0) * (part + 1) / per_wall)
        base = len(positions)
        positions += [(a[0], 0, a[1]), (b[0], 0, b[1]), (b[0], H, b[1]), (a[0], H, a[1])]
        uvs += [(0, 1), (1, 1), (1, 0), (0, 0)]
        # Seen from inside: (a, top a, top b), (a, top b, b) wind counter-clockwise.
        indices.append([base, base + 3, base + 2, base, base + 2, base + 1])
        name = "panel_%02d.png" % p
        if not os.path.exists(os.path.join(folder, name)):
            write_texture(os.path.join(folder, name), size, p)
        images.append({"uri": name})
        materials.append({"name": "panel %d" % p, "pbrMetallicRoughness": {
            "baseColorTexture": {"index": p}, "metallicFactor": 0, "roughnessFactor": 1}})
    # Floor and ceiling, grey.
    base = len(positions)
    for y, up in ((0.0, True), (H, False)):
        b0 = len(positions)
        positions += [(-W / 2, y, -W / 2), (W / 2, y, -W / 2), (W / 2, y, W / 2), (-W / 2, y, W / 2)]
        uvs += [(0, 0)] * 4
        indices.append([b0, b0 + 3, b0 + 2, b0, b0 + 2, b0 + 1] if up else [b0, b0 + 1, b0 + 2, b0, b0 + 2, b0 + 3])
    materials.append({"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1],
                                                                "metallicFactor": 0, "roughnessFactor": 1}})

    blob = b"".join(struct.pack("<3f", *p) for p in positions)
    uv_at = len(blob)
    blob += b"".join(struct.pack("<2f", *t) for t in uvs)
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": uv_at},
             {"buffer": 0, "byteOffset": uv_at, "byteLength": len(blob) - uv_at}]
    lo = [min(p[i] for p in positions) for i in range(3)]
    hi = [max(p[i] for p in positions) for i in range(3)]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3", "min": lo, "max": hi},
                 {"bufferView": 1, "componentType": 5126, "count": len(uvs), "type": "VEC2"}]
    for i, idx in enumerate(indices):
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": 4 * len(idx)})
        blob += struct.pack("<%dI" % len(idx), *idx)
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": len(accessors) - 1,
                           "material": min(i, count)})
    with open(os.path.join(folder, "room.bin"), "wb") as f:
        f.write(blob)
    doc = {
        "asset": {"version": "2.0"}, "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0},
                  {"camera": 0, "translation": [3.0, 1.6, 3.0], "rotation": [0, 0.38268, 0, 0.92388]},
                  {"translation": [0, 2.6, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.1, "aspectRatio": 1.5, "znear": 0.05}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 15}]}},
        "meshes": [{"primitives": primitives}],
        "materials": materials,
        "textures": [{"source": i} for i in range(count)],
        "images": images,
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "room.bin"}],
    }
    path = os.path.join(folder, "room.gltf")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def run_once(binary, scene, threads):
    with tempfile.TemporaryDirectory(prefix="raysplat_texbench_") as out:
        stats = os.path.join(out, "stats.json")
        cmd = ["/usr/bin/time", "-v", binary, "render", scene, "-o", os.path.join(out, "room.exr"),
               "--passes", "1", "--width", "300", "--threads", str(threads), "--stats-json", stats, "--quiet"]
        start = time.monotonic()
        r = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.monotonic() - start
        if r.returncode != 0:
            sys.exit("texture_bench: %s failed:\n%s" % (binary, r.stderr))
        peak_kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr).group(1))
        with open(stats) as f:
            s = json.load(f)
        seconds = s.get("seconds", s)
        return peak_kb / 1024.0 ** 2, float(seconds["load"]), wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", action="append", help="LABEL=PATH or PATH (repeatable; default build/raysplat)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--dir", default=os.path.join(tempfile.gettempdir(), "raysplat_texture_bench"))
    ap.add_argument("--size", type=int, default=4096)
    ap.add_argument("--count", type=int, default=16)
    args = ap.parse_args()
    if args.count % 4:
        sys.exit("texture_bench: --count must be a multiple of 4")
    binaries = []
    for b in args.binary or [os.path.join(ROOT, "build", "raysplat")]:
        label, _, path = b.rpartition("=")
        binaries.append((label or path, path))

    start = time.monotonic()
    scene = write_room(os.path.join(args.dir, "%dx%d" % (args.count, args.size)), args.size, args.count)
    print("scene %s (%d textures of %d², written in %.0f s)" % (scene, args.count, args.size, time.monotonic() - start))
    print("%-28s %14s %10s %10s" % ("binary", "peak memory", "load", "wall"))
    for label, path in binaries:
        runs = [run_once(path, scene, args.threads) for _ in range(args.runs)]
        peak, load, wall = (statistics.median(r[i] for r in runs) for i in range(3))
        print("%-28s %10.2f GiB %8.1f s %8.1f s   (runs: %s)" % (
            label, peak, load, wall, ", ".join("%.2f GiB %.1f s %.1f s" % r for r in runs)), flush=True)


if __name__ == "__main__":
    main()
