"""The add-on's operators inside Blender: triangulate (point cloud objects and particle
systems), import, smooth, polygonize, undo, and bad inputs that must cancel with an error
report while Blender keeps running."""
import math
import tomllib
from pathlib import Path

import bpy
import numpy as np
import pytest

from conftest import (emitter, living_particles, make_active, mesh_arrays, point_cloud_object,
                      redo, shown_mesh, undo)


def fibonacci_sphere(n, radius=1.0):
    i = np.arange(n, dtype=np.float64) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / n)
    theta = np.pi * (1.0 + 5.0 ** 0.5) * i
    p = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)
    return (radius * p).astype(np.float32)


def face_normals(co, tris):
    p = co.astype(np.float64)
    return np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])


def ply_vertex_count(path):
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"element vertex"):
                return int(line.split()[2])
            if line.startswith(b"end_header"):
                break
    raise AssertionError(f"no vertex element in {path}")


# ---- package ----------------------------------------------------------------------------------

def test_installed_from_the_zip_with_its_own_library(pm):
    installed = Path(pm.__file__).resolve().parent
    # The add-on's binding is the particlemesh package, carried in particlemesh/particlemesh/
    # with its library and the libraries that needs (a zip that runs on any Linux Blender).
    assert Path(pm.particlemesh.__file__).resolve().parent == installed / "particlemesh"
    assert Path(pm.particlemesh.library_path()).resolve().parent == installed / "particlemesh" / "lib"
    assert (installed / "particlemesh" / "lib" / "libtbb.so.12").is_file()
    manifest = tomllib.loads((installed / "blender_manifest.toml").read_text())
    assert manifest["version"] == ".".join(map(str, pm.bl_info["version"]))
    assert manifest["id"] == pm.__package__ == "particlemesh"
    for op in ("triangulate", "polygonize", "smooth", "import_cloud", "bake"):
        assert hasattr(bpy.ops.particlemesh, op), op
        assert "UNDO" in getattr(bpy.types, f"PARTICLEMESH_OT_{op}").bl_options
    assert hasattr(bpy.types, "VIEW3D_PT_particlemesh")
    import_menu = [f.__name__ for f in bpy.types.TOPBAR_MT_file_import._dyn_ui_initialize()]
    assert "menu_import" in import_menu


# ---- triangulate a point-cloud object ---------------------------------------------------------

def import_cloud(path):
    assert bpy.ops.particlemesh.import_cloud(filepath=str(path)) == {"FINISHED"}
    return bpy.context.active_object


def test_triangulate_scan_from_shared_data(pm, data_dir):
    source = import_cloud(data_dir / "points/spot_poisson.ply")
    assert source.name == "spot_poisson"
    assert len(source.data.vertices) == 8747 and len(source.data.polygons) == 0
    normals = pm.blender_mesh.get_point_attribute(source.data, "point_normal")
    assert normals.shape == (8747, 3)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-4)

    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
    result = bpy.context.active_object
    assert result is not source and result.name == "spot_poisson_triangulate"
    assert result.select_get() and not source.select_get()
    assert len(source.data.vertices) == 8747 and len(source.data.polygons) == 0  # source stays
    mesh = result.data
    co, tris = mesh_arrays(mesh)
    src_co, _ = mesh_arrays(source.data)
    np.testing.assert_array_equal(co, src_co)  # vertex i is particle i
    # The same triangles as the library gives for these particles, directly.
    direct = pm.particlemesh.triangulate(src_co, normals=normals)
    assert len(tris) == direct.triangle_count
    assert 2 * 8747 * 0.95 < len(tris) < 2 * 8747 * 1.35
    # Poisson-disk r0 = 0.02: every edge within the default 2 x estimated spacing, hole-filling
    # triangles within 1.5 x that.
    spacing = direct.stats["spacing"]
    assert 0.02 <= spacing < 0.025
    edges = np.linalg.norm(co[tris] - co[np.roll(tris, 1, axis=1)], axis=2)
    assert edges.max() <= 1.5 * 2 * spacing * (1 + 1e-5)
    # The finished surface: closed, manifold, outward, genus 0 (F = 2V - 4).
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
    assert rep["closed"] and rep["manifold"] and rep["consistently_oriented"] and rep["outward"]
    assert rep["euler_characteristic"] == 2 and rep["vertices_used"] == 8747
    assert len(tris) == 2 * 8747 - 4
    # Shading-ready: smooth faces; the library's normals are angle-weighted face normals,
    # which Blender computes itself, so no custom normals are needed: check they agree.
    smooth = np.empty(len(mesh.polygons), bool)
    mesh.polygons.foreach_get("use_smooth", smooth)
    assert smooth.all()
    assert not mesh.has_custom_normals
    blender_normals = pm.blender_mesh.vertex_normals(mesh)
    cosine = np.einsum("ij,ij->i", blender_normals, direct.normals)
    assert cosine.min() > np.cos(np.radians(0.5))
    assert (np.einsum("ij,ij->i", face_normals(co, tris), direct.normals[tris].sum(axis=1)) > 0).all()
    assert not mesh.validate(verbose=False), "mesh.validate() had to fix the mesh"
    # It remembers where it came from.
    state = result.particlemesh
    assert state.is_generated and state.source == source and state.method == "TRIANGULATE"
    assert state.source_kind == "VERTICES" and state.viewport.auto_spacing


def test_raw_triangles_use_the_scan_normals(pm, data_dir):
    source = import_cloud(data_dir / "points/spot_poisson.ply")
    normals = pm.blender_mesh.get_point_attribute(source.data, "point_normal")
    assert bpy.ops.particlemesh.triangulate(raw=True) == {"FINISHED"}
    mesh = bpy.context.active_object.data
    co, tris = mesh_arrays(mesh)
    assert len(tris) == pm.particlemesh.triangulate(co, raw=True).triangle_count
    assert mesh.has_custom_normals  # the scan's normals, as custom split normals
    assert (np.einsum("ij,ij->i", face_normals(co, tris), normals[tris].sum(axis=1)) > 0).all()
    assert not mesh.validate(verbose=False)


def test_property_defaults_are_the_library_defaults(pm):
    opt = pm.particlemesh.defaults("triangulate")
    props = pm.properties.PARTICLEMESH_PG_generator.bl_rna.properties
    assert props["max_edge_factor"].default == pytest.approx(opt["max_edge_factor"])
    assert np.degrees(props["normal_angle"].default) == pytest.approx(opt["normal_angle"])
    assert props["fill_holes"].default == opt["fill_holes"]
    assert props["fill_edge_factor"].default == pytest.approx(opt["fill_edge_factor"])
    assert props["min_component_triangles"].default == opt["min_component_triangles"] == 0
    assert props["normal_source"].default.lower() == opt["normal_source"]
    assert props["auto_spacing"].default and opt["spacing"] == 0
    assert props["threads"].default == opt["threads"] == 0
    assert not props["raw"].default
    assert props["repair"].default and props["orient"].default
    poly = pm.particlemesh.defaults("polygonize")
    props = pm.properties.PARTICLEMESH_PG_generator.bl_rna.properties
    assert props["kernel"].default.lower() == poly["kernel"]


def test_options_reach_the_library(pm):
    p = fibonacci_sphere(3000)
    source = point_cloud_object("sphere", p)
    assert bpy.ops.particlemesh.triangulate(auto_spacing=False, spacing=0.08,
                                            max_edge_factor=1.5) == {"FINISHED"}
    co, tris = mesh_arrays(bpy.context.active_object.data)
    assert len(tris) == pm.particlemesh.triangulate(p, spacing=0.08, max_edge_factor=1.5).triangle_count
    edges = np.linalg.norm(co[tris] - co[np.roll(tris, 1, axis=1)], axis=2)
    assert edges.max() <= 1.5 * 0.12 * (1 + 1e-5)  # hole filling may reach 1.5 L
    s = bpy.context.active_object.particlemesh.viewport
    assert not s.auto_spacing and math.isclose(s.spacing, 0.08, rel_tol=1e-6)
    bpy.context.view_layer.objects.active = source
    assert bpy.ops.particlemesh.triangulate(fill_holes=0, normal_angle=0.5) == {"FINISHED"}
    s = bpy.context.active_object.particlemesh.viewport
    assert s.fill_holes == 0 and s.normal_angle == pytest.approx(0.5)
    direct = pm.particlemesh.triangulate(p, fill_holes=0, normal_angle=np.degrees(0.5))
    assert len(bpy.context.active_object.data.polygons) == direct.triangle_count
    assert source.name in bpy.data.objects
    # Min Piece Triangles: a lone triangle beside the sphere is kept, then removed.
    r0 = np.sqrt(4 * np.pi / 3000)
    with_lone = np.concatenate([p, [[3, 0, 0], [3 + r0, 0, 0], [3 + r0 / 2, 0.87 * r0, 0]]])
    lone = point_cloud_object("sphere_and_lone", with_lone)
    counts = []
    for minimum in (0, 2):
        bpy.context.view_layer.objects.active = lone
        assert bpy.ops.particlemesh.triangulate(min_component_triangles=minimum) == {"FINISHED"}
        assert bpy.context.active_object.particlemesh.viewport.min_component_triangles == minimum
        counts.append(len(bpy.context.active_object.data.polygons))
    assert counts == [pm.particlemesh.triangulate(with_lone).triangle_count,
                      pm.particlemesh.triangulate(with_lone, min_component_triangles=2).triangle_count]
    assert counts[1] == counts[0] - 1


def test_world_transform_is_applied(pm):
    p = fibonacci_sphere(1500)
    source = point_cloud_object("moved", p)
    source.location = (10.0, 0.0, 0.0)
    source.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
    result = bpy.context.active_object
    co, _ = mesh_arrays(result.data)
    np.testing.assert_allclose(co, p * 2 + np.array([10, 0, 0], np.float32), atol=1e-5)
    assert tuple(result.matrix_world.translation) == (0.0, 0.0, 0.0)


# ---- particle systems -------------------------------------------------------------------------

def test_triangulate_particle_system_with_velocity(pm, clean_scene):
    em = emitter(speed=2.0)
    clean_scene.frame_set(3)
    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
    result = bpy.context.active_object
    state = result.particlemesh
    assert state.source == em and state.source_kind == "PARTICLES"
    assert state.particle_system == em.particle_systems[0].name
    positions, velocities = living_particles(em)
    assert len(positions) == len(em.data.vertices) == 642
    co, tris = mesh_arrays(result.data)
    np.testing.assert_allclose(co, positions, atol=1e-6)
    radius = np.linalg.norm(co, axis=1)
    assert radius.min() > 1.05  # the particles have flown outward
    velocity = pm.blender_mesh.get_point_attribute(result.data, "velocity")
    np.testing.assert_allclose(velocity, velocities, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(velocity, axis=1), 2.0, rtol=0.05)
    # An evenly spaced sphere: a closed outward genus-0 surface through every particle.
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
    assert rep["vertices_used"] == 642 and rep["components"] == 1
    assert rep["closed"] and rep["outward"] and len(tris) == 2 * 642 - 4
    assert not result.data.validate(verbose=False)


def test_particles_emitted_at_random_from_faces_close(pm, clean_scene):
    """Emission from faces with Distribution Random drops the particles at random (not evenly
    spaced): their edge limits are lengthened for it, and the sphere they lie on comes out as
    one closed outward surface (before, it fell apart into pieces)."""
    em = emitter(speed=0.0)
    settings = em.particle_systems[0].settings
    settings.count = 3000
    settings.emit_from = "FACE"
    settings.distribution = "RAND"
    clean_scene.frame_set(2)
    positions, _ = living_particles(em)
    assert len(positions) == 3000
    assert bpy.ops.particlemesh.triangulate(source="PARTICLES") == {"FINISHED"}
    co, tris = mesh_arrays(bpy.context.active_object.data)
    np.testing.assert_allclose(co, positions, atol=1e-6)
    mesh = pm.particlemesh.Mesh(co, tris)
    rep = pm.particlemesh.topology(mesh)
    assert rep["components"] == 1 and rep["closed"] and rep["outward"]
    assert rep["euler_characteristic"] == 2 and rep["vertices_used"] >= 2995
    assert pm.particlemesh.triangulate(positions).stats["reach_factor"] > 1.5  # (irregularity ~0.43 on the flat facets)


def test_jittered_emission_from_faces_gets_its_edge_factor(pm, clean_scene):
    """Emission from faces with Distribution Jittered (Blender's default) leaves gaps wider than
    the particles' spacing: with Edge Factor 2 the sphere comes out with holes and the warning
    names Edge Factor 3, with which it closes; Random emission gets no such warning."""
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0)
    em = bpy.context.active_object
    em.modifiers.new("particles", "PARTICLE_SYSTEM")
    settings = em.particle_systems[0].settings
    settings.count = 5000
    settings.frame_start = settings.frame_end = 1
    settings.lifetime = 1000
    settings.emit_from = "FACE"
    settings.distribution = "JIT"
    settings.normal_factor = 0.0
    settings.effector_weights.gravity = 0.0
    clean_scene.frame_set(2)
    positions, _ = living_particles(em)
    assert len(positions) == 5000
    assert bpy.ops.particlemesh.triangulate(source="PARTICLES") == {"FINISHED"}
    stats = pm.generate.triangulate(pm.generate.Particles(positions), {"auto_spacing": True}).stats
    assert stats["holes_left"] > 0
    warning = pm.generate.jittered_emission_warning(stats, {"max_edge_factor": 2.0}, ("FACE", "JIT"))
    assert warning and "Edge Factor to 3" in warning
    assert pm.generate.jittered_emission_warning(stats, {"max_edge_factor": 2.0}, ("FACE", "RAND")) is None
    assert pm.generate.jittered_emission_warning(stats, {"max_edge_factor": 2.0}, None) is None
    make_active(em)
    assert bpy.ops.particlemesh.triangulate(source="PARTICLES", max_edge_factor=3.0) == {"FINISHED"}
    co, tris = mesh_arrays(bpy.context.active_object.data)
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
    assert rep["components"] == 1 and rep["closed"] and rep["outward"] and rep["euler_characteristic"] == 2


def test_only_living_particles(pm, clean_scene):
    em = emitter(frame_start=1, frame_end=20)  # births spread over 20 frames
    clean_scene.frame_set(6)
    positions, _ = living_particles(em)
    assert 0 < len(positions) < 642
    assert bpy.ops.particlemesh.triangulate(source="PARTICLES") == {"FINISHED"}
    assert len(bpy.context.active_object.data.vertices) == len(positions)


def test_materials_kept_when_regenerated(pm, clean_scene):
    em = emitter()
    assert bpy.ops.particlemesh.triangulate(live=True) == {"FINISHED"}
    result = bpy.context.active_object
    material = bpy.data.materials.new("Skin")
    result.data.materials.append(material)
    mesh_before = result.data
    clean_scene.frame_set(4)
    assert pm.live.last_update[result.name]["frame"] == 4
    assert "error" not in pm.live.last_update[result.name]
    # The frame's own mesh (kept by the live cache), with the object's materials.
    assert shown_mesh(result) != mesh_before and list(shown_mesh(result).materials) == [material]
    # Update Now writes the object's own mesh in place, materials and all, and shows it.
    mesh_now = result.data
    assert bpy.ops.particlemesh.update() == {"FINISHED"}
    assert result.data == mesh_now and shown_mesh(result) == mesh_now
    assert list(result.data.materials) == [material]
    assert em.name in bpy.data.objects


# ---- import -----------------------------------------------------------------------------------

def test_import_every_ply_and_xyz(pm, data_dir, tmp_path):
    files = sorted((data_dir / "points").glob("*.ply")) + sorted((data_dir / "particles").glob("*.ply"))
    assert files
    for path in files:
        obj = import_cloud(path)
        assert len(obj.data.vertices) == ply_vertex_count(path), path.name
        assert len(obj.data.polygons) == 0
        has_normals = b"property float nx" in path.read_bytes()[:2000]
        assert (pm.blender_mesh.get_point_attribute(obj.data, "point_normal") is not None) == has_normals
    xyz = tmp_path / "three.xyz"
    xyz.write_text("0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n")
    obj = import_cloud(xyz)
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "point_normal"),
                               [[0, 0, 1]] * 3)
    # ParaView's CSV export: the positions last, a vector's components as Name:k; the velocity
    # becomes the FLOAT_VECTOR attribute motion blur reads, a name with a space an attribute.
    csv = tmp_path / "paraview.csv"
    csv.write_text('"Velocity:0","Velocity:1","Velocity:2","Point ID","Points:0","Points:1","Points:2"\n'
                   "1,2,3,0,0,0,0\n4,5,6,1,1,0,0\n7,8,9,2,0,1,0\n")
    obj = import_cloud(csv)
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert obj.data.attributes["velocity"].data_type == "FLOAT_VECTOR"
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "velocity"),
                               [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    assert "Point ID" in obj.data.attributes


def test_import_simulation_frames_velocity_reaches_motion_blur(pm, data_dir, clean_scene, tmp_path):
    """A simulator's frame (.vtk, .bgeo, Houdini's Blosc-compressed .bgeo.sc) imports with its
    channels; its `velocity` becomes the FLOAT_VECTOR point attribute Cycles' motion blur
    reads, on the import and on the mesh polygonize makes of it (interpolated)."""
    import gzip
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from particle_files import scf
    bgeo = data_dir / "particles" / "ParticleData_Fluid_50.bgeo"
    sc = tmp_path / "ParticleData_Fluid_50.bgeo.sc"
    sc.write_bytes(scf(gzip.decompress(bgeo.read_bytes())))
    for path in [data_dir / "particles" / "double_dam_break_frame_01_4732_particles.vtk", bgeo, sc]:
        obj = import_cloud(path)
        cloud = pm.particlemesh.read_points(path)
        assert len(obj.data.vertices) == len(cloud.positions)
        attribute = obj.data.attributes["velocity"]
        assert attribute.data_type == "FLOAT_VECTOR" and attribute.domain == "POINT"
        np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "velocity"),
                                   cloud.attributes["velocity"], atol=1e-6)
        # particle ids: Blender's own integer `id` attribute (the name is reserved for it)
        ids = obj.data.attributes["id"]
        assert ids.data_type == "INT"
        got = np.empty(len(obj.data.vertices), dtype=np.int32)
        ids.data.foreach_get("value", got)
        np.testing.assert_array_equal(got, cloud.attributes["id"].ravel().astype(np.int32))
    assert bpy.ops.particlemesh.polygonize() == {"FINISHED"}
    result = bpy.context.active_object
    attribute = result.data.attributes["velocity"]
    assert attribute.data_type == "FLOAT_VECTOR" and attribute.domain == "POINT"
    velocity = pm.blender_mesh.get_point_attribute(result.data, "velocity")
    assert len(velocity) == len(result.data.vertices) > 0
    speed = np.linalg.norm(cloud.attributes["velocity"], axis=1)
    assert np.linalg.norm(velocity, axis=1).max() <= speed.max() + 1e-4


def read_binary_pcd(path):
    """An independent decoder for `DATA binary` PCD files (numpy only): {field: array}."""
    raw = path.read_bytes()
    header, offset = {}, 0
    for line in raw.split(b"\n"):
        offset += len(line) + 1
        words = line.decode("ascii").split()
        if words and not words[0].startswith("#"):
            header[words[0]] = words[1:]
        if words and words[0] == "DATA":
            assert words[1] == "binary", path
            break
    kinds = {("F", "4"): "<f4", ("F", "8"): "<f8", ("U", "4"): "<u4", ("U", "1"): "u1",
             ("I", "4"): "<i4"}
    counts = header.get("COUNT", ["1"] * len(header["FIELDS"]))
    dtype = np.dtype([(name, kinds[(t, s)], (int(c),)) if int(c) > 1 else (name, kinds[(t, s)])
                      for name, t, s, c in zip(header["FIELDS"], header["TYPE"], header["SIZE"], counts)])
    n = int(header["POINTS"][0])
    return np.frombuffer(raw, dtype=dtype, count=n, offset=offset)


def packed_rgb(values):
    """PCL's packed rgb/rgba (0xAARRGGBB) as float r g b in [0, 1]."""
    v = np.asarray(values).view(np.uint32)
    return np.stack([(v >> 16) & 255, (v >> 8) & 255, v & 255], 1).astype(np.float32) / 255.0


def test_import_names_what_the_file_holds_but_does_not_read(pm, clean_scene, tmp_path):
    """A Houdini string attribute (no per-point number) is named in the import's report, not
    dropped silently; the import itself, with its channels, goes on. The package's
    NotReadWarning is the report's, not printed to the console."""
    import sys
    import warnings
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from particle_files import particles, write_bgeo
    p, a = particles(0)
    path = tmp_path / "named.bgeo"
    write_bgeo(path, p, a, names=["water", "foam"])

    class Importer:  # the operator's properties and report(), as Blender gives them to execute
        filepath, directory, files = str(path), "", []

        def __init__(self):
            self.reports = []

        def report(self, kind, message):
            self.reports.append((kind, message))
    op = Importer()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert pm.operators.PARTICLEMESH_OT_import_cloud.execute(op, bpy.context) == {"FINISHED"}
    obj = bpy.context.active_object
    assert len(obj.data.vertices) == len(p) and "velocity" in obj.data.attributes
    assert op.reports == [({"INFO"}, f"{obj.name}: {len(p)} points, {obj.name}: not read: "
                                     "point attribute 'name' (strings)")]


def test_import_every_pcd(pm, data_dir):
    """Every .pcd of the shared data through File > Import (the PCL bridge shipped in the
    zip): point counts after dropping NaN points, normals where the file has them."""
    installed = Path(pm.__file__).resolve().parent
    lib_dir = installed / "particlemesh" / "lib"
    assert (lib_dir / "libparticlemesh_pcl.so").is_file()
    assert Path(pm.particlemesh.pcl_bridge_path()).resolve().parent == lib_dir
    files = sorted((data_dir / "pcd").glob("*.pcd"))
    assert len(files) == 7
    # DATA.md: bunny/bun0 397 points, milk 13704, colored_cloud 1000, the Kinect frame
    # 307200 of which 35625 are NaN (invalid depth) and are dropped.
    expected = {"bunny.pcd": 397, "bun0.pcd": 397, "milk.pcd": 13704, "milk_binary.pcd": 13704,
                "colored_cloud.pcd": 1000,
                "kinect_frame_20121214T142255.814212.pcd": 307200 - 35625,
                "kinect_frame_20121214T142255.814212_binary.pcd": 307200 - 35625}
    with_normals = {"bun0.pcd", "colored_cloud.pcd"}
    with_colour = {"colored_cloud.pcd", "kinect_frame_20121214T142255.814212.pcd",
                   "kinect_frame_20121214T142255.814212_binary.pcd"}
    assert sorted(expected) == sorted(p.name for p in files)
    for path in files:
        obj = import_cloud(path)
        mesh = obj.data
        assert len(mesh.vertices) == expected[path.name], path.name
        assert len(mesh.polygons) == 0 and len(mesh.edges) == 0
        normals = pm.blender_mesh.get_point_attribute(mesh, "point_normal")
        assert (normals is not None) == (path.name in with_normals), path.name
        if normals is not None:
            np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-3)
        assert ("Col" in mesh.attributes) == (path.name in with_colour), path.name
        co, _ = mesh_arrays(mesh)
        assert np.isfinite(co).all()
        bpy.data.objects.remove(obj)
    # bun0.pcd's normals are the file's (x y z normal_x normal_y normal_z curvature, ascii).
    rows = [line.split() for line in (data_dir / "pcd/bun0.pcd").read_text().splitlines()]
    data = np.array([r for r in rows if len(r) == 7 and r[0][0] in "-.0123456789"], dtype=np.float64)
    assert len(data) == 397
    obj = import_cloud(data_dir / "pcd/bun0.pcd")
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, data[:, :3], atol=1e-6)
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "point_normal"),
                               data[:, 3:6], atol=1e-6)


@pytest.mark.parametrize("name", ["colored_cloud.pcd", "kinect_frame_20121214T142255.814212_binary.pcd"])
def test_import_pcd_colours(pm, data_dir, name):
    """The file's rgb / rgba reaches Blender as the `Col` colour attribute (RGBA float, alpha
    1), point for point, checked against an independent numpy decoding of the file."""
    path = data_dir / "pcd" / name
    points = read_binary_pcd(path)
    xyz = np.stack([points["x"], points["y"], points["z"]], 1)
    valid = np.isfinite(xyz).all(axis=1)
    colour_field = "rgb" if "rgb" in points.dtype.names else "rgba"
    expected = packed_rgb(points[colour_field][valid])
    obj = import_cloud(path)
    col = obj.data.attributes["Col"]
    assert col.domain == "POINT" and col.data_type == "FLOAT_COLOR"
    got = pm.blender_mesh.get_point_attribute(obj.data, "Col")
    assert got.shape == (int(valid.sum()), 4)
    np.testing.assert_allclose(got[:, :3], expected, atol=1e-6)
    np.testing.assert_allclose(got[:, 3], 1.0)
    assert len(np.unique(got[:, :3], axis=0)) > 10  # a real picture, not one colour
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, xyz[valid], atol=1e-6)


def test_import_ply_vertex_colours(pm, tmp_path):
    """A PLY with red/green/blue (uchar) vertex properties: colours as `Col`, normals kept."""
    rng = np.random.default_rng(7)
    p = fibonacci_sphere(40)
    rgb = rng.integers(0, 256, size=(40, 3), dtype=np.uint8)
    path = tmp_path / "coloured.ply"
    with open(path, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 40\n"
                b"property float x\nproperty float y\nproperty float z\n"
                b"property float nx\nproperty float ny\nproperty float nz\n"
                b"property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
        rec = np.zeros(40, dtype=[("p", "<f4", 3), ("n", "<f4", 3), ("c", "u1", 3)])
        rec["p"], rec["n"], rec["c"] = p, p, rgb
        f.write(rec.tobytes())
    obj = import_cloud(path)
    got = pm.blender_mesh.get_point_attribute(obj.data, "Col")
    np.testing.assert_allclose(got[:, :3], rgb / 255.0, atol=1e-6)
    np.testing.assert_allclose(got[:, 3], 1.0)
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "point_normal"), p,
                               atol=1e-6)
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, p, atol=1e-6)


def test_import_scanner_text_and_parallel_vtk(pm, tmp_path):
    """A Leica .pts (count line, x y z intensity r g b): colours as `Col`, intensity as a
    channel, no normals; a .pvtu's pieces (in a folder beside it) as one object."""
    pts = tmp_path / "scan.pts"
    pts.write_text("3\n0 0 0 -100 255 0 0\n1 0 0 200 0 255 0\n0 1 0 300 0 0 255\n")
    obj = import_cloud(pts)
    co, _ = mesh_arrays(obj.data)
    np.testing.assert_allclose(co, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    got = pm.blender_mesh.get_point_attribute(obj.data, "Col")
    np.testing.assert_allclose(got[:, :3], np.eye(3), atol=1e-6)
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(obj.data, "intensity").ravel(), [-100, 200, 300])
    assert pm.blender_mesh.get_point_attribute(obj.data, "point_normal") is None

    (tmp_path / "sim").mkdir()
    for k in range(2):
        (tmp_path / "sim" / f"sim_{k}.vtu").write_text(
            '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0">\n<UnstructuredGrid>'
            '<Piece NumberOfPoints="2" NumberOfCells="0"><Points><DataArray type="Float32" '
            f'NumberOfComponents="3" format="ascii">{k} 0 0 {k} 1 0</DataArray></Points></Piece>'
            "</UnstructuredGrid>\n</VTKFile>\n")
    pvtu = tmp_path / "sim.pvtu"
    pvtu.write_text('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0"><PUnstructuredGrid>'
                    '<Piece Source="sim/sim_0.vtu"/><Piece Source="sim/sim_1.vtu"/></PUnstructuredGrid></VTKFile>\n')
    co, _ = mesh_arrays(import_cloud(pvtu).data)
    np.testing.assert_allclose(co, [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]])


def test_import_malformed_pcd_cancels_naming_the_file(pm, tmp_path):
    bad = tmp_path / "broken.pcd"
    bad.write_text("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                   "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0 0 0\n1 0\n")
    with pytest.raises(RuntimeError, match="broken.pcd"):
        bpy.ops.particlemesh.import_cloud(filepath=str(bad))
    assert not bpy.data.objects


def test_import_several_files_at_once(pm, data_dir):
    directory = data_dir / "points"
    names = ["spot_poisson.ply", "bunny_poisson.ply"]
    assert bpy.ops.particlemesh.import_cloud(
        directory=str(directory), files=[{"name": n} for n in names]) == {"FINISHED"}
    assert sorted(o.name for o in bpy.context.selected_objects) == ["bunny_poisson", "spot_poisson"]


def test_point_cloud_mesh_keeps_normals_and_colours(pm):
    """What import_cloud builds from a cloud: normals as `point_normal`, RGB(A) colours as the
    `Col` colour attribute, other channels by name (files' colours: test_import_pcd_colours,
    test_import_ply_vertex_colours)."""
    p = fibonacci_sphere(50)
    rgb = np.random.default_rng(1).random((50, 3)).astype(np.float32)
    mesh = pm.blender_mesh.new_point_cloud_mesh("coloured", p, normals=p, colors=rgb,
                                                attributes={"radius": np.full((50, 1), 0.1, np.float32)})
    col = mesh.attributes["Col"]
    assert col.domain == "POINT" and col.data_type == "FLOAT_COLOR"
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(mesh, "Col"),
                               np.concatenate([rgb, np.ones((50, 1), np.float32)], 1))
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(mesh, "point_normal"), p)
    np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(mesh, "radius"), 0.1)
    assert len(mesh.vertices) == 50 and len(mesh.polygons) == 0
    assert not mesh.validate(verbose=False)
    bpy.data.meshes.remove(mesh)


def expect_edges_of_triangles(mesh, triangles):
    """A closed mesh's edges as written: each edge once, every loop on its edge, valid."""
    assert len(mesh.edges) == 3 * len(triangles) // 2
    ev = np.empty(2 * len(mesh.edges), dtype=np.uint32)
    mesh.edges.foreach_get("vertices", ev)
    loop_edge = np.empty(len(mesh.loops), dtype=np.uint32)
    mesh.loops.foreach_get("edge_index", loop_edge)
    a, b = triangles.ravel(), np.roll(triangles, -1, axis=1).ravel()
    np.testing.assert_array_equal(np.sort(ev.reshape(-1, 2)[loop_edge], axis=1),
                                  np.stack([np.minimum(a, b), np.maximum(a, b)], 1))
    assert not mesh.validate(verbose=False)


def test_index_buffers_have_the_format_blender_copies_in_bulk(pm):
    """blender_mesh.INDEX (uint32) is the format of Blender's unsigned index properties, so
    foreach_get / foreach_set copy them in bulk (any other format goes item by item, ~10x
    slower); a mesh written and read back keeps its triangles."""
    rna = bpy.types
    for owner, name in ((rna.MeshLoop, "vertex_index"), (rna.MeshPolygon, "loop_start"),
                        (rna.MeshPolygon, "loop_total"), (rna.MeshLoopTriangle, "vertices"),
                        (rna.MeshEdge, "vertices"), (rna.MeshLoop, "edge_index")):
        prop = owner.bl_rna.properties[name]
        assert prop.type == "INT" and prop.subtype == "UNSIGNED", (owner, name, prop.subtype)
    assert np.dtype(pm.blender_mesh.INDEX).char == "I"
    p = fibonacci_sphere(400)
    data = pm.particlemesh.triangulate(p)
    mesh = pm.blender_mesh.write(bpy.data.meshes.new("indices"), data)
    got = pm.blender_mesh.triangles(mesh)
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, data.triangles)
    # The edges come from the library (pm_triangle_edges), not Blender's edge pass: a valid
    # mesh (validate() finds nothing to fix), each edge once, every loop on its edge.
    expect_edges_of_triangles(mesh, data.triangles)
    assert mesh.validate(verbose=False) is False
    bpy.data.meshes.remove(mesh)


def test_shade_smooth_sets_every_face_and_nothing_else(pm, monkeypatch):
    """write()'s faces are smooth shaded in bulk (the faces' flag bits, where their layout is
    checked): every face smooth, the loops and flags otherwise as the one-face-at-a-time path
    leaves them, a mesh that validates; and the checked layout is refused when it differs."""
    p = np.random.default_rng(1).random((3000, 3)).astype(np.float32)
    data = pm.particlemesh.triangulate(p)
    meshes = []
    for bulk in (True, False):
        if not bulk:
            monkeypatch.setattr(pm.blender_mesh, "_mpoly_flags", lambda mesh, nt: None)
        mesh = pm.blender_mesh.write(bpy.data.meshes.new(f"bulk {bulk}"), data)
        meshes.append(mesh)
        smooth = np.zeros(len(mesh.polygons), bool)
        mesh.polygons.foreach_get("use_smooth", smooth)
        assert len(smooth) == data.triangle_count and smooth.all()
        assert not mesh.validate(verbose=False)
    for prop in ("loop_start", "loop_total", "material_index"):
        a, b = (np.empty(data.triangle_count, np.int32) for _ in range(2))
        meshes[0].polygons.foreach_get(prop, a)
        meshes[1].polygons.foreach_get(prop, b)
        np.testing.assert_array_equal(a, b)
    for prop in ("select", "hide"):
        a, b = (np.empty(data.triangle_count, bool) for _ in range(2))
        meshes[0].polygons.foreach_get(prop, a)
        meshes[1].polygons.foreach_get(prop, b)
        np.testing.assert_array_equal(a, b)
    monkeypatch.undo()
    if bpy.app.version < (3, 6, 0):
        # The layout check: a face's loop fields that disagree with the bytes read.
        mesh = meshes[1]
        assert pm.blender_mesh._mpoly_flags(mesh, len(mesh.polygons)) is not None
        monkeypatch.setattr(pm.blender_mesh, "_MPOLY_SIZE", 16)
        assert pm.blender_mesh._mpoly_flags(mesh, len(mesh.polygons)) is None
    for mesh in meshes:
        bpy.data.meshes.remove(mesh)


def test_bulk_index_fields_write_what_foreach_set_writes(pm, monkeypatch):
    """Before Blender 3.6 write() fills the corners', faces' and edges' index fields through a
    numpy view of their structs (where the layout checks out): the same mesh, field for field,
    as foreach_set writes; a layout that differs from the one checked is refused."""
    p = np.random.default_rng(2).random((3000, 3)).astype(np.float32)
    data = pm.particlemesh.triangulate(p)
    bulk = pm.blender_mesh.write(bpy.data.meshes.new("bulk fields"), data)
    if bpy.app.version < (3, 6, 0):
        fields = pm.blender_mesh._index_fields
        assert fields(bulk.loops, len(bulk.loops), 8, pm.blender_mesh._probe_loop) is not None
        assert fields(bulk.polygons, len(bulk.polygons), 12, pm.blender_mesh._probe_face) is not None
        assert fields(bulk.edges, len(bulk.edges), 12, pm.blender_mesh._probe_edge) is not None
        # A struct size other than the items' spacing, or fields other than those probed.
        assert fields(bulk.loops, len(bulk.loops), 12, pm.blender_mesh._probe_loop) is None
        assert fields(bulk.edges, len(bulk.edges), 12, lambda edge, k: (7, 7)) is None
        bpy.data.meshes.remove(bulk)
        bulk = pm.blender_mesh.write(bpy.data.meshes.new("bulk fields"), data)
    monkeypatch.setattr(pm.blender_mesh, "_index_fields", lambda *args: None)
    plain = pm.blender_mesh.write(bpy.data.meshes.new("foreach_set fields"), data)
    for name, items, props in (("loops", "loops", ("vertex_index", "edge_index")),
                               ("faces", "polygons", ("loop_start", "loop_total", "material_index")),
                               ("edges", "edges", ("vertices",))):
        for prop in props:
            got = []
            for mesh in (bulk, plain):
                collection = getattr(mesh, items)
                a = np.empty(len(collection) * (2 if prop == "vertices" else 1), np.int32)
                collection.foreach_get(prop, a)
                got.append(a)
            np.testing.assert_array_equal(got[0], got[1], err_msg=f"{name}.{prop}")
    for items, props in (("polygons", ("use_smooth", "select", "hide")),
                         ("edges", ("use_seam", "use_edge_sharp", "select", "hide"))):
        for prop in props:
            a, b = (np.empty(len(getattr(bulk, items)), bool) for _ in range(2))
            getattr(bulk, items).foreach_get(prop, a)
            getattr(plain, items).foreach_get(prop, b)
            np.testing.assert_array_equal(a, b, err_msg=f"{items}.{prop}")
    assert not bulk.validate(verbose=False) and not plain.validate(verbose=False)
    np.testing.assert_array_equal(pm.blender_mesh.triangles(bulk), data.triangles)
    for mesh in (bulk, plain):
        bpy.data.meshes.remove(mesh)


def test_writes_one_after_another_reuse_the_edge_arrays(pm):
    """write(keep_arrays=True) (live mode's) keeps the edge numbering's arrays and the float32
    vertices for the next mesh: a smaller mesh after a larger one, then the larger again, each
    with its own edges (a valid mesh, every corner on its edge); the arrays are let go of with
    the live cache. Other writes keep nothing."""
    big = pm.particlemesh.triangulate(fibonacci_sphere(3000))
    small = pm.particlemesh.triangulate(fibonacci_sphere(500))
    meshes = []
    pm.blender_mesh.release_buffers()
    bpy.data.meshes.remove(pm.blender_mesh.write(bpy.data.meshes.new("not kept"), small))
    assert not pm.blender_mesh._kept_arrays  # only live mode's writes keep them
    for data in (big, small, big):
        mesh = pm.blender_mesh.write(bpy.data.meshes.new("reuse"), data, keep_arrays=True)
        meshes.append(mesh)
        expect_edges_of_triangles(mesh, data.triangles)
    # The first mesh still has its own edges after the arrays were written again.
    ev = np.empty(2 * len(meshes[0].edges), dtype=np.uint32)
    meshes[0].edges.foreach_get("vertices", ev)
    ev2 = np.empty(2 * len(meshes[2].edges), dtype=np.uint32)
    meshes[2].edges.foreach_get("vertices", ev2)
    np.testing.assert_array_equal(ev, ev2)
    kept = pm.blender_mesh._kept_arrays
    assert len(kept["corners"]) >= 3 * big.triangle_count and len(kept["positions"]) >= 3 * big.vertex_count
    pm.live.clear_cache()
    assert not pm.blender_mesh._kept_arrays
    for mesh in meshes:
        bpy.data.meshes.remove(mesh)


def test_write_raises_what_the_edge_numbering_refuses(pm):
    """The edges are numbered in a thread of their own while Blender takes the rest: an index
    beyond the vertices still reaches the caller as the library's error, naming it."""
    data = pm.particlemesh.Mesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 2], [0, 2, 5]], np.int32))
    mesh = bpy.data.meshes.new("bad indices")
    with pytest.raises(pm.particlemesh.Error, match="triangle 1 has vertex index 5"):
        pm.blender_mesh.write(mesh, data)
    bpy.data.meshes.remove(mesh)


# ---- smooth and polygonize (the smoothing and volume C ABI) -----------------------------------

def icosphere_object():
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=1.0)
    return bpy.context.active_object


def test_smooth_loop_multiplies_faces_by_four(pm):
    obj = icosphere_object()
    faces = len(obj.data.polygons)
    material = bpy.data.materials.new("Kept")
    obj.data.materials.append(material)
    for levels in (1, 2):
        bpy.ops.ed.undo_push(message="before smooth")
        assert bpy.ops.particlemesh.smooth("EXEC_DEFAULT", True, levels=levels) == {"FINISHED"}
        obj = bpy.context.active_object
        assert len(obj.data.polygons) == faces * 4 ** levels
        assert list(obj.data.materials) == [material]
        assert not obj.data.validate(verbose=False)
        co, tris = mesh_arrays(obj.data)
        rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
        assert rep["closed"] and rep["euler_characteristic"] == 2 and rep["outward"]
        # Loop shrinks toward the limit surface, which lies inside the control hull.
        assert np.linalg.norm(co, axis=1).max() <= 1.0 + 1e-5
        undo()
        obj = bpy.context.active_object
        assert len(obj.data.polygons) == faces


def grid_with_everything(cells=7):
    """A flat grid of cells x cells quads (-1..1) holding what a modelled mesh holds: a UV map
    (u, v) = ((x + 1) / 2, (y + 1) / 2), moved by 2 in u on odd faces (a seam around each), a
    material per face parity, shape keys (one moving every vertex up, one a shear of the
    basis), vertex groups (constant weights) and a seam on one edge."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=cells, y_subdivisions=cells, size=2)
    obj = bpy.context.active_object
    mesh = obj.data
    co = np.array([v.co[:] for v in mesh.vertices])
    uv = mesh.uv_layers.active.data
    for face in mesh.polygons:
        face.material_index = face.index % 2
        for loop in face.loop_indices:
            x, y = co[mesh.loops[loop].vertex_index, :2]
            uv[loop].uv = ((x + 1) / 2 + 2 * (face.index % 2), (y + 1) / 2)
    for name in ("Even", "Odd"):
        mesh.materials.append(bpy.data.materials.new(name))
    whole = obj.vertex_groups.new(name="whole")
    whole.add(list(range(len(co))), 1.0, "REPLACE")
    half = obj.vertex_groups.new(name="half")
    half.add(list(range(len(co))), 0.5, "REPLACE")
    half.lock_weight = True
    obj.shape_key_add(name="Basis")
    up = obj.shape_key_add(name="Up")
    tilt = obj.shape_key_add(name="Tilt")
    for i, (x, y, z) in enumerate(co):
        up.data[i].co = (x, y, z + 0.5)
        tilt.data[i].co = (x, y, z + 0.1 * x)
    tilt.relative_key = up
    tilt.value = 0.3
    # A seam and a sharp edge on the border, away from the grid's corners (which Loop's
    # boundary curve rounds off).
    def border_edge(axis, side):
        for e in mesh.edges:
            a, b = co[list(e.vertices)]
            if a[axis] == b[axis] == side and abs(a[1 - axis]) < 0.3 and abs(b[1 - axis]) < 0.3:
                return e
        raise AssertionError("no such edge")
    border_edge(1, -1).use_seam = True
    border_edge(0, 1).use_edge_sharp = True
    mesh.edges[0].bevel_weight = 0.5
    return obj


def smooth_active(scheme, levels):
    """The Smooth operator on the active object, after an undo step (undo() goes back):
    (object, mesh, positions, triangles) of the valid mesh it leaves."""
    bpy.ops.ed.undo_push(message="before smooth")
    assert bpy.ops.particlemesh.smooth("EXEC_DEFAULT", True, scheme=scheme, levels=levels) == {"FINISHED"}
    obj = bpy.context.active_object
    assert not obj.data.validate(verbose=False)
    co, tris = mesh_arrays(obj.data)
    return obj, obj.data, co, tris


@pytest.mark.parametrize("turned", [False, True])
def test_smooth_carries_uvs_materials_shape_keys_and_vertex_groups(pm, turned):
    """What a modelled mesh holds goes through the subdivision: each output face keeps the
    material and UV island of the input face it lies in; UVs are linear over each input
    triangle (on a flat regular grid, where neither scheme moves vertices off their place
    away from the border, exactly (x, y)); shape keys are subdivided as the positions (a
    shifted or sheared basis stays shifted or sheared); constant weights stay; a seam and a
    sharp edge (on the grid's border, where both schemes keep the vertices on the line) mark
    the output edges along them; bevel weights are named as not carried. With one face
    turned against the rest, the library's orientation repair turns it back, and its
    corners' UVs and edges follow it."""
    cells = 7
    obj = grid_with_everything(cells)
    if turned:  # the face along the seam
        seam = next(e.key for e in obj.data.edges if e.use_seam)
        next(f for f in obj.data.polygons if seam in f.edge_keys).flip()
    carried = pm.smooth_carry.prepare(obj, obj.data)[3]
    assert carried.not_carried == ["edge bevel weights"]
    co0 = np.array([v.co[:] for v in obj.data.vertices])
    flagged = {field: co0[[list(e.vertices) for e in obj.data.edges if getattr(e, field)][0]]
               for field in ("use_seam", "use_edge_sharp")}
    for scheme, levels in (("LOOP", 1), ("LOOP", 2), ("BUTTERFLY", 1), ("BUTTERFLY", 2)):
        obj, mesh, co, tris = smooth_active(scheme, levels)
        assert len(tris) == 2 * cells * cells * 4 ** levels
        # The material and UV island of the input face each output face lies in.
        centre = co[tris].mean(1)
        cell = np.floor((centre[:, :2] + 1) / 2 * cells).astype(int)
        parity = (cell[:, 1] * cells + cell[:, 0]) % 2
        material = np.empty(len(tris), dtype=np.int32)
        mesh.polygons.foreach_get("material_index", material)
        np.testing.assert_array_equal(material, parity)
        assert [layer.name for layer in mesh.uv_layers] == ["UVMap"] and mesh.uv_layers.active.name == "UVMap"
        uv = np.empty(2 * len(mesh.loops), dtype=np.float32)
        mesh.uv_layers.active.data.foreach_get("uv", uv)
        uv = uv.reshape(-1, 3, 2)
        np.testing.assert_array_equal(np.floor(uv[:, :, 0] / 2).astype(int), parity[:, None] * np.ones(3, int))
        at = co[tris][:, :, :2]
        inside = (np.abs(at) < 1 - 2 / cells - 1e-6).all(2)
        assert inside.mean() > 0.4
        np.testing.assert_allclose((uv[..., 0] % 2)[inside], ((at[..., 0] + 1) / 2)[inside], atol=2e-6)
        np.testing.assert_allclose(uv[..., 1][inside], ((at[..., 1] + 1) / 2)[inside], atol=2e-6)
        # Shape keys: the same keys, settings and relations, one point per vertex.
        keys = mesh.shape_keys.key_blocks
        assert [k.name for k in keys] == ["Basis", "Up", "Tilt"]
        assert keys["Tilt"].relative_key.name == "Up" and keys["Tilt"].value == pytest.approx(0.3)
        def key(name):
            out = np.empty(3 * len(co), dtype=np.float32)
            keys[name].data.foreach_get("co", out)
            return out.reshape(-1, 3)
        np.testing.assert_allclose(key("Basis"), co, atol=1e-6)
        np.testing.assert_allclose(key("Up"), co + [0, 0, 0.5], atol=1e-6)
        np.testing.assert_allclose(key("Tilt")[:, 2], co[:, 2] + 0.1 * co[:, 0], atol=1e-6)
        # Vertex groups: names, lock and constant weights on every vertex.
        assert [(g.name, g.lock_weight) for g in obj.vertex_groups] == [("whole", False), ("half", True)]
        weights = {(v.index, g.group): g.weight for v in mesh.vertices for g in v.groups}
        assert len(weights) == 2 * len(co)
        assert all(abs(w - (1.0 if group == 0 else 0.5)) < 1e-6 for (_, group), w in weights.items())
        # Seams and sharp edges: the 2^levels output edges along the input edge, no other.
        for field, (a, b) in flagged.items():
            marked = np.empty(len(mesh.edges), dtype=bool)
            mesh.edges.foreach_get(field, marked)
            ends = np.array([list(e.vertices) for e in mesh.edges])[marked]
            assert len(ends) == 2 ** levels, (field, len(ends))
            for p in co[ends].reshape(-1, 3):
                t = np.dot(p - a, b - a) / np.dot(b - a, b - a)
                assert -1e-6 <= t <= 1 + 1e-6 and np.linalg.norm(a + t * (b - a) - p) < 1e-5, (field, p)
        undo()


def test_smooth_keeps_loose_vertices_and_edges(pm):
    """Vertices and edges of no face stay, as Blender's Subdivision Surface keeps them: a
    loose vertex with its position, shape key, weight and attribute; a loose edge between two
    loose vertices, and one from a loose vertex to a face vertex, which follows that vertex's
    image (output vertex i is the image of the i-th face vertex), with its seam flag."""
    mesh = bpy.data.meshes.new("patch with loose parts")
    # A 3 x 3 vertex patch (vertex 4 in the middle) and, before and after it in the vertex
    # order, loose vertices 0 and 10.
    grid = [(x, y, 0.0) for y in (-1.0, 0.0, 1.0) for x in (-1.0, 0.0, 1.0)]
    verts = [(3.0, 0.0, 0.5)] + grid + [(3.0, 1.0, 0.5)]
    quads = [(1 + a, 1 + a + 1, 1 + a + 4, 1 + a + 3) for a in (0, 1, 3, 4)]
    mesh.from_pydata(verts, [(0, 10), (0, 6)], quads)
    mesh.update()
    obj = bpy.data.objects.new("patch with loose parts", mesh)
    bpy.context.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    for e in mesh.edges:
        e.use_seam = sorted(e.vertices) == [0, 10]
    group = obj.vertex_groups.new(name="loose")
    group.add([0], 0.75, "REPLACE")
    group.add([10], 0.25, "REPLACE")
    temperature = mesh.attributes.new("temperature", "FLOAT", "POINT")
    temperature.data.foreach_set("value", np.arange(len(verts), dtype=np.float32))
    obj.shape_key_add(name="Basis")
    up = obj.shape_key_add(name="Up")
    for i, (x, y, z) in enumerate(verts):
        up.data[i].co = (x, y, z + 0.5)
    for scheme, levels in (("LOOP", 1), ("BUTTERFLY", 2)):
        obj, mesh, co, tris = smooth_active(scheme, levels)
        assert len(tris) == 8 * 4 ** levels
        surface = len(co) - 2
        assert tris.max() == surface - 1  # the loose vertices come after the surface's
        np.testing.assert_array_equal(co[surface:], [verts[0], verts[10]])
        ends = {tuple(sorted(e.vertices)): e for e in mesh.edges}
        # Vertex 6, (1, 0, 0) on the patch's border, is face vertex 5: output vertex 5.
        assert (surface, surface + 1) in ends and (5, surface) in ends
        assert ends[surface, surface + 1].use_seam and not ends[5, surface].use_seam
        np.testing.assert_allclose(co[5], [1.0, 0.0, 0.0], atol=1e-6)  # on the border curve
        key = np.empty(3 * len(co), dtype=np.float32)
        mesh.shape_keys.key_blocks["Up"].data.foreach_get("co", key)
        np.testing.assert_allclose(key.reshape(-1, 3)[surface:], np.array([verts[0], verts[10]]) + [0, 0, 0.5])
        weights = {v.index: g.weight for v in mesh.vertices for g in v.groups}
        assert weights[surface] == pytest.approx(0.75) and weights[surface + 1] == pytest.approx(0.25)
        values = np.empty(len(co), dtype=np.float32)
        mesh.attributes["temperature"].data.foreach_get("value", values)
        np.testing.assert_array_equal(values[surface:], [0.0, 10.0])
        undo()


def test_smooth_takes_edge_creases_as_loop_does(pm):
    """A cube with every edge creased (1.0: infinitely sharp, OpenSubdiv's sharpness 10 as
    Blender's Subdivision Surface converts c^2 x 10) keeps its faces flat under Loop; without
    creases Loop rounds it."""
    for creased in (True, False):
        bpy.ops.mesh.primitive_cube_add(size=2)
        obj = bpy.context.active_object
        if creased:
            if hasattr(obj.data.edges[0], "crease"):
                obj.data.edges.foreach_set("crease", np.ones(len(obj.data.edges), dtype=np.float32))
            else:
                obj.data.attributes.new("crease_edge", "FLOAT", "EDGE").data.foreach_set(
                    "value", np.ones(len(obj.data.edges), dtype=np.float32))
        assert bpy.ops.particlemesh.smooth("EXEC_DEFAULT", True, scheme="LOOP", levels=2) == {"FINISHED"}
        co, _ = mesh_arrays(obj.data)
        on_a_face = (np.abs(np.abs(co) - 1) < 1e-6).any(axis=1)
        assert on_a_face.all() if creased else not on_a_face.any(), creased
    bpy.ops.mesh.primitive_cube_add(size=2)
    obj = bpy.context.active_object
    obj.data.edges.foreach_set("crease", np.ones(len(obj.data.edges), dtype=np.float32))
    carried = pm.smooth_carry.prepare(obj, obj.data)[3]
    assert len(carried.crease_edges) == 12 and (carried.crease_sharpness == 10).all()


def lattice(n, spacing=0.1):
    g = np.arange(n, dtype=np.float32) * spacing
    return np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)


def test_polygonize_volume_particles(pm, clean_scene):
    p = lattice(8)
    source = point_cloud_object("block", p)
    assert bpy.ops.particlemesh.polygonize() == {"FINISHED"}
    result = bpy.context.active_object
    assert result is not source and result.name == "block_polygonize"
    state = result.particlemesh
    assert state.method == "POLYGONIZE" and state.source == source
    mesh = result.data
    co, tris = mesh_arrays(mesh)
    direct = pm.particlemesh.polygonize(p)
    assert len(tris) == direct.triangle_count and len(co) == direct.vertex_count
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
    assert rep["closed"] and rep["manifold"] and rep["outward"] and rep["components"] == 1
    assert rep["euler_characteristic"] == 2
    # The surface wraps the block: its box holds the particles' box, and nothing is far off.
    lo, hi = p.min(axis=0), p.max(axis=0)
    assert (co.min(axis=0) < lo).all() and (co.max(axis=0) > hi).all()
    assert (co > lo - 0.3).all() and (co < hi + 0.3).all()
    assert mesh.has_custom_normals  # the field gradient's normals
    assert not mesh.validate(verbose=False)
    # Options reach the library.
    bpy.context.view_layer.objects.active = source
    assert bpy.ops.particlemesh.polygonize(kernel="POLY6", radius_mode="FIXED", radius=0.25,
                                           auto_cell=False, cell_size=0.04) == {"FINISHED"}
    co2, tris2 = mesh_arrays(bpy.context.active_object.data)
    direct = pm.particlemesh.polygonize(p, kernel="poly6", radius=0.25, cell=0.04)
    assert len(tris2) == direct.triangle_count != len(tris)
    # Anisotropic kernels: the same mesh as the binding gives, stored on the generated object
    # (so live mode regenerates it with them), and a different one from the spherical kernels'.
    bpy.context.view_layer.objects.active = source
    assert bpy.ops.particlemesh.polygonize(anisotropic=True) == {"FINISHED"}
    result = bpy.context.active_object
    assert result.particlemesh.viewport.anisotropic and result.particlemesh.render.anisotropic
    co3, tris3 = mesh_arrays(result.data)
    direct = pm.particlemesh.polygonize(p, anisotropic=True)
    assert direct.stats["anisotropic"] == 1
    assert len(tris3) == direct.triangle_count != len(tris)
    np.testing.assert_allclose(co3, direct.vertices, atol=1e-6)
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co3, tris3))
    assert rep["closed"] and rep["manifold"] and rep["components"] == 1
    # Clean Slivers (on jittered particles: a lattice's crossings lie alike, without slivers):
    # the library's collapse_edges, fewer triangles, the same closed surface, stored on the
    # object for live mode.
    q = (p + np.random.default_rng(2).uniform(-0.02, 0.02, p.shape)).astype(np.float32)
    jittered = point_cloud_object("jittered", q)
    bpy.context.view_layer.objects.active = jittered
    assert bpy.ops.particlemesh.polygonize(clean_slivers=True) == {"FINISHED"}
    result = bpy.context.active_object
    assert result.particlemesh.viewport.clean_slivers and result.particlemesh.render.clean_slivers
    co4, tris4 = mesh_arrays(result.data)
    direct = pm.particlemesh.polygonize(q, collapse_edges=0.3)
    assert direct.stats["edges_collapsed"] > 0
    assert len(tris4) == direct.triangle_count
    assert direct.triangle_count == pm.particlemesh.polygonize(q).triangle_count - 2 * direct.stats["edges_collapsed"]
    np.testing.assert_allclose(co4, direct.vertices, atol=1e-6)
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co4, tris4))
    assert rep["closed"] and rep["manifold"] and rep["components"] == 1 and rep["euler_characteristic"] == 2
    assert not result.data.validate(verbose=False)
    # Nothing reaches the threshold: an error, no object.
    bpy.context.view_layer.objects.active = source
    expect_error("no surface|threshold", op=bpy.ops.particlemesh.polygonize, threshold=1000.0)


def test_polygonize_particle_system_with_sizes(pm, clean_scene):
    em = emitter(speed=0.5)
    settings = em.particle_systems[0].settings
    settings.particle_size = 0.1
    clean_scene.frame_set(2)
    assert bpy.ops.particlemesh.polygonize(radius_mode="PARTICLE_SIZE", radius_factor=2.0,
                                           live=True) == {"FINISHED"}
    result = bpy.context.active_object
    co, tris = mesh_arrays(result.data)
    rep = pm.particlemesh.topology(pm.particlemesh.Mesh(co, tris))
    assert rep["closed"] and rep["manifold"] and len(tris) > 1000
    # A shell of particles of radius about 1: the surface lies within 2 x 0.1 of it.
    positions, _ = living_particles(em)
    r = np.linalg.norm(co, axis=1)
    rp = np.linalg.norm(positions, axis=1).mean()
    assert (np.abs(r - rp) < 0.2 + 1e-3).all()
    clean_scene.frame_set(6)  # live: follows the expanding shell
    record = pm.live.last_update[result.name]
    assert "error" not in record, record
    r6 = np.linalg.norm(mesh_arrays(shown_mesh(result))[0], axis=1).mean()
    assert r6 > r.mean() + 0.05


def test_polygonize_sizes_from_a_pscale_attribute(pm, tmp_path, clean_scene):
    """Particle Size radii for a point cloud: its `pscale` (Houdini) point attribute, imported
    with the file, scaled by the object; the same mesh as the library given those radii."""
    p = fibonacci_sphere(3000)
    n = len(p)
    pscale = np.where(p[:, 0] > 0, 0.06, 0.03).astype(np.float32)
    ply = tmp_path / "sized.ply"
    with open(ply, "wb") as f:
        f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
                "property float z\nproperty float pscale\nend_header\n".encode())
        rec = np.zeros(n, dtype=[("p", "<f4", 3), ("s", "<f4")])
        rec["p"], rec["s"] = p, pscale
        f.write(rec.tobytes())
    source = import_cloud(ply)
    source.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    assert bpy.ops.particlemesh.polygonize(radius_mode="PARTICLE_SIZE", radius_factor=2.0) == {"FINISHED"}
    co, tris = mesh_arrays(bpy.context.active_object.data)
    world = p.astype(np.float64) * 2.0
    direct = pm.particlemesh.polygonize(world, radii=pscale.astype(np.float64) * 2.0 * 2.0,
                                        threshold=0.5 * pm.particlemesh.lattice_field("wyvill", 2.0, 2.0))
    assert len(tris) == direct.triangle_count > 1000
    np.testing.assert_allclose(co, direct.vertices, atol=1e-5)


# ---- undo -------------------------------------------------------------------------------------

def test_undo_restores_the_previous_state(pm):
    point_cloud_object("cloud", fibonacci_sphere(2000))
    bpy.ops.ed.undo_push(message="cloud")
    # As from the UI: INVOKE (background falls back to execute), undo step pushed.
    assert bpy.ops.particlemesh.triangulate("INVOKE_DEFAULT", True) == {"FINISHED"}
    assert sorted(o.name for o in bpy.data.objects) == ["cloud", "cloud_triangulate"]
    undo()
    assert [o.name for o in bpy.data.objects] == ["cloud"]
    assert bpy.context.view_layer.objects.active.name == "cloud"
    redo()
    assert sorted(o.name for o in bpy.data.objects) == ["cloud", "cloud_triangulate"]
    result = bpy.data.objects["cloud_triangulate"]
    assert result.particlemesh.is_generated and len(result.data.polygons) > 3000


# ---- bad inputs -------------------------------------------------------------------------------

def expect_error(pattern, op=None, **kwargs):
    before = sorted(o.name for o in bpy.data.objects)
    op = op or bpy.ops.particlemesh.triangulate
    with pytest.raises(RuntimeError, match=pattern):
        op(**kwargs)
    assert sorted(o.name for o in bpy.data.objects) == before, "a failed operator left an object"


def test_bad_inputs_cancel_with_an_error(pm, clean_scene, tmp_path):
    # No vertices.
    point_cloud_object("empty", np.zeros((0, 3), np.float32))
    expect_error("'empty' has no vertices")
    # Not a mesh.
    camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    clean_scene.collection.objects.link(camera)
    make_active(camera)
    expect_error("'cam' is a camera object")
    # NaN coordinate: the library names the particle and the coordinate.
    p = fibonacci_sphere(500)
    p[123, 2] = np.nan
    point_cloud_object("nan", p)
    expect_error(r"positions\[123\]\.z is NaN")
    # Absurd parameters.
    point_cloud_object("good", fibonacci_sphere(2000))
    expect_error("neighbo", auto_spacing=False, spacing=5.0)          # every point in range
    expect_error("no triangles|grid|cells", auto_spacing=False, spacing=1e-6)
    # Too few points.
    point_cloud_object("two", np.array([[0, 0, 0], [1, 0, 0]], np.float32))
    expect_error("point")
    # A hair system is not an emitter.
    em = emitter()
    em.particle_systems[0].settings.type = "HAIR"
    expect_error("hair", source="PARTICLES")
    # Particles not born yet.
    em2 = emitter(name="Late", frame_start=50, frame_end=60)
    make_active(em2)
    expect_error("no living particles", source="PARTICLES")
    # A file that is not there.
    expect_error("nope.ply", op=bpy.ops.particlemesh.import_cloud, filepath=str(tmp_path / "nope.ply"))
    # A bake on an object that was never generated.
    make_active(bpy.data.objects["good"])
    with pytest.raises(RuntimeError):
        bpy.ops.particlemesh.bake(frame_start=1, frame_end=2)
    # Blender keeps running: a good input still works.
    make_active(bpy.data.objects["good"])
    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
    assert len(bpy.context.active_object.data.polygons) > 3000


def test_worker_job_cancels(pm):
    """The interactive path's worker thread (jobs.Job) stops when Esc cancels it."""
    particles = pm.generate.Particles(fibonacci_sphere(200000))
    job = pm.jobs.Job(pm.generate.run, "TRIANGULATE", particles, {"auto_spacing": True})
    job.cancel()
    job.start()
    assert job.wait(120)
    assert isinstance(job.error, pm.particlemesh.CancelledError)
    job = pm.jobs.Job(pm.generate.run, "TRIANGULATE", pm.generate.Particles(fibonacci_sphere(5000)),
                      {"auto_spacing": True}).start()
    assert job.wait(120) and job.error is None
    assert job.result.triangle_count > 9000
    assert "%" in job.status_text()


# ---- the interactive path (modal operator, worker thread, Esc) --------------------------------

class _Event:
    def __init__(self, type, value="NOTHING"):
        self.type, self.value = type, value


class _Recorder:
    """Stands in for the window manager / workspace of an interactive session."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, name):
        return lambda *a, **k: self.calls.append((name, a))


class _Context:
    def __init__(self):
        self.window_manager = _Recorder()
        self.workspace = _Recorder()
        self.window = object()


def modal_driver(pm, job, finished):
    """A _ModalJob as Blender drives it, without a window system: TIMER events until done."""
    class Driver(pm.operators._ModalJob):
        def __init__(self):
            self.reports = []
            self._timer = None

        def report(self, kind, message):
            self.reports.append((kind, message))

        def job_finished(self, context, result):
            finished.append(result)

    driver = Driver()
    context = _Context()
    assert driver.start_job(context, job) == {"RUNNING_MODAL"}
    return driver, context


def run_modal(driver, context, first=None):
    if first is not None:
        assert driver.modal(context, first) == {"RUNNING_MODAL"}
    for _ in range(6000):
        state = driver.modal(context, _Event("TIMER"))
        if state != {"RUNNING_MODAL"}:
            return state
        driver._job.wait(0.01)
    raise AssertionError("the job never finished")


def test_particles_left_outside_a_polygonized_surface_warn(pm, clean_scene):
    """Irregular particles (uniform random points: their median neighbour distance is about
    half their mean spacing, as in an SPH frame in motion): the automatic radius follows their
    packing and takes most of them in. A Fixed radius of twice that neighbour distance leaves
    most of them outside the surface: a warning with the radius their packing suggests, the
    automatic one; packed particles do not warn."""
    scattered = np.random.default_rng(5).uniform(0, 1, (4000, 3))
    auto = pm.generate.run("POLYGONIZE", pm.generate.Particles(scattered), {"radius_mode": "AUTO"})
    assert auto.stats["enclosed_fraction"] > 0.5 and pm.generate.enclosure_warning(auto.stats) is None
    two = 2 * pm.particlemesh.estimate_spacing(scattered)
    assert auto.stats["radius"] > 1.25 * two
    data = pm.generate.run("POLYGONIZE", pm.generate.Particles(scattered), {"radius_mode": "FIXED", "radius": two})
    warning = pm.generate.enclosure_warning(data.stats)
    assert warning and "encloses only" in warning and "Fixed radius of" in warning
    suggested = float(warning.rsplit(" ", 1)[1])
    assert suggested == pytest.approx(auto.stats["radius"], rel=5e-3)  # as the warning rounds it
    fixed = pm.generate.run("POLYGONIZE", pm.generate.Particles(scattered), {"radius_mode": "FIXED", "radius": suggested})
    assert fixed.stats["enclosed_fraction"] > 0.5 and pm.generate.enclosure_warning(fixed.stats) is None
    g = np.stack(np.meshgrid(*[np.arange(10.0)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.1
    packed = pm.generate.run("POLYGONIZE", pm.generate.Particles(g), {"radius_mode": "AUTO"})
    assert pm.generate.enclosure_warning(packed.stats) is None
    assert packed.stats["radius"] == pytest.approx(0.2)
    # A radius of 10 spacings: said the other way round.
    huge = pm.generate.run("POLYGONIZE", pm.generate.Particles(g), {"radius_mode": "FIXED", "radius": 1.0})
    warning = pm.generate.enclosure_warning(huge.stats)
    assert warning and warning.startswith("the radius 1 is large") and "Fixed radius of 0.2" in warning


def test_a_surface_sampling_polygonized_into_blobs_warns(pm, clean_scene):
    """One layer of particles (a sphere's Fibonacci samples) polygonized with the automatic
    settings: every particle inside, but the surface falls into about a piece for every
    particle or two: a warning naming Triangulate; packed particles do not warn."""
    n = 5000
    i = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
    layer = np.c_[np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
    data = pm.generate.run("POLYGONIZE", pm.generate.Particles(layer), {"radius_mode": "AUTO"})
    pieces = pm.particlemesh.topology(data)["components"]
    assert pieces * 10 > n and data.stats["particles"] == n
    assert pm.generate.enclosure_warning(data.stats) is None
    warning = pm.generate.pieces_warning(pieces, data.stats["particles"])
    assert warning and f"fell into {pieces} pieces" in warning and "use Triangulate" in warning
    g = np.stack(np.meshgrid(*[np.arange(10.0)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.1
    packed = pm.generate.run("POLYGONIZE", pm.generate.Particles(g), {"radius_mode": "AUTO"})
    assert pm.generate.pieces_warning(pm.particlemesh.topology(packed)["components"], len(g)) is None


def test_unevenly_spaced_particles_warn(pm, clean_scene):
    """A sphere sampled 2.8x sparser on its upper half. With Local Spacing (the default) each
    particle's longest edge follows its neighbours and the sphere closes; with one longest edge
    for all, its sparse particles fall out of the surface and the operator warns with what
    helps (Local Spacing, Thin Out); an even sphere does not."""
    co, sparse = fibonacci_sphere(20000), fibonacci_sphere(2500)
    uneven = np.concatenate([co[co[:, 2] < 0], sparse[sparse[:, 2] >= 0]])
    local = pm.generate.run("TRIANGULATE", pm.generate.Particles(uneven), {"auto_spacing": True})
    assert local.stats["unused_points"] == 0 and pm.generate.uneven_spacing_warning(local.stats) is None
    rep = pm.particlemesh.topology(local)
    assert rep["closed"] and rep["components"] == 1 and rep["vertices_used"] == len(uneven)
    assert local.stats["local_spacing"][4] > 1.5 * local.stats["local_spacing"][0]  # the halves differ
    data = pm.generate.run("TRIANGULATE", pm.generate.Particles(uneven), {"auto_spacing": True, "local_spacing": False})
    assert data.stats["unused_points"] * 20 > len(uneven)
    warning = pm.generate.uneven_spacing_warning(data.stats)
    assert warning and "Local Spacing" in warning and "Thin Out" in warning and f"of {len(uneven)} particles" in warning
    even = pm.generate.run("TRIANGULATE", pm.generate.Particles(co), {"auto_spacing": True, "local_spacing": False})
    assert pm.generate.uneven_spacing_warning(even.stats) is None
    # Thin Out 2, as the warning says, meshes every kept particle: one closed sphere.
    thinned = pm.generate.run("TRIANGULATE", pm.generate.Particles(uneven),
                              {"auto_spacing": True, "thin": 2.0, "local_spacing": False})
    assert pm.generate.uneven_spacing_warning(thinned.stats) is None
    rep = pm.particlemesh.topology(thinned)
    assert rep["closed"] and rep["components"] == 1 and rep["vertices_used"] == thinned.vertex_count
    make_active(point_cloud_object("uneven", uneven))
    assert bpy.ops.particlemesh.triangulate(local_spacing=False) == {"FINISHED"}  # a warning, not a failure


def test_modal_job_finishes_and_shows_progress(pm):
    finished = []
    particles = pm.generate.Particles(fibonacci_sphere(20000))
    job = pm.jobs.Job(pm.generate.run, "TRIANGULATE", particles, {"auto_spacing": True})
    driver, context = modal_driver(pm, job, finished)
    # Navigation passes through, other input is held while the job runs.
    assert driver.modal(context, _Event("MIDDLEMOUSE", "PRESS")) == {"PASS_THROUGH"}
    assert driver.modal(context, _Event("A", "PRESS")) == {"RUNNING_MODAL"}
    assert run_modal(driver, context) == {"FINISHED"}
    assert finished and finished[0].triangle_count == 2 * 20000 - 4
    names = [c[0] for c in context.window_manager.calls]
    assert names[:3] == ["event_timer_add", "modal_handler_add", "progress_begin"]
    assert "progress_update" in names and names[-1] == "progress_end"
    assert ("status_text_set", (None,)) in context.workspace.calls  # status bar cleared


def test_modal_job_escape_cancels(pm):
    finished = []
    particles = pm.generate.Particles(fibonacci_sphere(300000))
    job = pm.jobs.Job(pm.generate.run, "TRIANGULATE", particles, {"auto_spacing": True})
    driver, context = modal_driver(pm, job, finished)
    assert run_modal(driver, context, first=_Event("ESC", "PRESS")) == {"CANCELLED"}
    assert not finished
    assert driver.reports == [({"WARNING"}, "particlemesh: cancelled")]
    assert [c[0] for c in context.window_manager.calls][-1] == "progress_end"


def test_modal_job_error_is_reported(pm):
    finished = []
    p = fibonacci_sphere(1000)
    p[7, 0] = np.inf
    job = pm.jobs.Job(pm.generate.run, "TRIANGULATE", pm.generate.Particles(p), {})
    driver, context = modal_driver(pm, job, finished)
    assert run_modal(driver, context) == {"CANCELLED"}
    assert driver.reports and driver.reports[0][0] == {"ERROR"}
    assert "positions[7].x" in driver.reports[0][1]


def test_triangulate_with_loop_smoothing(pm, clean_scene):
    em = emitter(speed=1.0)
    clean_scene.frame_set(2)
    positions, velocities = living_particles(em)
    plain = pm.particlemesh.triangulate(positions)
    assert pm.particlemesh.topology(plain)["manifold"]
    assert bpy.ops.particlemesh.triangulate(smooth="LOOP", smooth_levels=1) == {"FINISHED"}
    mesh = bpy.context.active_object.data
    assert len(mesh.polygons) == 4 * plain.triangle_count
    assert mesh.has_custom_normals  # Loop's exact limit normals
    velocity = pm.blender_mesh.get_point_attribute(mesh, "velocity")
    assert velocity.shape == (len(mesh.vertices), 3)
    speed = np.linalg.norm(velocity, axis=1)
    assert np.allclose(speed, np.linalg.norm(velocities, axis=1).mean(), rtol=0.05)
    assert not mesh.validate(verbose=False)
