"""The spacing estimate on particles with strays far away: an evenly sampled sphere (a
Fibonacci sphere of radius 1, --points) plus one particle 1e7 away, two such spheres 1e7
apart, 600 copies of one particle parked 1e9 away, and 5 % of the count scattered over a cube
of side 1e7. Each file is given to `particlemesh inspect` of every CLI named (the estimate,
then the grid's span check that names the stray), under --timeout seconds; the wall time and
the spacing it prints are listed, with the brute-force median (scipy's k-d tree) beside them.

    /usr/bin/python3 bench/far_strays_bench.py build/cli/particlemesh [OTHER_CLI ...] [--points N]
"""
import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree


def fibonacci_sphere(n, radius=1.0, centre=(0.0, 0.0, 0.0)):
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    p = np.c_[np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
    return p * radius + np.asarray(centre)


def median_nn(p):
    p = np.unique(p, axis=0)
    d, _ = cKDTree(p).query(p, k=2)
    return np.sort(d[:, 1])[(len(p) - 1) // 2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cli", nargs="+", help="particlemesh executables to compare")
    parser.add_argument("--points", type=int, default=100_000)
    parser.add_argument("--timeout", type=float, default=120)
    args = parser.parse_args()
    n = args.points
    sphere = fibonacci_sphere(n)
    rng = np.random.default_rng(1)
    cases = {
        "one stray 1e7 away": np.r_[sphere, [[1e7, 0, 0]]],
        "two spheres 1e7 apart": np.r_[sphere, fibonacci_sphere(n, 1.0, (1e7, 0, 0))],
        "600 copies parked 1e9 away": np.r_[sphere, np.tile([1e9, 1e9, 1e9], (600, 1))],
        "5 % scattered over 1e7": np.r_[sphere, rng.uniform(0, 1e7, (n // 20, 3))],
    }
    with tempfile.TemporaryDirectory() as folder:
        for name, points in cases.items():
            path = Path(folder) / "cloud.xyz"
            np.savetxt(path, points)
            print(f"{name} ({len(points)} particles): brute-force median {median_nn(points):.9g}")
            for cli in args.cli:
                t0 = time.perf_counter()
                try:
                    out = subprocess.run([cli, "inspect", str(path)], capture_output=True, text=True,
                                         timeout=args.timeout).stdout
                    spacing = next((line.split()[1] for line in out.splitlines() if line.strip().startswith("spacing")), "-")
                    print(f"  {cli}: {time.perf_counter() - t0:.2f} s, spacing {spacing}")
                except subprocess.TimeoutExpired:
                    print(f"  {cli}: over {args.timeout:.0f} s (stopped)")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
