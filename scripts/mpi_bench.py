#!/usr/bin/env python3
"""Distributed renders on this machine: the splat phase on 1, 2 and 4 Open MPI ranks.

    python3 scripts/mpi_bench.py [--build build] [--runs 3] [--scene data/glossy_box.glb]
                                 [--passes 1] [--width 500]

Renders the scene at the paper's settings (`--direct photons`, 100 000 photons, grid 192,
--passes 1 by default: every rank splats a share of the one pass) as one process, then under
`mpirun -np N` for N = 1, 2, 4 with the machine's cores divided between the ranks (at least
one thread each: where ranks outnumber cores, mpirun oversubscribes and the table says so).
Prints medians of --runs: wall time of the whole command, rank 0's splat time, and its
eye + tree + photon time (repeated on every rank when a pass is shared), and checks each
image is bit-identical to the single process's. Timings are medians: the machine may be
shared.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--scene", default=os.path.join(ROOT, "data", "glossy_box.glb"))
    ap.add_argument("--passes", type=int, default=1)
    ap.add_argument("--width", type=int, default=500)
    a = ap.parse_args()
    exe = os.path.join(a.build, "raysplat")
    if not shutil.which("mpirun"):
        sys.exit("mpi_bench: no mpirun (apt-get install openmpi-bin libopenmpi-dev, then rebuild)")
    cores = os.cpu_count() or 1
    common = ["render", a.scene, "--width", str(a.width), "--direct", "photons", "--passes", str(a.passes),
              "--photons", "100000", "--grid", "192", "--quiet"]
    # --bind-to none: Open MPI binds each of up to two ranks to one core by default, which would
    # leave a rank's threads sharing it.
    mpirun = ["mpirun", "--oversubscribe", "--bind-to", "none"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_bench_") as out:
        setups = [("1 process", 0)] + [("%d rank%s" % (n, "s" if n > 1 else ""), n) for n in (1, 2, 4)]
        reference = None
        print("%s, %dx%d, --direct photons --passes %d, %d cores, medians of %d" %
              (os.path.basename(a.scene), a.width, a.width, a.passes, cores, a.runs))
        print("| setup | threads a rank | wall s | splat s (rank 0) | eye + tree + photons s (rank 0) | same image |")
        print("| --- | --- | --- | --- | --- | --- |")
        for label, ranks in setups:
            threads = max(1, cores // max(ranks, 1))
            walls, splats, others, same = [], [], [], True
            for run in range(a.runs):
                exr, stats = os.path.join(out, "%d.exr" % ranks), os.path.join(out, "%d.json" % ranks)
                cmd = [exe] + common + ["-o", exr, "--stats-json", stats, "--threads", str(threads)]
                if ranks:
                    cmd = mpirun + ["-np", str(ranks)] + cmd
                t = time.perf_counter()
                r = subprocess.run(cmd, capture_output=True, text=True)
                walls.append(time.perf_counter() - t)
                if r.returncode != 0:
                    sys.exit("mpi_bench: %s failed: %s" % (" ".join(cmd), r.stderr.strip()))
                with open(stats) as f:
                    s = json.load(f)["seconds"]
                splats.append(s.get("splat", 0.0))
                others.append(sum(s.get(k, 0.0) for k in ("eye", "tree", "photons")))
                compare = subprocess.run([exe, "compare", exr, reference or exr], capture_output=True, text=True)
                if reference is None:
                    reference = os.path.join(out, "reference.exr")
                    shutil.copy(exr, reference)
                else:
                    errors = [float(l.split()[1]) for l in compare.stdout.splitlines()[1:]]  # every layer's
                    same = same and bool(errors) and max(errors) == 0.0
            note = " (oversubscribed)" if ranks * threads > cores else ""
            print("| %s%s | %d | %.2f | %.2f | %.2f | %s |" % (label, note, threads, statistics.median(walls),
                  statistics.median(splats), statistics.median(others), "yes" if same else "NO"))


if __name__ == "__main__":
    main()
