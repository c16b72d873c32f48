"""The particlemesh Python package: numpy in and out, the library's options as keywords with
its own defaults, errors as particlemesh.Error with the library's message, progress and
cancellation, handles freed on every path."""
import gc
import pickle
import signal
import threading
import weakref

import numpy as np
import pytest


def fibonacci_sphere(n, radius=1.0, dtype=np.float64):
    i = np.arange(n, dtype=np.float64) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / n)
    theta = np.pi * (1.0 + 5.0 ** 0.5) * i
    p = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)
    return (radius * p).astype(dtype)


def edge_lengths(vertices, triangles):
    t = triangles
    return np.concatenate([np.linalg.norm(vertices[t[:, a]] - vertices[t[:, b]], axis=1)
                           for a, b in ((0, 1), (1, 2), (2, 0))])


def tetrahedron():
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], np.float64)
    t = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], np.int32)
    return p, t


# ---- loading ----------------------------------------------------------------------------------

def test_the_package_loads_the_library_in_its_own_lib_folder(pm, pm_library):
    lib = pm_library.load()
    assert pm.library_path() == lib.path
    assert lib.path.startswith(pm_library.LIB_DIR)
    assert pm.version() == lib.version and pm.version().count(".") == 2


def test_abi_mismatch_is_refused(pm, pm_abi, pm_library, monkeypatch):
    monkeypatch.setattr(pm_abi, "PM_ABI_VERSION", 999)
    with pytest.raises(pm.LibraryNotFoundError, match="ABI version 1; this package needs version 999"):
        pm_library.load(pm.library_path())


def test_missing_library_gives_a_clear_message(pm, pm_library, monkeypatch, tmp_path):
    monkeypatch.setattr(pm_library, "_library", None)
    monkeypatch.setenv("PARTICLEMESH_LIBRARY", str(tmp_path / "libparticlemesh.so"))
    with pytest.raises(pm.LibraryNotFoundError, match="libparticlemesh.so does not exist"):
        pm.triangulate(fibonacci_sphere(100))
    bogus = tmp_path / "bogus.so"
    bogus.write_text("not a library")
    monkeypatch.setenv("PARTICLEMESH_LIBRARY", str(bogus))
    with pytest.raises(pm.LibraryNotFoundError, match="cannot load the particlemesh library"):
        pm.version()
    # Nothing anywhere: the message says where it looked and how to point at the library.
    monkeypatch.delenv("PARTICLEMESH_LIBRARY")
    monkeypatch.setattr(pm_library, "LIB_DIR", str(tmp_path))
    monkeypatch.setattr(pm_library.ctypes.util, "find_library", lambda name: None)
    with pytest.raises(pm.LibraryNotFoundError) as e:
        pm.version()
    assert str(tmp_path) in str(e.value) and "PARTICLEMESH_LIBRARY" in str(e.value)
    assert isinstance(e.value, pm.Error) and isinstance(e.value, Exception)


def test_a_library_missing_a_function_is_refused(pm, pm_abi, pm_library, monkeypatch):
    """No optional symbols: the package and its library ship together, so a library without
    every function of particlemesh.h is the wrong one, and says so."""
    monkeypatch.setitem(pm_abi.FUNCTIONS, "pm_no_such_function", (None, []))
    with pytest.raises(pm.LibraryNotFoundError, match="missing pm_no_such_function"):
        pm_library.load(pm.library_path())


# ---- triangulation ----------------------------------------------------------------------------

def test_triangulate_a_sphere_into_a_closed_outward_surface(pm):
    p = fibonacci_sphere(3000)
    mesh = pm.triangulate(p)
    assert isinstance(mesh, pm.Mesh)
    assert mesh.vertices.dtype == np.float64 and mesh.vertices.shape == (3000, 3)
    assert mesh.triangles.dtype == np.int32 and mesh.triangles.shape[1] == 3
    np.testing.assert_array_equal(mesh.vertices, p)  # vertex i is particle i
    s = mesh.stats
    assert s["points"] == 3000 and s["spacing_estimated"] == 1
    assert s["max_edge"] == pytest.approx(pm.defaults("triangulate")["max_edge_factor"] * s["spacing"])
    assert s["unused_points"] == 0 and s["holes_left"] == 0
    rep = pm.topology(mesh)
    assert rep["closed"] and rep["manifold"] and rep["consistently_oriented"] and rep["outward"]
    assert rep["euler_characteristic"] == 2 and rep["components"] == 1
    assert mesh.triangle_count == 2 * 3000 - 4
    assert mesh.normals.dtype == np.float64
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-9)
    assert (np.einsum("ij,ij->i", mesh.normals, p) > 0.99).all()


def test_particles_at_random_report_their_longer_reach(pm):
    """Points dropped uniformly at random on a sphere: the stats say how irregular the
    sampling is and by how much the edge limits grew; the sphere closes. The even sphere
    above keeps the factor 1."""
    rng = np.random.default_rng(5)
    z, phi = 2 * rng.random(3000) - 1, 2 * np.pi * rng.random(3000)
    p = np.c_[np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z]
    s = pm.triangulate(p).stats
    assert 0.45 < s["sampling_irregularity"] < 0.56 and s["reach_factor"] == 1.75
    assert s["holes_left"] == 0
    even = pm.triangulate(fibonacci_sphere(3000)).stats
    assert even["reach_factor"] == 1.0 and even["sampling_irregularity"] < 0.25


def test_particles_off_their_surface_report_its_thickness(pm):
    """The stats say how far the particles scatter across their surface: a clean sphere
    measures far below 0.2, one whose points are moved along the radius by noise of half
    their spacing about 0.37."""
    p = fibonacci_sphere(8000)
    spacing = np.sqrt(4 * np.pi / len(p))
    noisy = p * (1 + np.random.default_rng(3).normal(0, 0.5 * spacing, len(p)))[:, None]
    assert pm.triangulate(p).stats["sampling_thickness"] < 0.05
    assert 0.3 < pm.triangulate(noisy).stats["sampling_thickness"] < 0.45


def test_raw_is_the_seeds_triangle_set(pm):
    p = fibonacci_sphere(3000)
    raw = pm.triangulate(p, raw=True)
    assert raw.stats["kept"] == raw.triangle_count and raw.stats["holes_filled"] == 0
    assert edge_lengths(raw.vertices, raw.triangles).max() <= raw.stats["max_edge"] * (1 + 1e-9)
    assert (np.sort(raw.triangles, axis=1) == raw.triangles).all()  # canonical, not oriented
    assert raw.triangle_count > pm.triangulate(p, raw=False).triangle_count


def test_a_tunnel_at_a_rim_thinner_than_the_spacing_is_taken_out(pm):
    """A sphere flattened to 0.12 of its width: at its rim, thinner than the spacing, the
    surface had a tunnel (genus 1); the repair takes it out and says so."""
    p = fibonacci_sphere(800) * [1, 1, 0.12]
    mesh = pm.triangulate(p)
    assert mesh.stats["small_handles_removed"] == 1
    t = pm.topology(mesh)
    assert t["closed"] and t["components"] == 1 and t["euler_characteristic"] == 2
    assert mesh.stats["unused_points"] == 0


def test_near_copies_and_crowded_points_show_in_the_stats(pm):
    """The stats appended last reach Python intact (the ctypes struct matches the C ABI's):
    every particle of a sphere with a copy 0.02 spacings away is one particle, the copies set
    aside; with a neighbour limit of 8, the crowded particles' edge limits are shortened and
    counted; the last fields, flat_pieces_opened, nearly_closed_turned and folded_triangles,
    read 0 on both."""
    p = fibonacci_sphere(2000)
    r0 = pm.estimate_spacing(p)
    d = np.random.default_rng(4).normal(size=p.shape)
    copies = p + 0.02 * r0 * d / np.linalg.norm(d, axis=1)[:, None]
    twinned = pm.triangulate(np.r_[p, copies])
    alone = pm.triangulate(p)
    assert twinned.stats["near_duplicates"] == 2000 and twinned.stats["duplicate_points"] == 0
    assert (twinned.triangles == alone.triangles).all()
    assert twinned.stats["shortened_limits"] == 0 and twinned.stats["flat_pieces_opened"] == 0
    crowded = pm.triangulate(p, max_neighbors=8)
    assert 1000 < crowded.stats["shortened_limits"] <= 2000
    assert crowded.stats["near_duplicates"] == 0 and crowded.stats["flat_pieces_opened"] == 0
    assert twinned.stats["nearly_closed_turned"] == 0 == crowded.stats["nearly_closed_turned"]
    assert twinned.stats["folded_triangles"] == 0 == crowded.stats["folded_triangles"]


def teardrop(h=0.04, height=3.0):
    """A closed teardrop (a unit half ball below z = 0, a cone up to a sharp tip at z =
    height) sampled about h apart, with three round holes (0.25 across) in its side."""
    n = int(2 * np.pi / h ** 2)
    i = np.arange(n) + 0.5
    phi, th = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
    ball = np.c_[np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)]
    rings = [ball[ball[:, 2] < 0]]
    for z in np.arange(h / 2, height, h):
        r = 1 - z / height
        m = max(int(2 * np.pi * r / h), 3)
        a = np.arange(m) * 2 * np.pi / m + 7 * z
        rings.append(np.c_[r * np.cos(a), r * np.sin(a), np.full(m, z)])
    p = np.concatenate(rings + [[[0, 0, height]]])
    for c in ([1, 0, -0.3], [0, -1, -0.5], [-0.7, 0.7, 0.2]):
        c = np.array(c) / np.linalg.norm(c)
        p = p[np.linalg.norm(p - c * np.linalg.norm(p, axis=1)[:, None], axis=1) > 0.25]
    return p


def signed_volume(mesh):
    v, t = mesh.vertices, mesh.triangles
    return np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6


def test_a_surface_closed_but_for_small_holes_faces_outward(pm):
    """A model's vertices whose surface keeps a few holes open: without input normals the
    spanning tree alone says which way the surface faces, from its highest particle, here a
    sharp tip whose plane fit has no up: it chose inward. Judged with its holes capped, as a
    closed surface is, it faces outward (the same for any thread count); orient=False keeps
    the tree's choice, and input normals theirs (a scanner's, inside a room, face inward
    rightly)."""
    p = teardrop()
    mesh = pm.triangulate(p)
    assert mesh.stats["holes_left"] == 3 and pm.topology(mesh)["components"] == 1
    assert mesh.stats["nearly_closed_turned"] == 1
    assert 4.7 < signed_volume(mesh) < 5.24  # the solid's pi (2 + 3) / 3, less the holes' and chords'
    assert (pm.triangulate(p, threads=1).triangles == mesh.triangles).all()
    tree = pm.triangulate(p, orient=False)
    assert tree.stats["nearly_closed_turned"] == 0 and signed_volume(tree) < 0
    for sign in (-1, 1):
        given = pm.triangulate(p, sign * mesh.normals)
        assert given.stats["nearly_closed_turned"] == 0 and np.sign(signed_volume(given)) == sign


def ball_with_ears(h=0.04, thickness=2.0):
    """A unit ball with two thin ears (flat ellipsoids `thickness` spacings thick, one on top,
    one at its side), sampled about h apart: (points, their outward normals)."""
    c = thickness * h / 2
    parts = [((1.0, 1.0, 1.0), (0.0, 0.0, 0.0)), ((0.6, c, 0.45), (0.0, 0.0, 1.35)), ((0.6, c, 0.45), (1.3, 0.0, 0.6))]
    points, normals = [], []
    for k, (a, centre) in enumerate(parts):
        a, centre = np.array(a), np.array(centre)
        area = 4 * np.pi * (((a[0] * a[1]) ** 1.6 + (a[0] * a[2]) ** 1.6 + (a[1] * a[2]) ** 1.6) / 3) ** (1 / 1.6)
        n = int(area / (h * h * 0.866))
        i = np.arange(n) + 0.5
        phi, th = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
        u = np.c_[np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)]
        p, normal = u * a + centre, u / a
        keep = np.ones(len(p), bool)
        for j, (b, other) in enumerate(parts):
            if j != k:
                keep &= (((p - np.array(other)) / np.array(b)) ** 2).sum(axis=1) >= 1
        points.append(p[keep])
        normals.append(normal[keep] / np.linalg.norm(normal[keep], axis=1)[:, None])
    return np.concatenate(points), np.concatenate(normals)


def test_a_folded_surface_is_built_again_facing_outward(pm):
    """A ball's thin ears, without input normals: the spanning tree crosses between an ear's
    two sides and the surface folds over, a tenth of it facing into the solid. Found by ray
    parity (stats folded_triangles), the normals are turned and the surface built again:
    it faces outward, the same for any thread count, its progress never going back;
    orient=False leaves the tree's surface."""
    p, outward = ball_with_ears()
    seen = []
    mesh = pm.triangulate(p, progress=lambda stage, f: seen.append(f))
    assert seen == sorted(seen) and seen[-1] == 1.0  # built twice, the progress never goes back
    t = pm.topology(mesh)
    assert t["components"] == 1 and t["consistently_oriented"] and t["nonmanifold_edges"] == 0
    assert mesh.stats["folded_triangles"] > 0.05 * mesh.triangle_count
    v, tri = mesh.vertices, mesh.triangles
    face = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    inward = (np.einsum("tj,tcj->tc", face, outward[tri]) < 0).all(axis=1)
    assert inward.mean() < 0.002
    assert (pm.triangulate(p, threads=1).triangles == tri).all()
    tree = pm.triangulate(p, orient=False)
    assert tree.stats["folded_triangles"] == 0
    assert pm.triangulate(p, outward).stats["folded_triangles"] == 0


def depth_frame(sigma, n=160, seed=3):
    """A depth camera's frame (n x n rays from the origin along +z): a wall 2 away with a ball
    in front of it, depth noise of `sigma` and depth quantized in steps of 0.002, as a
    Kinect's."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(-0.5, 0.5, n), np.linspace(-0.4, 0.4, n))
    z = np.full(u.shape, 2.0)
    r2 = (u - 0.1) ** 2 + v ** 2
    ball = r2 < 0.2 ** 2
    z[ball] = 1.6 - 2 * np.sqrt(0.2 ** 2 - r2[ball])
    d = np.round((z + rng.normal(0, sigma, z.shape)) / 0.002) * 0.002
    return np.c_[u.ravel() * d.ravel(), v.ravel() * d.ravel(), d.ravel()]


def test_a_noisy_depth_frame_is_oriented_within_its_sheets(pm):
    """Depth noise puts neighbouring samples of one sheet a noise's depth apart, which looks
    like an edge between two sheets; in a sampling that scatters across its surface the
    normals' spanning tree takes such edges last. The frame's wall and ball come out whole
    (before: 69 pieces and 79 loops, 29 609 candidates dropped for facing against their
    neighbours' normals)."""
    p = depth_frame(0.006)
    mesh = pm.triangulate(p)
    assert mesh.stats["sampling_thickness"] > 0.22  # noisy
    top = pm.topology(mesh)
    assert top["components"] <= 6 and top["boundary_loops"] <= 10, top
    assert mesh.stats["rejected_conormal"] < 0.2 * mesh.stats["kept"]  # 14 % (before: 36 %)
    # A cleaner frame of the same scene: the wall (its hole's rim and outline) and the ball.
    clean = pm.topology(pm.triangulate(depth_frame(0.002)))
    assert clean["components"] == 2 and clean["boundary_loops"] == 3


def test_small_pieces_removed_on_request(pm):
    p = fibonacci_sphere(3000)
    r0 = np.sqrt(4 * np.pi / 3000)
    lone = np.array([[3, 0, 0], [3 + r0, 0, 0], [3 + r0 / 2, 0.87 * r0, 0]])
    points = np.concatenate([p, lone])
    kept = pm.triangulate(points)
    assert pm.topology(kept)["components"] == 2 and kept.stats["components_removed"] == 0
    assert (kept.stats["stray_pieces"], kept.stats["stray_piece_largest"]) == (1, 1)
    mesh = pm.triangulate(points, min_component_triangles=2)
    assert mesh.stats["components_removed"] == 1 and mesh.stats["component_triangles_removed"] == 1
    assert mesh.triangle_count == kept.triangle_count - 1
    assert mesh.stats["unused_points"] == kept.stats["unused_points"] + 3
    assert pm.topology(mesh)["components"] == 1 and pm.topology(mesh)["closed"]
    assert pm.defaults("triangulate")["min_component_triangles"] == 0
    with pytest.raises(pm.Error):
        pm.triangulate(points, min_component_triangles=-1)


def test_options_are_the_c_fields_with_the_librarys_defaults(pm):
    d = pm.defaults("triangulate")
    assert list(d)[:9] == ["spacing", "max_edge_factor", "threads", "max_neighbors",
                           "normal_angle", "fill_holes", "fill_edge_factor", "normal_source",
                           "max_triplets_per_point"]  # the struct's order; appended fields follow
    assert (d["spacing"], d["max_edge_factor"], d["normal_source"]) == (0.0, 2.0, "auto")
    assert pm.defaults("polygonize")["kernel"] == "wyvill"
    assert pm.defaults("smooth")["scheme"] == "loop" and pm.defaults("smooth")["levels"] == 1
    with pytest.raises(ValueError, match="no options for 'render'"):
        pm.defaults("render")
    p = fibonacci_sphere(2000)
    mesh = pm.triangulate(p, spacing=0.1, max_edge_factor=1.5, raw=True)
    assert mesh.stats["spacing"] == pytest.approx(0.1) and not mesh.stats["spacing_estimated"]
    assert mesh.stats["max_edge"] == pytest.approx(0.15)
    assert edge_lengths(mesh.vertices, mesh.triangles).max() <= 0.15 * (1 + 1e-9)
    # None is the library's default, exactly as leaving the keyword out.
    a = pm.triangulate(p, spacing=None, normal_angle=None)
    np.testing.assert_array_equal(a.triangles, pm.triangulate(p).triangles)


def test_bad_keywords_and_values_are_named(pm):
    p = fibonacci_sphere(500)
    with pytest.raises(TypeError, match="unexpected keyword argument 'spacingg'"):
        pm.triangulate(p, spacingg=0.1)
    with pytest.raises(TypeError, match="unexpected keyword argument 'flags'"):
        pm.triangulate(p, flags=1)  # raw=, repair=, orient= set it
    with pytest.raises(TypeError, match="spacing must be a number"):
        pm.triangulate(p, spacing="0.1")
    with pytest.raises(TypeError, match="threads must be an integer"):
        pm.triangulate(p, threads=1.5)
    with pytest.raises(pm.Error, match=r"fill_holes is -1; it must be 0\.\.4294967295") as e:
        pm.triangulate(p, fill_holes=-1)  # ctypes alone would wrap it to 4294967295
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT
    with pytest.raises(pm.Error, match="normal_source is 'outward'; it must be one of auto, input, estimate"):
        pm.triangulate(p, normal_source="outward")
    with pytest.raises(pm.Error, match="kernel is 7"):
        pm.polygonize(p, kernel=7)
    with pytest.raises(TypeError, match="unexpected keyword argument 'level'"):
        pm.smooth(pm.Mesh(*tetrahedron()), level=2)
    with pytest.raises(TypeError, match="both cell and cell_size"):
        pm.polygonize(p, cell=0.1, cell_size=0.1)


def test_finishing_options_reach_the_library(pm, data_dir):
    cloud = pm.read_points(data_dir / "points/spot_poisson.ply")
    full = pm.triangulate(cloud)  # Points: positions and normals together
    rep = pm.topology(full)
    assert rep["closed"] and rep["manifold"] and rep["outward"] and rep["euler_characteristic"] == 2
    assert full.stats["holes_filled"] > 0 and full.stats["holes_left"] == 0
    no_fill = pm.triangulate(cloud.positions, cloud.normals, fill_holes=0)
    assert no_fill.stats["holes_filled"] == 0 and no_fill.stats["holes_left"] > 0
    no_repair = pm.triangulate(cloud, repair=False)
    assert no_repair.stats["holes_filled"] == 0 and no_repair.triangle_count < full.triangle_count
    strict = pm.triangulate(cloud, normal_angle=30.0)
    assert strict.triangle_count != full.triangle_count
    assert pm.triangulate(cloud, orient=False, normal_source="ESTIMATE").triangle_count > 0
    with pytest.raises(pm.Error) as e:
        pm.triangulate(cloud, normal_angle=-5.0)
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT and "normal_angle" in str(e.value)


def test_threads_do_not_change_the_result(pm):
    p = fibonacci_sphere(4000)
    np.testing.assert_array_equal(pm.triangulate(p, threads=1).triangles,
                                  pm.triangulate(p, threads=2).triangles)


def test_input_arrays_of_any_layout(pm):
    p = fibonacci_sphere(1000)
    ref = pm.triangulate(p).triangles
    p32 = p.astype(np.float32)
    m32 = pm.triangulate(p32)  # crosses as float32, comes back as the same values in float64
    np.testing.assert_array_equal(m32.vertices, p32.astype(np.float64))
    np.testing.assert_array_equal(pm.triangulate(p.ravel()).triangles, ref)  # flat x y z ...
    np.testing.assert_array_equal(pm.triangulate(np.asfortranarray(p)).triangles, ref)
    np.testing.assert_array_equal(pm.triangulate(p.tolist()).triangles, ref)
    np.testing.assert_array_equal(pm.triangulate(pm.Points(p)).triangles, ref)
    with pytest.raises(pm.Error, match="shape"):
        pm.triangulate(p[:, :2])
    with pytest.raises(pm.Error, match="multiple of 3"):
        pm.triangulate(p.ravel()[:-1])
    with pytest.raises(pm.Error, match="normals has 999 rows but positions has 1000"):
        pm.triangulate(p, p[:-1])


def test_normals_and_attributes_pass_through(pm):
    p = fibonacci_sphere(1500)
    raw = pm.triangulate(p, normals=p, raw=True)
    np.testing.assert_allclose(raw.normals, p, atol=1e-12)  # raw: the particles' own normals
    assert pm.triangulate(p, raw=True).normals is None
    inward = pm.triangulate(p, normals=-p, normal_source="input", orient=False)
    rep = pm.topology(inward)
    assert rep["closed"] and not rep["outward"]
    speed = (p * 3).astype(np.float32)
    mesh = pm.triangulate(p, attributes={"velocity": speed, "radius": np.ones(1500)})
    np.testing.assert_array_equal(mesh.attributes["velocity"], speed)
    assert mesh.attributes["radius"].shape == (1500, 1)
    with pytest.raises(pm.Error, match="attribute 'velocity' has shape"):
        pm.triangulate(p, attributes={"velocity": speed[:10]})


def test_a_meshs_arrays_are_the_librarys_own_and_outlive_the_mesh(pm):
    """No copy out: the arrays of a returned mesh are the library's (lent), writable numpy
    arrays of the documented types, valid for as long as any of them lives, and the library's
    mesh is destroyed with the last one."""
    p = fibonacci_sphere(3000)
    speed = (p * 2).astype(np.float32)
    mesh = pm.polygonize(p, attributes={"velocity": speed}, threads=1)
    v, t, n, a = mesh.vertices, mesh.triangles, mesh.normals, mesh.attributes["velocity"]
    for array, dtype, columns in ((v, np.float64, 3), (t, np.int32, 3), (n, np.float64, 3),
                                  (a, np.float32, 3)):
        assert array.dtype == dtype and array.shape[1] == columns
        assert array.flags.c_contiguous and array.flags.writeable and not array.flags.owndata
    owner = v.base.owner
    assert t.base.owner is owner and n.base.owner is owner and a.base.owner is owner
    gone = weakref.ref(owner)
    copies = [x.copy() for x in (v, t, n, a)]
    # What the library made: the same mesh again, on two threads.
    again = pm.polygonize(p, attributes={"velocity": speed}, threads=2)
    for x, y in zip(copies, (again.vertices, again.triangles, again.normals,
                             again.attributes["velocity"])):
        np.testing.assert_array_equal(x, y)
    del y
    assert pickle.loads(pickle.dumps(mesh)).vertices.tobytes() == copies[0].tobytes()
    del mesh, owner, again
    gc.collect()
    assert gone() is not None  # the arrays still hold the library's mesh
    assert t.max() < len(v) and t.min() >= 0
    for i, x in enumerate((v, t, n, a)):
        np.testing.assert_array_equal(x, copies[i])
    del x, array  # the loops' last arrays
    v[0] = (7.0, 8.0, 9.0)  # their own memory: writing is allowed and stays
    assert tuple(v[0]) == (7.0, 8.0, 9.0)
    del v, t, n
    gc.collect()
    assert gone() is not None  # the attribute's array alone keeps it
    del a
    gc.collect()
    assert gone() is None
    empty = pm.polygonize(p, threshold=1e9)  # no surface: nothing to lend
    assert empty.vertices.shape == (0, 3) and empty.vertices.dtype == np.float64
    assert empty.triangles.shape == (0, 3) and empty.triangles.dtype == np.int32


def test_real_scan_from_shared_data(pm, data_dir):
    cloud = pm.read_points(data_dir / "points/spot_poisson.ply")
    assert cloud.positions.shape == (8747, 3) and cloud.positions.dtype == np.float64
    assert cloud.normals.shape == (8747, 3)
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-4)
    mesh = pm.triangulate(cloud.positions)
    assert 0.02 <= mesh.stats["spacing"] < 0.025  # Poisson-disk r0 = 0.02
    rep = pm.topology(mesh)
    assert rep["vertices_used"] == 8747 and rep["components"] == 1 and rep["closed"]
    assert mesh.triangle_count == 2 * 8747 - 4  # the cow is genus 0


# ---- errors -----------------------------------------------------------------------------------

def test_nan_names_the_index(pm):
    p = fibonacci_sphere(100)
    p[42, 1] = np.nan
    with pytest.raises(pm.Error) as e:
        pm.triangulate(p)
    assert e.value.status == pm.STATUS_INVALID_INPUT and e.value.status_name == "invalid input"
    assert "positions[42].y" in str(e.value) and "NaN" in str(e.value)


def test_empty_tiny_absurd_and_too_dense(pm):
    with pytest.raises(pm.Error, match="empty") as e:
        pm.triangulate(np.zeros((0, 3)))
    assert e.value.status == pm.STATUS_INVALID_INPUT
    with pytest.raises(pm.Error):
        pm.triangulate(np.zeros((1, 3)))
    for kwargs in ({"max_edge_factor": -1.0}, {"max_edge_factor": float("nan")},
                   {"spacing": -0.5}, {"spacing": float("inf")}):
        with pytest.raises(pm.Error) as e:
            pm.triangulate(fibonacci_sphere(200), **kwargs)
        assert e.value.status == pm.STATUS_INVALID_ARGUMENT and str(e.value), kwargs
    with pytest.raises(pm.Error) as e:
        pm.triangulate(fibonacci_sphere(3000), spacing=1.0)
    assert e.value.status == pm.STATUS_LIMIT_EXCEEDED


def test_missing_and_malformed_files(pm, tmp_path):
    with pytest.raises(pm.Error) as e:
        pm.read_points(tmp_path / "nope.ply")
    assert e.value.status == pm.STATUS_IO_ERROR and "nope.ply" in str(e.value)
    bad = tmp_path / "bad.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(pm.Error, match="bad.ply"):
        pm.read_points(bad)
    with pytest.raises(pm.Error, match="nope.obj"):
        pm.read_mesh(tmp_path / "nope.obj")


# ---- progress, cancellation, the GIL ----------------------------------------------------------

def test_progress_reports_stages(pm):
    seen = []
    pm.triangulate(fibonacci_sphere(20000), progress=lambda stage, f: seen.append((stage, f)))
    assert seen, "no progress reported"
    fractions = [f for _, f in seen]
    assert all(0.0 <= f <= 1.0 for f in fractions) and fractions == sorted(fractions)
    assert all(stage for stage, _ in seen)
    progress = pm.Progress()
    pm.polygonize(fibonacci_sphere(5000), progress=progress)
    assert progress.stage and progress.fraction > 0 and not progress.cancelled


def test_callback_returning_false_cancels(pm):
    with pytest.raises(pm.CancelledError) as e:
        pm.triangulate(fibonacci_sphere(20000), progress=lambda stage, f: False)
    assert e.value.status == pm.STATUS_CANCELLED
    with pytest.raises(pm.CancelledError):
        pm.smooth(pm.triangulate(fibonacci_sphere(20000)), levels=2, progress=lambda s, f: False)
    with pytest.raises(TypeError, match="progress must be"):
        pm.triangulate(fibonacci_sphere(200), progress=42)


def test_cancel_from_another_thread(pm):
    """How Blender's modal operator stops a worker: Esc calls cancel() on the UI thread."""
    progress = pm.Progress()
    started = threading.Event()
    progress.callback = lambda stage, f: started.set()
    result = {}

    def work():
        try:
            pm.triangulate(fibonacci_sphere(400000), progress=progress)
            result["finished"] = True
        except pm.CancelledError as e:
            result["cancelled"] = e

    t = threading.Thread(target=work)
    t.start()
    assert started.wait(60)
    progress.cancel()
    t.join(60)
    assert not t.is_alive() and "cancelled" in result and progress.cancelled


def test_an_exception_in_the_callback_cancels_and_is_raised(pm):
    def boom(stage, f):
        raise RuntimeError("bug in the host")

    with pytest.raises(RuntimeError, match="bug in the host"):
        pm.triangulate(fibonacci_sphere(20000), progress=boom)
    assert pm.triangulate(fibonacci_sphere(500)).triangle_count > 0  # and all is well after


def test_the_gil_is_released_during_a_call(pm):
    """Another Python thread keeps running while the library works: it counts many times
    between the call's first and last progress report (with the GIL held it could not count
    at all while the library computes)."""
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)

    reports = []

    def on_progress(stage, f):
        reports.append(len(ticks))

    t = threading.Thread(target=count)
    t.start()
    try:
        pm.triangulate(fibonacci_sphere(300000), progress=on_progress)
    finally:
        stop.set()
        t.join()
    assert len(reports) >= 2
    assert reports[-1] - reports[0] > 1000, reports


# ---- handles ----------------------------------------------------------------------------------

class _Made:
    """Records the handles a pm_*_create / call made (its out-pointer argument, on success)."""

    def __init__(self, fn, handles, out_index):
        self.fn, self.handles, self.out_index = fn, handles, out_index

    def __call__(self, *args):
        status = self.fn(*args)
        if status == 0:
            self.handles.append(args[self.out_index]._obj.value)
        return status


class _Freed:
    def __init__(self, fn, handles):
        self.fn, self.handles = fn, handles

    def __call__(self, handle):
        if handle.value is not None:
            self.handles.append(handle.value)
        return self.fn(handle)


def test_handles_are_freed_on_every_path(pm, pm_library, monkeypatch):
    """Every handle the library made is destroyed exactly once, whatever happens after."""
    lib = pm_library.load()
    made, freed = [], []
    for name, out_index in (("pm_cloud_create", 3), ("pm_cloud_create_f32", 3),
                            ("pm_triangulate", 2), ("pm_mesh_create", 5), ("pm_smooth", 2),
                            ("pm_polygonize_ex", 4)):
        monkeypatch.setattr(lib, name, _Made(getattr(lib.cdll, name), made, out_index))
    for name in ("pm_cloud_destroy", "pm_mesh_destroy"):
        monkeypatch.setattr(lib, name, _Freed(getattr(lib.cdll, name), freed))
    p = fibonacci_sphere(20000)
    mesh = pm.triangulate(p)                                    # cloud, mesh
    with pytest.raises(pm.Error):
        pm.triangulate(p, max_edge_factor=-1)                   # cloud; fails inside
    with pytest.raises(pm.CancelledError):
        pm.triangulate(p, progress=lambda s, f: False)          # cloud; cancelled
    with pytest.raises(pm.Error):
        pm.triangulate(p, attributes={"bad": np.full(20000, np.nan)})  # cloud; attribute fails
    pm.topology(mesh)                                           # mesh
    with pytest.raises(pm.Error):
        pm.topology(pm.Mesh(mesh.vertices, mesh.triangles + 10 ** 6))  # create fails: none
    pm.smooth(pm.Mesh(*tetrahedron()))                          # mesh in, mesh out
    with pytest.raises(pm.Error):
        pm.polygonize(p[:100], radii=np.ones(99))                # cloud; radii refused
    def copy_fails(*args, **kwargs):
        raise KeyboardInterrupt  # Ctrl-C while the mesh is copied out

    monkeypatch.setattr(pm, "read_mesh_handle", copy_fails)
    with pytest.raises(KeyboardInterrupt):
        pm.polygonize(p[:500])                                   # cloud, mesh; copy interrupted
    monkeypatch.undo()
    for name, out_index in (("pm_cloud_create", 3), ("pm_polygonize_ex", 4)):
        monkeypatch.setattr(lib, name, _Made(getattr(lib.cdll, name), made, out_index))
    finished = lib.pm_polygonize_ex

    def then_ctrl_c(*args):  # Ctrl-C just after the library finished
        status = finished(*args)
        signal.raise_signal(signal.SIGINT)
        return status

    monkeypatch.setattr(lib, "pm_polygonize_ex", then_ctrl_c)
    for name in ("pm_cloud_destroy", "pm_mesh_destroy"):
        monkeypatch.setattr(lib, name, _Freed(getattr(lib.cdll, name), freed))
    with pytest.raises(KeyboardInterrupt):
        pm.polygonize(p[:500])                                   # cloud, mesh; then Ctrl-C
    monkeypatch.undo()
    del mesh  # a returned mesh's arrays are its handle's own: it goes with the last of them
    gc.collect()
    assert len(made) == 13 and sorted(made) == sorted(freed)  # (addresses may be reused)


# ---- meshes and files -------------------------------------------------------------------------

def test_topology_of_a_closed_outward_tetrahedron(pm):
    p, t = tetrahedron()
    rep = pm.topology(pm.Mesh(p, t))
    assert rep["closed"] and rep["manifold"] and rep["consistently_oriented"] and rep["outward"]
    assert rep["euler_characteristic"] == 2 and rep["edges"] == 6
    assert not pm.topology(pm.Mesh(p, t[:, ::-1]))["outward"]
    with pytest.raises(TypeError, match="particlemesh.Mesh"):
        pm.topology((p, t))
    with pytest.raises(pm.Error, match="triangles must hold integer"):
        pm.topology(pm.Mesh(p, t.astype(float)))


def test_write_mesh_writes_the_attributes_and_says_what_obj_leaves_out(pm, tmp_path):
    """A Mesh's attributes reach the file (they were dropped: write_mesh gave the library the
    mesh without them): PLY and VTK hold every channel, read back; an OBJ holds the colour, and a
    NotWrittenWarning names the rest."""
    import warnings
    p, t = tetrahedron()
    velocity = np.arange(12, dtype=np.float32).reshape(4, 3)
    colour = np.array([[0, 0.5, 1]] * 4, np.float32)
    mesh = pm.Mesh(p, t, attributes={"velocity": velocity, "color": colour})
    for ext in ("ply", "vtk", "vtu"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            pm.write_mesh(mesh, tmp_path / f"m.{ext}")
        back = pm.read_mesh(tmp_path / f"m.{ext}")
        np.testing.assert_array_equal(back.attributes["velocity"], velocity, err_msg=ext)
        np.testing.assert_allclose(back.attributes["color"], colour, atol=1 / 255, err_msg=ext)
    with pytest.warns(pm.NotWrittenWarning, match=r"m\.obj: not written: velocity \(OBJ holds a colour"):
        pm.write_mesh(mesh, tmp_path / "m.obj")
    back = pm.read_mesh(tmp_path / "m.obj")
    assert set(back.attributes) == {"color"}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pm.write_mesh(pm.Mesh(p, t, attributes={"color": colour}), tmp_path / "c.obj")


def test_read_mesh_names_what_the_mesh_does_not_carry(pm, tmp_path):
    """An OBJ's texture coordinates that a face corner lacks: in stats["not_read"] and a
    NotReadWarning; a plain mesh file warns of nothing and has no such entry."""
    import warnings
    path = tmp_path / "uv.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 1\nf 1/1 2/2 3\n")
    line = "texture coordinates (2 vt; 1 face corner names none)"
    with pytest.warns(pm.NotReadWarning, match=r"uv\.obj: not read: texture coordinates \(2 vt; 1 face"):
        mesh = pm.read_mesh(path)
    assert mesh.stats == {"not_read": [line]} and mesh.corner_attributes == {}
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2]])
    p, t = tetrahedron()
    pm.write_mesh(pm.Mesh(p, t), tmp_path / "tet.ply")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert pm.read_mesh(tmp_path / "tet.ply").stats == {}


def test_texture_coordinates_are_corner_attributes_through_smooth_and_obj(pm, tmp_path):
    """An OBJ's vt become corner_attributes["uv"] (T, 3, 2); smooth() carries them (the
    children of triangle f are triangles 16f.. at two levels, their corners means of f's);
    write_mesh writes them back to .obj and .ply and warns where a format cannot hold them; they
    survive pickling; bad shapes and values are named."""
    import pickle
    import warnings
    path = tmp_path / "quad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = pm.read_mesh(path)
    uv = mesh.corner_attributes["uv"]
    assert uv.shape == (2, 3, 2) and uv.dtype == np.float32
    np.testing.assert_array_equal(uv, mesh.vertices[mesh.triangles][:, :, :2])
    smooth = pm.smooth(mesh, "butterfly", 2)
    suv = smooth.corner_attributes["uv"]
    assert suv.shape == (32, 3, 2)
    for scheme in ("loop", "butterfly"):  # the Smoother: the constructor's mesh's, subdivided
        with pm.Smoother(mesh, scheme, 2) as smoother:
            moved = pm.Mesh(mesh.vertices * 2, mesh.triangles)
            np.testing.assert_array_equal(smoother.evaluate(moved).corner_attributes["uv"],
                                          pm.smooth(mesh, scheme, 2).corner_attributes["uv"])
    for f in range(2):
        # The input's corners where the layout puts them: a of the first child, b of the
        # sixth (the second child's second), c of the eleventh (the third's third).
        assert (suv[16 * f, 0] == uv[f, 0]).all() and (suv[16 * f + 5, 1] == uv[f, 1]).all()
        assert (suv[16 * f + 10, 2] == uv[f, 2]).all()
        lo, hi = uv[f].min(0), uv[f].max(0)
        assert (suv[16 * f:16 * f + 16] >= lo - 1e-6).all() and (suv[16 * f:16 * f + 16] <= hi + 1e-6).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pm.write_mesh(smooth, tmp_path / "s.obj")
    back = pm.read_mesh(tmp_path / "s.obj")
    np.testing.assert_array_equal(back.corner_attributes["uv"], suv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pm.write_mesh(smooth, tmp_path / "s.ply")
    np.testing.assert_array_equal(pm.read_mesh(tmp_path / "s.ply").corner_attributes["uv"], suv)
    with pytest.warns(pm.NotWrittenWarning, match=r"not written: uv \(per corner\)"):
        pm.write_mesh(smooth, tmp_path / "s.vtk")
    assert "corner attributes uv" in repr(smooth)
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(smooth)).corner_attributes["uv"], suv)
    with pytest.raises(pm.Error, match=r"corner attribute 'uv' has shape \(2, 2\)"):
        pm.smooth(pm.Mesh(mesh.vertices, mesh.triangles, corner_attributes={"uv": np.zeros((2, 2))}))
    with pytest.raises(pm.Error, match=r"corner attribute 'uv' is not finite"):
        pm.smooth(pm.Mesh(mesh.vertices, mesh.triangles, corner_attributes={"uv": np.full((2, 3, 2), np.nan)}))


def test_components_number_the_pieces_with_their_volumes(pm):
    """Two tetrahedra (one turned inside out) and a vertex no triangle uses: each vertex's
    piece (-1 for the unused one), per piece its triangles, area and signed enclosed volume;
    dropping the pieces below a volume by the triangles' pieces keeps the other whole."""
    p, t = tetrahedron()
    q = np.vstack([p, 2 * p + 10, [[50, 50, 50]]])
    tris = np.vstack([t, t[:, ::-1] + 4]).astype(np.int32)
    c = pm.components(pm.Mesh(q, tris))
    np.testing.assert_array_equal(c["vertex"], [0, 0, 0, 0, 1, 1, 1, 1, -1])
    np.testing.assert_array_equal(c["triangles"], [4, 4])
    side = np.sqrt(8.0)  # a regular tetrahedron of edge sqrt(8): volume 8/3, area sqrt(3) side^2
    np.testing.assert_allclose(c["area"], [np.sqrt(3) * side ** 2, 4 * np.sqrt(3) * side ** 2])
    np.testing.assert_allclose(c["volume"], [8 / 3, -8 * 8 / 3])
    keep = np.abs(c["volume"][c["vertex"][tris[:, 0]]]) > 10
    np.testing.assert_array_equal(tris[keep], t[:, ::-1] + 4)
    empty = pm.components(pm.Mesh(p, np.zeros((0, 3), np.int32)))
    assert list(empty["vertex"]) == [-1] * 4 and len(empty["volume"]) == 0


def test_mesh_write_read_roundtrip(pm, tmp_path):
    p, t = tetrahedron()
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    for ext in ("ply", "obj"):
        path = tmp_path / f"tet.{ext}"
        pm.write_mesh(pm.Mesh(p, t, n), path)
        back = pm.read_mesh(str(path))
        np.testing.assert_allclose(back.vertices, p)
        np.testing.assert_array_equal(back.triangles, t)
        np.testing.assert_allclose(back.normals, n, atol=1e-6)
    with pytest.raises(pm.Error) as e:
        pm.write_mesh(pm.Mesh(p, t), tmp_path / "tet.xyz")
    assert "xyz" in str(e.value)


def test_points_keep_their_full_precision(pm, tmp_path):
    """Georeferenced coordinates (UTM) come back as read, not rounded to float32."""
    path = tmp_path / "utm.xyz"
    path.write_text("# comment\n500000.123456789 4649776.987654321 213.000000001 0 0 1\n"
                    "500001.5 4649777.25 213.75 0 0 1\n500000.75 4649778.125 214.0625 0 0 1\n")
    points = pm.read_points(path)
    np.testing.assert_array_equal(points.positions[0], [500000.123456789, 4649776.987654321,
                                                        213.000000001])
    np.testing.assert_array_equal(points.normals, [[0, 0, 1]] * 3)
    assert len(points) == 3 and points.attributes == {} and points.info == {"not_read": []}


def test_csv_as_numpy_and_paraview_write_it(pm, tmp_path):
    """np.savetxt with a header, and ParaView's CSV export (vectors as Name:k, the points
    last): the positions in full precision, the velocity one (N, 3) channel."""
    p = fibonacci_sphere(50) * 1000.0 + 0.123456789
    v = np.random.default_rng(5).normal(size=(50, 3))
    path = tmp_path / "numpy.csv"
    np.savetxt(path, np.hstack([p, v]), delimiter=",", header="x,y,z,vx,vy,vz", comments="", fmt="%.17g")
    cloud = pm.read_points(path)
    np.testing.assert_array_equal(cloud.positions, p)
    assert list(cloud.attributes) == ["velocity"]
    np.testing.assert_allclose(cloud.attributes["velocity"], v, rtol=1e-6)
    path = tmp_path / "paraview.csv"
    np.savetxt(path, np.hstack([v, np.arange(50)[:, None], p]), delimiter=",", fmt="%.17g", comments="",
               header='"Velocity:0","Velocity:1","Velocity:2","Point ID","Points:0","Points:1","Points:2"')
    cloud = pm.read_points(path)
    np.testing.assert_array_equal(cloud.positions, p)
    assert list(cloud.attributes) == ["velocity", "Point ID"]
    np.testing.assert_array_equal(cloud.attributes["Point ID"].ravel(), np.arange(50))
    path.write_text('"Velocity:0","Velocity:1","Velocity:2"\n1,2,3\n')
    with pytest.raises(pm.Error, match="nor the positions as a vector") as e:
        pm.read_points(path)
    assert e.value.status == pm.STATUS_FORMAT_ERROR


def test_ply_vertex_colours_are_read_back(pm, tmp_path):
    p = fibonacci_sphere(20, dtype=np.float32)
    rgb = np.random.default_rng(3).integers(0, 256, size=(20, 3), dtype=np.uint8)
    rec = np.zeros(20, dtype=[("p", "<f4", 3), ("c", "u1", 3)])
    rec["p"], rec["c"] = p, rgb
    path = tmp_path / "coloured.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 20\n"
                     b"property float x\nproperty float y\nproperty float z\n"
                     b"property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
                     + rec.tobytes())
    cloud = pm.read_points(path)
    np.testing.assert_array_equal(cloud.positions, p)
    assert cloud.normals is None
    np.testing.assert_allclose(cloud.attributes["color"], rgb / 255.0, atol=1e-6)


def test_estimate_spacing_and_thin(pm):
    p = np.stack(np.meshgrid(np.arange(40), np.arange(40), [0.0]), -1).reshape(-1, 3) * 0.25
    assert pm.estimate_spacing(p) == pytest.approx(0.25)
    assert pm.estimate_spacing(p, max_samples=50) == pytest.approx(0.25)
    with pytest.raises(pm.Error, match="max_samples"):
        pm.estimate_spacing(p, max_samples=0)
    idx = pm.thin(p, 0.6)
    assert idx.dtype == np.int64 and idx[0] == 0 and np.all(np.diff(idx) > 0)
    kept = p[idx]
    d = np.linalg.norm(kept[:, None] - kept[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 0.6
    assert np.linalg.norm(p[:, None] - kept[None], axis=-1).min(axis=1).max() < 0.6
    with pytest.raises(pm.Error, match="min_distance") as e:
        pm.thin(p, 0.0)
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT


def test_triangle_edges_number_every_corner(pm):
    mesh = pm.triangulate(fibonacci_sphere(2000))
    tris = mesh.triangles
    edges, corners = pm.triangle_edges(tris, mesh.vertex_count)
    assert edges.dtype == np.uint32 and corners.dtype == np.uint32
    assert 2 * len(edges) == 3 * len(tris) and np.all(edges[:, 0] < edges[:, 1])
    a, b = tris.ravel(), np.roll(tris, -1, axis=1).ravel()
    np.testing.assert_array_equal(edges[corners], np.stack([np.minimum(a, b), np.maximum(a, b)], 1))
    with pytest.raises(pm.Error, match="vertex index 2000"):
        pm.triangle_edges(np.array([[0, 1, 2000]]), 2000)
    # Into the caller's arrays (larger than needed; used again for a smaller mesh): the same
    # numbers, as views of them.
    out = (np.full((3 * len(tris) + 7, 2), 9, np.uint32), np.full(3 * len(tris) + 5, 9, np.uint32))
    got_edges, got_corners = pm.triangle_edges(tris, mesh.vertex_count, out=out)
    np.testing.assert_array_equal(got_edges, edges)
    np.testing.assert_array_equal(got_corners, corners)
    assert np.shares_memory(got_edges, out[0]) and np.shares_memory(got_corners, out[1])
    small = pm.triangulate(fibonacci_sphere(300))
    want = pm.triangle_edges(small.triangles, small.vertex_count)
    for got, expected in zip(pm.triangle_edges(small.triangles, small.vertex_count, out=out), want):
        np.testing.assert_array_equal(got, expected)
    for bad, what in (((out[0][:10], out[1]), "edges"), ((out[0], out[1].astype(np.int64)), "corners"),
                      ((out[0][:, :1], out[1]), "edges"), ((out[0], out[1][::2]), "corners")):
        with pytest.raises(pm.Error, match=f"out's {what} must be"):
            pm.triangle_edges(tris, mesh.vertex_count, out=bad)
    for bad in (5, (out[0],), [out[0], out[1], out[1]]):
        with pytest.raises(pm.Error, match="out must be a pair"):
            pm.triangle_edges(tris, mesh.vertex_count, out=bad)
    shared = np.empty(9 * len(tris), np.uint32)
    tris32 = np.ascontiguousarray(tris, dtype=np.uint32)
    for bad in ((shared[:6 * len(tris)].reshape(-1, 2), shared[3 * len(tris):6 * len(tris)]),
                (out[0], tris32.reshape(-1))):
        with pytest.raises(pm.Error, match="must not overlap"):
            pm.triangle_edges(tris32, mesh.vertex_count, out=bad)


def test_ray_crossings_are_odd_inside_a_closed_surface_whatever_its_winding(pm):
    mesh = pm.triangulate(fibonacci_sphere(2000))
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.5, 1.5, (500, 3))
    r = np.linalg.norm(q, axis=1)
    count = pm.ray_crossings(mesh, q)
    assert count.dtype == np.uint64 and count.shape == (500,)
    assert np.all(count[r < 0.95] == 1)  # inside: the ray leaves once
    assert np.all(count[r > 1.05] % 2 == 0) and np.any(count[r > 1.05] == 2)
    turned = pm.Mesh(mesh.vertices, mesh.triangles[:, ::-1])
    np.testing.assert_array_equal(pm.ray_crossings(turned, q, threads=1), count)
    # Two halves, each over its own vertices in the whole one's order, add up to it.
    upper = mesh.vertices[mesh.triangles].mean(axis=1)[:, 2] > 0.1
    halves = []
    for keep in (upper, ~upper):
        t = mesh.triangles[keep]
        v = np.unique(t)
        halves.append(pm.ray_crossings(pm.Mesh(mesh.vertices[v], np.searchsorted(v, t)), q))
    np.testing.assert_array_equal(halves[0] + halves[1], count)
    with pytest.raises(pm.Error, match="point 1 is not finite") as e:
        pm.ray_crossings(mesh, [[0, 0, 0], [0, np.nan, 0]])
    assert e.value.status == pm.STATUS_INVALID_INPUT
    with pytest.raises(pm.Error, match="refers to vertex 2000 of 2000"):
        pm.ray_crossings(pm.Mesh(mesh.vertices, np.array([[0, 1, 2000]])), q)
    assert len(pm.ray_crossings(mesh, np.zeros((0, 3)))) == 0


def test_a_frame_collection_lists_its_files_by_time(pm, tmp_path):
    (tmp_path / "sim.pvd").write_text(
        '<?xml version="1.0"?><VTKFile type="Collection"><Collection>'
        '<DataSet timestep="2" file="b.vtu"/><DataSet timestep="1" file="sub\\a.vtu"/>'
        '</Collection></VTKFile>')
    assert pm.is_frame_collection(tmp_path / "sim.pvd") and pm.is_frame_collection("a/F.VTU.SERIES")
    assert not pm.is_frame_collection("f_{}.pvd") and not pm.is_frame_collection("f.vtu")
    assert pm.read_frame_collection(tmp_path / "sim.pvd") == [
        (1.0, str(tmp_path / "sub" / "a.vtu")), (2.0, str(tmp_path / "b.vtu"))]
    (tmp_path / "up.series").write_text('{"files": [{"name": "../a.vtu", "time": 0}]}')
    with pytest.raises(pm.Error, match="'../a.vtu' is not a path inside the collection's folder") as e:
        pm.read_frame_collection(tmp_path / "up.series")
    assert e.value.status == pm.STATUS_FORMAT_ERROR
    with pytest.raises(pm.Error, match="none.pvd"):
        pm.read_frame_collection(tmp_path / "none.pvd")
    with pytest.raises(pm.Error, match="a collection of frames .* read_frame_collection lists its files"):
        pm.read_points(tmp_path / "sim.pvd")


def test_index_arrays_name_the_index_as_passed(pm):
    # The C ABI takes unsigned (or 32-bit) indices: -1 and 2^32 must be named as passed, not
    # as their 32-bit wraps (4294967295, 0), with the triangle and the corner that hold them.
    tris = np.array([[0, 1, 2], [0, 2, -1]])
    with pytest.raises(pm.Error, match=r"^triangle 1 corner 2 \(triangles\[1\]\[2\]\) has "
                       r"vertex index -1, which is negative$") as e:
        pm.triangle_edges(tris, 3)
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT
    with pytest.raises(pm.Error, match=r"triangle 0 corner 1 .* vertex index 4294967296, "
                       r"which is beyond the largest index 4294967295"):
        pm.triangle_edges(np.array([[0, 2 ** 32, 1]]), 3)
    with pytest.raises(pm.Error, match="must hold integer vertex indices"):
        pm.triangle_edges(np.array([[0, 1, 2.5]]), 3)
    with pytest.raises(pm.Error, match="vertex_count must not be negative, got -1"):
        pm.triangle_edges(np.array([[0, 1, 2]]), -1)
    p = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(pm.Error, match=r"triangle 0 corner 2 .* vertex index 2147483648"):
        pm.topology(pm.Mesh(p, np.array([[0, 1, 2 ** 31]])))
    t = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    with pytest.raises(pm.Error, match=r"crease edge 0 end 1 .* vertex index 4294967296"):
        pm.smooth(pm.Mesh(p, t), crease_edges=[[0, 2 ** 32]])


# ---- polygonize and smooth ----------------------------------------------------------------------

def test_polygonize_one_particle_is_a_sphere(pm):
    mesh = pm.polygonize(np.zeros((1, 3)), radius=1.0, threshold=0.5, cell=0.05)
    rep = pm.topology(mesh)
    assert rep["closed"] and rep["manifold"] and rep["euler_characteristic"] == 2 and rep["outward"]
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert r.std() < 0.05 * r.mean()
    assert mesh.stats["radius"] == 1.0 and mesh.stats["threshold"] == 0.5
    assert mesh.stats["cell_size"] == 0.05 and mesh.stats["triangles"] == mesh.triangle_count
    # The same with the C field's own name, and each kernel by name.
    same = pm.polygonize(np.zeros((1, 3)), radius=1.0, threshold=0.5, cell_size=0.05)
    np.testing.assert_array_equal(same.triangles, mesh.triangles)
    radii = {}
    for kernel in pm.KERNELS:
        m = pm.polygonize(np.zeros((1, 3)), radius=1.0, threshold=0.5, kernel=kernel, cell=0.05)
        radii[kernel] = np.linalg.norm(m.vertices, axis=1).mean()
    assert len(set(np.round(list(radii.values()), 3))) == 4  # four different kernels


def test_polygonize_radii_strengths_and_defaults(pm):
    p = np.array([[0.0, 0, 0], [5.0, 0, 0]])
    mesh = pm.polygonize(p, radii=[1.0, 2.0], strengths=[1.0, 1.0], threshold=0.5, cell=0.05)
    left = mesh.vertices[mesh.vertices[:, 0] < 2.5]
    right = mesh.vertices[mesh.vertices[:, 0] >= 2.5]
    r_left = np.linalg.norm(left - p[0], axis=1).mean()
    r_right = np.linalg.norm(right - p[1], axis=1).mean()
    assert r_right == pytest.approx(2 * r_left, rel=0.02)  # the field scales with R
    with pytest.raises(pm.Error, match="radii has 1 values for 2 points"):
        pm.polygonize(p, radii=[1.0])
    g = np.stack(np.meshgrid(np.arange(10), np.arange(10), np.arange(10), indexing="ij"), -1).reshape(-1, 3)
    block = 0.1 * g.astype(np.float64)
    auto = pm.polygonize(block)
    assert auto.stats["radius"] == pytest.approx(2 * auto.stats["spacing"]) == pytest.approx(0.2)
    assert pm.default_radius(block) == auto.stats["radius"]
    assert auto.stats["cell_size"] == pytest.approx(auto.stats["radius"] / 4)
    assert pm.topology(auto)["closed"]
    # How the particles sit in their field: uniform random points are mostly outside the
    # surface at 2 x their median nearest-neighbour distance; the radius their packing
    # suggests takes most in, and is the default.
    scattered = np.random.default_rng(5).uniform(0, 1, (4000, 3))
    two = 2 * pm.estimate_spacing(scattered)
    s = pm.polygonize(scattered, radius=two).stats
    assert s["enclosed_fraction"] < 0.2 and s["density_radius"] > 1.25 * s["radius"]
    d = pm.polygonize(scattered).stats
    assert d["radius"] == s["density_radius"] == pm.default_radius(scattered)
    assert d["enclosed_fraction"] > 0.5
    # The packing is read in units of the median strength; other kernels read it their way.
    assert pm.default_radius(scattered, strengths=np.full(len(scattered), 2.0)) == d["radius"]
    assert pm.default_radius(scattered, kernel="poly6") != d["radius"]
    with pytest.raises(pm.Error, match="strengths"):
        pm.default_radius(scattered, strengths=[1.0])
    with pytest.raises(pm.Error, match="spacing"):
        pm.default_radius(np.zeros((3, 3)))


def test_polygonize_anisotropic_and_finishing(pm):
    """The appended option fields reach the library: anisotropic kernels keep a jittered
    block's volume (the default threshold is calibrated on the particles), small pieces go,
    Taubin smoothing keeps the surface closed."""
    rng = np.random.default_rng(4)
    g = np.stack(np.meshgrid(np.arange(12), np.arange(8), np.arange(12), indexing="ij"), -1).reshape(-1, 3)
    block = (g + rng.uniform(-0.15, 0.15, g.shape)).astype(np.float64)
    iso = pm.polygonize(block)
    an = pm.polygonize(block, anisotropic=True)
    assert not iso.stats["anisotropic"] and an.stats["anisotropic"] == 1
    assert an.stats["anisotropic_particles"] == len(block)
    assert 1.5 < an.stats["calibration_ratio"] < 2.0
    rep = pm.topology(an)
    assert rep["closed"] and rep["manifold"] and rep["components"] == 1

    def volume(m):
        a, b, c = (m.vertices[m.triangles[:, k]] for k in range(3))
        return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6

    assert abs(volume(an) / len(block) - 1) < 0.05
    assert abs(volume(an) / len(block) - 1) < abs(volume(iso) / len(block) - 1)
    # A far pair of particles at a low threshold is a small piece; min_component_particles drops it.
    pair = np.vstack([block, [[40, 0, 0], [40.5, 0, 0]]])
    kept = pm.polygonize(pair, threshold=0.8)
    dropped = pm.polygonize(pair, threshold=0.8, min_component_particles=20, taubin_iterations=3)
    assert pm.topology(kept)["components"] == 2
    assert pm.topology(dropped)["components"] == 1 and pm.topology(dropped)["closed"]
    assert dropped.stats["components_removed"] == 1


def test_polygonize_collapses_short_edges(pm):
    """collapse_edges: marching cubes' slivers collapsed, the surface still closed and of the
    same topology, fewer triangles; the count in stats; out of range an Error naming it."""
    rng = np.random.default_rng(4)
    p = rng.uniform(-1, 1, (20000, 3))
    p = p[np.linalg.norm(p, axis=1) < 1] * [1.0, 0.6, 0.8]
    velocity = p * 2
    raw = pm.polygonize(p, attributes={"velocity": velocity})
    clean = pm.polygonize(p, attributes={"velocity": velocity}, collapse_edges=0.3)
    assert raw.stats["edges_collapsed"] == 0
    n = clean.stats["edges_collapsed"]
    assert n > 0.03 * raw.triangle_count
    assert clean.vertex_count == raw.vertex_count - n
    assert clean.triangle_count == raw.triangle_count - 2 * n
    r0, r1 = pm.topology(raw), pm.topology(clean)
    assert r1["closed"] and r1["manifold"] and r1["outward"]
    assert (r1["components"], r1["euler_characteristic"]) == (r0["components"], r0["euler_characteristic"])
    assert clean.attributes["velocity"].shape == (clean.vertex_count, 3)
    # The merged vertices' values are the particles' at their place, as for every vertex.
    asked = pm.polygonize_attributes(p, clean.vertices, attributes={"velocity": velocity})
    np.testing.assert_array_equal(asked["velocity"], clean.attributes["velocity"])
    for bad in (-1, 0.7, float("nan")):
        with pytest.raises(pm.Error, match="collapse_edges"):
            pm.polygonize(p, collapse_edges=bad)


def test_polygonize_attributes_are_polygonizes_own(pm):
    """Meshed without attributes, then interpolated at the float64 vertices: the values
    polygonize gives them itself, bit for bit, with the same keywords (float32 particles as
    Blender gives them, per-particle radii, a tile's domain); clear errors for bad points."""
    rng = np.random.default_rng(3)
    cloud = fibonacci_sphere(20000, dtype=np.float32)
    velocity = rng.uniform(-1, 1, (len(cloud), 3)).astype(np.float32)
    heat = rng.uniform(0, 10, len(cloud)).astype(np.float32)
    for kwargs in ({}, {"kernel": "poly6", "threads": 1},
                   {"radii": rng.uniform(0.03, 0.05, len(cloud)), "threshold": 0.6},
                   {"radius": 0.05, "domain_min": (-1.5, -1.5, -1.5), "domain_max_radius": 0.08}):
        attrs = {"velocity": velocity, "heat": heat}
        full = pm.polygonize(cloud, attributes=attrs, **kwargs)
        plain = pm.polygonize(cloud, **kwargs)
        np.testing.assert_array_equal(plain.vertices, full.vertices)
        assert plain.attributes == {}
        got = pm.polygonize_attributes(cloud, plain.vertices, attributes=attrs, **kwargs)
        assert list(got) == ["velocity", "heat"]
        assert got["velocity"].shape == (plain.vertex_count, 3) and got["velocity"].dtype == np.float32
        assert got["heat"].shape == (plain.vertex_count, 1)
        for name in attrs:
            want = full.attributes[name].reshape(got[name].shape)
            assert got[name].tobytes() == want.tobytes(), (kwargs, name)
    # Points: the cloud's own Points carry their attributes; no attributes, nothing.
    points = pm.Points(cloud, attributes={"heat": heat})
    again = pm.polygonize_attributes(points, plain.vertices[:10], radius=0.05,
                                     domain_min=(-1.5, -1.5, -1.5), domain_max_radius=0.08)
    assert again["heat"].tobytes() == got["heat"][:10].tobytes()
    assert pm.polygonize_attributes(cloud, plain.vertices[:10]) == {}
    # float32 vertices are other points: their values differ from the mesh's.
    rounded = pm.polygonize_attributes(cloud, plain.vertices.astype(np.float32),
                                       attributes={"heat": heat}, radius=0.05,
                                       domain_min=(-1.5, -1.5, -1.5), domain_max_radius=0.08)
    assert rounded["heat"].tobytes() != got["heat"].tobytes()
    with pytest.raises(pm.Error, match=r"points\[1\]\.y is NaN"):
        pm.polygonize_attributes(cloud, [[0, 0, 0], [0, np.nan, 0]], attributes={"heat": heat})
    with pytest.raises(pm.Error, match=r"points must have shape \(N, 3\)"):
        pm.polygonize_attributes(cloud, np.zeros((4, 2)), attributes={"heat": heat})
    with pytest.raises(pm.Error, match="attribute 'heat' has shape"):
        pm.polygonize_attributes(cloud, np.zeros((4, 3)), attributes={"heat": heat[:5]})
    with pytest.raises(pm.Error, match="radius"):
        pm.polygonize_attributes(cloud, np.zeros((4, 3)), radius=-1.0, attributes={"heat": heat})


def test_lattice_field(pm):
    # Half the lattice field at R = 2 spacings is the default threshold (3.33 for Wyvill).
    assert 0.5 * pm.lattice_field("wyvill", 2.0, 1.0) == pytest.approx(3.33, abs=0.01)
    assert pm.lattice_field("poly6", 2.0, 1.0) == pm.lattice_field(pm.KERNELS["poly6"], 2.0, 1.0)


def test_smooth_loop_butterfly_creases_attributes(pm):
    p, t = tetrahedron()
    heat = np.arange(4, dtype=np.float32)
    for levels in (1, 2):
        out = pm.smooth(pm.Mesh(p, t, attributes={"heat": heat}), levels=levels)
        assert out.triangle_count == 4 * 4 ** levels
        assert pm.topology(out)["closed"] and out.normals is not None
        assert out.attributes["heat"].shape == (out.vertex_count, 1)
        assert heat.min() <= out.attributes["heat"].min() <= out.attributes["heat"].max() <= heat.max()
    bf = pm.smooth(pm.Mesh(p, t), scheme="butterfly")
    np.testing.assert_allclose(bf.vertices[:4], p, atol=1e-12)  # interpolating
    loop = pm.smooth(pm.Mesh(p, t), limit=False)
    creased = pm.smooth(pm.Mesh(p, t), limit=False, crease_edges=[[0, 1]])
    assert not np.allclose(loop.vertices, creased.vertices)
    soft = pm.smooth(pm.Mesh(p, t), limit=False, crease_edges=[[0, 1]], crease_sharpness=[0.0])
    np.testing.assert_allclose(soft.vertices, loop.vertices, atol=1e-12)
    with pytest.raises(pm.Error, match=r"crease_edges must have shape \(K, 2\)"):
        pm.smooth(pm.Mesh(p, t), crease_edges=[0, 1])
    with pytest.raises(pm.Error, match=r"levels"):
        pm.smooth(pm.Mesh(p, t), levels=11)


# ---- .pcd through the PCL bridge ----------------------------------------------------------------

@pytest.fixture
def bridge(pm):
    import os
    if os.environ.get("PM_WITH_PCL") != "1":
        pytest.skip("the build has no PCL bridge (PM_WITH_PCL=OFF)")
    return pm.pcl_bridge_path()


def test_read_pcd_with_normals_and_colours(pm, pm_library, bridge, data_dir):
    assert bridge.startswith(pm_library.LIB_DIR)
    cloud = pm.read_points(data_dir / "pcd/colored_cloud.pcd")
    assert cloud.positions.shape == (1000, 3) and cloud.normals.shape == (1000, 3)
    colour = cloud.attributes["color"]
    assert colour.shape == (1000, 3) and colour.min() >= 0.0 and colour.max() <= 1.0
    np.testing.assert_allclose(colour * 255.0, np.round(colour * 255.0), atol=1e-3)
    assert cloud.info["format"] == "pcd" and cloud.info["has_color"] and cloud.info["has_normals"]
    assert (cloud.info["width"], cloud.info["height"]) == (1, 1000)


def test_read_pcd_drops_nan_points_and_says_so(pm, bridge, data_dir):
    cloud = pm.read_points(data_dir / "pcd/kinect_frame_20121214T142255.814212_binary.pcd")
    assert len(cloud.positions) == 307200 - 35625 and np.isfinite(cloud.positions).all()
    assert cloud.info["invalid_points"] == 35625 and cloud.normals is None


def test_read_malformed_pcd_names_the_file(pm, bridge, tmp_path):
    bad = tmp_path / "bad header.pcd"
    bad.write_text("VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0\n")
    with pytest.raises(pm.Error, match="missing field 'z'") as e:
        pm.read_points(bad)
    assert e.value.status == pm.STATUS_FORMAT_ERROR and str(bad) in str(e.value)


def test_preprocess_scan_smooths_noise_and_keeps_each_points_channels(pm, bridge):
    """preprocess_scan (the PCL bridge's pm_pcl_preprocess): moving least squares takes a
    scanner's noise off a sphere, outlier removal drops the stray points, each output point
    keeps its channels (by .info["kept"]), the normals face the viewpoint, the output is the
    same for any thread count; bad parameters are errors naming them."""
    n = 6000
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = i * np.pi * (3 - np.sqrt(5))
    sphere = np.c_[np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z]
    rng = np.random.default_rng(3)
    noisy = sphere * (1 + rng.uniform(-0.02, 0.02, (n, 1)))
    strays = rng.uniform(-3, 3, (30, 3))
    strays *= 2.5 / np.linalg.norm(strays, axis=1, keepdims=True)  # all 1.5 off the sphere
    points = np.vstack([noisy, strays])
    ids = np.arange(len(points), dtype=np.float32)
    out = pm.preprocess_scan(points, attributes={"id": ids}, remove_outliers=True, mls_radius=0.12,
                             estimate_normals=True, viewpoint=(0, 0, 0))
    kept = out.info["kept"]
    assert not np.isin(np.arange(n, n + 30), kept).any()  # every stray dropped
    assert out.info["outliers_removed"] >= 30 and out.info["output_points"] == len(out)
    np.testing.assert_array_equal(out.attributes["id"].ravel(), ids[kept])
    before = np.abs(np.linalg.norm(points[kept], axis=1) - 1).mean()
    after = np.abs(np.linalg.norm(out.positions, axis=1) - 1).mean()
    assert after < before / 2, (before, after)
    assert out.info["smoothed"] > 0.99 * len(out) and out.info["normals_estimated"]
    assert ((out.normals * out.positions).sum(axis=1) < 0).all()  # facing the centre
    again = pm.preprocess_scan(points, remove_outliers=True, mls_radius=0.12, estimate_normals=True,
                               threads=1)
    np.testing.assert_array_equal(again.positions, out.positions)
    thin = pm.preprocess_scan(points, downsampling="voxel-grid", leaf_size=0.1)
    assert 0 < len(thin) < len(points) and thin.info["downsampled_away"] == len(points) - len(thin)
    assert pm.defaults("preprocess_scan")["normal_k"] == 20
    with pytest.raises(pm.Error, match="leaf size > 0") as e:
        pm.preprocess_scan(points, downsampling="uniform")
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT
    with pytest.raises(pm.Error, match="downsampling is 'cubes'; it must be one of none, uniform, voxel-grid"):
        pm.preprocess_scan(points, downsampling="cubes")
    with pytest.raises(pm.Error, match="viewpoint must be 3 finite numbers"):
        pm.preprocess_scan(points, estimate_normals=True, viewpoint=(0, np.nan, 0))
    with pytest.raises(TypeError, match="unexpected keyword argument 'radius'"):
        pm.preprocess_scan(points, radius=1)


def test_missing_pcl_bridge_gives_a_clear_message(pm, pm_library, monkeypatch, tmp_path, data_dir):
    monkeypatch.setattr(pm_library, "_bridges", {})
    monkeypatch.setattr(pm_library, "pcl_candidate_paths", lambda core: ([], [str(tmp_path)]))
    with pytest.raises(pm.PclBridgeNotFoundError,
                       match=r"reading \.pcd and preprocess_scan need the PCL bridge library "
                             r"libparticlemesh_pcl") as e:
        pm.read_points(data_dir / "pcd/bun0.pcd")
    assert str(tmp_path) in str(e.value) and "PARTICLEMESH_PCL_LIBRARY" in str(e.value)
    assert len(pm.read_points(data_dir / "points/spot_poisson.ply").positions) == 8747
    monkeypatch.undo()
    monkeypatch.setattr(pm_library, "_bridges", {})
    bogus = tmp_path / "bogus.so"
    bogus.write_text("not a library")
    monkeypatch.setenv("PARTICLEMESH_PCL_LIBRARY", str(bogus))
    with pytest.raises(pm.PclBridgeNotFoundError, match="does not load"):
        pm.read_points(data_dir / "pcd/bun0.pcd")


def test_every_option_is_documented(pm):
    """docs/python.md has a table row for every keyword of every options struct (a field
    appended to the C struct needs its row)."""
    from conftest import ROOT
    doc = (ROOT / "docs" / "python.md").read_text()
    for function in ("triangulate", "polygonize", "smooth"):
        section = doc.split(f"### `{function}(")[1].split("\n### ")[0]
        for keyword in pm.defaults(function):
            assert f"| `{keyword}`" in section, f"docs/python.md: {function}() option {keyword}"
    # The Smoother takes smooth()'s keywords: its section names each one, and its methods.
    section = doc.split("### `Smoother(")[1].split("\n### ")[0]
    for keyword in list(pm.defaults("smooth")) + ["crease_edges", "crease_sharpness", "progress"]:
        assert f"`{keyword}`" in section, f"docs/python.md: Smoother() option {keyword}"
    for member in ("evaluate", "matches", "close", "vertex_count", "triangle_count"):
        assert hasattr(pm.Smoother, member) or member.endswith("_count")
        assert f"`{member}" in section, f"docs/python.md: Smoother.{member}"


def test_smoother_evaluates_what_smooth_gives(pm):
    """Refine once, evaluate many: each frame's evaluate() equals smooth() of that frame, byte
    for byte (positions, normals, triangles, attributes), for Loop and butterfly."""
    base = pm.triangulate(fibonacci_sphere(2000))
    for scheme in ("loop", "butterfly"):
        with pm.Smoother(base, scheme=scheme, levels=2, threads=2) as smoother:
            assert smoother.vertex_count == len(base.vertices)
            assert smoother.triangle_count == len(base.triangles)
            for frame in range(3):
                wobble = 1 + 0.03 * np.sin(frame + np.arange(len(base.vertices)))[:, None]
                moved = pm.Mesh(base.vertices * wobble, base.triangles,
                                attributes={"velocity": (base.vertices * frame).astype(np.float32)})
                assert smoother.matches(moved)
                got = smoother.evaluate(moved)
                want = pm.smooth(moved, scheme=scheme, levels=2, threads=2)
                assert got.vertices.tobytes() == want.vertices.tobytes(), scheme
                assert got.normals.tobytes() == want.normals.tobytes(), scheme
                assert np.array_equal(got.triangles, want.triangles)
                assert got.attributes["velocity"].tobytes() == want.attributes["velocity"].tobytes()


def test_loop_keeps_a_non_manifold_edge_sharp_and_butterfly_refuses_it(pm):
    # A fin: three squares on one edge, the x axis from 0 to 1, at uneven angles.
    v, t = [[0, 0, 0], [1, 0, 0]], []
    for a in (0.0, 1.9, 4.0):
        d = [0, np.cos(a), np.sin(a)]
        v += [[1, d[1], d[2]], [0, d[1], d[2]]]
        b = len(v) - 2
        t += [[0, 1, b], [0, b, b + 1]]
    fin = pm.Mesh(np.array(v, float), np.array(t))
    assert pm.topology(fin)["nonmanifold_edges"] == 1
    out = pm.smooth(fin, levels=2)
    top = pm.topology(out)
    assert top["nonmanifold_edges"] == 4 and top["triangles"] == 16 * len(t)
    e = np.sort(out.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    spine = np.unique(edges[count == 3])
    assert np.abs(out.vertices[spine][:, 1:]).max() < 1e-12  # still on the x axis
    smoother = pm.Smoother(fin, levels=2)
    np.testing.assert_array_equal(smoother.evaluate(fin).vertices, out.vertices)
    with pytest.raises(pm.Error, match=r"shared by 3 triangles .*the Loop scheme smooths such meshes"):
        pm.smooth(fin, scheme="butterfly")


def test_smoother_refuses_other_meshes_and_closed_use(pm):
    base = pm.triangulate(fibonacci_sphere(1000))
    smoother = pm.Smoother(base, levels=1)
    other = pm.triangulate(fibonacci_sphere(1200))
    assert not smoother.matches(other)
    shuffled = pm.Mesh(base.vertices, base.triangles[::-1].copy())
    assert not smoother.matches(shuffled)
    with pytest.raises(pm.Error, match="does not have the triangles") as e:
        smoother.evaluate(other)
    assert e.value.status == pm.STATUS_INVALID_ARGUMENT
    bad = pm.Mesh(base.vertices.copy(), base.triangles)
    bad.vertices[3, 1] = np.nan
    with pytest.raises(pm.Error, match=r"positions\[3\]"):
        smoother.evaluate(bad)
    smoother.close()
    with pytest.raises(pm.Error, match="closed"):
        smoother.evaluate(base)
    with pytest.raises(pm.Error, match="levels"):
        pm.Smoother(base, levels=11)
    # Its own progress, and cancellation from it.
    seen = []
    pm.Smoother(base, levels=2, progress=lambda stage, f: seen.append(stage) or True)
    assert seen
    with pytest.raises(pm.CancelledError):
        pm.Smoother(base, levels=2, progress=lambda stage, f: False)


def test_what_a_file_holds_but_does_not_read_is_said(pm, tmp_path):
    """read_points names the per-particle data it does not carry (a Houdini string attribute, a
    VTK string array) in info["not_read"] and in a NotReadWarning; a file whose every value is
    read gives an empty list and no warning."""
    import sys
    import warnings
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from particle_files import particles, write_bgeo, write_ply

    p, a = particles(0)
    write_bgeo(tmp_path / "named.bgeo", p, a, names=["water", "foam"])
    write_ply(tmp_path / "plain.ply", p, a)
    with pytest.warns(pm.NotReadWarning, match=r"named\.bgeo: not read: point attribute 'name' \(strings\)"):
        cloud = pm.read_points(tmp_path / "named.bgeo")
    assert cloud.info["not_read"] == ["point attribute 'name' (strings)"]
    assert set(cloud.attributes) == {"velocity", "density"}
    np.testing.assert_array_equal(cloud.positions, p.astype(np.float64))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert pm.read_points(tmp_path / "plain.ply").info["not_read"] == []
    assert issubclass(pm.NotReadWarning, UserWarning)


def test_simulator_files_carry_their_channels(pm, tmp_path):
    """read_points reads VTK, classic and binary-JSON bgeo particles (Houdini's .bgeo.sc too) with
    their channels; polygonize interpolates them onto the vertices (a constant field exactly), triangulate
    keeps them."""
    import sys
    import warnings
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from particle_files import particles, write_bgeo, write_bgeo_json, write_sc, write_vtu

    p, a = particles(0)
    a["velocity"][:] = np.array([1.0, 0.5, -2.0], np.float32)
    write_vtu(tmp_path / "f.vtu", p, a, "appended")
    write_bgeo(tmp_path / "f.bgeo", p, a)
    write_bgeo_json(tmp_path / "j.bgeo", p, a, page=64)  # velocity: constant pages
    write_sc(write_bgeo_json, block=512)(tmp_path / "j.bgeo.sc", p, a)
    for name in ("f.vtu", "f.bgeo", "j.bgeo", "j.bgeo.sc"):
        with warnings.catch_warnings():  # the binary-JSON files' string attribute "name" is said
            warnings.simplefilter("ignore", pm.NotReadWarning)
            cloud = pm.read_points(tmp_path / name)
        assert cloud.info["not_read"] == (["point attribute 'name' (strings)"] if name.startswith("j") else []), name
        np.testing.assert_array_equal(cloud.positions, p.astype(np.float64))
        assert set(cloud.attributes) == {"velocity", "density"}
        np.testing.assert_array_equal(cloud.attributes["density"].ravel(), a["density"])
        mesh = pm.polygonize(cloud, radius=0.14, cell=0.03)
        assert mesh.triangle_count > 100
        np.testing.assert_allclose(mesh.attributes["velocity"], [[1.0, 0.5, -2.0]] * mesh.vertex_count,
                                   atol=1e-5)
        d = mesh.attributes["density"]
        assert d.min() >= a["density"].min() - 1e-3 and d.max() <= a["density"].max() + 1e-3


def test_rows_far_apart_show_their_spacing_before_the_cap(pm):
    """The last stats fields reach Python intact: a sphere sampled in 25 rings of up to 300
    points (six times closer along a ring than across) has its local spacings held to the
    3 r0 cap, and the stats give their 90th percentile before it (over 3 r0) and the rows'
    spacing over the nearest distance (2 and more); an even sampling gives 0 for both."""
    rings = []
    for k in range(25):
        t = (k + 0.5) / 25 * np.pi
        m = max(6, round(300 * np.sin(t)))
        a = 2 * np.pi * np.arange(m) / m
        rings.append(np.c_[np.sin(t) * np.cos(a), np.sin(t) * np.sin(a), np.full(m, np.cos(t))])
    mesh = pm.triangulate(np.concatenate(rings))
    assert 3.5 < mesh.stats["uncapped_spacing_p90"] < 6, mesh.stats
    assert 2 <= mesh.stats["capped_spacing_over_nn"] < 10, mesh.stats
    even = pm.triangulate(fibonacci_sphere(5000))
    assert even.stats["uncapped_spacing_p90"] == 0 == even.stats["capped_spacing_over_nn"]
