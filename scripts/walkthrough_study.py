#!/usr/bin/env python3
"""Walkthroughs: how much two consecutive frames flicker, each frame's error, what reuse saves.

  python3 scripts/walkthrough_study.py [SCENE] [--frames A] [--width W] [--height H]
                                       [--time-limit T] [--reference-spp N] [--reuse-frames 8]
                                       [--reuse-passes P] [--memory-frames 48] [--build build]
                                       [--out out/walkthrough] [--json FILE]
  python3 scripts/walkthrough_study.py --make-staircase-walk SRC.glb DST.glb

SCENE (default data/interior_walk.gltf) must carry a camera animation whose keys are LINEAR
or STEP (Blender's exporter bakes one key a frame). Frames A and A+1, posed at A/fps and
(A+1)/fps, are written as stills and converted for Mitsuba 3 (gltf_to_mitsuba.py); their
converged references are Mitsuba's, two halves of N/2 samples each, cached.

1. Flicker. raysplat renders frames S..A+1 in one call (`--frames`, `--time-limit T` a
   frame: the photons traced once and splatted into every frame; S = --range-start, by
   default A: the pair alone, the walk's worst case, since a walk that began earlier has
   more passes stored by frame A) and frames A and A+1 alone, as stills; Mitsuba's
   path tracer gets raysplat's mean wall time a frame over the call, once with a new seed every frame and
   once with one seed for both. The flicker of a pair is the relative MSE of the change,
   mean((d − D)² / (M² + 0.01)), d the rendered frame A+1 minus frame A, D the references'
   change and M the references' mean. Every figure is given over all pixels and with the
   0.1 % worst pixels left out.
2. Reuse. Frames 1..K in one call against K calls of one frame each, at a fixed
   `--passes P`: the CPU seconds (user + system) of each, their ratio, and the photon passes
   the one call traced (its frames' stats summed: P when the photons are traced once).
3. Memory. The peak resident memory of `--frames 0-(F−1)` against one frame's, and the
   stored photons' MB from the stats.

--make-staircase-walk writes SRC (../shared/scenes/staircase/staircase_lambert.glb) with a
walk: the camera climbs at 1 m/s (0.8 forward, 0.6 up) and turns 15° a second to the left,
48 frames at 24 fps, one LINEAR key a frame.
"""

import argparse
import glob
import json
import math
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import venv_bootstrap  # noqa: E402

if __name__ == "__main__":
    venv_bootstrap.ensure()

import numpy as np  # noqa: E402

import animate_node  # noqa: E402
import gltf_to_mitsuba  # noqa: E402
import images  # noqa: E402
import studyutil  # noqa: E402
import validate_mitsuba  # noqa: E402
from equal_time import errors, mitsuba_for  # noqa: E402
from studyutil import log  # noqa: E402

FPS = 24.0


# -- Posing a file at a time --------------------------------------------------------------

def slerp(a, b, u):
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    d = float(np.dot(a, b))
    if d < 0.0:
        b, d = -b, -d
    if d > 0.9995:
        q = a + u * (b - a)
    else:
        th = math.acos(d)
        q = (math.sin((1 - u) * th) * a + math.sin(u * th) * b) / math.sin(th)
    return q / np.linalg.norm(q)


def sample(times, values, interpolation, t, path):
    """A channel's value at t: the ends held outside the keys; LINEAR and STEP only."""
    if interpolation not in ("LINEAR", "STEP"):
        sys.exit(f"error: {interpolation} keys: this study poses LINEAR and STEP keys only")
    if t <= times[0]:
        return values[0]
    if t >= times[-1]:
        return values[-1]
    k = int(np.searchsorted(times, t, side="right")) - 1
    if interpolation == "STEP":
        return values[k]
    u = (t - times[k]) / (times[k + 1] - times[k])
    if path == "rotation":
        return slerp(values[k], values[k + 1], u)
    return values[k] + u * (values[k + 1] - values[k])


def pose(doc, buffers, t):
    """A copy of doc with every animated node's TRS at time t and no animations."""
    posed = json.loads(json.dumps(doc))
    for anim in doc.get("animations", []):
        for ch in anim["channels"]:
            s = anim["samplers"][ch["sampler"]]
            times = gltf_to_mitsuba.read_accessor(doc, buffers, s["input"]).ravel()
            values = gltf_to_mitsuba.read_accessor(doc, buffers, s["output"]).astype(np.float64)
            node, path = posed["nodes"][ch["target"]["node"]], ch["target"]["path"]
            if path not in ("translation", "rotation", "scale"):
                sys.exit(f"error: {path} channels: this study poses node transforms only")
            node.pop("matrix", None)
            node[path] = [float(v) for v in sample(times, values, s.get("interpolation", "LINEAR"), t, path)]
    posed.pop("animations", None)
    return posed


def write_glb(path, doc, buffers, source_dir):
    """doc and its buffers as one GLB: the buffers joined into its binary chunk, images by
    file name made absolute so that the GLB may live elsewhere."""
    doc = json.loads(json.dumps(doc))
    joined, starts = bytearray(), []
    for b in buffers:
        starts.append(len(joined))
        joined += b + b"\0" * (-len(b) % 4)
    for view in doc.get("bufferViews", []):
        view["byteOffset"] = view.get("byteOffset", 0) + starts[view["buffer"]]
        view["buffer"] = 0
    doc["buffers"] = [{"byteLength": len(joined)}]
    for image in doc.get("images", []):
        if "uri" in image and not image["uri"].startswith("data:"):
            image["uri"] = os.path.abspath(os.path.join(source_dir, image["uri"]))
    animate_node.write_glb(path, doc, bytes(joined))


def quat_from_matrix(m):
    """Unit quaternion (x, y, z, w) of a rotation matrix's orthonormalised 3×3 part."""
    u, _, vt = np.linalg.svd(m[:3, :3])
    r = u @ vt
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    q = np.array([x, y, z, w])
    return q / np.linalg.norm(q)


def make_staircase_walk(src, dst, frames=48):
    """src's camera carried by a rig that climbs and turns (module docstring)."""
    doc, buffers = gltf_to_mitsuba.load_gltf(src)
    cam = next(i for i, n in enumerate(doc["nodes"]) if "camera" in n)
    world = dict(gltf_to_mitsuba.walk_nodes(doc))[cam]
    doc["nodes"][cam] = {"name": doc["nodes"][cam].get("name", "camera"), "camera": doc["nodes"][cam]["camera"],
                         "rotation": list(quat_from_matrix(world))}
    roots = doc["scenes"][doc.get("scene", 0)]["nodes"]
    if cam in roots:
        roots.remove(cam)
    else:
        for n in doc["nodes"]:
            if cam in n.get("children", []):
                n["children"].remove(cam)
    rig = len(doc["nodes"])
    doc["nodes"].append({"name": "camera_rig", "children": [cam]})
    roots.append(rig)
    forward = -world[:3, 2] * np.array([1, 0, 1])
    forward /= np.linalg.norm(forward)
    times, moves, turns = [], [], []
    for f in range(frames + 1):
        t = f / FPS
        times.append(t)
        moves.append(world[:3, 3] + t * (0.8 * forward + np.array([0.0, 0.6, 0.0])))
        a = math.radians(15.0) * t
        turns.append([0.0, math.sin(a / 2), 0.0, math.cos(a / 2)])
    blob = bytearray(buffers[0]) if buffers else bytearray()
    blob += b"\0" * (-len(blob) % 4)
    accessors = [animate_node.add_floats(doc, blob, [float(v) for row in rows for v in np.atleast_1d(row)], len(rows),
                                         kind) for rows, kind in ((times, "SCALAR"), (moves, "VEC3"), (turns, "VEC4"))]
    doc["nodes"][rig].update(translation=[float(v) for v in moves[0]], rotation=turns[0])  # the rest pose: frame 0
    doc["buffers"] = [{"byteLength": len(blob)}]
    doc["animations"] = [{"name": "walk", "samplers": [
        {"input": accessors[0], "output": accessors[1], "interpolation": "LINEAR"},
        {"input": accessors[0], "output": accessors[2], "interpolation": "LINEAR"}],
        "channels": [{"sampler": 0, "target": {"node": rig, "path": "translation"}},
                     {"sampler": 1, "target": {"node": rig, "path": "rotation"}}]}]
    write_glb(dst, doc, [bytes(blob)], os.path.dirname(os.path.abspath(src)))
    log(f"wrote {dst}: {frames} frames at {FPS:g} fps")


# -- Measuring ----------------------------------------------------------------------------

def run_measured(cmd):
    """Run cmd; (wall seconds, CPU seconds, peak resident MB) of the child."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} failed:\n{err.strip()}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def relative_change_error(a, b, ref_a, ref_b):
    """Flicker: mean((d − D)² / (M² + 0.01)) over all pixels and without the 0.1 % worst."""
    d, big_d, m = b - a, ref_b - ref_a, 0.5 * (ref_a + ref_b)
    # errors() measures (x − r)² / (r² + 0.01): give it d − D + M against M.
    return errors((d - big_d + m).astype(np.float64), m.astype(np.float64))


def fmt_pair(p):
    return f"{p[0]:.2e} / {p[1]:.2e}"


def flicker(binary, scene, args, outdir):
    doc, buffers = gltf_to_mitsuba.load_gltf(scene)
    frames = (args.frames, args.frames + 1)
    refs, xmls, noise = [], [], []
    for f in frames:
        still = os.path.join(outdir, f"frame{f}.glb")
        write_glb(still, pose(doc, buffers, f / FPS), buffers, os.path.dirname(os.path.abspath(scene)))
        xml = gltf_to_mitsuba.convert(still, os.path.join(outdir, f"mitsuba{f}"), args.width, args.height, 16)
        halves = []
        for seed in (1, 2):
            log(f"frame {f}: Mitsuba reference half {seed}, {args.reference_spp // 2} spp (cached when unchanged)")
            img, _ = validate_mitsuba.render_mitsuba(
                xml, os.path.join(outdir, f"ref{f}_{args.width}x{args.height}_{args.reference_spp}_h{seed}.exr"),
                args.reference_spp // 2, seed)
            halves.append(img.astype(np.float64))
        refs.append(0.5 * (halves[0] + halves[1]))
        noise.append(studyutil.half_noise(*halves))
        xmls.append(xml)
    common = ["--width", args.width, "--height", args.height, "--time-limit", args.time_limit]
    pattern = os.path.join(outdir, "walk_####.exr")
    wall, _, _ = run_measured([binary, "render", scene, "--quiet", "-o", pattern, *map(str, common),
                               "--frames", f"{args.range_start}-{frames[1]}"])
    walk = [images.read_layers(frame_file(pattern, f))["beauty"].astype(np.float64) for f in frames]
    per_frame = wall / (frames[1] - args.range_start + 1)
    stills = []
    for f in frames:
        out = os.path.join(outdir, f"still_{f}.exr")
        studyutil.render(binary, scene, out, "splat", [*common, "--frames", f])
        stills.append(images.read_layers(out)["beauty"].astype(np.float64))
    log(f"raysplat: frames {args.range_start}-{frames[1]} in one call, {wall:.1f} s ({per_frame:.1f} s a frame)")
    new_seed = [mitsuba_for(xmls[i], per_frame, seed=frames[i]) for i in (0, 1)]
    one_seed = [new_seed[0], mitsuba_for(xmls[1], per_frame, seed=frames[0])]
    res = {"frames": list(frames), "range_start": args.range_start, "seconds_per_frame": per_frame,
           "mitsuba_spp": [m[1] for m in new_seed],
           "error": {"walk": [errors(walk[i], refs[i]) for i in (0, 1)],
                     "still": [errors(stills[i], refs[i]) for i in (0, 1)],
                     "mitsuba": [errors(new_seed[i][0], refs[i]) for i in (0, 1)]},
           "flicker": {"walk": relative_change_error(*walk, *refs),
                       "mitsuba_new_seed": relative_change_error(new_seed[0][0], new_seed[1][0], *refs),
                       "mitsuba_one_seed": relative_change_error(one_seed[0][0], one_seed[1][0], *refs)},
           "reference_noise": noise}
    return res


def frame_file(pattern, f):
    return pattern.replace("####", f"{f:04d}")


def reuse(binary, scene, args, outdir):
    common = [binary, "render", scene, "--quiet", "--width", str(args.width), "--height", str(args.height),
              "--passes", str(args.reuse_passes)]
    k = args.reuse_frames
    one = run_measured(common + ["--frames", f"1-{k}", "-o", os.path.join(outdir, "reuse_####.exr"),
                                 "--stats-json", os.path.join(outdir, "reuse_####.json")])
    traced = sum(json.load(open(os.path.join(outdir, f"reuse_{f:04d}.json")))["counts"].get("photon_passes_traced", 0)
                 for f in range(1, k + 1))
    calls = [run_measured(common + ["--frames", str(f), "-o", os.path.join(outdir, f"alone_{f}.exr")])
             for f in range(1, k + 1)]
    return {"frames": k, "passes": args.reuse_passes, "one_call": {"wall": one[0], "cpu": one[1]},
            "calls": {"wall": sum(c[0] for c in calls), "cpu": sum(c[1] for c in calls)},
            "cpu_ratio": one[1] / sum(c[1] for c in calls), "wall_ratio": one[0] / sum(c[0] for c in calls),
            "photon_passes_traced": traced}


def memory(binary, scene, args, outdir):
    common = [binary, "render", scene, "--quiet", "--width", str(args.width), "--height", str(args.height),
              "--passes", str(args.reuse_passes)]
    n = args.memory_frames
    stats = os.path.join(outdir, "memory_####.json")
    one = run_measured(common + ["--frames", "0", "-o", os.path.join(outdir, "memory_one.exr")])
    many = run_measured(common + ["--frames", f"0-{n - 1}", "-o", os.path.join(outdir, "memory_####.exr"),
                                  "--stats-json", stats])
    store = json.load(open(frame_file(stats, n - 1)))["counts"].get("photon_store_mb")
    return {"frames": n, "one_frame_mb": one[2], "range_mb": many[2], "photon_store_mb": store}


BEGIN, END = "<!-- walkthrough:begin -->", "<!-- walkthrough:end -->"


def ratio_pair(theirs, ours):
    return " / ".join(f"{t / o:.2f}" if o > 0 else "–" for t, o in zip(theirs, ours))


def markdown(results):
    """The results page's walkthrough section: one row per scene measured."""
    lines = ["Measured by `scripts/walkthrough_study.py` (run by `scripts/run.sh study`). Each figure is a "
             "relative MSE over all pixels / with the 0.1 % worst pixels left out, against Mitsuba 3 "
             "references of the frames (two halves of the given samples a pixel); flicker is the relative MSE "
             "of the change between two consecutive frames. Mitsuba's path tracer gets raysplat's mean wall "
             "time a frame; the ratios are Mitsuba's figure over raysplat's (above 1: raysplat ahead).", "",
             "| scene (commit) | size, limit a frame (mean s) | frames A, A+1 of the call's | raysplat flicker | "
             "Mitsuba flicker, new seed a frame (ratio) | Mitsuba, one seed (ratio) | raysplat frame A+1 | "
             "the same frame as a still | Mitsuba frame A+1 |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in results:
        fl = r.get("flicker")
        if not fl:
            continue
        f, e = fl["flicker"], fl["error"]
        a, b = fl["frames"]
        walk = f"{a}, {b} of {fl['range_start']}–{b}"  # a call from the walk's start, or the pair alone
        lines.append(f"| {r['name']} ({r['machine']['commit']}) | {r['width']}×{r['height']}, {r['time_limit']:g} s ({fl['seconds_per_frame']:.1f} s) "
                     f"| {walk} | {fmt_pair(f['walk'])} | {fmt_pair(f['mitsuba_new_seed'])} "
                     f"({ratio_pair(f['mitsuba_new_seed'], f['walk'])}) | {fmt_pair(f['mitsuba_one_seed'])} "
                     f"({ratio_pair(f['mitsuba_one_seed'], f['walk'])}) | {fmt_pair(e['walk'][1])} | "
                     f"{fmt_pair(e['still'][1])} | {fmt_pair(e['mitsuba'][1])} |")
    lines += ["", "| scene | frames in one call / one call each (CPU s) | ratio | photon passes traced | "
              "peak memory, one frame / range | stored photons |", "| --- | --- | --- | --- | --- | --- |"]
    for r in results:
        u, m = r.get("reuse"), r.get("memory")
        if u and m:
            lines.append(f"| {r['name']} | 1–{u['frames']} at `--passes {u['passes']}`: {u['one_call']['cpu']:.1f} / "
                         f"{u['calls']['cpu']:.1f} | {u['cpu_ratio']:.2f} | {u['photon_passes_traced']} | "
                         f"{m['one_frame_mb']:.0f} MB / {m['range_mb']:.0f} MB ({m['frames']} frames) | "
                         f"{m['photon_store_mb']:.1f} MB |")
    machines = sorted({f"{r['machine']['cpu']}, {r['machine']['threads']} hardware threads" for r in results})
    lines += ["", "Machine: " + "; ".join(machines) + " (the commit measured beside each scene).", ""]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", default=os.path.join(studyutil.ROOT, "data", "interior_walk.gltf"))
    ap.add_argument("--make-staircase-walk", nargs=2, metavar=("SRC", "DST"))
    ap.add_argument("--frames", type=int, default=12, help="the first frame of the measured pair (default 12)")
    ap.add_argument("--range-start", type=int,
                    help="the walk renders frames from here to the pair's second (default: the pair alone)")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--time-limit", type=float, default=10.0, help="seconds a frame (default 10)")
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--reuse-frames", type=int, default=8)
    ap.add_argument("--reuse-passes", type=int, default=2)
    ap.add_argument("--memory-frames", type=int, default=48)
    ap.add_argument("--skip", default="", help="comma-separated parts to leave out: flicker, reuse, memory")
    ap.add_argument("--build", default=os.path.join(studyutil.ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(studyutil.ROOT, "out", "walkthrough"))
    ap.add_argument("--json", help="write the results here (default OUT/NAME/walk_fromS.json, S the range's start)")
    ap.add_argument("--readme", help="rewrite this page's walkthrough section from every OUT/*.json")
    args = ap.parse_args()
    if args.make_staircase_walk:
        make_staircase_walk(*args.make_staircase_walk)
        return
    binary = studyutil.find_binary(args.build)
    name = os.path.splitext(os.path.basename(args.scene))[0]
    outdir = os.path.join(args.out, name)
    os.makedirs(outdir, exist_ok=True)
    if args.range_start is None:
        args.range_start = args.frames
    if not 0 <= args.range_start <= args.frames:
        sys.exit(f"error: --range-start {args.range_start}: expected 0 to --frames {args.frames}")
    skip = set(filter(None, args.skip.split(",")))
    res = {"name": name, "scene": args.scene, "width": args.width, "height": args.height, "time_limit": args.time_limit,
           "machine": studyutil.machine()}
    if "flicker" not in skip:
        res["flicker"] = flicker(binary, args.scene, args, outdir)
        fl = res["flicker"]
        log(f"{name}: flicker raysplat {fmt_pair(fl['flicker']['walk'])}, Mitsuba new seed "
            f"{fmt_pair(fl['flicker']['mitsuba_new_seed'])}, one seed {fmt_pair(fl['flicker']['mitsuba_one_seed'])}")
        for i, f in enumerate(fl["frames"]):
            log(f"  frame {f}: in the walk {fmt_pair(fl['error']['walk'][i])}, as a still "
                f"{fmt_pair(fl['error']['still'][i])}, Mitsuba {fmt_pair(fl['error']['mitsuba'][i])}")
    if "reuse" not in skip:
        res["reuse"] = r = reuse(binary, args.scene, args, outdir)
        log(f"{name}: frames 1-{r['frames']} in one call / one call each, --passes {r['passes']}: CPU "
            f"{r['one_call']['cpu']:.1f} / {r['calls']['cpu']:.1f} s ({r['cpu_ratio']:.2f}), wall {r['wall_ratio']:.2f}; "
            f"photon passes traced {r['photon_passes_traced']}")
    if "memory" not in skip:
        res["memory"] = m = memory(binary, args.scene, args, outdir)
        log(f"{name}: peak memory {m['range_mb']:.0f} MB for {m['frames']} frames, {m['one_frame_mb']:.0f} MB for one; "
            f"stored photons {m['photon_store_mb']:.1f} MB")
    path = args.json or os.path.join(outdir, f"walk_from{args.range_start}.json")
    with open(path, "w") as f:
        json.dump(res, f, indent=1)
    log(f"wrote {path}")
    if args.readme:
        found = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(args.out, "*", "walk_from*.json")))]
        studyutil.replace_section(args.readme, BEGIN, END, markdown(found))
        log(f"updated {args.readme}")


if __name__ == "__main__":
    main()
