"""The Python package's call overhead against the C ABI, on 100k points.

    PYTHONPATH=build/python python3 bench/python_overhead.py [--build build] [--points 100000]
        [--rounds 5] [--repetitions 3]

Two measures, printed as Markdown:
  - end to end: triangulate() / polygonize() from Python against build/bench/capi_call_bench
    doing the same through the C ABI (cloud from arrays, the call with default options and a
    progress callback, vertices / triangles / normals copied out in double precision),
    interleaved in rounds so that both see the same machine load; the median of each;
  - around the main call: the time spent outside pm_triangulate / pm_polygonize_ex (making
    the cloud, copying the mesh out; timed from inside the binding, and inside the C program),
    in Python and in C; their difference is what the binding adds, and it hardly depends on
    the load on the machine, which the end-to-end times do."""
import argparse
import os
import platform
import statistics
import subprocess
import tempfile
import time

import numpy as np

import particlemesh as pm
from particlemesh import _library


def fibonacci_sphere(n):
    i = np.arange(n, dtype=np.float64) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / n)
    theta = np.pi * (1.0 + 5.0 ** 0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)


def c_times(program, path, repetitions, what):
    out = subprocess.run([program, path, str(repetitions), what], capture_output=True,
                         text=True, check=True).stdout
    return [(float(line.split()[1]), float(line.split()[2])) for line in out.splitlines()]


class Timed:
    """Wraps one library function to time the calls into it."""

    def __init__(self, fn):
        self.fn, self.seconds = fn, []

    def __call__(self, *args):
        start = time.perf_counter()
        try:
            return self.fn(*args)
        finally:
            self.seconds.append(time.perf_counter() - start)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default="build")
    parser.add_argument("--points", type=int, default=100000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repetitions", type=int, default=3)
    args = parser.parse_args()
    program = os.path.join(args.build, "bench", "capi_call_bench")
    points = fibonacci_sphere(args.points)
    lib = _library.load()
    print(f"particlemesh {pm.version()} ({lib.path}), numpy {np.__version__}, Python "
          f"{platform.python_version()}, {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.2f}")
    print()
    print(f"| call ({args.points} points) | C ABI | Python | end to end | around the call, C "
          "| around the call, Python | the binding adds |")
    print("|---|---|---|---|---|---|---|")
    notes = []
    with tempfile.NamedTemporaryFile(suffix=".f64") as f:
        f.write(points.astype("<f8").tobytes())
        f.flush()
        for what, call, entry in (("triangulate", lambda: pm.triangulate(points), "pm_triangulate"),
                                  ("polygonize", lambda: pm.polygonize(points), "pm_polygonize_ex")):
            c, py, inside = [], [], Timed(getattr(lib, entry))
            setattr(lib, entry, inside)
            try:
                call()  # warm up both sides (page cache, TBB's threads)
                c_times(program, f.name, 1, what)
                inside.seconds.clear()
                for round_ in range(args.rounds):  # C first, then Python first, in turn
                    if round_ % 2 == 0:
                        c += c_times(program, f.name, args.repetitions, what)
                    for _ in range(args.repetitions):
                        start = time.perf_counter()
                        call()
                        py.append(time.perf_counter() - start)
                    if round_ % 2 == 1:
                        c += c_times(program, f.name, args.repetitions, what)
            finally:
                setattr(lib, entry, inside.fn)
            c_med = statistics.median(total for total, _ in c)
            py_med = statistics.median(py)
            c_side = statistics.median(total - main for total, main in c)
            py_side = statistics.median([t - i for t, i in zip(py, inside.seconds)])
            print(f"| {what} | {1e3 * c_med:.1f} ms | {1e3 * py_med:.1f} ms | "
                  f"{100 * (py_med / c_med - 1):+.1f} % | {1e3 * c_side:.1f} ms | "
                  f"{1e3 * py_side:.1f} ms | {1e3 * (py_side - c_side):.1f} ms = "
                  f"{100 * (py_side - c_side) / c_med:.1f} % |")
            notes.append(f"{what}: the library call itself, median "
                         f"{1e3 * statistics.median(m for _, m in c):.1f} ms from C, "
                         f"{1e3 * statistics.median(inside.seconds):.1f} ms from Python")
    print()
    for note in notes:
        print(f"- {note}")


if __name__ == "__main__":
    main()
