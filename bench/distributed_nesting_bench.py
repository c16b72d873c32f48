"""What finding cavities costs triangulate_tiled: a hollow ball (Fibonacci spheres of 200 000
and 98 000 points, radii 1 and 0.7) with an 18 000-point marble in its cavity, in 2 x 2 x 1
tiles on a 2-worker LocalCluster, with the nesting round and with it skipped (every closed
component then enclosing positive volume, the behaviour before), alternated; one process's
triangulate beside them.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/distributed_nesting_bench.py [--runs 3]

With --pairs, only the driver's pairing of nested boxes (Stitch.nesting_pairs) on a tank
holding 1 000, 10 000 and 30 000 small closed bubbles, beside a test of every pair of boxes
(the pairing before), checked to give the same pairs.
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


def every_pair(lo, hi, point, closed):
    """The pairs as testing each closed component's box against every other's."""
    inner = closed[np.isfinite(point[closed, 0])]
    pairs = {}
    for d in closed.tolist():
        holds = ((lo[inner] >= lo[d]) & (hi[inner] <= hi[d])).all(axis=1) & (inner != d)
        if holds.any():
            pairs[d] = (inner[holds], point[inner[holds]])
    return pairs


def bench_pairs(runs):
    rng = np.random.default_rng(1)
    for n in (1000, 10000, 30000):
        st = _seams.Stitch.__new__(_seams.Stitch)
        st.n_pieces, st.root = n, np.arange(n)
        st.comp_open, st.extra = np.zeros(n, bool), np.zeros((0, 3), np.int64)
        c, r = rng.uniform(0, 10, (n, 3)), rng.uniform(0.01, 0.05, (n, 1))
        lo, hi = c - r, c + r
        lo[0], hi[0] = -1, 11  # the tank holds every bubble
        for _ in range(runs):
            t = time.perf_counter()
            got = st.nesting_pairs(lo, hi, c)
            t_sorted = time.perf_counter() - t
            t = time.perf_counter()
            ref = every_pair(lo, hi, c, np.arange(n))
            t_every = time.perf_counter() - t
            assert got.keys() == ref.keys() and all(np.array_equal(got[k][0], ref[k][0]) for k in got)
            print(f"{n} components, {sum(len(v[0]) for v in got.values())} pairs: by low x "
                  f"{t_sorted:.3f} s, every pair {t_every:.3f} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--pairs", action="store_true", help="only the driver's pairing")
    args = parser.parse_args()
    if args.pairs:
        return bench_pairs(args.runs)
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
