#!/usr/bin/env python3
"""cli_test: the raysplat command end to end, through the real binary ($RAYSPLAT).

Bad input (broken scenes, absurd settings, unwritable outputs) must end with exit code 1 --
never a crash signal -- one stderr line "raysplat: error: ..." naming the file and the glTF
object, and no output file or temporary left behind (docs/design.md §3, §10; errors: docs/design.md §10). Help
and usage, a good render's three outputs (EXR magic, PNG signature and size, stats JSON),
and bit-identical pixels with 1 and 2 threads (determinism: docs/design.md §2).

Stdlib only. Prints one line per test and closes with "N passed, M failed"; exits 1 on
any failure.
"""

import base64
import json
import os
import struct
import subprocess
import sys
import tempfile
import zlib

RAYSPLAT = os.environ.get("RAYSPLAT", "build/raysplat")
DATA = os.environ.get("RAYSPLAT_DATA",
                      os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data"))
CORNELL = os.path.join(DATA, "cornell_box.gltf")
GLOSSY = os.path.join(DATA, "glossy_box.glb")

FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5121, 5123, 5125
EXR_MAGIC = b"\x76\x2f\x31\x01"  # 0x762f3101, as the file's first four bytes
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Failure(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failure(what)


def run(*args, timeout=120):
    return subprocess.run([RAYSPLAT, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          timeout=timeout, text=True, errors="replace")


# -- Writing small glTF files -------------------------------------------------------------


def triangle_gltf(positions=((0, 0, 0), (1, 0, 0), (0, 1, 0)), indices=(0, 1, 2),
                  position_count=None, bin_uri=None):
    """A one-triangle glTF: returns (document dict, buffer bytes). POSITION is accessor 0,
    the indices (uint16) accessor 1. position_count overrides the POSITION accessor's count
    (to read past its bufferView); bin_uri None embeds the buffer as a data URI."""
    pos = b"".join(struct.pack("<3f", *p) for p in positions)
    idx = struct.pack("<%dH" % len(indices), *indices)
    idx += b"\0" * (-len(idx) % 4)
    buf = pos + idx
    uri = bin_uri or ("data:application/octet-stream;base64," + base64.b64encode(buf).decode())
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri", "mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [
            {"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "accessors": [
            {"bufferView": 0, "componentType": FLOAT, "type": "VEC3",
             "count": position_count if position_count is not None else len(positions)},
            {"bufferView": 1, "componentType": UNSIGNED_SHORT, "type": "SCALAR",
             "count": len(indices)},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
            {"buffer": 0, "byteOffset": len(pos), "byteLength": 2 * len(indices)},
        ],
        "buffers": [{"byteLength": len(buf), "uri": uri}],
    }
    return doc, buf


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def write_bytes(path, data):
    with open(path, "wb") as f:
        f.write(data)
    return path


def png_chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def textured_gltf(image_uri):
    """The triangle with a material whose baseColorTexture is texture 0 → image 0."""
    doc, _ = triangle_gltf()
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["materials"] = [{"name": "painted",
                         "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    doc["textures"] = [{"source": 0}]
    doc["images"] = [{"uri": image_uri}]
    return doc


# -- Bad input: one line, exit 1, no output -------------------------------------------------

MESSAGES = []  # (case, command, stderr line) for the closing summary


def expect_clean_error(case, args, names, outdir):
    """Runs raysplat with args; exit 1, one stderr line 'raysplat: error: ...' that contains
    every string of `names` (a tuple: any one of its strings), and `outdir` left as it was
    (no outputs, no temporaries)."""
    before = sorted(os.listdir(outdir)) if os.path.isdir(outdir) else None
    r = run(*args)
    lines = r.stderr.splitlines()
    MESSAGES.append((case, args[0], lines[0] if len(lines) == 1 else r.stderr.strip()))
    check(r.returncode >= 0 and r.returncode < 128,
          "%s: killed by a signal or crashed (returncode %d): %s" % (case, r.returncode, r.stderr))
    check(r.returncode == 1, "%s: exit code %d, expected 1; stderr: %r" % (case, r.returncode, r.stderr))
    check(len(lines) == 1, "%s: stderr is %d lines, expected 1: %r" % (case, len(lines), r.stderr))
    line = lines[0]
    check(line.startswith("raysplat: error: "), "%s: %r does not start with 'raysplat: error: '" % (case, line))
    for n in names:
        alternatives = n if isinstance(n, tuple) else (n,)
        check(any(a in line for a in alternatives), "%s: the message does not name %r: %r" % (case, n, line))
    if before is not None:
        after = sorted(os.listdir(outdir))
        check(after == before, "%s: files left in the output directory: %s" % (case, sorted(set(after) - set(before))))
    return line


def render_and_info_fail(case, scene, names):
    """Both `render` (with EXR, PNG and stats outputs requested; not --quiet, so any
    warning or progress line would show) and `info` fail cleanly."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        expect_clean_error(case, ["render", scene, "-o", os.path.join(out, "img.exr"),
                                  "--png", os.path.join(out, "img.png"),
                                  "--stats-json", os.path.join(out, "stats.json"),
                                  "--width", "16", "--spp", "1"], names, out)
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        expect_clean_error(case, ["info", scene], names, out)


IMAGE_0 = ("image 0", "image[0]")


def bad_scene_tests(tmp):
    """(name, function) pairs, one per broken-scene case; files are written into tmp."""
    def case(name, scene, *names):
        return name, lambda: render_and_info_fail(name, scene, [os.path.basename(scene), *names])

    # A missing file and a directory.
    missing = os.path.join(tmp, "missing.gltf")
    folder = os.path.join(tmp, "folder.gltf")
    os.mkdir(folder)

    invalid = write_bytes(os.path.join(tmp, "invalid_json.gltf"), b'{"asset": {"version": "2.0"}, "nodes": [')

    # A .gltf whose external buffer file is missing.
    doc, _ = triangle_gltf(bin_uri="no_such_buffer.bin")
    no_bin = write_json(os.path.join(tmp, "missing_bin.gltf"), doc)

    # Index 7 on a 3-vertex primitive.
    doc, _ = triangle_gltf(indices=(0, 1, 7))
    bad_index = write_json(os.path.join(tmp, "index_out_of_range.gltf"), doc)

    # A NaN coordinate in the buffer (vertex 1's y).
    doc, _ = triangle_gltf(positions=((0, 0, 0), (1, float("nan"), 0), (0, 1, 0)))
    nan_vertex = write_json(os.path.join(tmp, "nan_vertex.gltf"), doc)

    # POSITION accessor 0 claims 4 vertices; its bufferView holds 3.
    doc, _ = triangle_gltf(position_count=4)
    past_view = write_json(os.path.join(tmp, "accessor_past_view.gltf"), doc)

    # A sparse POSITION accessor whose one index, 3, is past its 3 vertices.
    doc, buf = triangle_gltf()
    sparse = struct.pack("<H", 3) + b"\0\0" + struct.pack("<3f", 1, 1, 1)
    buf += sparse
    doc["buffers"][0] = {"byteLength": len(buf),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}
    doc["bufferViews"] += [{"buffer": 0, "byteOffset": len(buf) - 16, "byteLength": 2},
                           {"buffer": 0, "byteOffset": len(buf) - 12, "byteLength": 12}]
    doc["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 2, "componentType": UNSIGNED_SHORT},
                                     "values": {"bufferView": 3}}
    sparse_past = write_json(os.path.join(tmp, "sparse_index_past_accessor.gltf"), doc)

    # An extension the renderer cannot do without.
    doc, _ = triangle_gltf()
    doc["extensionsUsed"] = doc["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    draco = write_json(os.path.join(tmp, "draco_required.gltf"), doc)

    # A 0-byte PNG, and a PNG whose IHDR claims 0 x 0 pixels, as baseColorTexture.
    write_bytes(os.path.join(tmp, "empty.png"), b"")
    zero_png = write_json(os.path.join(tmp, "empty_png_texture.gltf"), textured_gltf("empty.png"))
    ihdr = struct.pack(">IIBBBBB", 0, 0, 8, 2, 0, 0, 0)
    zero_by_zero = (PNG_SIGNATURE + png_chunk(b"IHDR", ihdr)
                    + png_chunk(b"IDAT", zlib.compress(b"")) + png_chunk(b"IEND", b""))
    write_bytes(os.path.join(tmp, "zero_by_zero.png"), zero_by_zero)
    zero_size_png = write_json(os.path.join(tmp, "zero_size_png_texture.gltf"),
                               textured_gltf("zero_by_zero.png"))
    zero_uri = "data:image/png;base64," + base64.b64encode(zero_by_zero).decode()
    zero_data_uri = write_json(os.path.join(tmp, "zero_size_png_data_uri.gltf"), textured_gltf(zero_uri))
    empty_data_uri = write_json(os.path.join(tmp, "empty_png_data_uri.gltf"),
                                textured_gltf("data:image/png;base64,"))

    # A good 64 x 64 RGB PNG cut off in its image data, and a text file named .png.
    rows = b"".join(b"\x00" + bytes((x * 4 + y) % 256 for x in range(64 * 3)) for y in range(64))
    good_png = (PNG_SIGNATURE + png_chunk(b"IHDR", struct.pack(">IIBBBBB", 64, 64, 8, 2, 0, 0, 0))
                + png_chunk(b"IDAT", zlib.compress(rows)) + png_chunk(b"IEND", b""))
    write_bytes(os.path.join(tmp, "cut.png"), good_png[:len(good_png) // 2])
    truncated_png = write_json(os.path.join(tmp, "truncated_png_texture.gltf"), textured_gltf("cut.png"))
    write_bytes(os.path.join(tmp, "notes.png"), b"these are notes, not an image\n")
    text_png = write_json(os.path.join(tmp, "text_png_texture.gltf"), textured_gltf("notes.png"))

    # data/glossy_box.glb cut short: the BIN chunk is truncated. Once as it is (the header's
    # length disagrees too), once with the header's total length patched to the file's length
    # so that only the BIN chunk's own length is wrong.
    with open(GLOSSY, "rb") as f:
        glb = f.read()
    cut = glb[:len(glb) // 2]
    truncated = write_bytes(os.path.join(tmp, "truncated.glb"), cut)
    patched = write_bytes(os.path.join(tmp, "truncated_chunk.glb"),
                          cut[:8] + struct.pack("<I", len(cut)) + cut[12:])

    # A TANGENT that is VEC3 (glTF wants VEC4 floats: xyz and the bitangent's sign).
    doc, buf = triangle_gltf()
    doc["accessors"].append({"bufferView": 0, "componentType": FLOAT, "type": "VEC3", "count": 3})
    doc["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 2
    vec3_tangent = write_json(os.path.join(tmp, "vec3_tangent.gltf"), doc)

    # KHR_texture_transform with a NaN rotation, and with a scale beyond a float (1e39).
    ihdr = struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)
    grey = (PNG_SIGNATURE + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", zlib.compress(b"\0\x80\x80\x80"))
            + png_chunk(b"IEND", b""))
    write_bytes(os.path.join(tmp, "grey.png"), grey)
    transforms = []
    for name, transform in (("nan_rotation", {"rotation": float("nan")}), ("huge_scale", {"scale": [1e39, 1]})):
        doc = textured_gltf("grey.png")
        doc["extensionsUsed"] = ["KHR_texture_transform"]
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
            "KHR_texture_transform": transform}
        transforms.append(write_json(os.path.join(tmp, "transform_%s.gltf" % name), doc))

    empty_gltf = write_bytes(os.path.join(tmp, "empty.gltf"), b"")
    empty_glb = write_bytes(os.path.join(tmp, "empty.glb"), b"")

    return [
        case("missing file", missing),
        case("directory instead of a file", folder),
        case("invalid JSON", invalid),
        case("missing .bin", no_bin, "no_such_buffer.bin"),
        case("index out of range", bad_index, "mesh 0", "7"),
        case("NaN vertex", nan_vertex, "mesh 0", "vertex 1"),
        case("accessor past its bufferView", past_view, "accessor 0"),
        case("sparse index past its accessor", sparse_past, "accessor 0", "index 3"),
        case("unsupported extensionsRequired", draco, "KHR_draco_mesh_compression"),
        # The loader says "image 0"; errors passed on from tinygltf say "image[0]".
        case("0-byte PNG texture", zero_png, IMAGE_0),
        case("0-byte PNG texture as a data URI", empty_data_uri, IMAGE_0),
        case("0x0 PNG texture", zero_size_png, IMAGE_0),
        case("0x0 PNG texture as a data URI", zero_data_uri, IMAGE_0),
        case("truncated PNG texture", truncated_png, "image 0", "cut.png"),
        case("text file named .png as a texture", text_png, "image 0", "notes.png"),
        case("TANGENT of the wrong type", vec3_tangent, "TANGENT", "accessor 2"),
        # nlohmann's JSON reader refuses the NaN literal (tinygltf's message names no object);
        # a finite number too large for a float is the loader's own check.
        case("texture transform with NaN", transforms[0]),
        case("texture transform beyond a float", transforms[1], "material 0", "KHR_texture_transform"),
        case("truncated .glb", truncated),
        case(".glb with a truncated chunk", patched),
        case("empty .gltf", empty_gltf),
        case("empty .glb", empty_glb),
    ]


def animated_gltf(times=(0.0, 1.0), values=((0, 0, 0), (1, 0, 0)), path="translation",
                  interpolation="LINEAR", node=0, time_type="SCALAR", value_type=None):
    """triangle_gltf with animation 0 'move': one channel on `node`, its keys' times and values
    (tuples of 3 or 4 floats) in a second embedded buffer; the accessors' types as given."""
    doc, _ = triangle_gltf()
    t = struct.pack("<%df" % len(times), *times)
    flat = [c for v in values for c in v]
    v = struct.pack("<%df" % len(flat), *flat)
    key_bytes = t + v
    uri = "data:application/octet-stream;base64," + base64.b64encode(key_bytes).decode()
    doc["buffers"].append({"byteLength": len(key_bytes), "uri": uri})
    doc["bufferViews"] += [{"buffer": 1, "byteOffset": 0, "byteLength": len(t)},
                           {"buffer": 1, "byteOffset": len(t), "byteLength": len(v)}]
    width = len(values[0]) if values else 3
    doc["accessors"] += [
        {"bufferView": 2, "componentType": FLOAT, "type": time_type, "count": len(times) // (3 if time_type == "VEC3" else 1)},
        {"bufferView": 3, "componentType": FLOAT, "type": value_type or "VEC%d" % width, "count": len(values)}]
    doc["animations"] = [{"name": "move", "samplers": [{"input": 2, "output": 3, "interpolation": interpolation}],
                          "channels": [{"sampler": 0, "target": {"node": node, "path": path}}]}]
    return doc


def bad_animation_tests(tmp):
    """Broken animations: render and info fail naming the file and the animation."""
    def case(name, doc, *names):
        scene = write_json(os.path.join(tmp, name.replace(" ", "_").replace("/", "_") + ".gltf"), doc)
        return name, lambda: render_and_info_fail(name, scene, [os.path.basename(scene), "animation 0 'move'", *names])

    nan, inf = float("nan"), float("inf")
    return [
        case("anim counts disagree", animated_gltf(values=((0, 0, 0), (1, 0, 0), (2, 0, 0))), "3 output values for 2 times"),
        case("anim cubicspline one value a key", animated_gltf(interpolation="CUBICSPLINE"), "three a key"),
        case("anim times not increasing", animated_gltf(times=(0.0, 0.0)), "not increasing"),
        case("anim NaN time", animated_gltf(times=(0.0, nan)), "time 1", "not finite"),
        case("anim infinite key", animated_gltf(values=((0, 0, 0), (inf, 0, 0))), "value 1", "not finite"),
        case("anim zero quaternion", animated_gltf(path="rotation", values=((0, 0, 0, 1), (0, 0, 0, 0))),
             "zero quaternion"),
        case("anim node does not exist", animated_gltf(node=5), "node 5 does not exist"),
        case("anim unknown path", animated_gltf(path="skew"), "unknown path 'skew'"),
        case("anim output of the wrong type", animated_gltf(path="rotation"), "not VEC4"),
        case("anim input of the wrong type", animated_gltf(times=(0, 1, 2, 3, 4, 5), time_type="VEC3"), "input", "SCALAR"),
        case("anim unknown interpolation", animated_gltf(interpolation="BOUNCE"), "BOUNCE"),
    ]


def bad_frames_tests(tmp):
    """--frames, --fps and --animation refused before anything is written."""
    walk = os.path.join(DATA, "interior_walk.gltf")

    def case(name, extra, *names, scene=walk, exr="walk_####.exr"):
        def test():
            with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
                args = ["render", scene, "-o", os.path.join(out, exr), "--width", "8", "--spp", "1", *extra]
                expect_clean_error(name, args, list(names), out)
        return name, test

    missing = os.path.join("no_such_dir", "walk_####.exr")
    read_only = os.path.join(tmp, "read_only")
    os.makedirs(read_only, exist_ok=True)
    os.chmod(read_only, 0o500)
    unwritable = [] if os.geteuid() == 0 else [  # root writes anywhere
        case("-o pattern in a read-only directory", ["--frames", "1-2", "-o", os.path.join(read_only, "w_####.exr")],
             "read_only", "cannot be written")]
    return unwritable + [
        case("--frames reversed", ["--frames", "5-2"], "--frames 5-2", "reversed"),
        case("--frames negative", ["--frames", "-3"], "--frames -3", "negative"),
        case("--frames negative end", ["--frames", "2--3"], "--frames", "negative"),
        case("--frames absurd", ["--frames", "0-1000000000"], "--frames", "1000000"),
        case("--frames not a number", ["--frames", "a-b"], "--frames", "a"),
        case("--fps 0", ["--frames", "1", "--fps", "0"], "--fps"),
        case("--animation names nothing", ["--frames", "1", "--animation", "run"], "interior_walk.gltf", "--animation run"),
        case("--animation index past the end", ["--frames", "1", "--animation", "1"], "interior_walk.gltf", "--animation 1"),
        case("--animation without --frames", ["--animation", "walk"], "--animation", "--frames"),
        case("--frame-step 0", ["--frames", "1-4", "--frame-step", "0"], "--frame-step 0", "out of range"),
        case("--frame-step without --frames", ["--frame-step", "2"], "--frame-step", "--frames"),
        case("-o pattern in a missing directory", ["--frames", "1-2"], missing, exr=missing),
        # The walkthrough keeps every pass's photons: 64 passes of a million need some 6 GiB,
        # where a still of the same settings needs 0.3.
        case("--frames keeping 64 passes of 1M photons",
             ["--frames", "1-2", "--photons", "1M", "--passes", "64", "--max-memory", "2G"],
             "needs about", "the walkthrough's photons", "--max-memory"),
    ]


def walk_args(*extra):
    """The walkthrough, as small and quick as it renders."""
    return ["render", os.path.join(DATA, "interior_walk.gltf"), "--width", "32", "--passes", "1",
            "--photons", "20k", "--spp", "1", "--direct-spp", "2", "--quiet", *extra]


def test_frames_are_numbered_and_skip_existing_continues():
    """--frames 1-2 writes walk_0001.exr and walk_0002.exr ('#' runs) and walk_0001.png (no '#':
    before the extension); --skip-existing over 1-3 then renders frame 3 alone."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        r = run(*walk_args("-o", os.path.join(out, "walk_####.exr"), "--png", os.path.join(out, "walk.png"),
                           "--frames", "1-2"), timeout=300)
        check(r.returncode == 0, "render --frames 1-2 failed: %s" % r.stderr)
        check(sorted(os.listdir(out)) == ["walk_0001.exr", "walk_0001.png", "walk_0002.exr", "walk_0002.png"],
              "outputs: %s" % sorted(os.listdir(out)))
        first = os.stat(os.path.join(out, "walk_0001.exr")).st_mtime_ns
        r = run(*walk_args("-o", os.path.join(out, "walk_####.exr"), "--png", os.path.join(out, "walk.png"),
                           "--frames", "1-3", "--skip-existing"), timeout=300)
        check(r.returncode == 0, "render --skip-existing failed: %s" % r.stderr)
        check(os.path.exists(os.path.join(out, "walk_0003.exr")), "frame 3 was not rendered")
        check(os.stat(os.path.join(out, "walk_0001.exr")).st_mtime_ns == first, "frame 1 was rendered again")
        attrs, _ = exr_header(open(os.path.join(out, "walk_0003.exr"), "rb").read())
        check(attrs["frame"][1].rstrip(b"\0").endswith(b"3"), "the EXR header's frame is %r" % (attrs["frame"],))


def test_frame_alone_equals_frame_in_range():
    """Frame 3 rendered alone (1 thread), within --frames 1-4 (2 threads) and within 1-4 at
    --frame-step 2 (which writes 1 and 3 alone): the same pixels; frames 1 and 3 differ (the camera walks). Frames past the animation's end hold its last
    pose: 48 and 49 (at 24 fps the walk ends at frame 48) are the same image, with a warning."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        r = run(*walk_args("-o", os.path.join(out, "alone.exr"), "--frames", "3", "--threads", "1"), timeout=300)
        check(r.returncode == 0, "render --frames 3 failed: %s" % r.stderr)
        r = run(*walk_args("-o", os.path.join(out, "range.exr"), "--frames", "1-4", "--threads", "2"), timeout=300)
        check(r.returncode == 0, "render --frames 1-4 failed: %s" % r.stderr)
        pixels = {}
        for name in ("alone.exr", "range_0001.exr", "range_0003.exr"):
            with open(os.path.join(out, name), "rb") as f:
                pixels[name] = exr_pixel_chunks(f.read())
        check(pixels["alone.exr"] == pixels["range_0003.exr"], "frame 3 alone and in 1-4 differ")
        # Every second frame: 1 and 3, and frame 3 the same image.
        r = run(*walk_args("-o", os.path.join(out, "step_#.exr"), "--frames", "1-4", "--frame-step", "2"), timeout=300)
        check(r.returncode == 0, "render --frames 1-4 --frame-step 2 failed: %s" % r.stderr)
        check(sorted(f for f in os.listdir(out) if f.startswith("step")) == ["step_1.exr", "step_3.exr"],
              "--frame-step 2 wrote %s" % sorted(os.listdir(out)))
        check(exr_pixel_chunks(open(os.path.join(out, "step_3.exr"), "rb").read()) == pixels["alone.exr"],
              "frame 3 of 1-4 at step 2 differs from frame 3 alone")
        check(pixels["range_0001.exr"] != pixels["range_0003.exr"], "frames 1 and 3 are the same image")
        r = run(*walk_args("-o", os.path.join(out, "end_##.exr"), "--frames", "48-49"), timeout=300)
        check(r.returncode == 0, "render --frames 48-49 failed: %s" % r.stderr)
        check("last pose is held" in r.stderr, "no warning past the end: %r" % r.stderr)
        ends = [exr_pixel_chunks(open(os.path.join(out, "end_%d.exr" % f), "rb").read()) for f in (48, 49)]
        check(ends[0] == ends[1], "frame 49 is not frame 48's pose")


def test_progress_json_carries_the_frame_and_info_lists_animations():
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        args = [a for a in walk_args("-o", os.path.join(out, "w.exr"), "--frames", "0-1") if a != "--quiet"]
        r = run(*args, "--progress", "json", timeout=300)
        check(r.returncode == 0, "render --progress json failed: %s" % r.stderr)
        events = [json.loads(line) for line in r.stderr.splitlines()]
        frames = [e for e in events if e["event"] == "frame"]
        check([(e["frame"], e["left"]) for e in frames] == [(0, 1), (1, 0)], "frame events: %s" % frames)
        first = events.index(frames[0])
        check(all("frame" in e for e in events[first:-1]), "events after the first frame without theirs: %s" % events)
        begins = [e["frame"] for e in events if e["event"] == "begin"]
        check(sorted(set(begins)) == [0, 1] and begins == sorted(begins), "the stages' frames: %s" % begins)
    r = run("info", os.path.join(DATA, "interior_walk.gltf"), "--fps", "12")
    check(r.returncode == 0, "info failed: %s" % r.stderr)
    check("0 'walk': 0 to 2 s, frames 0-24: node 84 'camera_rig' translation; node 85 'camera' rotation" in r.stdout,
          "info does not list the walk: %s" % r.stdout)


def test_info_frames_prints_each_frames_pose():
    """info --frames A-B --frame-step N: one JSON line a frame, node 0 moved by a LINEAR key from
    x = 0 at 0 s to x = 1 at 1 s, at 4 fps: x = f / 4 (held at 1 after the last key), in its
    matrix and in its triangle's bounds."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_in_") as tmp:
        scene = write_json(os.path.join(tmp, "moving.gltf"), animated_gltf())
        r = run("info", scene, "--frames", "0-6", "--frame-step", "2", "--fps", "4")
        check(r.returncode == 0, "info --frames failed: %s" % r.stderr)
        poses = [json.loads(line) for line in r.stdout.splitlines()]
        check([p["frame"] for p in poses] == [0, 2, 4, 6], "frames %s" % [p["frame"] for p in poses])
        for p in poses:
            world = p["nodes"][0]["world"]  # column-major: the translation is 12..14
            want = min(p["frame"] / 4.0, 1.0)
            check(abs(p["time"] - p["frame"] / 4.0) < 1e-7, "frame %d at %s s" % (p["frame"], p["time"]))
            check(abs(world[12] - want) < 1e-6 and world[13] == 0 and world[14] == 0 and world[:12] == [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0],
                  "frame %d: node 0's world matrix %s, expected x = %g" % (p["frame"], world, want))
            box = p["objects"][0]  # the triangle (0,0,0) (1,0,0) (0,1,0), moved
            check(abs(box["lo"][0] - want) < 1e-6 and abs(box["hi"][0] - (want + 1)) < 1e-6 and box["hi"][1] == 1,
                  "frame %d: the triangle's bounds %s, expected x from %g" % (p["frame"], box, want))


def bad_setting_tests(tmp):
    # A square EXR: an image, but not an equirectangular environment.
    not_equirect = os.path.join(tmp, "square_sky.exr")

    def case(name, extra, *names, exr="img.exr", png="img.png", stats="stats.json"):
        def test():
            with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
                args = ["render", CORNELL]
                if "NO_OUTPUT" not in extra:
                    args += ["-o", os.path.join(out, exr)]
                args += ["--png", os.path.join(out, png), "--stats-json", os.path.join(out, stats)]
                args += [a for a in extra if a != "NO_OUTPUT"]
                if not_equirect in args and not os.path.exists(not_equirect):
                    run("render", CORNELL, "-o", not_equirect, "--width", "8", "--height", "8", "--spp", "1",
                        "--passes", "1", "--quiet")
                expect_clean_error(name, args, list(names), out)
        return name, test

    missing = os.path.join("no_such_dir", "out")
    return [
        case("--spp -1", ["--spp", "-1", "--width", "16"], "--spp"),
        case("--spp -3", ["--spp", "-3", "--width", "16"], "--spp"),
        case("--spp abc", ["--spp", "abc", "--width", "16"], "--spp", "abc"),
        case("--width 100000", ["--width", "100000", "--spp", "1"], "--width"),
        case("--threads -1", ["--threads", "-1", "--width", "16", "--spp", "1"], "--threads"),
        case("unknown option", ["--bogus-option", "--width", "16"], "--bogus-option"),
        case("--direct bogus", ["--direct", "bogus", "--width", "16"], "--direct", "bogus"),
        case("direct photons with --direct sample", ["--split", "0.2,0.5,0.3", "--width", "16"],
             "--split", "--direct sample"),
        case("--passes -2", ["--passes", "-2", "--width", "16"], "--passes"),
        case("--alpha 2", ["--alpha", "2", "--width", "16"], "--alpha"),
        case("--light-samples 0", ["--light-samples", "0", "--width", "16"], "--light-samples"),
        case("--visibility bogus", ["--visibility", "bogus", "--width", "16"], "--visibility", "bogus", "mask"),
        case("--coverage-probes 17", ["--coverage-probes", "17", "--width", "16"], "--coverage-probes", "0..16"),
        case("--min-coverage 2", ["--min-coverage", "2", "--width", "16"], "--min-coverage", "0..1"),
        case("--direct-spp -1", ["--direct-spp", "-1", "--width", "16"], "--direct-spp"),
        case("--film-passes -1", ["--film-passes", "-1", "--width", "16"], "--film-passes"),
        case("--film-passes without a direct film", ["--film-passes", "2", "--direct-spp", "0", "--width", "16"],
             "--film-passes", "--direct-spp"),
        case("--film-passes with --time-limit", ["--film-passes", "2", "--time-limit", "5", "--width", "16"],
             "--film-passes", "--time-limit"),
        case("missing -o", ["NO_OUTPUT", "--width", "16", "--spp", "1"], "-o"),
        case("--env missing", ["--env", "no_such_sky.exr", "--width", "16"], "no_such_sky.exr", "no such file"),
        case("--env not an EXR", ["--env", CORNELL, "--width", "16", "--spp", "1"], CORNELL, "OpenEXR"),
        case("--env not 2:1", ["--env", not_equirect, "--width", "16", "--spp", "1"], not_equirect, "twice as wide"),
        case("--env with --sky", ["--env", CORNELL, "--sky", "1", "--width", "16"], "--env", "--sky"),
        case("--sky -1", ["--sky", "-1", "--width", "16"], "--sky"),
        case("--sky 1,2", ["--sky", "1,2", "--width", "16"], "--sky", "1,2"),
        case("--env-strength -1", ["--env-strength", "-1", "--width", "16"], "--env-strength"),
        # Settings within their ranges that the machine cannot hold fail before allocating.
        case("--photons 1000000000", ["--photons", "1000000000", "--width", "16"], "needs about", "photons",
             "available"),
        case("--grid 4096", ["--grid", "4096", "--width", "16"], "needs about", "grid", "available"),
        case("--max-memory 10M", ["--max-memory", "10M", "--width", "16"], "needs about", "--max-memory"),
        case("--max-memory abc", ["--max-memory", "abc", "--width", "16"], "--max-memory", "abc"),
        # --quiet: these runs fail only when they write, after the progress lines of the render.
        # docs/design.md §10: a failed run leaves no output, so neither may the outputs written
        # before the one that fails.
        case("EXR directory does not exist", ["--width", "8", "--spp", "1", "--quiet"],
             missing + ".exr", exr=missing + ".exr"),
        case("PNG directory does not exist", ["--width", "8", "--spp", "1", "--quiet"],
             missing + ".png", png=missing + ".png"),
        case("stats JSON directory does not exist", ["--width", "8", "--spp", "1", "--quiet"],
             missing + ".json", stats=missing + ".json"),
    ]


# -- Help and usage ----------------------------------------------------------------------


def test_no_arguments_prints_usage_and_exits_2():
    r = run()
    check(r.returncode == 2, "exit code %d, expected 2" % r.returncode)
    check("usage: raysplat" in r.stderr, "no usage on stderr: %r" % r.stderr)
    check("render" in r.stderr and "info" in r.stderr, "usage does not list the commands: %r" % r.stderr)


def test_help_of_each_command():
    wanted = {
        "render": ["usage: raysplat render", "-o", "--output", "--png", "--stats-json", "--spp",
                   "--threads", "--time-limit", "--width", "--seed", "--help"],
        "info": ["usage: raysplat info", "SCENE", "--help"],
        "voxelize": ["usage: raysplat voxelize", "--help"],
    }
    for command, words in wanted.items():
        r = run(command, "--help")
        check(r.returncode == 0, "%s --help: exit code %d" % (command, r.returncode))
        for w in words:
            check(w in r.stdout, "%s --help does not mention %s: %r" % (command, w, r.stdout))
    r = run("--help")
    check(r.returncode == 0 and "usage: raysplat" in r.stdout, "raysplat --help: %d %r" % (r.returncode, r.stdout))


def test_unknown_command_is_an_error():
    with tempfile.TemporaryDirectory() as out:
        expect_clean_error("unknown command", ["frobnicate", CORNELL], ["frobnicate"], out)


# -- Good renders ---------------------------------------------------------------------------


def exr_header(data):
    """Parses an OpenEXR single-part scanline header: returns (attributes dict of raw bytes,
    offset where the header ends)."""
    check(data[:4] == EXR_MAGIC, "no EXR magic number")
    pos, attrs = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        kind = data[end + 1:tend].decode()
        size = struct.unpack_from("<i", data, tend + 1)[0]
        attrs[name] = (kind, data[tend + 5:tend + 5 + size])
        pos = tend + 5 + size
    return attrs, pos + 1


def exr_pixel_chunks(data):
    """The EXR's pixel data: everything after the header and the chunk offset table (the
    offsets depend on the header's length, which holds timings)."""
    attrs, end = exr_header(data)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"][1])
    compression = attrs["compression"][1][0]
    lines = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 16, 8: 32, 9: 256}[compression]
    chunks = (ymax - ymin + 1 + lines - 1) // lines
    return data[end + 8 * chunks:]


def png_size(data):
    check(data[:8] == PNG_SIGNATURE, "no PNG signature")
    check(data[12:16] == b"IHDR", "the first PNG chunk is not IHDR")
    return struct.unpack(">II", data[16:24])


def png_pixels(data):
    """The 8-bit RGB rows of raysplat's PNG (one IDAT, filter type 0 per row)."""
    width, height = png_size(data)
    pos, idat = 8, b""
    while pos < len(data):
        n = struct.unpack(">I", data[pos:pos + 4])[0]
        if data[pos + 4:pos + 8] == b"IDAT":
            idat += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    raw = zlib.decompress(idat)
    check(len(raw) == height * (1 + 3 * width), "PNG data is %d bytes for %dx%d" % (len(raw), width, height))
    return b"".join(raw[y * (1 + 3 * width) + 1:(y + 1) * (1 + 3 * width)] for y in range(height))


def render_good(scene, out, name, *extra):
    exr, png, stats = (os.path.join(out, name + e) for e in (".exr", ".png", ".json"))
    r = run("render", scene, "-o", exr, "--png", png, "--stats-json", stats, *extra, timeout=300)
    check(r.returncode == 0, "render %s failed (%d): %s" % (scene, r.returncode, r.stderr))
    with open(exr, "rb") as f:
        exr_data = f.read()
    with open(png, "rb") as f:
        png_data = f.read()
    with open(stats) as f:
        stats_data = json.load(f)
    return exr_data, png_data, stats_data


def test_progress_json_and_defaults():
    """--progress json: every stderr line a JSON object, the passes counted up to their total,
    the last line "done" naming the output; render --defaults is one JSON object."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        exr = os.path.join(out, "p.exr")
        r = run("render", CORNELL, "-o", exr, "--width", "32", "--passes", "3", "--photons", "5000", "--progress", "json")
        check(r.returncode == 0, "render --progress json failed: %s" % r.stderr)
        events = [json.loads(line) for line in r.stderr.splitlines()]
        passes = [e for e in events if e["event"] == "progress" and "inner" not in e]
        check([e["done"] for e in passes] == [1, 2, 3] and all(e["total"] == 3 for e in passes),
              "the passes counted 1, 2, 3 of 3: %s" % passes)
        check(events[-1] == {"event": "done", "output": exr, "seconds": events[-1]["seconds"]}, "last line: %s" % events[-1])
        r = run("render", CORNELL, "-o", exr, "--progress", "xml")
        check(r.returncode == 1 and "--progress xml" in r.stderr, "--progress xml refused: %s" % r.stderr)
    r = run("render", "--defaults")
    d = json.loads(r.stdout)
    check(r.returncode == 0 and d["passes"] == {"splat": 8, "path": 1} and d["photons"] == 100000, "defaults: %s" % r.stdout)


def test_help_states_the_defaults_the_render_uses():
    """render --help's '(default …)' figures are RenderConfig's, as --defaults prints them."""
    d = json.loads(run("render", "--defaults").stdout)
    help_text = run("render", "--help").stdout
    def stated(flag):
        line = next(l for l in help_text.splitlines() if l.strip().startswith(flag + " "))
        return line[line.index("(default"):]
    expect = {
        "--width": "(default %d;" % d["width"],
        "--photons": "(default %d;" % d["photons"],
        "--direct-spp": "(default %d;" % d["direct_spp"],
        "--light-samples": "(default %d)" % d["light_samples"],
        "--grid": "(default %d," % d["grid"],
        "--seed": "(default %d)" % d["seed"],
        "--spp": "(default: splat %d eye samples, path %d;" % (d["spp"]["splat"], d["spp"]["path"]),
        "--passes": "(default: splat %d, each new eye samples and photons; path %d" % (d["passes"]["splat"], d["passes"]["path"]),
    }
    for flag, want in expect.items():
        check(stated(flag).startswith(want), "%s: help says %r, RenderConfig %r" % (flag, stated(flag), want))
    check("%d passes of eye pass" % d["passes"]["splat"] in help_text, "the summary's pass count")


def test_usage_page_lists_the_options_of_help():
    """docs/usage.md's option lists are the command's --help (scripts/update_usage.py)."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
    import update_usage
    with open(update_usage.USAGE) as f:
        _, written, _ = update_usage.split(f.read())
    check(written == update_usage.options_block(RAYSPLAT),
          "docs/usage.md's option lists differ from --help: run python3 scripts/update_usage.py")


def test_counts_take_exponents_and_suffixes():
    """--photons 2k, 2e3 and 2000 are the same render; 2.5, 1x and -3 are refused."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        pixels = []
        for i, count in enumerate(("2000", "2e3", "2k")):
            exr = os.path.join(out, "c%d.exr" % i)
            r = run("render", CORNELL, "-o", exr, "--width", "24", "--passes", "1", "--photons", count, "--quiet")
            check(r.returncode == 0, "--photons %s: %s" % (count, r.stderr))
            with open(exr, "rb") as f:
                pixels.append(exr_pixel_chunks(f.read()))
        check(pixels[0] == pixels[1] == pixels[2], "2000, 2e3 and 2k gave different images")
        for bad in ("2.5", "1x", "-3"):
            r = run("render", CORNELL, "-o", os.path.join(out, "bad.exr"), "--photons", bad)
            check(r.returncode == 1 and "--photons" in r.stderr and not os.path.exists(os.path.join(out, "bad.exr")),
                  "--photons %s: %r" % (bad, r.stderr))


def test_good_render_writes_exr_png_and_stats():
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        exr, png, stats = render_good(CORNELL, out, "cornell", "--width", "32", "--spp", "2",
                                      "--photons", "5000", "--grid", "64")
        check(sorted(os.listdir(out)) == ["cornell.exr", "cornell.json", "cornell.png"],
              "unexpected files: %s" % sorted(os.listdir(out)))
    check(exr[:4] == EXR_MAGIC, "the .exr does not start with 0x762f3101: %r" % exr[:4])
    attrs, _ = exr_header(exr)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"][1])
    # The Cornell camera's aspectRatio is 1: a 32-pixel-wide image is 32 high.
    check((xmax - xmin + 1, ymax - ymin + 1) == (32, 32), "EXR data window %r" % ((xmin, ymin, xmax, ymax),))
    channels = attrs["channels"][1]
    for ch in (b"R\0", b"G\0", b"B\0", b"direct.R\0", b"indirect.G\0", b"emission.B\0", b"albedo.R\0", b"normal.B\0"):
        check(ch in channels, "EXR has no channel %r" % ch)
    check(png_size(png) == (32, 32), "PNG IHDR says %dx%d, expected 32x32" % png_size(png))
    pixels = png_pixels(png)
    check(max(pixels) > 0, "the PNG is black: the lit Cornell box must show something")
    check("seconds" in stats and "counts" in stats, "stats JSON lacks seconds/counts: %r" % stats)
    check(isinstance(stats["seconds"], dict) and all(v >= 0 for v in stats["seconds"].values()),
          "stats seconds: %r" % stats["seconds"])
    check(stats["counts"].get("triangles") == 36, "stats counts triangles %r, expected 36" % stats["counts"].get("triangles"))
    check(stats["counts"].get("width") == 32 and stats["counts"].get("height") == 32, "stats size %r" % stats["counts"])


# Counts that depend on timing or on the thread count itself, not on the image.
TIMING_COUNTS = {"threads", "paths_per_second", "memory_estimate_mb"}  # depend on the machine or the threads


def test_stats_of_a_black_render_are_json():
    """A room no light reaches: every figure of --stats-json is a JSON number (the kernel scale's
    probe measures zero noise and zero bias there)."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_") as out:
        _, _, stats = render_good(os.path.join(DATA, "two_rooms_sealed.gltf"), out, "black", "--width", "24",
                                  "--passes", "2")
    check(stats["counts"]["kernel_scale"] == 1, "kernel_scale %r in the dark" % stats["counts"].get("kernel_scale"))
    check(all(isinstance(v, (int, float)) for v in stats["counts"].values()), "a count that is not a number")


def test_one_and_two_threads_give_identical_pixels():
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        common = ("--width", "48", "--spp", "4", "--photons", "20000", "--grid", "96", "--quiet")
        exr1, png1, stats1 = render_good(GLOSSY, out, "t1", "--threads", "1", *common)
        exr2, png2, stats2 = render_good(GLOSSY, out, "t2", "--threads", "2", *common)
    check(stats1["counts"]["threads"] == 1 and stats2["counts"]["threads"] == 2,
          "thread counts %r, %r" % (stats1["counts"].get("threads"), stats2["counts"].get("threads")))
    check(png1 == png2, "the PNG previews differ between --threads 1 and --threads 2")
    # The EXR headers hold per-stage timings; the pixel chunks after them must match bit for bit.
    check(exr_pixel_chunks(exr1) == exr_pixel_chunks(exr2),
          "the EXR pixel data differs between --threads 1 and --threads 2")
    c1 = {k: v for k, v in stats1["counts"].items() if k not in TIMING_COUNTS}
    c2 = {k: v for k, v in stats2["counts"].items() if k not in TIMING_COUNTS}
    check(c1 == c2, "stats counts differ: %r vs %r" % (c1, c2))


# -- Runner ----------------------------------------------------------------------------------


def test_repeated_warnings_collapse():
    """Eight primitives that are lines: one warning, one '… and 7 more' line, then the error
    (the scene has no triangles left), not eight warnings."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_in_") as tmp:
        doc, _ = triangle_gltf()
        doc["meshes"][0]["primitives"] = [{"attributes": {"POSITION": 0}, "mode": 1} for _ in range(8)]
        scene = write_json(os.path.join(tmp, "lines.gltf"), doc)
        r = run("info", scene)
        lines = r.stderr.splitlines()
        MESSAGES.append(("eight line primitives", "info", " | ".join(lines)))
        check(r.returncode == 1, "exit %d, expected 1: %r" % (r.returncode, r.stderr))
        check(len(lines) == 3, "stderr is %d lines, expected 3 (warning, summary, error): %r" % (len(lines), r.stderr))
        check("not made of triangles" in lines[0] and "primitive 0" in lines[0], "first warning: %r" % lines[0])
        check("and 7 more" in lines[1], "no summary of the other 7: %r" % lines[1])
        check(lines[2].startswith("raysplat: error: ") and "no triangles" in lines[2], "error: %r" % lines[2])


def emissive_triangle_gltf():
    """The triangle, emissive, for renders that need no lights."""
    doc, _ = triangle_gltf()
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["materials"] = [{"name": "glow", "emissiveFactor": [1, 1, 1]}]
    return doc


def test_cameras_by_name_node_or_index():
    """An unnamed perspective camera on node 'Front' and an orthographic 'top view' on node
    'Top': info lists both with index, name, node and type; --camera 1, --camera Top and
    --camera 'top view' render the same pixels, --camera 0 others; --camera 2 is an error."""
    doc = emissive_triangle_gltf()
    doc["scenes"][0]["nodes"] = [0, 1, 2]
    doc["nodes"] += [{"name": "Front", "camera": 0, "translation": [0.3, 0.3, 3]},
                     {"name": "Top", "camera": 1, "translation": [0.3, 0.3, 2]}]
    doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
                      {"name": "top view", "type": "orthographic",
                       "orthographic": {"xmag": 0.6, "ymag": 0.6, "znear": 0.1, "zfar": 10}}]
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_in_") as tmp:
        scene = write_json(os.path.join(tmp, "cameras.gltf"), doc)
        info = run("info", scene)
        check(info.returncode == 0 and info.stderr == "", "info: exit %d: %r" % (info.returncode, info.stderr))
        lines = [l for l in info.stdout.splitlines() if l.startswith("camera")]
        check(len(lines) == 2, "info lists %d cameras: %r" % (len(lines), lines))
        check(lines[0].startswith("camera 0") and "'camera 0' (node 'Front')" in lines[0] and "perspective" in lines[0]
              and "default" in lines[0], "info's camera 0: %r" % lines[0])
        check(lines[1].startswith("camera 1") and "'top view' (node 'Top')" in lines[1] and "orthographic" in lines[1],
              "info's camera 1: %r" % lines[1])
        pixels = {}
        for which in ("1", "Top", "top view", "0"):
            exr = os.path.join(tmp, "c.exr")
            r = run("render", scene, "-o", exr, "--method", "path", "--spp", "1", "--width", "16", "--quiet",
                    "--camera", which)
            check(r.returncode == 0, "--camera %r: %r" % (which, r.stderr))
            with open(exr, "rb") as f:
                pixels[which] = exr_pixel_chunks(f.read())
        check(pixels["1"] == pixels["Top"] == pixels["top view"], "--camera 1, Top and 'top view' differ")
        check(pixels["0"] != pixels["1"], "--camera 0 renders what --camera 1 does")
        with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
            expect_clean_error("--camera past the list", ["render", scene, "-o", os.path.join(out, "x.exr"),
                                                          "--camera", "2"], ["no camera '2'", "1 'top view'"], out)


def test_ignored_features_warn_once_each():
    """Clearcoat on two materials, sheen on one, morph targets, a skin and an unknown
    extension: one warning line each, naming the feature and the first object (the second
    clearcoat material counted), and the scene still loads. The same file with a broken index
    is one error line, none of the warnings."""
    doc = emissive_triangle_gltf()
    prim = doc["meshes"][0]["primitives"][0]
    doc["meshes"].append({"name": "face", "primitives": [dict(prim, targets=[{"POSITION": 0}])]})
    doc["materials"] = [{"name": "paint", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1}}},
                        {"name": "velvet", "extensions": {"KHR_materials_sheen": {},
                                                          "KHR_materials_clearcoat": {"clearcoatFactor": 0.5}}}]
    doc["nodes"] += [{"name": "body", "mesh": 1, "skin": 0}, {"name": "bone"}]
    doc["skins"] = [{"joints": [2]}]
    doc["scenes"][0]["nodes"] = [0, 1, 2]
    doc["extensionsUsed"] = ["KHR_materials_clearcoat", "KHR_materials_sheen", "EXT_made_up"]
    want = [("KHR_materials_clearcoat", "material 0 'paint' and 1 more"), ("KHR_materials_sheen", "material 1 'velvet'"),
            ("morph targets", "mesh 1 'face'"), ("skins", "node 1 'body'"), ("EXT_made_up", "extensionsUsed")]
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_in_") as tmp:
        scene = write_json(os.path.join(tmp, "ignored.gltf"), doc)
        r = run("info", scene)
        lines = r.stderr.splitlines()
        MESSAGES.append(("ignored features", "info", " | ".join(lines)))
        check(r.returncode == 0, "info: exit %d: %r" % (r.returncode, r.stderr))
        check(len(lines) == len(want), "%d warning lines, expected %d: %r" % (len(lines), len(want), lines))
        for feature, obj in want:
            hits = [l for l in lines if feature in l]
            check(len(hits) == 1 and obj in hits[0] and "ignored.gltf" in hits[0],
                  "%s: %r, expected one line naming %r" % (feature, hits, obj))
        doc["accessors"][1]["count"] = 6
        broken = write_json(os.path.join(tmp, "ignored_broken.gltf"), doc)
        with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
            expect_clean_error("ignored features, broken index", ["info", broken], ["accessor 1"], out)


def test_auto_voxelizer_follows_the_egl_device():
    """--voxelizer auto runs the GPU voxelizer on a hardware EGL device and the CPU one
    otherwise (on llvmpipe, or with no EGL at all), as `info --gpu` describes the device."""
    info = run("info", CORNELL, "--gpu")
    check(info.returncode == 0, "info --gpu: exit %d: %r" % (info.returncode, info.stderr[-300:]))
    gpu = [l for l in info.stdout.splitlines() if l.startswith("gpu")]
    check(len(gpu) == 1, "info --gpu printed no one gpu line: %r" % info.stdout[-300:])
    expected = "gpu" if "(hardware)" in gpu[0] else "cpu"
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_auto_") as out:
        r = run("voxelize", CORNELL, "-o", os.path.join(out, "a.vdb"), "--grid", "48")
        check(r.returncode == 0, "voxelize: exit %d: %r" % (r.returncode, r.stderr[-300:]))
        check("voxelizing (%s)" % expected in r.stderr,
              "device %r: expected the %s voxelizer, stderr %r" % (gpu[0], expected, r.stderr[-300:]))


def test_cache_under_concurrent_writers():
    """Four voxelize runs share one --cache folder and start together (two at once, then two
    more while they write): all succeed, none warns of a broken cache file (a reader never
    sees a half-written one: files are renamed into place whole), the folder ends with one
    cache file and no temporary, and a later run reads that file and gets the same grid."""
    import time
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_cache_") as tmp:
        cache = os.path.join(tmp, "cache")
        args = lambda i: ["voxelize", CORNELL, "-o", os.path.join(tmp, "g%d.vdb" % i), "--cache", cache,
                          "--grid", "320", "--voxelizer", "cpu"]
        procs = []
        for i in range(4):
            procs.append(subprocess.Popen([RAYSPLAT, *args(i)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          text=True, errors="replace"))
            if i == 1:
                time.sleep(0.4)
        for i, p in enumerate(procs):
            _, err = p.communicate(timeout=120)
            check(p.returncode == 0, "writer %d: exit %d: %r" % (i, p.returncode, err))
            check("warning" not in err, "writer %d warned: %r" % (i, err))
        left = sorted(os.listdir(cache))
        check(len(left) == 1 and left[0].endswith(".vdb") and not left[0].startswith("."),
              "the cache folder holds %s, expected one .vdb" % left)
        r = run(*args(9))
        check(r.returncode == 0 and "from the cache" in r.stderr, "a later run did not read the cache: %r" % r.stderr)
        # Byte for byte, but for the UUID OpenVDB gives every file it writes.
        import re
        uuid = re.compile(rb"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")
        with open(os.path.join(tmp, "g0.vdb"), "rb") as a, open(os.path.join(tmp, "g9.vdb"), "rb") as b:
            made, cached = (uuid.sub(b"", f.read(), count=1) for f in (a, b))
            check(made == cached and len(made) > 1000, "the grid read from the cache differs from the one made")


# -- Interrupted renders ---------------------------------------------------------------------


def interrupt(case, signals, delay, command="render"):
    """Starts a command writing into an empty folder, sends `signals` (0.05 s apart) `delay`
    seconds after its first line of progress (so that its handlers are in place, however
    loaded the machine), and checks the stop: exit 128 + the first signal and one line saying so, or
    (when it had finished) exit 0 with every output; never a partial output or a temporary."""
    import signal as sig
    import time
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_sig_") as out:
        if command == "render":
            args = ["render", CORNELL, "-o", os.path.join(out, "a.exr"), "--png", os.path.join(out, "a.png"),
                    "--stats-json", os.path.join(out, "a.json"), "--vdb", os.path.join(out, "a.vdb"),
                    "--width", "160", "--passes", "6", "--progress", "json"]
            outputs = ["a.exr", "a.png", "a.json", "a.vdb"]
        else:
            args = ["voxelize", CORNELL, "-o", os.path.join(out, "a.vdb"), "--grid", "640", "--voxelizer", "cpu",
                    "--progress", "json"]
            outputs = ["a.vdb"]
        p = subprocess.Popen([RAYSPLAT, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             errors="replace")
        first = p.stderr.readline()
        time.sleep(delay)
        sent = time.monotonic()
        for s in signals:
            p.send_signal(s)
            time.sleep(0.05)
        try:
            _, err = p.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            p.kill()
            raise Failure("%s: still running 30 s after the signal" % case)
        err = first + err
        stopped = time.monotonic() - sent
        left = sorted(os.listdir(out))
        if p.returncode == 0:
            check(left == sorted(outputs), "%s: finished, but the folder holds %s" % (case, left))
            return
        first = signals[0]
        name = "SIGINT" if first == sig.SIGINT else "SIGTERM"
        check(p.returncode == 128 + first, "%s: exit %d, expected %d" % (case, p.returncode, 128 + first))
        lines = [l for l in err.splitlines() if "interrupted" in l]
        check(len(lines) == 1 and name in lines[0], "%s: no one line naming %s: %r" % (case, name, err[-300:]))
        check(left == [], "%s: left %s behind" % (case, left))
        # A hang detector, not a speed figure: the stop comes at the next chunk of work.
        check(stopped < 10, "%s: took %.1f s to stop" % (case, stopped))
        MESSAGES.append((case, command, "%s (stopped %.2f s after the signal)" % (lines[0], stopped)))


def test_a_stopped_walkthrough_leaves_whole_frames():
    """SIGTERM while frame 2 of 0-40 renders: exit 143, the frames done before it whole (their EXRs
    parse, named by their frame) and nothing else: no temporary, no part of frame 2."""
    import signal as sig
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_sig_") as out:
        args = [a for a in walk_args("-o", os.path.join(out, "walk_####.exr"), "--frames", "0-40") if a != "--quiet"]
        p = subprocess.Popen([RAYSPLAT, *args, "--progress", "json"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, errors="replace")
        for line in p.stderr:
            event = json.loads(line)
            if event["event"] == "begin" and event.get("frame") == 2:
                p.send_signal(sig.SIGTERM)
                break
        try:
            p.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            p.kill()
            raise Failure("still running 30 s after the signal")
        check(p.returncode == 128 + sig.SIGTERM, "exit %d, expected %d" % (p.returncode, 128 + sig.SIGTERM))
        left = sorted(os.listdir(out))
        check(left == ["walk_0000.exr", "walk_0001.exr"], "the folder holds %s" % left)
        for name in left:
            with open(os.path.join(out, name), "rb") as f:
                check(len(exr_pixel_chunks(f.read())) > 0, "%s is not a whole EXR" % name)


def test_morph_targets_warn_once_and_render_the_rest_pose():
    """A morph target weights channel beside a translation: one warning naming morph targets,
    the frame rendered."""
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_out_") as out:
        doc = animated_gltf()
        doc["animations"][0]["channels"].append({"sampler": 0, "target": {"node": 0, "path": "weights"}})
        scene = write_json(os.path.join(out, "morph.gltf"), doc)
        r = run("render", scene, "-o", os.path.join(out, "m.exr"), "--frames", "0-1", "--width", "16", "--spp", "1",
                "--passes", "1", "--photons", "1000", "--sky", "1", "--quiet")
        check(r.returncode == 0, "render failed: %s" % r.stderr)
        warnings = [l for l in r.stderr.splitlines() if "morph targets" in l]
        check(len(warnings) == 1 and "rest pose" in warnings[0], "warnings: %r" % r.stderr)
        check(sorted(os.listdir(out)) == ["m_0000.exr", "m_0001.exr", "morph.gltf"], "outputs: %s" % os.listdir(out))


def interrupt_tests():
    import signal as sig
    return [
        ("SIGINT during set-up", lambda: interrupt("SIGINT during set-up", [sig.SIGINT], 0.0)),
        ("SIGINT during the passes", lambda: interrupt("SIGINT during the passes", [sig.SIGINT], 1.3)),
        ("SIGTERM during the passes", lambda: interrupt("SIGTERM during the passes", [sig.SIGTERM], 2.8)),
        ("two SIGINTs", lambda: interrupt("two SIGINTs", [sig.SIGINT, sig.SIGINT], 0.8)),
        ("SIGTERM while voxelizing", lambda: interrupt("SIGTERM while voxelizing", [sig.SIGTERM], 0.3, "voxelize")),
    ]


def main():
    if not os.access(RAYSPLAT, os.X_OK):
        print("cli_test: %s is not an executable (set RAYSPLAT)" % RAYSPLAT)
        return 1
    passed = failed = 0
    with tempfile.TemporaryDirectory(prefix="raysplat_cli_in_") as tmp:
        tests = [("bad scene: " + n, f) for n, f in bad_scene_tests(tmp)]
        tests += [("bad setting: " + n, f) for n, f in bad_setting_tests(tmp)]
        tests += [("bad animation: " + n, f) for n, f in bad_animation_tests(tmp)]
        tests += [("bad frames: " + n, f) for n, f in bad_frames_tests(tmp)]
        tests += [("interrupted: " + n, f) for n, f in interrupt_tests()]
        tests += [(f.__name__, f) for f in (
            test_unknown_command_is_an_error,
            test_repeated_warnings_collapse,
            test_cameras_by_name_node_or_index,
            test_ignored_features_warn_once_each,
            test_cache_under_concurrent_writers,
            test_auto_voxelizer_follows_the_egl_device,
            test_no_arguments_prints_usage_and_exits_2,
            test_help_of_each_command,
            test_good_render_writes_exr_png_and_stats,
            test_progress_json_and_defaults,
            test_help_states_the_defaults_the_render_uses,
            test_counts_take_exponents_and_suffixes,
            test_usage_page_lists_the_options_of_help,
            test_one_and_two_threads_give_identical_pixels,
            test_stats_of_a_black_render_are_json,
            test_frames_are_numbered_and_skip_existing_continues,
            test_frame_alone_equals_frame_in_range,
            test_progress_json_carries_the_frame_and_info_lists_animations,
            test_info_frames_prints_each_frames_pose,
            test_a_stopped_walkthrough_leaves_whole_frames,
            test_morph_targets_warn_once_and_render_the_rest_pose,
        )]
        for name, test in tests:
            try:
                test()
                passed += 1
                print("PASS  %s" % name)
            except (Failure, subprocess.TimeoutExpired, OSError, KeyError, ValueError) as e:
                failed += 1
                print("FAIL  %s: %s" % (name, e))
    print("\nerror messages printed:")
    for case, command, line in MESSAGES:
        print("  [%s, %s] %s" % (case, command, line))
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
