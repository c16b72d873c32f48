"""particlemesh on Dask: sequences of frames, and clouds bigger than one machine.

    from dask.distributed import Client, LocalCluster
    from particlemesh import distributed as pmd

    client = Client(LocalCluster(n_workers=2))            # or Client("tcp://scheduler:8786")
    summary = pmd.map_frames(client, "polygonize", "sim/fluid_{:04d}.xyz", "out/fluid_{:04d}.ply",
                             radius=0.02)                 # one task per frame; print(summary)
    mesh = pmd.polygonize_tiled(client, positions, tiles=(4, 4, 2), radius=0.02)
    surface = pmd.triangulate_tiled(client, positions, tiles=(2, 2, 1))

- map_frames: one task per frame; each output is the file the command-line tool writes for
  that input; a failed frame is retried once and reported, the others go on.
- polygonize_tiled: the cloud cut into tiles with halos as wide as the kernel's support, each
  meshing its own lattice cells; the merged mesh is particlemesh.polygonize's, bit for bit.
- triangulate_tiled: tiles with halos wide enough for every triangle's smallest-sphere test
  and the finishing stages, stitched on their seams into one manifold surface.
- Both tiled calls take, instead of arrays, a loader(lo, hi) that the workers call for their
  tile's particles, and the cloud's bounds: the cloud never has to sit in one process.

Dask (`distributed`) is imported when a call needs it: `import particlemesh` works without it.
See docs/distributed.md for running on a cluster (`dask scheduler` / `dask worker`)."""

from ._frames import FrameSummary, find_frames, frame_path, map_frames
from ._loaders import dask_array_loader, files_loader
from ._merge import canonical_mesh
from ._polygonize import polygonize_tiled
from ._triangulate import triangulate_tiled

__all__ = ["map_frames", "polygonize_tiled", "triangulate_tiled", "FrameSummary", "find_frames",
           "frame_path", "canonical_mesh", "files_loader", "dask_array_loader"]
