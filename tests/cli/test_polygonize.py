"""particlemesh polygonize, end to end through the binary."""
import json
import math
import random
from pathlib import Path

import pytest


def write_block(path: Path, nx=10, ny=14, nz=8, spacing=0.1, jitter=0.1, seed=5):
    """A dam-break-like block of particles on a jittered lattice, as .xyz."""
    rng = random.Random(seed)
    lines = []
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                lines.append("%.9g %.9g %.9g" % tuple((c + rng.uniform(-jitter, jitter)) * spacing for c in (x, y, z)))
    path.write_text("\n".join(lines) + "\n")
    return nx * ny * nz


def test_block_gives_one_closed_surface_with_defaults(cli, inspect, tmp_path):
    pts = tmp_path / "block.xyz"
    n = write_block(pts)
    out = tmp_path / "block.ply"
    report = tmp_path / "report.json"
    proc = cli("polygonize", pts, "-o", out, "--report", report)
    assert "threshold T" in proc.stdout
    r = json.loads(report.read_text())
    p = r["polygonize"]
    assert p["particles"] == n
    assert p["radius_defaulted"] and p["threshold_defaulted"] and p["cell_size_defaulted"]
    # A lattice jittered by up to a tenth of its spacing holds its particles at 2 x spacing.
    assert math.isclose(p["radius"], 2 * p["spacing"]) and p["enclosed_fraction"] > 0.9
    assert "radius R      %.6g (default: 2 x spacing)" % p["radius"] in proc.stdout
    assert math.isclose(p["cell_size"], p["radius"] / 4)
    assert p["kernel"] == "wyvill"
    assert p["sampled_nodes"] == 512 * p["sampled_blocks"]
    mesh = inspect(out)
    assert mesh["closed"] and mesh["manifold"] and mesh["consistently_oriented"] and mesh["outward"]
    assert mesh["components"] == 1
    assert mesh["euler_characteristic"] == 2
    assert mesh["triangles"] == p["triangles"] == r["topology"]["triangles"]
    header = out.read_bytes()[:400].decode("ascii", "replace")
    assert "property float nx" in header  # normals from the field gradient


def test_options_are_used(cli, tmp_path):
    pts = tmp_path / "block.xyz"
    write_block(pts, 6, 6, 6)
    out = tmp_path / "b.obj"
    report = tmp_path / "r.json"
    cli("polygonize", pts, "-o", out, "--radius", "0.25", "--threshold", "1.5", "--kernel", "poly6",
        "--cell", "0.04", "--threads", "1", "--report", report, "-q")
    p = json.loads(report.read_text())["polygonize"]
    assert (p["radius"], p["threshold"], p["cell_size"], p["kernel"]) == (0.25, 1.5, 0.04, "poly6")
    assert not (p["radius_defaulted"] or p["threshold_defaulted"] or p["cell_size_defaulted"])
    assert out.read_text().startswith("#") or out.read_text().lstrip().startswith("v")


def test_output_does_not_depend_on_threads(cli, tmp_path):
    pts = tmp_path / "block.xyz"
    write_block(pts, 12, 12, 12, jitter=0.3)
    a, b = tmp_path / "a.ply", tmp_path / "b.ply"
    cli("polygonize", pts, "-o", a, "--threads", "1", "-q")
    cli("polygonize", pts, "-o", b, "--threads", "2", "-q")
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("args, needle", [
    (["--radius", "-1"], "radius"),
    (["--kernel", "gauss"], "kernel"),
    (["--cell", "0"], "cell"),
])
def test_usage_errors(cli, tmp_path, args, needle):
    pts = tmp_path / "block.xyz"
    write_block(pts, 3, 3, 3)
    proc = cli("polygonize", pts, "-o", tmp_path / "x.ply", *args, check=False)
    assert proc.returncode == 2
    assert needle in proc.stderr


def test_errors_are_one_line_and_leave_no_file(cli, tmp_path):
    out = tmp_path / "x.ply"
    proc = cli("polygonize", tmp_path / "missing.xyz", "-o", out, check=False)
    assert proc.returncode == 1 and "no such file" in proc.stderr
    pts = tmp_path / "block.xyz"
    write_block(pts, 5, 5, 5)
    proc = cli("polygonize", pts, "-o", out, "--radius", "0.2", "--threshold", "1", "--cell", "0.001",
               "--max-grid-mib", "1", check=False)
    assert proc.returncode == 1
    # The command line's own options named (the library says max_grid_bytes).
    assert "(use a larger --cell or raise --max-grid-mib)" in proc.stderr and "max_grid_bytes" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert not out.exists()
    one = tmp_path / "one.xyz"
    one.write_text("0 0 0\n")
    proc = cli("polygonize", one, "-o", out, check=False)
    assert proc.returncode == 1 and "give a radius" in proc.stderr
    proc = cli("polygonize", one, "-o", out, "--radius", "1", "--threshold", "0.5")
    assert out.exists()


@pytest.mark.parametrize("name", ["double_dam_break_frame_26_4732_particles.ply",
                                  "bunny_frame_14_7705_particles.ply", "cube_2366_particles.ply"])
def test_sph_frames(cli, inspect, data_dir, tmp_path, name):
    out = tmp_path / "frame.ply"
    # splashsurf's parameters for these frames (particle radius r = 0.025): support 4r, cube r/2.
    cli("polygonize", data_dir / "particles" / name, "-o", out, "--radius", "0.1", "--cell", "0.0125", "-q")
    mesh = inspect(out)
    assert mesh["closed"] and mesh["manifold"] and mesh["consistently_oriented"]
    assert mesh["triangles"] > 1000


def test_particles_left_outside_the_surface_are_said(cli, tmp_path):
    """Irregular particles (uniform random points: their median nearest-neighbour distance is
    about half their mean spacing, like an SPH frame in motion): the default radius follows
    their packing and takes most of them in. At 2 x that distance most are left outside the
    surface: a warning with the share and the radius their packing suggests, the default's.
    A jittered lattice is not warned about."""
    rng = random.Random(3)
    pts = tmp_path / "random.xyz"
    pts.write_text("".join("%.9g %.9g %.9g\n" % (rng.random(), rng.random(), rng.random()) for _ in range(3000)))
    out, report = tmp_path / "m.ply", tmp_path / "r.json"
    proc = cli("polygonize", pts, "-o", out, "--report", report)
    assert "warning" not in proc.stderr
    default = json.loads(report.read_text())["polygonize"]
    assert default["radius_defaulted"] and default["enclosed_fraction"] > 0.6
    assert 1.25 * 2 * default["spacing"] < default["radius"] < 2 * 2 * default["spacing"]
    assert "from how densely the particles are packed" in proc.stdout
    proc = cli("polygonize", pts, "-o", out, "--report", report, "--radius", repr(2 * default["spacing"]))
    assert "warning: the surface encloses only" in proc.stderr
    assert "sample a surface rather than fill a volume: `particlemesh triangulate`" in proc.stderr
    r = json.loads(report.read_text())
    p = r["polygonize"]
    assert p["enclosed_fraction"] < 0.2 and math.isclose(p["density_radius"], default["radius"], rel_tol=1e-9)
    assert r["warning"].startswith("the surface encloses only") and "--radius %.3g" % p["density_radius"] in r["warning"]
    assert "enclosed      %.0f%% of the particles" % (100 * p["enclosed_fraction"]) in proc.stdout
    block = tmp_path / "block.xyz"
    write_block(block)
    proc = cli("polygonize", block, "-o", out, "--report", report)
    assert "warning" not in proc.stderr
    p = json.loads(report.read_text())["polygonize"]
    assert p["enclosed_fraction"] > 0.9 and math.isclose(p["density_radius"], p["radius"], rel_tol=0.1)


def test_a_radius_far_larger_than_the_packing_is_said(cli, inspect, tmp_path):
    """A radius of 10 spacings melts a block into one blob: said, with what the packing asks
    for; 2.5 spacings is not."""
    pts, out, report = tmp_path / "block.xyz", tmp_path / "m.ply", tmp_path / "r.json"
    write_block(pts, 8, 8, 8, jitter=0)
    proc = cli("polygonize", pts, "-o", out, "--report", report, "--radius", "1")
    assert "warning: the radius R = 1 is large for how densely the particles are packed" in proc.stderr
    # (8 spacings is as far as the packing is read; this block is smaller than its support)
    assert 0.25 <= float(proc.stderr.split("suggests --radius ")[1].split()[0].rstrip("):")) < 0.3
    r = json.loads(report.read_text())
    assert r["warning"].startswith("the radius R = 1 is large") and r["polygonize"]["enclosed_fraction"] == 1
    assert inspect(out)["components"] == 1
    proc = cli("polygonize", pts, "-o", out, "--report", report, "--radius", "0.25")
    assert "warning" not in proc.stderr and "warning" not in json.loads(report.read_text())


def test_a_surface_sampling_that_falls_into_blobs_is_said(cli, inspect, tmp_path):
    """One layer of particles (the samples of a sphere's surface) under the volume defaults:
    every particle inside, but the surface a blob around each few; said, with the command that
    meshes a surface sampling, in the summary's warning and the report. A block of volume
    particles, and the sphere's layer with a radius that joins it, are not."""
    layer, out, report = tmp_path / "layer.ply", tmp_path / "m.ply", tmp_path / "r.json"
    cli("sample", "fibonacci", "--points", "5000", "-o", layer, "-q")
    proc = cli("polygonize", layer, "-o", out, "--report", report)
    pieces = inspect(out)["components"]
    assert pieces * 10 > 5000
    assert "warning: the surface fell into %d pieces" % pieces in proc.stderr
    assert "`particlemesh triangulate` meshes such particles" in proc.stderr
    assert "fell into %d pieces" % pieces in json.loads(report.read_text())["warning"]
    proc = cli("polygonize", layer, "-o", out, "--radius", "0.15")
    assert "fell into" not in proc.stderr and inspect(out)["components"] <= 2
    block = tmp_path / "block.xyz"
    write_block(block)
    proc = cli("polygonize", block, "-o", out)
    assert "warning" not in proc.stderr


def test_an_sph_frame_in_motion_is_one_body_by_default(cli, inspect, tmp_path, data_dir):
    """SPH particles in motion sit closer than their rest spacing (a median nearest-neighbour
    distance of 0.036 where it is 0.05): at 2 x 0.036 the surface is mostly blobs, said, with
    about splashsurf's 4 x 0.025; the default radius is that and gives one body."""
    out, report = tmp_path / "m.ply", tmp_path / "r.json"
    frame = data_dir / "particles" / "dam_break_frame_9_6859_particles.bgeo"
    proc = cli("polygonize", frame, "-o", out, "-q", "--radius", "0.072")
    assert "warning: the surface encloses only" in proc.stderr and "their packing suggests --radius 0.09" in proc.stderr
    assert inspect(out)["components"] > 20
    proc = cli("polygonize", frame, "-o", out, "--report", report)
    assert "warning" not in proc.stderr
    p = json.loads(report.read_text())["polygonize"]
    assert p["enclosed_fraction"] > 0.9 and 0.09 < p["radius"] < 0.1
    mesh = inspect(out)
    assert mesh["components"] == 1 and mesh["closed"] and mesh["outward"]


def test_sigint_cancels_without_partial_output(cli, tmp_path):
    import os
    from test_triangulate import interrupt_while_computing
    exe = os.environ["PARTICLEMESH_CLI"]
    pts = tmp_path / "big.ply"
    cli("sample", "fibonacci", "--points", "2000000", "-o", pts)
    out = tmp_path / "big_out.ply"
    # Interrupted once the progress log shows the sampling (not after a fixed sleep, which on
    # a loaded machine may still be reading the input).
    r = interrupt_while_computing(
        exe, ["polygonize", pts, "-o", out, "--radius", "0.004", "--threshold", "0.5"], "sampling the field", tmp_path)
    assert r.prompt(cpu_limit=2.0), (r.seconds, r.cpu_seconds, r.err)
    assert r.rc == 130, r.err
    assert "error: cancelled (interrupted)" in r.err and "progress callback" not in r.err, r.err
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".big_out")]


def test_pcd_input_through_the_cli_reader(cli, inspect, data_dir, tmp_path):
    # The CLI's shared particle reader: .pcd through the PCL bridge when it is built.
    probe = cli("polygonize", "--help")
    if ".pcd" not in probe.stdout:
        pytest.skip("built without the PCL bridge")
    out = tmp_path / "bun.ply"
    report = tmp_path / "r.json"
    cli("polygonize", data_dir / "pcd/bunny.pcd", "-o", out, "--radius", "0.01", "--threshold", "0.5",
        "--report", report, "-q")
    r = json.loads(report.read_text())
    assert r["polygonize"]["particles"] == 397
    mesh = inspect(out)
    assert mesh["closed"] and mesh["manifold"] and mesh["consistently_oriented"]


def read_ply_mesh(path):
    """Vertices and triangles of a binary little-endian PLY written by particlemesh."""
    import struct
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = nf = 0
    props = []
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif w[0] == "property" and nf == 0 and w[1] != "list":
            props.append(w[1])
    size = {"float": 4, "double": 8}
    fmt = "<" + "".join("f" if p == "float" else "d" for p in props)
    stride = sum(size[p] for p in props)
    verts = [struct.unpack_from(fmt, data, end + i * stride)[:3] for i in range(nv)]
    off = end + nv * stride
    tris = []
    for _ in range(nf):
        n = data[off]
        tris.append(struct.unpack_from("<3i", data, off + 1))
        off += 1 + 4 * n
    return verts, tris


def volume(verts, tris):
    v = 0.0
    for a, b, c in tris:
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = verts[a], verts[b], verts[c]
        v += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6
    return v


def test_anisotropic_block_keeps_its_volume_and_is_flatter(cli, inspect, tmp_path):
    # A block of 16 x 10 x 16 particles, spacing 0.1, jittered by +-0.15 spacings.
    pts = tmp_path / "block.xyz"
    n = write_block(pts, 16, 10, 16, spacing=0.1, jitter=0.15, seed=3)
    iso, an = tmp_path / "iso.ply", tmp_path / "an.ply"
    report = tmp_path / "r.json"
    cli("polygonize", pts, "-o", iso, "-q")
    proc = cli("polygonize", pts, "-o", an, "--anisotropic", "--report", report)
    assert "anisotropic   %d of %d particles" % (n, n) in proc.stdout
    p = json.loads(report.read_text())["polygonize"]
    assert p["anisotropic"] and p["anisotropic_particles"] == n and p["threshold_defaulted"]
    mesh = inspect(an)
    assert mesh["closed"] and mesh["manifold"] and mesh["consistently_oriented"] and mesh["outward"]
    assert mesh["components"] == 1
    v_iso = volume(*read_ply_mesh(iso))
    v_an = volume(*read_ply_mesh(an))
    particles = n * 0.1 ** 3
    assert abs(v_an / particles - 1) < 0.05, v_an / particles
    assert abs(v_an / particles - 1) < abs(v_iso / particles - 1)

    # The top face (y up, particles at y <= 0.9), away from the edges: flatter normals.
    def tilt(path):
        verts, tris = read_ply_mesh(path)
        import struct
        data = path.read_bytes()
        end = data.index(b"end_header\n") + len(b"end_header\n")
        angles = []
        for i, (x, y, z) in enumerate(verts):
            if y > 0.85 and 0.4 < x < 1.1 and 0.4 < z < 1.1:
                ny = struct.unpack_from("<f", data, end + i * 24 + 16)[0]
                angles.append(math.degrees(math.acos(max(-1.0, min(1.0, ny)))))
        assert len(angles) > 100
        return math.sqrt(sum(a * a for a in angles) / len(angles))
    assert tilt(an) < 0.5 * tilt(iso)


def test_anisotropic_options_pieces_and_smoothing(cli, inspect, tmp_path):
    pts = tmp_path / "block.xyz"
    write_block(pts, 8, 8, 8, jitter=0.1)
    with pts.open("a") as f:  # a pair of particles far out: a small blob at a low threshold
        f.write("3 3 3\n3.05 3 3\n")
    a, b, c = tmp_path / "a.ply", tmp_path / "b.ply", tmp_path / "c.ply"
    report = tmp_path / "r.json"
    common = ["--anisotropic", "--aniso-radius", "1.5", "--aniso-max-stretch", "3", "--aniso-min-neighbors", "10",
              "--aniso-smoothing", "0.2", "--threshold", "0.8", "-q"]
    cli("polygonize", pts, "-o", a, *common, "--threads", "1")
    cli("polygonize", pts, "-o", b, *common, "--threads", "2", "--report", report)
    assert a.read_bytes() == b.read_bytes()
    p = json.loads(report.read_text())["polygonize"]
    assert p["anisotropic"] and p["threshold"] == 0.8
    assert inspect(a)["components"] == 2
    proc = cli("polygonize", pts, "-o", c, *common, "--min-component-particles", "20", "--taubin", "5",
               "--report", report)
    p = json.loads(report.read_text())["polygonize"]
    assert p["components_removed"] == 1 and p["smoothing_iterations"] == 5
    mesh = inspect(c)
    assert mesh["components"] == 1 and mesh["closed"] and mesh["manifold"]
    proc = cli("polygonize", pts, "-o", c, "--min-component-volume", "0.01", "--threshold", "0.8")
    assert "small pieces  1 dropped" in proc.stdout


def test_collapse_edges_takes_out_slivers_and_keeps_the_surface(cli, inspect, tmp_path):
    pts = tmp_path / "block.xyz"
    write_block(pts, 10, 8, 6, jitter=0.2)
    raw, a, b = tmp_path / "raw.ply", tmp_path / "a.ply", tmp_path / "b.ply"
    report = tmp_path / "r.json"
    cli("polygonize", pts, "-o", raw, "-q")
    proc = cli("polygonize", pts, "-o", a, "--collapse-edges", "0.3", "--threads", "1", "--report", report)
    n = json.loads(report.read_text())["polygonize"]["edges_collapsed"]
    assert n > 0 and f"slivers       {n} edges shorter than 0.3 h collapsed" in proc.stdout
    cli("polygonize", pts, "-o", b, "--collapse-edges", "0.3", "--threads", "2", "-q")
    assert a.read_bytes() == b.read_bytes()
    m0, m1 = inspect(raw), inspect(a)
    assert m1["closed"] and m1["manifold"] and m1["outward"]
    assert m1["triangles"] == m0["triangles"] - 2 * n
    assert (m1["components"], m1["euler_characteristic"]) == (m0["components"], m0["euler_characteristic"])


@pytest.mark.parametrize("args, needle", [
    (["--collapse-edges", "0.6"], "collapse-edges"),
    (["--collapse-edges", "-0.1"], "collapse-edges"),
    (["--anisotropic", "--aniso-max-stretch", "0.5"], "aniso-max-stretch"),
    (["--anisotropic", "--aniso-smoothing", "2"], "aniso-smoothing"),
    (["--anisotropic", "--aniso-radius", "nan"], "aniso-radius"),
    (["--taubin-mu", "0.3"], "taubin-mu"),
    (["--min-component-volume", "-1"], "min-component-volume"),
])
def test_anisotropic_usage_errors(cli, tmp_path, args, needle):
    pts = tmp_path / "block.xyz"
    write_block(pts, 3, 3, 3)
    proc = cli("polygonize", pts, "-o", tmp_path / "x.ply", *args, check=False)
    assert proc.returncode == 2, proc.stderr
    assert needle in proc.stderr
    assert not (tmp_path / "x.ply").exists()


def test_taubin_mu_must_exceed_lambda(cli, tmp_path):
    pts = tmp_path / "block.xyz"
    write_block(pts, 4, 4, 4)
    out = tmp_path / "x.ply"
    proc = cli("polygonize", pts, "-o", out, "--taubin", "3", "--taubin-lambda", "0.6", "--taubin-mu", "-0.5",
               check=False)
    assert proc.returncode == 1 and "taubin mu" in proc.stderr and proc.stderr.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("name", ["double_dam_break_frame_26_4732_particles.ply",
                                  "bunny_frame_14_7705_particles.ply", "cube_2366_particles.ply"])
def test_sph_frames_anisotropic(cli, inspect, data_dir, tmp_path, name):
    out = tmp_path / "frame.ply"
    cli("polygonize", data_dir / "particles" / name, "-o", out, "--anisotropic", "-q")
    mesh = inspect(out)
    # (The splashy dam break has a few small closed cavities inside its sheets: not "outward".)
    assert mesh["closed"] and mesh["manifold"] and mesh["consistently_oriented"]
    assert mesh["triangles"] > 1000


@pytest.mark.parametrize("command", ["polygonize", "triangulate"])
def test_report_and_summary_describe_the_written_mesh(cli, inspect, tmp_path, command):
    # The topology report is taken while the mesh is written (and not at all with -q alone):
    # the report and the summary must still describe exactly the mesh in the file.
    pts = tmp_path / "sphere.ply"
    cli("sample", "fibonacci", "--points", "4000", "-o", pts)
    out, rep = tmp_path / "out.ply", tmp_path / "r.json"
    cli(command, pts, "-o", out, "--report", rep, "-q")
    mesh = inspect(out)
    topo = json.loads(rep.read_text())["topology"]
    assert topo["triangles"] == mesh["triangles"] > 1000
    assert topo["vertices"] == mesh["vertices"] and topo["closed"] == mesh["closed"] is True
    proc = cli(command, pts, "-o", out)
    assert f"triangles     {mesh['triangles']}\n" in proc.stdout


def test_a_stray_particle_far_away_is_cropped_off(cli, inspect, tmp_path):
    """A particle a simulation flung far away makes the grid too large: the error (and inspect)
    names it and says --crop; with --crop the rest meshes exactly as without the stray (the same bytes),
    and the summary and the report count what was dropped. render takes --crop too; a box
    inside out or holding no particle is an error naming --crop."""
    block = tmp_path / "block.xyz"
    n = write_block(block)
    stray = tmp_path / "stray.xyz"
    stray.write_text(block.read_text() + "1e6 0.3 0.3\n")
    proc = cli("polygonize", stray, "-o", tmp_path / "x.ply", check=False)
    assert proc.returncode == 1 and not (tmp_path / "x.ply").exists(), proc.stderr
    assert f"point {n} (x = 1e+06)" in proc.stderr and "--crop MINX MINY MINZ MAXX MAXY MAXZ" in proc.stderr
    inspected = cli("inspect", stray).stdout  # inspect names the stray and the way on too
    assert "sampling      cannot be measured" in inspected and "--crop MINX" in inspected, inspected
    cli("polygonize", block, "-o", tmp_path / "block.ply", "-q")
    report = tmp_path / "r.json"
    proc = cli("polygonize", stray, "-o", tmp_path / "cropped.ply", "--crop", "-1,-1,-1,2,2,2", "--report", report)
    assert f"crop          {n} of {n + 1} particles inside the box (1 outside, dropped)" in proc.stdout
    assert (tmp_path / "cropped.ply").read_bytes() == (tmp_path / "block.ply").read_bytes()
    crop = json.loads(report.read_text())["read"]["crop"]
    assert crop == {"min": [-1, -1, -1], "max": [2, 2, 2], "kept": n, "dropped": 1}
    assert inspect(tmp_path / "cropped.ply")["closed"]
    cli("render", stray, "-o", tmp_path / "r.png", "--crop", "-1", "-1", "-1", "2", "2", "2", "-q")
    assert (tmp_path / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for box, message in [("2,-1,-1,1,2,2", "--crop: the box's minimum x (2) is above its maximum (1)"),
                         ("5,5,5,6,6,6", f"--crop: none of the {n + 1} particles lies inside the box")]:
        proc = cli("polygonize", stray, "-o", tmp_path / "y.ply", "--crop", box, check=False)
        assert proc.returncode == 1 and message in proc.stderr and not (tmp_path / "y.ply").exists(), proc.stderr
    proc = cli("polygonize", stray, "-o", tmp_path / "y.ply", "--crop", "0,0,nan,1,1,1", check=False)
    assert proc.returncode == 2 and "not a finite number" in proc.stderr
