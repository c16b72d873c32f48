"""A spinning lidar's sweep of flat ground, written as a point file: the kind of cloud whose
density varies by orders of magnitude (rings of points dense along each ring, the rings
farther apart the farther out), for timing the surface pipeline on it beside the peers.

    /usr/bin/python3 bench/lidar_sweep.py -o lidar.ply [--beams 64] [--step 0.2] [--noise 0.005]
    build/cli/particlemesh triangulate lidar.ply -o mesh.ply
    build/bench/scan_bench --scan lidar.ply --as-is --no-gp3 --runs 1

The sensor stands 2 m above the ground; its beams are spaced evenly from 25 to 1 degrees
below the horizon, fired every --step degrees of azimuth; returns beyond 120 m are dropped
and each coordinate gets Gaussian noise of --noise metres (a fixed seed). Written as text
for .xyz, else by the library's mesh writer (.ply, .obj, .vtk, .vtu, .vtp), points only.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402


def sweep(beams, step, noise, height=2.0, max_range=120.0, seed=0):
    """(N, 3) float64 returns of the sweep on the plane z = 0."""
    elevation = np.radians(np.linspace(-25.0, -1.0, beams))
    azimuth = np.radians(np.arange(0.0, 360.0, step))
    e, a = np.meshgrid(elevation, azimuth)
    direction = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)
    distance = height / -direction[:, 2]
    points = direction[distance < max_range] * distance[distance < max_range, None] + [0.0, 0.0, height]
    points[:, 2] = 0.0
    return points + np.random.default_rng(seed).normal(0.0, noise, points.shape)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--beams", type=int, default=64)
    parser.add_argument("--step", type=float, default=0.2, help="degrees of azimuth between firings")
    parser.add_argument("--noise", type=float, default=0.005, help="metres (Gaussian, per coordinate)")
    args = parser.parse_args()
    if args.beams < 2 or not args.step > 0 or not args.noise >= 0:
        parser.error("--beams must be at least 2, --step above 0 and --noise at least 0")
    points = sweep(args.beams, args.step, args.noise)
    if args.output.lower().endswith(".xyz"):
        np.savetxt(args.output, points, fmt="%.9g")
    else:
        pm.write_mesh(pm.Mesh(np.ascontiguousarray(points), np.zeros((0, 3), dtype=np.int32)), args.output)
    print(f"{len(points)} points -> {args.output}")


if __name__ == "__main__":
    main()
