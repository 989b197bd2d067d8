#!/usr/bin/env python3
"""raysplat against Mitsuba 3's path tracer at equal wall time, on one scene.

  python3 scripts/equal_time.py SCENE --width W [--height H] --time-limit T
                                [--runs N] [--reference EXR ... | --reference-spp N]
                                [--out out/equal_time] [--no-mitsuba] [-- RAYSPLAT_ARGS...]

Each run renders SCENE with `raysplat render --time-limit T` (the default method, or what
RAYSPLAT_ARGS set), takes the process's wall time, and gives Mitsuba's `path` integrator
(through gltf_to_mitsuba.py, the variant validate_mitsuba.py picks) the same seconds of
rendering: it renders passes of a few samples a pixel until the next would overrun them.
Both images are measured against a converged reference: two path-traced halves, given with
--reference or rendered here by `raysplat render --method path` (cached). Each relative MSE
(mean((x − ref)² / (ref² + 0.01))) is given twice: over every pixel, and with the 0.1 % of
pixels of largest error left out, so that a few fireflies do not carry a lead. The ratio is
Mitsuba's error over raysplat's: above 1, raysplat is ahead. Also printed: raysplat's passes
and stage seconds, each layer's mean over the reference's. Results go to OUT/NAME.json, beside
both renderers' images.
"""

import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import venv_bootstrap  # noqa: E402

if __name__ == "__main__":
    venv_bootstrap.ensure()

import numpy as np  # noqa: E402

import gltf_to_mitsuba  # noqa: E402
import images  # noqa: E402
import studyutil  # noqa: E402
import validate_mitsuba  # noqa: E402
from studyutil import log  # noqa: E402

TRIM = 0.001  # the share of pixels, largest error first, left out of the trimmed figure
STAGES = ("eye", "tree", "photons", "coverage", "splat", "reconstruct")


def errors(img, ref):
    """Relative MSE over all pixels, and with the TRIM worst pixels left out."""
    a, r = img.astype(np.float64), ref.astype(np.float64)
    per_pixel = np.mean((a - r) ** 2 / (r * r + 1e-2), axis=2).ravel()
    keep = per_pixel.size - int(np.ceil(TRIM * per_pixel.size))
    return float(per_pixel.mean()), float(np.sort(per_pixel)[:keep].mean())


def mitsuba_for(xml, seconds, seed, pass_spp=4):
    """Mitsuba's image after `seconds` of rendering (the scene loaded and its kernels compiled
    before the clock starts), and the samples a pixel it took."""
    mi = validate_mitsuba.mitsuba()
    scene = mi.load_file(xml)
    mi.render(scene, spp=1, seed=seed * 7 + 999_983)  # compile the kernels outside the time
    acc, spp, t0, longest = None, 0, time.perf_counter(), 0.0
    while True:
        t = time.perf_counter()
        img = np.array(mi.render(scene, spp=pass_spp, seed=seed * 1_000_003 + spp), dtype=np.float64)
        longest = max(longest, time.perf_counter() - t)
        acc = img * pass_spp if acc is None else acc + img * pass_spp
        spp += pass_spp
        if time.perf_counter() - t0 + longest > seconds:
            break
    return (acc / spp).astype(np.float32), spp, time.perf_counter() - t0


def layer_means(layers, ref):
    out = {}
    for name in ("beauty", "direct", "indirect", "caustic", "emission"):
        if name in layers and name in ref and float(ref[name].mean()) > 0:
            out[name] = float(layers[name].mean() / ref[name].mean())
    return out


def net_ratio(theirs, ours, ref_noise):
    """Mitsuba's error over raysplat's, each less the reference's own noise.

    Against a reference with noise n, a render whose error against the truth is e measures
    about e + n: a reference that is not converged pulls every ratio towards 1. Subtracting n
    from both (the halves' estimate of it, all pixels) gives the ratio against the truth; it is
    printed beside the measured one, not instead of it.
    """
    if ours - ref_noise <= 0:
        return float("inf")
    return (theirs - ref_noise) / (ours - ref_noise)


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, default=0, help="0: from the camera's aspect")
    ap.add_argument("--time-limit", type=float, required=True)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--reference", nargs="+", metavar="EXR",
                    help="path-traced renders of independent seeds, an even number (their two halves estimate the noise)")
    ap.add_argument("--reference-spp", type=int, default=2048)
    ap.add_argument("--build", default=os.path.join(studyutil.ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(studyutil.ROOT, "out", "equal_time"))
    ap.add_argument("--no-mitsuba", action="store_true", help="raysplat alone")
    ap.add_argument("--tag", default="", help="a name for this setting in the output files")
    args = ap.parse_args(argv)
    binary = studyutil.find_binary(args.build)
    name = os.path.splitext(os.path.basename(args.scene))[0]
    outdir = os.path.join(args.out, name)
    os.makedirs(outdir, exist_ok=True)

    if args.reference:
        if len(args.reference) % 2:
            sys.exit("error: --reference takes an even number of renders")
        renders = [images.read_layers(p) for p in args.reference]
        k = len(renders) // 2
        halves = [{n: sum(r[n] for r in part) / k for n in part[0]} for part in (renders[:k], renders[k:])]
    else:
        size = [args.width, args.height]
        if not size[1]:
            probe = os.path.join(outdir, "size_probe.exr")
            studyutil.render(binary, args.scene, probe, "path", ["--width", args.width, "--spp", 1], cache=True)
            size[1] = images.read_layers(probe)["beauty"].shape[0]
        _, _, halves = studyutil.reference(binary, args.scene, outdir, size, args.reference_spp, f"{name}: ")
    ref = {k: 0.5 * (halves[0][k] + halves[1][k]) for k in halves[0]}
    height, width = ref["beauty"].shape[:2]
    ref_noise = studyutil.half_noise(halves[0]["beauty"], halves[1]["beauty"])
    xml = None if args.no_mitsuba else gltf_to_mitsuba.convert(args.scene, os.path.join(outdir, "mitsuba"), width, height, 16)

    runs = []
    for run in range(args.runs):
        seed = run + 1
        out = os.path.join(outdir, f"raysplat{args.tag}_{width}x{height}_t{args.time_limit:g}_s{seed}.exr")
        wall, stats = studyutil.render(binary, args.scene, out, "splat",
                                       ["--width", width, "--height", height, "--time-limit", args.time_limit,
                                        "--seed", seed, *extra])
        ours = images.read_layers(out)
        r = {"seed": seed, "wall": wall, "passes": int(stats["counts"].get("passes", 0)),
             "stages": {s: stats["seconds"].get(s, 0.0) for s in STAGES if s in stats["seconds"]},
             "ours": errors(ours["beauty"], ref["beauty"]), "means": layer_means(ours, ref),
             "layers": {k: errors(ours[k], ref[k])[0] for k in ("direct", "indirect", "caustic", "emission")
                        if k in ours and k in ref}}
        line = (f"{name} run {seed}: raysplat {r['ours'][0]:.3e} / {r['ours'][1]:.3e} (trimmed) in {wall:.1f} s, "
                f"{r['passes']} passes; stages " + " ".join(f"{k} {v:.1f}" for k, v in r["stages"].items()) +
                "; means " + " ".join(f"{k} {v:.3f}" for k, v in r["means"].items()))
        if xml:
            theirs, spp, used = mitsuba_for(xml, wall, seed)
            # Kept, so that both renderers can be measured again against another reference.
            images.write_exr(os.path.join(outdir, f"mitsuba{args.tag}_{width}x{height}_t{args.time_limit:g}_s{seed}.exr"), theirs)
            r["mitsuba"] = errors(theirs, ref["beauty"])
            r["mitsuba_spp"], r["mitsuba_seconds"] = spp, used
            r["ratio"] = [m / o if o > 0 else float("inf") for m, o in zip(r["mitsuba"], r["ours"])]
            r["ratio_net"] = net_ratio(r["mitsuba"][0], r["ours"][0], ref_noise)
            line += (f"\n    Mitsuba {r['mitsuba'][0]:.3e} / {r['mitsuba'][1]:.3e} at {spp} spp in {used:.1f} s: "
                     f"ratio {r['ratio'][0]:.2f} / {r['ratio'][1]:.2f}, net of the reference's noise {r['ratio_net']:.2f}")
        log(line)
        runs.append(r)

    summary = {"scene": args.scene, "width": width, "height": height, "time_limit": args.time_limit,
               "raysplat_args": extra, "reference_noise": ref_noise, "runs": runs}
    if xml:
        for k in (0, 1):
            summary[("ratio", "ratio_trimmed")[k]] = statistics.median(r["ratio"][k] for r in runs)
        summary["ratio_net"] = statistics.median(r["ratio_net"] for r in runs)
    with open(os.path.join(outdir, f"equal_time{args.tag}_{width}x{height}_t{args.time_limit:g}.json"), "w") as f:
        json.dump(summary, f, indent=1)
    log(f"{name}: reference noise {ref_noise:.2e}; median raysplat {statistics.median(r['ours'][0] for r in runs):.3e} / "
        f"{statistics.median(r['ours'][1] for r in runs):.3e}" +
        (f", median ratio {summary['ratio']:.2f} / {summary['ratio_trimmed']:.2f}"
         f" (all pixels net of the reference's noise {summary['ratio_net']:.2f})" if xml else ""))


if __name__ == "__main__":
    main()
