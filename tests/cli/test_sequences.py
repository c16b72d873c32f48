"""Simulators' files, particle attributes and frame sequences through the CLI."""

import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from particle_files import (FORMATS, particles, read_ascii_ply, scf, write_bgeo, write_bgeo_json,  # noqa: E402
                            write_geo_classic, write_las, write_ply, write_vtk)

POLY = ["--radius", "0.14", "--cell", "0.03"]  # fixed R and h: frames share a lattice


def frames(folder, numbers, fmt=".vtk"):
    folder.mkdir(parents=True, exist_ok=True)
    for f in numbers:
        p, a = particles(f)
        FORMATS[fmt](folder / f"f_{f}{fmt}", p, a)


def test_same_particles_same_mesh_whatever_the_file(cli, tmp_path):
    p, a = particles(0)
    meshes = {}
    for fmt, write in FORMATS.items():
        src = tmp_path / f"in{fmt}"
        write(src, p, a)
        out = tmp_path / f"out{fmt}.ply"
        cli("polygonize", src, "-o", out, *POLY, "-q")
        meshes[fmt] = out.read_bytes()
        tri = tmp_path / f"tri{fmt}.ply"
        cli("triangulate", src, "-o", tri, "--raw", "-q")
        meshes["tri" + fmt] = tri.read_bytes()
        # The vector channel by its name from every format (PLY: velocity_0, _1, _2 are it).
        vtu = tmp_path / f"out{fmt}.vtu"
        cli("polygonize", src, "-o", vtu, *POLY, "--attributes", "velocity,density", "-q")
        meshes["vtu" + fmt] = vtu.read_bytes()
    for fmt in FORMATS:
        assert meshes[fmt] == meshes[".ply"], f"{fmt} gives another polygonize mesh than .ply"
        assert meshes["tri" + fmt] == meshes["tri.ply"], f"{fmt} gives another triangulate mesh than .ply"
        assert meshes["vtu" + fmt] == meshes["vtu.ply"], f"{fmt} gives another .vtu than .ply"
    assert b'Name="velocity" NumberOfComponents="3"' in meshes["vtu.ply"]
    assert b"property float velocity_2" in meshes[".ply"] and b"property float density" in meshes[".ply"]


def test_attributes_reach_the_mesh(cli, tmp_path):
    p, a = particles(0)
    src = tmp_path / "in.vtk"
    # A constant velocity: normalised kernel weights give exactly it on every vertex.
    a["velocity"][:] = np.array([0.5, -0.25, 2.0], np.float32)
    write_vtk(src, p, a)
    cli("polygonize", src, "-o", tmp_path / "m.ply", "--ascii", *POLY, "-q")
    pos, cols, faces = read_ascii_ply(tmp_path / "m.ply")
    assert len(faces) > 100
    vel = np.column_stack([cols[f"velocity_{c}"] for c in range(3)])
    np.testing.assert_allclose(vel, np.tile([0.5, -0.25, 2.0], (len(pos), 1)), atol=1e-5)
    # density varies: interpolated values lie within the particles' range (a convex combination).
    assert cols["density"].min() >= a["density"].min() - 1e-3 and cols["density"].max() <= a["density"].max() + 1e-3
    assert np.ptp(cols["density"]) > 0.1

    # triangulate: vertex i is particle i, with its own values.
    _, a = particles(0)
    write_vtk(src, p, a)
    cli("triangulate", src, "-o", tmp_path / "t.ply", "--ascii", "-q")
    pos, cols, faces = read_ascii_ply(tmp_path / "t.ply")
    assert len(pos) == len(p) and len(faces) > 0
    np.testing.assert_allclose(pos, p, atol=1e-6)
    np.testing.assert_array_equal(cols["density"].astype(np.float32), a["density"])
    np.testing.assert_array_equal(cols["velocity_1"].astype(np.float32), a["velocity"][:, 1])

    # --attributes picks; a name the particles lack is a clear error.
    cli("polygonize", src, "-o", tmp_path / "d.ply", "--ascii", *POLY, "-q", "--attributes", "density")
    _, cols, _ = read_ascii_ply(tmp_path / "d.ply")
    assert "density" in cols and "velocity_0" not in cols
    cli("polygonize", src, "-o", tmp_path / "n.ply", "--ascii", *POLY, "-q", "--attributes", "none")
    _, cols, _ = read_ascii_ply(tmp_path / "n.ply")
    assert set(cols) == {"x", "y", "z", "nx", "ny", "nz"}
    r = cli("polygonize", src, "-o", tmp_path / "x.ply", *POLY, "--attributes", "speed", check=False)
    assert r.returncode == 1 and "no 'speed'" in r.stderr and "velocity, density" in r.stderr
    assert not (tmp_path / "x.ply").exists()

    # VTK output: point-data arrays of the channels' names.
    cli("polygonize", src, "-o", tmp_path / "m.vtu", *POLY, "-q")
    text = (tmp_path / "m.vtu").read_bytes()
    assert b'Name="velocity"' in text and b'NumberOfComponents="3"' in text and b'Name="density"' in text


def test_radius_from_a_channel(cli, tmp_path):
    """--radius-channel pscale: R_i = F x pscale_i (Houdini's per-particle size). A constant
    pscale gives exactly the mesh of the same --radius; a larger pscale on one side reaches
    further out there; bad channels and values are named, and nothing is written."""
    p, a = particles(0)
    n = len(p)
    pscale = np.full(n, 1 / 32, np.float32)
    src = tmp_path / "in.bgeo"
    write_bgeo(src, p, {"pscale": pscale, "density": a["density"]})
    cli("polygonize", src, "-o", tmp_path / "ch.ply", "--radius-channel", "pscale", "--cell", "0.03", "-q")
    cli("polygonize", src, "-o", tmp_path / "r.ply", "--radius", "0.125", "--cell", "0.03", "-q")
    assert (tmp_path / "ch.ply").read_bytes() == (tmp_path / "r.ply").read_bytes()
    # Another factor: R = 4.48 x pscale, and the threshold of touching particles of their size at
    # that R (above the default's: the field inside a packing grows with R / spacing).
    cli("polygonize", src, "-o", tmp_path / "f.ply", "--radius-channel", "pscale", "--radius-scale", "4.48",
        "--cell", "0.03", "-q", "--report", tmp_path / "f.json")
    report = json.loads((tmp_path / "f.json").read_text())["polygonize"]
    assert report["radius"] == pytest.approx(0.14) and report["threshold"] > 3.34
    cli("polygonize", src, "-o", tmp_path / "r2.ply", "--radius", "0.14", "--threshold", repr(report["threshold"]),
        "--cell", "0.03", "-q")
    assert (tmp_path / "f.ply").read_bytes() == (tmp_path / "r2.ply").read_bytes()

    # Doubled pscale where x is above the middle: the surface reaches further out on that side only.
    big = pscale.copy()
    big[p[:, 0] > p[:, 0].mean()] *= 2
    write_bgeo(src, p, {"pscale": big, "density": a["density"]})
    cli("polygonize", src, "-o", tmp_path / "v.ply", "--ascii", "--radius-channel", "pscale", "--cell", "0.03", "-q")
    pos_v, _, faces = read_ascii_ply(tmp_path / "v.ply")
    cli("polygonize", src, "-o", tmp_path / "c.ply", "--ascii", "--radius", "0.125", "--cell", "0.03", "-q")
    pos_c, _, _ = read_ascii_ply(tmp_path / "c.ply")
    assert len(faces) > 100
    assert pos_v[:, 0].max() > pos_c[:, 0].max() + 0.05  # the big side grew
    assert abs(pos_v[:, 0].min() - pos_c[:, 0].min()) < 0.02  # the small side barely moved

    for args, code, message in [
            (["--radius-channel", "size"], 1, "--radius-channel size: "),
            (["--radius-channel", "pscale", "--radius", "1"], 2, "--radius excludes --radius-channel"),
    ]:
        r = cli("polygonize", src, "-o", tmp_path / "x.ply", *args, check=False)
        assert r.returncode == code and message in r.stderr, r.stderr
        assert not (tmp_path / "x.ply").exists()
    r = cli("polygonize", src, "-o", tmp_path / "x.ply", "--radius-channel", "size", check=False)
    assert "has no such channel (it has pscale, density)" in r.stderr
    big[5] = 0
    write_bgeo(src, p, {"pscale": big, "density": a["density"]})
    r = cli("polygonize", src, "-o", tmp_path / "x.ply", "--radius-channel", "pscale", check=False)
    assert r.returncode == 1 and "particle 5's pscale is 0 (a radius must be positive)" in r.stderr
    assert not (tmp_path / "x.ply").exists()


def test_render_takes_the_radius_from_a_channel_as_polygonize_does(cli, tmp_path):
    """render --radius-channel: the image of the field polygonize meshes from the same options
    (a constant pscale gives the image of the same --radius; the threshold for sizes); bad
    channels refused as polygonize refuses them."""
    p, a = particles(0)
    src = tmp_path / "in.bgeo"
    write_bgeo(src, p, {"pscale": np.full(len(p), 1 / 32, np.float32), "density": a["density"]})
    cli("render", src, "-o", tmp_path / "ch.png", "--radius-channel", "pscale", "--width", "96", "--height", "64", "-q")
    cli("render", src, "-o", tmp_path / "r.png", "--radius", "0.125", "--width", "96", "--height", "64", "-q")
    assert (tmp_path / "ch.png").read_bytes() == (tmp_path / "r.png").read_bytes()
    r = cli("render", src, "-o", tmp_path / "ch.png", "--radius-channel", "pscale", "--radius-scale", "6",
            "--width", "96", "--height", "64")
    assert "per particle: 6 x 'pscale'" in r.stdout and "touching particles at R = 6 x size" in r.stdout
    r = cli("render", src, "-o", tmp_path / "x.png", "--radius-channel", "size", check=False)
    assert r.returncode == 1 and "has no such channel (it has pscale, density)" in r.stderr
    assert not (tmp_path / "x.png").exists()
    r = cli("render", src, "-o", tmp_path / "x.png", "--radius-channel", "pscale", "--radius", "1", check=False)
    assert r.returncode == 2 and "--radius excludes --radius-channel" in r.stderr


def test_las_lidar_files(cli, tmp_path):
    """ASPRS LAS 1.2 (formats 0-3) and 1.4 (formats 6-8, a VLR, extra bytes per record): the
    positions exactly (the PLY's mesh byte for byte), intensity, classification and colours
    (16-bit, or 8-bit values) as channels; LAZ and broken files refused by name."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(3000, 3))
    p = np.round(v / np.linalg.norm(v, axis=1)[:, None] * 1024) / 1024 + [100.0, -50.0, 7.0]
    intensity = rng.integers(0, 65536, len(p))
    rgb16 = rng.integers(0, 65536, (len(p), 3))
    rgb8 = rng.integers(0, 256, (len(p), 3))
    write_ply(tmp_path / "ref.ply", p.astype(np.float32), {})
    cli("triangulate", tmp_path / "ref.ply", "-o", tmp_path / "ref_out.ply", "--attributes", "none", "-q")
    reference = (tmp_path / "ref_out.ply").read_bytes()
    cases = [dict(point_format=0), dict(point_format=1), dict(point_format=2, rgb=rgb16), dict(point_format=3, rgb=rgb8),
             dict(point_format=6, minor=4), dict(point_format=7, minor=4, rgb=rgb16, vlr=b"x" * 54, extra_bytes=6),
             dict(point_format=8, minor=4, rgb=rgb8)]
    for k, case in enumerate(cases):
        src = tmp_path / f"scan{k}.las"
        write_las(src, p, intensity, **case)
        cli("triangulate", src, "-o", tmp_path / "out.ply", "--attributes", "none", "-q")
        assert (tmp_path / "out.ply").read_bytes() == reference, case
        cli("triangulate", src, "-o", tmp_path / "attr.ply", "--ascii", "-q")
        _, cols, _ = read_ascii_ply(tmp_path / "attr.ply")
        np.testing.assert_array_equal(cols["intensity"], intensity)
        assert (cols["classification"] == 2).all()
        if "rgb" in case:
            expected = case["rgb"] if case["rgb"] is rgb8 else np.round(case["rgb"] / 65535 * 255)
            np.testing.assert_allclose(np.column_stack([cols["red"], cols["green"], cols["blue"]]), expected, atol=1)
        else:
            assert "red" not in cols

    write_las(tmp_path / "c.laz", p, intensity, point_format=2, rgb=rgb16, laz=True)
    for name, message in [("c.laz", "this is LAZ (compressed LAS), which is not read: decompress it first")]:
        r = cli("triangulate", tmp_path / name, "-o", tmp_path / "x.ply", check=False)
        assert r.returncode == 1 and message in r.stderr, r.stderr
    data = (tmp_path / "scan2.las").read_bytes()
    (tmp_path / "cut.las").write_bytes(data[:-10])
    (tmp_path / "sig.las").write_bytes(b"LASX" + data[4:])
    for name, message in [("cut.las", "truncated: 3000 points of 26 bytes, but the file holds"),
                          ("sig.las", "not a LAS file")]:
        r = cli("triangulate", tmp_path / name, "-o", tmp_path / "x.ply", check=False)
        assert r.returncode == 1 and name in r.stderr and message in r.stderr, r.stderr
        assert not (tmp_path / "x.ply").exists()


def test_sequence_meshes_each_frame_as_its_file_alone(cli, tmp_path):
    frames(tmp_path / "in", [1, 2, 3, 10])
    out = tmp_path / "out"
    out.mkdir()
    r = cli("polygonize", tmp_path / "in/f_{}.vtk", "-o", out / "m_{:04d}.ply", *POLY, "--jobs", "1")
    # numeric order (10 after 3), one line per frame, the gap reported, a summary
    order = [int(line.split(":")[0].split()[1]) for line in r.stderr.splitlines() if line.startswith("frame ")]
    assert order == [1, 2, 3, 10]
    assert "6 missing frames skipped (no file): 4, 5, 6, 7, 8, 9" in r.stderr
    assert "meshed        4" in r.stdout and "failed        0" in r.stdout
    for f in [1, 2, 3, 10]:
        single = tmp_path / f"single_{f}.ply"
        cli("polygonize", tmp_path / f"in/f_{f}.vtk", "-o", single, *POLY, "-q")
        assert (out / f"m_{f:04d}.ply").read_bytes() == single.read_bytes(), f"frame {f}"
    # --jobs 2: the same bytes
    out2 = tmp_path / "out2"
    out2.mkdir()
    cli("polygonize", tmp_path / "in/f_{}.vtk", "-o", out2 / "m_{:04d}.ply", *POLY, "--jobs", "2", "-q")
    for f in [1, 2, 3, 10]:
        assert (out2 / f"m_{f:04d}.ply").read_bytes() == (out / f"m_{f:04d}.ply").read_bytes()
    # triangulate sequences too
    cli("triangulate", tmp_path / "in/f_{}.vtk", "-o", out / "t_{}.obj", "-q")
    assert sorted(x.name for x in out.glob("t_*.obj")) == ["t_1.obj", "t_10.obj", "t_2.obj", "t_3.obj"]


def test_rerun_leaves_up_to_date_frames_alone(cli, tmp_path):
    frames(tmp_path / "in", [0, 1, 2])
    pat_in, pat_out = tmp_path / "in/f_{}.vtk", tmp_path / "m_{}.ply"
    cli("polygonize", pat_in, "-o", pat_out, *POLY)
    stamp = {f: os.stat(tmp_path / f"m_{f}.ply").st_mtime_ns for f in range(3)}
    r = cli("polygonize", pat_in, "-o", pat_out, *POLY)
    assert "meshed        0" in r.stdout and "up to date    3" in r.stdout
    assert all(os.stat(tmp_path / f"m_{f}.ply").st_mtime_ns == stamp[f] for f in range(3))
    # an input newer than its output: that frame only
    t = os.stat(tmp_path / "in/f_1.vtk").st_mtime - 10
    os.utime(tmp_path / "m_1.ply", (t, t))
    r = cli("polygonize", pat_in, "-o", pat_out, *POLY)
    assert "meshed        1" in r.stdout and "up to date    2" in r.stdout
    assert os.stat(tmp_path / "m_1.ply").st_mtime_ns > stamp[1]
    # other options: every frame
    r = cli("polygonize", pat_in, "-o", pat_out, "--radius", "0.15", "--cell", "0.03")
    assert "meshed        3" in r.stdout
    # --threads does not change the output: still up to date; --force redoes them
    r = cli("polygonize", pat_in, "-o", pat_out, "--radius", "0.15", "--cell", "0.03", "--threads", "1")
    assert "meshed        0" in r.stdout
    r = cli("polygonize", pat_in, "-o", pat_out, "--radius", "0.15", "--cell", "0.03", "--force")
    assert "meshed        3" in r.stdout
    # a removed output: that frame again
    (tmp_path / "m_2.ply").unlink()
    r = cli("polygonize", pat_in, "-o", pat_out, "--radius", "0.15", "--cell", "0.03", "--dry-run")
    assert "m_2.ply (to mesh)" in r.stdout and "m_0.ply (up to date" in r.stdout


def test_frame_range_and_bad_frames(cli, tmp_path):
    frames(tmp_path / "in", [1, 2, 3, 4, 6])
    pat_in = tmp_path / "in/f_{}.vtk"
    r = cli("polygonize", pat_in, "-o", tmp_path / "r_{}.ply", *POLY, "--frames", "2:5")
    assert sorted(x.name for x in tmp_path.glob("r_*.ply")) == ["r_2.ply", "r_3.ply", "r_4.ply"]
    assert "1 missing frame skipped (no file): 5" in r.stderr
    # a truncated frame and a frame with other attributes fail, named; the others go on
    data = (tmp_path / "in/f_3.vtk").read_bytes()
    (tmp_path / "in/f_3.vtk").write_bytes(data[: len(data) // 2])
    p, a = particles(4)
    del a["density"]
    write_vtk(tmp_path / "in/f_4.vtk", p, a)
    r = cli("polygonize", pat_in, "-o", tmp_path / "b_{}.ply", *POLY, check=False)
    assert r.returncode == 1
    assert "frame 3 (" in r.stderr and "f_3.vtk" in r.stderr
    assert "frame 4 (" in r.stderr and "every frame of a sequence must carry the same" in r.stderr
    assert "failed        2" in r.stdout
    assert sorted(x.name for x in tmp_path.glob("b_*.ply")) == ["b_1.ply", "b_2.ply", "b_6.ply"]
    # the failed frames are not up to date: they run again (and fail again)
    r = cli("polygonize", pat_in, "-o", tmp_path / "b_{}.ply", *POLY, check=False)
    assert r.returncode == 1 and "up to date    3" in r.stdout and "failed        2" in r.stdout


def test_sequence_usage_errors(cli, tmp_path):
    frames(tmp_path / "in", [1])
    pat_in = tmp_path / "in/f_{}.vtk"
    cases = [
        ([pat_in, "-o", tmp_path / "m.ply"], "has no frame field"),
        ([tmp_path / "in/f_1.vtk", "-o", tmp_path / "m_{}.ply"], "the input is not a sequence"),
        ([tmp_path / "in/f_1.vtk", "-o", tmp_path / "m.ply", "--frames", "1:2"], "--frames is for a sequence"),
        ([pat_in, "-o", tmp_path / "m_{}.ply", "--frames", "5:2"], "the first frame is after the last"),
        ([pat_in, "-o", tmp_path / "m_{}.ply", "--frames", "a:b"], "expected FIRST:LAST"),
        ([tmp_path / "in/f_{x}.vtk", "-o", tmp_path / "m_{}.ply"], "unsupported field"),
        ([tmp_path / "in/f_{}_{}.vtk", "-o", tmp_path / "m_{}.ply"], "more than one frame field"),
        ([pat_in, "-o", tmp_path / "m_{}.stl"], "-o"),
        ([pat_in, "-o", tmp_path / "nofolder/m_{}.ply"], "-o"),
    ]
    for args, message in cases:
        r = cli("polygonize", *args, check=False)
        assert r.returncode == 2 and message in r.stderr, (args, r.stderr)
    r = cli("polygonize", tmp_path / "none_{}.vtk", "-o", tmp_path / "m_{}.ply", check=False)
    assert r.returncode == 1 and "no file matches" in r.stderr
    # zero-padded patterns: f_07 is not frame 7 of f_{}
    (tmp_path / "in/f_07.vtk").write_bytes((tmp_path / "in/f_1.vtk").read_bytes())
    r = cli("polygonize", pat_in, "-o", tmp_path / "m_{}.ply", *POLY, "--dry-run")
    assert r.stdout.count("frame ") == 1


def pvd(path, entries):
    """A ParaView collection: (timestep, file) per DataSet, in the order given."""
    rows = "".join(f'    <DataSet timestep="{t}" group="" part="0" file="{f}"/>\n' for t, f in entries)
    path.write_text(f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                    f'  <Collection>\n{rows}  </Collection>\n</VTKFile>\n')


def test_a_paraview_collection_is_a_sequence(cli, tmp_path):
    # A .pvd and a .series list frame files with their times, in any order: frame n is the n-th by
    # time, meshed as its file alone; a listed file that does not exist is a missing frame, named.
    frames(tmp_path / "sim/data", [5, 6, 7])
    listed = [(0.25, "data/f_7.vtk"), (0.0, "data/f_5.vtk"), (0.125, "data\\f_6.vtk"), (0.5, "data/f_9.vtk")]
    pvd(tmp_path / "sim/run.pvd", listed)
    (tmp_path / "sim/run.vtk.series").write_text(json.dumps(
        {"file-series-version": "1.0", "files": [{"name": f, "time": t} for t, f in listed]}))
    by_time = [5, 6, 7]
    for collection, out in (("run.pvd", "a"), ("run.vtk.series", "b")):
        (tmp_path / out).mkdir()
        r = cli("polygonize", tmp_path / "sim" / collection, "-o", tmp_path / out / "m_{:02d}.ply", *POLY)
        assert "meshed        3" in r.stdout and "missing       1: 3" in r.stdout, r.stdout
        assert "frame 3: '" in r.stderr and "f_9.vtk' is not a file" in r.stderr, r.stderr
        for n, f in enumerate(by_time):
            single = tmp_path / f"single_{f}.ply"
            if not single.exists():
                cli("polygonize", tmp_path / f"sim/data/f_{f}.vtk", "-o", single, *POLY, "-q")
            assert (tmp_path / out / f"m_{n:02d}.ply").read_bytes() == single.read_bytes(), (collection, n)
        # up to date on a re-run; --frames picks by position
        r = cli("polygonize", tmp_path / "sim" / collection, "-o", tmp_path / out / "m_{:02d}.ply", *POLY)
        assert "meshed        0" in r.stdout and "up to date    3" in r.stdout
        r = cli("triangulate", tmp_path / "sim" / collection, "-o", tmp_path / out / "t_{}.ply", "--frames", "1:1",
                "-q")
        assert sorted(x.name for x in (tmp_path / out).glob("t_*.ply")) == ["t_1.ply"]

    # inspect lists the frames as the sequence numbers them, and the missing one.
    r = cli("inspect", tmp_path / "sim/run.pvd")
    assert "a collection of 4 frames, times 0 to 0.5, 1 missing" in r.stdout, r.stdout
    assert "frame 1     t = 0.125" in r.stdout and "f_9.vtk  (missing: not a file)" in r.stdout
    j = json.loads(cli("inspect", tmp_path / "sim/run.vtk.series", "--json").stdout)
    assert [(f["frame"], Path(f["path"]).name, f["exists"]) for f in j["frames"]] == [
        (0, "f_5.vtk", True), (1, "f_6.vtk", True), (2, "f_7.vtk", True), (3, "f_9.vtk", False)]

    def refused(name, text, message, code=1, output="x_{}.ply"):
        (tmp_path / "sim" / name).write_text(text) if text is not None else None
        r = cli("polygonize", tmp_path / "sim" / name, "-o", tmp_path / output, *POLY, check=False)
        assert r.returncode == code and message in r.stderr, (name, r.stderr)
        assert not list(tmp_path.glob("x_*.ply"))

    pvd(tmp_path / "sim/twice.pvd", [(0, "data/f_5.vtk"), (0, "data/f_6.vtk")])
    refused("twice.pvd", None, "'data/f_5.vtk' and 'data/f_6.vtk' share the time 0 (one file per frame")
    for outside in ("../sim/data/f_5.vtk", "/etc/passwd", "data/../../f.vtk"):
        pvd(tmp_path / "sim/outside.pvd", [(0, outside)])
        refused("outside.pvd", None, "is not a path inside the collection's folder")
    refused("grid.pvd", '<VTKFile type="UnstructuredGrid"></VTKFile>', "is not a Collection")
    refused("empty.pvd", '<VTKFile type="Collection"><Collection></Collection></VTKFile>', "lists no frame")
    refused("notime.pvd", '<VTKFile type="Collection"><Collection><DataSet file="data/f_5.vtk"/></Collection></VTKFile>',
            "DataSet 0 ('data/f_5.vtk') has no timestep")
    refused("nan.pvd", '<VTKFile type="Collection"><Collection><DataSet timestep="x" file="a.vtk"/></Collection>'
            '</VTKFile>', "the timestep 'x' of 'a.vtk' is not a number")
    refused("bad.series", '{"files": [', "not a JSON file series")
    refused("nofiles.series", '{"file-series-version": "1.0"}', 'no "files" list')
    refused("noname.series", '{"files": [{"time": 0}]}', 'files[0] has no "name"')
    frames(tmp_path / "sim/data", [1])
    pvd(tmp_path / "sim/self.pvd", [(0, "data/f_5.vtk"), (1, "./data/f_1.vtk")])
    refused("self.pvd", None, "names the collection's frame", 2, output="sim/data/f_{}.vtk")
    refused("run.pvd", None, "has no frame field", 2, output="x.ply")
    # Read alone, a collection says how it is meshed.
    r = cli("triangulate", tmp_path / "sim/data/f_5.vtk", "-o", tmp_path / "one.ply", "-q")
    (tmp_path / "sim/as.vtu").write_text('<VTKFile type="Collection"><Collection></Collection></VTKFile>')
    r = cli("triangulate", tmp_path / "sim/as.vtu", "-o", tmp_path / "one.ply", check=False)
    assert r.returncode == 1 and "a collection of frames (.pvd)" in r.stderr, r.stderr


def test_binary_json_bgeo_pages_and_clear_errors(cli, tmp_path):
    """Houdini 12+'s binary-JSON bgeo (and ASCII .geo): constant pages (a channel constant over some pages of a
    packed vector and of a scalar) give what the same values as PLY give; a malformed file is
    an error naming it and what is wrong (a damaged .bgeo.sc container too)."""
    p, a = particles(0)  # 216 particles: pages of 50, the last one short
    a["velocity"][:100, 1:] = [0.25, -0.5]  # pages 0 and 1 of the [1, 2] packing's second part
    a["density"][150:] = 1000.0  # pages 3 and 4 (16 particles)
    write_ply(tmp_path / "in.ply", p, a)
    write_bgeo_json(tmp_path / "in.bgeo", p, a, big=True, page=50)
    raw = (tmp_path / "in.bgeo").read_bytes()
    assert b"constantpageflags" in raw
    for src in ("in.ply", "in.bgeo"):
        cli("polygonize", tmp_path / src, "-o", tmp_path / f"{src}.out.ply", *POLY, "-q")
        cli("triangulate", tmp_path / src, "-o", tmp_path / f"{src}.tri.ply", "--raw", "-q")
    assert (tmp_path / "in.bgeo.out.ply").read_bytes() == (tmp_path / "in.ply.out.ply").read_bytes()
    assert (tmp_path / "in.bgeo.tri.ply").read_bytes() == (tmp_path / "in.ply.tri.ply").read_bytes()

    write_bgeo_json(tmp_path / "good.bgeo", p, a)
    good = (tmp_path / "good.bgeo").read_bytes()
    # inspect names Houdini's compressed forms whole.
    (tmp_path / "good.bgeo.sc").write_bytes(scf(good))
    report = json.loads(cli("inspect", tmp_path / "good.bgeo.sc", "--json").stdout)
    assert report["input"]["format"] == "bgeo.sc" and report["input"]["points"] == len(p)
    cases = {
        "truncated.bgeo": (good[: len(good) // 2], "truncated"),
        "magic.bgeo": (b"\x7fNSJx" + good[5:], "magic number"),
        "token.bgeo": (good[:5] + b"\x99" + good[6:], "unknown binary JSON token 0x99"),
        "undefined.bgeo": (good[:5] + b"\x26\x05" + good[5:], "string token 5, which was never defined"),
        "noP.bgeo": (good.replace(b"\x01P", b"\x01Q", 1), "no position attribute 'P'"),
        "b.bgeo.sc": (b"scf1" + b"\0" * 64, "it does not end with the SCF footer '1fcs'"),
        "cut.bgeo.sc": (scf(good, block=1000)[:-100], "it does not end with the SCF footer"),
        "chunk.bgeo.sc": (scf(good, block=1000)[:2000] + scf(good, block=1000)[2100:], "runs past the seek index"),
        "comma.geo": (b'["pointcount", 3 "attributes", []]', "',' or ']' expected in a list"),
        "escape.geo": (b'["pointcount", 1, "\\q"]', "unknown escape"),
        "nan.geo": (b'["pointcount", 1, "attributes", [nan]]', "'nan' is not a JSON value"),
        "classic.geo": (b"PGEOMETRY V5\nNPoints 1 NPrims 0\n", "truncated: the file ends in the header"),
        "classic4.geo": (b"PGEOMETRY V4\n", "classic .geo version 'V4' (only V5 is read)"),
        "classic_cut.geo": (b"PGEOMETRY V5\nNPoints 2 NPrims 0\nNPointGroups 0 NPrimGroups 0\n"
                            b"NPointAttrib 0 NVertexAttrib 0 NPrimAttrib 0 NAttrib 0\n0 0 0 1\n1 0",
                            "truncated: the file ends in point 1 of the 2 the header promises"),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        r = cli("polygonize", tmp_path / name, "-o", tmp_path / "m.ply", check=False)
        assert r.returncode == 1 and message in r.stderr and name in r.stderr, (name, r.stderr)
        assert not (tmp_path / "m.ply").exists()


def test_houdini_velocity_v_is_the_velocity_channel(cli, tmp_path):
    """Houdini names the velocity `v`: every bgeo form gives it as the channel `velocity` (what
    --attributes velocity, the PLY's velocity_0.. and Blender's motion blur use)."""
    p, a = particles(0)
    houdini = {"v": a["velocity"], "density": a["density"]}
    forms = {"classic.bgeo": write_bgeo, "json.bgeo": write_bgeo_json,
             "text.geo": lambda path, p, a: write_bgeo_json(path, p, a, ascii=True),
             "classic.geo": write_geo_classic}
    for name, write in forms.items():
        src = tmp_path / name
        write(src, p, houdini)
        out = tmp_path / (name + ".ply")
        cli("triangulate", src, "-o", out, "--raw", "--attributes", "velocity", "--ascii", "-q")
        _, cols, _ = read_ascii_ply(out)
        assert "density" not in cols, name
        got = np.column_stack([cols[f"velocity_{k}"] for k in range(3)]).astype(np.float32)
        np.testing.assert_array_equal(got, a["velocity"], err_msg=name)


def test_shared_simulator_samples(cli, tmp_path):
    d = os.environ.get("PM_TEST_DATA")
    folder = Path(d) / "particles" if d else None
    if not folder or not folder.is_dir():
        pytest.skip("shared particle samples not found (set PM_TEST_DATA to the shared/data folder)")
    # The same frame as .ply and .vtk: the same mesh.
    ply, vtk = folder / "cube_2366_particles.ply", folder / "cube_2366_particles.vtk"
    cli("polygonize", ply, "-o", tmp_path / "a.ply", "-q", "--attributes", "none")
    cli("polygonize", vtk, "-o", tmp_path / "b.ply", "-q", "--attributes", "none")
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    for name in ["ParticleData_Fluid_50.bgeo", "fluid_250_particles.vtu", "fluid_encoded_250_particles.vtu",
                 "double_dam_break_frame_01_4732_particles.vtk"]:
        r = cli("inspect", folder / name, "--json", check=False)
        cli("polygonize", folder / name, "-o", tmp_path / "s.vtu", "-q")
        assert (tmp_path / "s.vtu").stat().st_size > 0, name


def test_ctrl_c_cancels_the_frames_in_flight(tmp_path):
    exe = os.environ.get("PARTICLEMESH_CLI")
    if not exe:
        pytest.skip("PARTICLEMESH_CLI is not set to the built particlemesh binary")
    import signal
    import subprocess
    for f in range(4):
        p, a = particles(f, n=30)
        write_vtk(tmp_path / f"f_{f}.vtk", p, a, binary=True)
    proc = subprocess.Popen([exe, "polygonize", tmp_path / "f_{}.vtk", "-o", tmp_path / "m_{}.ply",
                             "--radius", "0.14", "--cell", "0.004", "--jobs", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "cancelled (interrupted)" in err
    # No temporary is left; a frame finished before the signal has its mesh and its sidecar.
    left = {x.name for x in tmp_path.iterdir() if not x.name.endswith(".vtk")}
    meshes = {n for n in left if n.startswith("m_")}
    assert left == meshes | {f".{m}.particlemesh" for m in meshes}, left
    assert len(meshes) < 4
