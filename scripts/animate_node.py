#!/usr/bin/env python3
"""Adds a translation animation to nodes of a .glb, for walkthroughs where a mesh moves
(docs/usage.md "Animations and walkthroughs"): each named node slides by OFFSET metres over
FRAMES frames at FPS, one LINEAR key a frame as Blender's exporter bakes them.

  animate_node.py IN.glb OUT.glb NODE [NODE…] [--offset X Y Z] [--frames N] [--fps F]

Only the standard library.
"""

import argparse
import json
import os
import struct
import sys


def read(path):
    data = open(path, "rb").read()
    if data[:4] != b"glTF":
        sys.exit("animate_node.py: %s is not a .glb" % path)
    length = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + length])
    rest = data[20 + length:]
    binary = b""
    if len(rest) >= 8 and rest[4:8] == b"BIN\0":
        binary = rest[8:8 + struct.unpack("<I", rest[:4])[0]]
    return doc, binary


def write_glb(path, doc, binary):
    """doc and its one buffer's bytes as a .glb at path, written whole or not at all."""
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I", len(text)) + b"JSON" + text + struct.pack("<I", len(binary)) + b"BIN\0" + binary
    with open(path + ".tmp", "wb") as f:
        f.write(b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks)
    os.replace(path + ".tmp", path)


def add_floats(doc, binary, values, count, kind):
    """Appends float32 values to the bytearray binary (buffer 0) as a new accessor of count
    elements of kind; returns its index."""
    view = len(doc.setdefault("bufferViews", []))
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": 4 * len(values)})
    binary.extend(struct.pack("<%df" % len(values), *values))
    acc = {"bufferView": view, "componentType": 5126, "count": count, "type": kind}
    if kind == "SCALAR":
        acc["min"], acc["max"] = [min(values)], [max(values)]
    doc.setdefault("accessors", []).append(acc)
    return len(doc["accessors"]) - 1


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("nodes", nargs="+", help="node names")
    p.add_argument("--offset", nargs=3, type=float, default=(0.5, 0.0, 0.0))
    p.add_argument("--frames", type=int, default=24)
    p.add_argument("--fps", type=float, default=24.0)
    a = p.parse_args()
    doc, binary = read(a.input)
    names = {n.get("name"): i for i, n in enumerate(doc["nodes"])}
    missing = [n for n in a.nodes if n not in names]
    if missing:
        sys.exit("animate_node.py: no node named %s in %s" % (", ".join(missing), a.input))
    binary = bytearray(binary + b"\0" * (-len(binary) % 4))
    times = [f / a.fps for f in range(a.frames + 1)]
    time_accessor = add_floats(doc, binary, times, len(times), "SCALAR")
    samplers, channels = [], []
    for name in a.nodes:
        node = doc["nodes"][names[name]]
        if "matrix" in node:
            sys.exit("animate_node.py: node %s has a matrix, not TRS" % name)
        t0 = node.get("translation", [0.0, 0.0, 0.0])
        keys = [c for f in range(a.frames + 1) for c in (t0[k] + a.offset[k] * f / a.frames for k in range(3))]
        samplers.append({"input": time_accessor, "output": add_floats(doc, binary, keys, a.frames + 1, "VEC3"), "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": names[name], "path": "translation"}})
    doc.setdefault("animations", []).append({"name": "slide", "samplers": samplers, "channels": channels})
    doc["buffers"][0]["byteLength"] = len(binary)
    write_glb(a.output, doc, bytes(binary))


if __name__ == "__main__":
    main()
