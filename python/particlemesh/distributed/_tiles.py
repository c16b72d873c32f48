"""One cloud in tiles: the boxes, which tile owns a particle, and where a tile's particles
come from (arrays on the driver, sliced and sent; or a loader the workers call)."""

import numbers

import numpy as np

from .._data import Points
from .._errors import Error
from .. import _abi


def invalid(message):
    return Error(message, _abi.PM_STATUS_INVALID_ARGUMENT)


def tile_shape(tiles):
    """(nx, ny, nz) from tiles=(nx, ny, nz) (or one int: that many along x)."""
    if isinstance(tiles, numbers.Integral):
        tiles = (int(tiles), 1, 1)
    try:
        shape = tuple(int(t) for t in tiles)
    except (TypeError, ValueError):
        raise invalid(f"tiles must be (nx, ny, nz) positive integers, got {tiles!r}") from None
    if len(shape) != 3 or min(shape) < 1:
        raise invalid(f"tiles must be (nx, ny, nz) positive integers, got {tiles!r}")
    return shape


def tile_indices(shape):
    """Every tile's (i, j, k), x slowest: the order tiles are submitted and merged in."""
    return [(i, j, k) for i in range(shape[0]) for j in range(shape[1]) for k in range(shape[2])]


def bounds_of(bounds):
    """(lo, hi) float64 (3,) arrays from bounds=((x0, y0, z0), (x1, y1, z1))."""
    try:
        lo, hi = (np.asarray(b, dtype=np.float64).reshape(3) for b in bounds)
    except (TypeError, ValueError):
        raise invalid("bounds must be ((x0, y0, z0), (x1, y1, z1))") from None
    if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (lo <= hi).all()):
        raise invalid(f"bounds must be finite with lo <= hi, got {lo.tolist()}, {hi.tolist()}")
    return lo, hi


class Cuts:
    """The planes between tiles: tile (i, j, k) owns the points with cut[a][i] <= x_a <
    cut[a][i + 1] (the outermost tiles reach to infinity), so every point has one owner,
    decided by its coordinates alone (the same on every worker)."""

    def __init__(self, lo, hi, shape):
        self.shape = shape
        self.inner = [np.linspace(lo[a], hi[a], shape[a] + 1)[1:-1] for a in range(3)]

    def box(self, index):
        """The tile's own box (lo, hi), infinite outward."""
        lo = np.empty(3)
        hi = np.empty(3)
        for a in range(3):
            c = self.inner[a]
            lo[a] = c[index[a] - 1] if index[a] > 0 else -np.inf
            hi[a] = c[index[a]] if index[a] < len(c) else np.inf
        return lo, hi

    def unflat(self, flat):
        """(i, j, k) of a flat tile number."""
        k = flat % self.shape[2]
        j = (flat // self.shape[2]) % self.shape[1]
        return (flat // (self.shape[2] * self.shape[1]), j, k)

    def owner(self, positions):
        """Flat tile number (x slowest) of each point."""
        p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        flat = np.zeros(len(p), dtype=np.int64)
        for a in range(3):
            flat = flat * self.shape[a] + np.searchsorted(self.inner[a], p[:, a], side="right")
        return flat


def in_box(positions, lo, hi):
    """Indices (ascending) of the points in the closed box [lo, hi]."""
    p = np.asarray(positions)
    return np.flatnonzero(((p >= lo) & (p <= hi)).all(axis=1))


PER_POINT = ("normals", "radii", "strengths", "ids")


def normalize(loaded, where="the loader"):
    """A loader's answer as a dict: positions (N, 3) float64 and, when given, normals,
    attributes {name: (N, C)}, radii, strengths, ids (int64 global ids). Accepts an (N, 3)
    array, Points, or a dict with those keys."""
    if isinstance(loaded, Points):
        out = {"positions": loaded.positions, "normals": loaded.normals,
               "attributes": dict(loaded.attributes)}
    elif isinstance(loaded, dict):
        unknown = set(loaded) - {"positions", "attributes", *PER_POINT}
        if unknown:
            raise invalid(f"{where} returned unknown keys {sorted(unknown)}; it may return "
                          "positions, normals, attributes, radii, strengths, ids")
        if "positions" not in loaded:
            raise invalid(f"{where} returned a dict without 'positions'")
        out = dict(loaded)
    else:
        out = {"positions": loaded}
    p = np.asarray(out["positions"], dtype=np.float64)
    if p.ndim == 1 and p.size % 3 == 0:
        p = p.reshape(-1, 3)
    if p.ndim != 2 or p.shape[1] != 3:
        raise invalid(f"{where} returned positions of shape {p.shape}; (N, 3) is needed")
    out["positions"] = p
    n = len(p)
    for key in PER_POINT:
        v = out.get(key)
        if v is None:
            out[key] = None
            continue
        v = np.asarray(v)
        if len(v) != n:
            raise invalid(f"{where} returned {len(v)} {key} for {n} positions")
        out[key] = v
    attrs = out.get("attributes") or {}
    for name, values in attrs.items():
        if len(values) != n:
            raise invalid(f"{where} returned attribute {name!r} with {len(values)} rows for "
                          f"{n} positions")
    out["attributes"] = attrs
    return out


def select(particles, index):
    """The particles at `index` (a dict as normalize() returns)."""
    out = {"positions": particles["positions"][index]}
    for key in PER_POINT:
        v = particles.get(key)
        out[key] = None if v is None else np.asarray(v)[index]
    out["attributes"] = {k: np.asarray(v)[index] for k, v in particles["attributes"].items()}
    return out


class Source:
    """Where tiles' particles come from. Arrays on the driver: each tile is sent the particles
    in its box (with their indices in the cloud as ids). A loader: each worker calls
    loader(lo, hi) for its box and keeps what lies in it; the cloud is never in one process."""

    def __init__(self, particles, *, normals=None, attributes=None, radii=None, strengths=None,
                 bounds=None):
        self.loader = particles if callable(particles) else None
        if self.loader is not None:
            if bounds is None:
                raise invalid("with a loader, give bounds=((x0, y0, z0), (x1, y1, z1)): the "
                              "domain's lower and upper corners (every particle inside)")
            for name, v in (("normals", normals), ("attributes", attributes), ("radii", radii),
                            ("strengths", strengths)):
                if v is not None:
                    raise invalid(f"with a loader, {name} come from the loader (return a dict "
                                  f"with '{name}'), not from the call")
            self.lo, self.hi = bounds_of(bounds)
            self.particles = None
            return
        if isinstance(particles, Points):
            normals = particles.normals if normals is None else normals
            attributes = particles.attributes if attributes is None else attributes
            particles = particles.positions
        data = {"positions": particles, "normals": normals, "attributes": attributes or {},
                "radii": radii, "strengths": strengths, "ids": None}
        self.particles = normalize(data, "the particles")
        p = self.particles["positions"]
        if len(p) == 0:
            raise Error("there are no particles", _abi.PM_STATUS_INVALID_INPUT)
        bad = ~np.isfinite(p)
        if bad.any():
            i, a = np.argwhere(bad)[0]
            raise Error(f"positions[{i}].{'xyz'[a]} is {p[i, a]}", _abi.PM_STATUS_INVALID_INPUT)
        if bounds is not None:
            raise invalid("bounds= is for a loader; with arrays the bounds are the particles'")
        self.lo, self.hi = p.min(axis=0), p.max(axis=0)

    @property
    def count(self):
        return None if self.particles is None else len(self.particles["positions"])

    def payload(self, lo, hi):
        """What a tile's task gets: its particles (arrays), or the loader and its box."""
        if self.loader is not None:
            return {"loader": self.loader, "lo": lo, "hi": hi}
        index = in_box(self.particles["positions"], lo, hi)
        part = select(self.particles, index)
        part["ids"] = index
        return {"particles": part, "lo": lo, "hi": hi}


def load(payload):
    """On a worker: the tile's particles (a dict as normalize() returns, in the cloud's order),
    with the particles outside the tile's box dropped."""
    if "particles" in payload:
        return payload["particles"]
    lo, hi = payload["lo"], payload["hi"]
    loaded = normalize(payload["loader"](lo.copy(), hi.copy()))
    index = in_box(loaded["positions"], lo, hi)
    if len(index) < len(loaded["positions"]):
        loaded = select(loaded, index)
    return loaded


def nbytes(obj):
    """Bytes of the numpy arrays in a (nested) payload or result: the data it moves."""
    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if isinstance(obj, dict):
        return sum(nbytes(v) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(nbytes(v) for v in obj)
    return 0
