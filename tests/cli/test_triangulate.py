"""particlemesh triangulate / inspect / sample, end to end through the binary."""
import json
import re
import math
import os
import random
import signal
import struct
import subprocess
import time
from pathlib import Path


def test_sample_then_triangulate_knot(cli, inspect, tmp_path):
    pts = tmp_path / "trefoil.xyz"
    cli("sample", "trefoil", "-o", pts, "--spacing", "0.08")
    n = sum(1 for line in pts.read_text().splitlines() if line.strip())
    assert n > 3000
    out = tmp_path / "trefoil.ply"
    report = tmp_path / "report.json"
    proc = cli("triangulate", pts, "-o", out, "--report", report)
    assert "spacing r0" in proc.stdout and "triangles" in proc.stdout
    r = json.loads(report.read_text())
    assert r["triangulation"]["points"] == n
    assert r["triangulation"]["spacing_estimated"] is True
    assert math.isclose(r["triangulation"]["max_edge"], 2 * r["triangulation"]["spacing"])
    assert r["topology"]["vertices_used"] == n
    mesh = inspect(out)
    assert mesh["triangles"] == r["topology"]["triangles"]
    assert mesh["vertices"] == n
    # The knotted tube is one closed, outward oriented torus-like surface using every particle.
    assert mesh["closed"] and mesh["manifold"] and mesh["outward"]
    assert mesh["components"] == 1 and mesh["per_component"][0]["genus"] == 1
    assert mesh["vertices_used"] == n
    assert r["surface"]["unused_points"] == 0


def test_the_vertices_of_a_quad_mesh_with_a_thin_tube_stay_one_surface(cli, inspect, tmp_path):
    # A modeller's quad mesh of a thin torus (8 quads around, each twice as long as it is
    # wide, as a quad-meshed animal's legs are), its vertices triangulated as particles.
    # Each ring of vertices lies in one plane that once outvoted the tube's own, turned the
    # normals along the tube and left it in 40 capped pieces.
    rings, around, rho = 40, 8, 0.1
    lines = []
    for i in range(rings):
        u = 2 * math.pi * i / rings
        for j in range(around):
            v = 2 * math.pi * j / around
            lines.append(f"v {(1 + rho * math.cos(v)) * math.cos(u)} {(1 + rho * math.cos(v)) * math.sin(u)} "
                         f"{rho * math.sin(v)}")
    for i in range(rings):
        for j in range(around):
            a, b = i * around + j, i * around + (j + 1) % around
            c, d = ((i + 1) % rings) * around + (j + 1) % around, ((i + 1) % rings) * around + j
            lines.append(f"f {a + 1} {b + 1} {c + 1} {d + 1}")
    obj = tmp_path / "tube.obj"
    obj.write_text("\n".join(lines) + "\n")
    out = tmp_path / "tube.ply"
    cli("triangulate", obj, "-o", out, "-q")
    mesh = inspect(out)
    assert mesh["components"] == 1 and mesh["closed"] and mesh["manifold"] and mesh["outward"]
    assert mesh["per_component"][0]["genus"] == 1
    assert mesh["vertices_used"] == rings * around


def test_sharp_shapes_close_and_the_old_normal_angle_leaves_a_slit(cli, inspect, tmp_path):
    # Machined-part creases: the cone's rim is a 63-degree crease, the prism's edges 60
    # degrees; bare points (.xyz), so the normals are estimated.
    for shape in ("box", "cone", "prism"):
        pts = tmp_path / f"{shape}.xyz"
        cli("sample", shape, "-o", pts, "--spacing", "0.03", "--seed", "3")
        n = sum(1 for line in pts.read_text().splitlines() if line.strip())
        out = tmp_path / f"{shape}.ply"
        cli("triangulate", pts, "-o", out, "-q")
        mesh = inspect(out)
        assert mesh["closed"] and mesh["manifold"] and mesh["outward"], shape
        assert mesh["components"] == 1 and mesh["euler_characteristic"] == 2, shape
        assert mesh["vertices_used"] == n, shape
    # With the sampler's exact face normals (no bisector on the rim, as the estimate gives),
    # the default angle joins the cone's faces, and 90 degrees (the default before) leaves
    # the rim open: the option reaches the library.
    pts = tmp_path / "cone_normals.ply"
    cli("sample", "cone", "-o", pts, "--spacing", "0.03", "--seed", "3")
    for angle, closed in ((None, True), ("90", False)):
        out = tmp_path / f"cone_{angle}.ply"
        report = tmp_path / f"cone_{angle}.json"
        cli("triangulate", pts, "-o", out, "-q", "--normals", "input", "--report", report,
            *(("--normal-angle", angle) if angle else ()))
        r = json.loads(report.read_text())
        assert inspect(out)["closed"] == closed, angle
        if not closed:
            assert r["surface"]["largest_hole_left"] > 60  # the slit runs around the rim


def test_raw_counts_match_reference_on_bunny(cli, inspect, data_dir, tmp_path):
    out = tmp_path / "bunny.obj"
    cli("triangulate", data_dir / "points/bunny_poisson.ply", "-o", out, "--raw", "--threads", "1")
    r = inspect(out)
    assert r["triangles"] == 21591  # shared/notes/seed-test-behaviour.md
    assert r["nonmanifold_edges"] == 6458
    assert r["euler_characteristic"] == -34


def test_explicit_spacing_and_factor(cli, tmp_path):
    pts = tmp_path / "s.xyz"
    cli("sample", "fibonacci", "--points", "2000", "-o", pts)
    rep = tmp_path / "r.json"
    cli("triangulate", pts, "-o", tmp_path / "s.ply", "--spacing", "0.1", "--max-edge-factor", "1.5",
        "--report", rep, "--ascii", "-q")
    r = json.loads(rep.read_text())["triangulation"]
    assert r["spacing"] == 0.1 and not r["spacing_estimated"]
    assert math.isclose(r["max_edge"], 0.15)
    assert (tmp_path / "s.ply").read_bytes().startswith(b"ply\nformat ascii")


def test_thin_meshes_an_even_subset(cli, inspect, tmp_path):
    pts = tmp_path / "s.ply"
    cli("sample", "fibonacci", "--points", "20000", "-o", pts)
    full, thin = tmp_path / "full.json", tmp_path / "thin.json"
    cli("triangulate", pts, "-o", tmp_path / "full.ply", "--report", full, "-q")
    proc = cli("triangulate", pts, "-o", tmp_path / "thin.ply", "--thin", "2", "--report", thin)
    assert "thinned" in proc.stdout
    r0 = json.loads(full.read_text())["triangulation"]["spacing"]
    r = json.loads(thin.read_text())
    assert r["thin"]["of"] == 20000 and 20000 / 8 < r["thin"]["kept"] < 20000 / 3
    assert math.isclose(r["thin"]["distance"], 2 * r0)
    # The subset's own spacing, estimated: at least the thinning distance.
    assert r["triangulation"]["spacing_estimated"] and r["triangulation"]["spacing"] >= 2 * r0
    mesh = inspect(tmp_path / "thin.ply")
    assert mesh["vertices"] == r["thin"]["kept"] == mesh["vertices_used"]
    assert mesh["closed"] and mesh["manifold"] and mesh["outward"] and mesh["components"] == 1
    assert mesh["euler_characteristic"] == 2
    # A given spacing sets the thinning distance; a factor below 1 is refused.
    cli("triangulate", pts, "-o", tmp_path / "t2.ply", "--thin", "2", "--spacing", str(2 * r0),
        "--report", thin, "-q")
    assert math.isclose(json.loads(thin.read_text())["thin"]["distance"], 4 * r0)
    proc = cli("triangulate", pts, "-o", tmp_path / "t3.ply", "--thin", "0.5", check=False)
    assert proc.returncode == 2 and "--thin" in proc.stderr
    assert not (tmp_path / "t3.ply").exists()


def test_georeferenced_coordinates_mesh_as_at_the_origin(cli, inspect, tmp_path):
    """A scan at UTM-like coordinates, as a binary PLY of doubles: read exactly, meshed as the
    same cloud at the origin, and written back with double positions (float32 steps are 0.5
    there, wider than the spacing)."""
    pts = tmp_path / "s.xyz"
    cli("sample", "fibonacci", "--points", "5000", "-o", pts)
    rows = [tuple(map(float, line.split()[:3])) for line in pts.read_text().splitlines() if line.strip()]
    offset = (512345.678, 5412345.678, 250.5)
    far = tmp_path / "far.ply"
    with far.open("wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(rows))
        f.write(b"property double x\nproperty double y\nproperty double z\nend_header\n")
        for x, y, z in rows:
            f.write(struct.pack("<3d", x + offset[0], y + offset[1], z + offset[2]))
    cli("triangulate", pts, "-o", tmp_path / "near.ply", "-q")
    cli("triangulate", far, "-o", tmp_path / "far_mesh.ply", "-q")
    near, moved = inspect(tmp_path / "near.ply"), inspect(tmp_path / "far_mesh.ply")
    assert moved["closed"] and moved["outward"] and moved["components"] == 1
    assert moved["euler_characteristic"] == 2 and moved["vertices_used"] == len(rows)
    assert moved["triangles"] == near["triangles"]
    data = (tmp_path / "far_mesh.ply").read_bytes()
    header = data[: data.index(b"end_header\n") + len(b"end_header\n")]
    assert b"property double x" in header
    assert b"property float x" in (tmp_path / "near.ply").read_bytes()[:200]
    first = struct.unpack_from("<3d", data, len(header))
    assert first == (rows[0][0] + offset[0], rows[0][1] + offset[1], rows[0][2] + offset[2])


def test_near_copies_of_most_particles_are_set_aside(cli, inspect, tmp_path):
    """Every particle with a copy a fiftieth of the spacing away (an airborne scanner's first
    and last returns): the copies are set aside, named by the summary, the report and
    `inspect`, and the rest meshes as the particles alone do (before, nothing was meshed)."""
    pts = tmp_path / "s.xyz"
    cli("sample", "fibonacci", "--points", "3000", "-o", pts)
    rows = [tuple(map(float, line.split()[:3])) for line in pts.read_text().splitlines() if line.strip()]
    rng = random.Random(5)
    copies = []
    for x, y, z in rows:
        d = [rng.gauss(0, 1) for _ in range(3)]
        n = math.sqrt(sum(v * v for v in d))
        copies.append(tuple(p + 0.0012 * v / n for p, v in zip((x, y, z), d)))  # spacing ~0.065
    both = tmp_path / "twinned.xyz"
    both.write_text("".join("%.9f %.9f %.9f\n" % r for r in rows + copies))
    alone = tmp_path / "alone.xyz"
    alone.write_text("".join("%.9f %.9f %.9f\n" % r for r in rows))
    proc = cli("triangulate", both, "-o", tmp_path / "both.ply", "--report", tmp_path / "r.json")
    assert "(3000 near copies (a neighbour ten times nearer than every other) set aside)" in proc.stdout, proc.stdout
    assert json.loads((tmp_path / "r.json").read_text())["triangulation"]["near_duplicates"] == 3000
    cli("triangulate", alone, "-o", tmp_path / "alone.ply", "-q")
    got, want = inspect(tmp_path / "both.ply"), inspect(tmp_path / "alone.ply")
    assert got["closed"] and got["components"] == 1 and got["vertices_used"] == 3000
    assert got["triangles"] == want["triangles"] and got["vertices"] == 6000
    text = cli("inspect", both).stdout
    assert re.search(r"near copies +3000 particles lie ten times nearer to another", text), text
    twinned, single = json.loads(cli("inspect", both, "--json").stdout), json.loads(cli("inspect", alone, "--json").stdout)
    assert twinned["near_duplicates"] == 3000 and single["near_duplicates"] == 0
    # The spacing with the copies is their offset; apart from them, the particles' own.
    assert twinned["spacing"] < 0.0013 and twinned["spacing_apart"] == single["spacing"] == single["spacing_apart"]


def test_unevenly_spaced_particles_get_a_hint(cli, tmp_path):
    """A sphere sampled 2.8x sparser on its upper half. By default each particle's L follows
    its own spacing and the sphere closes through every particle. With --global-spacing the
    sparse particles are farther apart than L = 2 r0 of the dense half, fall out of the
    surface, and the summary and the report say what helps (and --thin 2 does: one closed
    sphere); an even sphere gets no hint."""
    pts, sparse = tmp_path / "s.xyz", tmp_path / "sparse.xyz"
    cli("sample", "fibonacci", "--points", "20000", "-o", pts)
    cli("sample", "fibonacci", "--points", "2500", "-o", sparse)
    rows = lambda p: [line for line in p.read_text().splitlines() if line.strip()]  # noqa: E731
    uneven = ([r for r in rows(pts) if float(r.split()[2]) < 0]
              + [r for r in rows(sparse) if float(r.split()[2]) >= 0])
    (tmp_path / "uneven.xyz").write_text("\n".join(uneven) + "\n")
    rep = tmp_path / "r.json"
    proc = cli("triangulate", tmp_path / "uneven.xyz", "-o", tmp_path / "l.ply", "--report", rep)
    r = json.loads(rep.read_text())
    assert "hint" not in r and "hint" not in proc.stdout and r["spacing"] == "local"
    assert r["topology"]["closed"] and r["topology"]["components"] == 1 and r["surface"]["unused_points"] == 0
    spread = r["surface"]["local_spacing"]
    assert abs(spread["min"] - 1) < 0.01 and spread["max"] > 1.5  # the dense half meshes at r0, the sparse one wider
    assert "local spacing" in proc.stdout
    proc = cli("triangulate", tmp_path / "uneven.xyz", "-o", tmp_path / "u.ply", "--report", rep, "--global-spacing")
    r = json.loads(rep.read_text())
    assert r["spacing"] == "global" and r["surface"]["local_spacing"]["max"] == 1
    assert r["surface"]["unused_points"] * 20 > len(uneven)
    assert "--thin 2" in r["hint"] and "--max-edge-factor" in r["hint"] and "leave out --global-spacing" in r["hint"]
    assert "hint" in proc.stdout and "--thin 2" in proc.stdout
    proc = cli("triangulate", tmp_path / "uneven.xyz", "-o", tmp_path / "t.ply", "--thin", "2", "--report", rep,
               "--global-spacing")
    r = json.loads(rep.read_text())
    assert "hint" not in r and r["topology"]["closed"] and r["topology"]["components"] == 1
    proc = cli("triangulate", pts, "-o", tmp_path / "e.ply", "--report", rep)
    assert "hint" not in proc.stdout and "hint" not in json.loads(rep.read_text())


def test_particles_at_random_close_with_a_longer_reach(cli, tmp_path):
    """Particles dropped uniformly at random on a sphere (as Blender's Random emission): the
    summary's sampling line says their edge limits were lengthened, the report gives the
    irregularity and the factor, and the sphere closes through (nearly) every particle. An even
    sphere keeps the factor 1 and gets no such line."""
    rng = random.Random(7)
    rows = []
    for _ in range(4000):
        z, phi = 2 * rng.random() - 1, 2 * math.pi * rng.random()
        r = math.sqrt(1 - z * z)
        rows.append(f"{r * math.cos(phi):.9g} {r * math.sin(phi):.9g} {z:.9g}")
    (tmp_path / "random.xyz").write_text("\n".join(rows) + "\n")
    rep = tmp_path / "r.json"
    proc = cli("triangulate", tmp_path / "random.xyz", "-o", tmp_path / "r.ply", "--report", rep)
    r = json.loads(rep.read_text())
    assert "sampling      irregular" in proc.stdout and "1.8 x the sampling's" in proc.stdout
    assert 0.44 < r["triangulation"]["sampling_irregularity"] < 0.56
    assert r["triangulation"]["reach_factor"] == 1.75
    assert r["topology"]["closed"] and r["topology"]["components"] == 1
    # At random some particles lie almost on top of another: one such may be passed by.
    assert r["topology"]["euler_characteristic"] == 2 and r["surface"]["unused_points"] <= 4
    even = tmp_path / "even.xyz"
    cli("sample", "fibonacci", "--points", "4000", "-o", even)
    proc = cli("triangulate", even, "-o", tmp_path / "e.ply", "--report", rep)
    r = json.loads(rep.read_text())
    assert "sampling" not in proc.stdout and r["triangulation"]["reach_factor"] == 1
    assert r["triangulation"]["sampling_irregularity"] < 0.25


def test_a_spacing_given_too_small_is_named(cli, tmp_path):
    """--spacing well below the particles' median nearest-neighbour distance leaves them all
    out (edges of 2 x it reach no neighbour): the hint names the given spacing and the
    measured one, not the particles' evenness; a fitting --spacing gets no hint."""
    pts, rep = tmp_path / "s.xyz", tmp_path / "r.json"
    cli("sample", "fibonacci", "--points", "4000", "-o", pts)
    measured = json.loads(cli("inspect", pts, "--json").stdout)["spacing"]
    proc = cli("triangulate", pts, "-o", tmp_path / "m.ply", "--report", rep, "--spacing", "%.6g" % (0.45 * measured))
    r = json.loads(rep.read_text())
    assert r["topology"]["triangles"] == 0
    assert r["hint"].startswith("the given --spacing") and "45%" in r["hint"] and "--thin" not in r["hint"]
    assert "the given --spacing" in proc.stdout
    proc = cli("triangulate", pts, "-o", tmp_path / "m.ply", "--report", rep, "--spacing", "%.6g" % measured)
    assert "hint" not in json.loads(rep.read_text()) and "hint" not in proc.stdout


def test_loops_the_settings_left_open_get_a_hint(cli, tmp_path):
    """Loops left open for a fill limit set too low are named with the setting that reaches
    them, and that setting closes them (no hint then); an edge limit given below the default
    is named as the cause of the open loops it leaves; the defaults close the sphere."""
    pts, rep, out = tmp_path / "s.ply", tmp_path / "r.json", tmp_path / "m.ply"
    cli("sample", "sphere", "--spacing", "0.05", "-o", pts, "-q")
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    r = json.loads(rep.read_text())
    assert "hint" not in r and "hint" not in proc.stdout and r["topology"]["closed"]
    proc = cli("triangulate", pts, "-o", out, "--report", rep, "--fill-edge-factor", "1")
    r = json.loads(rep.read_text())
    loops = r["topology"]["boundary_loops"]
    assert loops > 5
    assert r["hint"].startswith("all %d loops left open are narrow" % loops), r["hint"]
    factor = r["hint"].split("try --fill-edge-factor ")[1].split()[0]
    widest = max(l["width_over_L"] for l in r["surface"]["open_loops"])
    assert r["surface"]["narrow_loops"] == {"count": loops, "width_over_L": widest,
                                            "edges": max(l["edges"] for l in r["surface"]["open_loops"])}
    assert 1 < widest <= float(factor) < widest + 0.1 + 1e-9
    proc = cli("triangulate", pts, "-o", out, "--report", rep, "--fill-edge-factor", factor)
    r = json.loads(rep.read_text())
    assert r["topology"]["closed"] and "hint" not in r and "hint" not in proc.stdout
    assert r["surface"]["narrow_loops"]["count"] == 0
    proc = cli("triangulate", pts, "-o", out, "--report", rep, "--max-edge-factor", "1.5")
    r = json.loads(rep.read_text())
    assert r["topology"]["boundary_loops"] > 20
    assert r["hint"].startswith("--max-edge-factor 1.5 is below the default 2: edges of 1.5 x r0 leave %d loops open"
                                % r["topology"]["boundary_loops"]), r["hint"]
    assert "--fill-edge-factor" not in r["hint"]


def test_a_small_handle_taken_out_is_in_the_summary_and_report(cli, tmp_path):
    """A sphere flattened to 0.12 of its width has a rim thinner than its spacing; the tunnel
    the surface had there is taken out: the summary and the report say so, genus 0."""
    pts, rep, out = tmp_path / "s.xyz", tmp_path / "r.json", tmp_path / "m.ply"
    cli("sample", "fibonacci", "--points", "800", "-o", pts, "-q")
    rows = [line.split()[:3] for line in pts.read_text().splitlines() if line.strip()]
    pts.write_text("".join(f"{x} {y} {float(z) * 0.12!r}\n" for x, y, z in rows))
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    assert "1 small handle removed" in proc.stdout, proc.stdout
    r = json.loads(rep.read_text())
    assert r["surface"]["small_handles_removed"] == 1
    assert r["topology"]["closed"] and r["topology"]["euler_characteristic"] == 2


def obj_volume(path):
    """The signed volume an OBJ's triangles enclose (positive facing outward)."""
    v, volume = [], 0.0
    for line in path.read_text().splitlines():
        f = line.split()
        if f and f[0] == "v":
            v.append([float(x) for x in f[1:4]])
        elif f and f[0] == "f":
            a, b, c = (v[int(x.split("/")[0]) - 1] for x in f[1:4])
            volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                       + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6
    return volume


def test_a_surface_closed_but_for_small_holes_is_turned_outward(cli, tmp_path):
    """A teardrop's particles (a half ball, a cone up to a sharp tip) with three holes in its
    side: the normals' spanning tree faced it inward from its tip; judged with its holes
    capped it faces outward, and the summary and the report say it was turned."""
    h, height, rows = 0.04, 3.0, []
    n = int(2 * math.pi / h ** 2)
    for i in range(n):
        phi, th = math.acos(1 - 2 * (i + 0.5) / n), math.pi * (1 + 5 ** 0.5) * (i + 0.5)
        if math.cos(phi) < 0:
            rows.append((math.cos(th) * math.sin(phi), math.sin(th) * math.sin(phi), math.cos(phi)))
    for k in range(int(height / h)):
        z = h / 2 + k * h
        r = 1 - z / height
        m = max(int(2 * math.pi * r / h), 3)
        rows += [(r * math.cos(2 * math.pi * j / m + 7 * z), r * math.sin(2 * math.pi * j / m + 7 * z), z)
                 for j in range(m)]
    rows.append((0.0, 0.0, height))
    for c in ((1, 0, -0.3), (0, -1, -0.5), (-0.7, 0.7, 0.2)):
        c = [x / math.hypot(*c) for x in c]
        rows = [p for p in rows if math.dist(p, [x * math.hypot(*p) for x in c]) > 0.25]
    pts, rep, out = tmp_path / "t.xyz", tmp_path / "r.json", tmp_path / "m.obj"
    pts.write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in rows))
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    assert "1 part closed but for small openings turned outward" in proc.stdout, proc.stdout
    assert json.loads(rep.read_text())["surface"]["nearly_closed_turned"] == 1
    volume = obj_volume(out)
    assert 4.7 < volume < 5.24, volume  # pi (2 + 3) / 3, less the holes' and the chords' share
    proc = cli("triangulate", pts, "-o", out, "--no-orient")
    assert "turned outward" not in proc.stdout


def test_a_folded_surface_built_again_is_named(cli, tmp_path):
    """A ball with two thin ears (flat ellipsoids 2 spacings thick), without normals: the
    normals' spanning tree crosses between an ear's sides and the surface folds over; it is
    built again with the normals turned, and the summary and the report say so. The result
    encloses the ball's volume (4.19) and the ears' outside it (about 0.04 each); folded, the
    ears faced inward and took theirs away (4.19 in all)."""
    h, c, rows = 0.04, 0.04, []
    parts = [((1.0, 1.0, 1.0), (0.0, 0.0, 0.0)), ((0.6, c, 0.45), (0.0, 0.0, 1.35)), ((0.6, c, 0.45), (1.3, 0.0, 0.6))]
    for k, (a, centre) in enumerate(parts):
        area = 4 * math.pi * (((a[0] * a[1]) ** 1.6 + (a[0] * a[2]) ** 1.6 + (a[1] * a[2]) ** 1.6) / 3) ** (1 / 1.6)
        n = int(area / (h * h * 0.866))
        for i in range(n):
            phi, th = math.acos(1 - 2 * (i + 0.5) / n), math.pi * (1 + 5 ** 0.5) * (i + 0.5)
            u = (math.cos(th) * math.sin(phi), math.sin(th) * math.sin(phi), math.cos(phi))
            p = tuple(u[d] * a[d] + centre[d] for d in range(3))
            if all(j == k or sum(((p[d] - o[d]) / b[d]) ** 2 for d in range(3)) >= 1 for j, (b, o) in enumerate(parts)):
                rows.append(p)
    pts, rep, out = tmp_path / "ears.xyz", tmp_path / "r.json", tmp_path / "m.obj"
    pts.write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in rows))
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    assert re.search(r"\d+ triangles facing into the solid \(a fold\) built again", proc.stdout), proc.stdout
    assert json.loads(rep.read_text())["surface"]["folded_triangles"] > 1000
    volume = obj_volume(out)
    assert 4.24 < volume < 4.30, volume
    proc = cli("triangulate", pts, "-o", out, "--no-orient")
    assert "a fold" not in proc.stdout


def test_stray_pieces_are_named_and_removed_on_request(cli, inspect, tmp_path):
    """Lone triangles apart from a surface (a scanner's strays) are kept by default, and a hint
    names the --min-component-triangles that removes just them; with it they are gone (their
    particles unused, their outlines no loops left open) and the sphere stays closed."""
    pts, rep, out = tmp_path / "s.xyz", tmp_path / "r.json", tmp_path / "m.ply"
    cli("sample", "fibonacci", "--points", "4000", "-o", pts, "-q")
    lines = [" ".join(line.split()[:3]) for line in pts.read_text().splitlines() if line.strip()]
    r0 = math.sqrt(4 * math.pi / 4000)
    for k in range(6):  # six lone triangles on a ring far from the unit sphere
        x, y = 3 * math.cos(k), 3 * math.sin(k)
        lines += [f"{x} {y} 0", f"{x + r0} {y} 0", f"{x + r0 / 2} {y + 0.87 * r0} 0"]
    pts.write_text("\n".join(lines) + "\n")
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    r = json.loads(rep.read_text())
    assert r["topology"]["components"] == 7 and r["surface"]["components_removed"] == 0
    assert r["surface"]["stray_pieces"] == {"count": 6, "triangles": 6, "largest": 1}
    assert "6 lone triangles lie apart from the rest: --min-component-triangles 2 removes them" \
        in r["hint"], r["hint"]
    assert "--min-component-triangles 2" in proc.stdout
    before = r["surface"]["unused_points"]
    proc = cli("triangulate", pts, "-o", out, "--report", rep, "--min-component-triangles", "2")
    r = json.loads(rep.read_text())
    assert "removed       6 pieces of fewer than 2 triangles (6 triangles)" in proc.stdout
    assert r["surface"]["components_removed"] == 6 and r["surface"]["component_triangles_removed"] == 6
    assert r["surface"]["unused_points"] == before + 18 and r["surface"]["holes_left"] == 0
    assert "hint" not in r
    mesh = inspect(out)
    assert mesh["components"] == 1 and mesh["closed"] and mesh["manifold"] and mesh["outward"]
    assert mesh["vertices"] == 4018 and mesh["vertices_used"] == 4000


def test_a_models_vertices_get_the_fill_that_closes_them(cli, tmp_path, data_dir):
    """The vertices of a coarse closed model (long thin triangles: an uneven sampling) leave one
    loop 1.6 L across at the default fill limit of 1.5 L: named, and the fill it names closes
    the surface."""
    out, rep = tmp_path / "m.ply", tmp_path / "r.json"
    pts = data_dir / "points" / "bunny_coarse_vertices.ply"
    proc = cli("triangulate", pts, "-o", out, "--report", rep)
    hint = json.loads(rep.read_text())["hint"]
    assert hint.startswith("the loop left open is narrow") and hint in proc.stdout
    factor = hint.split("try --fill-edge-factor ")[1].split()[0]
    cli("triangulate", pts, "-o", out, "--report", rep, "--fill-edge-factor", factor)
    r = json.loads(rep.read_text())
    assert r["topology"]["closed"] and r["topology"]["components"] == 1 and "hint" not in r


def test_volume_particles_get_a_hint_to_polygonize(cli, tmp_path):
    """Particles filling a block (a jittered lattice: what a fluid simulation gives) are no
    surface sample: most seed triangles join particles facing opposite ways, the surface does
    not close, and the summary and report point to polygonize. Surface samples (a sphere, a
    box) get no such hint."""
    import random
    rng = random.Random(5)
    rows = ["%.6f %.6f %.6f" % (i + rng.gauss(0, 0.1), j + rng.gauss(0, 0.1), k + rng.gauss(0, 0.1))
            for i in range(14) for j in range(14) for k in range(14)]
    (tmp_path / "block.xyz").write_text("\n".join(rows) + "\n")
    rep = tmp_path / "r.json"
    proc = cli("triangulate", tmp_path / "block.xyz", "-o", tmp_path / "b.ply", "--report", rep)
    r = json.loads(rep.read_text())
    assert r["surface"]["rejected_conormal"] * 20 > r["triangulation"]["kept"] * 7
    assert r["surface"]["looks_like_volume"] is True
    assert "particlemesh polygonize" in r["hint"]
    assert "hint" in proc.stdout and "polygonize" in proc.stdout
    # Polygonize does mesh them: one closed surface.
    cli("polygonize", tmp_path / "block.xyz", "-o", tmp_path / "p.ply", "--report", rep)
    assert json.loads(rep.read_text())["topology"]["closed"]
    for shape in ("sphere", "box"):
        pts = tmp_path / f"{shape}.xyz"
        cli("sample", shape, "--spacing", "0.05", "-o", pts)
        proc = cli("triangulate", pts, "-o", tmp_path / f"{shape}.ply", "--report", rep)
        report = json.loads(rep.read_text())
        assert "polygonize" not in proc.stdout and "hint" not in report
        assert report["surface"]["looks_like_volume"] is False


def test_sph_frames_get_the_polygonize_hint(cli, tmp_path, data_dir):
    """The SPH frames that fill a volume (thickness 0.82-0.88), and the fluid frame of a thin
    layer (0.54: as thick as noisy samples can be, the hint offers both readings), are named
    volume particles; the double dam break's frame, 4 732 particles spread over a 3 x 3 tank
    (a film a particle or two deep: thickness 0.29), is met as a noisy surface, with the
    smoothing to try."""
    kinds = {}
    frames = sorted((data_dir / "particles").glob("*.ply")) + sorted((data_dir / "particles").glob("*.bgeo"))
    for frame in frames:
        rep = tmp_path / "r.json"
        cli("triangulate", frame, "-o", tmp_path / "o.ply", "--report", rep)
        r = json.loads(rep.read_text())
        thickness = r["triangulation"]["sampling_thickness"]
        volume = thickness >= 0.45
        assert r["surface"]["looks_like_volume"] == volume, (frame, thickness)
        assert ("particlemesh polygonize" in r.get("hint", "")) == volume, (frame, thickness)
        assert thickness >= 0.75 or "scatter across their surface" in r.get("hint", ""), frame
        kinds[frame.name.split("_")[0]] = volume
    assert kinds == {"bunny": True, "cube": True, "double": False, "ParticleData": True, "dam": True,
                     "octocat": True}


def test_threads_do_not_change_output(cli, tmp_path):
    pts = tmp_path / "t.xyz"
    cli("sample", "torus", "--spacing", "0.06", "-o", pts)
    outs = []
    for t in (1, 2, 4):
        o = tmp_path / f"t{t}.ply"
        cli("triangulate", pts, "-o", o, "--threads", t, "-q")
        outs.append(o.read_bytes())
    assert outs[0] == outs[1] == outs[2]


def _fails(cli, tmp_path, args, needle):
    out = tmp_path / "out.ply"
    proc = cli("triangulate", *args, "-o", out, check=False)
    assert proc.returncode != 0, proc.stdout
    lines = [l for l in proc.stderr.splitlines() if l.strip()]
    assert len(lines) == 1, proc.stderr  # one line naming the problem
    assert needle in lines[0], lines[0]
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out")], "temporary file left"
    return lines[0]


def test_bad_inputs_give_one_line_errors(cli, tmp_path):
    _fails(cli, tmp_path, [tmp_path / "missing.xyz"], "no such file")
    (tmp_path / "empty.xyz").write_text("")
    _fails(cli, tmp_path, [tmp_path / "empty.xyz"], "empty")
    (tmp_path / "one.xyz").write_text("1 2 3\n")
    _fails(cli, tmp_path, [tmp_path / "one.xyz"], "three points")
    (tmp_path / "same.xyz").write_text("1 2 3\n" * 10)
    _fails(cli, tmp_path, [tmp_path / "same.xyz"], "coincide")
    (tmp_path / "nan.xyz").write_text("0 0 0\n1 0 0\n0 1 0\nnan 0 0\n")
    _fails(cli, tmp_path, [tmp_path / "nan.xyz"], "positions[3].x is NaN")
    (tmp_path / "inf.xyz").write_text("0 0 0\n1 0 0\n0 inf 0\n")
    _fails(cli, tmp_path, [tmp_path / "inf.xyz"], "positions[2].y is infinite")
    (tmp_path / "text.xyz").write_text("0 0 0\nhello world 1\n")
    _fails(cli, tmp_path, [tmp_path / "text.xyz"], "line 2")
    good = tmp_path / "good.xyz"
    cli("sample", "fibonacci", "--points", "1000", "-o", good)
    full = tmp_path / "full.ply"
    cli("sample", "fibonacci", "--points", "1000", "-o", full)
    data = full.read_bytes()
    (tmp_path / "cut.ply").write_bytes(data[: len(data) // 2])
    _fails(cli, tmp_path, [tmp_path / "cut.ply"], "cut.ply")
    # More neighbours within a point's radius than --max-neighbors, with one L for the whole
    # cloud: the error names the limit that lets the run through, and that limit does (the
    # spacing measured; a --spacing far too large gets no such advice: the spacing is what is
    # wrong there). With each particle's own L (the default) the crowded points' L are
    # shortened instead, and the summary says how many.
    proc = cli("triangulate", good, "-o", tmp_path / "x.ply", "--max-neighbors", "8", "--global-spacing", check=False)
    assert proc.returncode == 1 and "more than the limit of 8" in proc.stderr, proc.stderr
    most = re.search(r"\(--max-neighbors (\d+)\)", proc.stderr)
    assert most and not (tmp_path / "x.ply").exists(), proc.stderr
    cli("triangulate", good, "-o", tmp_path / "x.ply", "--max-neighbors", most.group(1), "--global-spacing", "-q")
    assert (tmp_path / "x.ply").exists()
    (tmp_path / "x.ply").unlink()
    proc = cli("triangulate", good, "-o", tmp_path / "x.ply", "--max-neighbors", "8", "--report", tmp_path / "r.json")
    crowded = re.search(r"crowded +(\d+) particles' L shortened so that each reaches at most 8 others", proc.stdout)
    assert crowded and int(crowded.group(1)) > 500, proc.stdout
    assert json.loads((tmp_path / "r.json").read_text())["triangulation"]["shortened_limits"] == int(crowded.group(1))
    (tmp_path / "x.ply").unlink()
    proc = cli("triangulate", good, "-o", tmp_path / "x.ply", "--spacing", "0.5", check=False)
    assert proc.returncode == 1 and "more than the limit of 256" in proc.stderr, proc.stderr
    assert "give a smaller spacing" in proc.stderr and "(--max-neighbors" not in proc.stderr
    # Out-of-range numbers: the message says what the option takes, with its bounds as written
    # (not CLI11's "not in range 0.000000 to 1797693134862315708...000000").
    for args, message in [(("triangulate", "--spacing", "-1"), "--spacing: value -1 is not positive (it must be > 0)"),
                          (("triangulate", "--threads", "-2"), "--threads: value -2 is negative (it must be >= 0)"),
                          (("polygonize", "--collapse-edges", "0.7"), "--collapse-edges: value 0.7 is outside [0, 0.5]"),
                          (("polygonize", "--taubin-mu", "0"), "--taubin-mu: value 0 is outside [-1, -1e-09]")]:
        proc = cli(args[0], good, "-o", tmp_path / "x.ply", *args[1:], check=False)
        assert proc.returncode == 2 and message in proc.stderr and "0.000000" not in proc.stderr, proc.stderr
        assert not (tmp_path / "x.ply").exists()
    # CLI11's range checks let NaN through: every float option also checks it is finite.
    for option in ("--spacing", "--thin", "--max-edge-factor", "--normal-angle", "--fill-edge-factor"):
        proc = cli("triangulate", good, "-o", tmp_path / "x.ply", option, "nan", check=False)
        assert proc.returncode == 2 and option in proc.stderr and "not a finite number" in proc.stderr
        assert not (tmp_path / "x.ply").exists()
    proc = cli("triangulate", good, "-o", tmp_path / "x.unknown", check=False)
    assert proc.returncode != 0 and "x.unknown" in proc.stderr
    proc = cli("triangulate", good, "-o", tmp_path / "nodir" / "x.ply", check=False)
    assert proc.returncode != 0 and "does not exist" in proc.stderr


def test_inspect_reads_shared_meshes(cli, inspect, data_dir):
    r = inspect(data_dir / "meshes/rocker_arm.obj")
    assert r["closed"] and r["components"] == 1
    assert r["per_component"][0]["genus"] == 1
    b = inspect(data_dir / "meshes/bunny.obj")
    assert b["boundary_loops"] == 5
    assert b["vertices"] - b["vertices_used"] == 1113
    text = cli("inspect", data_dir / "meshes/spot.obj").stdout
    assert "euler char.   2" in text


def test_help_and_usage(cli):
    for sub in ("triangulate", "inspect", "sample"):
        proc = cli(sub, "--help")
        assert "Usage" in proc.stdout or "usage" in proc.stdout.lower()
    proc = cli("no-such-command", check=False)
    assert proc.returncode == 2


def _cpu_seconds(pid):
    """User + system CPU time of a running process so far, from /proc/PID/stat."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _children_cpu_seconds():
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


class Interrupted:
    """What interrupt_while_computing saw: `seconds` from the signal to the exit (wall),
    `cpu_seconds` the CPU time the process spent after the signal (all its threads: on a
    loaded machine the wall time stretches, this does not), `rc` and `err` (stderr)."""

    def __init__(self, seconds, cpu_seconds, rc, err):
        self.seconds, self.cpu_seconds, self.rc, self.err = seconds, cpu_seconds, rc, err

    def prompt(self, cpu_limit):
        """Whether it stopped within `cpu_limit` CPU seconds, and in no absurd wall time."""
        return self.cpu_seconds < cpu_limit and self.seconds < 10 * cpu_limit


def interrupt_while_computing(exe, args, stage, tmp_path):
    """Start `particlemesh ARGS`, wait until its progress log (stderr, one line per stage when
    not a terminal) shows `stage` (so it is computing, not reading), send SIGINT, and return
    an Interrupted. Waiting for a stage instead of a fixed sleep keeps the test meaningful on
    a loaded machine."""
    children_before = _children_cpu_seconds()
    proc = subprocess.Popen([exe, *map(str, args)], stderr=subprocess.PIPE, text=True)
    seen = []
    try:
        for line in proc.stderr:
            seen.append(line)
            if stage in line:
                break
        else:
            raise AssertionError(f"finished before stage '{stage}': {''.join(seen)}")
        cpu_at_signal = _cpu_seconds(proc.pid)
        start = time.monotonic()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        seconds = time.monotonic() - start
        cpu_after = _children_cpu_seconds() - children_before - cpu_at_signal
        return Interrupted(seconds, cpu_after, proc.returncode, "".join(seen) + err)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_sigint_cancels_without_partial_output(cli, tmp_path):
    exe = os.environ["PARTICLEMESH_CLI"]
    pts = tmp_path / "big.ply"
    cli("sample", "fibonacci", "--points", "3000000", "-o", pts)
    out = tmp_path / "big_out.ply"
    report = tmp_path / "big_report.json"
    r = interrupt_while_computing(
        exe, ["triangulate", pts, "-o", out, "--raw", "--report", report], "testing triangles", tmp_path)
    assert r.prompt(cpu_limit=1.5), (r.seconds, r.cpu_seconds, r.err)
    assert r.rc == 130, r.err
    assert "cancel" in r.err
    assert not out.exists() and not report.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".big_")]


def test_rows_far_apart_get_the_edge_factor_that_crosses_them(cli, inspect, tmp_path):
    """A sphere sampled in rings (300 points around, 25 rings: six times closer along a ring
    than across to the next, as a scanner's rows or a mesh's rings of vertices): the local
    spacing across lies past the 3 r0 the edge limits stop at, so the surface falls apart into
    strips; the summary says so and names a --max-edge-factor, which closes it."""
    lines = []
    for k in range(25):
        t = (k + 0.5) / 25 * math.pi
        m = max(6, round(300 * math.sin(t)))
        lines += ["%.9g %.9g %.9g" % (math.sin(t) * math.cos(2 * math.pi * j / m), math.sin(t) * math.sin(2 * math.pi * j / m),
                                      math.cos(t)) for j in range(m)]
    rings = tmp_path / "rings.xyz"
    rings.write_text("\n".join(lines) + "\n")
    out = tmp_path / "rings.ply"
    report = tmp_path / "rings.json"
    proc = cli("triangulate", rings, "-o", out, "--report", report)
    assert inspect(out)["boundary_loops"] > 100, proc.stdout
    hint = re.search(r"closer along lines than across them .*: 10% of them are ([0-9.]+) x r0 or more .* "
                     r"--max-edge-factor ([0-9.]+) may let the edges cross", proc.stdout)
    assert hint, proc.stdout
    across = json.loads(report.read_text())["triangulation"]["uncapped_spacing_p90"]
    assert across > 3 and float(hint.group(1)) == round(across, 1), (across, hint.group(0))
    assert "expect the run to take" not in proc.stdout  # a factor of a few: no warning
    cli("triangulate", rings, "-o", out, "--max-edge-factor", hint.group(2), "-q")
    mesh = inspect(out)
    assert mesh["closed"] and mesh["components"] == 1 and mesh["manifold"], mesh
    # An even sampling of the same sphere gets no such hint.
    even = tmp_path / "even.xyz"
    cli("sample", "fibonacci", "--points", "5000", "-o", even)
    proc = cli("triangulate", even, "-o", out)
    assert "closer along lines" not in proc.stdout


def test_a_lidar_sweeps_rows_get_the_factor_with_what_it_costs(cli, tmp_path):
    """A spinning lidar's sweep of the ground (16 beams, a firing every degree, 2 m up): the
    rings of returns lie tens of spacings apart far out, so the factor that crosses them is
    many times the default, and it lengthens the dense near field's limits as much (a 115k
    sweep took 32 s with it, 1.1 s without): the hint says so."""
    lines = []
    rng = random.Random(0)
    for beam in range(16):
        e = math.radians(-25 + 24 * beam / 15)
        t = -2.0 / math.sin(e)
        if t >= 120:
            continue
        for step in range(360):
            a = math.radians(step)
            lines.append("%.6f %.6f %.6f" % (t * math.cos(e) * math.cos(a) + rng.gauss(0, 0.005),
                                             t * math.cos(e) * math.sin(a) + rng.gauss(0, 0.005), rng.gauss(0, 0.005)))
    sweep = tmp_path / "sweep.xyz"
    sweep.write_text("\n".join(lines) + "\n")
    proc = cli("triangulate", sweep, "-o", tmp_path / "sweep.ply")
    hint = re.search(r"--max-edge-factor ([0-9.]+) may let the edges cross \(it lengthens the dense particles' "
                     r"limits too: expect the run to take many times longer\)", proc.stdout)
    assert hint and float(hint.group(1)) > 6, proc.stdout


def test_parts_sparser_all_round_get_thinning_not_rows(cli, inspect, tmp_path):
    """A floor scanned coarsely (20k points 7 cm apart) with a close-up of a patch of it on top
    (20k points 1.4 mm apart): the median spacing is the patch's, the floor lies 50 times
    sparser all round, past the 3 r0 the edge limits stop at, and is left out. The hint says so
    (not "rows": the floor's own neighbours are as far apart as its spacing) and names the
    thinning that meshes all of it, which does."""
    rng = random.Random(3)
    lines = []
    for side, count, at, z in ((10.0, 141, 0.0, 0.0), (0.2, 141, 5.0, 0.0005)):
        step = side / count
        for i in range(count):
            for j in range(count):
                lines.append("%.7f %.7f %.7f" % (at + (i + rng.uniform(-0.3, 0.3)) * step,
                                                 at + (j + rng.uniform(-0.3, 0.3)) * step, z))
    cloud = tmp_path / "floor.xyz"
    cloud.write_text("\n".join(lines) + "\n")
    out = tmp_path / "floor.ply"
    report = tmp_path / "floor.json"
    proc = cli("triangulate", cloud, "-o", out, "--report", report)
    assert inspect(out)["vertices_used"] < 0.6 * len(lines), proc.stdout
    assert json.loads(report.read_text())["triangulation"]["capped_spacing_over_nn"] < 2
    assert "along lines" not in proc.stdout and "try --thin 2" not in proc.stdout, proc.stdout
    hint = re.search(r"sampled far sparser all round .* --thin ([0-9.]+) --global-spacing", proc.stdout)
    assert hint, proc.stdout
    cli("triangulate", cloud, "-o", out, "--thin", hint.group(1), "--global-spacing", "-q")
    mesh = inspect(out)
    assert mesh["components"] == 1 and mesh["manifold"], mesh
    # The thinning keeps the floor: nearly all of its particles, each in a triangle.
    assert mesh["vertices_used"] >= 0.95 * 141 * 141, mesh


def test_a_part_a_few_times_sparser_gets_the_factor_that_reaches_it(cli, inspect, tmp_path):
    """A sheet whose right part is sampled five times sparser all round (14 % of the
    particles): its local spacing lies past the 3 r0 cap and it is left in pieces. The hint
    says the part is sparser all round (not rows) and names a factor a few times the default,
    without the warning; with it every particle is in one piece, and the hint is not given
    again (the sheet's rim leaves a loop open)."""
    rng = random.Random(5)
    lines = []
    for x0, step, nx, ny in ((0.0, 0.01, 70, 70), (0.7, 0.05, 56, 14)):
        for i in range(nx):
            for j in range(ny):
                lines.append("%.7f %.7f 0" % (x0 + (i + 0.5 + rng.uniform(-0.3, 0.3)) * step,
                                              (j + 0.5 + rng.uniform(-0.3, 0.3)) * step))
    cloud = tmp_path / "sheet.xyz"
    cloud.write_text("\n".join(lines) + "\n")
    out = tmp_path / "sheet.ply"
    proc = cli("triangulate", cloud, "-o", out)
    assert inspect(out)["vertices_used"] < len(lines) - 300, proc.stdout
    hint = re.search(r"sampled sparser all round .* --max-edge-factor ([0-9.]+) may reach them$", proc.stdout, re.M)
    assert hint and 3 < float(hint.group(1)) < 6, proc.stdout
    assert "expect the run" not in proc.stdout and "along lines" not in proc.stdout
    proc = cli("triangulate", cloud, "-o", out, "--max-edge-factor", hint.group(1))
    mesh = inspect(out)
    assert mesh["vertices_used"] == len(lines) and mesh["components"] == 1 and mesh["manifold"], mesh
    assert "sparser all round" not in proc.stdout, proc.stdout
