"""particlemesh.distributed on a real Dask cluster: LocalCluster(n_workers=2, processes=True)
over loopback. Frames against the command-line tool byte for byte, polygonize_tiled against
polygonize bit for bit, triangulate_tiled's stitched surface against the one-machine one's
topology. Sized for CI (about 30 s with the cluster's start)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

try:
    from dask.distributed import Client, LocalCluster
except ImportError as e:  # setup.sh installs python3-distributed: its absence is a failure
    pytest.fail(f"Dask's distributed scheduler is not installed ({e}): apt install "
                "python3-distributed", pytrace=False)


@pytest.fixture(scope="module")
def pmd(pm):
    import particlemesh.distributed as module
    return module


@pytest.fixture(scope="module")
def client(pm):
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address=None)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def cli():
    exe = os.environ.get("PARTICLEMESH_CLI")
    assert exe and Path(exe).is_file(), f"PARTICLEMESH_CLI is not the built tool: {exe!r}"

    def run(*args):
        proc = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        return proc
    return run


def blob(n, seed):
    """Volume particles filling an ellipsoid (an SPH-like blob), in a fixed order."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1, 1, (n, 3))
    return p[np.linalg.norm(p, axis=1) < 1] * [1.0, 0.7, 0.5]


def fibonacci_sphere(n, radius=1.0):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (1 + 5 ** 0.5) * i
    return radius * np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def same_arrays(a, b):
    return a.shape == b.shape and np.array_equal(a, b)


# ---- import --------------------------------------------------------------------------------

def test_import_particlemesh_needs_no_dask(pm):
    """`import particlemesh` imports no Dask (the add-on in Blender has none); the subpackage
    imports it only when called."""
    code = ("import sys, particlemesh, particlemesh.distributed as d; "
            "assert 'distributed' not in sys.modules and 'dask' not in sys.modules, "
            "[m for m in sys.modules if m.startswith(('dask', 'distributed'))]; "
            "print(d.polygonize_tiled.__name__)")
    env = dict(os.environ, PYTHONPATH=str(Path(pm.__file__).parents[1]))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "polygonize_tiled"
    # Without Dask, a call says what to install.
    code = ("import sys; sys.modules['distributed'] = None; import particlemesh.distributed as d\n"
            "try:\n    d.map_frames(None, 'triangulate', 'a_{}.xyz', 'b_{}.ply')\n"
            "except ImportError as e:\n    print(e)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0 and "python3-distributed" in out.stdout, out.stdout + out.stderr


# ---- frames ----------------------------------------------------------------------------------

def test_map_frames_writes_what_the_cli_writes(pm, pmd, client, cli, tmp_path):
    frames = [3, 4, 5]
    for f in frames:
        np.savetxt(tmp_path / f"fluid_{f:04d}.xyz", blob(3000, f))
        np.savetxt(tmp_path / f"shell_{f:04d}.xyz", fibonacci_sphere(1500 + 100 * f))
    done = []
    s = pmd.map_frames(client, "polygonize", tmp_path / "fluid_{:04d}.xyz",
                       tmp_path / "out" / "fluid_{:04d}.ply", radius=0.25, threshold=2.5,
                       progress=lambda i, n: done.append((i, n)))
    assert s.ok and [d["frame"] for d in s.done] == frames and not s.failed, str(s)
    assert done[-1] == (3, 3)
    t = pmd.map_frames(client, "triangulate", str(tmp_path / "shell_{:04d}.xyz"),
                       str(tmp_path / "out" / "shell_{:04d}.obj"), frames=frames, fill_holes=50)
    assert t.ok, str(t)
    for f in frames:
        cli("polygonize", tmp_path / f"fluid_{f:04d}.xyz", "-o", tmp_path / "cli.ply",
            "--radius", 0.25, "--threshold", 2.5, "-q")
        assert (tmp_path / "out" / f"fluid_{f:04d}.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
        cli("triangulate", tmp_path / f"shell_{f:04d}.xyz", "-o", tmp_path / "cli.obj",
            "--fill-holes", 50, "-q")
        assert (tmp_path / "out" / f"shell_{f:04d}.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    assert pmd.find_frames(tmp_path / "fluid_{:04d}.xyz") == frames
    # Particles with a channel (velocity): both meshes carry it on their vertices, byte for
    # byte (the package's write_mesh once left every attribute out).
    for f in frames:
        points = blob(3000, f)
        velocity = np.round(np.random.default_rng(f).normal(size=points.shape), 3)
        np.savetxt(tmp_path / f"chan_{f}.xyz", np.hstack([points, velocity]), header="x y z vx vy vz", comments="")
    v = pmd.map_frames(client, "polygonize", tmp_path / "chan_{}.xyz", tmp_path / "out" / "chan_{}.ply",
                       radius=0.25, threshold=2.5)
    assert v.ok, str(v)
    for f in frames:
        cli("polygonize", tmp_path / f"chan_{f}.xyz", "-o", tmp_path / "cli.ply", "--radius", 0.25,
            "--threshold", 2.5, "-q")
        written = (tmp_path / "cli.ply").read_bytes()
        assert b"property float velocity_0" in written
        assert (tmp_path / "out" / f"chan_{f}.ply").read_bytes() == written
    # A ParaView collection: frame n is its n-th file by time, whatever order it lists them in;
    # the outputs are the command-line tool's for the same collection, byte for byte.
    series = tmp_path / "fluid.xyz.series"
    series.write_text(json.dumps({"file-series-version": "1.0", "files": [
        {"name": "fluid_0005.xyz", "time": 0.2}, {"name": "fluid_0003.xyz", "time": 0.0},
        {"name": "fluid_0004.xyz", "time": 0.1}, {"name": "gone.xyz", "time": 0.3}]}))
    c = pmd.map_frames(client, "polygonize", series, tmp_path / "col" / "f_{}.ply", radius=0.25,
                       threshold=2.5)
    assert c.ok and [(d["frame"], Path(d["input"]).name) for d in c.done] == [
        (0, "fluid_0003.xyz"), (1, "fluid_0004.xyz"), (2, "fluid_0005.xyz")], str(c)
    assert c.missing == [3] and "1 missing (no file): 3" in str(c)  # gone.xyz
    (tmp_path / "cli").mkdir()
    cli("polygonize", series, "-o", tmp_path / "cli" / "f_{}.ply", "--radius", 0.25, "--threshold", 2.5, "-q")
    for n in range(3):
        assert (tmp_path / "col" / f"f_{n}.ply").read_bytes() == (tmp_path / "cli" / f"f_{n}.ply").read_bytes()
    with pytest.raises(ValueError, match="frame 4 is not one of the 4 frames"):
        pmd.map_frames(client, "polygonize", series, tmp_path / "col" / "g_{}.ply", frames=[4])


def flaky_once(source, output):
    """A frame command that fails on its first attempt (the marker file says which)."""
    marker = Path(output + ".tried")
    if not marker.exists():
        marker.write_text("1")
        raise RuntimeError("first attempt fails")
    Path(output).write_text(Path(source).read_text())
    return {"vertices": 0, "triangles": 0}


def test_a_failed_frame_is_retried_once_then_reported_and_the_others_go_on(pmd, client, tmp_path):
    for f in range(4):
        np.savetxt(tmp_path / f"in_{f}.xyz", fibonacci_sphere(800))
    (tmp_path / "in_2.xyz").write_text("1 2\nnot a number\n")  # broken twice: reported
    s = pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "out_{}.ply")
    assert [d["frame"] for d in s.done] == [0, 1, 3]
    assert [f["frame"] for f in s.failed] == [2] and not s.ok
    assert "in_2.xyz" in s.failed[0]["error"] and "Error" in s.failed[0]["error"]
    assert not (tmp_path / "out_2.ply").exists() and (tmp_path / "out_3.ply").stat().st_size > 0
    assert "frame 2:" in str(s)
    # Fails once, succeeds on the retry.
    r = pmd.map_frames(client, flaky_once, tmp_path / "in_{}.xyz", str(tmp_path / "copy_{}.xyz"),
                       frames=[0, 1])
    assert r.ok and [d["frame"] for d in r.done] == [0, 1], str(r)
    assert (tmp_path / "copy_1.xyz").read_text() == (tmp_path / "in_1.xyz").read_text()
    # Resuming: frames with outputs are left alone.
    again = pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "out_{}.ply",
                           skip_existing=True)
    assert again.skipped == [0, 1, 3] and [f["frame"] for f in again.failed] == [2]


def test_frames_without_a_file_are_missing_as_the_cli_says(pmd, client, cli, tmp_path):
    """A gap among the files found, or a frame asked for without its file, is not run: it is
    listed as missing (the command-line tool's frames), not failed; the others are meshed."""
    for f in (1, 2, 4, 7):
        np.savetxt(tmp_path / f"in_{f}.xyz", fibonacci_sphere(600 + 50 * f))
    s = pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "out_{}.ply")
    assert s.ok and [d["frame"] for d in s.done] == [1, 2, 4, 7] and not s.failed, str(s)
    assert s.missing == [3, 5, 6] and "3 missing (no file): 3, 5, 6" in str(s)
    proc = cli("triangulate", tmp_path / "in_{}.xyz", "-o", tmp_path / "cli_{}.ply")
    assert "3 missing frames skipped (no file): 3, 5, 6" in proc.stderr, proc.stderr
    for f in (1, 2, 4, 7):
        assert (tmp_path / f"out_{f}.ply").read_bytes() == (tmp_path / f"cli_{f}.ply").read_bytes()
    t = pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "again_{}.ply",
                       frames=[9, 2, 3])
    assert t.ok and [d["frame"] for d in t.done] == [2] and t.missing == [9, 3], str(t)
    assert not (tmp_path / "again_9.ply").exists() and not (tmp_path / "again_3.ply").exists()
    # A function's frames too; none with a file is an error before anything runs.
    u = pmd.map_frames(client, flaky_once, tmp_path / "in_{}.xyz", str(tmp_path / "copy_{}.xyz"),
                       frames=[3, 4])
    assert [d["frame"] for d in u.done] == [4] and u.missing == [3], str(u)
    with pytest.raises(FileNotFoundError, match="no input file exists"):
        pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "o_{}.ply",
                       frames=[3, 5])


def test_map_frames_refuses_bad_patterns_and_options_before_running(pmd, client, tmp_path):
    with pytest.raises(ValueError, match="frame field"):
        pmd.map_frames(client, "triangulate", tmp_path / "in.xyz", tmp_path / "out_{}.ply")
    with pytest.raises(ValueError, match="frame field"):
        pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "out.ply", frames=[1, 2])
    with pytest.raises(FileNotFoundError, match="no file matches"):
        pmd.map_frames(client, "triangulate", tmp_path / "none_{}.xyz", tmp_path / "out_{}.ply")
    with pytest.raises(TypeError, match="radius"):
        pmd.map_frames(client, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "o_{}.ply",
                       frames=[1], radius=2)
    with pytest.raises(ValueError, match="command"):
        pmd.map_frames(client, "smooth", tmp_path / "in_{}.xyz", tmp_path / "o_{}.ply", frames=[1])
    with pytest.raises(TypeError, match="Client"):
        pmd.map_frames(None, "triangulate", tmp_path / "in_{}.xyz", tmp_path / "o_{}.ply", frames=[1])


# ---- polygonize in tiles -------------------------------------------------------------------

def test_nesting_pairs_are_every_pair_of_nested_boxes(pmd):
    """The driver pairs closed components whose boxes nest (an enclosing part and each part
    inside its box), by a sort on the boxes' low x: the same pairs as testing every pair, on
    random boxes with shared faces, open components, pieces of one component and parts
    without a point."""
    from particlemesh.distributed._seams import Stitch
    rng = np.random.default_rng(5)
    n = 400
    st = Stitch.__new__(Stitch)
    st.n_pieces = n
    st.root = np.arange(n)
    st.root[300:] = rng.integers(0, 300, 100)  # pieces joined to another component
    st.comp_open = rng.random(n) < 0.1
    st.extra = np.zeros((0, 3), dtype=np.int64)
    lo = np.round(rng.uniform(0, 10, (n, 3)), 1)  # a coarse grid: equal faces are common
    hi = lo + np.round(rng.uniform(0.1, 6, (n, 3)), 1)
    query = np.where(rng.random((n, 1)) < 0.9, lo + 0.01, np.nan)
    pairs = st.nesting_pairs(lo, hi, query)
    # Brute force: each component's box is the union of its pieces'.
    clo, chi = np.full((n, 3), np.inf), np.full((n, 3), -np.inf)
    np.minimum.at(clo, st.root, lo)
    np.maximum.at(chi, st.root, hi)
    roots = [c for c in range(n) if st.root[c] == c and not st.comp_open[c]]
    has_point = {c for c in roots if np.isfinite(query[st.root == c][:, 0]).any()}
    expect = {}
    for d in roots:
        inner = [c for c in roots if c != d and c in has_point and
                 (clo[c] >= clo[d]).all() and (chi[c] <= chi[d]).all()]
        if inner:
            expect[d] = inner
    assert sum(len(v) for v in expect.values()) > 50  # the case is not trivial
    assert {d: list(c) for d, (c, _) in pairs.items()} == expect
    for d, (c, pts) in pairs.items():  # each inner part's point is its first piece's
        for ci, q in zip(c, pts):
            assert np.array_equal(q, query[np.flatnonzero((st.root == ci) & np.isfinite(query[:, 0]))[0]])


def test_unpinch_keeps_the_largest_fan_at_each_pinched_vertex(pmd):
    """A vertex whose triangles meet only through it keeps its largest fan; a closed surface
    and a disk lose nothing."""
    from particlemesh.distributed._seams import unpinch
    octahedron = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                           [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    keep, touched = unpinch(octahedron)
    assert keep.all() and len(touched) == 0
    # Vertex 0: a fan of three triangles (0 1 2, 0 2 3, 0 3 4) and a lone one (0 5 6) beside.
    bowtie = np.array([[0, 5, 6], [0, 1, 2], [0, 2, 3], [0, 3, 4]])
    keep, touched = unpinch(bowtie)
    assert keep.tolist() == [False, True, True, True] and touched.tolist() == [0, 5, 6]
    # Two fans of one triangle each: the one listed first stays.
    keep, _ = unpinch(np.array([[0, 1, 2], [0, 3, 4]]))
    assert keep.tolist() == [True, False]


def assert_identical(tiled, one):
    assert tiled.vertex_count == one.vertex_count > 0
    assert same_arrays(tiled.vertices, one.vertices)
    assert same_arrays(tiled.normals, one.normals)
    assert same_arrays(tiled.triangles, one.triangles)


def test_polygonize_tiled_is_the_one_machine_mesh_bit_for_bit(pm, pmd, client):
    p = blob(40000, 1)
    one = pmd.canonical_mesh(pm.polygonize(p))  # default radius: the whole cloud's spacing
    tiled = pmd.polygonize_tiled(client, p, tiles=(2, 2, 1))
    assert_identical(tiled, one)
    assert tiled.stats["origin"] == one.stats["origin"]  # the library reports its lattice
    assert tiled.stats["bytes_sent"] > 0 and len(tiled.stats["tile_particles"]) == 4
    # An odd tiling, a kernel, per-particle radii and strengths: the same.
    rng = np.random.default_rng(7)
    radii, strengths = rng.uniform(0.08, 0.16, len(p)), rng.uniform(0.5, 2.0, len(p))
    one = pmd.canonical_mesh(pm.polygonize(p, radii=radii, strengths=strengths, kernel="poly6"))
    tiled = pmd.polygonize_tiled(client, p, tiles=(3, 1, 2), radii=radii, strengths=strengths,
                                 kernel="poly6")
    assert_identical(tiled, one)
    # Two particles 15 times larger than the rest: the whole cloud keeps them apart from its
    # particle grid's cells (particle_grid_radius), and so does every tile.
    radii[[5, 15000]] = 1.8, 2.4
    assert pm.particle_grid_radius(radii) == radii[radii < 1].max()
    one = pmd.canonical_mesh(pm.polygonize(p, radii=radii, strengths=strengths, kernel="poly6"))
    tiled = pmd.polygonize_tiled(client, p, tiles=(2, 1, 2), radii=radii, strengths=strengths,
                                 kernel="poly6")
    assert_identical(tiled, one)


def test_polygonize_tiles_are_the_whole_clouds_cells(pm):
    """The library's tile options alone: two tiles' meshes hold exactly the whole mesh's
    triangles (none twice) and share their seam vertices bit for bit."""
    p = blob(20000, 2)
    whole = pm.polygonize(p, radius=0.15)
    lo, h = p.min(axis=0), whole.stats["cell_size"]
    origin = np.asarray(whole.stats["origin"])
    assert np.array_equal(origin, (lo - 0.15) - 9 * h)
    cut = int(round((0.0 - origin[0]) / h))
    far = 2 ** 40
    meshes = []
    for cells in (((-far, -far, -far), (cut, far, far)), ((cut, -far, -far), (far, far, far))):
        x0, x1 = origin[0] + cells[0][0] * h, origin[0] + cells[1][0] * h
        keep = (p[:, 0] >= x0 - 0.15 - h) & (p[:, 0] <= x1 + 0.15 + h)
        meshes.append(pm.polygonize(p[keep], radius=0.15, domain_min=lo, cells=cells))
    as_set = lambda m: {tuple(sorted(map(tuple, m.vertices[t]))) for t in m.triangles}
    a, b = as_set(meshes[0]), as_set(meshes[1])
    assert not (a & b) and (a | b) == as_set(whole)
    seam = {tuple(v) for v in meshes[0].vertices} & {tuple(v) for v in meshes[1].vertices}
    assert seam and all(abs(v[0] - (origin[0] + cut * h)) < 1e-9 for v in seam)
    with pytest.raises(pm.Error, match="domain_min.x"):
        pm.polygonize(p, radius=0.15, domain_min=lo + [0.5, 0, 0])
    with pytest.raises(pm.Error, match="empty"):
        pm.polygonize(p, radius=0.15, cells=((0, 0, 0), (0, 5, 5)))


def test_polygonize_tiled_from_a_loader_never_holds_the_cloud(pm, pmd, client):
    """A loader that makes a tile's particles on the worker (a jittered lattice, in global
    lattice order): the driver never has them; the result is the one-machine mesh."""
    loader = JitteredLattice(spacing=0.05, size=(28, 20, 12))
    p = loader(np.full(3, -np.inf), np.full(3, np.inf))
    one = pmd.canonical_mesh(pm.polygonize(p, radius=0.1))
    tiled = pmd.polygonize_tiled(client, loader, tiles=(2, 2, 1), radius=0.1,
                                 bounds=(p.min(axis=0), p.max(axis=0)))
    assert_identical(tiled, one)
    assert tiled.stats["bytes_sent"] < 1000  # only the loader and the boxes travel
    with pytest.raises(pm.Error, match="bounds"):
        pmd.polygonize_tiled(client, loader, radius=0.1)
    with pytest.raises(pm.Error, match="radius"):
        pmd.polygonize_tiled(client, loader, bounds=(p.min(axis=0), p.max(axis=0)))


class JitteredLattice:
    """Particles of a jittered cubic lattice, made for any box on demand (each lattice point's
    jitter from its index), listed in lattice order: a loader over a cloud that exists
    nowhere whole."""

    def __init__(self, spacing, size):
        self.h, self.size = spacing, np.asarray(size)

    def __call__(self, lo, hi):
        a = np.clip(np.floor(np.asarray(lo) / self.h) - 1, 0, self.size).astype(int)
        b = np.clip(np.ceil(np.asarray(hi) / self.h) + 1, 0, self.size).astype(int)
        i, j, k = np.meshgrid(*(np.arange(a[d], b[d]) for d in range(3)), indexing="ij")
        idx = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1)
        flat = (idx[:, 0] * self.size[1] + idx[:, 1]) * self.size[2] + idx[:, 2]
        order = np.argsort(flat)
        idx, flat = idx[order], flat[order]
        jitter = ((flat[:, None] * [0.61803, 0.41421, 0.73205]) % 1.0 - 0.5) * 0.4
        return (idx + jitter) * self.h


# ---- triangulate in tiles ------------------------------------------------------------------

@pytest.fixture(scope="module")
def torus(cli, tmp_path_factory):
    path = tmp_path_factory.mktemp("torus") / "torus.ply"
    cli("sample", "torus", "--spacing", 0.02, "-o", path, "-q")
    return path


def check_surface(pm, tiled, one):
    top, ref = pm.topology(tiled), pm.topology(one)
    assert ref["closed"] and ref["manifold"]  # the one-machine surface the tiles must match
    for key in ("closed", "manifold", "consistently_oriented", "outward"):
        assert top[key] == ref[key], (key, top, tiled.stats)
    assert top["vertices_used"] == ref["vertices_used"], tiled.stats
    assert top["components"] == ref["components"]
    assert top["euler_characteristic"] == ref["euler_characteristic"]
    assert tiled.stats["unused_points"] == one.stats["unused_points"]
    # Every vertex normal faces as the surface winds (outward).
    assert np.allclose(np.linalg.norm(tiled.normals, axis=1), 1.0)


def test_triangulate_tiled_is_manifold_closed_and_uses_every_particle(pm, pmd, client, torus):
    sphere, ring = fibonacci_sphere(12000), pm.read_points(torus).positions
    # The sphere's normals face out above z = 0 and in below: they orient the two halves'
    # tiles opposite ways (the stitching turns them to agree, the sphere faces outward as on
    # one machine). The torus's tiles choose differently at the seams (holes to close).
    flipped = sphere * np.where(sphere[:, 2] >= 0, 1.0, -1.0)[:, None]
    for points, normals, tiles in ((sphere, flipped, (2, 1, 2)), (ring, None, (1, 1, 3)),
                                   (ring, None, (3, 2, 1))):
        one = pm.triangulate(points, normals)
        tiled = pmd.triangulate_tiled(client, points, tiles=tiles, normals=normals)
        check_surface(pm, tiled, one)
        assert tiled.stats["seam_triangles"] > 0 and tiled.stats["pieces"] >= np.prod(tiles)
        assert same_arrays(tiled.vertices, points)  # vertex i is particle i
        # Most triangles are the one-machine ones; the seams differ by little.
        as_set = lambda m: {tuple(sorted(t)) for t in m.triangles.tolist()}
        common = len(as_set(tiled) & as_set(one)) / one.triangle_count
        assert common > 0.97, common
        # Normals agree with the one-machine surface's.
        assert np.median(np.einsum("ij,ij->i", tiled.normals, one.normals)) > 0.99


def test_triangulate_tiled_keeps_an_open_surface_open_and_facing_as_one_machine(pm, pmd, client):
    s = fibonacci_sphere(16000)
    band = s[np.abs(s[:, 2]) < 0.5]  # two boundary loops, a real opening each
    one = pm.triangulate(band)
    tiled = pmd.triangulate_tiled(client, band, tiles=(2, 1, 2))
    top, ref = pm.topology(tiled), pm.topology(one)
    for key in ("closed", "manifold", "consistently_oriented", "boundary_loops", "vertices_used"):
        assert top[key] == ref[key], key
    assert not top["closed"] and top["boundary_loops"] == 2
    assert np.median(np.einsum("ij,ij->i", tiled.normals, one.normals)) > 0.99


def test_triangulate_tiled_turns_a_surface_closed_but_for_small_holes_outward_as_one_machine(pm, pmd, client):
    """A teardrop with three holes (test_particlemesh.teardrop): one machine judges it with
    its holes capped, the stitched surface by the normal at its highest particle (its sharp
    tip); both face outward."""
    from test_particlemesh import signed_volume, teardrop
    p = teardrop()
    one = pm.triangulate(p)
    assert one.stats["nearly_closed_turned"] == 1
    for tiles in ((2, 2, 1), (1, 2, 2)):
        tiled = pmd.triangulate_tiled(client, p, tiles=tiles)
        assert signed_volume(tiled) == pytest.approx(signed_volume(one), rel=1e-3), tiles
        assert np.median(np.einsum("ij,ij->i", tiled.normals, one.normals)) > 0.99


def test_triangulate_tiled_leaves_no_pinched_vertex_at_the_seams(pm, pmd, client):
    """A depth frame (test_particlemesh.depth_frame: a wall and a ball in front of it) cut in
    four: where seam triangles of two tiles met at a corner only, the stitched surface had a
    pinched vertex (two on this frame). The largest fan stays there, as one machine's repair
    leaves it: a manifold, with the one-machine result's pieces."""
    from test_particlemesh import depth_frame
    p = depth_frame(0.002)
    one = pm.topology(pm.triangulate(p))
    tiled = pmd.triangulate_tiled(client, p, tiles=(2, 2, 1))
    top = pm.topology(tiled)
    assert top["manifold"] and top["nonmanifold_vertices"] == 0, top
    assert top["consistently_oriented"] and one["manifold"]
    assert 1 <= tiled.stats["pinch_triangles_removed"] <= 4
    assert abs(top["components"] - one["components"]) <= 1
    n = np.linalg.norm(tiled.normals[np.unique(tiled.triangles)], axis=1)
    assert np.allclose(n, 1)


def test_triangulate_tiled_removes_small_pieces_of_the_stitched_surface(pm, pmd, client):
    """min_component_triangles applies to the stitched surface, as one machine removes them:
    the sphere's pieces in each tile (cut by the seams, some of them small) all stay, the lone
    triangles apart from it go."""
    s = fibonacci_sphere(6000)
    r0 = np.sqrt(4 * np.pi / 6000)
    lone = [[3 * np.cos(k), 3 * np.sin(k), 0.0] for k in range(4)]
    lone = np.concatenate([np.array(p) + np.array([[0, 0, 0], [r0, 0, 0], [r0 / 2, 0.87 * r0, 0]])
                           for p in lone])
    points = np.concatenate([s, lone])
    one = pm.triangulate(points, min_component_triangles=2)
    assert one.stats["components_removed"] == 4
    tiled = pmd.triangulate_tiled(client, points, tiles=(2, 2, 1), min_component_triangles=2)
    assert tiled.stats["components_removed"] == 4 and tiled.stats["component_triangles_removed"] == 4
    top = pm.topology(tiled)
    assert top["components"] == 1 and top["closed"] and top["manifold"]
    assert top["vertices_used"] == len(s) == pm.topology(one)["vertices_used"]
    kept = pmd.triangulate_tiled(client, points, tiles=(2, 2, 1))
    assert pm.topology(kept)["components"] == 5 and kept.stats["components_removed"] == 0


def test_triangulate_tiled_from_a_loader(pm, pmd, client, torus):
    pts = pm.read_points(torus)
    loader = pmd.files_loader([torus])
    lo, hi = pts.positions.min(axis=0), pts.positions.max(axis=0)
    one = pm.triangulate(pts)
    tiled = pmd.triangulate_tiled(client, loader, tiles=(2, 2, 1), bounds=(lo, hi),
                                  spacing=one.stats["spacing"])
    check_surface(pm, tiled, one)
    # The vertices are the particles, tile by tile.
    assert sorted(map(tuple, tiled.vertices)) == sorted(map(tuple, pts.positions))


def test_triangulate_tiled_turns_a_cavitys_wall_into_it_as_one_machine(pm, pmd, client):
    # A hollow ball with a marble in its cavity, every surface cut by the tiles: the cavity's
    # wall must face into the cavity (negative volume) and the marble out, as one machine
    # orients them. The tiles hold the enclosing surfaces' triangles, so which part lies
    # inside which is counted on them (the rays' crossings added up with the seams').
    pts = np.concatenate([fibonacci_sphere(12000), fibonacci_sphere(5880, 0.7),
                          fibonacci_sphere(1080, 0.3) + [0.1, 0, 0]])
    parts = [(0, 12000), (12000, 17880), (17880, len(pts))]
    one = pm.triangulate(pts)
    ref = pm.topology(one)
    assert ref["closed_components"] == 3 and ref["outward"]

    def faces_as_one_machine(tiled):
        top = pm.topology(tiled)
        for key in ("closed", "manifold", "consistently_oriented", "outward", "closed_components"):
            assert top[key] == ref[key], (key, top, tiled.stats)
        dots = np.einsum("ij,ij->i", tiled.normals, one.normals)
        for a, b in parts:  # the cavity's wall too
            assert np.median(dots[a:b]) > 0.99, (a, b)
        assert tiled.stats["nested_components"] == 2  # the wall (depth 1), the marble (2)
        assert tiled.stats["nesting_tests"] == 3

    faces_as_one_machine(pmd.triangulate_tiled(client, pts, tiles=(2, 2, 1)))
    # From a loader whose ids are not in the cloud's order: the tiles number the triangles
    # they count by final id, as the stitched surface does.
    perm = np.random.default_rng(5).permutation(len(pts))
    inverse = np.argsort(perm)  # particle perm[j] is vertex j: particle i is vertex inverse[i]

    def loader(lo, hi):
        inside = np.flatnonzero(((pts >= lo) & (pts <= hi)).all(axis=1))
        return {"positions": pts[inside], "ids": inverse[inside]}

    tiled = pmd.triangulate_tiled(client, loader, tiles=(1, 2, 2), bounds=(pts.min(axis=0), pts.max(axis=0)),
                                  spacing=one.stats["spacing"])
    assert np.array_equal(tiled.vertices, pts[perm])
    # Back in the cloud's order, so that the normals compare with one machine's.
    back = pm.Mesh(pts, perm[tiled.triangles], tiled.normals[inverse])
    back.stats = tiled.stats
    faces_as_one_machine(back)


def test_a_cluster_started_as_the_docs_say(pm, pmd, tmp_path):
    """`dask scheduler` and `dask worker` (docs/distributed.md), the package on the worker's
    PYTHONPATH: a frame and a tiled call run there."""
    dask = Path(sys.executable).parent / "dask"
    assert dask.is_file(), f"{dask}: the dask command (python3-distributed) is missing"
    env = dict(os.environ, PYTHONPATH=str(Path(pm.__file__).parents[1]))
    sched = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--dashboard-address", ":0", "--scheduler-file", str(sched)],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        procs.append(subprocess.Popen([str(dask), "worker", "--scheduler-file", str(sched),
                                       "--nworkers", "1", "--nthreads", "1", "--memory-limit", "0",
                                       "--local-directory", str(tmp_path / "w")],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        import time
        deadline = time.monotonic() + 60
        while not sched.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        with Client(scheduler_file=str(sched), timeout=60) as c:
            c.wait_for_workers(1, timeout=60)
            np.savetxt(tmp_path / "f_1.xyz", blob(2000, 1))
            s = pmd.map_frames(c, "polygonize", tmp_path / "f_{}.xyz", tmp_path / "f_{}.ply",
                               radius=0.25)
            assert s.ok and (tmp_path / "f_1.ply").stat().st_size > 0, str(s)
            p = blob(8000, 2)
            tiled = pmd.polygonize_tiled(c, p, tiles=(2, 1, 1), radius=0.2)
            assert_identical(tiled, pmd.canonical_mesh(pm.polygonize(p, radius=0.2)))
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            proc.wait(timeout=30)


def test_tiled_calls_refuse_bad_arguments(pm, pmd, client):
    p = fibonacci_sphere(500)
    with pytest.raises(pm.Error, match="tiles"):
        pmd.triangulate_tiled(client, p, tiles=(0, 1, 1))
    with pytest.raises(pm.Error, match="raw"):
        pmd.triangulate_tiled(client, p, raw=True)
    with pytest.raises(pm.Error, match="halo"):
        pmd.triangulate_tiled(client, p, halo=1)
    with pytest.raises(TypeError, match="bogus"):
        pmd.triangulate_tiled(client, p, bogus=1)
    with pytest.raises(TypeError, match="bogus"):
        pmd.polygonize_tiled(client, p, bogus=1)
    for key in ("anisotropic", "min_component_particles", "collapse_edges", "taubin_iterations"):
        with pytest.raises(pm.Error, match=f"does not support {key}"):
            pmd.polygonize_tiled(client, p, radius=0.1, **{key: 0.3 if key == "collapse_edges" else 1})
    with pytest.raises(pm.Error, match=r"positions\[3\].y"):
        q = p.copy()
        q[3, 1] = np.nan
        pmd.polygonize_tiled(client, q, radius=0.1)
