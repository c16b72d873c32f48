"""The package where users get it: `cmake --install` (the sources in
<prefix>/lib/python3/dist-packages/particlemesh, linked to the installed library), `pip
install` from the build tree (offline, Debian's setuptools), each used from a fresh process
with nothing but PYTHONPATH; and the example script, run against the install."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT

EXAMPLE = ROOT / "python" / "examples" / "mesh_particles.py"


def clean_env(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("PARTICLEMESH_LIBRARY", "PARTICLEMESH_PCL_LIBRARY", "LD_LIBRARY_PATH",
                        "PYTHONPATH")}
    env.update(extra)
    return env


@pytest.fixture(scope="module")
def build_dir():
    d = os.environ.get("PM_BUILD_DIR")
    assert d and Path(d, "CMakeCache.txt").is_file(), f"PM_BUILD_DIR is not the build: {d!r}"
    return Path(d)


def test_cmake_install_and_the_example(build_dir, tmp_path):
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", str(build_dir), "--prefix", str(prefix)],
                   check=True, capture_output=True, text=True)
    site = prefix / "lib" / "python3" / "dist-packages"
    package = site / "particlemesh"
    assert (package / "__init__.py").is_file()
    link = package / "lib" / "libparticlemesh.so"
    assert link.is_symlink() and not os.path.isabs(os.readlink(link))
    assert link.resolve().parent == (prefix / "lib").resolve() or \
        link.resolve().parent.parent == (prefix / "lib").resolve()  # lib/ or lib/<multiarch>/
    out = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path / "out"), "--points", "6000"],
                         env=clean_env(PYTHONPATH=str(site)), capture_output=True, text=True,
                         timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert str(package / "lib" / "libparticlemesh.so") in lines[0]
    assert re.search(r"torus: \d+ particles -> \d+ triangles, .* closed True, genus 1$", lines[1])
    assert re.search(r"torus, 2 Loop levels: \d+ triangles, closed True$", lines[2])
    drop = re.search(r"drop: \d+ triangles, radius ([0-9.]+) \+- ([0-9.]+), closed True$", lines[3])
    # A ball of radius 1 cut from a jittered lattice: its surface within about a spacing.
    assert drop and 0.85 < float(drop.group(1)) < 1.1 and float(drop.group(2)) < 0.1
    assert "a bad option is an Error: " in lines[4] and "max_edge_factor" in lines[4]
    assert "triangulate:" in out.stderr  # the progress line
    for name in ("torus.ply", "torus_smooth.ply", "drop.ply"):
        assert (tmp_path / "out" / name).stat().st_size > 10000
    # The command-line tool as installed: the library from the prefix, and PCL's part (a .pcd
    # file, PCL's downsampling) from its two modules in the prefix's library folder, with
    # nothing in the environment.
    exe = prefix / "bin" / "particlemesh"
    if (build_dir / "cli" / "particlemesh").is_file():
        pts = "".join(f"{0.1 * i} {0.1 * j} 0\n" for i in range(20) for j in range(20))
        runs = [(tmp_path / "plane.xyz", [])]
        runs[0][0].write_text(pts)
        if (build_dir / "cli" / "libparticlemesh_cli_pcl.so").is_file():
            for name in ("libparticlemesh_cli_pcd.so", "libparticlemesh_cli_pcl.so"):
                assert list(prefix.glob(f"lib*/**/{name}")), f"{name} is not installed"
            pcd = tmp_path / "plane.pcd"
            pcd.write_text("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 400\n"
                           "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 400\nDATA ascii\n" + pts)
            runs += [(pcd, []), (runs[0][0], ["--voxel-grid", "0.1"])]
        for k, (src, extra) in enumerate(runs):
            mesh = tmp_path / f"{k}.ply"
            run = subprocess.run([str(exe), "triangulate", str(src), "-o", str(mesh), *extra], env=clean_env(),
                                 capture_output=True, text=True, timeout=120, cwd=tmp_path)
            assert run.returncode == 0, run.stderr
            assert "triangles" in run.stdout and mesh.stat().st_size > 1000


def test_pip_install_from_the_build_tree(build_dir, tmp_path):
    staged = Path(os.environ["PM_PYTHON_PATH"])
    target = tmp_path / "site"
    out = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-index",
                          "--no-build-isolation", "--no-deps", "--target", str(target),
                          str(staged)], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path, env=clean_env(PIP_NO_CACHE_DIR="1"))
    assert out.returncode == 0, out.stderr
    code = ("import particlemesh as pm, numpy as np\n"
            "m = pm.polygonize(np.zeros((1, 3)), radius=1.0, threshold=0.5)\n"
            "print(pm.library_path()); print(pm.topology(m)['closed'])\n")
    run = subprocess.run([sys.executable, "-c", code], env=clean_env(PYTHONPATH=str(target)),
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    path, closed = run.stdout.split()
    assert path == str(target / "particlemesh" / "lib" / "libparticlemesh.so") and closed == "True"
    assert (target / "particlemesh" / "lib" / "licenses" / "README").is_file()
    dist = list(target.glob("particlemesh-*.dist-info"))
    assert len(dist) == 1 and "Version: " in (dist[0] / "METADATA").read_text()
