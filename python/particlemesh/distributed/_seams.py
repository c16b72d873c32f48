"""Stitching triangulated tiles along their seams (the driver's part of triangulate_tiled):
the tiles' seam and band triangles joined over final vertex ids, the tiles' pieces turned to
agree, the seam triangles every owner chose kept, the holes where tiles chose differently
closed, the components turned outward, vertex normals near the seams. All of it works on the
triangles near the seams only (arrays; Python loops only over seam triangles and holes).

Why hand-written: the library's finishing stages run on one whole cloud; across tiles only
their results meet, and what is left to do there (a 2-colouring of a small graph of pieces,
filling a few loops of a handful of edges) has no library of its own."""

import math
from collections import defaultdict

import numpy as np

from .. import Mesh, ray_crossings


class UnionFind:
    """Disjoint sets over 0..n-1 with a parity per element relative to its root (for
    orientations: parity 1 = turned against the root)."""

    def __init__(self, n):
        self.parent = list(range(n))
        self.parity = [0] * n

    def find(self, x):
        path = []
        while self.parent[x] != x:
            path.append(x)
            x = self.parent[x]
        root, acc = x, 0
        for y in reversed(path):  # compress, accumulating each one's parity to the root
            acc ^= self.parity[y]
            self.parity[y] = acc
            self.parent[y] = root
        return root

    def parity_of(self, x):
        self.find(x)
        return self.parity[x] if self.parent[x] != x else 0

    def union(self, a, b, relation=0):
        """Join a and b with parity(a) ^ parity(b) == relation; False if that contradicts
        what is known (then nothing changes)."""
        ra, rb = self.find(a), self.find(b)
        pa, pb = self.parity_of(a), self.parity_of(b)
        if ra == rb:
            return (pa ^ pb) == relation
        self.parent[rb] = ra
        self.parity[rb] = pa ^ pb ^ relation
        return True


def even_windings(tris):
    """Per triangle (rows of 3 distinct ids): whether its corners, in its order, are a rotation
    of their ascending order (its winding relative to the sorted corners)."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    return ((a < b) & (b < c)) | ((b < c) & (c < a)) | ((c < a) & (a < b))


def turn(tris, mask):
    """The triangles with the rows in `mask` wound the other way."""
    out = np.array(tris, dtype=np.int64).reshape(-1, 3)
    out[mask] = out[mask][:, [0, 2, 1]]
    return out


def boundary_steps(triangles, ok):
    """The hole steps (b, a) of a triangle set: a -> b is a directed edge of one triangle and
    b -> a of none, both ends `ok` (a boolean per vertex index)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return []
    he = t[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    n = int(he.max()) + 1
    key, rev = he[:, 0] * n + he[:, 1], he[:, 1] * n + he[:, 0]
    b = ~np.isin(key, rev) & ok[he[:, 0]] & ok[he[:, 1]]
    return sorted(zip(he[b, 1].tolist(), he[b, 0].tolist()))


def trace_loops(steps):
    """Closed loops from hole steps (v -> w): v0, v1, ... with every (v_i, v_{i+1}) a step. A
    loop through a vertex twice is split there; a chain that does not close is not a hole of
    ours (it leaves the vertices we know). Each loop starts at its smallest vertex; sorted."""
    succ = defaultdict(list)
    for v, w in steps:
        succ[v].append(w)
    unused = set(steps)
    loops = []
    for step in steps:
        if step not in unused:
            continue
        path, at = [step[0]], {step[0]: 0}
        while True:
            unused.discard(step)
            v = step[1]
            if v in at:  # the part of the path since v's visit is a loop
                i = at[v]
                if len(path) - i >= 3:
                    loops.append(path[i:])
                for x in path[i + 1:]:
                    del at[x]
                del path[i + 1:]
            else:
                at[v] = len(path)
                path.append(v)
            nxt = [w for w in succ[v] if (v, w) in unused]
            if not nxt:
                break
            step = (v, nxt[0])
    out = []
    for loop in loops:
        i = loop.index(min(loop))
        out.append(loop[i:] + loop[:i])
    return sorted(out)


def _angle(p, q, r):
    """The angle at q of triangle p, q, r, in radians."""
    u, v = p - q, r - q
    nu, nv = math.sqrt(u @ u), math.sqrt(v @ v)
    if nu == 0 or nv == 0:
        return math.pi
    return math.acos(max(-1.0, min(1.0, float(u @ v) / (nu * nv))))


def fill_loop(loop, P, max_edge, edge_exists):
    """Triangles (indices into the loop, wound with it: the fill holds v_i -> v_{i+1}) closing
    a loop with corner positions P, by the triangulation that minimises its largest angle (as
    the library fills small holes), with no edge longer than max_edge and no diagonal that is
    already an edge elsewhere; None when there is none. O(m^3) in the loop's edges m."""
    m = len(loop)
    ok = [[False] * m for _ in range(m)]
    for i in range(m):
        for j in range(i + 1, m):
            adjacent = j == i + 1 or (i == 0 and j == m - 1)
            d = P[i] - P[j]
            ok[i][j] = ok[j][i] = adjacent or (math.sqrt(d @ d) <= max_edge
                                               and not edge_exists(loop[i], loop[j]))
    inf = float("inf")
    cost = [[inf] * m for _ in range(m)]
    best = [[-1] * m for _ in range(m)]
    for i in range(m - 1):
        cost[i][i + 1] = 0.0
    for span in range(2, m):
        for i in range(m - span):
            j = i + span
            if not ok[i][j]:
                continue
            for k in range(i + 1, j):
                if cost[i][k] == inf or cost[k][j] == inf:
                    continue
                worst = max(_angle(P[j], P[i], P[k]), _angle(P[i], P[k], P[j]),
                            _angle(P[k], P[j], P[i]))
                c = max(cost[i][k], cost[k][j], worst)
                if c < cost[i][j]:
                    cost[i][j], best[i][j] = c, k
    if cost[0][m - 1] == inf:
        return None
    out, stack = [], [(0, m - 1)]
    while stack:
        i, j = stack.pop()
        if j - i >= 2:
            k = best[i][j]
            out.append((i, k, j))
            stack += [(i, k), (k, j)]
    return out


def angle_weighted_normals(positions, triangles, count):
    """Per vertex 0..count-1: the unit sum of its triangles' unit normals weighted by their
    angle there (the library's vertex normals); zero where it has none."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    out = np.zeros((count, 3))
    if len(t) == 0:
        return out
    p = positions[t]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    ln = np.linalg.norm(n, axis=1)
    good = ln > 0
    n[good] /= ln[good, None]
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        c = np.einsum("ij,ij->i", u, v) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
        w = np.arccos(np.clip(c, -1.0, 1.0)) * good
        for a in range(3):
            out[:, a] += np.bincount(t[:, k], weights=w * n[:, a], minlength=count)
    ln = np.linalg.norm(out, axis=1)
    out[ln > 0] /= ln[ln > 0, None]
    return out


def unpinch(triangles, at=None):
    """The library's last repair of pinches, on the stitched surface: a vertex whose triangles
    make several fans (joined only through it: seam triangles of two tiles meeting at a corner)
    keeps its largest fan (the most triangles, then the one with the first triangle), and the
    other fans' triangles at it are removed, until no vertex has two. Only the vertices in `at`
    (ids; None: all) and those of removed triangles are looked at: the tiles' own surfaces have
    no pinch. Returns the mask of the triangles kept and the vertices whose triangles changed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    keep = np.ones(len(t), dtype=bool)
    if len(t) == 0:
        return keep, np.zeros(0, dtype=np.int64)
    n = int(t.max()) + 1
    look = np.ones(n, dtype=bool) if at is None else np.zeros(n, dtype=bool)
    if at is not None:
        ids = np.asarray(at, dtype=np.int64)
        look[ids[(ids >= 0) & (ids < n)]] = True
    touched = []
    while True:
        # The live triangles at a vertex looked at: all of its triangles, so its fans are whole.
        live = np.flatnonzero(keep & look[t].any(axis=1))
        if len(live) == 0:
            break
        # Corner c = 3 i + k of those: vertex v = t[i, k], the others a, b. Two corners at v
        # are in one fan when their triangles share an edge (v, x).
        sub = t[live]
        v = sub.ravel()
        a = sub[:, [1, 2, 0]].ravel()
        b = sub[:, [2, 0, 1]].ravel()
        corner = np.arange(len(v))
        keys = np.concatenate([v * n + a, v * n + b])
        owner = np.concatenate([corner, corner])
        order = np.argsort(keys, kind="stable")
        same = keys[order][1:] == keys[order][:-1]
        rows, cols = owner[order][1:][same], owner[order][:-1][same]
        graph = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(len(v), len(v)))
        fan = connected_components(graph, directed=False)[1]
        size = np.bincount(fan)
        first = np.full(len(size), len(v))
        np.minimum.at(first, fan, corner)
        pairs = np.unique(np.stack([v, fan], axis=1), axis=0)
        pairs = pairs[look[pairs[:, 0]]]
        counts = np.bincount(pairs[:, 0], minlength=n)
        # Fans of pinched vertices, best first per vertex: most corners, then earliest.
        cand = pairs[counts[pairs[:, 0]] > 1]
        if len(cand) == 0:
            break
        rank = np.lexsort((first[cand[:, 1]], -size[cand[:, 1]], cand[:, 0]))
        cand = cand[rank]
        best = np.r_[True, cand[1:, 0] != cand[:-1, 0]]
        losing = np.zeros(len(size), dtype=bool)
        losing[cand[~best, 1]] = True
        drop = live[np.unique(corner[losing[fan]] // 3)]
        keep[drop] = False
        changed = np.unique(t[drop])
        touched.append(changed)
        look[:] = False
        look[changed] = True
    return keep, (np.unique(np.concatenate(touched)) if touched else np.zeros(0, dtype=np.int64))


class Stitch:
    """The seams of a tiled triangulation, from the tiles' seam_part()s (see _triangulate).

    Vertices are final ids; `table` holds the particles the seam and band triangles use that
    some tile owns: their position, owner tile, piece (a global number: tile's base + its
    component) and whether they lie near their tile's faces (then all their triangles are
    here)."""

    def __init__(self, parts, cuts, first_id):
        self.piece_base = np.concatenate([[0], np.cumsum([p["pieces"] for p in parts])[:-1]]).astype(np.int64)
        self.n_pieces = int(sum(p["pieces"] for p in parts))
        # Own vertices: final ids.
        vid, own_seam = [], {}
        for t, p in enumerate(parts):
            ids = np.full(len(p["v_rank"]), -1, dtype=np.int64)
            mine = p["v_rank"] >= 0
            ids[mine] = p["v_id"][mine] if p["has_ids"] else first_id[t] + p["v_rank"][mine]
            vid.append(ids)
            seam_v = np.unique(p["tri"][:p["seam_count"]])
            for i in seam_v[mine[seam_v]]:
                own_seam[(t, p["v_pos"][i].tobytes())] = int(ids[i])
        # Another tile's particles: by their owner and exact coordinates (the owner lists them
        # when its own surface uses them near its faces; else no triangle of the owner holds
        # them, and the triangles naming them are not kept).
        for t, p in enumerate(parts):
            foreign = np.flatnonzero(vid[t] < 0)
            if len(foreign):
                owners = cuts.owner(p["v_pos"][foreign])
                for i, u in zip(foreign, owners):
                    vid[t][i] = own_seam.get((int(u), p["v_pos"][i].tobytes()), -1)
        # The table of own vertices.
        cols = {"id": [], "pos": [], "near": [], "piece": [], "normal": [], "owner": []}
        for t, p in enumerate(parts):
            mine = p["v_rank"] >= 0
            cols["id"].append(vid[t][mine])
            cols["pos"].append(p["v_pos"][mine])
            cols["near"].append(p["v_near"][mine])
            cols["piece"].append(self.piece_base[t] + p["v_piece"][mine])
            cols["normal"].append(p["v_normal"][mine])
            cols["owner"].append(np.full(int(mine.sum()), t, dtype=np.int64))
        order = np.argsort(np.concatenate(cols["id"]), kind="stable")
        for k, v in cols.items():
            setattr(self, k, np.concatenate(v)[order] if len(v) else np.zeros(0))
        self.count = len(self.id)
        # Triangles, as table indices: seam copies (tile, piece, winding) and band.
        seam, seam_tile, seam_piece, band, band_piece = [], [], [], [], []
        for t, p in enumerate(parts):
            corners = vid[t][p["tri"]]
            k = p["seam_count"]
            good = (corners[:k] >= 0).all(axis=1)
            seam.append(corners[:k][good])
            seam_tile.append(np.full(int(good.sum()), t))
            seam_piece.append(self.piece_base[t] + p["tri_piece"][:k][good])
            band.append(corners[k:])
            band_piece.append(self.piece_base[t] + p["tri_piece"][k:])
        self.seam = self.index(np.concatenate(seam))
        self.seam_tile = np.concatenate(seam_tile).astype(np.int64)
        self.seam_piece = np.concatenate(seam_piece).astype(np.int64)
        self.band = self.index(np.concatenate(band))
        self.band_piece = np.concatenate(band_piece).astype(np.int64)
        ok = (self.seam >= 0).all(axis=1)  # a corner no tile owns here: the owner did not choose it
        self.seam, self.seam_tile, self.seam_piece = self.seam[ok], self.seam_tile[ok], self.seam_piece[ok]

    def index(self, ids):
        """Table rows of final ids (-1 where absent)."""
        ids = np.asarray(ids, dtype=np.int64)
        if self.count == 0:
            return np.full(ids.shape, -1, dtype=np.int64)
        at = np.clip(np.searchsorted(self.id, ids), 0, self.count - 1)
        return np.where(self.id[at] == ids, at, -1)

    def orient_pieces(self):
        """Turn pieces to agree where the same seam triangle is in two tiles (majority of
        their seam triangles, most-shared pairs first): per piece, 1 = turned."""
        self.key, self.group = np.unique(np.sort(self.seam, axis=1), axis=0, return_inverse=True)
        self.group = self.group.reshape(-1)
        self.even = even_windings(self.seam)
        votes = defaultdict(lambda: [0, 0])
        order = np.argsort(self.group, kind="stable")
        g = self.group[order]
        starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
        ends = np.r_[starts[1:], len(g)]
        self.copies = [order[s:e] for s, e in zip(starts, ends)]
        for rows in self.copies:
            for i in range(len(rows)):
                for j in range(i + 1, len(rows)):
                    a, b = rows[i], rows[j]
                    pa, pb = int(self.seam_piece[a]), int(self.seam_piece[b])
                    if pa != pb:
                        votes[(min(pa, pb), max(pa, pb))][int(self.even[a] != self.even[b])] += 1
        uf = UnionFind(self.n_pieces)
        for (a, b), (same, opposite) in sorted(votes.items(), key=lambda kv: (-sum(kv[1]), kv[0])):
            uf.union(a, b, int(opposite > same))
        self.flip = np.array([uf.parity_of(i) for i in range(self.n_pieces)], dtype=bool)
        return self.flip

    def choose(self):
        """The seam triangles every owner of their corners chose, wound alike once the pieces
        are turned: (triangles wound as the turned pieces, their piece), and how many were not
        kept."""
        owner = self.owner
        kept, pieces, rejected = [], [], 0
        wind = self.even ^ self.flip[self.seam_piece]
        for rows, key in zip(self.copies, self.key):
            owners = set(owner[key].tolist())
            tiles = set(self.seam_tile[rows].tolist())
            if not owners <= tiles or len(set(wind[rows].tolist())) != 1:
                rejected += 1
                continue
            first = rows[self.seam_tile[rows] == owner[key[0]]][0]
            kept.append(key if wind[first] else key[[0, 2, 1]])
            pieces.append(self.seam_piece[first])
        self.stitched = np.array(kept, dtype=np.int64).reshape(-1, 3)
        self.stitched_piece = np.array(pieces, dtype=np.int64)
        self.rejected = rejected
        return self.stitched

    def close_holes(self, max_edge, max_loop):
        """Fill the holes near the seams (loops through near vertices) where the fill stays
        within max_edge and max_loop edges; the rest stay open (returned)."""
        around = np.concatenate([turn(self.band, self.flip[self.band_piece]), self.stitched])
        loops = trace_loops(boundary_steps(around, self.near.astype(bool)))
        fills, left = [], []
        if loops:
            in_loops = np.zeros(self.count, dtype=bool)
            in_loops[np.concatenate([np.asarray(lp) for lp in loops])] = True
            e = around[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
            e = e[in_loops[e[:, 0]] & in_loops[e[:, 1]]]
            edges = {(min(a, b), max(a, b)) for a, b in e.tolist()}
            for loop in loops:
                tris = None
                if len(loop) <= max_loop:
                    tris = fill_loop(loop, self.pos[loop], max_edge,
                                     lambda a, b: (min(a, b), max(a, b)) in edges)
                if tris is None:
                    left.append(loop)
                    continue
                for i, k, j in tris:
                    tri = (loop[i], loop[k], loop[j])
                    fills.append(tri)
                    edges.update((min(a, b), max(a, b)) for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])))
        self.fills = np.array(fills, dtype=np.int64).reshape(-1, 3)
        self.fills_piece = self.piece[self.fills[:, 0]] if len(fills) else np.zeros(0, dtype=np.int64)
        self.loops, self.left = loops, left
        return left

    def join(self, is_open):
        """The components: pieces joined by the seam and fill triangles (self.root, per piece
        its component's first piece) and whether each is open (self.comp_open, per root): a
        tile saw a real opening in one of its pieces, or a loop here stayed open. is_open: per
        piece."""
        is_open = is_open.copy()
        self.extra = np.concatenate([self.stitched, self.fills])
        for loop in self.left:
            is_open[self.piece[loop]] = True
        joined = UnionFind(self.n_pieces)
        for tri in self.extra.tolist():
            ps = self.piece[tri]
            joined.union(int(ps[0]), int(ps[1]))
            joined.union(int(ps[0]), int(ps[2]))
        self.root = np.array([joined.find(i) for i in range(self.n_pieces)], dtype=np.int64)
        self.comp_open = np.bincount(self.root, weights=is_open, minlength=self.n_pieces) > 0
        return self.root

    def nesting_pairs(self, box_lo, box_hi, query):
        """Which closed components may lie inside which, as the library's nesting test pairs
        them (the enclosing one's box holds the other's), with each inner one's point (its
        first piece's, see _piece_boxes; else a corner of its seam triangles): {outer root:
        (inner roots, their points)}. box_lo, box_hi, query: per piece."""
        n = self.n_pieces
        lo = np.full((n, 3), np.inf)
        hi = np.full((n, 3), -np.inf)
        np.minimum.at(lo, self.root, box_lo)
        np.maximum.at(hi, self.root, box_hi)
        point = np.full((n, 3), np.nan)
        if len(self.extra):  # a component of seam triangles only: a corner of its first one
            corner = self.extra[:, 0]
            roots, first = np.unique(self.root[self.piece[corner]], return_index=True)
            point[roots] = self.pos[corner[first]]
        has = np.flatnonzero(np.isfinite(query[:, 0]))
        roots, first = np.unique(self.root[has], return_index=True)  # its first piece's point
        point[roots] = query[has[first]]
        closed = np.flatnonzero((self.root == np.arange(n)) & ~self.comp_open & (lo[:, 0] <= hi[:, 0]))
        inner = closed[np.isfinite(point[closed, 0])]
        # The inner candidates by their box's low x (ties by root), and for each d only those
        # whose low x lies within d's box, as the library pairs them: near linear for parts
        # side by side (a frame of bubbles), not one test per pair of parts.
        inner = inner[np.lexsort((inner, lo[inner, 0]))]
        inner_lo, inner_hi, inner_x = lo[inner], hi[inner], lo[inner, 0]
        first = np.searchsorted(inner_x, lo[closed, 0], side="left")
        last = np.searchsorted(inner_x, hi[closed, 0], side="right")
        pairs = {}
        for d, a, b in zip(closed.tolist(), first.tolist(), last.tolist()):
            if b <= a:
                continue
            c = inner[a:b]
            holds = ((inner_lo[a:b] >= lo[d]) & (inner_hi[a:b] <= hi[d])).all(axis=1) & (c != d)
            if holds.any():
                c = np.sort(c[holds])  # root order, as before
                pairs[d] = (c, point[c])
        return pairs

    def crossings(self, d, points):
        """How many of the seam and fill triangles of component d the ray straight up from each
        point crosses (rows of the table are in final-id order, as the tiles number theirs)."""
        sel = self.extra[self.root[self.piece[self.extra[:, 0]]] == d] if len(self.extra) else self.extra
        if len(sel) == 0:
            return np.zeros(len(points), dtype=np.uint64)
        verts = np.unique(sel)
        local = np.searchsorted(verts, sel)
        return ray_crossings(Mesh(self.pos[verts], local), points, threads=1)

    def nesting_depths(self, pairs, crossings):
        """Per component (root): how many closed components enclose it, from the total
        crossings of each pair's ray (odd: inside)."""
        depth = np.zeros(self.n_pieces, dtype=np.int64)
        for d, (inner, _) in pairs.items():
            np.add.at(depth, inner, (crossings[d] % 2).astype(np.int64))
        return depth

    def outward(self, volume, top_z, top_nz, depth):
        """Turn each component outward: per piece (tile components, joined by the seam and fill
        triangles) the final sign (+1 or -1 against the tile's own winding). A closed
        component faces away from the solid it bounds, as on one machine: it encloses positive
        volume, or negative at an odd nesting depth (a cavity's wall); an open one faces up
        (+z) at its highest particle. volume, top_z, top_nz: per piece, as the tiles wound
        them; depth: per component (nesting_depths)."""
        sign = np.where(self.flip, -1.0, 1.0)
        volume = volume * sign
        top_nz = top_nz * sign
        if len(self.extra):
            p = self.pos[self.extra]
            det = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0
            volume += np.bincount(self.piece[self.extra[:, 0]], weights=det, minlength=self.n_pieces)
        root = self.root
        comp_volume = np.bincount(root, weights=volume, minlength=self.n_pieces)
        highest = {}
        for i in np.argsort(top_z, kind="stable"):
            highest[root[i]] = i  # the last (highest) wins
        outward = np.zeros(self.n_pieces, dtype=bool)
        for r, i in highest.items():
            if self.comp_open[r]:
                outward[r] = top_nz[i] < 0
            else:  # turned unless it faces away from its solid (mesh/nesting.h)
                outward[r] = (comp_volume[r] < 0) if depth[r] % 2 == 0 else (comp_volume[r] > 0)
        self.turn_component = outward[root]
        self.sign = sign * np.where(self.turn_component, -1.0, 1.0)
        return self.sign

    def triangles(self):
        """The stitched and fill triangles, wound as the final surface faces (final ids)."""
        extra = np.concatenate([turn(self.stitched, self.turn_component[self.stitched_piece]),
                                turn(self.fills, self.turn_component[self.fills_piece])])
        return self.id[extra] if len(extra) else extra

    def normals(self):
        """(final ids, unit normals) of the near vertices, from the triangles around them."""
        around = np.concatenate([turn(self.band, self.sign[self.band_piece] < 0),
                                 turn(self.stitched, self.turn_component[self.stitched_piece]),
                                 turn(self.fills, self.turn_component[self.fills_piece])])
        n = angle_weighted_normals(self.pos, around, self.count)
        near = self.near.astype(bool) & (np.linalg.norm(n, axis=1) > 0)
        return self.id[near], n[near]
