#!/usr/bin/env python3
"""Regenerate docs/anisotropic_kernels.png: SPH frames rendered by `particlemesh render` with
spherical kernels (left) and anisotropic kernels (right), side by side.

    docs/make_anisotropic_figure.py [--cli build/cli/particlemesh] [--data ../shared/data]
                                    [--out docs/anisotropic_kernels.png]

The frames are ../shared/data/particles/double_dam_break_frame_26_4732_particles.ply (top) and
bunny_frame_14_7705_particles.ply (bottom), SPlisHSPlasH, particle radius r = 0.025. Every
render uses splashsurf's support R = 4r = 0.1; the spherical ones splashsurf's iso level,
T = 0.6 x the rest level (`--threshold 4`), the anisotropic ones their default, calibrated
threshold (`--anisotropic`). Both of a pair take the spherical render's default camera, moved
in (FRAMES), so they show the same view. Standard library only (the PNGs are read and written here).
"""
import argparse
import re
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def read_png(path):
    """(width, height, rows of RGB bytes) of an 8-bit RGB PNG (any filter, not interlaced)."""
    data = path.read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise SystemExit(f"{path}: not a PNG")
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if (depth, colour, interlace) != (8, 2, 0):
                raise SystemExit(f"{path}: only 8-bit RGB, non-interlaced PNGs are read")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride, rows, prev = 3 * w, [], bytearray(3 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b, c = prev[x], prev[x - 3] if x >= 3 else 0
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
    return w, h, rows


def write_png(path, w, h, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff)
    raw = b"".join(b"\0" + r for r in rows)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                     chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def render(cli, frame, out, *args):
    proc = subprocess.run([str(cli), "render", str(frame), "-o", str(out), "--width", "480", "--height", "360",
                           "--radius", "0.1", *args], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr)
    return proc.stdout


# (frame, how far in to move the default camera): a splashy frame with a thin film on the
# floor, and a bulk of fluid.
FRAMES = [("double_dam_break_frame_26_4732_particles.ply", 0.75), ("bunny_frame_14_7705_particles.ply", 0.6)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", default=ROOT / "build/cli/particlemesh", type=Path)
    ap.add_argument("--data", default=ROOT.parent / "shared/data", type=Path)
    ap.add_argument("--out", default=ROOT / "docs/anisotropic_kernels.png", type=Path)
    a = ap.parse_args()
    rows = []
    gap = bytes([255, 255, 255]) * 8
    with tempfile.TemporaryDirectory() as tmp:
        for name, zoom in FRAMES:
            frame = a.data / "particles" / name
            if not frame.exists():
                raise SystemExit(f"{frame} not found (give --data, the shared data folder)")
            left, right = Path(tmp) / "spherical.png", Path(tmp) / "anisotropic.png"
            # The spherical render's default camera (it frames every particle's support,
            # splashes included), moved in.
            summary = render(a.cli, frame, left, "--threshold", "4")
            m = re.search(r"eye (\S+) (\S+) (\S+)\s+target (\S+) (\S+) (\S+)", summary)
            eye, target = [float(v) for v in m.groups()[:3]], [float(v) for v in m.groups()[3:]]
            eye = [t + zoom * (e - t) for e, t in zip(eye, target)]
            camera = ",".join("%.6g" % v for v in eye + target)
            render(a.cli, frame, left, "--threshold", "4", "--camera", camera)
            render(a.cli, frame, right, "--anisotropic", "--camera", camera)
            w1, h1, r1 = read_png(left)
            w2, h2, r2 = read_png(right)
            if rows:
                rows += [bytes([255, 255, 255]) * (w1 + 8 + w2)] * 8
            rows += [x + gap + y for x, y in zip(r1, r2)]
            print(f"{name}: camera {camera}")
    write_png(a.out, w1 + 8 + w2, len(rows), rows)
    print(f"{a.out}: spherical (left) and anisotropic (right) kernels")


if __name__ == "__main__":
    sys.exit(main())
