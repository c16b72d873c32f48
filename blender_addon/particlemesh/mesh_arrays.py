"""Array work between Blender and the library, in numpy only (bpy-free, testable outside
Blender): transforms, particle masks, winding from normals, the per-frame cache key."""

import hashlib

import numpy as np


def transform_points(points, matrix):
    """(N, 3) float32 points times a 4x4 matrix (any nested sequence), in float64 then back."""
    m = np.asarray(matrix, dtype=np.float64).reshape(4, 4)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return (p @ m[:3, :3].T + m[:3, 3]).astype(np.float32)


def transform_normals(normals, matrix):
    """Normals under the inverse transpose of the matrix's linear part, re-normalised."""
    m = np.asarray(matrix, dtype=np.float64).reshape(4, 4)[:3, :3]
    try:
        nm = np.linalg.inv(m).T
    except np.linalg.LinAlgError:
        nm = m
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3) @ nm.T
    length = np.linalg.norm(n, axis=1, keepdims=True)
    np.divide(n, length, out=n, where=length > 0)
    return n.astype(np.float32)


def check_finite(points, what):
    """Raise ValueError naming the first non-finite coordinate, in the library's words
    ("positions[12].y is NaN"). Checked before any transform mixes the coordinates."""
    a = np.asarray(points).reshape(-1, 3)
    bad = ~np.isfinite(a)
    if not bad.any():
        return
    i = int(np.argmax(bad.any(axis=1)))
    j = int(np.argmax(bad[i]))
    value = "NaN" if np.isnan(a[i, j]) else "infinite"
    raise ValueError(f"{what}[{i}].{'xyz'[j]} is {value}")


def orient_by_normals(triangles, normals, positions):
    """Flip the triangles whose winding disagrees with the sum of their corners' normals, so
    that Blender's face normals (backface culling, Cycles' geometric normal, its own smooth
    shading) agree with the particles' normals. Returns the triangles and how many flipped.

    The library's raw triangles are canonical (a < b < c), i.e. not oriented; its finishing
    stage orients them, after which this is a no-op."""
    if len(triangles) == 0 or normals is None:
        return triangles, 0
    p = np.asarray(positions, dtype=np.float64)
    t = triangles
    face = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    corner = normals[t[:, 0]].astype(np.float64) + normals[t[:, 1]] + normals[t[:, 2]]
    flip = np.einsum("ij,ij->i", face, corner) < 0
    count = int(flip.sum())
    if count:
        t = t.copy()
        t[flip, 1], t[flip, 2] = triangles[flip, 2], triangles[flip, 1]
    return t, count


def alive_mask(states, alive_values):
    """Boolean mask of particles whose alive_state value is one of `alive_values`."""
    return np.isin(np.asarray(states), np.asarray(list(alive_values)))


def loop_starts(triangle_count):
    return np.arange(0, 3 * triangle_count, 3, dtype=np.uint32)


def content_hash(*arrays):
    """A short digest of array contents (the cache key of the particles of one frame)."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        if a is None:
            h.update(b"-")
            continue
        a = np.ascontiguousarray(a)
        h.update(str(a.dtype).encode() + str(a.shape).encode())
        h.update(memoryview(a).cast("B"))
    return h.hexdigest()


def settings_key(settings):
    """A hashable, order-independent key of a flat settings dict."""
    return tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v)
                        for k, v in settings.items()))
