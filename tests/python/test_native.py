"""The add-on's ctypes binding (native.py) outside Blender: loading, signatures, numpy buffers
in and out, errors as exceptions with the library's message, progress and cancellation, and
handles freed on every path."""
import ctypes
import re
import threading
from pathlib import Path

import numpy as np
import pytest

from conftest import load_native_module


def fibonacci_sphere(n, radius=1.0):
    i = np.arange(n, dtype=np.float64) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / n)
    theta = np.pi * (1.0 + 5.0 ** 0.5) * i
    p = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)
    return (radius * p).astype(np.float32)


def edge_lengths(positions, triangles):
    p = positions.astype(np.float64)
    t = triangles
    return np.concatenate([np.linalg.norm(p[t[:, a]] - p[t[:, b]], axis=1)
                           for a, b in ((0, 1), (1, 2), (2, 0))])


# ---- loading ----------------------------------------------------------------------------------

def test_loads_and_checks_abi_version(native):
    lib = native.load()
    assert lib.abi_version == native.ABI_VERSION == 1
    assert lib.version.count(".") >= 1
    ok, version = native.available()
    assert ok and version == lib.version


def test_every_function_has_a_declared_signature(native):
    lib = native.load()
    for name, (restype, argtypes) in native._REQUIRED.items():
        fn = getattr(lib.cdll, name)
        assert fn.argtypes == argtypes, name
        assert fn.restype == restype, name
    for name in native._OPTIONAL:
        if lib.has(name):
            assert getattr(lib.cdll, name).argtypes is not None, name


def test_abi_mismatch_is_refused(native, monkeypatch):
    other = load_native_module("pm_native_abi_check")
    monkeypatch.setattr(other, "ABI_VERSION", 999)
    with pytest.raises(other.LibraryNotFoundError, match="ABI version 1; this add-on needs version 999"):
        other.load(native.load().path)


def test_missing_library_gives_a_clear_message(native, monkeypatch, tmp_path):
    other = load_native_module("pm_native_missing")
    monkeypatch.setenv("PARTICLEMESH_LIBRARY", str(tmp_path / "libparticlemesh.so"))
    with pytest.raises(other.LibraryNotFoundError, match="does not exist"):
        other.load()
    ok, why = other.available()
    assert not ok and "libparticlemesh.so" in why
    # A file that is not a shared library.
    bogus = tmp_path / "bogus.so"
    bogus.write_text("not a library")
    monkeypatch.setenv("PARTICLEMESH_LIBRARY", str(bogus))
    with pytest.raises(other.LibraryNotFoundError, match="cannot load"):
        other.load()


def test_library_override_is_used(native, monkeypatch):
    other = load_native_module("pm_native_override")
    path = native.load().path
    monkeypatch.setenv("PARTICLEMESH_LIBRARY", path)
    assert other._candidate_paths() == [path]
    assert other.load().path == path


def test_imports_without_bpy():
    import sys
    load_native_module("pm_native_nobpy")
    assert "bpy" not in sys.modules


# ---- triangulation ----------------------------------------------------------------------------

def test_triangulate_sphere_vertices_are_the_particles(native):
    p = fibonacci_sphere(3000)
    mesh = native.triangulate(p)
    assert mesh.positions.dtype == np.float32 and mesh.positions.shape == (3000, 3)
    assert mesh.triangles.dtype == np.int32 and mesh.triangles.shape[1] == 3
    np.testing.assert_array_equal(mesh.positions, p)  # output vertex i is particle i
    assert mesh.triangles.min() >= 0 and mesh.triangles.max() < 3000
    s = mesh.stats
    assert s["points"] == 3000 and s["spacing_estimated"] == 1 and not s["raw"]
    assert s["max_edge"] == pytest.approx(2.0 * s["spacing"])
    assert s["unused_points"] == 0 and s["holes_left"] == 0
    # The finished surface of a sphere: closed, manifold, outward, genus 0, F = 2V - 4.
    rep = native.mesh_report(mesh.positions, mesh.triangles)
    assert rep["closed"] and rep["manifold"] and rep["consistently_oriented"] and rep["outward"]
    assert rep["euler_characteristic"] == 2 and rep["components"] == 1
    assert mesh.triangle_count == 2 * 3000 - 4
    assert s["kept"] >= mesh.triangle_count  # the seed's test keeps more (overlaps, slivers)
    # Its normals: unit, outward, from the faces.
    assert mesh.normals is not None
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    assert (np.einsum("ij,ij->i", mesh.normals, p) > 0.99).all()


def test_raw_is_the_seeds_triangle_set(native):
    p = fibonacci_sphere(3000)
    raw = native.triangulate(p, raw=True)
    s = raw.stats
    assert s["raw"] and s["kept"] == raw.triangle_count
    assert s["holes_filled"] == 0 and s["unused_points"] == 0
    assert edge_lengths(raw.positions, raw.triangles).max() <= s["max_edge"] * (1 + 1e-5)
    assert (np.sort(raw.triangles, axis=1) == raw.triangles).all()  # canonical, not oriented
    assert raw.triangle_count > native.triangulate(p).triangle_count


def test_triangulate_options_reach_the_library(native):
    p = fibonacci_sphere(2000)
    mesh = native.triangulate(p, spacing=0.1, max_edge_factor=1.5, raw=True)
    assert mesh.stats["spacing"] == pytest.approx(0.1)
    assert not mesh.stats["spacing_estimated"]
    assert mesh.stats["max_edge"] == pytest.approx(0.15)
    assert edge_lengths(mesh.positions, mesh.triangles).max() <= 0.15 * (1 + 1e-5)
    tight = native.triangulate(p, spacing=0.1, max_edge_factor=0.5, raw=True)
    assert tight.triangle_count < mesh.triangle_count


def test_finishing_options_reach_the_library(native, data_dir):
    cloud = native.read_cloud(data_dir / "points/spot_poisson.ply")
    p, n = cloud.positions, cloud.normals
    full = native.triangulate(p, normals=n)
    rep = native.mesh_report(full.positions, full.triangles)
    assert rep["closed"] and rep["manifold"] and rep["outward"] and rep["euler_characteristic"] == 2
    assert full.stats["holes_filled"] > 0 and full.stats["holes_left"] == 0
    no_fill = native.triangulate(p, normals=n, fill_holes=0)
    assert no_fill.stats["holes_filled"] == 0 and no_fill.stats["holes_left"] > 0
    no_repair = native.triangulate(p, normals=n, repair=False)
    assert no_repair.stats["holes_filled"] == 0 and no_repair.triangle_count < full.triangle_count
    strict = native.triangulate(p, normals=n, normal_angle=30.0)
    assert strict.triangle_count != full.triangle_count
    unoriented = native.triangulate(p, normals=n, orient=False, normal_source="ESTIMATE")
    assert unoriented.triangle_count > 0
    with pytest.raises(native.ParticlemeshError):
        native.triangulate(p, fill_holes=-1)
    with pytest.raises(native.ParticlemeshError) as e:
        native.triangulate(p, normal_angle=-5.0)
    assert e.value.status == native.STATUS_INVALID_ARGUMENT


def test_threads_do_not_change_the_result(native):
    p = fibonacci_sphere(4000)
    a = native.triangulate(p, threads=1)
    b = native.triangulate(p, threads=2)
    np.testing.assert_array_equal(a.triangles, b.triangles)


def test_input_buffers_of_any_layout(native):
    p = fibonacci_sphere(1000)
    ref = native.triangulate(p).triangles
    np.testing.assert_array_equal(native.triangulate(p.astype(np.float64)).triangles, ref)
    np.testing.assert_array_equal(native.triangulate(p.ravel()).triangles, ref)  # flat x y z ...
    fortran = np.asfortranarray(p)
    np.testing.assert_array_equal(native.triangulate(fortran).triangles, ref)
    with pytest.raises(native.ParticlemeshError, match="shape"):
        native.triangulate(p[:, :2])
    with pytest.raises(native.ParticlemeshError, match="multiple of 3"):
        native.triangulate(p.ravel()[:-1])


def test_normals_are_passed_and_returned(native):
    p = fibonacci_sphere(1500)
    raw = native.triangulate(p, normals=p, raw=True)
    np.testing.assert_allclose(raw.normals, p, atol=1e-6)  # raw: the particles' normals
    assert native.triangulate(p, raw=True).normals is None
    # Inward input normals turn the finished surface inward when they are followed as given.
    inward = native.triangulate(p, normals=-p, normal_source="INPUT", orient=False)
    rep = native.mesh_report(inward.positions, inward.triangles)
    assert rep["closed"] and not rep["outward"]


def test_real_scan_from_shared_data(native, data_dir):
    cloud = native.read_cloud(data_dir / "points/spot_poisson.ply")
    assert cloud.positions.shape == (8747, 3)
    assert cloud.normals is not None and cloud.normals.shape == (8747, 3)
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-4)
    mesh = native.triangulate(cloud.positions)
    assert mesh.vertex_count == 8747
    # Poisson-disk r0 = 0.02: the estimated spacing is the median NN distance, a bit above.
    assert 0.02 <= mesh.stats["spacing"] < 0.025
    rep = native.mesh_report(mesh.positions, mesh.triangles)
    assert rep["vertices_used"] == 8747
    assert rep["components"] == 1 and rep["closed"] and rep["outward"]
    assert mesh.triangle_count == 2 * 8747 - 4  # the cow is genus 0


# ---- errors -----------------------------------------------------------------------------------

def test_nan_names_the_index(native):
    p = fibonacci_sphere(100)
    p[42, 1] = np.nan
    with pytest.raises(native.ParticlemeshError) as e:
        native.triangulate(p)
    assert e.value.status == native.STATUS_INVALID_INPUT
    assert "positions[42].y" in str(e.value) and "NaN" in str(e.value)


def test_empty_and_tiny_inputs(native):
    with pytest.raises(native.ParticlemeshError, match="empty") as e:
        native.triangulate(np.zeros((0, 3), np.float32))
    assert e.value.status == native.STATUS_INVALID_INPUT
    with pytest.raises(native.ParticlemeshError):
        native.triangulate(np.zeros((1, 3), np.float32))


@pytest.mark.parametrize("kwargs", [
    {"max_edge_factor": -1.0},
    {"max_edge_factor": float("nan")},
    {"spacing": -0.5},
    {"spacing": float("inf")},
])
def test_absurd_parameters(native, kwargs):
    with pytest.raises(native.ParticlemeshError) as e:
        native.triangulate(fibonacci_sphere(200), **kwargs)
    assert e.value.status == native.STATUS_INVALID_ARGUMENT
    assert str(e.value)


def test_too_dense_for_the_spacing_is_a_limit(native):
    with pytest.raises(native.ParticlemeshError) as e:
        native.triangulate(fibonacci_sphere(3000), spacing=1.0)
    assert e.value.status == native.STATUS_LIMIT_EXCEEDED


def test_missing_file(native, tmp_path):
    with pytest.raises(native.ParticlemeshError) as e:
        native.read_cloud(tmp_path / "nope.ply")
    assert e.value.status == native.STATUS_IO_ERROR
    assert "nope.ply" in str(e.value)


# ---- progress and cancellation ----------------------------------------------------------------

def test_progress_reports_stages(native):
    seen = []
    progress = native.Progress(lambda stage, f: seen.append((stage, f)))
    native.triangulate(fibonacci_sphere(20000), progress=progress)
    assert seen, "no progress reported"
    fractions = [f for _, f in seen]
    assert all(0.0 <= f <= 1.0 for f in fractions)
    assert fractions == sorted(fractions)
    assert all(stage for stage, _ in seen)


def test_callback_returning_false_cancels(native):
    progress = native.Progress(lambda stage, f: False)
    with pytest.raises(native.CancelledError):
        native.triangulate(fibonacci_sphere(20000), progress=progress)
    assert progress.cancelled


def test_cancel_from_another_thread(native):
    """How Blender's modal operator stops a worker: Esc calls cancel() on the UI thread."""
    progress = native.Progress()
    progress.cancel()  # before the first report: the call stops at its first callback
    result = {}

    def work():
        try:
            native.triangulate(fibonacci_sphere(50000), progress=progress)
            result["ok"] = True
        except native.CancelledError as e:
            result["cancelled"] = e

    t = threading.Thread(target=work)
    t.start()
    t.join(60)
    assert not t.is_alive()
    assert "cancelled" in result


def test_exception_in_callback_cancels_instead_of_crashing(native):
    def boom(stage, f):
        raise RuntimeError("bug in the host")

    progress = native.Progress(boom)
    with pytest.raises(native.CancelledError):
        native.triangulate(fibonacci_sphere(20000), progress=progress)
    assert isinstance(progress.error, RuntimeError)


# ---- handles ----------------------------------------------------------------------------------

class _Counting:
    def __init__(self, fn, counter, key):
        self.fn, self.counter, self.key = fn, counter, key

    def __call__(self, *args):
        self.counter[self.key] += 1
        return self.fn(*args)


def test_handles_are_freed_on_every_path(native, monkeypatch):
    lib = native.load()
    count = {"cloud+": 0, "cloud-": 0, "mesh+": 0, "mesh-": 0}
    for name, key in (("pm_cloud_create_f32", "cloud+"), ("pm_cloud_read", "cloud+"),
                      ("pm_cloud_destroy", "cloud-"), ("pm_triangulate", "mesh+"),
                      ("pm_mesh_create", "mesh+"), ("pm_mesh_read", "mesh+"),
                      ("pm_mesh_destroy", "mesh-")):
        monkeypatch.setattr(lib, name, _Counting(getattr(lib.cdll, name), count, key), raising=False)

    p = fibonacci_sphere(20000)
    native.triangulate(p)
    with pytest.raises(native.ParticlemeshError):
        native.triangulate(p, max_edge_factor=-1)          # fails inside pm_triangulate
    with pytest.raises(native.CancelledError):
        native.triangulate(p, progress=native.Progress(lambda s, f: False))
    mesh = native.triangulate(p[:500])
    native.mesh_report(mesh.positions, mesh.triangles)
    with pytest.raises(native.ParticlemeshError):
        native.mesh_report(mesh.positions, mesh.triangles + 10**6)  # bad index: create fails
    # pm_*_create / read that failed returned no handle; every handle that was made is freed.
    assert count["cloud+"] == 4 and count["cloud-"] == 4
    assert count["mesh-"] == 3  # two triangulations + one report; the failing create made none
    monkeypatch.undo()


# ---- meshes -----------------------------------------------------------------------------------

def tetrahedron():
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], np.float32)
    t = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], np.int32)
    return p, t


def test_report_of_a_closed_outward_tetrahedron(native):
    p, t = tetrahedron()
    rep = native.mesh_report(p, t)
    assert rep["closed"] and rep["manifold"] and rep["consistently_oriented"] and rep["outward"]
    assert rep["euler_characteristic"] == 2
    flipped = native.mesh_report(p, t[:, ::-1])
    assert flipped["closed"] and not flipped["outward"]


def test_mesh_write_read_roundtrip(native, tmp_path):
    p, t = tetrahedron()
    data = native.MeshData(p, t)
    for ext in ("ply", "obj"):
        path = tmp_path / f"tet.{ext}"
        native.write_mesh(data, path)
        back = native.read_mesh(path)
        np.testing.assert_allclose(back.positions, p)
        np.testing.assert_array_equal(back.triangles, t)


def test_read_xyz_with_normals(native, tmp_path):
    path = tmp_path / "pts.xyz"
    path.write_text("# comment\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n")
    cloud = native.read_cloud(path)
    np.testing.assert_allclose(cloud.positions, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_allclose(cloud.normals, [[0, 0, 1]] * 3)


def test_estimate_spacing(native):
    p = np.stack(np.meshgrid(np.arange(20), np.arange(20), [0.0]), -1).reshape(-1, 3) * 0.25
    assert native.estimate_spacing(p) == pytest.approx(0.25)
    assert native.estimate_spacing(p, max_samples=50) == pytest.approx(0.25)
    with pytest.raises(native.ParticlemeshError, match="max_samples"):
        native.estimate_spacing(p, max_samples=0)


def test_thin_keeps_an_even_subset(native):
    # A 0.25 grid thinned to 0.6: kept points at least 0.6 apart, every grid point within 0.6
    # of a kept one, the first point always kept, indices ascending.
    p = np.stack(np.meshgrid(np.arange(40), np.arange(40), [0.0]), -1).reshape(-1, 3) * 0.25
    idx = native.thin(p, 0.6)
    assert idx[0] == 0 and np.all(np.diff(idx) > 0) and idx[-1] < len(p)
    kept = p[idx]
    d = np.linalg.norm(kept[:, None] - kept[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 0.6
    assert np.linalg.norm(p[:, None] - kept[None], axis=-1).min(axis=1).max() < 0.6
    assert len(p) / 9 < len(idx) < len(p) / 4
    with pytest.raises(native.ParticlemeshError, match="min_distance") as e:
        native.thin(p, 0.0)
    assert e.value.status == native.STATUS_INVALID_ARGUMENT


def test_triangle_edges_number_every_corner(native):
    # A closed surface: E = 3T / 2, each edge once (a < b, ordered), every corner's edge joins
    # that corner to the next.
    data = native.triangulate(fibonacci_sphere(2000))
    tris = data.triangles
    edges, corners = native.triangle_edges(tris, data.vertex_count)
    assert edges.dtype == np.uint32 and corners.dtype == np.uint32
    assert 2 * len(edges) == 3 * len(tris)
    assert np.all(edges[:, 0] < edges[:, 1])
    key = edges[:, 0].astype(np.int64) * data.vertex_count + edges[:, 1]
    assert np.all(np.diff(key) > 0)
    a, b = tris.ravel(), np.roll(tris, -1, axis=1).ravel()
    np.testing.assert_array_equal(edges[corners], np.stack([np.minimum(a, b), np.maximum(a, b)], 1))
    with pytest.raises(native.ParticlemeshError, match="vertex index 2000") as e:
        native.triangle_edges(np.array([[0, 1, 2000]]), 2000)
    assert e.value.status == native.STATUS_INVALID_ARGUMENT


# ---- functions other issues add ---------------------------------------------------------------

def test_polygonize_when_available(native):
    if not native.has_polygonize():
        with pytest.raises(native.NotAvailableError, match="needs a newer particlemesh library"):
            native.polygonize(fibonacci_sphere(10))
        return
    # One particle: a closed sphere whose radius follows from the kernel and threshold.
    mesh = native.polygonize(np.zeros((1, 3), np.float32), radius=1.0, threshold=0.5,
                             cell_size=0.05)
    rep = native.mesh_report(mesh.positions, mesh.triangles)
    assert rep["closed"] and rep["manifold"] and rep["euler_characteristic"] == 2
    assert rep["outward"]
    r = np.linalg.norm(mesh.positions, axis=1)
    assert r.std() < 0.05 * r.mean()


def test_smooth_when_available(native):
    p, t = tetrahedron()
    if not native.has_smooth():
        with pytest.raises(native.NotAvailableError, match="needs a newer particlemesh library"):
            native.smooth(p, t)
        return
    for levels in (1, 2):
        out = native.smooth(p, t, scheme=native.SMOOTH_LOOP, levels=levels)
        assert out.triangle_count == 4 * 4 ** levels
        rep = native.mesh_report(out.positions, out.triangles)
        assert rep["closed"] and rep["euler_characteristic"] == 2
    bf = native.smooth(p, t, scheme=native.SMOOTH_BUTTERFLY, levels=1)
    np.testing.assert_allclose(bf.positions[:4], p, atol=1e-6)  # interpolating


# ---- the binding's structs against the header and the library ---------------------------------

HEADER = Path(__file__).resolve().parents[2] / "native/include/particlemesh/particlemesh.h"


def header_struct_fields(name):
    """Field names, in order, of `typedef struct name { ... } name;` in particlemesh.h."""
    text = HEADER.read_text()
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    m = re.search(r"typedef struct %s \{(.*?)\} %s;" % (name, name), text, flags=re.S)
    if not m:
        return None
    fields = []
    for decl in m.group(1).split(";"):
        decl = decl.strip()
        if not decl:
            continue
        decl = re.sub(r"\(\s*\*\s*(\w+)\s*\)\s*\(.*\)", r"\1", decl)  # function pointers
        decl = re.sub(r"\[\s*\d+\s*\]\s*$", "", decl)  # arrays: the name
        head, *rest = [d.strip() for d in decl.split(",")]
        fields.append(re.findall(r"(\w+)\s*$", head)[0])
        fields.extend(rest)
    return fields


STRUCTS = {"pm_triangulate_options": "TriangulateOptions",
           "pm_triangulate_stats": "TriangulateStats",
           "pm_topology_report": "TopologyReport",
           "pm_polygonize_options": "PolygonizeOptions",
           "pm_polygonize_stats": "PolygonizeStats",
           "pm_smooth_options": "SmoothOptions"}


@pytest.mark.parametrize("c_name", sorted(STRUCTS))
def test_structs_match_the_header(native, c_name):
    fields = header_struct_fields(c_name)
    if fields is None:
        pytest.skip(f"{c_name} is not in this particlemesh.h yet")
    ours = [f for f, _ in getattr(native, STRUCTS[c_name])._fields_]
    assert ours == fields


@pytest.mark.parametrize("init,struct", [("pm_triangulate_options_init", "TriangulateOptions"),
                                         ("pm_polygonize_options_init", "PolygonizeOptions"),
                                         ("pm_smooth_options_init", "SmoothOptions")])
def test_struct_sizes_match_the_library(native, init, struct):
    lib = native.load()
    if not lib.has(init):
        pytest.skip(f"{init} is not in this library")
    buffer = (ctypes.c_uint8 * 4096)()
    getattr(lib.cdll, init)(ctypes.cast(buffer, ctypes.POINTER(getattr(native, struct))))
    size = ctypes.c_uint32.from_buffer(buffer).value
    assert size == ctypes.sizeof(getattr(native, struct))


# ---- .pcd through the PCL bridge, colours read back (issue 6) ---------------------------------

@pytest.fixture
def bridge(native):
    import os
    if not os.environ.get("PARTICLEMESH_PCL_LIBRARY"):
        pytest.skip("PARTICLEMESH_PCL_LIBRARY is not set to the built libparticlemesh_pcl")
    return native.load_pcl()


def test_pcl_bridge_functions_have_declared_signatures(native, bridge):
    assert bridge.abi_version == native.PCL_ABI_VERSION == 1
    for name, (restype, argtypes) in native._PCL_FUNCTIONS.items():
        fn = getattr(bridge.cdll, name)
        assert fn.argtypes == argtypes and fn.restype == restype, name
    ok, path = native.has_pcd()
    assert ok and path == bridge.path


def test_read_pcd_with_normals_and_colours(native, bridge, data_dir):
    cloud = native.read_cloud(data_dir / "pcd/colored_cloud.pcd")
    assert cloud.positions.shape == (1000, 3) and cloud.positions.dtype == np.float32
    assert cloud.normals.shape == (1000, 3)
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-3)
    assert sorted(cloud.attributes) == ["color"]
    colour = cloud.attributes["color"]
    assert colour.shape == (1000, 3) and colour.dtype == np.float32
    assert colour.min() >= 0.0 and colour.max() <= 1.0 and np.ptp(colour) > 0.5
    # Every value is an 8-bit channel / 255.
    np.testing.assert_allclose(colour * 255.0, np.round(colour * 255.0), atol=1e-3)
    assert cloud.info["format"] == "pcd" and cloud.info["has_color"] and cloud.info["has_normals"]
    assert (cloud.info["width"], cloud.info["height"]) == (1, 1000)
    assert cloud.info["invalid_points"] == 0


def test_read_pcd_drops_nan_points_and_says_so(native, bridge, data_dir):
    for name in ("kinect_frame_20121214T142255.814212.pcd",
                 "kinect_frame_20121214T142255.814212_binary.pcd"):
        cloud = native.read_cloud(data_dir / "pcd" / name)
        assert len(cloud.positions) == 307200 - 35625, name
        assert np.isfinite(cloud.positions).all()
        assert cloud.normals is None
        assert cloud.attributes["color"].shape == (307200 - 35625, 3)
        assert cloud.info["invalid_points"] == 35625
        assert (cloud.info["width"], cloud.info["height"]) == (640, 480)
    compressed = native.read_cloud(data_dir / "pcd/milk.pcd")
    binary = native.read_cloud(data_dir / "pcd/milk_binary.pcd")
    np.testing.assert_array_equal(compressed.positions, binary.positions)
    assert len(binary.positions) == 13704 and binary.attributes == {}


def test_read_malformed_pcd_names_the_file(native, bridge, tmp_path):
    bad = tmp_path / "bad header.pcd"
    bad.write_text("VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0\n")
    with pytest.raises(native.ParticlemeshError, match="missing field 'z'") as e:
        native.read_cloud(bad)
    assert e.value.status == native.STATUS_FORMAT_ERROR
    assert str(bad) in str(e.value)
    with pytest.raises(native.ParticlemeshError, match="no such file") as e:
        native.read_cloud(tmp_path / "gone.pcd")
    assert e.value.status == native.STATUS_IO_ERROR and "gone.pcd" in str(e.value)


def test_missing_pcl_bridge_gives_a_clear_message(native, monkeypatch, tmp_path, data_dir):
    other = load_native_module("pm_native_no_bridge")
    # Nowhere to be found: one message saying what .pcd needs and where we looked.
    monkeypatch.delenv("PARTICLEMESH_PCL_LIBRARY", raising=False)
    monkeypatch.setattr(other, "_pcl_candidate_paths", lambda core: ([], [str(tmp_path)]))
    with pytest.raises(other.PclBridgeNotFoundError,
                       match=r"reading \.pcd needs the PCL bridge library libparticlemesh_pcl") as e:
        other.read_cloud(data_dir / "pcd/bun0.pcd")
    assert str(tmp_path) in str(e.value) and "PARTICLEMESH_PCL_LIBRARY" in str(e.value)
    ok, why = other.has_pcd()
    assert not ok and "PCL bridge" in why
    # Everything else still works without it.
    assert len(other.read_cloud(data_dir / "points/spot_poisson.ply").positions) == 8747
    # An override that does not exist / is not a library.
    monkeypatch.undo()
    monkeypatch.setenv("PARTICLEMESH_PCL_LIBRARY", str(tmp_path / "libparticlemesh_pcl.so"))
    with pytest.raises(other.PclBridgeNotFoundError, match="does not exist"):
        other.read_cloud(data_dir / "pcd/bun0.pcd")
    bogus = tmp_path / "bogus.so"
    bogus.write_text("not a library")
    monkeypatch.setenv("PARTICLEMESH_PCL_LIBRARY", str(bogus))
    with pytest.raises(other.PclBridgeNotFoundError, match="does not load"):
        other.read_cloud(data_dir / "pcd/bun0.pcd")


def test_ply_vertex_colours_are_read_back(native, tmp_path):
    p = fibonacci_sphere(20)
    rgb = np.random.default_rng(3).integers(0, 256, size=(20, 3), dtype=np.uint8)
    path = tmp_path / "coloured.ply"
    rec = np.zeros(20, dtype=[("p", "<f4", 3), ("c", "u1", 3)])
    rec["p"], rec["c"] = p, rgb
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 20\n"
                     b"property float x\nproperty float y\nproperty float z\n"
                     b"property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
                     + rec.tobytes())
    cloud = native.read_cloud(path)
    np.testing.assert_array_equal(cloud.positions, p)
    assert cloud.normals is None
    np.testing.assert_allclose(cloud.attributes["color"], rgb / 255.0, atol=1e-6)
    assert cloud.info == {}


def test_cloud_attributes_set_are_read_back(native):
    lib = native.load()
    p = fibonacci_sphere(10)
    cloud = native._new_cloud(lib, p)
    try:
        speed = np.arange(30, dtype=np.float32).reshape(10, 3)
        native._set_cloud_attributes(lib, cloud, {"velocity": speed, "radius": np.ones(10)}, 10)
        data = native._cloud_to_data(lib, cloud)
    finally:
        lib.pm_cloud_destroy(cloud)
    assert list(data.attributes) == ["velocity", "radius"]
    np.testing.assert_array_equal(data.attributes["velocity"], speed)
    np.testing.assert_array_equal(data.attributes["radius"], np.ones((10, 1), np.float32))
