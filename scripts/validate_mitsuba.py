#!/usr/bin/env python3
"""Validate raysplat's path tracer against Mitsuba 3 on the scenes of data/.

  python3 scripts/validate_mitsuba.py [--build build] [--out out/study]
                                      [--size 256] [--reference-spp 2048] [--mitsuba-spp 1024]
                                      [SCENE ...]

Each scene is converted by gltf_to_mitsuba.py and rendered by Mitsuba's `path`
integrator (llvm_ad_rgb when a libLLVM ≥ 16 is installed, else scalar_rgb) and by
`raysplat render --method path`, each as two independent halves. The halves estimate each
renderer's own noise, so the test is whether the two renderers differ by more than their
noise: ratio = relMSE(raysplat, Mitsuba) / (noise of raysplat + noise of Mitsuba), near 1
when they agree, per pixel and on 8×8-pixel block means (which shows a low-frequency bias
64× more sharply). Renders are cached in OUT; a changed scene or setting renders again.
"""

import argparse
import glob
import json
import os
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
from studyutil import log  # noqa: E402

AGREE_RATIO = 1.5  # block-level ratio up to which two renders count as equal within noise
BLOCK = 8
_variant = None


def mitsuba():
    """The mitsuba module with the fastest variant that works on this machine."""
    global _variant
    import mitsuba as mi
    if _variant is None:
        for v in ("llvm_ad_rgb", "scalar_rgb"):
            try:
                mi.set_variant(v)
                if v.startswith("llvm"):
                    # Dr.Jit loads whichever libLLVM it finds; before 16 it aborts the whole
                    # process ("Cannot select: fmaximum") on real scenes, which no try catches.
                    import drjit
                    version = tuple(drjit.detail.llvm_version())
                    if version < (16,):
                        raise RuntimeError(f"libLLVM {'.'.join(map(str, version))} is older than 16")
                mi.render(mi.load_dict({"type": "scene", "i": {"type": "path"}, "s": {"type": "perspective",
                                        "film": {"type": "hdrfilm", "width": 2, "height": 2}}}), spp=1)
                _variant = v
                break
            except Exception as e:  # a missing libLLVM surfaces as a plain exception
                log(f"mitsuba: variant {v} unavailable ({str(e).splitlines()[0]})")
        if _variant is None:
            sys.exit("error: no usable Mitsuba 3 variant")
        log(f"mitsuba {mi.__version__}, variant {_variant}")
    return mi


def render_mitsuba(xml, out, spp, seed, pass_spp=32):
    """Render xml at spp samples (in passes of pass_spp, bounded memory); cached by key."""
    mi = mitsuba()
    key = out[:-4] + ".key"
    want = json.dumps({"xml": studyutil.file_digest(xml), "spp": spp, "seed": seed,
                       "mitsuba": mi.__version__, "variant": _variant})
    if os.path.exists(out) and os.path.exists(key) and open(key).read() == want:
        return images.read_layers(out)["beauty"], None
    scene = mi.load_file(xml)
    t0 = time.perf_counter()
    acc, done = None, 0
    while done < spp:
        n = min(pass_spp, spp - done)
        img = np.array(mi.render(scene, spp=n, seed=seed * 1_000_003 + done), dtype=np.float64)
        acc = img * n if acc is None else acc + img * n
        done += n
    wall = time.perf_counter() - t0
    rgb = (acc / spp).astype(np.float32)
    images.write_exr(out, rgb)
    with open(key, "w") as f:
        f.write(want)
    return rgb, wall


def validate(binary, scene, outdir, size, reference_spp, mitsuba_spp):
    """Compare the raysplat path-traced reference of scene with Mitsuba. Returns a dict."""
    name = os.path.splitext(os.path.basename(scene))[0]
    outdir = os.path.join(outdir, name)
    ref, ref_noise, halves = studyutil.reference(binary, scene, outdir, size, reference_spp, f"{name}: ")
    xml = gltf_to_mitsuba.convert(scene, os.path.join(outdir, "mitsuba"), size[0], size[1], mitsuba_spp)
    mi_halves, walls, mi_files = [], [], []
    for seed in (1, 2):
        log(f"{name}: Mitsuba half {seed}: {mitsuba_spp // 2} spp (cached when unchanged)")
        mi_files.append(os.path.join(outdir, f"mitsuba_{mitsuba_spp}spp_half{seed}.exr"))
        rgb, wall = render_mitsuba(xml, mi_files[-1], mitsuba_spp // 2, seed)
        mi_halves.append(rgb)
        walls.append(wall)
    ours = ref["beauty"]
    theirs = 0.5 * (mi_halves[0] + mi_halves[1])
    mi_noise = studyutil.half_noise(*mi_halves)
    ours_b, theirs_b, block_err, block_noise = block_agreement([h["beauty"] for h in halves], mi_halves)
    result = {
        "mitsuba_halves": mi_files,
        "scene": os.path.basename(scene),
        "variant": _variant,
        "mitsuba_spp": mitsuba_spp,
        "reference_spp": reference_spp,
        "rel_mse": images.rel_mse(ours, theirs),
        "noise": ref_noise + mi_noise,
        "block_rel_mse": block_err,
        "block_noise": block_noise,
        "mean_ours": ours.mean(axis=(0, 1)).tolist(),
        "mean_mitsuba": theirs.mean(axis=(0, 1)).tolist(),
        "flip": images.flip(ours, theirs)[0],
    }
    # A sealed room seen from inside is black: both renders all zeros, noise and error 0, and
    # the ratios 0/0. Agreement then means that both are black.
    result["max_ours"], result["max_mitsuba"] = float(np.max(ours)), float(np.max(theirs))
    result["black"] = result["max_ours"] <= 0 and result["max_mitsuba"] <= 0
    if result["black"]:
        result["ratio"] = result["block_ratio"] = float("nan")
        result["agrees"] = True
    else:
        result["ratio"] = ratio(result["rel_mse"], result["noise"])
        result["block_ratio"] = ratio(result["block_rel_mse"], block_noise)
        result["agrees"] = result["block_ratio"] <= AGREE_RATIO
    result["mitsuba_seconds"] = sum(w for w in walls if w is not None) if all(w is not None for w in walls) else None

    # Picture: raysplat | Mitsuba | relative difference of 8×8 block means (black 0, bright ≥ 10 %).
    e = images.auto_exposure(theirs)
    zmap = studyutil.upscale(images.false_colour(images.diff_image(ours_b, theirs_b), 0.1), BLOCK)
    pad = np.full((ours.shape[0], 4, 3), 255, np.uint8)
    result["image"] = os.path.join(outdir, "mitsuba_vs_raysplat.png")
    images.save_png(result["image"], np.hstack([images.to_srgb8(ours, e), pad, images.to_srgb8(theirs, e), pad,
                                                zmap[:ours.shape[0], :ours.shape[1]]]))
    return result


def block_agreement(ours, theirs):
    """Two renders, each as two independent halves (or seeds): the averages' BLOCK × BLOCK block
    means, their relative MSE, and its expected value from noise alone (both averages' noise)."""
    ob = [studyutil.block_means(h, BLOCK) for h in ours]
    tb = [studyutil.block_means(h, BLOCK) for h in theirs]
    ours_b, theirs_b = 0.5 * (ob[0] + ob[1]), 0.5 * (tb[0] + tb[1])
    return ours_b, theirs_b, images.rel_mse(ours_b, theirs_b), studyutil.half_noise(*ob) + studyutil.half_noise(*tb)


def ratio(err, noise):
    """err / noise; infinite when there is an error but no noise to explain it."""
    if noise > 0:
        return err / noise
    return 0.0 if err == 0 else float("inf")


def fmt(x, spec):
    """x formatted by spec, or '–' when it is NaN or None (FLIP of a black reference)."""
    return "–" if x is None or x != x else format(x, spec)


def verdict(r):
    if r.get("black"):
        return "black in both"
    if r.get("max_ours", 1) <= 0 or r.get("max_mitsuba", 1) <= 0:
        return "differ (" + ("raysplat" if r["max_ours"] <= 0 else "Mitsuba") + " black, the other not)"
    return "agree within noise" if r["agrees"] else "differ"


def data_scenes():
    return sorted(glob.glob(os.path.join(studyutil.ROOT, "data", "*.gltf")) +
                  glob.glob(os.path.join(studyutil.ROOT, "data", "*.glb")))


def markdown(results):
    lines = ["| Scene | Mitsuba / raysplat mean RGB | relMSE (noise) | ratio | 8×8 blocks: relMSE (noise) | ratio | FLIP | verdict |",
             "|---|---|---|---|---|---|---|---|"]
    for r in results:
        if r.get("black"):
            ratio_of_means = "0 / 0"
        else:
            ratio_of_means = " ".join(f"{m / o:.3f}" if o > 0 else ("–" if m == 0 else "∞")
                                      for m, o in zip(r["mean_mitsuba"], r["mean_ours"]))
        lines.append(f"| {r['scene']} | {ratio_of_means} | {r['rel_mse']:.2e} ({r['noise']:.2e}) "
                     f"| {fmt(r['ratio'], '.2f')} | {r['block_rel_mse']:.2e} ({r['block_noise']:.2e}) "
                     f"| {fmt(r['block_ratio'], '.2f')} | {fmt(r['flip'], '.3f')} | {verdict(r)} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    studyutil.add_common_arguments(ap)
    args = ap.parse_args()
    binary = studyutil.find_binary(args.build)
    results = [validate(binary, s, args.out, (args.size, args.size), args.reference_spp, args.mitsuba_spp)
               for s in (args.scenes or data_scenes())]
    print(markdown(results))
    for r in results:
        print(f"{r['scene']}: {r['image']}")
    sys.exit(0 if all(r["agrees"] for r in results) else 1)


if __name__ == "__main__":
    main()
