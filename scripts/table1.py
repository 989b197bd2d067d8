#!/usr/bin/env python3
"""The paper's Table 1 for raysplat, measured: the glossy box at the paper's settings.

    python3 scripts/table1.py [--build build] [--runs 3] [--width 500] [--scene data/glossy_box.glb]
                              [--reference-spp 4096]

Renders the scene with the paper's estimator (`--direct photons --passes 1`: 500x500x4 eye
samples, 100 000 photons split 20/50/30, grid 192) --runs times and prints the median memory
(tree + eye samples + photon rays, MB), build (voxelize + tree), eye, light (photons + splat)
and total seconds. Then it finds how long the path tracer needs for the same relative MSE
against a converged path-traced reference (rendered once and kept in out/, several minutes),
by doubling its samples per pixel.

An extra row, not in the paper, measures raysplat's current default the same way
(`--direct sample`: direct light by light sampling in a direct film, visibility by rays with
the kernels' coverage measured, photons split 0/50/30, the default number of passes), with
the path tracer's equal-error time for it.
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


PAPER = ["--direct", "photons", "--passes", "1"]  # the paper's estimator, whatever the defaults
DEFAULT = ["--direct", "sample"]  # raysplat's default estimator (default passes and split)


def measure(exe, scene, out, width, extra, runs, label):
    """Median stage times and memory of `runs` renders, and the stats of the last."""
    rows = []
    for i in range(runs):
        s = render(exe, scene, out, width, extra)
        sec, c = s["seconds"], s["counts"]
        rows.append({
            "memory": c["tree_mb"] + c["eye_samples_mb"] + c["photon_mb"],
            "tree": c["tree_mb"], "eye_mb": c["eye_samples_mb"], "photon_mb": c["photon_mb"],
            "build": sec.get("voxelize", 0) + sec.get("tree", 0),
            "eye": sec["eye"], "light": sec["photons"] + sec["splat"],
            "photons": sec["photons"], "splat": sec["splat"], "total": s["total_seconds"],
        })
        print("%s, run %d: total %.2f s" % (label, i + 1, rows[-1]["total"]), file=sys.stderr)
    return {k: statistics.median(r[k] for r in rows) for k in rows[0]}, s


class PathSearch:
    """The path tracer at 1, 2, 4, ... spp, each rendered once and remembered."""

    def __init__(self, exe, scene, out, width, reference, max_spp):
        self.exe, self.scene, self.out, self.width = exe, scene, out, width
        self.reference, self.max_spp, self.done = reference, max_spp, {}

    def at(self, spp):
        if spp not in self.done:
            s = render(self.exe, self.scene, self.out, self.width, ["--method", "path", "--spp", str(spp)])
            self.done[spp] = (s["total_seconds"], rel_mse(self.exe, self.out, self.reference))
        return self.done[spp]

    def equal_error(self, target):
        """(spp, seconds, rel. MSE, reached) of the fewest samples with rel. MSE <= target."""
        spp = 1
        while True:
            seconds, err = self.at(spp)
            if err <= target or spp * 2 > self.max_spp:
                return spp, seconds, err, err <= target
            spp *= 2


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

    paper_exr = os.path.join(out, "%s_splat.exr" % name)
    default_exr = os.path.join(out, "%s_splat_default.exr" % name)
    med, _ = measure(exe, args.scene, paper_exr, args.width, PAPER, args.runs, "paper's estimator")
    dmed, dstats = measure(exe, args.scene, default_exr, args.width, DEFAULT, args.runs, "default")

    reference = os.path.join(out, "%s_reference_%d_%dspp.exr" % (name, args.width, args.reference_spp))
    if not os.path.exists(reference):
        print("rendering the reference (%d spp)..." % args.reference_spp, file=sys.stderr)
        render(exe, args.scene, reference, args.width, ["--method", "path", "--spp", str(args.reference_spp), "--seed", "1"])
    target = rel_mse(exe, paper_exr, reference)
    dtarget = rel_mse(exe, default_exr, reference)

    search = PathSearch(exe, args.scene, os.path.join(out, "%s_path.exr" % name), args.width, reference,
                        max(1, args.reference_spp // 4))
    spp, path_time, path_err, reached = search.equal_error(target)
    dspp, dpath_time, dpath_err, dreached = search.equal_error(dtarget)
    c = dstats["counts"]
    passes = c.get("passes", 1)
    photons = c.get("photons_stored", 0) / max(passes, 1)

    def path_row(label, spp, seconds, err, reached):
        note = "" if reached else " (not reached at %d spp, the most tried)" % search.max_spp
        return "| %s | path tracer, %d spp, equal error to %s%s | - | - | - | - | %.2f | %.4f |" % (
            name, spp, label, note, seconds, err)

    print("| Scene | Method | Memory MB (tree+eye+photons) | Build | Eye | Light | Total | rel. MSE |")
    print("|---|---|---|---|---|---|---|---|")
    print("| %s | ray-splat %dx%dx4, 100k photons, grid 192 (the paper's estimator: --direct photons --passes 1) "
          "| %.1f (%.1f+%.1f+%.1f) | %.2f | %.2f | %.2f (%.2f+%.2f) | %.2f | %.4f |" % (
              name, args.width, args.width, med["memory"], med["tree"], med["eye_mb"], med["photon_mb"],
              med["build"], med["eye"], med["light"], med["photons"], med["splat"], med["total"], target))
    print(path_row("the paper's estimator", spp, path_time, path_err, reached))
    print("| paper | GLOSSY BOX, ray-splat 192^3 (one 2007 core) | 37 (5+26+6) | 3.2 | 1.4 | 54 | 59 | - |")
    print("| %s | not in the paper: raysplat's default, %dx%dx4, direct light sampled, %d pass%s x %dk photons "
          "(split 0/50/30), grid 192 | %.1f (%.1f+%.1f+%.1f) | %.2f | %.2f | %.2f (%.2f+%.2f) | %.2f | %.4f |" % (
              name, args.width, args.width, passes, "" if passes == 1 else "es", round(photons / 1000),
              dmed["memory"], dmed["tree"], dmed["eye_mb"], dmed["photon_mb"], dmed["build"], dmed["eye"],
              dmed["light"], dmed["photons"], dmed["splat"], dmed["total"], dtarget))
    print(path_row("raysplat's default", dspp, dpath_time, dpath_err, dreached))


if __name__ == "__main__":
    main()
