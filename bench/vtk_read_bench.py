"""Reading VTK particle files: particlemesh.read_points beside VTK's own readers
(vtkXMLUnstructuredGridReader, vtkUnstructuredGridReader; Debian's python3-vtk9) on the same
files, written by VTK's writers: XML with each of its compressors (raw appended data, 32 KiB
blocks, VTK's default levels), and the legacy format in BINARY (big-endian) and ASCII.

    PM_PYTHON_PATH=build/python /usr/bin/python3 bench/vtk_read_bench.py [--points 1000000] [--reps 5]

Prints per compressor the file size and the median wall time of each reader; both give the
same positions (checked)."""
import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

sys.path.insert(0, os.environ.get("PM_PYTHON_PATH", str(Path(__file__).resolve().parents[1] / "build" / "python")))
import particlemesh as pm  # noqa: E402


def grid(n):
    rng = np.random.default_rng(3)
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(rng.random((n, 3)).astype(np.float32), deep=True))
    g = vtk.vtkUnstructuredGrid()
    g.SetPoints(pts)
    for name, values in (("velocity", rng.normal(size=(n, 3)).astype(np.float32)),
                         ("density", rng.uniform(900, 1100, n).astype(np.float32))):
        a = numpy_to_vtk(values, deep=True)
        a.SetName(name)
        g.GetPointData().AddArray(a)
    return g


def median_time(f, reps):
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def compare(label, path, reader_class, reps, exact=True):
    """One table row: `path` read by particlemesh and by VTK's `reader_class`, same positions."""

    def ours():
        return pm.read_points(path).positions

    def theirs():
        r = reader_class()
        r.SetFileName(path)
        if hasattr(r, "ReadAllScalarsOn"):  # the legacy reader: every array, as ours
            r.ReadAllScalarsOn()
            r.ReadAllVectorsOn()
        r.Update()
        return vtk_to_numpy(r.GetOutput().GetPoints().GetData())

    t_pm, p_pm = median_time(ours, reps)
    t_vtk, p_vtk = median_time(theirs, reps)
    if exact:
        assert np.array_equal(p_pm, p_vtk.astype(np.float64)), label
    else:  # text: ours keeps the printed values in double, VTK rounds them to float32
        assert np.allclose(p_pm, p_vtk, rtol=1e-6, atol=1e-6), label
    print(f"| {label} | {os.path.getsize(path) / 1e6:.1f} MB | {t_pm:.3f} s | {t_vtk:.3f} s |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()
    g = grid(args.points)
    print(f"{args.points} particles (positions, velocity, density; Float32), median of {args.reps}")
    print("| file kind | file | particlemesh.read_points | VTK's reader |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for compressor in ("None", "ZLib", "LZ4", "LZMA"):
            path = os.path.join(tmp, f"p_{compressor}.vtu")
            w = vtk.vtkXMLUnstructuredGridWriter()
            w.SetInputData(g)
            w.SetFileName(path)
            w.SetDataModeToAppended()
            w.EncodeAppendedDataOff()
            getattr(w, "SetCompressorTypeTo" + compressor)()
            w.Write()
            compare(f"XML, {compressor}", path, vtk.vtkXMLUnstructuredGridReader, args.reps)
        for mode in ("Binary", "ASCII"):
            path = os.path.join(tmp, f"p_{mode}.vtk")
            w = vtk.vtkUnstructuredGridWriter()
            w.SetInputData(g)
            w.SetFileName(path)
            getattr(w, "SetFileTypeTo" + mode)()
            w.Write()
            compare(f"legacy {mode}", path, vtk.vtkUnstructuredGridReader, args.reps, exact=mode == "Binary")

if __name__ == "__main__":
    main()
