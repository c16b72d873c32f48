"""Ready-made loaders for the tiled calls: particles from files, or from a dask array, read
piece by piece on the worker that needs them, so the cloud never sits in one process."""

import numpy as np

from .. import read_points

from ._tiles import in_box, invalid


class files_loader:
    """A loader over particle files (.ply, .xyz, .pcd: anything particlemesh.read_points
    reads) that together hold the cloud, listed in the cloud's order: a tile reads them one
    by one and keeps its box's particles (normals and attributes come along). A tile reads
    every file whose bounds (`bounds`: one (lo, hi) per file, when known, e.g. from the
    simulation's domain decomposition) meet its box; without `bounds`, every file."""

    def __init__(self, paths, bounds=None):
        self.paths = [str(p) for p in paths]
        if not self.paths:
            raise invalid("files_loader needs at least one file")
        self.bounds = None
        if bounds is not None:
            self.bounds = [(np.asarray(lo, float), np.asarray(hi, float)) for lo, hi in bounds]
            if len(self.bounds) != len(self.paths):
                raise invalid(f"files_loader: {len(self.bounds)} bounds for {len(self.paths)} files")

    def __call__(self, lo, hi):
        parts = []
        for i, path in enumerate(self.paths):
            if self.bounds is not None:
                flo, fhi = self.bounds[i]
                if (flo > hi).any() or (fhi < lo).any():
                    continue
            points = read_points(path)
            index = in_box(points.positions, lo, hi)
            parts.append((points, index))
        if not parts:
            return np.zeros((0, 3))
        out = {"positions": np.concatenate([p.positions[i] for p, i in parts])}
        if all(p.normals is not None for p, _ in parts):
            out["normals"] = np.concatenate([p.normals[i] for p, i in parts])
        names = set.intersection(*(set(p.attributes) for p, _ in parts))
        out["attributes"] = {n: np.concatenate([p.attributes[n][i] for p, i in parts]) for n in names}
        return out


class dask_array_loader:
    """A loader over a dask array of positions, shape (N, 3), chunked along N (e.g.
    dask.array.from_zarr, from_npy_stack): a tile computes one chunk at a time on its worker
    (the synchronous scheduler) and keeps its box's particles, in the array's order. Optional
    dask arrays of the same length and chunks: radii, strengths (polygonize), normals."""

    def __init__(self, positions, *, radii=None, strengths=None, normals=None):
        self.arrays = {"positions": positions, "radii": radii, "strengths": strengths,
                       "normals": normals}
        shape = getattr(positions, "shape", None)
        if shape is None or len(shape) != 2 or shape[1] != 3 or not hasattr(positions, "blocks"):
            raise invalid("dask_array_loader needs a dask array of shape (N, 3)")
        if len(positions.chunks[1]) != 1:
            raise invalid("dask_array_loader: chunk the positions along N only (chunks=(n, 3))")
        for name, a in self.arrays.items():
            if a is not None and a.shape[0] != shape[0]:
                raise invalid(f"dask_array_loader: {name} has {a.shape[0]} rows for {shape[0]}")

    def __call__(self, lo, hi):
        given = {k: a for k, a in self.arrays.items() if a is not None}
        rows = given["positions"].chunks[0]
        parts = {k: [] for k in given}
        start = 0
        for count in rows:
            p = np.asarray(given["positions"][start:start + count].compute(scheduler="sync"))
            index = in_box(p, lo, hi)
            if len(index):
                parts["positions"].append(p[index])
                for k, a in given.items():
                    if k != "positions":
                        parts[k].append(np.asarray(a[start:start + count].compute(scheduler="sync"))[index])
            start += count
        if not parts["positions"]:
            return np.zeros((0, 3))
        return {k: np.concatenate(v) for k, v in parts.items()}
