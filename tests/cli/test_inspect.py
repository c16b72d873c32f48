"""`particlemesh inspect`: a mesh's topology report; for a file of particles (no triangles),
the count, bounds, spacing, normals and channels the meshing commands will read."""
import json

import numpy as np
import pytest

from particle_files import particles, write_bgeo, write_ply, write_vtk, write_vtu


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
