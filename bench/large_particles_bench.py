"""Polygonize with per-particle radii when a few are far larger than the rest: a jittered
block of 40 x 80 x 40 particles (spacing 0.02, pscale 0.01: R = 4 x pscale = 2 spacings),
as it is, with one particle's pscale 0.2 (R 20 times the rest), with 50 drawn from 0.05-0.3,
and with every pscale drawn from 0.01-0.05 (an even spread). Each case goes through
`particlemesh polygonize --radius-channel pscale` of every CLI named (--runs times, the
median wall time, under --timeout seconds), with the triangle count and whether the meshes
of the CLIs are the same file, or the largest vertex distance between them when not.

    /usr/bin/python3 bench/large_particles_bench.py build/cli/particlemesh [OTHER_CLI ...] [--runs 3]
"""
import argparse
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np


def write_ply(path, points, pscale):
    data = np.zeros(len(points), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("pscale", "<f4")])
    data["x"], data["y"], data["z"] = points.T
    data["pscale"] = pscale
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(points)}\n"
              "property float x\nproperty float y\nproperty float z\nproperty float pscale\n"
              "end_header\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(data.tobytes())


def read_ply_vertices(path):
    """The vertices of a binary little-endian PLY of float x y z (+ more floats) as written
    by particlemesh."""
    raw = Path(path).read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    lines = raw[:end].decode().splitlines()
    count = next(int(line.split()[2]) for line in lines if line.startswith("element vertex"))
    types = {"float": "<f4", "double": "<f8", "uchar": "u1", "int": "<i4", "uint": "<u4"}
    dtype = []
    in_vertex = False
    for line in lines:
        if line.startswith("element"):
            in_vertex = line.startswith("element vertex")
        elif line.startswith("property") and in_vertex:
            _, t, name = line.split()
            dtype.append((name, types[t]))
    v = np.frombuffer(raw, dtype=dtype, count=count, offset=end)
    return np.c_[v["x"], v["y"], v["z"]].astype(np.float64)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cli", nargs="+", help="particlemesh executables to compare")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--timeout", type=float, default=300)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    grid = np.stack(np.meshgrid(np.arange(40), np.arange(80), np.arange(40), indexing="ij"), -1)
    points = grid.reshape(-1, 3) * 0.02 + rng.uniform(-0.004, 0.004, (40 * 80 * 40, 3))
    n = len(points)
    even = np.full(n, 0.01)
    one = even.copy()
    one[n // 2] = 0.2
    fifty = even.copy()
    fifty[rng.choice(n, 50, replace=False)] = rng.uniform(0.05, 0.3, 50)
    cases = {"equal radii": even, "one 20 times larger": one, "50 of 5-30 times": fifty,
             "all drawn from 1-5 times": rng.uniform(0.01, 0.05, n)}
    with tempfile.TemporaryDirectory() as folder:
        for name, pscale in cases.items():
            path = Path(folder) / "block.ply"
            write_ply(path, points, pscale)
            print(f"{name} ({n} particles):")
            outputs = []
            for k, cli in enumerate(args.cli):
                out = Path(folder) / f"out{k}.ply"
                times = []
                for _ in range(args.runs):
                    t0 = time.perf_counter()
                    try:
                        subprocess.run([cli, "polygonize", str(path), "-o", str(out), "--radius-channel",
                                        "pscale", "-q"], check=True, timeout=args.timeout)
                    except subprocess.TimeoutExpired:
                        times = None
                        break
                    times.append(time.perf_counter() - t0)
                if times is None:
                    print(f"  {cli}: over {args.timeout:.0f} s")
                    outputs.append(None)
                    continue
                v = read_ply_vertices(out)
                outputs.append((out.read_bytes(), v))
                print(f"  {cli}: {statistics.median(times):.3f} s (median of {len(times)}), {len(v)} vertices")
            if len(outputs) > 1 and all(outputs):
                ref = outputs[0]
                for o, cli in zip(outputs[1:], args.cli[1:]):
                    if o[0] == ref[0]:
                        print(f"  {cli}: the same file")
                    elif o[1].shape == ref[1].shape:
                        print(f"  {cli}: largest vertex distance {np.abs(o[1] - ref[1]).max():.3g}")
                    else:
                        print(f"  {cli}: {len(o[1])} vertices against {len(ref[1])}")


if __name__ == "__main__":
    main()
