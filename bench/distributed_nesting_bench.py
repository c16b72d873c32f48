"""What finding cavities costs triangulate_tiled: a hollow ball (Fibonacci spheres of 200 000
and 98 000 points, radii 1 and 0.7) with an 18 000-point marble in its cavity, in 2 x 2 x 1
tiles on a 2-worker LocalCluster, with the nesting round and with it skipped (every closed
component then enclosing positive volume, the behaviour before), alternated; one process's
triangulate beside them.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/distributed_nesting_bench.py [--runs 3]
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402
import particlemesh.distributed as pmd  # noqa: E402
from particlemesh.distributed import _seams  # noqa: E402


def fibonacci_sphere(n, radius=1.0, centre=(0.0, 0.0, 0.0)):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (1 + 5 ** 0.5) * i
    return radius * np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1) + centre


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    from dask.distributed import Client, LocalCluster
    pts = np.concatenate([fibonacci_sphere(200000), fibonacci_sphere(98000, 0.7),
                          fibonacci_sphere(18000, 0.3, (0.1, 0, 0))])
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=None)
    client = Client(cluster)
    t = time.perf_counter()
    one = pm.triangulate(pts)
    print(f"one process: {time.perf_counter() - t:.3f} s, outward {pm.topology(one)['outward']}")
    pairs = _seams.Stitch.nesting_pairs
    for _ in range(args.runs):
        for mode in ("nesting", "skipped"):
            _seams.Stitch.nesting_pairs = pairs if mode == "nesting" else (lambda self, *a: {})
            t = time.perf_counter()
            m = pmd.triangulate_tiled(client, pts, tiles=(2, 2, 1))
            wall = time.perf_counter() - t
            print(f"{mode}: {wall:.3f} s, driver's seams {m.stats['seconds_seams']:.3f} s, "
                  f"tests {m.stats['nesting_tests']}, outward {pm.topology(m)['outward']}")
    _seams.Stitch.nesting_pairs = pairs
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
