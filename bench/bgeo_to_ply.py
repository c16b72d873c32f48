#!/usr/bin/env python3
"""Particle positions of a Houdini classic .bgeo file ("BgeoV", version 5, gzip or not) as a
binary PLY (x y z float32), for the benchmarks: the CLI and the library read .ply and .xyz, and
the larger SPH frames of ../shared/data/particles come as .bgeo only.

    bench/bgeo_to_ply.py ../shared/data/particles/octocat_32614_particles.bgeo build/octocat.ply

Only points are read (primitives, groups and the rest of the file are ignored); point attributes
are skipped. Standard library only.
"""
import gzip
import struct
import sys


def read_points(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:2] == b"\x1f\x8b":
        data = gzip.decompress(data)
    if data[:5] != b"BgeoV":
        raise SystemExit(f"{path}: not a classic bgeo file (no BgeoV magic)")
    (version,) = struct.unpack_from(">i", data, 5)
    if version != 5:
        raise SystemExit(f"{path}: bgeo version {version}, only 5 is read")
    npoints, _prims, _pgroups, _primgroups, npattr, _vattr, _primattr, _attr = struct.unpack_from(">8i", data, 9)
    off = 41
    floats_per_point = 4  # x y z w
    for _ in range(npattr):
        (nlen,) = struct.unpack_from(">H", data, off)
        off += 2 + nlen
        size, _type = struct.unpack_from(">Hi", data, off)
        off += 6 + 4 * size  # the default values
        floats_per_point += size
    stride = 4 * floats_per_point
    if off + npoints * stride > len(data):
        raise SystemExit(f"{path}: truncated ({npoints} points of {stride} bytes do not fit)")
    return [struct.unpack_from(">3f", data, off + i * stride) for i in range(npoints)]


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    pts = read_points(sys.argv[1])
    header = ("ply\nformat binary_little_endian 1.0\ncomment from %s\nelement vertex %d\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n") % (sys.argv[1].split("/")[-1], len(pts))
    with open(sys.argv[2], "wb") as f:
        f.write(header.encode("ascii"))
        f.write(b"".join(struct.pack("<3f", *p) for p in pts))
    print(f"{sys.argv[2]}: {len(pts)} particles")


if __name__ == "__main__":
    main()
