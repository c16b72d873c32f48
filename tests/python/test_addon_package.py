"""The add-on package outside Blender: a valid Blender 4.2 extension manifest that agrees with
bl_info, relative imports only, bpy-free modules that really are; the built zip: its layout
(the Python package as the one source of its binding), libraries that need nothing beyond the
C/C++ runtime, their licences, the glibc they need; and the bpy-free pipeline modules
(generate, jobs, mesh_arrays) as the zip ships them."""
import ast
import os
import re
import subprocess
import sys
import tomllib
import zipfile

import numpy as np
import pytest

from conftest import ROOT

PACKAGE = ROOT / "blender_addon" / "particlemesh"
PYTHON_PACKAGE = ROOT / "python" / "particlemesh"
BPY_FREE = ("mesh_arrays", "jobs", "generate")


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
    """An extension is imported as bl_ext.<repo>.particlemesh, and carries the Python package
    as its particlemesh.particlemesh: no absolute self-imports in either."""
    for path in [*PACKAGE.glob("*.py"), *PYTHON_PACKAGE.rglob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                assert not any(a.name.split(".")[0] == "particlemesh" for a in node.names), path
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                assert node.module.split(".")[0] != "particlemesh", path
    assert "__package__" in (PACKAGE / "properties.py").read_text()  # AddonPreferences id


def test_bpy_free_modules_do_not_import_bpy():
    trees = [parse(name) for name in BPY_FREE]
    trees += [ast.parse(p.read_text()) for p in PYTHON_PACKAGE.rglob("*.py")]
    for name, tree in zip([*BPY_FREE, *PYTHON_PACKAGE.rglob("*.py")], trees):
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module]
            assert not any(n.split(".")[0] in ("bpy", "bmesh", "mathutils") for n in names), name


# ---- the zip ----------------------------------------------------------------------------------

def test_zip_layout_carries_the_python_package_as_is(addon_zip):
    with zipfile.ZipFile(addon_zip) as z:
        names = set(z.namelist())
        # One source: the add-on's binding is the Python package, byte for byte.
        for path in PYTHON_PACKAGE.rglob("*.py"):
            name = path.relative_to(PYTHON_PACKAGE).as_posix()
            assert z.read(f"particlemesh/particlemesh/{name}") == path.read_bytes(), name
    sources = {f"particlemesh/{p.name}" for p in PACKAGE.glob("*.py")}
    assert sources <= names and "particlemesh/native.py" not in names
    assert "particlemesh/blender_manifest.toml" in names
    assert "particlemesh/particlemesh/lib/libparticlemesh.so" in names
    package = {n for n in names if n.startswith("particlemesh/particlemesh/") and n.endswith(".py")}
    assert package == {f"particlemesh/particlemesh/{p.relative_to(PYTHON_PACKAGE).as_posix()}"
                       for p in PYTHON_PACKAGE.rglob("*.py")}
    # One top-level folder: Blender 3.4 unpacks it into addons/, 4.2 finds the manifest in it.
    assert {n.split("/")[0] for n in names} == {"particlemesh"}
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)


#: What every Linux has, and Blender loads itself: the only libraries the zip may need from the
#: system (the PCL bridge, for .pcd files only, also needs PCL).
SYSTEM_RUNTIME = re.compile(r"^(libc\.so\.6|libm\.so\.6|libstdc\+\+\.so\.6|libgcc_s\.so\.1|"
                            r"ld-linux-x86-64\.so\.2|libpthread\.so\.0|libdl\.so\.2|"
                            r"librt\.so\.1|libz\.so\.1)$")


def dynamic_section(path):
    out = subprocess.run(["readelf", "-d", str(path)], capture_output=True, text=True,
                         check=True).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.*?)\]", out)
    runpath = re.findall(r"\((?:RUNPATH|RPATH)\)\s+Library r(?:un)?path: \[(.*?)\]", out)
    soname = re.findall(r"\(SONAME\)\s+Library soname: \[(.*?)\]", out)
    return needed, runpath, soname


def test_zip_libraries_need_only_the_c_runtime_or_each_other(unpacked_addon):
    """Every NEEDED entry of every library in the zip is the C/C++ runtime or another library
    in the zip (found through RUNPATH $ORIGIN); only the PCL bridge may need PCL."""
    lib_dir = unpacked_addon / "particlemesh" / "lib"
    libraries = sorted(p for p in lib_dir.iterdir() if p.is_file() and ".so" in p.name)
    names = {p.name for p in libraries}
    assert {"libparticlemesh.so", "libtbb.so.12", "libOpenMeshCore.so.9.0", "libosdCPU.so.3.5.0",
            "libpng16.so.16", "libgomp.so.1"} <= names, names
    for path in libraries:
        needed, runpath, _ = dynamic_section(path)
        assert runpath == ["$ORIGIN"], (path.name, runpath)
        if path.name == "libparticlemesh_pcl.so":
            assert "libparticlemesh.so.0.1" in needed
            continue
        foreign = [n for n in needed if not SYSTEM_RUNTIME.match(n) and n not in names]
        assert not foreign, f"{path.name} needs {foreign} from the system"
    # The core library's own name is its soname's target here: the bridge asks for the
    # soname, which the loader matches with the loaded libparticlemesh.so.
    assert dynamic_section(lib_dir / "libparticlemesh.so")[2] == ["libparticlemesh.so.0.1"]


def test_zip_carries_the_licence_of_every_bundled_library(unpacked_addon):
    lib_dir = unpacked_addon / "particlemesh" / "lib"
    readme = (lib_dir / "licenses" / "README").read_text()
    for path in lib_dir.iterdir():
        if path.is_file() and ".so" in path.name and not path.name.startswith("libparticlemesh"):
            line = re.search(rf"^  {re.escape(path.name)}: Debian package (\S+) \S+, "
                             r"licenses/(\S+)$", readme, re.M)
            assert line, f"no licence entry for {path.name}"
            text = (lib_dir / "licenses" / line.group(2)).read_text()
            assert "Copyright" in text or "copyright" in text, path.name


def glibc_versions(path, prefix):
    out = subprocess.run(["objdump", "-T", str(path)], capture_output=True, text=True,
                         check=True).stdout
    return {tuple(map(int, v.split("."))) for v in re.findall(rf"\b{prefix}_([0-9.]+)\b", out)}


def test_zip_needs_glibc_2_34_and_the_libstdcxx_of_gcc_11(unpacked_addon):
    """What docs/blender.md states, from the symbol versions the zip's libraries require: glibc
    2.34 (Debian 12, Ubuntu 22.04, RHEL 9; libtbb and libgomp ask for it) and the libstdc++ of
    GCC 11 or newer (GLIBCXX_3.4.29, CXXABI_1.3.13)."""
    lib_dir = unpacked_addon / "particlemesh" / "lib"
    found = {"GLIBC": set(), "GLIBCXX": set(), "CXXABI": set()}
    for path in lib_dir.iterdir():
        if path.is_file() and ".so" in path.name and path.name != "libparticlemesh_pcl.so":
            for prefix, versions in found.items():
                versions |= glibc_versions(path, prefix)
    assert max(found["GLIBC"]) == (2, 34)
    assert max(found["GLIBCXX"]) == (3, 4, 29)
    assert max(found["CXXABI"]) == (1, 3, 13)


def test_zip_libraries_are_the_ones_loaded(unpacked_addon, data_dir):
    """In a fresh process with no override, the zip's package loads its own libparticlemesh,
    and every library it needs beyond the runtime comes from the zip's lib/ (RUNPATH
    $ORIGIN), not the system's; the PCL bridge beside it reads a .pcd."""
    lib_dir = unpacked_addon / "particlemesh" / "lib"
    code = (
        "import sys, importlib\n"
        f"sys.path.insert(0, {str(unpacked_addon)!r})\n"
        "pm = importlib.import_module('particlemesh')\n"
        "assert pm.__file__.startswith(sys.path[0]), pm.__file__\n"
        f"c = pm.read_points({str(data_dir / 'pcd' / 'colored_cloud.pcd')!r})\n"
        "import numpy as np\n"
        "i = np.arange(2000) + 0.5; phi = np.arccos(1 - 2 * i / 2000); t = np.pi * (1 + 5 ** 0.5) * i\n"
        "s = np.stack([np.cos(t) * np.sin(phi), np.sin(t) * np.sin(phi), np.cos(phi)], 1)\n"
        "assert pm.topology(pm.smooth(pm.triangulate(s)))['closed']\n"
        "print(pm.library_path()); print(pm.pcl_bridge_path()); print(len(c.positions))\n"
        "print(open('/proc/self/maps').read())\n")
    env = {k: v for k, v in os.environ.items()
           if k not in ("PARTICLEMESH_LIBRARY", "PARTICLEMESH_PCL_LIBRARY", "LD_LIBRARY_PATH",
                        "PYTHONPATH")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=120, cwd=unpacked_addon.parent)
    assert out.returncode == 0, out.stderr
    core, bridge, count, maps = out.stdout.split("\n", 3)
    assert os.path.dirname(core) == str(lib_dir) and os.path.dirname(bridge) == str(lib_dir)
    assert count == "1000"
    for name in ("libtbb.so.12", "libOpenMeshCore.so.9.0", "libosdCPU.so.3.5.0", "libpng16.so.16",
                 "libgomp.so.1"):
        mapped = {line.split()[-1] for line in maps.splitlines() if name.split(".so")[0] + ".so" in line}
        assert mapped == {str(lib_dir / name)}, (name, mapped)


# ---- bpy-free modules of the package ----------------------------------------------------------

@pytest.fixture(scope="module")
def pkg(addon):
    """The zip's bpy-free modules (conftest.addon), and its copy of the package as pkg.pm."""
    return addon


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
        idx = pkg.pm.thin(p, mesh.stats["thin_distance"])
        np.testing.assert_array_equal(mesh.vertices, p[idx])
        np.testing.assert_array_equal(mesh.attributes["velocity"], velocity[idx])
        # Still one closed sphere, facing out: V - E + F = 2 with E = 3F / 2.
        report = pkg.pm.topology(mesh)
        assert report["boundary_edges"] == 0 and report["vertices_used"] == mesh.vertex_count
        assert mesh.vertex_count - mesh.triangle_count // 2 == 2
        assert (face_dots(mesh.vertices, mesh.triangles) > 0).all()
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
        report = pkg.pm.topology(mesh)
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
    r0 = pkg.pm.estimate_spacing(p, max_samples=pkg.generate.THIN_SPACING_SAMPLES)
    first = len(pkg.pm.thin(p, pkg.generate.budget_thin(len(p), 2000) * r0))
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
    assert data.stats["looks_like_volume"] == 1
    warning = pkg.generate.volume_particles_warning(data.stats)
    assert warning and "Polygonize" in warning
    surface = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(sphere(5000)), {})
    assert pkg.generate.volume_particles_warning(surface.stats) is None
    assert surface.stats["rejected_conormal"] * 20 < surface.stats["kept"]
    assert surface.stats["looks_like_volume"] == 0


def test_narrow_holes_warn_with_the_fill_that_reaches_them(pkg):
    """Holes the fill did not try for the Fill Edge Factor set, though narrow: the library
    counts them (narrow_loops, their widest and longest), the warning names the settings, and
    those settings close the sphere; at the defaults, no warning."""
    x = np.random.default_rng(3).normal(size=(40000, 3))
    x /= np.linalg.norm(x, axis=1)[:, None]
    p = x[pkg.pm.thin(x, 0.05)].astype(np.float32)  # a Poisson-disk sampling: not on a grid
    assert pkg.generate.narrow_holes_warning(pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p), {}).stats,
                                             {}) is None
    data = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p), {"fill_edge_factor": 1.0})
    s = data.stats
    assert s["holes_left"] > 3 and s["narrow_loops"] == s["holes_left"]
    assert 1.0 < s["narrow_loop_width"] <= 3.0 and s["narrow_loop_edges"] >= 3
    warning = pkg.generate.narrow_holes_warning(s, {"fill_edge_factor": 1.0, "fill_holes": 100})
    assert warning and warning.startswith(f"all {s['holes_left']} holes left open are narrow gaps in the sampling")
    assert pkg.generate.narrow_holes_warning({**s, "holes_left": s["narrow_loops"] + 2}, {}).startswith(
        f"{s['narrow_loops']} of the {s['narrow_loops'] + 2} holes")
    assert pkg.generate.narrow_holes_warning({**s, "holes_left": 1, "narrow_loops": 1}, {}).startswith(
        "the hole left open is a narrow gap")
    factor = float(warning.split("Fill Edge Factor to ")[1].split()[0])
    assert s["narrow_loop_width"] <= factor < s["narrow_loop_width"] + 0.1 + 1e-9
    assert "Fill Holes" not in warning
    assert "Fill Holes to 2" in pkg.generate.narrow_holes_warning({**s, "narrow_loop_edges": 2}, {"fill_holes": 1})
    filled = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(p), {"fill_edge_factor": factor})
    assert filled.stats["holes_left"] == 0 and filled.stats["narrow_loops"] == 0
    assert pkg.generate.narrow_holes_warning(filled.stats, {"fill_edge_factor": factor}) is None
    assert pkg.pm.topology(filled)["closed"]


def test_stray_pieces_warn_with_the_min_piece_triangles_that_removes_them(pkg):
    """Six lone triangles far from a sphere: the warning names Min Piece Triangles 2, which
    removes them; none once it is set, none for fewer than five strays."""
    p = sphere(3000)
    r0 = np.sqrt(4 * np.pi / 3000)
    lone = [np.array([3 * np.cos(k), 3 * np.sin(k), 0.0]) + np.array([[0, 0, 0], [r0, 0, 0], [r0 / 2, 0.87 * r0, 0]])
            for k in range(6)]
    points = np.concatenate([p] + lone).astype(np.float32)
    data = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(points), {})
    warning = pkg.generate.stray_pieces_warning(data.stats, {}, data.triangle_count)
    assert warning == "6 lone triangles lie apart from the rest: set Min Piece Triangles to 2 to remove them"
    assert pkg.generate.stray_pieces_warning(data.stats, {"min_component_triangles": 2}, data.triangle_count) is None
    assert pkg.generate.stray_pieces_warning({**data.stats, "stray_pieces": 4}, {}, data.triangle_count) is None
    removed = pkg.generate.run("TRIANGULATE", pkg.generate.Particles(points), {"min_component_triangles": 2})
    assert removed.stats["components_removed"] == 6 and removed.stats["stray_pieces"] == 0
    assert pkg.pm.topology(removed)["components"] == 1
    # A limit above every piece leaves nothing: the error names the setting, not the spacing.
    with pytest.raises(pkg.generate.EmptyResult, match="fewer than Min Piece Triangles \\(100000\\): lower it"):
        pkg.generate.run("TRIANGULATE", pkg.generate.Particles(points), {"min_component_triangles": 100000})


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
    with pytest.raises(pkg.pm.Error, match="no triangles"):
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
    threshold = pkg.generate.polygonize_threshold
    sizes = {"radius_mode": "PARTICLE_SIZE", "radius_factor": 2.0, "kernel": "WYVILL"}
    assert threshold(sizes, True) == pytest.approx(0.5)  # only the particle itself within 2 s
    assert threshold({**sizes, "radius_factor": 4.0}, True) == pytest.approx(
        0.5 * pkg.pm.lattice_field("wyvill", 2.0, 1.0))
    assert threshold({**sizes, "threshold": 1.5}, True) == 1.5     # an explicit level stays
    assert threshold({"radius_mode": "AUTO"}, False) == 0.0        # the library's default
    assert threshold({**sizes}, False) == 0.0                       # no sizes: as AUTO
    one = pkg.generate.Particles(np.zeros((1, 3), np.float32), sizes=np.float32([0.1]))
    ball = pkg.generate.run("POLYGONIZE", one, sizes)
    r = np.linalg.norm(ball.vertices, axis=1)
    assert ball.triangle_count > 100 and abs(r.mean() - 0.1) < 0.01 and r.std() < 0.005
    # A sheet of particles 1.46 sizes apart (a 642-vertex icosphere of radius 1, size 0.1).
    p = sphere(642)
    shell = pkg.generate.Particles(p, sizes=np.full(642, 0.1, np.float32))
    mesh = pkg.generate.run("POLYGONIZE", shell, sizes)
    assert mesh.triangle_count > 1000
    assert (np.abs(np.linalg.norm(mesh.vertices, axis=1) - 1.0) < 0.2).all()
    with pytest.raises(pkg.pm.Error, match="no surface"):
        pkg.generate.run("POLYGONIZE", shell, {**sizes, "threshold": 3.33})
    # Anisotropic kernels: the library calibrates the threshold itself.
    assert threshold({**sizes, "anisotropic": True}, True) == 0.0
    assert threshold({**sizes, "anisotropic": True, "threshold": 1.5}, True) == 1.5


def test_polygonize_anisotropic_setting(pkg):
    """The add-on's Anisotropic Kernels setting reaches the library: a one-particle sheet stays
    one surface with it, while spherical kernels of the same radius leave little of it."""
    rng = np.random.default_rng(2)
    x, z = np.meshgrid(np.arange(40.0), np.arange(40.0))
    sheet = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1) + rng.uniform(-0.15, 0.15, (x.size, 3))
    particles = pkg.generate.Particles(sheet.astype(np.float32))
    an = pkg.generate.run("POLYGONIZE", particles, {"anisotropic": True})
    rep = pkg.pm.topology(an)
    assert rep["closed"] and rep["components"] == 1
    assert an.stats["anisotropic"] == 1
    iso = pkg.generate.run("POLYGONIZE", particles, {"radius_mode": "FIXED", "radius": an.stats["radius"]})
    assert iso.triangle_count < 0.5 * an.triangle_count


def test_job_runs_and_cancels(pkg):
    particles = pkg.generate.Particles(sphere(100000))
    job = pkg.jobs.Job(pkg.generate.run, "TRIANGULATE", particles, {})
    job.cancel()
    job.start()
    assert job.wait(60)
    assert isinstance(job.error, pkg.pm.CancelledError) and job.result is None
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
