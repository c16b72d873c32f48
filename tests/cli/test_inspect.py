"""`particlemesh inspect`: a mesh's topology report; for a file of particles (no triangles),
the count, bounds, spacing, normals and channels the meshing commands will read."""
import json
import struct

import numpy as np
import pytest

from particle_files import (fibonacci_sphere, particles, write_bgeo, write_bgeo_json, write_geo_classic, write_las,
                            write_ply, write_vtk, write_vtu)


def inspect_json(cli, path):
    return json.loads(cli("inspect", path, "--json").stdout)


def median_nn(p):
    """The median nearest-neighbour distance of distinct points, by brute force (the lower
    median, as estimate_spacing takes it)."""
    q = np.unique(p.astype(np.float64), axis=0)
    d2 = ((q[:, None, :] - q[None, :, :]) ** 2).sum(-1)
    np.fill_diagonal(d2, np.inf)
    nn = np.sort(np.sqrt(d2.min(1)))
    return nn[(len(nn) - 1) // 2]


@pytest.mark.parametrize("kind", ["ply", "vtk", "vtk_binary", "vtu", "bgeo"])
def test_particle_files_summarised(cli, tmp_path, kind):
    p, attrs = particles(n=7)
    p = np.vstack([p, p[:3]])  # three exact duplicates
    attrs = {k: np.concatenate([v, v[:3]]) for k, v in attrs.items()}
    path = tmp_path / f"p.{kind.split('_')[0]}"
    {"ply": lambda: write_ply(path, p, attrs), "vtk": lambda: write_vtk(path, p, attrs),
     "vtk_binary": lambda: write_vtk(path, p, attrs, binary=True), "vtu": lambda: write_vtu(path, p, attrs),
     "bgeo": lambda: write_bgeo(path, p, attrs)}[kind]()
    r = inspect_json(cli, path)
    assert r["particles"] == len(p) and r["duplicate_points"] == 3
    assert r["bounds"]["min"] == p.min(0).astype(np.float64).tolist()
    assert r["bounds"]["max"] == p.max(0).astype(np.float64).tolist()
    assert r["spacing"] == pytest.approx(median_nn(p), rel=1e-12)
    assert r["normals"] is False
    channels = {c["name"]: c for c in r["channels"]}
    assert set(channels) == set(attrs)
    for name, a in attrs.items():
        c = channels[name]
        assert c["components"] == (1 if a.ndim == 1 else a.shape[1])
        assert (c["min"], c["max"]) == (float(a.min()), float(a.max()))
    text = cli("inspect", path).stdout
    assert f"particles     {len(p)} (3 exact duplicates)" in text
    # (PLY: the properties velocity_0, velocity_1, velocity_2 are the one vector channel)
    assert "velocity (3 components): " in text and "density: " in text


NAME_STRINGS = "point attribute 'name' (strings)"


def files_with_data_not_read(folder, p, attrs):
    """{file: what its reader names as not read}: a string attribute of each Houdini format, a
    VTK string array (legacy FIELD data and a .vtu's PointData), a PLY list property on the
    vertices, a LAS file's other fields and extra bytes; a PLY whose every property is read."""
    n = len(p)
    f = {name: folder / name for name in ("a.bgeo", "a.geo", "a.json.bgeo", "a.vtk", "a.vtu", "a.ply", "a.las",
                                           "plain.ply")}
    write_bgeo(f["a.bgeo"], p, attrs, names=["fluid", "foam"])
    write_geo_classic(f["a.geo"], p, attrs, names=["fluid", "foam"])
    write_bgeo_json(f["a.json.bgeo"], p, attrs)  # it carries a string attribute "name"
    write_vtk(f["a.vtk"], p, attrs)
    with open(f["a.vtk"], "a") as out:
        out.write(f"FIELD FieldData 1\nlabel 1 {n} string\n" + "".join(f"p{i}\n" for i in range(n)))
    write_vtu(f["a.vtu"], p, attrs)
    text = f["a.vtu"].read_text().replace(
        "<PointData>\n", '<PointData>\n<Array type="String" Name="label" format="ascii">'  # as VTK writes it
        + " ".join("112 0" for _ in range(n)) + "</Array>\n")
    f["a.vtu"].write_text(text)
    head = f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n" \
           "property list uchar int neighbours\nend_header\n"
    f["a.ply"].write_text(head + "".join(f"{x!r} {y!r} {z!r} 2 {i} {i}\n" for i, (x, y, z) in
                                         enumerate(p.astype(np.float64))))
    write_las(f["a.las"], p, np.arange(n) % 7, point_format=0, extra_bytes=4)
    write_ply(f["plain.ply"], p, attrs)
    las = "the LAS fields return number, number of returns, scan angle, user data, point source ID"
    return {f["a.bgeo"]: [NAME_STRINGS], f["a.geo"]: [NAME_STRINGS], f["a.json.bgeo"]: [NAME_STRINGS],
            f["a.vtk"]: ["POINT_DATA FIELD array 'label' (strings)"], f["a.vtu"]: ["PointData array 'label' (strings)"],
            f["a.ply"]: ["vertex list property 'neighbours' (lists)"], f["a.las"]: [las, "extra bytes (4 per point)"],
            f["plain.ply"]: []}


def test_what_a_file_holds_per_particle_but_does_not_read_is_named(cli, tmp_path):
    """Nothing is dropped silently: inspect, the meshing commands' summary and their reports
    name the per-particle data no channel carries; the rest of the file is read as before."""
    p, attrs = particles(n=5)
    for path, expected in files_with_data_not_read(tmp_path, p, attrs).items():
        r = inspect_json(cli, path)
        assert r["particles"] == len(p), path
        assert r["input"].get("not_read", []) == expected, path
        line = "  not read      " + "; ".join(expected)
        assert (line in cli("inspect", path).stdout) == bool(expected), path
        if path.name not in ("a.las", "a.ply"):  # (LAS: intensity and classification; the PLY: none)
            assert {c["name"] for c in r["channels"]} == set(attrs), path
    # The meshing commands: the same line in the summary, the same list in the report.
    bgeo = tmp_path / "a.bgeo"
    out = cli("triangulate", bgeo, "-o", tmp_path / "m.ply", "--report", tmp_path / "m.json").stdout
    assert "  not read      " + NAME_STRINGS in out
    assert json.loads((tmp_path / "m.json").read_text())["input_cloud"]["not_read"] == [NAME_STRINGS]
    out = cli("polygonize", bgeo, "-o", tmp_path / "v.ply", "--report", tmp_path / "v.json").stdout
    assert "  not read      " + NAME_STRINGS in out
    assert json.loads((tmp_path / "v.json").read_text())["read"]["not_read"] == [NAME_STRINGS]
    out = cli("triangulate", tmp_path / "plain.ply", "-o", tmp_path / "m.ply", "--report", tmp_path / "m.json").stdout
    assert "not read" not in out and "not_read" not in json.loads((tmp_path / "m.json").read_text())["input_cloud"]


def test_a_mesh_keeps_its_topology_report(cli, tmp_path):
    pts, mesh = tmp_path / "torus.xyz", tmp_path / "torus.ply"
    cli("sample", "torus", "-o", pts, "-q")
    cli("triangulate", pts, "-o", mesh, "-q")
    r = inspect_json(cli, mesh)
    assert "particles" not in r and r["closed"] and r["per_component"][0]["genus"] == 1
    # The particles of the same torus: a .xyz with normals, no channels.
    r = inspect_json(cli, pts)
    assert r["particles"] > 1000 and r["normals"] is True and r["channels"] == []
    assert "closed" not in r


def test_shared_simulator_file(cli, data_dir):
    path = data_dir / "particles" / "dam_break_frame_9_6859_particles.bgeo"
    if not path.exists():
        pytest.skip(f"{path} is not in the shared data")
    r = inspect_json(cli, path)
    assert r["particles"] == 6859 and {c["name"] for c in r["channels"]} >= {"velocity", "density"}
    assert 0 < r["spacing"] < 0.1


def test_values_that_are_not_finite_are_counted_apart(cli, tmp_path):
    path = tmp_path / "nan.xyz"
    path.write_text("x y z density speed\n0 0 0 nan nan\n1 0 0 2 nan\n0 1 0 inf nan\n0 0 1 -3 nan\n")
    c = {c["name"]: c for c in inspect_json(cli, path)["channels"]}
    assert (c["density"]["min"], c["density"]["max"], c["density"]["non_finite"]) == (-3.0, 2.0, 2)
    assert c["speed"]["min"] is None and c["speed"]["max"] is None and c["speed"]["non_finite"] == 4
    assert "speed: no finite value (4 NaN or infinite)" in cli("inspect", path).stdout


def test_what_cannot_be_read_is_an_error(cli, tmp_path):
    proc = cli("inspect", tmp_path / "missing.vtk", check=False)
    assert proc.returncode == 1 and "missing.vtk" in proc.stderr
    one = tmp_path / "one.xyz"
    one.write_text("0 0 0\n")
    r = inspect_json(cli, one)  # read, but one point has no spacing: said, not fatal
    assert r["particles"] == 1 and r["spacing"] is None and "two points" in r["spacing_error"]


@pytest.mark.parametrize("fmt", ["binary_little_endian", "ascii"])
def test_a_meshio_point_cloud_ply_gets_the_particle_report(cli, tmp_path, fmt):
    """meshio.write("p.ply", meshio.Mesh(points, [("vertex", idx)])) writes each vertex cell as
    a 1-corner face: the mesh reader refuses them, the meshing commands skip them. inspect
    reads the file as they do and says why it is not a mesh."""
    p, _ = particles(n=4)
    p = p.astype(np.float64)
    n = len(p)
    head = (f"ply\nformat {fmt} 1.0\ncomment Created by meshio\nelement vertex {n}\nproperty double x\n"
            f"property double y\nproperty double z\nelement face {n}\nproperty list uint8 int32 vertex_indices\n"
            "end_header\n").encode()
    if fmt == "ascii":
        body = ("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in p.tolist()) +
                "".join(f"1 {i}\n" for i in range(n))).encode()
    else:
        body = p.astype("<f8").tobytes() + b"".join(struct.pack("<Bi", 1, i) for i in range(n))
    path = tmp_path / "p.ply"
    path.write_bytes(head + body)
    why = "'face' element 0 has 1 corner (a face needs at least 3)"
    r = inspect_json(cli, path)
    assert r["particles"] == n and r["not_a_mesh"] == why
    assert r["bounds"]["min"] == p.min(0).tolist() and r["bounds"]["max"] == p.max(0).tolist()
    assert r["spacing"] == pytest.approx(median_nn(p), rel=1e-12)
    assert "triangles" not in r and r["channels"] == []
    text = cli("inspect", path).stdout
    assert f"  not a mesh    {why}; read as particles\n" in text and f"  particles     {n}\n" in text
    # Cut short inside the faces: refused both ways, with the mesh reader's error.
    cut = tmp_path / "cut.ply"
    cut.write_bytes(head + body[:-3])
    proc = cli("inspect", cut, check=False)
    assert proc.returncode == 1 and "cut.ply" in proc.stderr and "1 corner" in proc.stderr, proc.stderr
    assert proc.stdout == ""


def test_an_obj_point_cloud_gets_the_particle_report(cli, tmp_path):
    """MeshLab, Blender and CloudCompare export point clouds as OBJ v lines (x y z r g b),
    with one vn per v and no faces."""
    p, _ = particles(n=3)
    n = len(p)
    rgb = np.stack([np.arange(n) % 2, np.arange(n) / (2 * n), np.full(n, 0.25)], -1)
    path = tmp_path / "cloud.obj"
    path.write_text("# MeshLab point cloud\n" +
                    "".join(f"v {x!r} {y!r} {z!r} {r!r} {g!r} {b!r}\n"
                            for (x, y, z), (r, g, b) in zip(p.astype(np.float64).tolist(), rgb.tolist())) +
                    "vn 0 0 1\n" * n)
    r = inspect_json(cli, path)
    assert r["particles"] == n and r["normals"] is True and "not_a_mesh" not in r
    assert r["bounds"]["min"] == p.min(0).astype(np.float64).tolist()
    assert r["bounds"]["max"] == p.max(0).astype(np.float64).tolist()
    assert r["channels"] == [{"name": "color", "components": 3, "min": 0.0, "max": 1.0}]
    text = cli("inspect", path).stdout
    assert f"  particles     {n}\n" in text and "  normals       yes\n" in text
    assert "color (3 components): 0 to 1" in text and "not a mesh" not in text


def test_particles_say_what_their_sampling_is(cli, tmp_path):
    """The particle report measures the sampling as triangulate will: an even clean sphere;
    the same moved off its surface by noise of half its spacing (thick: --mls suggested);
    particles dropped at random (the longer reach triangulate gives them); a block of
    particles filling a volume (polygonize suggested)."""
    n = 8000
    even = fibonacci_sphere(n)
    rng = np.random.default_rng(4)
    noisy = even * (1 + rng.normal(0, 0.5 * np.sqrt(4 * np.pi / n), n))[:, None]
    zr, pr = 2 * rng.random(n) - 1, 2 * np.pi * rng.random(n)
    random = np.c_[np.sqrt(1 - zr * zr) * np.cos(pr), np.sqrt(1 - zr * zr) * np.sin(pr), zr]
    block = np.stack(np.meshgrid(*[np.arange(14.0)] * 3), -1).reshape(-1, 3)
    report, text = {}, {}
    for name, p in (("even", even), ("noisy", noisy), ("random", random), ("block", block)):
        path = tmp_path / f"{name}.ply"
        write_ply(path, p.astype(np.float32), {})
        report[name] = inspect_json(cli, path)["sampling"]
        text[name] = cli("inspect", path).stdout
    assert report["even"]["reach_factor"] == 1 and report["even"]["thickness"] < 0.05
    assert report["even"]["local_spacing"]["median"] == pytest.approx(1, abs=0.05)
    assert "an even sampling" in text["even"] and "a clean surface" in text["even"]
    assert 0.3 < report["noisy"]["thickness"] < 0.45 and "scattered across a surface" in text["noisy"]
    assert report["random"]["reach_factor"] == 1.75 and 0.44 < report["random"]["irregularity"] < 0.56
    assert "lengthens its edge limits 1.75 x" in text["random"]
    assert report["block"]["thickness"] > 0.75 and "polygonize meshes it" in text["block"]
    # Too few particles for a neighbourhood: said, not read as an even, clean sampling.
    few = tmp_path / "few.ply"
    write_ply(few, even[:6].astype(np.float32), {})
    r = inspect_json(cli, few)
    assert r["sampling"] is None and "no neighbourhood to measure" in r["sampling_error"]
    assert "cannot be measured" in cli("inspect", few).stdout
