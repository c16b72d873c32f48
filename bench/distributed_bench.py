"""particlemesh.distributed against one process: a generated block of volume particles
polygonized by polygonize_tiled on a LocalCluster of W worker processes (1 thread each), and by
particlemesh.polygonize in one process (W threads); time, each worker's peak memory (the
resident set's high-water mark, VmHWM, started over before each run), bytes moved, and
whether the meshes are identical. Optionally the same for triangulate_tiled on a sphere.

    PYTHONPATH=build/python /usr/bin/python3 bench/distributed_bench.py \\
        --particles 10000000 --workers 2 --tiles 2,4,8,16,32

The block is a jittered cubic lattice (spacing 1, radius 2, default threshold and cell)
that a loader makes on the workers, tile by tile: the cloud is never in one process except in
the one-process run. Results: bench/RESULTS.md."""

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np


class JitteredBlock:
    """Particles of a jittered cubic lattice of side^3 points (spacing 1), made for any box
    on demand in lattice order (each point's jitter from its index)."""

    def __init__(self, side):
        self.side = side

    def __call__(self, lo, hi):
        a = np.clip(np.floor(np.asarray(lo)) - 1, 0, self.side).astype(np.int64)
        b = np.clip(np.ceil(np.asarray(hi)) + 1, 0, self.side).astype(np.int64)
        i, j, k = np.meshgrid(*(np.arange(a[d], b[d]) for d in range(3)), indexing="ij")
        idx = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1)
        del i, j, k
        flat = (idx[:, 0] * self.side + idx[:, 1]) * self.side + idx[:, 2]
        jitter = ((flat[:, None] * np.array([0.61803, 0.41421, 0.73205])) % 1.0 - 0.5) * 0.4
        return idx + jitter

    def bounds(self):
        p = self(np.zeros(3), np.full(3, 2.0))  # the corner's particles hold the minimum
        q = self(np.full(3, self.side - 3.0), np.full(3, float(self.side)))
        return p.min(axis=0), q.max(axis=0)


def digest(mesh):
    """A hash of a mesh's canonical arrays: equal hashes, identical meshes."""
    from particlemesh.distributed import canonical_mesh

    m = canonical_mesh(mesh)
    h = hashlib.sha256()
    for a in (m.vertices, m.triangles, m.normals):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def one_process(side, threads, radius):
    """Run in a child: the whole block in this process, polygonized with `threads` threads."""
    import particlemesh as pm

    block = JitteredBlock(side)
    t = time.perf_counter()
    p = block(np.full(3, -np.inf), np.full(3, np.inf))
    t_gen = time.perf_counter() - t
    t, c = time.perf_counter(), cpu_seconds()
    mesh = pm.polygonize(p, radius=radius, threads=threads)
    t_mesh, c_mesh = time.perf_counter() - t, cpu_seconds() - c
    print(json.dumps({"particles": len(p), "seconds_generate": t_gen, "seconds": t_mesh,
                      "cpu_seconds": c_mesh,
                      "peak_mib": peak_mib(), "vertices": mesh.vertex_count,
                      "triangles": mesh.triangle_count, "digest": digest(mesh)}))


def vm(field):
    """A field of /proc/self/status in MiB (VmHWM: the resident set's high-water mark)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError(f"no {field} in /proc/self/status")


def worker_peak():
    return vm("VmHWM")


def reset_peak():
    """Start the high-water mark over from the current resident set (Linux clear_refs 5)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    return vm("VmRSS")


def sphere(n):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def one_process_triangulate(n, threads):
    import particlemesh as pm

    p = sphere(n)
    t, c = time.perf_counter(), cpu_seconds()
    mesh = pm.triangulate(p, threads=threads)
    print(json.dumps({"particles": n, "seconds": time.perf_counter() - t,
                      "cpu_seconds": cpu_seconds() - c, "peak_mib": peak_mib(),
                      "triangles": mesh.triangle_count, "closed": pm.topology(mesh)["closed"]}))


def child(args):
    out = subprocess.run([sys.executable, __file__] + args, capture_output=True, text=True,
                         env=os.environ)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--particles", type=int, default=10_000_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--tiles", default="2,4,8,16,32", help="tile counts to run (comma list)")
    ap.add_argument("--triangulate", type=int, default=0,
                    help="also triangulate a Fibonacci sphere of this many particles")
    ap.add_argument("--triangulate-tiles", default="2,4")
    ap.add_argument("--one-process", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--one-process-triangulate", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--threads", type=int, default=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    radius = 2.0
    if args.one_process:
        return one_process(args.one_process, args.threads, radius)
    if args.one_process_triangulate:
        return one_process_triangulate(args.one_process_triangulate, args.threads)

    import particlemesh as pm
    from dask.distributed import Client, LocalCluster
    from particlemesh.distributed import polygonize_tiled, triangulate_tiled

    side = round(args.particles ** (1 / 3))
    print(f"machine: {os.cpu_count()} cores, {os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 2**30:.0f} GiB, "
          f"load {os.getloadavg()[0]:.1f}; particlemesh {pm.version()}", flush=True)
    base = child(["--one-process", str(side), "--threads", str(args.workers)])
    print(f"one process ({args.workers} threads): {base['particles']} particles, "
          f"{base['seconds']:.1f} s (cpu {base['cpu_seconds']:.1f} s), peak {base['peak_mib']:.0f} MiB, "
          f"{base['vertices']} vertices (generating the block: {base['seconds_generate']:.1f} s)",
          flush=True)

    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address=None, memory_limit=0)
    client = Client(cluster)
    block = JitteredBlock(side)
    bounds = block.bounds()
    shapes = {2: (2, 1, 1), 4: (2, 2, 1), 8: (2, 2, 2), 16: (4, 2, 2), 32: (4, 4, 2),
              64: (4, 4, 4), 128: (8, 4, 4)}
    rows = []
    for count in [int(c) for c in args.tiles.split(",")]:
        idle = max(client.run(reset_peak).values())  # the high-water marks start over
        cpu = sum(client.run(cpu_seconds).values())
        t = time.perf_counter()
        mesh = polygonize_tiled(client, block, tiles=shapes[count], bounds=bounds,
                                radius=radius, threads=1)
        seconds = time.perf_counter() - t
        cpu = sum(client.run(cpu_seconds).values()) - cpu
        peaks = sorted(client.run(worker_peak).values())
        same = digest(mesh) == base["digest"]
        rows.append((count, seconds, peaks, idle, mesh.stats, same))
        print(f"tiles {count:3d} {shapes[count]}: {seconds:6.1f} s (workers' cpu {cpu:.1f} s), worker peaks "
              f"{', '.join(f'{p:.0f}' for p in peaks)} MiB (idle {idle:.0f}), largest tile "
              f"{max(mesh.stats['tile_particles'])} particles, received "
              f"{mesh.stats['bytes_received'] / 2**20:.0f} MiB, identical: {same}", flush=True)

    half = [c for c, _, peaks, _, _, _ in rows if max(peaks) <= base["peak_mib"] / 2]
    print(f"a worker's peak is at most half the one process's ({base['peak_mib'] / 2:.0f} MiB) from "
          f"{min(half) if half else 'more than ' + str(max(r[0] for r in rows))} tiles on", flush=True)

    if args.triangulate:
        tri = child(["--one-process-triangulate", str(args.triangulate), "--threads", str(args.workers)])
        print(f"triangulate, one process: {tri['particles']} particles, {tri['seconds']:.1f} s "
              f"(cpu {tri['cpu_seconds']:.1f} s), "
              f"peak {tri['peak_mib']:.0f} MiB", flush=True)
        p = sphere(args.triangulate)
        for count in [int(c) for c in args.triangulate_tiles.split(",")]:
            client.run(reset_peak)
            cpu = sum(client.run(cpu_seconds).values())
            t = time.perf_counter()
            mesh = triangulate_tiled(client, p, tiles=shapes[count], threads=1)
            seconds = time.perf_counter() - t
            cpu = sum(client.run(cpu_seconds).values()) - cpu
            peaks = sorted(client.run(worker_peak).values())
            top = pm.topology(mesh)
            print(f"triangulate tiles {count}: {seconds:.1f} s (workers' cpu {cpu:.1f} s; tiles "
                  f"{mesh.stats['seconds_tiles']:.1f} s, "
                  f"seams {mesh.stats['seconds_seams']:.2f} s), worker peaks "
                  f"{', '.join(f'{q:.0f}' for q in peaks)} MiB, closed {top['closed']}, "
                  f"holes filled {mesh.stats['holes_filled']}", flush=True)
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
