#!/usr/bin/env python3
"""Compare two EXR images: relative MSE, RMSE and mean HDR-FLIP, per layer.

  python3 scripts/compare.py A.exr REFERENCE.exr [--layer NAME] [--crop x,y,w,h]
                             [--diff diff.png]

The second file is the reference. Every layer both files have is compared (beauty =
R,G,B; direct., indirect., caustic., emission.) unless --layer names one. --crop
restricts the figures to a pixel rectangle (origin top left). --diff writes a
false-colour PNG of the beauty (or --layer) difference: black where the images agree,
bright where |A − REF| reaches half the reference (relative to |REF| + 0.1).

Relative MSE is mean((A − REF)² / (REF² + 0.01)), the formula of `raysplat compare`.
FLIP is NVIDIA's HDR-FLIP (PyPI flip-evaluator), 0 for identical images.
The script installs its packages into .venv-study/ on first use.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import venv_bootstrap  # noqa: E402

venv_bootstrap.ensure()

import images  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("image", help="EXR to measure")
    ap.add_argument("reference", help="reference EXR")
    ap.add_argument("--layer", choices=images.LAYERS, help="compare only this layer")
    ap.add_argument("--crop", metavar="x,y,w,h", help="compare only this pixel rectangle")
    ap.add_argument("--diff", metavar="PNG", help="write a false-colour difference image")
    args = ap.parse_args()

    a = images.read_layers(args.image)
    ref = images.read_layers(args.reference)
    if a["beauty"].shape != ref["beauty"].shape:
        sys.exit(f"error: {args.image} is {a['beauty'].shape[1]}×{a['beauty'].shape[0]} but "
                 f"{args.reference} is {ref['beauty'].shape[1]}×{ref['beauty'].shape[0]}")
    window = images.parse_crop(args.crop, a["beauty"].shape) if args.crop else (slice(None), slice(None))
    names = [args.layer] if args.layer else [n for n in images.LAYERS if n in a and n in ref]
    for name in names:
        if name not in a or name not in ref:
            sys.exit(f"error: layer '{name}' is missing from "
                     f"{args.image if name not in a else args.reference}")
    print(f"{'layer':<10} {'relMSE':>10} {'RMSE':>10} {'FLIP':>8}")
    for name in names:
        x, r = a[name][window], ref[name][window]
        if not r.any() and not x.any():
            print(f"{name:<10} {'(empty in both)':>30}")
            continue
        fl, _ = images.flip(x, r)
        print(f"{name:<10} {images.rel_mse(x, r):10.5f} {images.rmse(x, r):10.5f} {fl:8.4f}")
    if args.diff:
        name = args.layer or "beauty"
        d = images.diff_image(a[name][window], ref[name][window])
        images.save_png(args.diff, images.false_colour(d, 0.5))
        print(f"wrote {args.diff}")


if __name__ == "__main__":
    main()
