#!/usr/bin/env python3
"""Quality-versus-time study of raysplat: what photon ray splatting buys and what it costs.

  python3 scripts/study.py [--build build] [--out out/study] [--size 256]
                           [--passes 1,2,4,8,16] [--reuse]
                           [--reference-spp 2048] [--mitsuba-spp 1024]
                           [--readme docs/results.md | --no-readme] [--results DIR] [SCENE ...]

(`scripts/run.sh study` installs what is missing, builds, and runs this.)

For each scene (default: every scene of data/):
  1. a converged reference from raysplat's path tracer (two seeds, cached in OUT), itself
     checked against Mitsuba 3 (validate_mitsuba.py);
  2. raysplat at its defaults (direct light sampled in a direct film, visibility by rays,
     100 000 photons a pass split 0/50/30) at increasing budgets: `--passes P` for each P of --passes, each
     timed; the default pass count again with `--seed 2`, and the two against the reference and
     against Mitsuba on 8×8 block means, whose ratio to the noise shows bias above the noise;
  3. the paper's own estimator (`--direct photons --passes 1`: direct light from photons,
     split 20/50/30) and, at the same settings, splatting without visibility (the paper's
     Fig. 4b);
  4. the path tracer at the wall times of step 2 (samples per pixel chosen from two timed
     calibration runs, start-up and per-sample cost, then the real time measured);
  5. relative MSE and FLIP of every render against the reference, and the mean of each
     layer (direct / indirect / caustic) of the splat against the reference's, which shows
     bias.
It writes a plot of relative MSE against time, Table-1-style tables, the layers of the
paper's Fig. 5 (direct / indirect / caustic / beauty) and the shadow contrast of its Fig. 4
into docs/results/, and docs/results.md between its `results:begin` and
`results:end` markers. Times are wall-clock seconds of one `raysplat render` each (load and
voxelization included), on however many cores the machine has; each render is
deterministic, so only its time varies between runs.

A scene whose reference is black (two_rooms_sealed: the camera's room gets no light) has
no error to compare: relative MSE stays defined, FLIP is not (shown as –), and the verdict
says whether raysplat's image is black too.
"""

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import venv_bootstrap  # noqa: E402

if __name__ == "__main__":
    venv_bootstrap.ensure()

import numpy as np  # noqa: E402

import images  # noqa: E402
import studyutil  # noqa: E402
import validate_mitsuba  # noqa: E402
from studyutil import log  # noqa: E402

RESULTS_DIR = os.path.join("docs", "results")
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
# Regions of interest at 256×256 (x, y, w, h), scaled with --size: where each scene shows
# shadows, the caustic under the glossy box's glass sphere, the light through the opening
# and on the floor of two_rooms_gap (the same region of the black two_rooms_sealed), the
# caustics on caustic_pool's floor, point_shadows' hard shadows, the interior's banister and
# the daylight room's window, plant and sun stripes, and textured_room's screen, leaves and
# their shadow on the bevelled floor.
CROPS = {"cornell_box": (16, 120, 128, 128), "glossy_box": (24, 136, 112, 112),
         "direct_light": (20, 48, 112, 112), "two_rooms_gap": (8, 80, 128, 128),
         "two_rooms_sealed": (8, 80, 128, 128), "caustic_pool": (64, 96, 128, 128),
         "point_shadows": (24, 40, 128, 128), "interior": (112, 96, 128, 128),
         "daylight": (48, 40, 144, 144), "textured_room": (40, 70, 128, 128)}
DEFAULT_PASSES = 8  # raysplat's default --passes: the run whose layers and bias are shown
PAPER = ["--direct", "photons", "--passes", 1]  # the paper's estimator (its split is then the default)
LAYER_NAMES = ("direct", "indirect", "caustic", "beauty")


def scene_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def measure(layers, ref):
    return {"rel_mse": images.rel_mse(layers["beauty"], ref["beauty"]),
            "flip": images.flip(layers["beauty"], ref["beauty"])[0],
            "max": float(np.max(layers["beauty"])),
            "layer_means": {k: float(np.mean(layers[k], dtype=np.float64)) for k in LAYER_NAMES if k in layers}}


def run_scene(binary, scene, args):
    reuse = args.reuse
    name = scene_name(scene)
    outdir = os.path.join(args.out, name)
    size = (args.size, args.size)
    log(f"== {name}")
    validation = validate_mitsuba.validate(binary, scene, args.out, size, args.reference_spp, args.mitsuba_spp)
    ref, ref_noise, ref_halves = studyutil.reference(binary, scene, outdir, size, args.reference_spp)
    common = ["--width", args.size, "--height", args.size]
    runs = []

    for n in args.passes:
        out = os.path.join(outdir, f"splat_{n}pass.exr")
        log(f"{name}: splat, {n} pass{'es' if n != 1 else ''}")
        wall, stats = studyutil.render(binary, scene, out, "splat", common + ["--passes", n], cache=reuse)
        runs.append({"method": "splat", "passes": n, "seconds": wall, "stats": stats, "exr": out,
                     **measure(images.read_layers(out), ref)})

    agreement = agree_with_references(binary, scene, outdir, common, args, runs, ref_halves, validation)

    out = os.path.join(outdir, "paper.exr")
    log(f"{name}: the paper's estimator (direct light from photons, 1 pass)")
    wall, stats = studyutil.render(binary, scene, out, "splat", common + PAPER, cache=reuse)
    paper = {"method": "paper", "passes": 1, "seconds": wall, "stats": stats, "exr": out,
             **measure(images.read_layers(out), ref)}

    out = os.path.join(outdir, "novis_paper.exr")
    log(f"{name}: splat without visibility (the paper's estimator otherwise)")
    wall, stats = studyutil.render(binary, scene, out, "splat-novis", common + PAPER, cache=reuse)
    novis = {"method": "splat-novis", "passes": 1, "seconds": wall, "stats": stats, "exr": out,
             **measure(images.read_layers(out), ref)}

    startup, per_spp = calibrate_path(binary, scene, outdir, common, reuse)
    paths = []
    for r in runs:
        spp = max(1, int(round((r["seconds"] - startup) / per_spp)))
        out = os.path.join(outdir, f"path_{spp}spp.exr")
        log(f"{name}: path tracer, {spp} spp (matching {r['seconds']:.1f} s)")
        wall, stats = studyutil.render(binary, scene, out, "path", common + ["--spp", spp], cache=reuse)
        paths.append({"method": "path", "spp": spp, "seconds": wall, "stats": stats, "exr": out,
                      **measure(images.read_layers(out), ref)})
    return {"name": name, "scene": scene, "ref": ref, "ref_noise": ref_noise, "validation": validation,
            "ref_max": float(np.max(ref["beauty"])),
            "ref_layer_means": {k: float(np.mean(ref[k], dtype=np.float64)) for k in LAYER_NAMES if k in ref},
            "splat": runs, "paper": paper, "novis": novis, "path": paths, "agreement": agreement,
            "default_passes": default_passes(args.passes)}


def agree_with_references(binary, scene, outdir, common, args, runs, ref_halves, validation):
    """raysplat's default render against the path-traced reference and against Mitsuba, on 8×8
    block means: the render at the default passes and a second one with another seed, averaged;
    the noise from the two seeds and from each reference's halves. A kernel estimator is biased:
    this says whether its bias shows above the noise at that budget."""
    passes = default_passes(args.passes)
    second = os.path.join(outdir, f"splat_{passes}pass_seed2.exr")
    log(f"{scene_name(scene)}: splat, {plural(passes, 'pass')}, a second seed (the splat's own noise)")
    studyutil.render(binary, scene, second, "splat", common + ["--passes", passes, "--seed", 2], cache=args.reuse)
    first = next(r["exr"] for r in runs if r["passes"] == passes)
    ours = [images.read_layers(p)["beauty"] for p in (first, second)]
    refs = {"path": [h["beauty"] for h in ref_halves],
            "mitsuba": [images.read_layers(p)["beauty"] for p in validation["mitsuba_halves"]]}
    result = {"passes": passes}
    for key, theirs in refs.items():
        _, _, err, noise = validate_mitsuba.block_agreement(ours, theirs)
        black = max(float(np.max(o)) for o in ours) <= 0 and max(float(np.max(t)) for t in theirs) <= 0
        result[key] = {"block_rel_mse": err, "block_noise": noise,
                       "block_ratio": float("nan") if black else validate_mitsuba.ratio(err, noise), "black": black}
    return result


def agreement_table(results):
    lines = ["| Scene | passes | against the path tracer: relMSE (noise) | ratio | against Mitsuba: relMSE (noise) "
             "| ratio | verdict |", "|---|---|---|---|---|---|---|"]
    for res in results:
        a = res["agreement"]
        cells = []
        for key in ("path", "mitsuba"):
            x = a[key]
            cells.append(f"{x['block_rel_mse']:.2e} ({x['block_noise']:.2e}) | "
                         f"{validate_mitsuba.fmt(x['block_ratio'], '.2f')}")
        if a["path"]["black"] and a["mitsuba"]["black"]:
            word = "black in all"
        elif all(a[k]["block_ratio"] <= validate_mitsuba.AGREE_RATIO for k in ("path", "mitsuba")):
            word = "agree within noise"
        else:
            word = "bias above the noise"
        lines.append(f"| {res['name']} | {a['passes']} | " + " | ".join(cells) + f" | {word} |")
    return "\n".join(lines)


def calibrate_path(binary, scene, outdir, common, reuse):
    """(start-up seconds, seconds per sample per pixel) of the path tracer, from two timed
    runs: 16 spp, then enough samples for about two seconds (at least 64). Start-up (load,
    BVH) dominates a short run on a small image; one run alone would overestimate the cost
    of a sample and give runs much shorter than the splat runs they are meant to match."""
    t1, _ = studyutil.render(binary, scene, os.path.join(outdir, "path_calibration.exr"), "path",
                             common + ["--spp", 16], cache=reuse)
    n2 = int(min(65536, max(64, 2.0 / max(t1 / 16, 1e-9))))
    t2, _ = studyutil.render(binary, scene, os.path.join(outdir, "path_calibration2.exr"), "path",
                             common + ["--spp", n2], cache=reuse)
    per_spp = (t2 - t1) / (n2 - 16)
    if per_spp <= 0:  # timing noise on a shared machine: fall back to the longer run alone
        return 0.0, t2 / n2
    return max(0.0, t1 - 16 * per_spp), per_spp


def default_passes(passes):
    """The pass count shown in the pictures and the bias table: raysplat's default where the
    study has it, else the smallest it has."""
    return DEFAULT_PASSES if DEFAULT_PASSES in passes else min(passes)


def default_run(res):
    return next(r for r in res["splat"] if r["passes"] == res["default_passes"])


def plural(n, word):
    return f"{n} {word}{'' if n == 1 else 'es' if word.endswith('s') else 's'}"


def path_error_at(paths, seconds):
    """Path tracer's rel. MSE at `seconds`: interpolated in log-log between measured points;
    past the longest run, extrapolated as error ∝ 1/time (variance ∝ 1/samples). Zero errors
    (a black reference rendered black) are clipped to a tiny value for the logarithm."""
    pts = sorted((p["seconds"], max(p["rel_mse"], 1e-300)) for p in paths)
    t = np.log([p[0] for p in pts])
    e = np.log([p[1] for p in pts])
    if seconds > pts[-1][0]:
        return pts[-1][1] * pts[-1][0] / seconds
    return float(np.exp(np.interp(np.log(seconds), t, e)))


def is_black(res):
    return res["ref_max"] <= 0


def black_verdict(res):
    """For a black reference there is no error to compare: is raysplat's image black too?"""
    lit = [r for r in res["splat"] + [res["paper"]] if r["max"] > 0]
    path_lit = [r for r in res["path"] if r["max"] > 0]
    tail = ("" if not path_lit else
            f"; the path tracer's image is not black either (max {max(r['max'] for r in path_lit):.3g})")
    nv = res["novis"]
    tail += ("; without visibility (the paper's Fig. 4b) light leaks through the wall: "
             f"max {nv['max']:.3g}, rel. MSE {nv['rel_mse']:.3g}" if nv["max"] > 0 else
             "; without visibility it is black too")
    if not lit:
        return ("the reference is black (no light reaches the camera's room) and so is every raysplat image "
                f"(max pixel value 0 at {', '.join(str(r['passes']) for r in res['splat'])} passes and for the "
                "paper's estimator): no light leaks" + tail)
    leaks = ", ".join((f"{plural(r['passes'], 'pass')}" if r["method"] == "splat" else "the paper's estimator") +
                      f" max {r['max']:.3g}, rel. MSE {r['rel_mse']:.3g}" for r in lit)
    return f"the reference is black (no light reaches the camera's room) but raysplat's image is not: {leaks}" + tail


def verdict(result):
    if is_black(result):
        return black_verdict(result)
    ratios = [r["rel_mse"] / path_error_at(result["path"], r["seconds"]) for r in result["splat"]]
    wins = [r for r, q in zip(result["splat"], ratios) if q < 1.0]
    budget = lambda r: f"{plural(r['passes'], 'pass')} ({r['seconds']:.0f} s)"  # noqa: E731
    budgets = ", ".join(budget(r) for r in result["splat"])
    margin = (f"; at equal time raysplat's relative MSE is {min(ratios):.3g}–{max(ratios):.3g}× "
              "the path tracer's")
    paper = result["paper"]
    q = paper["rel_mse"] / path_error_at(result["path"], paper["seconds"])
    margin += (f" (the paper's estimator: {q:.3g}× at {paper['seconds']:.0f} s)")
    if not wins:
        return f"nowhere: the path tracer has the lower error at every budget measured ({budgets}){margin}"
    if len(wins) == len(result["splat"]):
        return f"raysplat has the lower error at every budget measured ({budgets}){margin}"
    return ("raysplat has the lower error at " + ", ".join(budget(r) for r in wins) +
            "; the path tracer at the other budgets (of " + budgets + ")" + margin)


# -- Pictures -------------------------------------------------------------------------------

def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    ncols = min(3, len(results))
    nrows = (len(results) + ncols - 1) // ncols
    fig, grid = plt.subplots(nrows, ncols, figsize=(4.2 * ncols, 3.6 * nrows), squeeze=False)
    axes = grid.reshape(-1)
    for ax in axes[len(results):]:
        ax.set_visible(False)
    for ax, res in zip(axes, results):
        # Zero errors (a black reference rendered black) have no place on a log scale: skipped.
        pos = lambda rs: [r for r in rs if r["rel_mse"] > 0]  # noqa: E731
        s, p = pos(res["splat"]), pos(res["path"])
        paper, nv = pos([res["paper"]]), pos([res["novis"]])
        ax.set_xscale("log")
        ax.set_yscale("log")
        if s:
            ax.plot([r["seconds"] for r in s], [r["rel_mse"] for r in s], "o-", label="raysplat (passes)")
        for r in s:
            ax.annotate(f"{r['passes']}", (r["seconds"], r["rel_mse"]), textcoords="offset points",
                        xytext=(4, 4), fontsize=7)
        if p:
            ax.plot([r["seconds"] for r in p], [r["rel_mse"] for r in p], "s-", label="path tracer (spp)")
        for r in p:
            ax.annotate(f"{r['spp']}", (r["seconds"], r["rel_mse"]), textcoords="offset points", xytext=(4, -10),
                        fontsize=7)
        for r in paper:
            ax.plot([r["seconds"]], [r["rel_mse"]], "D", color="tab:red", label="paper's estimator")
        for r in nv:
            ax.plot([r["seconds"]], [r["rel_mse"]], "x", color="gray", label="paper's, no visibility")
        if res["ref_noise"] > 0:
            ax.axhline(res["ref_noise"], color="gray", lw=0.8, ls=":", label="reference noise")
        every = res["splat"] + res["path"] + [res["paper"], res["novis"]]
        zero = [r for r in every if r["rel_mse"] <= 0]
        if zero:
            kinds = sorted({"raysplat" if r["method"] == "splat" else "path tracer" if r["method"] == "path" else
                            "paper's estimator" if r["method"] == "paper" else "no visibility" for r in zero})
            ax.text(0.5, 0.5, ("black reference: " if is_black(res) else "") + "error 0 (not drawn)\nfor " +
                    ", ".join(kinds), transform=ax.transAxes, ha="center", va="center", fontsize=8)
        if len(zero) == len(every):
            ax.set_yscale("linear")
            ax.set_yticks([])
            times = [r["seconds"] for r in every]
            ax.set_xlim(min(times) / 1.5, max(times) * 1.5)
        ax.set_title(res["name"])
        ax.set_xlabel("wall time (s)")
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":  # 1, 2, 5 per decade: labels even on a short range
                axis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
            axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", lw=0.3)
    for row in grid:
        row[0].set_ylabel("relative MSE")
    # One legend with every kind of entry any panel drew.
    handles = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    axes[0].legend(handles.values(), handles.keys(), fontsize=7)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)
    plt.close(fig)


def grid_figure(rows, cols, cells, path, cell_inches=1.9):
    """cells[r][c] are RGB8 images; rows and cols are labels."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(rows), len(cols), figsize=(cell_inches * len(cols), cell_inches * len(rows) + 0.3),
                             squeeze=False)
    for i, row in enumerate(rows):
        for j, col in enumerate(cols):
            ax = axes[i][j]
            ax.imshow(cells[i][j], interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(col, fontsize=9)
            if j == 0:
                ax.set_ylabel(row, fontsize=9)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=100)
    os.replace(tmp, path)
    plt.close(fig)


def crop_rect(name, size):
    x, y, w, h = CROPS.get(name, (64, 64, 128, 128))
    s = size / 256.0
    return tuple(int(round(v * s)) for v in (x, y, w, h))


def figures(res, size, outdir):
    ref = res["ref"]
    rect = crop_rect(res["name"], size)
    exposure = images.auto_exposure(ref["beauty"])
    splat = default_run(res)
    path = res["path"][res["splat"].index(splat)]
    splat_layers = images.read_layers(splat["exr"])
    paper_layers = images.read_layers(res["paper"]["exr"])
    rows = {f"reference ({res['validation']['reference_spp']} spp)": ref,
            f"raysplat, {plural(splat['passes'], 'pass')} ({splat['seconds']:.0f} s)": splat_layers,
            f"paper's estimator ({res['paper']['seconds']:.0f} s)": paper_layers,
            f"path tracer, {path['spp']} spp ({path['seconds']:.0f} s)": images.read_layers(path["exr"])}
    cols = list(LAYER_NAMES)
    cells = []
    for layers in rows.values():
        row = []
        for c in cols:
            img = studyutil.crop(layers[c], rect)
            # Layers dimmer than the beauty get their own exposure, the same in every row.
            e = exposure if c == "beauty" else images.auto_exposure(studyutil.crop(ref[c], rect) + 1e-6)
            row.append(images.to_srgb8(img, min(e, exposure + 3)))
        cells.append(row)
    layers_png = os.path.join(outdir, f"{res['name']}_layers.png")
    grid_figure(list(rows), cols, cells, layers_png)

    novis = images.read_layers(res["novis"]["exr"])
    shadows = [("reference", ref), ("paper's, no visibility", novis), ("paper's estimator", paper_layers),
               (f"raysplat, {plural(splat['passes'], 'pass')}", splat_layers)]
    shadows_png = os.path.join(outdir, f"{res['name']}_shadows.png")
    grid_figure([""], [s[0] for s in shadows],
                [[images.to_srgb8(studyutil.crop(s[1]["beauty"], rect), exposure) for s in shadows]], shadows_png,
                cell_inches=2.4)
    return layers_png, shadows_png


# -- Tables and README ------------------------------------------------------------------

def fmt_mb(x):
    return f"{x:.1f}"


def fmt(x, spec):
    """x formatted by spec; '–' for NaN or None (FLIP against a black reference)."""
    return "–" if x is None or x != x else format(x, spec)


def photons_per_pass(r):
    cnt = r["stats"]["counts"]
    stored = cnt.get("photons_stored")
    return f"{int(round(stored / max(cnt.get('passes', 1), 1))):,}" if stored is not None else "?"


def setting(r):
    if r["method"] == "splat":
        return f"{plural(r['passes'], 'pass')}, {photons_per_pass(r)} photons/pass, direct sampled"
    return f"1 pass, {photons_per_pass(r)} photons, direct from photons"


def scene_table(res):
    lines = ["| Method | Setting | Time s | Build (voxelize + tree) | Eye | Photons | Splat | "
             "Memory MB (tree + eye + photons) | rel. MSE | FLIP |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    labels = {"splat": "raysplat", "paper": "paper's estimator", "splat-novis": "paper's, no visibility"}
    for r in res["splat"] + [res["paper"], res["novis"]]:
        sec, cnt = r["stats"]["seconds"], r["stats"]["counts"]
        build = sec.get("voxelize", 0) + sec.get("tree", 0)
        mem = cnt.get("tree_mb", 0) + cnt.get("eye_samples_mb", 0) + cnt.get("photon_mb", 0)
        lines.append(f"| {labels[r['method']]} | {setting(r)} | {r['seconds']:.1f} | {build:.2f} | "
                     f"{sec.get('eye', 0):.2f} | {sec.get('photons', 0):.2f} | {sec.get('splat', 0):.1f} | "
                     f"{fmt_mb(mem)} ({fmt_mb(cnt.get('tree_mb', 0))} + {fmt_mb(cnt.get('eye_samples_mb', 0))} + "
                     f"{fmt_mb(cnt.get('photon_mb', 0))}) | {r['rel_mse']:.3g} | {fmt(r['flip'], '.3f')} |")
    for r in res["path"]:
        lines.append(f"| path tracer | {r['spp']} spp | {r['seconds']:.1f} | – | – | – | – | – | "
                     f"{r['rel_mse']:.3g} | {fmt(r['flip'], '.3f')} |")
    return "\n".join(lines)


def mean_ratio(ours, ref):
    """ours / ref as text; for a black reference layer, whether ours is black too."""
    if ref > 0:
        return f"{ours / ref:.3f}"
    return "0 / 0" if ours == 0 else f"ref 0, ours {ours:.3g}"


def bias_runs(res):
    runs = [default_run(res)]
    longest = max(res["splat"], key=lambda r: r["passes"])
    if longest is not runs[0]:
        runs.append(longest)
    return runs + [res["paper"]]


def bias_table(res):
    """Mean of each layer of a render over the reference's: 1 for an unbiased render, up to noise."""
    lines = ["| Render | " + " | ".join(LAYER_NAMES) + " |", "|---|" + "---|" * len(LAYER_NAMES)]
    for r in bias_runs(res):
        label = (f"raysplat, {plural(r['passes'], 'pass')}" if r["method"] == "splat" else "paper's estimator")
        lines.append(f"| {label} | " + " | ".join(mean_ratio(r["layer_means"].get(k, 0.0), res["ref_layer_means"][k])
                                                   for k in LAYER_NAMES) + " |")
    return "\n".join(lines)


def bias_summary(res):
    return {("paper" if r["method"] == "paper" else f"{r['passes']}pass"):
            {k: (r["layer_means"].get(k, 0.0) / res["ref_layer_means"][k] if res["ref_layer_means"][k] > 0 else None)
             for k in LAYER_NAMES} for r in bias_runs(res)}


def results_markdown(results, machine, args, plot_png, pictures):
    here = os.path.dirname(os.path.abspath(args.readme))  # links relative to the page written
    rel = lambda p: os.path.relpath(p, here)  # noqa: E731
    passes = ", ".join(str(p) for p in args.passes)
    out = [f"Measured by `scripts/run.sh study` (`scripts/study.py`) on {machine['date']}: {machine['cpu']}, "
           f"{machine['threads']} hardware threads, {machine['os']}, raysplat commit {machine['commit']}. "
           f"Images {args.size}×{args.size}; raysplat at its defaults (4 receivers and a direct film of 16 samples "
           "per pixel and pass, visibility by rays with the kernels' coverage measured, 100000 photons per pass "
           "split 0/50/30 %, grid 192), passes varied "
           f"({passes}: each pass new eye samples and photons, kernels shrinking). The paper's estimator "
           "(`--direct photons --passes 1`: direct light from photons too, split 20/50/30 %) is measured once "
           "per scene, and so is splatting without visibility at its settings (the paper's Fig. 4b). Each time "
           "is the wall time of one `raysplat render` (scene load and voxelization included) on a machine that "
           "may be shared, so times can be off by tens of per cent; errors are exact, since every render is "
           "deterministic.",
           "",
           "### The reference, checked against Mitsuba 3",
           "",
           f"The references are raysplat's own path tracer at {args.reference_spp} spp. Each scene was also "
           f"converted to Mitsuba 3 (`scripts/gltf_to_mitsuba.py`) and rendered by its `path` integrator at "
           f"{args.mitsuba_spp} spp (`scripts/validate_mitsuba.py`). *ratio* is the relative MSE between the two "
           "renderers divided by the sum of their own noise (estimated from two independent halves of each): "
           "about 1 when they differ by noise only. Per pixel, rare bright caustic paths make the noise "
           "estimate of the glossy box and the caustic pool unreliable; the 8×8-pixel block means are the test "
           f"(agreement: ratio ≤ {validate_mitsuba.AGREE_RATIO}). A black scene (the sealed room) agrees when "
           "both renderers give all zeros.",
           "",
           validate_mitsuba.markdown([r["validation"] for r in results]),
           "",
           "This check found a bug: shadow rays aimed from the offset origin along the unoffset direction hit "
           "the light itself on surfaces facing it at low elevation (the top of the Cornell box's tall box was "
           "up to 3× too dark). It is fixed, and `tests/path_test.cpp` now checks Lambert's polygon formula "
           "there. Material models: the gold icosahedron is Mitsuba's `principled` (metallic 1), whose masking "
           "term is the separable Smith one where raysplat uses the height-correlated one; at roughness 0.3 "
           "the difference stays inside the noise. A scene whose materials the converter cannot carry over "
           "differs by design: textured_room's normal, metallic-roughness and emissive textures and its vertex "
           "colours are left out of its Mitsuba scene (the converter warns of each); Blender's Cycles checks "
           "that scene instead (`scripts/blender_cycles_check.py`, in the `blender` test suite).",
           ""]
    for res in results:
        v = res["validation"]
        out.append(f"{res['name']}: raysplat | Mitsuba | difference of 8×8 block means (black 0, bright ≥ 10 %)")
        out.append("")
        out.append(f"![{res['name']}: raysplat against Mitsuba]({rel(v['published_image'])})")
        out.append("")
    out += ["### raysplat against both references", "",
            f"raysplat's default render ({plural(default_passes(args.passes), 'pass')}) and a second one with "
            "`--seed 2`, averaged, against the path-traced reference and against Mitsuba, on 8×8-pixel block means "
            "as above; the noise is the two seeds' and the reference's own. A kernel estimator is biased "
            "(light moved within a kernel's width); *ratio* says whether that bias shows above the noise at this "
            f"budget (agreement: ratio ≤ {validate_mitsuba.AGREE_RATIO}).", "",
            agreement_table(results), "",
            "### Error against time", "",
            f"![relative MSE against wall time]({rel(plot_png)})", "",
            "Relative MSE is mean((x − ref)² / (ref² + 0.01)) over pixels and channels, as `raysplat compare` "
            "prints it; the dotted line is the reference's own noise, a floor under every curve. Numbers by the "
            "raysplat curve are passes, by the path tracer's samples per pixel; the diamond is the paper's "
            "estimator. The path tracer's sample counts come from two timed runs (start-up cost and cost per sample), so "
            "its times come out close to, but not exactly at, those of the splat runs they match; *when raysplat "
            "wins* therefore "
            "compares each splat run with the path tracer's error at the same time, interpolated along its "
            "curve (and extrapolated as error ∝ 1/time past its longest run). Zero errors (a black reference "
            "rendered black) cannot be drawn on the log scale and are left out.", "",
            "*Bias* tables give the mean of each layer of a splat render over the reference's mean of the same "
            "layer: 1 for an unbiased render up to noise, below 1 where light is lost (e.g. kernels refused "
            "behind walls), above where it leaks.", ""]
    for res, (layers_png, shadows_png) in zip(results, pictures):
        out += [f"### {res['name']}", "",
                f"**When raysplat wins:** {verdict(res)}.", "",
                scene_table(res), "",
                "Bias: mean of each layer over the reference's:", "",
                bias_table(res), "",
                f"Layers (the paper's Fig. 5), crop {crop_rect(res['name'], args.size)}:", "",
                f"![{res['name']} layers]({rel(layers_png)})", "",
                "Shadow contrast (the paper's Fig. 4): without visibility the splat leaks light into shadows.", "",
                f"![{res['name']} shadows]({rel(shadows_png)})", ""]
    return "\n".join(out).rstrip() + "\n"


def json_safe(x):
    """NaN and infinities (FLIP of a black reference) as null: study.json stays strict JSON."""
    if isinstance(x, float) and not np.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    studyutil.add_common_arguments(ap)
    ap.add_argument("--passes", default="1,2,4,8,16",
                    help="pass counts for raysplat at its defaults, comma-separated (default 1,2,4,8,16)")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the timed renders of an earlier run (with their times) to redo the report")
    ap.add_argument("--readme", default=os.path.join(studyutil.ROOT, "docs", "results.md"),
                    help="the page whose results section is rewritten")
    ap.add_argument("--no-readme", action="store_true", help="leave that page alone")
    ap.add_argument("--results", default=os.path.join(studyutil.ROOT, RESULTS_DIR),
                    help="directory for the published pictures (default docs/results)")
    args = ap.parse_args()
    try:
        args.passes = sorted(set(int(v) for v in args.passes.split(",")))
    except ValueError:
        sys.exit(f"error: --passes '{args.passes}': expected comma-separated integers")
    if not args.passes or min(args.passes) < 1 or args.size < 16 or args.reference_spp < 2:
        sys.exit("error: --passes must be positive, --size ≥ 16 and --reference-spp ≥ 2")
    binary = studyutil.find_binary(args.build)
    scenes = args.scenes or validate_mitsuba.data_scenes()
    machine = studyutil.machine()

    results = [run_scene(binary, s, args) for s in scenes]
    os.makedirs(args.results, exist_ok=True)
    for res in results:  # publish the Mitsuba comparison next to the other pictures
        v = res["validation"]
        v["published_image"] = os.path.join(args.results, f"{res['name']}_mitsuba.png")
        with open(v["image"], "rb") as src, open(v["published_image"] + ".tmp", "wb") as dst:
            dst.write(src.read())
        os.replace(v["published_image"] + ".tmp", v["published_image"])
    plot_png = os.path.join(args.results, "rel_mse_vs_time.png")
    plot(results, plot_png)
    pictures = [figures(res, args.size, args.results) for res in results]
    body = results_markdown(results, machine, args, plot_png, pictures)
    keys = ("seconds", "rel_mse", "flip", "max")
    summary = {res["name"]: {"verdict": verdict(res),
                             "reference_max": res["ref_max"],
                             "splat": [{"passes": r["passes"], **{k: r[k] for k in keys}} for r in res["splat"]],
                             "paper": {k: res["paper"][k] for k in keys},
                             "novis": {k: res["novis"][k] for k in keys},
                             "path": [{"spp": r["spp"], **{k: r[k] for k in keys}} for r in res["path"]],
                             "layer_mean_ratio": bias_summary(res),
                             "agreement": res["agreement"],
                             "validation": {k: v for k, v in res["validation"].items() if k != "image"}}
               for res in results}
    with open(os.path.join(args.out, "study.json"), "w") as f:
        json.dump(json_safe({"machine": machine, "passes": args.passes, "scenes": summary}), f, indent=1,
                  allow_nan=False)
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write(body)
    if not args.no_readme:
        studyutil.replace_section(args.readme, BEGIN, END, body)
        log(f"updated {os.path.relpath(args.readme, studyutil.ROOT)}")
    for name, s in summary.items():
        log(f"{name}: {s['verdict']}")


if __name__ == "__main__":
    main()
