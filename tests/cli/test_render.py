"""particlemesh render, end to end through the binary."""
import struct
import zlib
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parent.parent / "data"
SCENE = DATA / "render_scene.xyz"
REFERENCE = DATA / "render_scene_reference.png"


def read_png(path):
    """Decode an 8-bit RGB, non-interlaced PNG (what the renderer writes): width, height, rows."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, colour, interlace) == (8, 2, 0)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride, bpp, rows, prev = 3 * width, 3, [], bytearray(3 * width)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, rows


def test_scene_matches_the_reference_image(cli, tmp_path):
    out = tmp_path / "scene.png"
    proc = cli("render", SCENE, "-o", out, "--radius", "0.8", "--threshold", "0.5", "--width", "160", "--height", "120")
    assert "pixels on the surface" in proc.stdout and "default framing" in proc.stdout
    w, h, rows = read_png(out)
    rw, rh, ref = read_png(REFERENCE)
    assert (w, h) == (rw, rh) == (160, 120)
    diffs = [abs(p - q) for r1, r2 in zip(rows, ref) for p, q in zip(r1, r2)]
    assert sum(d > 12 for d in diffs) <= len(diffs) // 200
    assert sum(diffs) / len(diffs) < 0.5


def test_options_are_used_and_threads_do_not_matter(cli, tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    common = ["--radius", "0.8", "--threshold", "0.4", "--kernel", "poly4", "--width", "64", "--height", "48",
              "--camera", "0,6,0.01,0,0,0", "--up", "0,0,1", "--fov", "50", "--shading", "normal", "-q"]
    assert cli("render", SCENE, "-o", a, "--threads", "1", *common).stdout == ""
    cli("render", SCENE, "-o", b, "--threads", "2", *common)
    assert a.read_bytes() == b.read_bytes()
    w, h, rows = read_png(a)
    assert (w, h) == (64, 48)
    # Seen from straight above with normal shading: the middle shows the top of the stack,
    # whose normal is +y: green (y + 1) / 2 near 255.
    r, g, bl = rows[24][3 * 32:3 * 32 + 3]
    assert g > 230 and abs(r - 128) < 40
    assert rows[0][:3] == rows[47][-3:]  # background in the corners


def test_default_size_and_sph_frame(cli, data_dir, tmp_path):
    out = tmp_path / "cube.png"
    proc = cli("render", data_dir / "particles" / "cube_2366_particles.ply", "-o", out)
    assert "default: 2 x spacing)" in proc.stdout  # a lattice: 2 x its spacing
    w, h, rows = read_png(out)
    assert (w, h) == (640, 480)
    background = rows[0][:3]
    lit = sum(row[x:x + 3] != background for row in rows for x in range(0, 3 * w, 3))
    assert lit > 0.05 * w * h


def test_errors_are_one_line_and_leave_no_file(cli, tmp_path):
    out = tmp_path / "x.png"
    proc = cli("render", tmp_path / "missing.xyz", "-o", out, check=False)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1 and "missing.xyz" in proc.stderr
    proc = cli("render", SCENE, "-o", out, "--camera", "1,2,3", check=False)
    assert proc.returncode == 2
    proc = cli("render", SCENE, "-o", out, "--radius", "0.8", "--camera", "0,0,0,0,0,0", check=False)
    assert proc.returncode == 1 and "eye and target coincide" in proc.stderr
    # An output folder that does not exist is a usage error, found before any work.
    proc = cli("render", SCENE, "-o", tmp_path / "no" / "dir" / "x.png", "--radius", "0.8", "--width", "8",
               "--height", "8", check=False)
    assert proc.returncode == 2 and "does not exist" in proc.stderr
    assert not out.exists()


def test_anisotropic_render(cli, data_dir, tmp_path):
    frame = data_dir / "particles" / "double_dam_break_frame_26_4732_particles.ply"
    a, b, iso = tmp_path / "a.png", tmp_path / "b.png", tmp_path / "iso.png"
    common = ["--width", "96", "--height", "72", "-q"]
    cli("render", frame, "-o", a, "--anisotropic", "--threads", "1", *common)
    cli("render", frame, "-o", b, "--anisotropic", "--threads", "2", *common)
    assert a.read_bytes() == b.read_bytes()
    cli("render", frame, "-o", iso, *common)
    assert a.read_bytes() != iso.read_bytes()
    w, h, rows = read_png(a)
    background = rows[0][:3]
    lit = sum(row[x:x + 3] != background for row in rows for x in range(0, 3 * w, 3))
    assert lit > 0.05 * w * h
    proc = cli("render", frame, "-o", a, "--anisotropic", *common[:-1])
    assert "anisotropic" in proc.stdout and "got an ellipsoid" in proc.stdout
    proc = cli("render", frame, "-o", a, "--anisotropic", "--aniso-max-stretch", "200", *common, check=False)
    assert proc.returncode == 2


def test_particles_left_outside_the_surface_are_said(cli, tmp_path):
    """As polygonize: irregular particles (uniform random points) get a default radius from
    their packing; at 2 x their median nearest-neighbour distance most of them are left outside
    the surface, which the render shows as scattered blobs: said, with the radius their packing
    suggests; at that radius, not."""
    import random
    rng = random.Random(3)
    pts = tmp_path / "random.xyz"
    pts.write_text("".join("%.9g %.9g %.9g\n" % (rng.random(), rng.random(), rng.random()) for _ in range(3000)))
    out = tmp_path / "r.png"
    proc = cli("render", pts, "-o", out, "--width", "64", "--height", "48")
    assert "warning" not in proc.stderr and "from how densely the particles are packed" in proc.stdout
    default, ratio = proc.stdout.split("radius R")[1].split()[0:3:2]  # "R (default: X x spacing, ..."
    assert 2.5 < float(ratio) < 4
    # At 2 x spacing: warned.
    two_spacings = 2 * float(default) / float(ratio)
    proc = cli("render", pts, "-o", out, "--width", "64", "--height", "48", "-q", "--radius", repr(two_spacings))
    assert "render: warning: the surface encloses only" in proc.stderr and "triangulate" not in proc.stderr
    radius = proc.stderr.split("--radius ")[1].split()[0]
    proc = cli("render", pts, "-o", out, "--width", "64", "--height", "48", "-q", "--radius", radius)
    assert "warning" not in proc.stderr
    # Far larger than the packing asks for: said too.
    proc = cli("render", pts, "-o", out, "--width", "64", "--height", "48", "-q", "--radius", "%g" % (4 * float(radius)))
    assert "render: warning: the radius R = %g is large for how densely the particles are packed" % (
        4 * float(radius)) in proc.stderr
