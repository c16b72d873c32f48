"""One cloud of volume particles polygonized in tiles (polygonize_tiled).

The lattice and the order in which each sample sums its particles do not depend on the
tiling: the library anchors both to the cloud's lower corner and largest radius
(`domain_min`, `domain_max_radius`), each tile meshes only its own lattice cells (`cells`)
with every particle within reach of them (the halo: the largest radius and a cell), in their
order in the cloud. The tiles' meshes then hold the cloud's triangles, cell by cell, and the
vertices on their seams are the same bit for bit; merging them on their coordinates gives the
one-machine mesh exactly (see native/include/particlemesh/volume/polygonize.h)."""

import time
import uuid

import numpy as np

from .. import _abi, _library, _options
from .. import default_radius, lattice_field, particle_grid_radius, polygonize
from .._errors import Error
from ._dask import check_client, distributed, gather_in_order
from ._merge import merge_by_position
from ._tiles import Source, invalid, load, nbytes, tile_indices, tile_shape

# A cell index beyond any lattice (the library clamps ranges to +-2^40): the outermost tiles
# reach it, so every cell has one tile whatever the rounding.
_FAR = 2 ** 40


def _median(values):
    """The median as the library takes it: the element at n / 2 after sorting."""
    v = np.asarray(values, dtype=np.float64)
    return float(np.partition(v, len(v) // 2)[len(v) // 2])


def polygonize_tile(payload, cells, domain_min, domain_max_radius, options):
    """On a worker: one tile's mesh (its cells only) and what it measured."""
    t0 = time.perf_counter()
    particles = load(payload)
    if len(particles["positions"]) == 0:
        empty = np.zeros((0, 3))
        return {"vertices": empty, "triangles": np.zeros((0, 3), dtype=np.int32),
                "normals": empty, "attributes": {}, "particles": 0,
                "seconds": time.perf_counter() - t0}
    if particles["strengths"] is not None and "threshold" not in options:
        raise invalid("the loader returns strengths: give threshold= (the default threshold "
                      "is from the median strength of the whole cloud)")
    mesh = polygonize(particles["positions"], radii=particles["radii"],
                         strengths=particles["strengths"], attributes=particles["attributes"],
                         domain_min=domain_min, domain_max_radius=domain_max_radius,
                         cells=cells, **options)
    return {"vertices": mesh.vertices, "triangles": mesh.triangles, "normals": mesh.normals,
            "attributes": mesh.attributes, "particles": len(particles["positions"]),
            "origin": mesh.stats["origin"], "seconds": time.perf_counter() - t0}


def polygonize_tiled(client, particles, tiles=(2, 2, 1), *, bounds=None, radius=None,
                     threshold=None, kernel=None, cell=None, radii=None, strengths=None,
                     attributes=None, lattice_anchor="particles", progress=None, **options):
    """particlemesh.polygonize of one cloud, cut into tiles that Dask meshes in parallel.

    particles: (N, 3) positions or Points, or a loader: a function loader(lo, hi) returning the
    particles in the box [lo, hi] (at least those; more are dropped) as an (N, 3) array, Points
    or a dict (positions, radii, strengths, attributes), called on the workers, always in the
    cloud's order (the order the whole cloud would list them in); with a loader, bounds=(lo,
    hi) is the cloud's box (lo at or below every particle) and radius= (or, with per-particle
    radii, domain_max_radius=, their maximum, and where a few radii are far above the rest
    domain_grid_radius=particlemesh.particle_grid_radius(all radii)) is needed. tiles=(nx, ny, nz): the lattice cut
    evenly along each axis. The other arguments are polygonize's (lattice_anchor="space"
    too: the tiles round the same origin).

    Returns the Mesh particlemesh.polygonize(particles, ...) returns, vertices in canonical
    order (canonical_mesh): the same vertex coordinates and normals bit for bit, the same
    triangles. With a loader it is that of polygonize(all particles, ..., domain_min=lo), the
    same as the plain call when lo is the particles' smallest coordinates. mesh.stats: the
    lattice (origin, cell_size, radius), tiles, per-tile particles and seconds, bytes sent to
    and from the workers, seconds. progress(finished, total) as tiles end."""
    distributed()
    check_client(client)
    lib = _library.load()
    t0 = time.perf_counter()
    shape = tile_shape(tiles)
    if cell is not None:
        if options.get("cell_size") is not None:
            raise TypeError("polygonize_tiled() got both cell and cell_size (the same option)")
        options["cell_size"] = cell
    for key in ("domain_min", "cells"):
        if key in options:
            raise TypeError(f"polygonize_tiled() sets {key} itself")
    # Anisotropic kernels need each particle's neighbours (and calibrate their default
    # threshold on the whole cloud); dropping pieces, collapsing edges and smoothing need the
    # whole surface.
    for key in ("anisotropic", "min_component_volume", "min_component_particles",
                "collapse_edges", "taubin_iterations"):
        if options.get(key):
            raise Error(f"polygonize_tiled() does not support {key} yet: it needs the whole "
                        "cloud or surface (use particlemesh.polygonize)")
    domain_max_radius = options.pop("domain_max_radius", None) or 0.0
    source = Source(particles, attributes=attributes, radii=radii, strengths=strengths,
                    bounds=bounds)
    # Validate every keyword here, once, not in every task.
    _options.POLYGONIZE.build(lib, {**options, "radius": radius, "threshold": threshold,
                                    "kernel": kernel})

    # The parameters the library would resolve from the whole cloud, resolved here once:
    # R (the radius, or the median of the radii), R_max (the largest radius), h (the cell).
    if lattice_anchor not in ("particles", "space"):
        raise invalid(f"lattice_anchor must be 'particles' or 'space', not {lattice_anchor!r}")
    tile_options = {k: v for k, v in {**options, "threshold": threshold, "kernel": kernel,
                                      "lattice_anchor": lattice_anchor}.items()
                    if v is not None}
    if source.loader is None:
        p = source.particles
        if p["radii"] is not None:
            r = np.asarray(p["radii"], dtype=np.float64)
            if not (np.isfinite(r).all() and (r > 0).all()):
                raise invalid("radii must be finite lengths > 0")
            R = _median(r)
            R_max = max(float(r.max()), float(domain_max_radius))
            if not domain_max_radius and not options.get("domain_grid_radius"):
                # The particle grid as the whole cloud's: its few far larger particles (if
                # any) kept apart in every tile alike.
                tile_options["domain_grid_radius"] = particle_grid_radius(r)
        else:
            R = float(radius) if radius else default_radius(p["positions"], p["strengths"], kernel)
            R_max = max(R, float(domain_max_radius))
            tile_options["radius"] = R
        if not threshold and p["strengths"] is not None:
            w = _median(p["strengths"])
            if not w > 0:
                raise invalid("the default threshold needs a positive median strength: give a "
                              "threshold")
            k = _options.POLYGONIZE.convert("kernel", "kernel", kernel or "wyvill")
            tile_options["threshold"] = 0.5 * w * lattice_field(k, 2.0, 1.0)
    else:
        if not (radius or domain_max_radius):
            raise invalid("with a loader, give radius= (and with per-particle radii "
                          "domain_max_radius=, their largest, and cell=): the defaults need the "
                          "whole cloud")
        if radius:
            tile_options["radius"] = R = float(radius)
        elif not options.get("cell_size"):
            raise invalid("with a loader and per-particle radii, give cell= (the default cell "
                          "is a quarter of the median radius of the whole cloud)")
        else:
            R = float(domain_max_radius)
        R_max = max(R, float(domain_max_radius))
    if not (np.isfinite(R_max) and R_max > 0):
        raise invalid(f"radius {R_max} is not a finite length > 0")
    h = float(options.get("cell_size") or 0.0) or 0.25 * R  # the library's default cell
    tile_options["cell_size"] = h
    lower = source.lo
    origin = (lower - R_max) - 9.0 * h  # the library's lattice origin (polygonize.h)
    if lattice_anchor == "space":  # space_anchored_origin: down to a multiple of h
        rounded = np.floor(origin / h) * h
        origin = np.where(rounded > origin, rounded - h, rounded)
    top = np.ceil((source.hi + R_max - origin) / h).astype(np.int64) + 1

    tasks = []
    halo = R_max * (1 + 1e-9) + h
    for index in tile_indices(shape):
        cmin, cmax = np.empty(3, np.int64), np.empty(3, np.int64)
        lo, hi = np.empty(3), np.empty(3)
        for a in range(3):
            cut = np.round(np.linspace(0, top[a], shape[a] + 1)).astype(np.int64)
            i = index[a]
            cmin[a] = -_FAR if i == 0 else cut[i]
            cmax[a] = _FAR if i == shape[a] - 1 else cut[i + 1]
            lo[a] = -np.inf if i == 0 else origin[a] + cmin[a] * h - halo
            hi[a] = np.inf if i == shape[a] - 1 else origin[a] + cmax[a] * h + halo
        tasks.append((index, (cmin, cmax), source.payload(lo, hi)))

    payloads = [t[2] for t in tasks]
    sent = nbytes(payloads)
    if source.loader is None:  # the arrays go to the workers once, one tile each
        payloads = client.scatter(payloads, hash=False)
    token = uuid.uuid4().hex[:8]
    n = len(tasks)
    futures = client.map(polygonize_tile, payloads, [t[1] for t in tasks], [lower] * n,
                         [R_max] * n, [tile_options] * n,
                         key=[f"particlemesh-polygonize-{i}-{token}" for i in range(n)], pure=False)
    results = gather_in_order(futures, (lambda done: progress(done, n)) if progress else None)
    for r in results:
        if "origin" in r and not np.array_equal(np.asarray(r["origin"]), origin):
            raise Error(f"a tile's lattice origin {list(r['origin'])} is not {origin.tolist()} "
                        "(the library's lattice changed: particlemesh.distributed must follow)",
                        _abi.PM_STATUS_INTERNAL)
    received = sum(nbytes(r) for r in results)
    mesh = merge_by_position([(r["vertices"], r["triangles"], r["normals"], r["attributes"])
                              for r in results])
    mesh.stats = {
        "origin": tuple(origin), "cell_size": h, "radius": R, "max_radius": R_max,
        "tiles": shape, "tile_particles": [r["particles"] for r in results],
        "tile_seconds": [r["seconds"] for r in results], "bytes_sent": sent,
        "bytes_received": received, "vertices": mesh.vertex_count,
        "triangles": mesh.triangle_count, "seconds": time.perf_counter() - t0,
    }
    return mesh
