"""Stitching triangulated tiles along their seams (the driver's part of triangulate_tiled):
aligning the tiles' orientations, closing the holes where two tiles' surfaces disagree, and
vertex normals there. Everything here works on the few triangles near the seams.

Why hand-written: the finishing stages of the library (manifold extraction, repair) run on one
whole cloud; across tiles only their results meet, and what is left to do there (a 2-colouring
of a small graph, filling a few loops of a handful of edges) has no library of its own."""

import math
from collections import defaultdict

import numpy as np


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
        for y in reversed(path):  # compress, accumulating the parity to the root
            acc ^= self.parity[y]
            self.parity[y] = acc
            self.parent[y] = root
        return root

    def parity_of(self, x):
        self.find(x)
        return self.parity[x] if self.parent[x] != x else 0

    def union(self, a, b, relation=0):
        """Join a and b with parity(a) ^ parity(b) == relation; False if that contradicts
        what is known."""
        ra, rb = self.find(a), self.find(b)
        pa, pb = self.parity_of(a), self.parity_of(b)
        if ra == rb:
            return (pa ^ pb) == relation
        self.parent[rb] = ra
        self.parity[rb] = pa ^ pb ^ relation
        return True


def even_permutation(tri):
    """Whether the triangle's corners, in its order, are an even permutation (a rotation) of
    their ascending order: the winding relative to the sorted corners."""
    a, b, c = tri
    return (a < b < c) or (b < c < a) or (c < a < b)


def boundary_loops(triangles, vertices_ok):
    """The holes of a triangle set whose vertices_ok(v) vertices have complete stars: closed
    loops v0, v1, ... such that each (v_{i+1}, v_i) is a directed edge of one triangle and
    (v_i, v_{i+1}) of none, through vertices_ok vertices only (a chain that leaves them is not
    a hole of ours). A loop through a vertex twice is split there. Deterministic: each loop
    starts at its smallest vertex, the list is sorted."""
    directed = set()
    for a, b, c in triangles:
        directed.update(((a, b), (b, c), (c, a)))
    # Along a hole: b -> a for each boundary half-edge a -> b.
    steps = sorted((b, a) for a, b in directed
                   if (b, a) not in directed and vertices_ok(a) and vertices_ok(b))
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
                break  # closed, or a chain leaving the vertices we know: not a hole of ours
            step = (v, nxt[0])
    out = []
    for loop in loops:
        i = loop.index(min(loop))
        out.append(loop[i:] + loop[:i])
    return sorted(out)


def _angle(p, q, r):
    """The angle at q of triangle p, q, r, in radians."""
    u, v = p - q, r - q
    nu, nv = np.linalg.norm(u), np.linalg.norm(v)
    if nu == 0 or nv == 0:
        return math.pi
    return math.acos(max(-1.0, min(1.0, float(np.dot(u, v) / (nu * nv)))))


def fill_loop(loop, position, max_edge, edge_exists):
    """Triangles (wound with the loop: the fill holds v_i -> v_{i+1}) closing a loop, with the
    triangulation that minimises its largest angle (as the library fills small holes), using
    no edge longer than max_edge and no diagonal that is already an edge elsewhere; None when
    there is none."""
    m = len(loop)
    P = [np.asarray(position(v), dtype=np.float64) for v in loop]
    ok = [[False] * m for _ in range(m)]
    for i in range(m):
        for j in range(i + 1, m):
            adjacent = j == i + 1 or (i == 0 and j == m - 1)
            short = np.linalg.norm(P[i] - P[j]) <= max_edge
            ok[i][j] = ok[j][i] = adjacent or (short and not edge_exists(loop[i], loop[j]))
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
                if not (ok[i][k] and ok[k][j]) or cost[i][k] == inf or cost[k][j] == inf:
                    continue
                worst = max(_angle(P[j], P[i], P[k]), _angle(P[i], P[k], P[j]),
                            _angle(P[k], P[j], P[i]))
                c = max(cost[i][k], cost[k][j], worst)
                if c < cost[i][j]:
                    cost[i][j], best[i][j] = c, k
    if cost[0][m - 1] == inf:
        return None
    out = []
    stack = [(0, m - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        k = best[i][j]
        out.append((loop[i], loop[k], loop[j]))
        stack += [(i, k), (k, j)]
    return out


def vertex_normals(triangles, position, vertices):
    """Angle-weighted normals (the library's vertex normals) of `vertices` from the triangles
    around them: {v: unit normal}."""
    acc = {v: np.zeros(3) for v in vertices}
    for tri in triangles:
        p = [np.asarray(position(v), dtype=np.float64) for v in tri]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        ln = np.linalg.norm(n)
        if ln == 0:
            continue
        n /= ln
        for k in range(3):
            v = tri[k]
            if v in acc:
                acc[v] += _angle(p[k - 1], p[k], p[(k + 1) % 3]) * n
    out = {}
    for v, n in acc.items():
        ln = np.linalg.norm(n)
        if ln > 0:
            out[v] = n / ln
    return out
