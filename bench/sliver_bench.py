"""Marching cubes' slivers and collapse_edges: for each input, polygonize with the defaults and
with collapse_edges = 0.2, 0.3 and 0.4, and print the triangles, the share of triangles whose
smallest angle is under 5, 10 and 20 degrees, the topology (components, Euler
characteristic, closed) and the wall time of the call (best of --runs). Inputs: the shared SPH frames (../shared/data/particles, skipped with a message when
absent) and the live-mode bench frame (1.5 x a 100 000-point Fibonacci sphere, 1.47M
triangles).

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/sliver_bench.py [--runs 3] [--data DIR]
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402


def fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def smallest_angles(m):
    v, t = m.vertices, m.triangles
    corners = [v[t[:, k]] for k in range(3)]
    least = np.full(len(t), 180.0)
    for k in range(3):
        p, q, r = corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]
        u, w = q - p, r - p
        c = np.einsum("ij,ij->i", u, w) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
        least = np.minimum(least, np.degrees(np.arccos(np.clip(c, -1, 1))))
    return least


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data"))
    args = parser.parse_args()
    inputs = []
    for name in ("double_dam_break_frame_26_4732_particles.vtk", "bunny_frame_14_7705_particles.vtk"):
        path = os.path.join(args.data, "particles", name)
        if os.path.isfile(path):
            inputs.append((name, pm.read_points(path).positions))
        else:
            print(f"{name}: not found under {args.data}: skipped")
    inputs.append(("live frame: 1.5 x fibonacci_sphere(100000)", 1.5 * fibonacci_sphere(100000)))
    for name, p in inputs:
        print(name)
        for f in (0.0, 0.2, 0.3, 0.4):
            best, m = float("inf"), None
            for _ in range(args.runs):
                t = time.perf_counter()
                m = pm.polygonize(p, collapse_edges=f)
                best = min(best, time.perf_counter() - t)
            a = smallest_angles(m)
            top = pm.topology(m)
            print(f"  collapse_edges {f:.1f}: {m.triangle_count:8d} triangles, angle < 5: "
                  f"{100 * np.mean(a < 5):5.2f} %, < 10: {100 * np.mean(a < 10):5.2f} %, < 20: "
                  f"{100 * np.mean(a < 20):5.1f} %; components {top['components']}, Euler "
                  f"{top['euler_characteristic']}, closed {top['closed']}; {best:.3f} s")


if __name__ == "__main__":
    main()
