"""particlemesh smooth, and triangulate --smooth, end to end through the binary."""
import json
import math
import os


def _octahedron(path):
    v = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    path.write_text("".join("v %g %g %g\n" % p for p in v) + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f))
    return v, f


def _torus(path, nu=24, nv=12, R=1.0, r=0.4):
    verts, faces = [], []
    for i in range(nu):
        for j in range(nv):
            u, w = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            verts.append(((R + r * math.cos(w)) * math.cos(u), (R + r * math.cos(w)) * math.sin(u), r * math.sin(w)))
    idx = lambda i, j: (i % nu) * nv + (j % nv)
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            faces += [(a, b, c), (a, c, d)]
    path.write_text("".join("v %r %r %r\n" % p for p in verts) + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in faces))
    return verts, faces


def _read_ascii_ply_vertices(path):
    lines = path.read_text().splitlines()
    n = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
    start = lines.index("end_header") + 1
    return [tuple(map(float, l.split()[:3])) for l in lines[start:start + n]]


def _fails(cli, tmp_path, args, needle, code=1):
    out = tmp_path / "out.ply"
    proc = cli(*args, "-o", out, check=False)
    assert proc.returncode == code, (proc.returncode, proc.stderr)
    lines = [l for l in proc.stderr.splitlines() if l.strip()]
    if code == 1:
        assert len(lines) == 1, proc.stderr  # one line naming the problem
    assert needle in proc.stderr, proc.stderr
    assert not out.exists()
    return proc.stderr


def test_loop_counts_topology_and_report(cli, inspect, tmp_path):
    src = tmp_path / "torus.obj"
    verts, faces = _torus(src)
    out = tmp_path / "torus_s.ply"
    rep = tmp_path / "r.json"
    proc = cli("smooth", src, "-o", out, "--scheme", "loop", "--levels", "2", "--report", rep)
    assert "limit positions and normals" in proc.stdout
    r = inspect(out)
    f, e, v = len(faces), len(faces) * 3 // 2, len(verts)
    for _ in range(2):
        v, e, f = v + e, 2 * e + 3 * f, 4 * f
    assert (r["triangles"], r["vertices"], r["edges"]) == (f, v, e)
    assert r["euler_characteristic"] == 0 and r["closed"] and r["manifold"]
    assert r["consistently_oriented"] and r["outward"]
    s = json.loads(rep.read_text())["smooth"]
    assert s["levels"] == 2 and s["limit"] is True and s["control_edges"] == len(faces) * 3 // 2
    assert s["triangles"] == f


def test_the_summary_and_report_follow_the_written_mesh(cli, inspect, tmp_path):
    # The topology report is taken while the mesh is written: the summary and --report give
    # the written mesh's counts (and the same with -q), and a failed write leaves no report.
    src = tmp_path / "torus.obj"
    _torus(src)
    out, rep, rep_q = tmp_path / "s.ply", tmp_path / "r.json", tmp_path / "rq.json"
    proc = cli("smooth", src, "-o", out, "--levels", "1", "--report", rep)
    r = inspect(out)
    assert f"triangles     {r['triangles']}" in proc.stdout and "euler char.   0" in proc.stdout
    cli("smooth", src, "-o", tmp_path / "q.ply", "--levels", "1", "--report", rep_q, "-q")
    for path in (rep, rep_q):
        t = json.loads(path.read_text())["topology"]
        assert (t["triangles"], t["edges"], t["closed"], t["outward"]) == (r["triangles"], r["edges"], True, True)
    if os.path.exists("/dev/full"):
        gone = tmp_path / "gone.json"
        proc = cli("smooth", src, "-o", "/dev/full", "--levels", "1", "--report", gone, check=False)
        assert proc.returncode == 1 and "/dev/full" in proc.stderr and not gone.exists()


def _write_obj(path, verts, faces):
    path.write_text("".join("v %r %r %r\n" % tuple(p) for p in verts) +
                    "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in faces))


def test_the_loop_report_is_the_written_mesh_report(cli, inspect, tmp_path):
    # For one clean closed piece, smooth derives the report of its Loop result from the
    # control mesh's; elsewhere (two pieces, a hole) it measures the output. Either way it is
    # what inspect measures on the written mesh (the signed volume to float32's precision:
    # the PLY stores float32 positions).
    octa = tmp_path / "octa.obj"
    v, f = _octahedron(octa)
    torus = tmp_path / "torus.obj"
    _torus(torus)
    inward = tmp_path / "inward.obj"
    _write_obj(inward, v, [(a, c, b) for a, b, c in f])
    two = tmp_path / "two.obj"
    _write_obj(two, v + [(x + 3, y, z) for x, y, z in v], f + [(a + 6, b + 6, c + 6) for a, b, c in f])
    hole = tmp_path / "hole.obj"
    _write_obj(hole, v, f[:-1])
    for src in (octa, torus, inward, two, hole):
        out, rep = tmp_path / (src.stem + "_s.ply"), tmp_path / (src.stem + ".json")
        cli("smooth", src, "-o", out, "--levels", "2", "--report", rep)
        got, want = json.loads(rep.read_text())["topology"], inspect(out)
        for c in got["per_component"] + want["per_component"]:
            c["signed_volume"] = round(c["signed_volume"], 5)
        assert got == want, src.stem
    assert len(want["per_component"]) == 1 and want["boundary_loops"] == 1  # the hole


def test_butterfly_keeps_the_original_vertices(cli, tmp_path):
    src = tmp_path / "oct.obj"
    verts, faces = _octahedron(src)
    out = tmp_path / "oct_b.ply"
    cli("smooth", src, "-o", out, "--scheme", "butterfly", "--levels", "2", "--ascii", "-q")
    got = _read_ascii_ply_vertices(out)
    assert len(got) == 6 + 12 + (24 + 24)  # V + E per level (E = 12, then 2*12 + 3*8 = 48)
    for a, b in zip(verts, got):
        assert all(abs(x - y) < 1e-7 for x, y in zip(a, b))
    # Loop moves them inward (approximating); at the limit the octahedron's corners shrink.
    out2 = tmp_path / "oct_l.ply"
    cli("smooth", src, "-o", out2, "--levels", "1", "--ascii", "-q")
    assert math.dist(_read_ascii_ply_vertices(out2)[0], verts[0]) > 0.1


def test_options_creases_boundary_and_threads(cli, inspect, tmp_path):
    src = tmp_path / "torus.obj"
    _torus(src)
    outs = []
    for t in (1, 3):
        o = tmp_path / f"t{t}.ply"
        cli("smooth", src, "-o", o, "--levels", "2", "--threads", t, "-q", "--crease", "0,1", "--crease", "1,2,2.5")
        outs.append(o.read_bytes())
    assert outs[0] == outs[1]
    plain = tmp_path / "plain.ply"
    cli("smooth", src, "-o", plain, "--levels", "2", "-q")
    assert plain.read_bytes() != outs[0]  # the creases changed the surface
    rep = tmp_path / "r.json"
    cli("smooth", src, "-o", tmp_path / "n.ply", "--no-limit", "--boundary", "edge-only", "--crease-method", "chaikin",
        "--report", rep, "-q")
    assert json.loads(rep.read_text())["smooth"]["limit"] is False


def test_bad_input_gives_one_line_errors(cli, tmp_path):
    _fails(cli, tmp_path, ["smooth", tmp_path / "missing.obj"], "missing.obj")
    fin = tmp_path / "fin.obj"  # three triangles on edge (1, 2)
    fin.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 1 1 1\nf 1 2 3\nf 2 4 3\nf 2 3 5\n")
    _fails(cli, tmp_path, ["smooth", fin, "--scheme", "butterfly"], "edge (1, 2) is shared by 3 triangles")
    src = tmp_path / "oct.obj"
    _octahedron(src)
    _fails(cli, tmp_path, ["smooth", src, "--crease", "0,1"], "creases[0] = (0, 1) is not an edge")
    _fails(cli, tmp_path, ["smooth", src, "--crease", "0,x"], "--crease '0,x'")
    _fails(cli, tmp_path, ["smooth", src, "--scheme", "butterfly", "--crease", "0,2"], "Loop scheme only")
    _fails(cli, tmp_path, ["smooth", src, "--levels", "9", "--max-triangles", "1000"], "more than max_triangles = 1000")
    _fails(cli, tmp_path, ["smooth", src, "--levels", "11"], "levels", code=2)
    _fails(cli, tmp_path, ["smooth", src, "--scheme", "catmull"], "scheme", code=2)


def _hex_lattice(path, nx=14, ny=12):
    pts = [(i + 0.5 * (j % 2), j * math.sqrt(3) / 2, 0.0) for j in range(ny) for i in range(nx)]
    path.write_text("".join("%r %r %r\n" % p for p in pts))
    return pts


def test_triangulate_then_smooth_in_one_step(cli, inspect, tmp_path):
    pts = tmp_path / "hex.xyz"
    _hex_lattice(pts)
    plain = tmp_path / "plain.ply"
    cli("triangulate", pts, "-o", plain, "-q")
    base = inspect(plain)
    assert base["manifold"] and base["nonmanifold_edges"] == 0
    for scheme in ("loop", "butterfly"):
        out = tmp_path / f"{scheme}.ply"
        cli("triangulate", pts, "-o", out, "--smooth", scheme, "--levels", "2", "-q")
        r = inspect(out)
        assert r["triangles"] == 16 * base["triangles"]
        assert r["manifold"] and r["consistently_oriented"]
        assert r["euler_characteristic"] == base["euler_characteristic"] == 1
        assert r["vertices"] == r["vertices_used"]
    proc = cli("triangulate", pts, "-o", tmp_path / "x.ply", "--levels", "2", check=False)
    assert proc.returncode == 2 and "--smooth" in proc.stderr


def test_triangulate_smooth_on_a_sampled_torus(cli, inspect, tmp_path):
    # Particles -> finished surface -> Loop at the limit, in one step: still a closed, outward
    # genus-1 manifold with 16x the triangles; the raw triangle set is refused by butterfly
    # with a line naming the smoothing step (it is not a manifold) and leaves no file.
    pts = tmp_path / "torus.xyz"
    cli("sample", "torus", "--spacing", "0.08", "-o", pts)
    plain = tmp_path / "plain.ply"
    cli("triangulate", pts, "-o", plain, "-q")
    base = inspect(plain)
    assert base["closed"] and base["manifold"]
    for scheme in ("loop", "butterfly"):
        out = tmp_path / f"{scheme}.ply"
        cli("triangulate", pts, "-o", out, "--smooth", scheme, "--levels", "2", "-q")
        r = inspect(out)
        assert r["triangles"] == 16 * base["triangles"]
        assert r["closed"] and r["manifold"] and r["consistently_oriented"] and r["outward"]
        assert r["euler_characteristic"] == 0 and r["per_component"][0]["genus"] == 1
    out = tmp_path / "raw.ply"
    proc = cli("triangulate", pts, "-o", out, "--raw", "--smooth", "butterfly", check=False)
    assert proc.returncode == 1, proc.stderr
    assert "--smooth butterfly: " in proc.stderr and "non-manifold" in proc.stderr
    assert "the Loop scheme smooths such meshes" in proc.stderr
    assert len([l for l in proc.stderr.splitlines() if l.strip()]) == 1
    assert not out.exists()
    # Loop smooths the raw triangle set too, its edges in three or more triangles kept sharp.
    raw = tmp_path / "raw_plain.ply"
    cli("triangulate", pts, "-o", raw, "--raw", "-q")
    proc = cli("smooth", raw, "-o", out, "--levels", "1")
    assert "non-manifold  " in proc.stdout and "kept sharp" in proc.stdout, proc.stdout
    r, before = inspect(out), inspect(raw)
    assert before["nonmanifold_edges"] > 0 and r["nonmanifold_edges"] == 2 * before["nonmanifold_edges"]


def test_help(cli):
    proc = cli("smooth", "--help")
    assert "--scheme" in proc.stdout and "--levels" in proc.stdout and "--no-limit" in proc.stdout
    assert "--smooth" in cli("triangulate", "--help").stdout


def test_sigint_cancels_without_output(cli, tmp_path):
    # Cancellation takes effect at the next stage boundary (OpenSubdiv's topology refinement is
    # one call), so the bound is loose; what matters is status 130 and no file.
    import os
    import signal
    import subprocess
    import time

    src = tmp_path / "big.obj"
    _torus(src, nu=320, nv=160)  # 102 400 triangles -> 6.5 million at level 3
    out = tmp_path / "big_s.ply"
    proc = subprocess.Popen([os.environ["PARTICLEMESH_CLI"], "smooth", src, "-o", out, "--levels", "3"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(0.7)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "cancel" in err or "interrupted" in err
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".big_s")]


def test_what_the_input_mesh_holds_but_is_not_smoothed_is_named(cli, tmp_path):
    """An OBJ's materials, and texture coordinates its faces do not use, are not carried
    through the smoothing: the summary, the report and inspect name them; a plain mesh names
    nothing."""
    obj = tmp_path / "uv.obj"
    _octahedron(tmp_path / "octa.obj")
    text = (tmp_path / "octa.obj").read_text()
    obj.write_text("mtllib m.mtl\nusemtl skin\nvt 0 0\nvt 1 1\n" + text)
    uv = "texture coordinates (2 vt; 24 face corners name none)"
    line = f"  not read      {uv}; materials (1 usemtl)"
    out = cli("smooth", obj, "-o", tmp_path / "s.ply", "--report", tmp_path / "s.json").stdout
    assert line in out
    assert json.loads((tmp_path / "s.json").read_text())["not_read"] == [uv, "materials (1 usemtl)"]
    assert line in cli("inspect", obj).stdout
    assert json.loads(cli("inspect", obj, "--json").stdout)["not_read"][0] == uv
    out = cli("smooth", tmp_path / "octa.obj", "-o", tmp_path / "t.ply", "--report", tmp_path / "t.json").stdout
    assert "not read" not in out and "not_read" not in json.loads((tmp_path / "t.json").read_text())
    assert "not_read" not in json.loads(cli("inspect", tmp_path / "octa.obj", "--json").stdout)


def _obj_corners(path):
    """(positions, [(vertex, (u, v)) per corner of each face]) of an OBJ with v/vt corners."""
    v, vt, faces = [], [], []
    for line in path.read_text().splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            v.append(tuple(map(float, w[1:4])))
        elif w[0] == "vt":
            vt.append(tuple(map(float, w[1:3])))
        elif w[0] == "f":
            faces.append([(int(c.split("/")[0]) - 1, vt[int(c.split("/")[1]) - 1]) for c in w[1:]])
    return v, faces


def test_texture_coordinates_go_through_the_smoothing(cli, tmp_path):
    """An OBJ's texture coordinates (u = x + 3 on the lower faces, v = y + z: a seam around
    the equator) come out as vt: linear over each input face, so every output corner's
    (u, v) is a mean of its face's input corners', and the seam stays where it was; a .ply
    output holds them too. An output that cannot hold them says so."""
    verts, faces = _octahedron(tmp_path / "octa.obj")
    lines = ["v %g %g %g" % p for p in verts]
    corners = []
    for n, face in enumerate(faces):
        for i in face:
            x, y, z = verts[i]
            lines.append("vt %g %g" % (x + (3 if n >= 4 else 0), y + z))
            corners.append("%d/%d" % (i + 1, len(lines) - len(verts)))
    lines += ["f " + " ".join(corners[3 * n:3 * n + 3]) for n in range(len(faces))]
    src = tmp_path / "uv.obj"
    src.write_text("\n".join(lines) + "\n")
    assert "  per corner    uv (2 per corner)" in cli("inspect", src).stdout
    assert json.loads(cli("inspect", src, "--json").stdout)["corner_attributes"] == ["uv (2 per corner)"]
    out = cli("smooth", src, "-o", tmp_path / "s.obj", "--levels", "2").stdout
    assert "not read" not in out and "not written" not in out
    _, smooth_faces = _obj_corners(tmp_path / "s.obj")
    assert len(smooth_faces) == 16 * len(faces)
    for n, face in enumerate(smooth_faces):
        parent = faces[n // 16]
        lower = n // 16 >= 4
        for vertex, (u, v) in face:
            # A mean of the parent's corners' (u, v): inside their triangle, on the right side of the seam.
            assert (u > 1.5) == lower, (n, u)
            pu = [verts[i][0] + (3 if lower else 0) for i in parent]
            assert min(pu) - 1e-6 <= u <= max(pu) + 1e-6
            if vertex < len(verts):  # a corner of the input: its own coordinates
                assert vertex in parent
                x, y, z = verts[vertex]
                assert (u, v) == (x + (3 if lower else 0), y + z)
    # PLY holds them as MeshLab's texcoord lists: inspect finds them there too.
    out = cli("smooth", src, "-o", tmp_path / "s.ply", "--levels", "2").stdout
    assert "not written" not in out
    assert "  per corner    uv (2 per corner)" in cli("inspect", tmp_path / "s.ply").stdout
    out = cli("smooth", src, "-o", tmp_path / "s.vtk", "--report", tmp_path / "s.json").stdout
    assert ("  not written   uv (per corner) (only .obj and .ply hold texture coordinates (uv), "
            "and no other value per corner)") in out
    assert json.loads((tmp_path / "s.json").read_text())["not_written"] == ["uv (per corner)"]
