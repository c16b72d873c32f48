"""Frames per second of `particlemesh polygonize` on a sequence, against the shell loop a user
would otherwise write (one process per frame).

    /usr/bin/python3 bench/sequence_bench.py build/cli/particlemesh [--frames 100] [--side 24]

Generates a sequence of FRAMES binary PLY frames (velocity and density per particle) in a
scratch folder: a block of side^3 particles (spacing 0.02) sloshing like a dam break (the top
shears and tilts from frame to frame). Then meshes it four ways, each timed by wall clock:

  loop       one `particlemesh polygonize fluid_NNN.ply -o mesh_NNN.ply` per frame (the peer)
  --jobs 1   `particlemesh polygonize "fluid_{:03d}.ply" -o "seq1/mesh_{:03d}.ply" --jobs 1`
  --jobs 2   the same with --jobs 2 (and --threads shared between the two frames in flight)
  re-run     --jobs 2 again: every frame is up to date (the options sidecars are checked)

and checks that the three sets of meshes are the same bytes. Prints a Markdown table row per
way (frames/s), for bench/RESULTS.md."""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

SPACING = 0.02
OPTIONS = ["--radius", "0.04", "--cell", "0.01", "-q"]


def frame(f, frames, side):
    """The particles of frame f: a block whose upper layers shear along x and slump."""
    g = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3) * SPACING
    t = f / max(frames - 1, 1)
    h = g[:, 2] / (side * SPACING)
    p = g.copy()
    p[:, 0] += 0.5 * side * SPACING * t * h ** 2 * np.sin(3 * t + g[:, 1] * 4)
    p[:, 2] *= 1.0 - 0.3 * t * h
    v = np.column_stack([1.5 * h ** 2 * np.cos(3 * t + g[:, 1] * 4), np.zeros(len(p)), -0.3 * h])
    d = 1000.0 + 50 * (1 - h)
    return p.astype(np.float32), v.astype(np.float32), d.astype(np.float32)


def write_ply(path, p, v, d):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(p) +
            "".join(f"property float {q}\n" for q in
                    ["x", "y", "z", "velocity_x", "velocity_y", "velocity_z", "density"]) +
            "end_header\n")
    with open(path, "wb") as out:
        out.write(head.encode() + np.hstack([p, v, d[:, None]]).astype("<f4").tobytes())


def timed(cmd):
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cli")
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--side", type=int, default=24)
    ap.add_argument("--keep", action="store_true", help="keep the scratch folder")
    a = ap.parse_args()
    cli = os.path.abspath(a.cli)
    work = tempfile.mkdtemp(prefix="pm_sequence_bench_")
    try:
        for f in range(a.frames):
            write_ply(os.path.join(work, f"fluid_{f:03d}.ply"), *frame(f, a.frames, a.side))
        for sub in ("loop", "seq1", "seq2"):
            os.mkdir(os.path.join(work, sub))
        n = a.side ** 3
        rows = []
        t = time.perf_counter()
        for f in range(a.frames):
            subprocess.run([cli, "polygonize", os.path.join(work, f"fluid_{f:03d}.ply"), "-o",
                            os.path.join(work, "loop", f"mesh_{f:03d}.ply"), *OPTIONS], check=True)
        rows.append(("loop of single-file runs (peer)", time.perf_counter() - t))
        pattern = os.path.join(work, "fluid_{:03d}.ply")
        rows.append(("sequence, --jobs 1", timed([cli, "polygonize", pattern, "-o",
                                                  os.path.join(work, "seq1", "mesh_{:03d}.ply"),
                                                  *OPTIONS, "--jobs", "1"])))
        rows.append(("sequence, --jobs 2", timed([cli, "polygonize", pattern, "-o",
                                                  os.path.join(work, "seq2", "mesh_{:03d}.ply"),
                                                  *OPTIONS, "--jobs", "2"])))
        rows.append(("re-run, all up to date", timed([cli, "polygonize", pattern, "-o",
                                                      os.path.join(work, "seq2", "mesh_{:03d}.ply"),
                                                      *OPTIONS, "--jobs", "2"])))
        for f in range(a.frames):
            name = f"mesh_{f:03d}.ply"
            ref = open(os.path.join(work, "loop", name), "rb").read()
            for sub in ("seq1", "seq2"):
                if open(os.path.join(work, sub, name), "rb").read() != ref:
                    sys.exit(f"{sub}/{name} differs from the single-file run's")
        size = os.path.getsize(os.path.join(work, "loop", "mesh_000.ply"))
        print(f"{a.frames} frames of {n} particles (velocity, density), "
              f"polygonize {' '.join(OPTIONS)}; frame 0's mesh {size / 1e6:.1f} MB; "
              "outputs identical in all three runs")
        print("| run | wall (s) | frames/s |")
        print("|---|---|---|")
        for name, s in rows:
            print(f"| {name} | {s:.2f} | {a.frames / s:.2f} |")
    finally:
        if a.keep:
            print("scratch folder:", work)
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
