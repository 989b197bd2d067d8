#!/usr/bin/env python3
"""Quality-versus-time study of raysplat: what photon ray splatting buys and what it costs.

  python3 scripts/study.py [--build build] [--out out/study] [--size 256]
                           [--photons 25000,50000,100000,200000,400000]
                           [--reference-spp 2048] [--mitsuba-spp 1024]
                           [--readme README.md | --no-readme] [SCENE ...]

(`scripts/run.sh study` installs what is missing, builds, and runs this.)

For each scene (default: every scene of data/):
  1. a converged reference from raysplat's path tracer (two seeds, cached in OUT), itself
     checked against Mitsuba 3 (validate_mitsuba.py);
  2. raysplat's photon ray splatting at increasing photon counts, each timed;
  3. the path tracer at the same wall times (samples per pixel chosen from a timed
     calibration run, then the real time measured), and splatting without visibility;
  4. relative MSE and FLIP of every render against the reference.
It writes a plot of relative MSE against time, Table-1-style tables, the layers of the
paper's Fig. 5 (direct / indirect / caustic / beauty) and the shadow contrast of its Fig. 4
(reference / splat-novis / splat) into docs/results/, and the README's Results section
between its `results:begin` and `results:end` markers. Times are wall-clock seconds of one
`raysplat render` each (load and voxelization included), on however many cores the machine
has; each render is deterministic, so only its time varies between runs.
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
# shadows and, in the glossy box, the caustic under the glass sphere.
CROPS = {"cornell_box": (16, 120, 128, 128), "glossy_box": (24, 136, 112, 112),
         "direct_light": (20, 48, 112, 112)}


def scene_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def measure(layers, ref):
    return {"rel_mse": images.rel_mse(layers["beauty"], ref["beauty"]),
            "flip": images.flip(layers["beauty"], ref["beauty"])[0]}


def run_scene(binary, scene, args):
    reuse = args.reuse
    name = scene_name(scene)
    outdir = os.path.join(args.out, name)
    size = (args.size, args.size)
    log(f"== {name}")
    validation = validate_mitsuba.validate(binary, scene, args.out, size, args.reference_spp, args.mitsuba_spp)
    ref, ref_noise, _ = studyutil.reference(binary, scene, outdir, size, args.reference_spp)
    common = ["--width", args.size, "--height", args.size]
    runs = []

    for n in args.photons:
        out = os.path.join(outdir, f"splat_{n}.exr")
        log(f"{name}: splat, {n} photons")
        wall, stats = studyutil.render(binary, scene, out, "splat", common + ["--photons", n], cache=reuse)
        runs.append({"method": "splat", "photons": n, "seconds": wall, "stats": stats, "exr": out,
                     **measure(images.read_layers(out), ref)})

    default_photons = args.photons[len(args.photons) // 2]
    out = os.path.join(outdir, f"novis_{default_photons}.exr")
    log(f"{name}: splat without visibility, {default_photons} photons")
    wall, stats = studyutil.render(binary, scene, out, "splat-novis", common + ["--photons", default_photons],
                                   cache=reuse)
    novis = {"method": "splat-novis", "photons": default_photons, "seconds": wall, "stats": stats, "exr": out,
             **measure(images.read_layers(out), ref)}

    calib_spp = 16
    wall, _ = studyutil.render(binary, scene, os.path.join(outdir, "path_calibration.exr"), "path",
                               common + ["--spp", calib_spp], cache=reuse)
    per_spp = wall / calib_spp
    paths = []
    for r in runs:
        spp = max(1, int(round(r["seconds"] / per_spp)))
        out = os.path.join(outdir, f"path_{spp}spp.exr")
        log(f"{name}: path tracer, {spp} spp (matching {r['seconds']:.1f} s)")
        wall, stats = studyutil.render(binary, scene, out, "path", common + ["--spp", spp], cache=reuse)
        paths.append({"method": "path", "spp": spp, "seconds": wall, "stats": stats, "exr": out,
                      **measure(images.read_layers(out), ref)})
    return {"name": name, "scene": scene, "ref": ref, "ref_noise": ref_noise, "validation": validation,
            "splat": runs, "novis": novis, "path": paths, "default_photons": default_photons}


def path_error_at(paths, seconds):
    """Path tracer's rel. MSE at `seconds`: interpolated in log-log between measured points;
    past the longest run, extrapolated as error ∝ 1/time (variance ∝ 1/samples)."""
    pts = sorted((p["seconds"], p["rel_mse"]) for p in paths)
    t = np.log([p[0] for p in pts])
    e = np.log([p[1] for p in pts])
    if seconds > pts[-1][0]:
        return pts[-1][1] * pts[-1][0] / seconds
    return float(np.exp(np.interp(np.log(seconds), t, e)))


def verdict(result):
    ratios = [r["rel_mse"] / path_error_at(result["path"], r["seconds"]) for r in result["splat"]]
    wins = [r for r, q in zip(result["splat"], ratios) if q < 1.0]
    budgets = ", ".join(f"{r['seconds']:.0f} s" for r in result["splat"])
    margin = (f"; at equal time raysplat's relative MSE is {min(ratios):.3g}–{max(ratios):.3g}× "
              "the path tracer's")
    if not wins:
        return f"nowhere: the path tracer has the lower error at every budget measured ({budgets}){margin}"
    if len(wins) == len(result["splat"]):
        return f"raysplat has the lower error at every budget measured ({budgets}){margin}"
    return ("raysplat has the lower error at " + ", ".join(f"{r['seconds']:.0f} s" for r in wins) +
            "; the path tracer at the other budgets (" + budgets + ")" + margin)


# -- Pictures -------------------------------------------------------------------------------

def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    fig, axes = plt.subplots(1, len(results), figsize=(4.2 * len(results), 3.6), squeeze=False)
    for ax, res in zip(axes[0], results):
        s, p = res["splat"], res["path"]
        ax.loglog([r["seconds"] for r in s], [r["rel_mse"] for r in s], "o-", label="raysplat (photons)")
        for r in s:
            ax.annotate(f"{r['photons'] // 1000}k", (r["seconds"], r["rel_mse"]), textcoords="offset points",
                        xytext=(4, 4), fontsize=7)
        ax.loglog([r["seconds"] for r in p], [r["rel_mse"] for r in p], "s-", label="path tracer (spp)")
        for r in p:
            ax.annotate(f"{r['spp']}", (r["seconds"], r["rel_mse"]), textcoords="offset points", xytext=(4, -10),
                        fontsize=7)
        nv = res["novis"]
        ax.loglog([nv["seconds"]], [nv["rel_mse"]], "x", color="gray", label="splat, no visibility")
        ax.axhline(res["ref_noise"], color="gray", lw=0.8, ls=":", label="reference noise")
        ax.set_title(res["name"])
        ax.set_xlabel("wall time (s)")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
            axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", lw=0.3)
    axes[0][0].set_ylabel("relative MSE")
    axes[0][0].legend(fontsize=7)
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
    splat = next(r for r in res["splat"] if r["photons"] == res["default_photons"])
    path = res["path"][res["splat"].index(splat)]
    rows = {f"reference ({res['validation']['reference_spp']} spp)": ref,
            f"raysplat, {splat['photons'] // 1000}k photons ({splat['seconds']:.0f} s)": images.read_layers(splat["exr"]),
            f"path tracer, {path['spp']} spp ({path['seconds']:.0f} s)": images.read_layers(path["exr"])}
    cols = ["direct", "indirect", "caustic", "beauty"]
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
    shadows = [("reference", ref), ("splat, no visibility", novis), ("splat", images.read_layers(splat["exr"]))]
    shadows_png = os.path.join(outdir, f"{res['name']}_shadows.png")
    grid_figure([""], [s[0] for s in shadows],
                [[images.to_srgb8(studyutil.crop(s[1]["beauty"], rect), exposure) for s in shadows]], shadows_png,
                cell_inches=2.4)
    return layers_png, shadows_png


# -- Tables and README ------------------------------------------------------------------

def fmt_mb(x):
    return f"{x:.1f}"


def scene_table(res):
    lines = ["| Method | Setting | Time s | Build (voxelize + tree) | Eye | Photons | Splat | "
             "Memory MB (tree + eye + photons) | rel. MSE | FLIP |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in res["splat"] + [res["novis"]]:
        sec, cnt = r["stats"]["seconds"], r["stats"]["counts"]
        build = sec.get("voxelize", 0) + sec.get("tree", 0)
        mem = cnt.get("tree_mb", 0) + cnt.get("eye_samples_mb", 0) + cnt.get("photon_mb", 0)
        label = "raysplat" if r["method"] == "splat" else "raysplat, no visibility"
        lines.append(f"| {label} | {r['photons']:,} photons | {r['seconds']:.1f} | {build:.2f} | "
                     f"{sec.get('eye', 0):.2f} | {sec.get('photons', 0):.2f} | {sec.get('splat', 0):.1f} | "
                     f"{fmt_mb(mem)} ({fmt_mb(cnt.get('tree_mb', 0))} + {fmt_mb(cnt.get('eye_samples_mb', 0))} + "
                     f"{fmt_mb(cnt.get('photon_mb', 0))}) | {r['rel_mse']:.3g} | {r['flip']:.3f} |")
    for r in res["path"]:
        lines.append(f"| path tracer | {r['spp']} spp | {r['seconds']:.1f} | – | – | – | – | – | "
                     f"{r['rel_mse']:.3g} | {r['flip']:.3f} |")
    return "\n".join(lines)


def results_markdown(results, machine, args, plot_png, pictures):
    rel = lambda p: os.path.relpath(p, studyutil.ROOT)  # noqa: E731
    out = [f"Measured by `scripts/run.sh study` (`scripts/study.py`) on {machine['date']}: {machine['cpu']}, "
           f"{machine['threads']} hardware threads, {machine['os']}, raysplat commit {machine['commit']}. "
           f"Images {args.size}×{args.size}; raysplat at its defaults (4 eye samples per pixel, photon split "
           f"20/50/30 %, grid 192) but for the photon count. Each time is the wall time of one `raysplat render` "
           "(scene load and voxelization included) on a machine that may be shared, so times can be off by tens "
           "of per cent; errors are exact, since every render is deterministic.",
           "",
           "### The reference, checked against Mitsuba 3",
           "",
           f"The references are raysplat's own path tracer at {args.reference_spp} spp. Each scene was also "
           f"converted to Mitsuba 3 (`scripts/gltf_to_mitsuba.py`) and rendered by its `path` integrator at "
           f"{args.mitsuba_spp} spp (`scripts/validate_mitsuba.py`). *ratio* is the relative MSE between the two "
           "renderers divided by the sum of their own noise (estimated from two independent halves of each): "
           "about 1 when they differ by noise only. Per pixel, rare bright caustic paths make the noise "
           "estimate of the glossy box unreliable; the 8×8-pixel block means are the test "
           f"(agreement: ratio ≤ {validate_mitsuba.AGREE_RATIO}).",
           "",
           validate_mitsuba.markdown([r["validation"] for r in results]),
           "",
           "This check found a bug: shadow rays aimed from the offset origin along the unoffset direction hit "
           "the light itself on surfaces facing it at low elevation (the top of the Cornell box's tall box was "
           "up to 3× too dark). It is fixed, and `tests/path_test.cpp` now checks Lambert's polygon formula "
           "there. Material models: the gold icosahedron is Mitsuba's `principled` (metallic 1), whose masking "
           "term is the separable Smith one where raysplat uses the height-correlated one; at roughness 0.3 "
           "the difference stays inside the noise.",
           ""]
    for res in results:
        v = res["validation"]
        out.append(f"{res['name']}: raysplat | Mitsuba | difference of 8×8 block means (black 0, bright ≥ 10 %)")
        out.append("")
        out.append(f"![{res['name']}: raysplat against Mitsuba]({rel(v['published_image'])})")
        out.append("")
    out += ["### Error against time", "",
            f"![relative MSE against wall time]({rel(plot_png)})", "",
            "Relative MSE is mean((x − ref)² / (ref² + 0.01)) over pixels and channels, as `raysplat compare` "
            "prints it; the dotted line is the reference's own noise, a floor under every curve. The path "
            "tracer's sample counts come from a timed 16-spp run, whose start-up cost makes them come out "
            "somewhat shorter than the splat runs they match; *when raysplat wins* therefore compares each "
            "splat run with the path tracer's error at the same time, interpolated along its curve (and "
            "extrapolated as error ∝ 1/time past its longest run).", ""]
    for res, (layers_png, shadows_png) in zip(results, pictures):
        out += [f"### {res['name']}", "",
                f"**When raysplat wins:** {verdict(res)}.", "",
                scene_table(res), "",
                f"Layers (the paper's Fig. 5), crop {crop_rect(res['name'], args.size)}:", "",
                f"![{res['name']} layers]({rel(layers_png)})", "",
                "Shadow contrast (the paper's Fig. 4): without visibility the splat leaks light into shadows.", "",
                f"![{res['name']} shadows]({rel(shadows_png)})", ""]
    return "\n".join(out).rstrip() + "\n"


def update_readme(readme, body):
    text = open(readme, encoding="utf-8").read()
    if BEGIN not in text or END not in text:
        sys.exit(f"error: {readme} has no '{BEGIN}' … '{END}' markers for the results")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    tmp = readme + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(head + BEGIN + "\n" + body + END + tail)
    os.replace(tmp, readme)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    studyutil.add_common_arguments(ap)
    ap.add_argument("--photons", default="25000,50000,100000,200000,400000",
                    help="photon counts for raysplat, comma-separated")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the timed renders of an earlier run (with their times) to redo the report")
    ap.add_argument("--readme", default=os.path.join(studyutil.ROOT, "README.md"), help="README to update")
    ap.add_argument("--no-readme", action="store_true", help="leave the README alone")
    ap.add_argument("--results", default=os.path.join(studyutil.ROOT, RESULTS_DIR),
                    help="directory for the published pictures (default docs/results)")
    args = ap.parse_args()
    try:
        args.photons = [int(v) for v in args.photons.split(",")]
    except ValueError:
        sys.exit(f"error: --photons '{args.photons}': expected comma-separated integers")
    if not args.photons or min(args.photons) < 1 or args.size < 16 or args.reference_spp < 2:
        sys.exit("error: --photons, --size (≥ 16) and --reference-spp (≥ 2) must be positive")
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
    summary = {res["name"]: {"verdict": verdict(res),
                             "splat": [{k: r[k] for k in ("photons", "seconds", "rel_mse", "flip")} for r in res["splat"]],
                             "path": [{k: r[k] for k in ("spp", "seconds", "rel_mse", "flip")} for r in res["path"]],
                             "validation": {k: v for k, v in res["validation"].items() if k != "image"}}
               for res in results}
    with open(os.path.join(args.out, "study.json"), "w") as f:
        json.dump({"machine": machine, "scenes": summary}, f, indent=1)
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write(body)
    if not args.no_readme:
        update_readme(args.readme, body)
        log(f"updated {os.path.relpath(args.readme, studyutil.ROOT)}")
    for name, s in summary.items():
        log(f"{name}: {s['verdict']}")


if __name__ == "__main__":
    main()
