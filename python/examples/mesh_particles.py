"""particlemesh from Python, end to end: surface particles to a smooth closed surface, volume
particles to an iso-surface, with progress on the terminal.

    python3 python/examples/mesh_particles.py [OUT_DIR] [--points N]

(with the package importable: PYTHONPATH=build/python after building, or installed). Writes
OUT_DIR/torus.ply (the finished triangulation), torus_smooth.ply (two Loop levels) and
drop.ply (the polygonized volume particles), and prints what each step made."""
import argparse
import os
import sys

import numpy as np

import particlemesh as pm


def torus_particles(n, major=1.0, minor=0.35):
    """About n evenly spaced points on a torus, with outward normals: rows of points around
    the tube, as many rows as the circumference ratio asks."""
    rows = max(8, int(round(np.sqrt(n * major / minor))))
    cols = max(8, n // rows)
    u = 2 * np.pi * (np.arange(rows)[:, None] + 0.5 * (np.arange(cols) % 2)[None, :]) / rows
    v = np.broadcast_to(2 * np.pi * np.arange(cols)[None, :] / cols, u.shape)
    u, v = u.ravel(), v.ravel()
    centre = np.stack([major * np.cos(u), major * np.sin(u), np.zeros_like(u)], 1)
    normal = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], 1)
    return centre + minor * normal, normal


def volume_particles(n, seed=1):
    """n particles filling a ball of radius 1 with jitter, as a fluid simulation's frame."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil((6 * n / np.pi) ** (1 / 3)))
    grid = np.stack(np.meshgrid(*[np.linspace(-1, 1, side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    inside = grid[np.linalg.norm(grid, axis=1) <= 1.0]
    return inside + rng.normal(0, 0.1 * 2 / side, inside.shape)


def progress_line(label):
    def report(stage, fraction):
        print(f"\r  {label}: {stage:<24} {100 * fraction:5.1f}%", end="", file=sys.stderr,
              flush=True)
    return report


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="out/python_example")
    parser.add_argument("--points", type=int, default=20000)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    print(f"particlemesh {pm.version()} ({pm.library_path()})")

    positions, normals = torus_particles(args.points)
    mesh = pm.triangulate(positions, normals, progress=progress_line("triangulate"))
    print(file=sys.stderr)
    report = pm.topology(mesh)
    print(f"torus: {len(positions)} particles -> {mesh.triangle_count} triangles, spacing "
          f"{mesh.stats['spacing']:.4f}, closed {report['closed']}, genus "
          f"{(2 - report['euler_characteristic']) // 2}")
    pm.write_mesh(mesh, os.path.join(args.out, "torus.ply"))

    smooth = pm.smooth(mesh, levels=2)
    print(f"torus, 2 Loop levels: {smooth.triangle_count} triangles, "
          f"closed {pm.topology(smooth)['closed']}")
    pm.write_mesh(smooth, os.path.join(args.out, "torus_smooth.ply"))

    drop = pm.polygonize(volume_particles(args.points // 2), kernel="poly6")
    r = np.linalg.norm(drop.vertices, axis=1)
    print(f"drop: {drop.triangle_count} triangles, radius {r.mean():.3f} +- {r.std():.3f}, "
          f"closed {pm.topology(drop)['closed']}")
    pm.write_mesh(drop, os.path.join(args.out, "drop.ply"))

    try:
        pm.triangulate(positions, max_edge_factor=-1)
    except pm.Error as e:
        print(f"a bad option is an Error: {e}")


if __name__ == "__main__":
    main()
