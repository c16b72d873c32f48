"""One cloud of surface particles triangulated in tiles (triangulate_tiled).

Each tile runs the library's whole chain (the smallest-sphere test, normals, manifold
extraction, repair) on its particles and a halo of `halo` x L around them, wide enough that
every triangle touching the tile, with its smallest-sphere test, is decided as on one machine,
and that the extraction sees enough of the surface around. Each particle belongs to one tile
(its box); the stitched surface takes, around every particle, the triangles its own tile chose
(a triangle with corners in several tiles is kept when each of those tiles chose it). Where
two tiles' extractions chose differently near a seam (about 1 % of the triangles there, in
small patches), this leaves small holes, which are closed as the library closes its own small
holes (the triangulation of the loop with the smallest largest angle, edges within
fill_edge_factor x L). Tiles orient their pieces independently: pieces that share seam
triangles are turned to agree, and each closed component is then turned to face away from
the solid it bounds (into its cavity when it lies inside another: the rays' crossings that
decide it are counted on the tiles that hold the triangles, and added up).

Only the seams cross to the driver first; the tiles' bulk triangles stay on the workers until
the orientation is known, then come back once. Why not the raw test alone in the tiles and the
one-machine finishing on the driver: the finishing (normals, extraction, repair) is 45-60 % of
the one-machine time (bench/RESULTS.md), so that could not go faster than 1.7-2.2x on any
number of workers, and the driver would need the whole cloud's finishing working set."""

import time
import uuid

import numpy as np

from .. import _abi, _library, _options
from .. import Mesh, estimate_spacing, ray_crossings, triangulate
from .. import defaults as library_defaults
from .._errors import Error
from ._dask import check_client, distributed, gather_in_order
from ._merge import canonical_triangles
from ._seams import Stitch, angle_weighted_normals, unpinch
from ._tiles import Cuts, Source, invalid, load, nbytes, tile_indices, tile_shape

#: Halo width in units of L (the longest edge): the raw test needs L + 2L/sqrt(3) (2.2 L); the
#: extraction's choices near the seam agree better with more context (measured on a sphere in
#: 4 tiles: boundary edges left to close 74 at 3 L, 53 at 6 L, 36 at 12 L).
DEFAULT_HALO = 6.0
# Vertices within this many L of a tile's inner faces have their whole star sent to the driver.
_NEAR = 3.0


def _components(n, triangles):
    """Connected components of the vertices through the triangles' edges (SciPy): labels."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if len(triangles) == 0:
        return np.arange(n)
    # Two edges of each triangle connect its three corners.
    rows = np.concatenate([triangles[:, 0], triangles[:, 1]])
    cols = np.concatenate([triangles[:, 1], triangles[:, 2]])
    graph = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _signed_volumes(positions, triangles, labels, count):
    """Per label: the signed volume the triangles enclose with the origin (det / 6)."""
    if len(triangles) == 0:
        return np.zeros(count)
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    det = (a[:, 0] * (b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1]) +
           a[:, 1] * (b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2]) +
           a[:, 2] * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])) / 6.0
    return np.bincount(labels, weights=det, minlength=count)


def triangulate_tile(payload, tile, cuts, options, near):
    """On a worker: the library's whole chain on a tile and its halo, kept on the worker; the
    driver asks for the seams (seam_part) and then the rest (finish_tile)."""
    t0 = time.perf_counter()
    particles = load(payload)
    pos = particles["positions"]
    n = len(pos)
    core = cuts.owner(pos) == tile
    if n < 3 or not core.any():
        tri = np.zeros((0, 3), dtype=np.int64)
        normals = particles["normals"] if particles["normals"] is not None else np.zeros((n, 3))
    else:
        mesh = triangulate(pos, particles["normals"], **options)
        tri = mesh.triangles.astype(np.int64)
        normals = mesh.normals
    label = _components(n, tri)
    tri_label = label[tri[:, 0]] if len(tri) else np.zeros(0, dtype=np.int64)
    core_corner = core[tri] if len(tri) else np.zeros((0, 3), dtype=bool)
    touching = core_corner.any(axis=1)
    interior = core_corner.all(axis=1)
    lo, hi = cuts.box(cuts.unflat(tile))
    dist = np.full(n, np.inf)
    for a in range(3):
        if np.isfinite(lo[a]):
            dist = np.minimum(dist, pos[:, a] - lo[a])
        if np.isfinite(hi[a]):
            dist = np.minimum(dist, hi[a] - pos[:, a])
    near_v = core & (dist <= near)
    # Real openings (boundary edges of the tile's surface at its own particles; the halo's
    # cut edge is farther out) mark their piece open.
    ncomp = int(label.max()) + 1 if n else 0
    open_piece = np.zeros(ncomp, dtype=bool)
    if len(tri):
        # Edges of one triangle only (the surface is a manifold: each edge has one or two).
        u = np.concatenate([tri[:, 0], tri[:, 1], tri[:, 2]])
        v = np.concatenate([tri[:, 1], tri[:, 2], tri[:, 0]])
        key = np.sort(np.minimum(u, v) * n + np.maximum(u, v))
        once = np.ones(len(key), dtype=bool)
        same = key[1:] == key[:-1]
        once[1:] &= ~same
        once[:-1] &= ~same
        a, b = key[once] // n, key[once] % n
        at_core = core[a] | core[b]
        open_piece[np.unique(label[a[at_core]])] = True
    used = np.zeros(n, dtype=bool)
    used[tri[touching].ravel()] = True
    return {
        "n": n, "positions": pos, "normals": normals, "attributes": particles["attributes"],
        "ids": particles["ids"], "core": core, "label": label, "tri": tri, "tri_label": tri_label,
        "touching": touching, "interior": interior, "near": near_v, "open_piece": open_piece,
        "volume": _signed_volumes(pos, tri[interior], tri_label[interior], ncomp),
        "pieces": ncomp, "unused_core": int((core & ~used).sum()),
        "particles": n, "seconds": time.perf_counter() - t0,
    }


def _piece_boxes(result):
    """Per piece: the box of its own particles that its triangles use, and a point on it (the
    first corner of its first triangle with every corner its own: a vertex of the stitched
    surface), NaN where it has none. For the driver's test of which closed parts lie inside
    which."""
    pieces, pos, core, tri = result["pieces"], result["positions"], result["core"], result["tri"]
    box_lo = np.full((pieces, 3), np.inf)
    box_hi = np.full((pieces, 3), -np.inf)
    query = np.full((pieces, 3), np.nan)
    if len(tri) == 0:
        return box_lo, box_hi, query
    used = np.zeros(result["n"], dtype=bool)
    used[tri[result["touching"]].ravel()] = True
    v = np.flatnonzero(core & used)
    if len(v):
        order = np.argsort(result["label"][v], kind="stable")
        lab = result["label"][v][order]
        starts = np.flatnonzero(np.r_[True, lab[1:] != lab[:-1]])
        p = pos[v[order]]
        box_lo[lab[starts]] = np.minimum.reduceat(p, starts, axis=0)
        box_hi[lab[starts]] = np.maximum.reduceat(p, starts, axis=0)
    inner = np.flatnonzero(result["interior"])
    pieces_with, first = np.unique(result["tri_label"][inner], return_index=True)
    query[pieces_with] = pos[tri[inner[first], 0]]
    return box_lo, box_hi, query


def _final_ids(result, first_id):
    """Per particle of a tile (with its halo): its vertex id in the stitched surface, the
    loader's id or first_id + its rank among the tile's own; -1 for the halo's."""
    core, ids = result["core"], result["ids"]
    out = np.full(result["n"], -1, dtype=np.int64)
    out[core] = ids[core] if ids is not None else first_id + np.arange(int(core.sum()))
    return out


def _crossings(positions, triangles, final_ids, points):
    """particlemesh.ray_crossings of the triangles (rows of vertex indices) over their own
    vertices renumbered in the order of their final ids, as the stitched surface numbers them
    (the counts of the tiles and the driver then add up to the stitched surface's)."""
    verts = np.unique(triangles)
    verts = verts[np.argsort(final_ids[verts], kind="stable")]
    local = np.zeros(int(verts.max()) + 1, dtype=np.int64)
    local[verts] = np.arange(len(verts))
    return ray_crossings(Mesh(positions[verts], local[triangles]), points, threads=1)


def tile_crossings(result, first_id, piece_root, queries):
    """On a worker: for each closed component d in `queries` ({d: points}), how many of the
    tile's own triangles of d (its pieces whose piece_root is d) the ray straight up from each
    point crosses."""
    final = _final_ids(result, first_id)
    own = result["tri"][result["interior"]]
    root = piece_root[result["tri_label"][result["interior"]]]
    out = {}
    for d, points in queries.items():
        sel = own[root == d]
        out[d] = (_crossings(result["positions"], sel, final, points) if len(sel)
                  else np.zeros(len(points), dtype=np.uint64))
    return out


def seam_part(result):
    """On a worker: what the driver needs of a tile to stitch it: the triangles that reach
    another tile (seam) and those around the tile's particles near its faces (band), over a
    table of their vertices (own core rank or -1, position, owner tile, piece, normal), and
    per piece its volume, openness and highest particle."""
    tri, core, label = result["tri"], result["core"], result["label"]
    seam = result["touching"] & ~result["interior"]
    band = result["interior"] & result["near"][tri].any(axis=1) if len(tri) else seam
    parts = np.concatenate([np.flatnonzero(seam), np.flatnonzero(band & ~seam)])
    local = tri[parts]
    verts, inverse = np.unique(local.ravel(), return_inverse=True)
    rank = np.cumsum(core) - 1
    pos = result["positions"]
    ids = result["ids"]
    v_id = np.full(len(verts), -1, dtype=np.int64)
    if ids is not None:
        v_id[core[verts]] = ids[verts[core[verts]]]
    # Per piece: its highest own particle (for facing up when it stays open) and that
    # particle's normal's z.
    own = np.flatnonzero(core)
    top_z = np.full(result["pieces"], -np.inf)
    top_nz = np.zeros(result["pieces"])
    if len(own):
        order = np.lexsort((pos[own, 2], result["label"][own]))
        lab = result["label"][own[order]]
        last = np.flatnonzero(np.append(lab[1:] != lab[:-1], True))
        top = own[order[last]]
        top_z[result["label"][top]] = pos[top, 2]
        top_nz[result["label"][top]] = result["normals"][top, 2]
    box_lo, box_hi, query = _piece_boxes(result)
    return {
        "tri": inverse.reshape(-1, 3), "seam_count": int(seam.sum()),
        "tri_piece": result["tri_label"][parts],
        "v_rank": np.where(core[verts], rank[verts], -1), "v_id": v_id, "v_pos": pos[verts],
        "v_near": result["near"][verts],
        "v_piece": label[verts], "v_normal": result["normals"][verts],
        "pieces": result["pieces"], "volume": result["volume"], "open": result["open_piece"],
        "top_z": top_z, "top_nz": top_nz, "box_lo": box_lo, "box_hi": box_hi, "query": query,
        "core_count": int(core.sum()),
        "has_ids": ids is not None,
        "unused_core": result["unused_core"], "particles": result["particles"],
        "seconds": result["seconds"],
    }


def finish_tile(result, flip, first_id, with_points):
    """On a worker: the tile's own triangles (every corner its own) in final vertex ids, each
    piece turned as the driver decided (flip: +1/-1 per piece), and its particles' normals
    likewise; with_points: also their positions and attributes (a loader's tile)."""
    core, tri, label = result["core"], result["tri"], result["label"]
    to_final = _final_ids(result, first_id)
    final = to_final[core]
    own = tri[result["interior"]]
    turn = flip[result["tri_label"][result["interior"]]] < 0
    own = np.where(turn[:, None], own[:, [0, 2, 1]], own)
    out = {"ids": final, "triangles": to_final[own],
           "normals": result["normals"][core] * flip[label[core]][:, None]}
    if with_points:
        out["positions"] = result["positions"][core]
        out["attributes"] = {k: np.asarray(v)[core] for k, v in result["attributes"].items()}
    return out


def _spacing_of_tile(payload):
    """On a worker (a loader without spacing=): the tile's spacing estimate and particles."""
    p = load(payload)["positions"]
    if len(p) < 2:
        return 0.0, 0
    return estimate_spacing(p, max_samples=200_000), len(p)


def triangulate_tiled(client, particles, tiles=(2, 2, 1), *, normals=None, attributes=None,
                      bounds=None, halo=DEFAULT_HALO, progress=None, **options):
    """particlemesh.triangulate of one cloud, cut into tiles that Dask triangulates in parallel
    and stitched into one surface.

    particles: (N, 3) positions or Points (normals, attributes as in triangulate), or a loader
    loader(lo, hi) returning the particles in that box (an (N, 3) array, Points, or a dict with
    positions, normals, attributes, ids) in the cloud's order, with bounds=(lo, hi) the cloud's
    box. tiles=(nx, ny, nz): the box cut evenly. halo: the width around each tile, in units of
    the longest edge L (at least 3). Options are triangulate's (spacing, max_edge_factor,
    normal_angle, fill_holes, fill_edge_factor, normal_source, threads, ...; raw=True is not
    distributed; min_component_triangles applies to the stitched surface, whose pieces may
    span tiles). spacing defaults to the whole cloud's estimate (with a loader, the median of
    the tiles' estimates: give spacing= for the one-machine value).

    Returns a Mesh: vertex i is particle i (with a loader: the tiles' particles in tile order,
    x slowest, each tile's in the loader's order, or at the loader's ids), triangles
    canonical, normals angle-weighted from the surface. It is a consistently oriented
    2-manifold wherever the one-machine result is, closed components facing outward, every
    particle used that the tiles use; near the seams some triangles differ from the
    one-machine choice. A closed component inside another (a cavity's wall) faces into its
    cavity, as on one machine. mesh.stats: spacing, max_edge, tiles, halo, seam triangles,
    holes filled and left, triangles removed at pinched seam vertices, pieces turned, nested components, unused particles, pieces and
    triangles removed for min_component_triangles, bytes moved, seconds."""
    distributed()
    check_client(client)
    lib = _library.load()
    t0 = time.perf_counter()
    shape = tile_shape(tiles)
    if options.get("raw"):
        raise invalid("triangulate_tiled makes the finished surface; raw=True is not distributed")
    options.pop("raw", None)
    _options.TRIANGULATE.build(lib, {k: v for k, v in options.items()
                                     if k not in ("repair", "orient")})
    if not halo >= 3:
        raise invalid(f"halo is {halo}: at least 3 (units of L) so that every triangle at a "
                      "tile's particles, and its smallest-sphere test, is the one-machine one")
    source = Source(particles, normals=normals, attributes=attributes, bounds=bounds)
    defaults = library_defaults("triangulate")
    factor = float(options.get("max_edge_factor") or defaults["max_edge_factor"])
    fill_factor = float(options.get("fill_edge_factor") or defaults["fill_edge_factor"])
    fill_holes = options.get("fill_holes")
    fill_holes = defaults["fill_holes"] if fill_holes is None else int(fill_holes)
    cuts = Cuts(source.lo, source.hi, shape)
    indices = tile_indices(shape)

    spacing = options.get("spacing") or 0.0
    if not spacing:
        if source.loader is None:
            spacing = estimate_spacing(source.particles["positions"])
        else:
            futures = client.map(_spacing_of_tile, [source.payload(*cuts.box(i)) for i in indices],
                                 pure=False)
            est = [r for r in client.gather(futures) if r[1] > 0]
            if not est:
                raise Error("the loader returned no particles", _abi.PM_STATUS_INVALID_INPUT)
            est.sort()
            weights = np.cumsum([c for _, c in est])
            spacing = est[int(np.searchsorted(weights, weights[-1] / 2))][0]
    L = factor * spacing
    # Small pieces are removed from the stitched surface, not from the tiles: a piece cut by a
    # tile's halo may be small there and large across the seams.
    min_triangles = int(options.get("min_component_triangles") or 0)
    tile_options = dict(options, spacing=spacing, min_component_triangles=0)
    t_setup = time.perf_counter() - t0

    # ---- the tiles, each its whole chain; only the seams come back now -------------------
    payloads = []
    for index in indices:
        lo, hi = cuts.box(index)
        payloads.append(source.payload(lo - halo * L, hi + halo * L))
    sent = nbytes(payloads)
    if source.loader is None:  # the arrays go to the workers once, one tile each
        payloads = client.scatter(payloads, hash=False)
    token = uuid.uuid4().hex[:8]
    n = len(indices)
    results = client.map(triangulate_tile, payloads, range(n), [cuts] * n, [tile_options] * n,
                         [_NEAR * L] * n, key=[f"particlemesh-tile-{i}-{token}" for i in range(n)],
                         pure=False)
    summaries = client.map(seam_part, results, key=[f"particlemesh-seams-{i}-{token}" for i in range(n)],
                           pure=False)
    report = (lambda done: progress(done, 2 * n)) if progress is not None else None
    parts = gather_in_order(summaries, report)
    received = nbytes(parts)
    t_tiles = time.perf_counter() - t0 - t_setup

    # ---- the seams ----------------------------------------------------------------------------
    counts = [p["core_count"] for p in parts]
    first_id = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    total = int(sum(counts))
    if source.count is not None and total != source.count:
        raise Error(f"the tiles own {total} particles, not {source.count}", _abi.PM_STATUS_INTERNAL)
    seams = Stitch(parts, cuts, first_id)
    seams.orient_pieces()
    seams.choose()
    seams.close_holes(fill_factor * L, fill_holes)
    joined = lambda key: np.concatenate([p[key] for p in parts])
    seams.join(joined("open"))
    # Closed components inside others (a hollow object's inner wall, and what lies in its
    # cavity) face into their cavity, as on one machine: whether a component's point lies
    # inside another is the parity of the triangles the ray from it crosses, counted on the
    # tiles that hold the enclosing one's triangles and at the seams, and added up.
    pairs = seams.nesting_pairs(joined("box_lo"), joined("box_hi"), joined("query"))
    crossings = {d: seams.crossings(d, points) for d, (_, points) in pairs.items()}
    if pairs:
        base = seams.piece_base
        jobs = []
        for t in range(n):
            roots = seams.root[base[t]:base[t] + parts[t]["pieces"]]
            asked = {d: points for d, (_, points) in pairs.items() if (roots == d).any()}
            jobs.append((t, roots, asked))
        jobs = [j for j in jobs if j[2]]
        counted = client.map(tile_crossings, [results[t] for t, _, _ in jobs],
                             [int(first_id[t]) for t, _, _ in jobs], [r for _, r, _ in jobs],
                             [a for _, _, a in jobs], pure=False,
                             key=[f"particlemesh-nesting-{t}-{token}" for t, _, _ in jobs])
        counted = client.gather(counted)
        received += nbytes(counted)
        for part in counted:
            for d, c in part.items():
                crossings[d] = crossings[d] + c
    depth = seams.nesting_depths(pairs, crossings)
    sign = seams.outward(joined("volume"), joined("top_z"), joined("top_nz"), depth)
    t_seams = time.perf_counter() - t0 - t_setup - t_tiles

    # ---- the tiles' own triangles, now turned, come back once --------------------------------
    with_points = source.loader is not None
    base = seams.piece_base
    finals = client.map(finish_tile, results,
                        [sign[base[t]:base[t] + parts[t]["pieces"]] for t in range(n)],
                        first_id.tolist(), [with_points] * n,
                        key=[f"particlemesh-finish-{i}-{token}" for i in range(n)], pure=False)
    report = (lambda done: progress(n + done, 2 * n)) if progress is not None else None
    done = gather_in_order(finals, report)
    received += nbytes(done)

    if with_points:
        order = np.concatenate([d["ids"] for d in done])
        if len(order) != total or not np.array_equal(np.sort(order), np.arange(total)):
            raise invalid("the loader's ids are not 0..N-1, each particle once")
        vertices = np.empty((total, 3))
        for d in done:
            vertices[d["ids"]] = d["positions"]
        attrs = {}
        for name in set.intersection(*(set(d["attributes"]) for d in done)):
            first = np.asarray(done[0]["attributes"][name])
            a = np.empty((total,) + first.shape[1:], dtype=first.dtype)
            for d in done:
                a[d["ids"]] = d["attributes"][name]
            attrs[name] = a
    else:
        vertices = source.particles["positions"]
        attrs = {k: np.asarray(v) for k, v in source.particles["attributes"].items()}
    vnormals = np.zeros((total, 3))
    for d in done:
        vnormals[d["ids"]] = d["normals"]
    ids, nrm = seams.normals()
    vnormals[ids] = nrm
    extra = seams.triangles()
    triangles = np.concatenate([d["triangles"] for d in done] + [extra])
    # Where seam triangles of two tiles meet at a corner only, that vertex is pinched: the
    # largest fan stays there, as the library's repair leaves it (the rest's normals anew).
    kept, touched = unpinch(triangles, np.unique(extra))
    pinches_triangles = int((~kept).sum())
    if pinches_triangles:
        triangles = triangles[kept]
        around = triangles[np.isin(triangles, touched).any(axis=1)]
        local, index = np.unique(around, return_inverse=True)
        n_local = angle_weighted_normals(vertices[local], index.reshape(-1, 3), len(local))
        at = np.isin(local, touched) & (np.linalg.norm(n_local, axis=1) > 0)
        vnormals[local[at]] = n_local[at]
    pieces_removed = triangles_removed = 0
    if min_triangles > 1 and len(triangles):
        labels = _components(total, triangles)
        per_piece = np.bincount(labels[triangles[:, 0]], minlength=int(labels.max()) + 1)
        small = per_piece < min_triangles
        keep = ~small[labels[triangles[:, 0]]]
        pieces_removed = int((small & (per_piece > 0)).sum())
        triangles_removed = int((~keep).sum())
        triangles = triangles[keep]
    used = np.zeros(total, dtype=bool)
    used[triangles.ravel()] = True
    mesh = Mesh(vertices, canonical_triangles(triangles), vnormals, attrs)
    mesh.stats = {
        "spacing": spacing, "max_edge": L, "tiles": shape, "halo": halo,
        "tile_particles": [p["particles"] for p in parts],
        "tile_seconds": [p["seconds"] for p in parts],
        "seam_triangles": len(seams.copies), "seam_rejected": seams.rejected,
        "pieces": seams.n_pieces, "pieces_aligned": int(seams.flip.sum()),
        "pieces_turned": int((sign < 0).sum()),
        "nested_components": int((depth > 0).sum()), "nesting_tests": sum(len(c) for c, _ in pairs.values()),
        "holes_filled": len(seams.loops) - len(seams.left), "fill_triangles": len(seams.fills),
        "holes_left": len(seams.left), "pinch_triangles_removed": pinches_triangles,
        "unused_points": int((~used).sum()),
        "components_removed": pieces_removed, "component_triangles_removed": triangles_removed,
        "bytes_sent": sent, "bytes_received": received, "seconds_tiles": t_tiles,
        "seconds_seams": t_seams, "seconds": time.perf_counter() - t0,
    }
    return mesh

