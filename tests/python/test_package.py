"""The add-on package outside Blender: a valid Blender 4.2 extension manifest that agrees with
bl_info, relative imports only, bpy-free modules that really are, the built zip's layout and
its library; and the bpy-free pipeline modules (generate, jobs, mesh_arrays)."""
import ast
import importlib
import os
import re
import sys
import tomllib
import types
import zipfile

import numpy as np
import pytest

from conftest import NATIVE_PY, ROOT

PACKAGE = ROOT / "blender_addon" / "particlemesh"
BPY_FREE = ("native", "mesh_arrays", "jobs", "generate")


def parse(name):
    return ast.parse((PACKAGE / f"{name}.py").read_text(), filename=f"{name}.py")


def bl_info():
    for node in parse("__init__").body:
        if isinstance(node, ast.Assign) and node.targets[0].id == "bl_info":
            return ast.literal_eval(node.value)
    raise AssertionError("no bl_info")


# ---- manifest (rules of Blender 4.2's extension validation, cli/blender_ext.py) ---------------

SEMVER = re.compile(r"^(0|[1-9]\d*)\.(0|[1-9]\d*)\.(0|[1-9]\d*)$")


def test_manifest_is_a_valid_extension_manifest():
    m = tomllib.loads((PACKAGE / "blender_manifest.toml").read_text())
    for key in ("schema_version", "id", "name", "tagline", "version", "type", "maintainer",
                "license", "blender_version_min"):
        assert key in m, key
    assert m["schema_version"] == "1.0.0"
    assert m["id"].isidentifier() and "__" not in m["id"] and not m["id"].startswith("_")
    assert SEMVER.match(m["version"])
    assert m["type"] == "add-on"
    assert len(m["tagline"]) <= 64 and (m["tagline"][-1].isalnum() or m["tagline"][-1] in ")]}")
    assert m["tagline"] == m["tagline"].strip()
    assert all(lic.startswith("SPDX:") for lic in m["license"]) and m["license"]
    assert m["blender_version_min"].count(".") == 2
    assert tuple(map(int, m["blender_version_min"].split("."))) >= (4, 2, 0)
    assert set(m["platforms"]) <= {"windows-x64", "windows-arm64", "macos-x64", "macos-arm64",
                                   "linux-x64"}
    for key, reason in m.get("permissions", {}).items():
        assert key in {"files", "network", "clipboard", "camera", "microphone"}
        assert len(reason) <= 64 and reason[-1].isalnum()


def test_manifest_agrees_with_bl_info_and_the_project():
    m = tomllib.loads((PACKAGE / "blender_manifest.toml").read_text())
    info = bl_info()
    assert m["version"] == ".".join(map(str, info["version"]))
    assert m["id"] == PACKAGE.name == info["name"]
    assert info["blender"] == (3, 4, 0)
    cmake = (ROOT / "CMakeLists.txt").read_text()
    project_version = re.search(r"project\(particlemesh VERSION (\S+)", cmake).group(1)
    assert m["version"] == project_version


def test_relative_imports_only():
    """An extension is imported as bl_ext.<repo>.particlemesh: no absolute self-imports."""
    for path in PACKAGE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                assert not any(a.name.split(".")[0] == "particlemesh" for a in node.names), path
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                assert node.module.split(".")[0] != "particlemesh", path
    assert "__package__" in (PACKAGE / "properties.py").read_text()  # AddonPreferences id


def test_bpy_free_modules_do_not_import_bpy():
    for name in BPY_FREE:
        for node in ast.walk(parse(name)):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module]
            assert not any(n.split(".")[0] in ("bpy", "bmesh", "mathutils") for n in names), name


# ---- the zip ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def addon_zip():
    path = os.environ.get("PM_ADDON_ZIP")
    if not path or not os.path.isfile(path):
        pytest.skip("PM_ADDON_ZIP is not set to the built add-on zip")
    return path


def test_zip_layout(addon_zip):
    with zipfile.ZipFile(addon_zip) as z:
        names = set(z.namelist())
    sources = {f"particlemesh/{p.name}" for p in PACKAGE.glob("*.py")}
    assert sources <= names
    assert "particlemesh/blender_manifest.toml" in names
    assert "particlemesh/lib/libparticlemesh.so" in names
    # One top-level folder: Blender 3.4 unpacks it into addons/, 4.2 finds the manifest in it.
    assert {n.split("/")[0] for n in names} == {"particlemesh"}
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)


def test_zip_library_loads_and_matches(addon_zip, native, tmp_path):
    with zipfile.ZipFile(addon_zip) as z:
        z.extractall(tmp_path)
    lib = native.load(str(tmp_path / "particlemesh/lib/libparticlemesh.so"))
    assert lib.abi_version == native.ABI_VERSION
    assert lib.version == native.load().version


def test_zip_pcl_bridge_reads_pcd_from_the_unpacked_zip(addon_zip, data_dir, tmp_path):
    """The zip's libparticlemesh_pcl.so, unpacked alone, in a fresh process with no override:
    native.py finds it next to libparticlemesh and it binds to that library (its soname),
    not to the build tree (its RUNPATH is $ORIGIN)."""
    import subprocess
    with zipfile.ZipFile(addon_zip) as z:
        assert "particlemesh/lib/libparticlemesh_pcl.so" in z.namelist()
        z.extractall(tmp_path)
    lib_dir = tmp_path / "particlemesh" / "lib"
    code = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('n', {str(tmp_path / 'particlemesh' / 'native.py')!r})\n"
        "n = importlib.util.module_from_spec(spec); spec.loader.exec_module(n)\n"
        f"c = n.read_cloud({str(data_dir / 'pcd' / 'colored_cloud.pcd')!r})\n"
        "print(n.load().path); print(n.load_pcl().path); print(len(c.positions), sorted(c.attributes))\n")
    env = {k: v for k, v in os.environ.items()
           if k not in ("PARTICLEMESH_LIBRARY", "PARTICLEMESH_PCL_LIBRARY", "LD_LIBRARY_PATH")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    core, bridge, summary = out.stdout.strip().splitlines()
    assert os.path.dirname(core) == str(lib_dir) and os.path.dirname(bridge) == str(lib_dir)
    assert summary == "1000 ['color']"
    import shutil
    if shutil.which("readelf"):
        dynamic = subprocess.run(["readelf", "-d", str(lib_dir / "libparticlemesh_pcl.so")],
                                 capture_output=True, text=True, check=True).stdout
        runpath = [line for line in dynamic.splitlines() if "RUNPATH" in line or "RPATH" in line]
        assert runpath and all("[$ORIGIN]" in line for line in runpath), runpath


# ---- bpy-free modules of the package ----------------------------------------------------------

@pytest.fixture(scope="module")
def pkg(native):
    """The package's bpy-free modules, imported under a stand-in package (its __init__ needs
    bpy), so their relative imports resolve."""
    name = "pm_addon_bpy_free"
    package = types.ModuleType(name)
    package.__path__ = [str(PACKAGE)]
    sys.modules[name] = package
    try:
        return types.SimpleNamespace(**{m: importlib.import_module(f"{name}.{m}") for m in BPY_FREE})
    finally:
        for key in [k for k in sys.modules if k == name or k.startswith(name + ".")]:
            del sys.modules[key]


def sphere(n):
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)],
                    1).astype(np.float32)


def face_dots(p, triangles):
    face = np.cross(p[triangles[:, 1]] - p[triangles[:, 0]], p[triangles[:, 2]] - p[triangles[:, 0]])
    return np.einsum("ij,ij->i", face, p[triangles].mean(axis=1))


def test_generate_triangulate_finished_surface_and_velocity(pkg):
    p = sphere(2000)
    velocity = np.tile(np.float32([0, 0, 1]), (2000, 1))
    particles = pkg.generate.Particles(p, normals=-p, velocities=velocity)  # inward normals
    mesh = pkg.generate.run("TRIANGULATE", particles, {"auto_spacing": True})
    np.testing.assert_array_equal(mesh.attributes["velocity"], velocity)
    assert (face_dots(p, mesh.triangles) > 0).all()  # closed parts face outward regardless
    assert mesh.stats["normals_are_face_weighted"]    # Blender's own normals will do
    kept = pkg.generate.run("TRIANGULATE", particles, {"orient": False, "normal_source": "INPUT"})
    assert (face_dots(p, kept.triangles) < 0).all()   # followed the given normals


def test_generate_thin_meshes_an_even_subset_with_its_channels(pkg):
    p = sphere(20000)
    velocity = p * 3.0  # per particle, so a wrong subset shows
    particles = pkg.generate.Particles(p, velocities=velocity)
    full = pkg.generate.run("TRIANGULATE", particles, {})
    for settings in ({"thin": 2.0}, {"thin": 2.0, "auto_spacing": False,
                                     "spacing": full.stats["spacing"]}):
        mesh = pkg.generate.run("TRIANGULATE", particles, settings)
        assert mesh.stats["thinned_from"] == 20000
        assert 20000 / 8 < mesh.vertex_count < 20000 / 3
        # Its vertices are particles, each with its own velocity.
        idx = pkg.native.thin(p, mesh.stats["thin_distance"])
        np.testing.assert_array_equal(mesh.positions, p[idx])
        np.testing.assert_array_equal(mesh.attributes["velocity"], velocity[idx])
        # Still one closed sphere, facing out: V - E + F = 2 with E = 3F / 2.
        report = pkg.native.mesh_report(mesh.positions, mesh.triangles)
        assert report["boundary_edges"] == 0 and report["vertices_used"] == mesh.vertex_count
        assert mesh.vertex_count - mesh.triangle_count // 2 == 2
        assert (face_dots(mesh.positions, mesh.triangles) > 0).all()
    assert "thinned_from" not in pkg.generate.run("TRIANGULATE", particles, {"thin": 1.0}).stats


def test_viewport_budget_thins_a_bigger_system_to_about_the_budget(pkg):
    """Live mode's viewport budget: a system over it is thinned (an even subset, still one
    closed sphere) to at most about the budget; one under it, or budget 0, is meshed whole."""
    p = sphere(20000)
    particles = pkg.generate.Particles(p)
    for budget in (1000, 4000):
        mesh = pkg.generate.run("TRIANGULATE", particles, {"viewport_budget": budget})
        assert budget / 2 <= mesh.vertex_count <= pkg.generate.BUDGET_SLACK * budget
        assert mesh.stats["thinned_from"] == 20000
        assert mesh.stats["thin_factor"] > 1.0
        report = pkg.native.mesh_report(mesh.positions, mesh.triangles)
        assert report["boundary_edges"] == 0 and report["vertices_used"] == mesh.vertex_count
        assert mesh.vertex_count - mesh.triangle_count // 2 == 2
    # A Thin Out coarser than the budget needs stays.
    coarse = pkg.generate.run("TRIANGULATE", particles, {"viewport_budget": 4000, "thin": 4.0})
    assert coarse.stats["thin_factor"] == 4.0 and coarse.vertex_count < 2000
    for settings in ({"viewport_budget": 20000}, {"viewport_budget": 0}):
        whole = pkg.generate.run("TRIANGULATE", particles, settings)
        assert whole.vertex_count == 20000 and "thinned_from" not in whole.stats


def test_viewport_budget_corrects_for_unevenly_spaced_particles(pkg):
    """Where part of the cloud is sparser than its median spacing (a scan's far side), the
    thinning by the even-spacing factor keeps far more than the budget; the measured count
    corrects the factor."""
    dense, sparse = sphere(15000), sphere(5000) * 3.0 + np.float32([10, 0, 0])
    p = np.concatenate([dense, sparse])
    r0 = pkg.native.estimate_spacing(p, max_samples=pkg.generate.THIN_SPACING_SAMPLES)
    first = len(pkg.native.thin(p, pkg.generate.budget_thin(len(p), 2000) * r0))
    assert first > 2 * 2000  # the sparse sphere keeps nearly all of its particles
    mesh = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p), {"viewport_budget": 2000})
    assert mesh.vertex_count <= pkg.generate.BUDGET_SLACK * 2000


def test_volume_particles_warn_to_polygonize(pkg):
    """Particles filling a block (a jittered lattice, as a fluid simulation gives) are no
    surface sample: most seed triangles are dropped by co-normality, loops stay open, and the
    warning says Polygonize; a sphere's surface particles get no such warning."""
    rng = np.random.default_rng(5)
    grid = np.stack(np.meshgrid(*[np.arange(14.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    block = (grid + rng.normal(0, 0.1, grid.shape)).astype(np.float32)
    data = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(block), {})
    assert data.stats["rejected_conormal"] * 20 > data.stats["kept"] * 7
    warning = pkg.generate.volume_particles_warning(data.stats)
    assert warning and "Polygonize" in warning
    surface = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(sphere(5000)), {})
    assert pkg.generate.volume_particles_warning(surface.stats) is None
    assert surface.stats["rejected_conormal"] * 20 < surface.stats["kept"]


def test_generate_raw_is_wound_by_the_normals(pkg):
    p = sphere(2000)
    out = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p, normals=p), {"raw": True})
    assert (face_dots(p, out.triangles) > 0).all()
    assert "normals_are_face_weighted" not in out.stats
    inward = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p, normals=-p), {"raw": True})
    assert (face_dots(p, inward.triangles) < 0).all()


def test_generate_settings_keys_match_the_properties():
    """Every key generate.py reads is a property of the operators and generated objects."""
    tree = parse("properties")
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    used = set(re.findall(r'settings(?:\.get\(|\[)"(\w+)"', (PACKAGE / "generate.py").read_text()))
    assert used and used <= names, used - names


def test_generate_reports_an_empty_result(pkg):
    particles = pkg.generate.Particles(sphere(500))
    with pytest.raises(pkg.native.ParticlemeshError, match="no triangles"):
        pkg.generate.run("TRIANGULATE", particles, {"auto_spacing": False, "spacing": 1e-4})


def test_polygonize_radii(pkg):
    p = pkg.generate.Particles(sphere(10), sizes=np.full(10, 0.5, np.float32), particle_size=0.5)
    assert pkg.generate.polygonize_radii(p, {"radius_mode": "AUTO"}) == (0.0, None)
    assert pkg.generate.polygonize_radii(p, {"radius_mode": "FIXED", "radius": 0.3}) == (0.3, None)
    r, radii = pkg.generate.polygonize_radii(p, {"radius_mode": "PARTICLE_SIZE", "radius_factor": 3})
    assert r == 0.0 and np.allclose(radii, 1.5)
    no_sizes = pkg.generate.Particles(sphere(10), particle_size=0.25)
    assert pkg.generate.polygonize_radii(no_sizes, {"radius_mode": "PARTICLE_SIZE",
                                                    "radius_factor": 2}) == (0.5, None)


def test_polygonize_threshold_from_particle_sizes(pkg):
    """Radii from the particles' sizes: the default threshold takes the size as half the rest
    spacing (touching balls), so an isolated particle becomes a ball of about its size and a
    sparse sheet of particles still has a surface, where the library's R = 2 spacings default
    (3.33 for Wyvill) would give none."""
    if not pkg.native.has_polygonize():
        pytest.skip("pm_polygonize is not in this library (issue 7)")
    threshold = pkg.generate.polygonize_threshold
    sizes = {"radius_mode": "PARTICLE_SIZE", "radius_factor": 2.0, "kernel": "WYVILL"}
    assert threshold(sizes, True) == pytest.approx(0.5)  # only the particle itself within 2 s
    assert threshold({**sizes, "radius_factor": 4.0}, True) == pytest.approx(
        0.5 * pkg.native.lattice_field(pkg.native.KERNEL_WYVILL, 2.0, 1.0))
    assert threshold({**sizes, "threshold": 1.5}, True) == 1.5     # an explicit level stays
    assert threshold({"radius_mode": "AUTO"}, False) == 0.0        # the library's default
    assert threshold({**sizes}, False) == 0.0                       # no sizes: as AUTO
    one = pkg.generate.Particles(np.zeros((1, 3), np.float32), sizes=np.float32([0.1]))
    ball = pkg.generate.run("POLYGONIZE", one, sizes)
    r = np.linalg.norm(ball.positions, axis=1)
    assert ball.triangle_count > 100 and abs(r.mean() - 0.1) < 0.01 and r.std() < 0.005
    # A sheet of particles 1.46 sizes apart (a 642-vertex icosphere of radius 1, size 0.1).
    p = sphere(642)
    shell = pkg.generate.Particles(p, sizes=np.full(642, 0.1, np.float32))
    mesh = pkg.generate.run("POLYGONIZE", shell, sizes)
    assert mesh.triangle_count > 1000
    assert (np.abs(np.linalg.norm(mesh.positions, axis=1) - 1.0) < 0.2).all()
    with pytest.raises(pkg.native.ParticlemeshError, match="no surface"):
        pkg.generate.run("POLYGONIZE", shell, {**sizes, "threshold": 3.33})
    # Anisotropic kernels: the library calibrates the threshold itself.
    assert threshold({**sizes, "anisotropic": True}, True) == 0.0
    assert threshold({**sizes, "anisotropic": True, "threshold": 1.5}, True) == 1.5


def test_polygonize_anisotropic_setting(pkg):
    """The add-on's Anisotropic Kernels setting reaches the library: a one-particle sheet stays
    one surface with it, while the default spherical kernels leave little of it."""
    if not pkg.native.has_polygonize():
        pytest.skip("pm_polygonize is not in this library (issue 7)")
    rng = np.random.default_rng(2)
    x, z = np.meshgrid(np.arange(40.0), np.arange(40.0))
    sheet = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1) + rng.uniform(-0.15, 0.15, (x.size, 3))
    particles = pkg.generate.Particles(sheet.astype(np.float32))
    an = pkg.generate.run("POLYGONIZE", particles, {"anisotropic": True})
    rep = pkg.native.mesh_report(an.positions, an.triangles)
    assert rep["closed"] and rep["components"] == 1
    assert an.stats["anisotropic"] == 1
    iso = pkg.generate.run("POLYGONIZE", particles, {})
    assert iso.triangle_count < 0.5 * an.triangle_count


def test_job_runs_and_cancels(pkg):
    particles = pkg.generate.Particles(sphere(100000))
    job = pkg.jobs.Job(pkg.generate.run, "TRIANGULATE", particles, {})
    job.cancel()
    job.start()
    assert job.wait(60)
    assert isinstance(job.error, pkg.native.CancelledError) and job.result is None
    job = pkg.jobs.Job(pkg.generate.run, "TRIANGULATE", pkg.generate.Particles(sphere(3000)), {})
    assert job.start().wait(60) and job.error is None and job.result.triangle_count > 5000
    assert job.progress.fraction > 0 and job.progress.stage


def test_mesh_arrays(pkg):
    ma = pkg.mesh_arrays
    m = np.eye(4)
    m[:3, :3] *= 2
    m[:3, 3] = [1, 2, 3]
    np.testing.assert_allclose(ma.transform_points([[1, 1, 1]], m), [[3, 4, 5]])
    np.testing.assert_allclose(ma.transform_normals([[0, 0, 3]], m), [[0, 0, 1]])
    p = np.zeros((4, 3), np.float32)
    p[2, 1] = np.inf
    with pytest.raises(ValueError, match=r"positions\[2\]\.y is infinite"):
        ma.check_finite(p, "positions")
    ma.check_finite(np.ones((3, 3)), "positions")
    assert ma.alive_mask([1, 2, 3, 4], [3, 4]).tolist() == [False, False, True, True]
    a = np.arange(12, dtype=np.float32)
    assert ma.content_hash(a) == ma.content_hash(a.copy()) != ma.content_hash(a + 1)
    assert ma.content_hash(a, None) != ma.content_hash(a)
    assert ma.loop_starts(3).tolist() == [0, 3, 6]
