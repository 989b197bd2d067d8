"""EXR layers, error metrics and PNG output shared by the study scripts.

Layers are H×W×3 float32 arrays keyed by name: "beauty" is R,G,B; "direct" is
direct.R, direct.G, direct.B; and so on for every prefix the file has.
rel_mse() is the same formula as raysplat's own `compare` (lib/film.cpp), so figures
from the CLI and from these scripts agree.
"""

import os

import numpy as np

LAYERS = ("beauty", "direct", "indirect", "caustic", "emission")
# Below this peak reference luminance FLIP's exposure range is empty (start > stop exposure).
FLIP_MIN_LUMINANCE = 1e-6


def read_layers(path):
    import OpenEXR
    if not os.path.exists(path):
        raise SystemExit(f"error: {path}: no such file")
    try:
        with OpenEXR.File(path, separate_channels=True) as f:
            channels = {k: np.asarray(v.pixels, dtype=np.float32) for k, v in f.channels().items()}
    except Exception as e:  # OpenEXR raises plain exceptions for unreadable files
        raise SystemExit(f"error: {path}: not a readable EXR file ({e})")
    layers = {}
    for name in ("",) + tuple(n + "." for n in LAYERS[1:] + ("albedo", "normal")):
        keys = [name + c for c in "RGB"]
        if all(k in channels for k in keys):
            layers[name[:-1] if name else "beauty"] = np.stack([channels[k] for k in keys], axis=-1)
    if "beauty" not in layers:
        raise SystemExit(f"error: {path}: EXR has no R, G, B channels")
    return layers


def write_exr(path, rgb):
    """Beauty-only EXR (float32 R, G, B); written under a temporary name, then renamed."""
    import OpenEXR
    tmp = path + ".tmp.exr"
    channels = {c: np.ascontiguousarray(rgb[..., i], dtype=np.float32) for i, c in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(tmp)
    os.replace(tmp, path)


def parse_crop(text, shape):
    """"x,y,w,h" in pixels (origin top left) → a pair of slices inside the image."""
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise SystemExit(f"error: --crop '{text}': expected x,y,w,h in pixels")
    height, width = shape[:2]
    if w <= 0 or h <= 0 or x < 0 or y < 0 or x + w > width or y + h > height:
        raise SystemExit(f"error: --crop '{text}' is outside the {width}×{height} image")
    return (slice(y, y + h), slice(x, x + w))


def rel_mse(a, ref):
    """Mean over pixels and channels of (a − ref)² / (ref² + 0.01)."""
    a = a.astype(np.float64)
    ref = ref.astype(np.float64)
    return float(np.mean((a - ref) ** 2 / (ref * ref + 1e-2)))


def rmse(a, ref):
    return float(np.sqrt(np.mean((a.astype(np.float64) - ref.astype(np.float64)) ** 2)))


def flip(a, ref):
    """Mean HDR-FLIP error (0 = identical) and the per-pixel error map.

    NaN (and a NaN map) when the reference is black or nearly so: FLIP derives its exposure
    range from the reference and aborts the whole process (no exception) when it is empty.
    """
    import flip_evaluator
    lum = np.clip(ref, 0, None).astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    if not np.isfinite(lum).all() or lum.max() < FLIP_MIN_LUMINANCE:
        return float("nan"), np.full(a.shape[:2], np.nan)
    emap, mean, _ = flip_evaluator.evaluate(np.clip(ref, 0, None).astype(np.float32),
                                            np.clip(a, 0, None).astype(np.float32), "HDR",
                                            applyMagma=False)
    return float(mean), np.asarray(emap).reshape(a.shape[:2])


def to_srgb8(rgb, exposure=0.0):
    """Linear radiance → 8-bit sRGB with a plain exposure scale and clipping."""
    x = np.clip(rgb * (2.0 ** exposure), 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255.0 + 0.5).astype(np.uint8)


def false_colour(values, vmax):
    """Scalar map → RGB8 through matplotlib's magma, 0 black and vmax (or more) bright."""
    from matplotlib import colormaps
    t = np.clip(values / vmax if vmax > 0 else values * 0, 0.0, 1.0)
    return (colormaps["magma"](t)[..., :3] * 255 + 0.5).astype(np.uint8)


def diff_image(a, ref):
    """Per-pixel relative difference |a − ref| / (|ref| + 0.1), luminance-weighted; scale 0..1."""
    w = np.array([0.2126, 0.7152, 0.0722])
    return np.abs((a - ref) @ w) / (np.abs(ref @ w) + 0.1)


def save_png(path, rgb8):
    from PIL import Image
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp.png"
    Image.fromarray(rgb8).save(tmp, format="PNG", optimize=True)
    os.replace(tmp, path)


def auto_exposure(ref):
    """Exposure (stops) that maps the 97th luminance percentile of ref to 0.8."""
    lum = ref @ np.array([0.2126, 0.7152, 0.0722])
    p = float(np.percentile(lum, 97))
    return float(np.log2(0.8 / p)) if p > 0 else 0.0
