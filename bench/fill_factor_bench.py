"""Triangulating a model's vertices at several fill edge factors, beside the model itself: per
factor, the loops left open, how many of the model's own openings are still open (a model
loop counts as open when at least 30 % of its vertices lie on the surface's boundary), the
genus summed over the pieces, and the longest edge in units of r0.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/fill_factor_bench.py MODEL.obj ... \
        [--factors 1.5,2.0,2.5]

Each MODEL is any mesh particlemesh reads (.obj, .off, .ply, .stl); its vertices are the
particles, its triangles only the reference.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402


def boundary_vertices(triangles):
    """The vertices on an edge of exactly one triangle."""
    e = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    edges, uses = np.unique(e, axis=0, return_counts=True)
    return np.unique(edges[uses == 1])


def model_loops(triangles):
    """The model's boundary loops as vertex sets (boundary edges joined through shared vertices)."""
    e = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    edges, uses = np.unique(e, axis=0, return_counts=True)
    parent = {}

    def find(x):
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for a, b in edges[uses == 1]:
        parent[find(int(a))] = find(int(b))
    loops = {}
    for v in list(parent):
        loops.setdefault(find(v), set()).add(v)
    return list(loops.values())


def genus(mesh):
    t = pm.topology(mesh)
    return (2 * t["components"] - t["euler_characteristic"] - t["boundary_loops"]) / 2, t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="+")
    ap.add_argument("--factors", default="1.5,2.0,2.5")
    a = ap.parse_args()
    factors = [float(x) for x in a.factors.split(",")]
    print("| model | model's loops / genus | " + " | ".join(
        f"{f:g}: loops / openings open / genus / longest r0" for f in factors) + " |")
    print("|---" * (2 + len(factors)) + "|")
    for path in a.models:
        model = pm.read_mesh(path)
        points = np.ascontiguousarray(model.vertices, dtype=np.float64)
        g, t = genus(model)
        openings = model_loops(model.triangles)
        cells = [os.path.basename(path), f"{t['boundary_loops']} / {g:g}"]
        for f in factors:
            m = pm.triangulate(points, fill_edge_factor=f)
            mg, mt = genus(m)
            on_boundary = set(boundary_vertices(m.triangles).tolist()) if len(m.triangles) else set()
            still_open = sum(1 for loop in openings if len(loop & on_boundary) >= 0.3 * len(loop))
            tri = m.triangles
            e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
            longest = np.linalg.norm(points[e[:, 0]] - points[e[:, 1]], axis=1).max() / m.stats["spacing"]
            cells.append(f"{mt['boundary_loops']} / {still_open} of {len(openings)} / {mg:g} / {longest:.1f}")
        print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
