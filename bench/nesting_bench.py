"""What judging closed parts by their nesting costs the topology report (mesh/nesting.h): a
1M-triangle sphere with 1000 small closed spheres inside it (each tested against it), the
same with the small spheres moved outside its box (no test: the cost of everything else),
and 1000 spheres side by side. Best of 5 per case.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/nesting_bench.py
"""
import os
import sys
import time
import types

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402


def uv_sphere(n):
    """A closed, outward UV sphere of about n^2 triangles."""
    nu, nv = n, n // 2
    th = np.linspace(0, np.pi, nv + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    v = [[0, 0, 1]] + [[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)] for t in th for p in ph] + [[0, 0, -1]]
    f = [[0, 1 + j, 1 + (j + 1) % nu] for j in range(nu)]
    for i in range(nv - 2):
        for j in range(nu):
            a, b = 1 + i * nu + j, 1 + i * nu + (j + 1) % nu
            f += [[a, a + nu, b], [b, a + nu, b + nu]]
    last, base = len(v) - 1, 1 + (nv - 2) * nu
    f += [[last, base + (j + 1) % nu, base + j] for j in range(nu)]
    return np.array(v, float), np.array(f, np.int64)


def joined(parts):
    off, vs, fs = 0, [], []
    for v, f in parts:
        vs.append(v)
        fs.append(f + off)
        off += len(v)
    return types.SimpleNamespace(vertices=np.vstack(vs), triangles=np.vstack(fs).astype(np.uint32))


big, small = uv_sphere(1000), uv_sphere(24)
rng = np.random.default_rng(1)
offsets = rng.uniform(-0.5, 0.5, (1000, 3))
cases = {
    "1M-triangle sphere alone": [big],
    "with 1000 small spheres inside it": [big] + [(small[0] * 0.01 + o, small[1]) for o in offsets],
    "with the 1000 outside its box": [big] + [(small[0] * 0.01 + o + [5, 0, 0], small[1]) for o in offsets],
    "1000 spheres side by side": [(small[0] * 0.4 + [i, 0, 0], small[1]) for i in range(1000)],
}
for name, parts in cases.items():
    mesh = joined(parts)
    best = min((lambda t: (pm.topology(mesh), time.perf_counter() - t)[1])(time.perf_counter()) for _ in range(5))
    r = pm.topology(mesh)
    print(f"{name:36s} {len(mesh.triangles):8d} triangles {r['components']:5d} components  {best * 1000:6.1f} ms")
