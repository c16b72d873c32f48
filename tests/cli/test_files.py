"""Files through the CLI: every output checked before any work and put in place together,
written safely (devices, FIFOs, links and standard output written through; modes kept; no
temporary left by any signal or limit); every input read once, exactly, and refused by name
when malformed; values at the edges of double precision; prompt cancellation; readable
messages. docs/hostile_inputs.md lists every case with its test."""
import json
import os
import resource
import signal
import stat
import struct
import subprocess
import threading
import time

import pytest

EXE = os.environ.get("PARTICLEMESH_CLI", "")


def temporaries(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


@pytest.fixture(scope="module")
def sphere(tmp_path_factory, cli):
    d = tmp_path_factory.mktemp("sphere")
    pts = d / "sphere.xyz"
    cli("sample", "sphere", "--spacing", "0.08", "-o", pts)
    return pts


def has_pcl(cli):
    return "--pcl-mesh" in cli("triangulate", "--help").stdout


# ---- outputs: checked before any work -------------------------------------------------------

def test_outputs_are_checked_before_reading(cli, tmp_path, sphere):
    """A side output that cannot be written used to be found after the work (exit 1, the mesh
    left behind). Now every output is checked first: a usage error (exit 2) before the input
    is even read (here the input is not a readable file at all, which would be exit 1)."""
    bad_input = tmp_path / "garbage.ply"
    bad_input.write_text("not a ply file\n")
    out = tmp_path / "o.ply"
    (tmp_path / "folder").mkdir()
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    ro = tmp_path / "ro.json"
    ro.write_text("{}")
    ro.chmod(0o444)
    cases = {
        "missing folder": tmp_path / "no" / "r.json",
        "a folder": tmp_path / "folder",
        "read-only folder": locked / "r.json",
        "read-only file": ro,
    }
    for what, report in cases.items():
        for inp in (bad_input, sphere):
            proc = cli("triangulate", inp, "-o", out, "--report", report, check=False)
            assert proc.returncode == 2, (what, proc.stderr)
            assert "--report" in proc.stderr, proc.stderr
            assert not out.exists(), what
    for cmd in (["polygonize", sphere, "-o", tmp_path / "p.txt"], ["smooth", sphere, "-o", tmp_path / "s.stl"],
                ["render", sphere, "-o", tmp_path / "r.jpg"], ["sample", "sphere", "-o", tmp_path / "s.csv"]):
        proc = cli(*cmd, check=False)
        assert proc.returncode == 2, proc.stderr
    assert ro.read_text() == "{}"
    assert temporaries(tmp_path) == []


def test_colliding_paths_are_refused(cli, tmp_path, sphere):
    """--report equal to the input overwrote the input, --report or --pcl-mesh equal to -o
    overwrote the mesh, both with exit 0. Now a usage error, whatever the spelling."""
    inp = tmp_path / "in.xyz"
    inp.write_bytes(sphere.read_bytes())
    before = inp.read_bytes()
    (tmp_path / "sub").mkdir()
    os.symlink(inp, tmp_path / "alias.json")
    out = tmp_path / "o.ply"
    for args in (["--report", inp], ["--report", tmp_path / "sub" / ".." / "in.xyz"], ["--report", tmp_path / "alias.json"],
                 ["--report", out], ["--report", tmp_path / "sub" / ".." / "o.ply"]):
        proc = cli("triangulate", inp, "-o", out, *args, check=False)
        assert proc.returncode == 2, (args, proc.stderr)
        assert not out.exists()
    proc = cli("triangulate", inp, "-o", inp.with_suffix(".ply"), "--report", inp.with_suffix(".ply"), check=False)
    assert proc.returncode == 2 and "both name" in proc.stderr
    if has_pcl(cli):
        proc = cli("triangulate", inp, "-o", out, "--pcl-mesh", out, check=False)
        assert proc.returncode == 2 and "-o and --pcl-mesh both name" in proc.stderr
    mesh = tmp_path / "m.ply"
    cli("triangulate", inp, "-o", mesh)
    mesh_bytes = mesh.read_bytes()
    proc = cli("smooth", mesh, "-o", mesh, check=False)
    assert proc.returncode == 2 and "is the input file" in proc.stderr
    assert mesh.read_bytes() == mesh_bytes
    assert inp.read_bytes() == before
    # /dev/null twice is fine: a sink.
    cli("triangulate", inp, "-o", "/dev/null", "--report", "/dev/null")


def test_outputs_appear_together_or_not_at_all(cli, tmp_path, sphere):
    """When the second output fails (here: a file size limit that the mesh fits under and
    PCL's larger mesh does not), the first is not left either."""
    if not has_pcl(cli):
        pytest.skip("built without the PCL bridge: no second mesh output to fail")
    out, pcl = tmp_path / "o.ply", tmp_path / "pcl.ply"
    cli("triangulate", sphere, "-o", out, "--pcl-mesh", pcl)
    small, large = out.stat().st_size, pcl.stat().st_size
    assert large > small, "PCL's PLY is expected larger (it carries more fields)"
    out.unlink()
    pcl.unlink()
    limit = (small + large) // 2

    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    proc = subprocess.run([EXE, "triangulate", str(sphere), "-o", str(out), "--pcl-mesh", str(pcl)],
                          capture_output=True, text=True, preexec_fn=preexec, timeout=120)
    assert proc.returncode == 1, proc.stderr
    assert "pcl.ply" in proc.stderr
    assert not out.exists() and not pcl.exists()
    assert temporaries(tmp_path) == []


# ---- outputs: written safely -----------------------------------------------------------------

def test_devices_fifos_links_and_stdout_are_written_through(cli, tmp_path, sphere):
    """Run as root, render -o /dev/null replaced the machine's /dev/null with a file, -o
    /dev/stdout replaced the link and printed nothing; FIFOs and links were replaced too."""
    if os.geteuid() == 0:
        null = tmp_path / "null"
        os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        cli("render", sphere, "-o", null, "--width", "16", "--height", "12")
        cli("triangulate", sphere, "-o", null, "--report", null)
        assert stat.S_ISCHR(null.lstat().st_mode)
    else:
        print("not root: the device case (mknod) is not run; the FIFO below covers the same code")
    fifo = tmp_path / "report.fifo"
    os.mkfifo(fifo)
    got = {}
    reader = threading.Thread(target=lambda: got.setdefault("report", fifo.read_text()))
    reader.start()
    cli("triangulate", sphere, "-o", tmp_path / "o.ply", "--report", fifo)
    reader.join(30)
    assert json.loads(got["report"])["topology"]["closed"] is True
    assert stat.S_ISFIFO(fifo.lstat().st_mode)
    # Standard output: the file's bytes alone on stdout, the summary on stderr.
    proc = subprocess.run([EXE, "triangulate", str(sphere), "-o", "/dev/stdout"], capture_output=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(b"ply\nformat binary_little_endian 1.0\n")
    assert b"particlemesh triangulate" in proc.stderr
    proc = subprocess.run([EXE, "sample", "sphere", "-o", "-", "-q"], capture_output=True, timeout=120)
    assert proc.returncode == 0 and len(proc.stdout.splitlines()) > 1000
    # A link is kept; its target is written.
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / "mesh.ply"
    os.symlink(target, tmp_path / "link.ply")
    cli("triangulate", sphere, "-o", tmp_path / "link.ply")
    assert (tmp_path / "link.ply").is_symlink() and target.read_bytes().startswith(b"ply\n")
    assert temporaries(tmp_path) == [] and temporaries(tmp_path / "data") == []


def test_replaced_file_keeps_its_mode_and_long_names_work(cli, tmp_path, sphere):
    out = tmp_path / "o.ply"
    out.write_text("old")
    out.chmod(0o600)
    cli("triangulate", sphere, "-o", out)
    assert stat.S_IMODE(out.stat().st_mode) == 0o600
    assert out.read_bytes().startswith(b"ply\n")
    long_name = tmp_path / ("n" * 246 + ".ply")  # 250 bytes: a legal name
    cli("triangulate", sphere, "-o", long_name)
    assert long_name.exists()


def mesh_temporary_then_block(tmp_path, sphere, fifo):
    """Start a run whose mesh is written into its temporary and which then blocks opening a
    FIFO for --report (nobody reads it): the moment a signal must clean up after."""
    out = tmp_path / "o.ply"
    proc = subprocess.Popen([EXE, "triangulate", str(sphere), "-o", str(out), "--report", str(fifo)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not [p for p in tmp_path.iterdir() if p.name.startswith(".pm")]:
        time.sleep(0.02)
    return proc, out


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGQUIT, signal.SIGPIPE, signal.SIGTERM, signal.SIGINT])
def test_signals_leave_no_temporary(tmp_path, sphere, sig):
    """SIGHUP, SIGQUIT and SIGPIPE left a hidden temporary of the mesh; SIGTERM and SIGINT
    while writing left the temporary too."""
    fifo = tmp_path / "r.fifo"
    os.mkfifo(fifo)
    proc, out = mesh_temporary_then_block(tmp_path, sphere, fifo)
    try:
        assert [p for p in tmp_path.iterdir() if p.name.startswith(".pm")], "no temporary seen: nothing to test"
        proc.send_signal(sig)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    if sig in (signal.SIGTERM, signal.SIGINT):
        assert proc.returncode == 130
    else:
        assert proc.returncode == -sig  # ended by the signal, as the shell expects
    assert not out.exists()
    assert temporaries(tmp_path) == []


def test_file_size_limit_is_a_clear_error(tmp_path, sphere):
    """A file size limit (ulimit -f) killed the process with SIGXFSZ and left a temporary."""
    out = tmp_path / "o.ply"

    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))

    proc = subprocess.run([EXE, "triangulate", str(sphere), "-o", str(out), "--ascii"], capture_output=True, text=True,
                          preexec_fn=preexec, timeout=120)
    assert proc.returncode == 1, proc
    assert "File too large" in proc.stderr and "o.ply" in proc.stderr
    assert not out.exists() and temporaries(tmp_path) == []


def test_write_errors_on_stdout_fail_the_run(cli, tmp_path, sphere):
    mesh = tmp_path / "m.ply"
    cli("triangulate", sphere, "-o", mesh)
    with open("/dev/full", "w") as full:
        proc = subprocess.run([EXE, "inspect", str(mesh)], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert proc.returncode == 1
    assert "cannot write to standard output" in proc.stderr


# ---- inputs: read once, exactly, refused by name ------------------------------------------------

def ply_header(fmt, props, n, faces=0, face_first=False):
    v = f"element vertex {n}\n" + "".join(f"property {p}\n" for p in props)
    f = f"element face {faces}\nproperty list uchar int vertex_indices\n" if faces else ""
    return f"ply\nformat {fmt} 1.0\n" + (f + v if face_first else v + f) + "end_header\n"


def test_hostile_ply_and_obj_files(cli, tmp_path, inspect):
    tri = "0 0 0\n1 0 0\n0 1 0\n"
    # No z: refused by name (was z = 0, exit 0).
    noz = tmp_path / "noz.ply"
    noz.write_text(ply_header("ascii", ["float x", "float y"], 3) + "0 0\n1 0\n0 1\n")
    proc = cli("triangulate", noz, "-o", tmp_path / "o.ply", check=False)
    assert proc.returncode == 1 and "noz.ply" in proc.stderr and "no 'z' property" in proc.stderr
    # Upper-case X Y Z: read (was "all points coincide", the file not named).
    up = tmp_path / "up.ply"
    up.write_text(ply_header("ascii", ["float X", "float Y", "float Z"], 3, 1) + tri + "3 0 1 2\n")
    assert inspect(up)["triangles"] == 1
    # A list inside the vertex element (was: coordinates shifted, exit 0).
    lst = tmp_path / "list.ply"
    lst.write_text(ply_header("ascii", ["float x", "list uchar int ids", "float y", "float z"], 3, 1) +
                   "0 2 5 6 0 0\n1 0 0 0\n0 1 9 1 0\n3 0 1 2\n")
    r = inspect(lst)
    assert r["triangles"] == 1 and r["degenerate_triangles"] == 0
    # Faces before vertices (was "a face refers to a vertex that does not exist").
    first = tmp_path / "first.ply"
    first.write_text(ply_header("ascii", ["float x", "float y", "float z"], 3, 1, face_first=True) + "3 0 1 2\n" + tri)
    assert inspect(first)["triangles"] == 1
    # More data than the header counts (was ignored silently).
    more = tmp_path / "more.ply"
    more.write_text(ply_header("ascii", ["float x", "float y", "float z"], 3, 1) + tri + "3 0 1 2\n3 0 2 1\n")
    proc = cli("inspect", more, check=False)
    assert proc.returncode == 1 and "more.ply" in proc.stderr and "a count in the header is too small" in proc.stderr
    # Double coordinates of 4e38 and more (every face was dropped; inspect said 0 triangles).
    big = tmp_path / "big.ply"
    big.write_bytes(ply_header("binary_little_endian", ["double x", "double y", "double z"], 3, 1).encode() +
                    struct.pack("<9d", 4e38, 0, 0, 5e38, 0, 0, 4e38, 1e38, 0) + struct.pack("<B3i", 3, 0, 1, 2))
    assert inspect(big)["triangles"] == 1
    # OBJ: NaN and beyond double, named with the line (was "a face refers to a vertex ...").
    for text, expected in (("v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n", "line 2: vertex x is NaN"),
                           ("v 0 0 0\nv 1e400 1 0\nv 0 1 0\nf 1 2 3\n", "line 2: vertex x '1e400' is beyond the range")):
        obj = tmp_path / "v.obj"
        obj.write_text(text)
        proc = cli("inspect", obj, check=False)
        assert proc.returncode == 1 and expected in proc.stderr, proc.stderr
    obj.write_text("v 0 0 0\nv 1e39 1 0\nv 0 1e39 0\nf 1 2 3\n")
    assert inspect(obj)["triangles"] == 1


def test_hostile_xyz_files(cli, tmp_path, sphere):
    bom = tmp_path / "bom.xyz"
    bom.write_bytes(b"\xef\xbb\xbf" + sphere.read_bytes())
    cli("triangulate", bom, "-o", tmp_path / "o.ply")  # was "not a number"
    # /dev/zero behind an .xyz name grew to ~10 GB before "read error"; the address space is
    # capped here so that the old behaviour fails the test instead of the machine.
    zero = tmp_path / "zero.xyz"
    os.symlink("/dev/zero", zero)

    def preexec():
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

    start = time.monotonic()
    proc = subprocess.run([EXE, "triangulate", str(zero), "-o", str(tmp_path / "z.ply")], capture_output=True, text=True,
                          preexec_fn=preexec, timeout=60)
    assert proc.returncode == 1 and "line 1 is longer than 65536 bytes" in proc.stderr, proc.stderr
    assert time.monotonic() - start < 10


# ---- values ------------------------------------------------------------------------------------

def test_normals_without_a_direction(cli, tmp_path, sphere, inspect):
    """All-zero normals were used as normals: the sphere came out in open pieces; with
    --normals input, 0 triangles, exit 0 and a wrong hint."""
    zero = tmp_path / "zero.xyz"
    zero.write_text("".join(" ".join(l.split()[:3]) + " 0 0 0\n" for l in sphere.read_text().splitlines()))
    cli("triangulate", zero, "-o", tmp_path / "z.ply")
    r = inspect(tmp_path / "z.ply")
    assert r["components"] == 1 and r["closed"] and r["outward"]
    proc = cli("triangulate", zero, "-o", tmp_path / "zi.ply", "--normals", "input", check=False)
    assert proc.returncode == 1 and "normals[0] has no direction" in proc.stderr
    assert not (tmp_path / "zi.ply").exists()


def scaled_copy(src, dst, s):
    dst.write_text("".join(" ".join(repr(float(v) * s) for v in l.split()[:3]) + "\n" for l in src.read_text().splitlines()))


def test_coordinates_at_the_edges_of_double(cli, tmp_path, sphere, inspect):
    """1e39 was written as inf into float32 files (exit 0); 1e-44 gave degenerate triangles;
    1e-300 said "all points coincide"."""
    for s in (1e39, 1e-44):
        pts, out = tmp_path / "s.xyz", tmp_path / "s.ply"
        scaled_copy(sphere, pts, s)
        cli("triangulate", pts, "-o", out)
        assert b"property double x" in out.read_bytes()[:300]
        r = inspect(out)
        assert r["closed"] and r["degenerate_triangles"] == 0, s
    pts = tmp_path / "tiny.xyz"
    scaled_copy(sphere, pts, 1e-300)
    for cmd in ("triangulate", "polygonize"):
        proc = cli(cmd, pts, "-o", tmp_path / "t.ply", check=False)
        assert proc.returncode == 1 and "below the 1e-50" in proc.stderr and "coincide" not in proc.stderr, proc.stderr


def test_polygonize_budget_and_empty_surfaces(cli, tmp_path, sphere):
    for bad in ("nan", "1e-9", "-1", "inf"):
        proc = cli("polygonize", sphere, "-o", tmp_path / "p.ply", "--max-grid-mib", bad, check=False)
        assert proc.returncode == 2, (bad, proc.stderr)
    # A threshold above the whole field: the empty mesh is written, with a warning (was: no word).
    report = tmp_path / "p.json"
    proc = cli("polygonize", sphere, "-o", tmp_path / "p.ply", "--threshold", "1000", "--report", report)
    assert "warning: no surface" in proc.stderr
    assert "lower --threshold" in json.loads(report.read_text())["warning"]
    proc = cli("render", sphere, "-o", tmp_path / "p.png", "--threshold", "1000", "--width", "16", "--height", "12")
    assert "warning: the surface appears in no pixel" in proc.stderr


def test_sigterm_with_the_limits_lifted(cli, tmp_path):
    """--max-edge-factor 100 --max-neighbors 100000 --max-triplets-per-point 0 on 2000 points:
    SIGTERM took 441 s (the cancel flag was checked between points only)."""
    pts = tmp_path / "f.xyz"
    cli("sample", "fibonacci", "--points", "2000", "-o", pts)
    proc = subprocess.Popen([EXE, "triangulate", str(pts), "-o", str(tmp_path / "o.ply"), "--max-edge-factor", "100",
                             "--max-neighbors", "100000", "--max-triplets-per-point", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = threading.Event()

    def watch():
        for line in proc.stderr:
            if "testing triangles" in line:
                seen.set()

    threading.Thread(target=watch, daemon=True).start()
    try:
        # The progress log names the stage after a second; a run that never reports (as before,
        # within one block of points) is signalled after 20 s anyway.
        seen.wait(20)
        start = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            pass
        assert time.monotonic() - start < 2.0, "no reaction to SIGTERM"
        assert proc.returncode == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert temporaries(tmp_path) == [] and not (tmp_path / "o.ply").exists()


# ---- messages and options ------------------------------------------------------------------

def test_messages_show_numbers_readably(cli, tmp_path, sphere):
    far = tmp_path / "far.xyz"
    far.write_text(sphere.read_text() + "1e300 -1e300 0 0 0 1\n")
    proc = cli("triangulate", far, "-o", tmp_path / "o.ply", "--spacing", "1e-7", check=False)
    assert proc.returncode == 1
    assert len(proc.stderr) < 400 and "0.000000" not in proc.stderr and "e+3" in proc.stderr, proc.stderr
    for cmd in (["polygonize", far, "-o", tmp_path / "p.ply"], ["render", far, "-o", tmp_path / "p.png"]):
        proc = cli(*cmd, "--radius", "0.1", check=False)
        assert proc.returncode == 1 and "spacing" not in proc.stderr and len(proc.stderr) < 400, proc.stderr


def test_sample_seed_must_be_a_seed(cli, tmp_path):
    """-1, 2^64 and 1e23 silently gave the same cloud."""
    for bad in ("-1", "18446744073709551616", "1e23", "1.5", ""):
        proc = cli("sample", "sphere", "-o", tmp_path / "s.xyz", "--seed", bad, check=False)
        assert proc.returncode == 2, (bad, proc.stderr)
    cli("sample", "sphere", "-o", tmp_path / "a.xyz", "--seed", "18446744073709551615")
    cli("sample", "sphere", "-o", tmp_path / "b.xyz", "--seed", "2")
    assert (tmp_path / "a.xyz").read_bytes() != (tmp_path / "b.xyz").read_bytes()


def test_smooth_keeps_vertex_colours(cli, tmp_path):
    """The CLI's smooth dropped vertex colours, though attributes are carried."""
    verts = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    faces = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    mesh = tmp_path / "oct.ply"
    mesh.write_text("ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 8\n"
                    "property list uchar int vertex_indices\nend_header\n" +
                    "".join(f"{x} {y} {z} {200 if i == 0 else 10} 30 {40 + i}\n" for i, (x, y, z) in enumerate(verts)) +
                    "".join(f"3 {a} {b} {c}\n" for a, b, c in faces))
    out = tmp_path / "s.ply"
    cli("smooth", mesh, "-o", out, "--ascii", "--scheme", "butterfly")
    lines = out.read_text().splitlines()
    assert "property uchar red" in lines
    body = lines[lines.index("end_header") + 1:]
    # Butterfly keeps the control vertices: the first keeps its colour exactly.
    assert body[0].split()[-3:] == ["200", "30", "40"]


def test_channels_an_obj_cannot_hold_are_said(cli, tmp_path):
    """An OBJ output holds a colour per vertex and texture coordinates and no other
    channel: the summary's "not written" line and the report's not_written name the
    channels left out (triangulate, polygonize, smooth); a PLY output, --attributes none,
    and a colour alone name nothing."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from particle_files import particles, write_ply
    p, attrs = particles(n=6)
    src = tmp_path / "p.ply"
    write_ply(src, p, attrs)
    line = "  not written   velocity, density (OBJ holds a colour per vertex and texture coordinates only"
    for command in ("triangulate", "polygonize"):
        out = cli(command, src, "-o", tmp_path / "m.obj", "--report", tmp_path / "m.json").stdout
        assert line in out, command
        assert json.loads((tmp_path / "m.json").read_text())["not_written"] == ["velocity", "density"], command
        out = cli(command, src, "-o", tmp_path / "m.ply", "--report", tmp_path / "m.json").stdout
        assert "not written" not in out and "not_written" not in json.loads((tmp_path / "m.json").read_text())
        assert "not written" not in cli(command, src, "-o", tmp_path / "n.obj", "--attributes", "none").stdout
    cli("triangulate", src, "-o", tmp_path / "m.ply", "-q")
    out = cli("smooth", tmp_path / "m.ply", "-o", tmp_path / "s.obj").stdout
    assert line in out
    coloured = tmp_path / "c.ply"  # a colour alone: OBJ's v x y z r g b holds it
    coloured.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
                        "property list uchar int vertex_indices\nend_header\n0 0 0 1 2 3\n1 0 0 4 5 6\n0 1 0 7 8 9\n3 0 1 2\n")
    assert "not written" not in cli("smooth", coloured, "-o", tmp_path / "c.obj").stdout
    if has_pcl(cli):  # PCL's PLY writer holds rgb and intensity: said for --pcl-mesh too
        out = cli("triangulate", src, "-o", tmp_path / "m.ply", "--pcl-mesh", tmp_path / "pcl.ply",
                  "--report", tmp_path / "m.json")
        assert "  not written   --pcl-mesh: velocity, density (PCL's PLY writer" in out.stdout
        assert "unknown field" not in out.stderr
        report = json.loads((tmp_path / "m.json").read_text())
        assert report["pcl_mesh_not_written"] == ["velocity", "density"] and "not_written" not in report


def test_a_meshs_vertices_are_particles_in_every_mesh_format(cli, tmp_path, sphere):
    """triangulate re-meshes a model from its vertices whatever file holds it: an OFF (no
    faces, or faces that are ignored) gives the mesh of the same points as text, byte for
    byte; a binary STL's corners, shared, are the particles once each."""
    lines = [ln.split() for ln in sphere.read_text().splitlines() if ln.strip()]
    off = tmp_path / "v.off"
    off.write_text(f"OFF\n{len(lines)} 1 0\n" + "".join(" ".join(ln) + "\n" for ln in lines) + "3 0 1 2\n")
    cli("triangulate", sphere, "-o", tmp_path / "from_xyz.ply", "-q")
    cli("triangulate", off, "-o", tmp_path / "from_off.ply", "-q")
    assert (tmp_path / "from_off.ply").read_bytes() == (tmp_path / "from_xyz.ply").read_bytes()
    # The mesh as a binary STL (float32 corners, each triangle's own), then its vertices again.
    r = cli("triangulate", sphere, "-o", tmp_path / "m.obj", "-q")
    obj = (tmp_path / "m.obj").read_text().splitlines()
    v = [tuple(map(float, ln.split()[1:4])) for ln in obj if ln.startswith("v ")]
    f = [tuple(int(x.split("/")[0]) - 1 for x in ln.split()[1:4]) for ln in obj if ln.startswith("f ")]
    stl = tmp_path / "m.stl"
    with open(stl, "wb") as out:
        out.write(b"\0" * 80 + struct.pack("<I", len(f)))
        for t in f:
            out.write(struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v[i]) for i in t) + b"\0\0")
    r = cli("inspect", stl, "--json")
    assert json.loads(r.stdout)["vertices"] == len(v)
    cli("triangulate", stl, "-o", tmp_path / "from_stl.ply", "--report", tmp_path / "r.json", "-q")
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["triangulation"]["points"] == len(v)
    assert report["topology"]["closed"] and report["topology"]["components"] == 1
