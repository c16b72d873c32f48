"""particlemesh triangulate on PCL's .pcd files, the PCL preprocessing switches and --pcl-mesh."""
import json
import math
import os
import shutil
import struct
import subprocess

import numpy as np
import pytest

from particle_files import fibonacci_sphere, write_ply

KINECT = "pcd/kinect_frame_20121214T142255.814212.pcd"


@pytest.fixture(scope="session")
def pcl_cli(cli):
    if "--pcl-mesh" not in cli("triangulate", "--help").stdout:
        pytest.skip("the CLI was built without the PCL bridge (PM_WITH_PCL=OFF)")
    return cli


def _report(pcl_cli, tmp_path, src, *extra):
    out = tmp_path / "mesh.ply"
    rep = tmp_path / "report.json"
    proc = pcl_cli("triangulate", src, "-o", out, "--report", rep, *extra)
    return proc, json.loads(rep.read_text())


@pytest.mark.parametrize(
    "name,points,nan,encoding,organized,normals,color",
    [
        ("pcd/bunny.pcd", 397, 0, "ascii", False, False, False),
        ("pcd/bun0.pcd", 397, 0, "ascii", False, True, False),
        ("pcd/milk.pcd", 13704, 0, "binary_compressed", False, False, False),
        ("pcd/milk_binary.pcd", 13704, 0, "binary", False, False, False),
        (KINECT, 307200, 35625, "binary_compressed", True, False, True),
        ("pcd/colored_cloud.pcd", 1000, 0, "binary", True, True, True),
    ],
)
def test_every_shared_pcd_triangulates(pcl_cli, inspect, data_dir, tmp_path, name, points, nan, encoding,
                                       organized, normals, color):
    proc, r = _report(pcl_cli, tmp_path, data_dir / name)
    c = r["input_cloud"]
    assert c["format"] == "pcd" and c["encoding"] == encoding
    assert c["points"] == points and c["invalid_points"] == nan and c["valid_points"] == points - nan
    assert c["organized"] == organized and c["has_normals"] == normals and c["has_color"] == color
    assert r["triangulation"]["points"] == points - nan
    if nan:
        assert f"{nan} invalid (NaN/Inf) dropped" in proc.stdout
    mesh = inspect(tmp_path / "mesh.ply")
    assert mesh["vertices"] == points - nan
    assert mesh["triangles"] == r["topology"]["triangles"] > 0
    # the finished surface: manifold and consistently oriented, also on these raw scans
    assert mesh["nonmanifold_edges"] == 0 and mesh["orientation_conflicts"] == 0


def test_kinect_frame_with_the_documented_preprocessing(pcl_cli, inspect, data_dir, tmp_path):
    # docs/pcl.md: outlier removal, uniform sampling to 5 mm, normals toward the sensor.
    pcl_mesh = tmp_path / "pcl.ply"
    proc, r = _report(pcl_cli, tmp_path, data_dir / KINECT, "--remove-outliers", "--uniform-sampling", "0.005",
                      "--estimate-normals", "--pcl-mesh", pcl_mesh)
    p = r["input_cloud"]["preprocessing"]
    assert p["outliers_removed"] > 0 and p["downsampled_away"] > 100000
    assert p["normals_estimated"] and p["normals_failed"] == 0
    assert p["output_points"] == 307200 - 35625 - p["outliers_removed"] - p["downsampled_away"]
    assert r["triangulation"]["points"] == p["output_points"]
    assert r["triangulation"]["spacing"] == 0.005 and not r["triangulation"]["spacing_estimated"]  # r0 = the leaf
    assert "outliers removed" in proc.stdout and "uniform sampling 0.005" in proc.stdout
    # The pcl::PolygonMesh PLY: same triangles, and it carries the frame's colours.
    ours, theirs = inspect(tmp_path / "mesh.ply"), inspect(pcl_mesh)
    assert theirs["triangles"] == ours["triangles"] and theirs["vertices"] == ours["vertices"]
    assert ours["nonmanifold_edges"] == 0 and ours["orientation_conflicts"] == 0
    assert ours["per_component"][0]["triangles"] > 75000  # one main surface of the scene
    header = pcl_mesh.read_bytes()[:600].split(b"end_header")[0].decode()
    assert "property uchar red" in header and "property float nx" in header
    assert "element face" in header


def test_depth_scan_gives_no_pillows_and_unit_normals_everywhere(pcl_cli, data_dir, tmp_path):
    # The raw frame: flat rows of collinear points, depth edges, patches of a few points. Before
    # the fold check in the small-hole fill, 346 of its 2850 components were capped patches
    # (closed, with no volume), and 2226 used points had zero normals (triangles folded onto
    # each other cancel in the angle-weighted sum).
    out = tmp_path / "kinect.obj"
    proc, r = _report(pcl_cli, tmp_path, data_dir / KINECT)
    pcl_cli("triangulate", data_dir / KINECT, "-o", out)
    t = r["topology"]
    assert t["manifold"] and t["consistently_oriented"]
    assert t["closed_components"] < 20  # a room: almost nothing closed
    assert t["vertices_used"] * 1000 > r["triangulation"]["points"] * 995  # each particle's own spacing: all in
    assert r["surface"]["viewpoint_used"]  # the frame's VIEWPOINT: the Kinect's origin
    normals, used = [], set()
    for line in out.read_text().splitlines():
        if line.startswith("vn "):
            normals.append([float(x) for x in line.split()[1:]])
        elif line.startswith("f "):
            used.update(int(c.split("/")[0]) - 1 for c in line.split()[1:])
    assert len(used) == t["vertices_used"]
    bad = [v for v in used if abs(math.sqrt(sum(x * x for x in normals[v])) - 1) > 1e-4]
    assert not bad, f"{len(bad)} used points without a unit normal"


def test_voxel_grid_and_uniform_sampling_exclude_each_other(pcl_cli, data_dir, tmp_path):
    proc = pcl_cli("triangulate", data_dir / "pcd/milk.pcd", "-o", tmp_path / "m.ply", "--uniform-sampling", "0.003",
                   "--voxel-grid", "0.003", check=False)
    assert proc.returncode == 2
    _, r = _report(pcl_cli, tmp_path, data_dir / "pcd/milk.pcd", "--voxel-grid", "0.003")
    assert r["input_cloud"]["preprocessing"]["downsampling"] == "voxel_grid"
    assert r["triangulation"]["points"] < 13704


def _fails(pcl_cli, tmp_path, src, needle):
    out = tmp_path / "out.ply"
    proc = pcl_cli("triangulate", src, "-o", out, check=False)
    assert proc.returncode == 1, proc.stdout
    lines = [l for l in proc.stderr.splitlines() if l.strip()]
    assert len(lines) == 1, proc.stderr
    assert str(src) in lines[0] and needle in lines[0], lines[0]
    assert not out.exists()


def test_malformed_pcd_files_give_one_line_errors(pcl_cli, data_dir, tmp_path):
    ascii_ = (data_dir / "pcd/bunny.pcd").read_bytes()
    binary = (data_dir / "pcd/milk_binary.pcd").read_bytes()
    compressed = (data_dir / "pcd/milk.pcd").read_bytes()
    cases = {
        "cut_binary.pcd": (binary[:5000], "truncated data"),
        "cut_compressed.pcd": (compressed[:3000], "truncated data"),
        "cut_ascii.pcd": (ascii_[: len(ascii_) // 3], "truncated data"),
        "garbage.pcd": (b"hello world\n", "not a PCD file"),
        "empty.pcd": (b"", "empty file"),
        "fields.pcd": (ascii_.replace(b"FIELDS x y z", b"FIELDS a b c"), "missing field 'x'"),
        "points.pcd": (ascii_.replace(b"POINTS 397", b"POINTS 400"), "count mismatch"),
        "size.pcd": (ascii_.replace(b"SIZE 4 4 4", b"SIZE 4 4"), "count mismatch"),
    }
    for name, (content, needle) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        _fails(pcl_cli, tmp_path, path, needle)
    _fails(pcl_cli, tmp_path, tmp_path / "missing.pcd", "no such file")


def test_all_nan_pcd_is_an_input_error(pcl_cli, tmp_path):
    path = tmp_path / "nan.pcd"
    body = struct.pack("<6f", *([float("nan")] * 6))
    path.write_bytes(b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                     b"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n" + body)
    _fails(pcl_cli, tmp_path, path, "no valid point")


def test_estimated_normals_face_the_viewpoint(pcl_cli, tmp_path):
    # A flat square of points at z = 0: PCL's normals are +-z, flipped toward the viewpoint.
    pts = tmp_path / "plane.xyz"
    pts.write_text("".join(f"{0.1 * i} {0.1 * j} 0\n" for i in range(20) for j in range(20)))
    for vz, sign in ((5, 1), (-5, -1)):
        out = tmp_path / f"plane{vz}.ply"
        proc = pcl_cli("triangulate", pts, "-o", out, "--estimate-normals", "--viewpoint", 0, 0, vz, "--ascii")
        assert f"toward 0 0 {vz}" in proc.stdout
        lines = out.read_text().splitlines()
        header = lines[: lines.index("end_header")]
        assert "property float nx" in header
        body = lines[len(header) + 1:]
        nz = [float(l.split()[5]) for l in body[:400]]
        assert all(n * sign > 0.99 for n in nz), nz[:5]


def test_moving_least_squares_closes_a_noisy_scan(pcl_cli, tmp_path):
    # A sphere of 20 000 points, each moved along its radius by noise of 0.6 spacings: as it
    # is, the surface keeps holes (noise of half a spacing closes since the normals' tree
    # keeps within a sheet in noisy samplings); smoothed with --mls over 2.4 spacings, one
    # closed sphere whose vertices lie closer to it.
    n = 20000
    spacing = math.sqrt(4 * math.pi / n)
    p = fibonacci_sphere(n) * (1 + np.random.default_rng(0).normal(0, 0.6 * spacing, n))[:, None]
    src = tmp_path / "noisy.ply"
    write_ply(src, p, {})
    proc, raw = _report(pcl_cli, tmp_path, src)
    assert not raw["topology"]["closed"] and raw["topology"]["boundary_loops"] >= 2
    # The summary says the particles scatter across their surface, and what smoothing to try.
    assert 0.35 < raw["triangulation"]["sampling_thickness"] < 0.5
    assert "oriented by a spanning tree (a noisy sampling: within each sheet first)" in proc.stdout
    hint = next(line for line in proc.stdout.splitlines() if "scatter across their surface" in line)
    suggested = float(hint.split("--mls ")[1].split()[0])
    assert 2.5 * spacing < suggested < 3.5 * spacing, hint
    _, tried = _report(pcl_cli, tmp_path, src, "--mls", suggested)
    assert tried["topology"]["components"] == 1 and tried["topology"]["closed"]
    radius = 2.4 * spacing
    proc, r = _report(pcl_cli, tmp_path, src, "--mls", radius)
    pre = r["input_cloud"]["preprocessing"]
    assert pre["mls_radius"] == radius and pre["mls_order"] == 2
    # A few points flung far by the noise have fewer than 3 neighbours within the radius.
    assert pre["smoothed"] + pre["smoothing_skipped"] == n and pre["smoothing_skipped"] <= 10
    assert (f"moving least squares (radius {radius:.6g}, order 2): {pre['smoothed']} points moved"
            in proc.stdout)
    assert 0 < pre["smoothing_mean_shift"] < pre["smoothing_max_shift"] < radius
    t = r["topology"]
    assert t["components"] == 1 and t["closed"] and t["manifold"]
    assert "scatter across" not in proc.stdout  # closed: no hint
    with open(tmp_path / "mesh.ply", "rb") as f:
        data = f.read()
    body = data[data.index(b"end_header\n") + 11:]
    v = np.frombuffer(body[: 12 * n], dtype="<f4").reshape(-1, 3).astype(float)
    before = np.abs(np.linalg.norm(p, axis=1) - 1).mean()
    after = np.abs(np.linalg.norm(v, axis=1) - 1).mean()
    assert after < before / 3, (before, after)
    # A radius that is not a positive number is refused by the option.
    assert pcl_cli("triangulate", src, "-o", tmp_path / "x.ply", "--mls", -1, check=False).returncode != 0
    assert not (tmp_path / "x.ply").exists()


def test_a_far_stray_point_is_named_and_removable(pcl_cli, tmp_path):
    # A sphere of 5000 points and one stray a million away (a particle a simulation flung off,
    # an invalid return): no grid spans both; the error names the point and the switch that
    # drops it, which then gives the closed sphere.
    n = 5000
    src = tmp_path / "stray.ply"
    write_ply(src, np.r_[fibonacci_sphere(n), [[1e6, 0, 0]]], {})
    proc = pcl_cli("triangulate", src, "-o", tmp_path / "x.ply", check=False)
    assert proc.returncode != 0 and not (tmp_path / "x.ply").exists()
    assert f"point {n} (x = 1e+06) lies 1e+06 from the points' median x" in proc.stderr, proc.stderr
    assert "--remove-outliers drops them" in proc.stderr
    proc, r = _report(pcl_cli, tmp_path, src, "--remove-outliers")
    assert r["input_cloud"]["preprocessing"]["outliers_removed"] == 1
    assert r["topology"]["components"] == 1 and r["topology"]["closed"]


def _plane_pcd(path, n=20):
    pts = "".join(f"{0.1 * i} {0.1 * j} 0\n" for i in range(n) for j in range(n))
    path.write_text(f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n * n}\nHEIGHT 1\n"
                    f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n * n}\nDATA ascii\n" + pts)
    return path


def test_pcl_is_loaded_only_when_asked_for(pcl_cli, tmp_path):
    # The dynamic linker lists every library it loads (LD_DEBUG=files): PCL's only for a .pcd
    # file or a PCL switch; PCL's io library alone (the CLI's PCD module) for reading a .pcd
    # file and --pcl-mesh, its features, filters and surface libraries (the PCL module) only
    # for preprocessing.
    exe = os.environ["PARTICLEMESH_CLI"]
    xyz = tmp_path / "plane.xyz"
    xyz.write_text("".join(f"{0.1 * i} {0.1 * j} 0\n" for i in range(20) for j in range(20)))
    pcd = _plane_pcd(tmp_path / "plane.pcd")

    def loaded(*args):
        env = dict(os.environ, LD_DEBUG="files")
        proc = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return proc.stderr

    preprocessing_libraries = ("particlemesh_cli_pcl.so", "libpcl_features", "libpcl_filters", "libpcl_surface")
    for args in (["triangulate", xyz, "-o", tmp_path / "a.ply", "-q"], ["smooth", tmp_path / "a.ply", "-o", tmp_path / "b.ply", "-q"]):
        log = loaded(*args)
        assert "libpcl_" not in log and "particlemesh_cli_pc" not in log, args
    for args in (["triangulate", pcd, "-o", tmp_path / "c.ply", "-q"],
                 ["triangulate", xyz, "-o", tmp_path / "e.ply", "-q", "--pcl-mesh", tmp_path / "e_pcl.ply"]):
        log = loaded(*args)
        assert "particlemesh_cli_pcd.so" in log and "libpcl_io" in log, args
        assert not [name for name in preprocessing_libraries if name in log], args
    for args in (["triangulate", xyz, "-o", tmp_path / "d.ply", "-q", "--estimate-normals"],
                 ["triangulate", pcd, "-o", tmp_path / "f.ply", "-q", "--voxel-grid", "0.15"]):
        log = loaded(*args)
        assert all(name in log for name in preprocessing_libraries), args
        assert "particlemesh_cli_pcd.so" not in log, args


def test_a_missing_pcl_module_is_a_clear_error(pcl_cli, tmp_path):
    # The program alone, without its PCL module beside it or in ../lib: what needs no PCL
    # works, what does fails with one line naming the module, and writes nothing.
    alone = tmp_path / "bin" / "particlemesh"
    alone.parent.mkdir()
    shutil.copy2(os.environ["PARTICLEMESH_CLI"], alone)
    xyz = tmp_path / "plane.xyz"
    xyz.write_text("".join(f"{0.1 * i} {0.1 * j} 0\n" for i in range(20) for j in range(20)))
    ok = subprocess.run([alone, "triangulate", xyz, "-o", tmp_path / "a.ply", "-q"], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    pcd = _plane_pcd(tmp_path / "plane.pcd")
    for args, what, module in (([pcd], ".pcd input", "libparticlemesh_cli_pcd.so"),
                               ([xyz, "--voxel-grid", "0.2"], "PCL preprocessing", "libparticlemesh_cli_pcl.so"),
                               ([xyz, "--pcl-mesh", tmp_path / "p.ply"], "--pcl-mesh", "libparticlemesh_cli_pcd.so")):
        out = tmp_path / "out.ply"
        proc = subprocess.run([alone, "triangulate", *map(str, args), "-o", out], capture_output=True, text=True)
        assert proc.returncode == 1, proc.stdout
        lines = [l for l in proc.stderr.splitlines() if l.strip()]
        assert len(lines) == 1, proc.stderr
        assert what in lines[0] and "PCL module" in lines[0] and module in lines[0], lines[0]
        assert str(alone.parent) in lines[0], lines[0]  # where it looked
        assert not out.exists() and not (tmp_path / "p.ply").exists()
