"""Meshes in a canonical order, and tiles' meshes merged on their shared vertices."""

import numpy as np

from .._data import Mesh


def canonical_triangles(triangles):
    """Each triangle turned to start at its smallest vertex (the winding kept), the list
    sorted: the same array for the same set of triangles."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return np.zeros((0, 3), dtype=np.int32)
    r = np.argmin(t, axis=1)
    rows = np.arange(len(t))
    t = np.stack([t[rows, (r + k) % 3] for k in range(3)], axis=1)
    t = t[np.lexsort((t[:, 2], t[:, 1], t[:, 0]))]
    return t.astype(np.int32)


def _position_order(vertices):
    """A stable order of the vertices by z, then y, then x."""
    v = vertices
    return np.lexsort((v[:, 0], v[:, 1], v[:, 2]))


def canonical_mesh(mesh):
    """The same mesh with its vertices ordered by position (z, then y, then x) and its
    triangles canonical (canonical_triangles): two meshes with the same vertices and the same
    triangles, in any order, become identical arrays. polygonize_tiled returns this order, so
    canonical_mesh(particlemesh.polygonize(...)) compares with it array for array."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    order = _position_order(v)
    rank = np.empty(len(v), dtype=np.int64)
    rank[order] = np.arange(len(v))
    normals = None if getattr(mesh, "normals", None) is None else np.asarray(mesh.normals)[order]
    attributes = {k: np.asarray(a)[order] for k, a in (getattr(mesh, "attributes", None) or {}).items()}
    triangles = canonical_triangles(rank[np.asarray(mesh.triangles, dtype=np.int64)])
    return Mesh(v[order], triangles, normals, attributes, dict(getattr(mesh, "stats", {}) or {}))


def merge_by_position(parts):
    """One mesh from tiles' meshes whose shared vertices are the same bit for bit: vertices
    with equal coordinates become one (its normal and attributes are the first tile's; they
    are equal), in canonical order (see canonical_mesh). parts: [(vertices, triangles,
    normals or None, attributes)]."""
    parts = [p for p in parts if len(p[0])]
    if not parts:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32), None, {})
    vertices = np.concatenate([p[0] for p in parts])
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    triangles = np.concatenate([np.asarray(p[1], dtype=np.int64) + o for p, o in zip(parts, offsets)])
    has_normals = all(p[2] is not None for p in parts)
    names = set(parts[0][3])
    order = _position_order(vertices)
    sorted_v = vertices[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = (sorted_v[1:] != sorted_v[:-1]).any(axis=1)
    remap = np.empty(len(order), dtype=np.int64)
    remap[order] = np.cumsum(first) - 1
    keep = order[first]
    normals = np.concatenate([p[2] for p in parts])[keep] if has_normals else None
    attributes = {n: np.concatenate([p[3][n] for p in parts])[keep] for n in names
                  if all(n in p[3] for p in parts)}
    return Mesh(vertices[keep], canonical_triangles(remap[triangles]), normals, attributes)
