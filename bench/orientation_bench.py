"""Which way a model's vertices come out facing: each model's vertices triangulated, every output
triangle's winding compared with the model's own normals at its corners (area-weighted vertex
normals of the model's triangles); a triangle counts as reversed when it faces against the
model's normal at all three corners. Per model: the triangles, the share reversed, the loops
left open and the pieces, and how many parts the orientation stage turned for being closed but
for small openings.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/orientation_bench.py MODEL.obj ... \
        [--noise 0.5]

Each MODEL is any mesh particlemesh reads (.obj, .off, .ply, .stl) whose triangles face
outward; its vertices are the particles (exact copies merged first), its triangles only the
reference. --noise F moves each vertex along the model's normal by Gaussian noise of F times
the vertices' spacing (a fixed seed): a scan's depth noise on a model whose normals are known.
--with-normals gives the model's normals with the particles (the surface then faces as they
say, where they are a consistent orientation).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", "build/python"))
import particlemesh as pm  # noqa: E402


def vertex_normals(vertices, triangles):
    """Area-weighted unit vertex normals of a mesh (zero where a vertex is in no triangle)."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    face = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    n = np.zeros_like(v)
    for c in range(3):
        np.add.at(n, t[:, c], face)
    length = np.linalg.norm(n, axis=1)
    return np.divide(n, length[:, None], out=np.zeros_like(n), where=length[:, None] > 0)


def reversed_share(mesh, normals):
    """The share of `mesh`'s triangles facing against `normals` (per vertex) at all three corners."""
    v, t = mesh.vertices, mesh.triangles
    face = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    against = np.einsum("tj,tcj->tc", face, normals[t]) < 0
    return int(against.all(axis=1).sum())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--noise", type=float, default=0.0)
    parser.add_argument("--with-normals", action="store_true")
    args = parser.parse_args()
    print("| model | vertices | triangles | reversed | loops | pieces | turned (nearly closed) | thickness |")
    print("|---|---|---|---|---|---|---|---|")
    total = reversed_total = 0
    for path in args.models:
        model = pm.read_mesh(path)
        if model.triangle_count == 0:
            print(f"| {os.path.basename(path)} | no triangles |")
            continue
        normals = vertex_normals(model.vertices, model.triangles)
        points, first = np.unique(np.asarray(model.vertices), axis=0, return_index=True)
        normals = normals[first]
        if args.noise:
            spacing = pm.estimate_spacing(points)
            rng = np.random.default_rng(0)
            points = points + normals * rng.normal(0, args.noise * spacing, len(points))[:, None]
        mesh = pm.triangulate(points, normals if args.with_normals else None)
        top = pm.topology(mesh)
        bad = reversed_share(mesh, normals)
        total += mesh.triangle_count
        reversed_total += bad
        print(f"| {os.path.basename(path)} | {len(points)} | {mesh.triangle_count} | "
              f"{100.0 * bad / max(1, mesh.triangle_count):.2f} % | {top['boundary_loops']} | "
              f"{top['components']} | {mesh.stats['nearly_closed_turned']} | "
              f"{mesh.stats['sampling_thickness']:.2f} |")
    print(f"| all | | {total} | {100.0 * reversed_total / max(1, total):.2f} % | | | | |")


if __name__ == "__main__":
    main()
