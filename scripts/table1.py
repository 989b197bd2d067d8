#!/usr/bin/env python3
"""The paper's Table 1 for raysplat, measured: the glossy box at the paper's settings.

    python3 scripts/table1.py [--build build] [--runs 3] [--width 500] [--scene data/glossy_box.glb]

Renders the scene with the default method (500x500x4 eye samples, 100 000 photons split
20/50/30, grid 192) --runs times and prints the median memory (tree + eye samples + photon
rays, MB), build (voxelize + tree), eye, light (photons + splat) and total seconds. Then it
finds how long the path tracer needs for the same relative MSE against a converged path-traced
reference (rendered once and kept in out/, several minutes), by doubling its samples per pixel.
Timings are medians: the machine may be shared.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("table1: %s failed: %s" % (" ".join(cmd), r.stderr.strip()))
    return r.stdout


def render(exe, scene, out, width, extra):
    stats = out + ".json"
    run([exe, "render", scene, "-o", out, "--width", str(width), "--quiet", "--stats-json", stats] + extra)
    with open(stats) as f:
        return json.load(f)


def rel_mse(exe, image, reference):
    for line in run([exe, "compare", image, reference]).splitlines():
        if line.startswith("beauty"):
            return float(line.split()[1])
    sys.exit("table1: compare printed no beauty line")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "data", "glossy_box.glb"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--width", type=int, default=500)
    ap.add_argument("--reference-spp", type=int, default=4096)
    args = ap.parse_args()
    exe = os.path.join(args.build, "raysplat")
    out = os.path.join(ROOT, "out")
    os.makedirs(out, exist_ok=True)
    name = os.path.splitext(os.path.basename(args.scene))[0]

    rows = []
    for i in range(args.runs):
        s = render(exe, args.scene, os.path.join(out, "%s_splat.exr" % name), args.width, [])
        sec, c = s["seconds"], s["counts"]
        rows.append({
            "memory": c["tree_mb"] + c["eye_samples_mb"] + c["photon_mb"],
            "tree": c["tree_mb"], "eye_mb": c["eye_samples_mb"], "photon_mb": c["photon_mb"],
            "build": sec.get("voxelize", 0) + sec.get("tree", 0),
            "eye": sec["eye"], "light": sec["photons"] + sec["splat"],
            "photons": sec["photons"], "splat": sec["splat"], "total": s["total_seconds"],
        })
        print("run %d: total %.2f s" % (i + 1, rows[-1]["total"]), file=sys.stderr)
    med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}

    reference = os.path.join(out, "%s_reference_%d_%dspp.exr" % (name, args.width, args.reference_spp))
    if not os.path.exists(reference):
        print("rendering the reference (%d spp)..." % args.reference_spp, file=sys.stderr)
        render(exe, args.scene, reference, args.width, ["--method", "path", "--spp", str(args.reference_spp), "--seed", "1"])
    target = rel_mse(exe, os.path.join(out, "%s_splat.exr" % name), reference)

    spp, path_time, path_err = 1, None, None
    while spp <= args.reference_spp // 4:
        s = render(exe, args.scene, os.path.join(out, "%s_path.exr" % name), args.width, ["--method", "path", "--spp", str(spp)])
        path_err = rel_mse(exe, os.path.join(out, "%s_path.exr" % name), reference)
        path_time = s["total_seconds"]
        if path_err <= target:
            break
        spp *= 2

    print("| Scene | Method | Memory MB (tree+eye+photons) | Build | Eye | Light | Total | rel. MSE |")
    print("|---|---|---|---|---|---|---|---|")
    print("| %s | ray-splat %dx%dx4, 100k photons, grid 192 | %.1f (%.1f+%.1f+%.1f) | %.2f | %.2f | %.2f (%.2f+%.2f) | %.2f | %.4f |" % (
        name, args.width, args.width, med["memory"], med["tree"], med["eye_mb"], med["photon_mb"], med["build"],
        med["eye"], med["light"], med["photons"], med["splat"], med["total"], target))
    print("| %s | path tracer, %d spp | - | - | - | - | %.2f | %.4f |" % (name, spp, path_time, path_err))
    print("| paper | GLOSSY BOX, ray-splat 192^3 (one 2007 core) | 37 (5+26+6) | 3.2 | 1.4 | 54 | 59 | - |")


if __name__ == "__main__":
    main()
