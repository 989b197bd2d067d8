#!/usr/bin/env python3
"""mpi_test: a render divided between Open MPI ranks is the render of one process, to the bit.

Runs the real binary ($RAYSPLAT) under `mpirun --oversubscribe` against the same command
without mpirun, and compares the EXRs' pixel data byte for byte (docs/design.md §11): splat with
passes going round the ranks and with one pass shared between them, the path tracer both ways,
and a --time-limit render, whose ranks must agree on one pass count; a walkthrough's frames
dealt whole to ranks, each the frame one process renders. A failing rank must end every rank
with one error line and no output. Skips (77) without mpirun or without MPI in the
build.

  mpi_test.py --mpi true|false   (whether raysplat was built with Open MPI)
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cli_test as cli  # noqa: E402  (the EXR parsing and the runner's conventions)

RAYSPLAT = cli.RAYSPLAT
SMALL = ("--width", "32", "--spp", "2", "--photons", "4000", "--grid", "48", "--threads", "1", "--quiet")


def mpirun_command(ranks):
    return ["mpirun", "--oversubscribe", "-np", str(ranks)] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])


def mpirun(ranks, *args, timeout=300):
    return subprocess.run(mpirun_command(ranks) + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          timeout=timeout, text=True, errors="replace")


def render(out, name, ranks, scene, *args):
    """Renders to out/name.exr (with stats) with `ranks` MPI ranks, or one plain process for 0."""
    exr, stats = os.path.join(out, name + ".exr"), os.path.join(out, name + ".json")
    command = ["render", scene, "-o", exr, "--stats-json", stats, *SMALL, *args]
    r = mpirun(ranks, RAYSPLAT, *command) if ranks else cli.run(*command, timeout=300)
    cli.check(r.returncode == 0, "%s with %d ranks failed (%d): %s" % (name, ranks, r.returncode, r.stderr))
    with open(exr, "rb") as f:
        pixels = cli.exr_pixel_chunks(f.read())
    with open(stats) as f:
        counts = json.load(f)["counts"]
    return pixels, counts


def same_image(ranks, scene, *args):
    def test():
        with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
            one, one_counts = render(out, "one", 0, scene, *args)
            many, many_counts = render(out, "many", ranks, scene, *args)
        cli.check(many_counts.get("ranks") == ranks, "stats say %r ranks" % many_counts.get("ranks"))
        cli.check(many_counts["passes"] == one_counts["passes"], "passes %r vs %r" % (many_counts["passes"], one_counts["passes"]))
        cli.check(many == one, "the pixels of %d ranks differ from one process's" % ranks)
    return test


def test_time_limit_ranks_agree_on_the_passes():
    """With a given kernel scale the passes go in whole rounds; with the scale measured (the
    default), the first pass is every rank's, then whole rounds follow."""
    fixed = ("--kernel-scale", "1")
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        many, counts = render(out, "many", 2, cli.CORNELL, "--time-limit", "2", *fixed)
        passes, film = int(counts["passes"]), int(counts["film_passes"])
        cli.check(passes >= 2 and passes % 2 == 0, "2 ranks rendered %d passes: whole rounds of 2 expected" % passes)
        cli.check(film % 2 == 0, "2 ranks rendered %d film passes: whole rounds of 2 expected" % film)
        film_args = ("--film-passes", str(film)) if film else ()
        one, _ = render(out, "one", 0, cli.CORNELL, "--passes", str(passes), *film_args, *fixed)
        _, measured = render(out, "measured", 2, cli.CORNELL, "--time-limit", "2")
    cli.check(many == one, "the time-limited image differs from %d passes and %d film passes in one process" % (passes, film))
    shared = int(measured["passes"])
    cli.check(shared % 2 == 1, "2 ranks measuring the kernel scale rendered %d passes: 1 + whole rounds of 2 expected" % shared)


def check_rank_without_its_scene(scene, output, *args):
    """Rank 0 renders scene, rank 1 a scene that does not exist (mpirun's MPMD form), both to
    output (a name in the temporary folder) with args: one error line naming the missing file,
    a non-zero exit and no file left."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        target = os.path.join(out, output)
        good = ["render", scene, "-o", target, *args, *SMALL]
        bad = ["render", os.path.join(out, "missing.gltf"), "-o", target, *args, *SMALL]
        r = mpirun(1, RAYSPLAT, *good, ":", "-np", "1", RAYSPLAT, *bad)
        leftover = os.listdir(out)
    errors = [line for line in r.stderr.splitlines() if line.startswith("raysplat")]
    cli.check(r.returncode != 0, "mpirun exited 0")
    cli.check(errors == ["raysplat: error: %s: no such file" % os.path.join(out, "missing.gltf")],
              "expected one error line naming the file, got %r" % errors)
    cli.check(leftover == [], "files left behind: %r" % leftover)


def test_a_failing_rank_ends_all_with_one_message():
    """Rank 1 is given a scene that does not exist: no output, one line."""
    check_rank_without_its_scene(cli.CORNELL, "x.exr")


def test_ctrl_c_stops_every_rank_cleanly():
    """SIGINT to mpirun (it sends the ranks SIGTERM): every rank stops, one line, no files."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        command = mpirun_command(2) + [RAYSPLAT, "render", cli.CORNELL, "-o", os.path.join(out, "x.exr"), "--png",
                    os.path.join(out, "x.png"), "--passes", "50", "--threads", "1"]
        interrupt_after(command, "rendering", 1)  # once the passes have begun
        leftover = os.listdir(out)
    cli.check(leftover == [], "files left behind: %r" % leftover)


def interrupt_after(command, word, times):
    """Runs command (an mpirun), sends it SIGINT once `word` has appeared `times` times in its
    standard error, and checks that it stops within 30 s, exits non-zero and says "stopped" in
    one line."""
    p = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace")
    seen = ""
    while seen.count(word) < times:
        line = p.stderr.readline()
        cli.check(line != "", "mpirun ended before %r appeared %d times: %s" % (word, times, seen))
        seen += line
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        p.kill()
        raise cli.Failure("the ranks did not stop within 30 s of SIGINT")
    stopped = [line for line in err.splitlines() if line.startswith("raysplat:") and "stopped" in line]
    cli.check(p.returncode != 0, "mpirun exited 0 after SIGINT")
    cli.check(len(stopped) == 1, "expected one 'stopped' line, got %r" % stopped)


def walk(out, name, ranks, *args, frames=(1, 3)):
    """--frames 1-3 (`frames`) of the walkthrough (2 passes a frame) to out/name_####.exr with
    stats, by `ranks` MPI ranks or one plain process for 0: {frame: (pixels, counts)}, and stderr."""
    command = ["render", os.path.join(cli.DATA, "interior_walk.gltf"), "-o", os.path.join(out, name + "_####.exr"),
               "--stats-json", os.path.join(out, name + "_####.json"), "--frames", "%d-%d" % frames, "--width", "32",
               "--passes", "2", "--photons", "8000", "--spp", "1", "--direct-spp", "2", "--grid", "48", *args]
    r = mpirun(ranks, RAYSPLAT, *command) if ranks else cli.run(*command, timeout=300)
    cli.check(r.returncode == 0, "%s with %d ranks failed (%d): %s" % (name, ranks, r.returncode, r.stderr))
    written = {}
    for f in range(frames[0], frames[1] + 1):
        if not os.path.exists(os.path.join(out, "%s_%04d.exr" % (name, f))):
            continue
        with open(os.path.join(out, "%s_%04d.exr" % (name, f)), "rb") as exr, \
                open(os.path.join(out, "%s_%04d.json" % (name, f))) as stats:
            written[f] = (cli.exr_pixel_chunks(exr.read()), json.load(stats)["counts"])
    return written, r.stderr


def test_whole_frames_go_to_ranks():
    """mpirun -n 2 … --frames 1-3: rank 0 renders frames 1 and 3, rank 1 frame 2, each by itself
    (its own photons, traced once a rank for the range); every frame's pixels are those one
    process renders (with another thread count). Rank 0 reports every frame once. With frame 2
    removed, --skip-existing renders it alone, the same again."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        one, _ = walk(out, "one", 0, "--threads", "2")
        many, err = walk(out, "many", 2, "--threads", "1")
        cli.check(sorted(many) == [1, 2, 3], "frames written: %r" % sorted(many))
        for f in (1, 2, 3):
            cli.check(many[f][0] == one[f][0], "frame %d of 2 ranks differs from one process's" % f)
            cli.check(many[f][1]["ranks"] == 1, "frame %d was divided between %r ranks" % (f, many[f][1]["ranks"]))
        traced = {f: many[f][1]["photon_passes_traced"] for f in (1, 2, 3)}
        cli.check(traced == {1: 2, 2: 2, 3: 0}, "passes traced a frame (rank 0: 1 and 3, rank 1: 2): %r" % traced)
        wrote = [line for line in err.splitlines() if "wrote" in line]
        cli.check(len(wrote) == 3 and ", rank 1," in wrote[1] and ", rank 0," in wrote[2], "the frames' lines: %r" % wrote)
        os.remove(os.path.join(out, "many_0002.exr"))
        again, err = walk(out, "many", 2, "--threads", "1", "--skip-existing")
        cli.check(again[2][0] == one[2][0], "frame 2 rendered again differs")
        skipped = [line for line in err.splitlines() if "skipped" in line]
        cli.check(len(skipped) == 2, "expected frames 1 and 3 skipped once each: %r" % skipped)


def test_fewer_frames_than_ranks_are_divided():
    """mpirun -n 3 … --frames 1-2: each frame divided between the 3 ranks as a still is, its
    pixels one process's."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        one, _ = walk(out, "one", 0, frames=(1, 2))
        many, _ = walk(out, "many", 3, "--threads", "1", frames=(1, 2))
    cli.check(sorted(many) == [1, 2], "frames written: %r" % sorted(many))
    for f in (1, 2):
        cli.check(many[f][0] == one[f][0], "frame %d of 3 ranks differs from one process's" % f)
        cli.check(many[f][1]["ranks"] == 3, "frame %d was rendered by %r ranks" % (f, many[f][1]["ranks"]))


def test_frame_step_deals_every_nth_frame():
    """mpirun -n 2 … --frames 1-5 --frame-step 2: frames 1, 3 and 5 alone are written, whole
    frames to ranks (rank 0: 1 and 5, rank 1: 3), each the one process's."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        one, _ = walk(out, "one", 0, "--frame-step", "2", frames=(1, 5))
        many, err = walk(out, "many", 2, "--threads", "1", "--frame-step", "2", frames=(1, 5))
    cli.check(sorted(one) == [1, 3, 5] and sorted(many) == [1, 3, 5], "frames written: %r, %r" % (sorted(one), sorted(many)))
    for f in (1, 3, 5):
        cli.check(many[f][0] == one[f][0], "frame %d of 2 ranks differs from one process's" % f)
        cli.check(many[f][1]["ranks"] == 1, "frame %d was divided between %r ranks" % (f, many[f][1]["ranks"]))
    wrote = [line for line in err.splitlines() if "wrote" in line]
    cli.check(len(wrote) == 3 and "(frame 3, rank 1," in wrote[1] and "(frame 5, rank 0," in wrote[2], "the frames' lines: %r" % wrote)


def test_a_failing_rank_stops_the_frames():
    """Rank 1 cannot read its scene: one error line and no frame written by either rank."""
    check_rank_without_its_scene(os.path.join(cli.DATA, "interior_walk.gltf"), "w_####.exr", "--frames", "1-4")


def test_ctrl_c_leaves_whole_frames():
    """SIGINT to mpirun once the first round of frames is written: every rank stops, one line,
    and the files left are whole frames of that range (no staged files)."""
    with tempfile.TemporaryDirectory(prefix="raysplat_mpi_") as out:
        command = mpirun_command(2) + [RAYSPLAT, "render", os.path.join(cli.DATA, "interior_walk.gltf"), "-o",
                                       os.path.join(out, "w_####.exr"), "--frames", "0-40", "--width", "32",
                                       "--passes", "4", "--photons", "8000", "--threads", "1"]
        interrupt_after(command, "wrote", 2)  # once two frames are written
        left = sorted(os.listdir(out))
        for name in left:
            cli.check(len(name) == len("w_0000.exr") and name.startswith("w_") and name.endswith(".exr"),
                      "a file that is not a frame: %r" % name)
            with open(os.path.join(out, name), "rb") as f:
                cli.check(len(cli.exr_pixel_chunks(f.read())) > 0, "%s is not a whole EXR" % name)
    cli.check("w_0000.exr" in left and "w_0001.exr" in left and len(left) < 41, "frames left: %r" % left)


def test_bad_settings_are_said_once():
    r = mpirun(2, RAYSPLAT, "render", cli.CORNELL, "-o", "x.exr", "--spp", "-1")
    errors = [line for line in r.stderr.splitlines() if line.startswith("raysplat")]
    cli.check(r.returncode != 0 and len(errors) == 1, "exit %d, error lines %r" % (r.returncode, errors))


def main():
    built_with_mpi = "--mpi" in sys.argv and sys.argv[sys.argv.index("--mpi") + 1] == "true"
    if not built_with_mpi or not shutil.which("mpirun"):
        print("mpi_test: skipped: %s" % ("raysplat was built without MPI" if not built_with_mpi else "no mpirun"))
        return 77
    tests = [
        ("splat: 3 passes round 2 ranks", same_image(2, cli.GLOSSY, "--passes", "3")),
        ("splat: 1 pass shared by 3 ranks (the paper's estimator)", same_image(3, cli.GLOSSY, "--direct", "photons", "--passes", "1")),
        ("splat: 2 passes and 3 film passes round 2 ranks", same_image(2, cli.CORNELL, "--passes", "2", "--film-passes", "3")),
        ("splat: 1 pass of 2 photon rounds shared by 2 ranks", same_image(2, cli.CORNELL, "--passes", "1", "--photon-rounds", "2")),
        ("splat: 3 passes of 2 photon rounds round 2 ranks", same_image(2, cli.CORNELL, "--passes", "3", "--photon-rounds", "2")),
        ("path: 3 passes round 2 ranks", same_image(2, cli.GLOSSY, "--method", "path", "--passes", "3")),
        ("path: 1 pass's rows shared by 3 ranks", same_image(3, cli.GLOSSY, "--method", "path")),
        ("time limit: ranks agree on the passes", test_time_limit_ranks_agree_on_the_passes),
        ("a failing rank ends all ranks with one message", test_a_failing_rank_ends_all_with_one_message),
        ("walkthrough: whole frames go to ranks, each the one process's", test_whole_frames_go_to_ranks),
        ("walkthrough: fewer frames than ranks are divided", test_fewer_frames_than_ranks_are_divided),
        ("walkthrough: --frame-step deals every Nth frame to ranks", test_frame_step_deals_every_nth_frame),
        ("walkthrough: a failing rank stops the frames", test_a_failing_rank_stops_the_frames),
        ("walkthrough: Ctrl-C leaves whole frames", test_ctrl_c_leaves_whole_frames),
        ("bad settings are said once", test_bad_settings_are_said_once),
        ("Ctrl-C stops every rank cleanly", test_ctrl_c_stops_every_rank_cleanly),
    ]
    failed = 0
    for name, test in tests:
        try:
            test()
            print("PASS  %s" % name)
        except (cli.Failure, subprocess.TimeoutExpired, OSError, KeyError, ValueError) as e:
            failed += 1
            print("FAIL  %s: %s" % (name, e))
    print("%d passed, %d failed" % (len(tests) - failed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
