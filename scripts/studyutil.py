"""Running raysplat from the study scripts: timed renders, cached references, machine facts."""

import hashlib
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

import images

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def log(msg):
    print(msg, flush=True)


def add_common_arguments(ap):
    """Arguments shared by study.py and validate_mitsuba.py, with the same defaults, so
    that either script reuses the renders the other cached."""
    ap.add_argument("scenes", nargs="*", help="glTF scenes (default: every scene of data/)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="meson build directory")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "study"), help="renders and caches")
    ap.add_argument("--size", type=int, default=256, help="image width and height in pixels (default 256)")
    ap.add_argument("--reference-spp", type=int, default=2048,
                    help="samples per pixel of the path-traced reference (default 2048)")
    ap.add_argument("--mitsuba-spp", type=int, default=1024, help="Mitsuba samples per pixel (default 1024)")


def find_binary(build):
    path = os.path.join(build, "raysplat")
    if not os.access(path, os.X_OK):
        sys.exit(f"error: {path} not found: build it first (scripts/run.sh build)")
    return path


def file_digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()[:16]


def render(binary, scene, out, method, args=(), cache=False):
    """Run `raysplat render` and return (wall seconds, stats JSON).

    With cache=True an earlier result with the same command line and scene bytes is
    reused (references only: they take minutes). Timed runs are never cached.
    """
    stats = out[:-4] + ".json"
    cmd = [binary, "render", scene, "-o", out, "--method", method, "--stats-json", stats, "--quiet", *map(str, args)]
    key = os.path.splitext(out)[0] + ".key"
    want = json.dumps({"cmd": [os.path.basename(binary)] + cmd[1:], "scene": file_digest(scene)})
    if cache and os.path.exists(out) and os.path.exists(key) and open(key).read() == want:
        with open(stats) as f:
            s = json.load(f)
        return s.get("wall_seconds", s["total_seconds"]), s
    os.makedirs(os.path.dirname(out), exist_ok=True)
    t0 = time.perf_counter()
    r = subprocess.run(cmd, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} failed:\n{r.stderr.strip()}")
    with open(stats) as f:
        s = json.load(f)
    s["wall_seconds"] = wall
    with open(stats, "w") as f:
        json.dump(s, f, indent=1)
    with open(key, "w") as f:
        f.write(want)
    return wall, s


def reference(binary, scene, outdir, size, spp, log_prefix=""):
    """Converged path-traced reference: two independent halves of spp/2 samples each.

    Returns (layers of the average, noise): noise is the expected relative MSE of the
    average against the true image, estimated from the halves (relMSE(h1, h2) / 4).
    """
    halves = []
    for seed in (1, 2):
        out = os.path.join(outdir, f"reference_{size[0]}x{size[1]}_{spp}spp_half{seed}.exr")
        log(f"{log_prefix}reference half {seed}: path tracer, {spp // 2} spp (cached when unchanged)")
        render(binary, scene, out, "path",
                         ["--width", size[0], "--height", size[1], "--spp", spp // 2, "--seed", seed], cache=True)
        halves.append(images.read_layers(out))
    layers = {k: 0.5 * (halves[0][k] + halves[1][k]) for k in halves[0]}
    return layers, half_noise(halves[0]["beauty"], halves[1]["beauty"]), halves


def half_noise(h1, h2):
    """Expected relative MSE of (h1 + h2) / 2 against the truth, for independent halves.

    h1 − avg = (h1 − h2) / 2 has the variance σ²/2 of the average itself, so the error of
    the average is estimated by the mean of relMSE(h1, avg) and relMSE(h2, avg).
    """
    avg = 0.5 * (h1 + h2)
    return 0.5 * (images.rel_mse(h1, avg) + images.rel_mse(h2, avg))


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip()
    except OSError:
        commit = ""
    return {"cpu": cpu, "threads": len(os.sched_getaffinity(0)), "date": time.strftime("%Y-%m-%d"),
            "os": platform.platform(terse=True), "commit": commit or "unknown"}


def block_means(img, block):
    h, w = img.shape[0] // block * block, img.shape[1] // block * block
    return img[:h, :w].reshape(h // block, block, w // block, block, -1).mean(axis=(1, 3))


def crop(img, rect):
    x, y, w, h = rect
    return img[y:y + h, x:x + w]


def upscale(img8, factor):
    return np.repeat(np.repeat(img8, factor, axis=0), factor, axis=1)


def replace_section(path, begin, end, body):
    """Rewrite what lies between the markers begin and end in the page at path."""
    text = open(path, encoding="utf-8").read()
    if begin not in text or end not in text:
        sys.exit(f"error: {path} has no '{begin}' … '{end}' markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(head + begin + "\n" + body + end + tail)
    os.replace(tmp, path)
