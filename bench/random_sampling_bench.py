#!/usr/bin/python3
"""Particles dropped uniformly at random on a surface (a Poisson process: Blender's "Random"
emission, a mesh sampled uniformly by area), meshed by `particlemesh triangulate` with its
defaults, beside CGAL's advancing front (build/bench/scan_bench, when the benchmarks are built).

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/random_sampling_bench.py \\
        [--cli build/cli/particlemesh]... [--points 20000] [--no-cgal]

The clouds (numpy, fixed seeds): a unit sphere (1.5 x --points), a torus R = 1, r = 0.4, and
the shared data's bunny, spot and rocker arm meshes, each sampled by area. Every --cli given
meshes every cloud (e.g. an older build beside this one). Printed per cloud and program: the
sampling's irregularity and the reach factor the summary reports, components (closed), open
loops, genus per component, unused particles, the longest edge / r0 and the time (the whole
process); then scan_bench's rows for CGAL's advancing front on the same file (--as-is: the
points as given; its columns: small holes (< 10 edges), boundary loops, points in the mesh,
longest edge / r0, triangles > 6 r0, non-manifold edges, orientation conflicts, seconds;
once with its triangles over 6 r0 cut, once uncut)."""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", str(ROOT / "build" / "python")))
import particlemesh as pm  # noqa: E402


def write_ply(path, p):
    p = np.asarray(p, dtype=np.float32)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(p)}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    path.write_bytes(header.encode() + p.tobytes())


def on_mesh(vertices, triangles, n, seed):
    """n points uniformly at random on the mesh: a triangle chosen by area, a point uniformly
    inside it."""
    rng = np.random.default_rng(seed)
    v, t = np.asarray(vertices, float), np.asarray(triangles)
    a, b = v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]
    area = np.linalg.norm(np.cross(a, b), axis=1)
    f = rng.choice(len(t), n, p=area / area.sum())
    x, y = rng.random(n), rng.random(n)
    flip = x + y > 1
    x[flip], y[flip] = 1 - x[flip], 1 - y[flip]
    return v[t[f, 0]] + x[:, None] * a[f] + y[:, None] * b[f]


def sphere(n, seed):
    rng = np.random.default_rng(seed)
    z, phi = 2 * rng.random(n) - 1, 2 * np.pi * rng.random(n)
    r = np.sqrt(1 - z * z)
    return np.c_[r * np.cos(phi), r * np.sin(phi), z]


def torus(n, seed):
    """By rejection: the angle around the tube kept in proportion to the circle it sweeps."""
    rng = np.random.default_rng(seed)
    out = np.empty((0, 3))
    while len(out) < n:
        u, v, w = (rng.random(4 * n) * 2 * np.pi, rng.random(4 * n) * 2 * np.pi, rng.random(4 * n))
        keep = w < (1 + 0.4 * np.cos(v)) / 1.4
        u, v = u[keep], v[keep]
        ring = 1 + 0.4 * np.cos(v)
        out = np.r_[out, np.c_[ring * np.cos(u), ring * np.sin(u), 0.4 * np.sin(v)]]
    return out[:n]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cli", action="append", help="particlemesh executables (default build/cli/particlemesh)")
    ap.add_argument("--points", type=int, default=20000)
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--no-cgal", action="store_true")
    args = ap.parse_args()
    clis = args.cli or [str(ROOT / "build" / "cli" / "particlemesh")]
    n = args.points
    clouds = {"sphere": sphere(n + n // 2, 1), "torus": torus(n, 2)}
    for name in ("bunny", "spot", "rocker_arm"):
        path = Path(args.data) / "meshes" / f"{name}.obj"
        if not path.exists():
            print(f"skipped {name}: {path} is absent")
            continue
        m = pm.read_mesh(str(path))
        clouds[name] = on_mesh(m.vertices, m.triangles, n, 3)
    scan_bench = ROOT / "build" / "bench" / "scan_bench"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        print("| cloud | program | irregularity | reach | components (closed) | open loops | genus | unused | longest / r0 | time s |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for name, p in clouds.items():
            src = tmp / f"random_{name}.ply"
            write_ply(src, p)
            for cli in clis:
                out, rep = tmp / "out.ply", tmp / "r.json"
                t0 = time.perf_counter()
                subprocess.run([cli, "triangulate", str(src), "-o", str(out), "--report", str(rep), "-q"], check=True)
                seconds = time.perf_counter() - t0
                r = json.loads(rep.read_text())
                tri, topo = r["triangulation"], r["topology"]
                mesh = pm.read_mesh(str(out))
                v, t = np.asarray(mesh.vertices, float), np.asarray(mesh.triangles)
                edges = np.linalg.norm(v[t] - v[np.roll(t, 1, axis=1)], axis=2).max()
                genus = " ".join(str(c["genus"]) for c in topo["per_component"][:6])
                print(f"| {name} ({len(p)}) | {cli} | {tri.get('sampling_irregularity', float('nan')):.2f} | "
                      f"{tri.get('reach_factor', 1.0):.2f} | {topo['components']} ({topo['closed_components']}) | "
                      f"{topo['boundary_loops']} | {genus}{' ...' if len(topo['per_component']) > 6 else ''} | "
                      f"{r['surface']['unused_points']} | {edges / tri['spacing']:.1f} | {seconds:.2f} |", flush=True)
            if not args.no_cgal and scan_bench.exists():
                proc = subprocess.run([str(scan_bench), "--scan", str(src), "--as-is", "--no-gp3", "--runs", "1"],
                                      capture_output=True, text=True)
                # Its per-scan rows (the summary table repeats them without the cloud's name).
                rows = [line for line in proc.stdout.splitlines() if line.startswith(f"| random_{name} ")]
                for line in rows:
                    print(f"  scan_bench: {line}", flush=True)
                if proc.returncode != 0:
                    print(f"  scan_bench failed: {proc.stderr.strip()[:300]}")


if __name__ == "__main__":
    main()
