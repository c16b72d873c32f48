"""Writers of simulators' particle files for the tests: the same particles as PLY, VTK legacy
(ASCII, BINARY), VTK XML .vtu (ascii, base64, raw appended, zlib) and Houdini's classic bgeo
(plain, gzip). Values are multiples of 1/1024 so that every text form is exact in float32."""

import base64
import gzip
import struct
import zlib

import numpy as np


def particles(frame=0, n=6, seed=1):
    """A small block of n^3 particles (spacing 1/16, jittered on a 1/1024 grid) moving along x
    with frame, carrying velocity (3) and density (1)."""
    rng = np.random.default_rng(seed + frame)
    g = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
    p = g / 16.0 + rng.integers(-8, 9, size=g.shape) / 1024.0 + np.array([frame / 64.0, 0, 0])
    v = np.round(np.column_stack([np.sin(p[:, 1] * 9), p[:, 0], -p[:, 2]]) * 1024) / 1024
    d = np.round((1000 + 10 * p[:, 2]) * 64) / 64
    return p.astype(np.float32), {"velocity": v.astype(np.float32), "density": d.astype(np.float32)}


def write_ply(path, p, attrs):
    cols = [p]
    props = ["x", "y", "z"]
    for name, a in attrs.items():
        a = a.reshape(len(p), -1)
        cols.append(a)
        props += [name] if a.shape[1] == 1 else [f"{name}_{c}" for c in range(a.shape[1])]
    data = np.hstack(cols).astype("<f4")
    head = "ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(p)
    head += "".join(f"property float {q}\n" for q in props) + "end_header\n"
    with open(path, "wb") as f:
        f.write(head.encode() + data.tobytes())


def write_vtk(path, p, attrs, binary=False):
    n = len(p)
    out = [b"# vtk DataFile Version 3.0\nparticles\n" + (b"BINARY\n" if binary else b"ASCII\n")]
    out.append(b"DATASET POLYDATA\nPOINTS %d float\n" % n)

    def block(a):
        if binary:
            return a.astype(">f4").tobytes() + b"\n"
        return ("\n".join(" ".join(repr(float(x)) for x in row) for row in a.reshape(n, -1)) + "\n").encode()

    out.append(block(p))
    out.append(b"VERTICES %d %d\n" % (n, 2 * n))
    cells = np.column_stack([np.ones(n, np.int32), np.arange(n, dtype=np.int32)])
    out.append(cells.astype(">i4").tobytes() + b"\n" if binary else
               ("\n".join(f"1 {i}" for i in range(n)) + "\n").encode())
    out.append(b"POINT_DATA %d\n" % n)
    for name, a in attrs.items():
        a = a.reshape(n, -1)
        if a.shape[1] == 3:
            out.append(b"VECTORS %s float\n" % name.encode())
        else:
            out.append(b"SCALARS %s float %d\nLOOKUP_TABLE default\n" % (name.encode(), a.shape[1]))
        out.append(block(a))
    with open(path, "wb") as f:
        f.write(b"".join(out))


def write_vtu(path, p, attrs, encoding="ascii"):
    """encoding: ascii, base64, appended (raw), zlib (base64, compressed)."""
    n = len(p)
    arrays = [("Points", p)] + list(attrs.items())
    appended = b""

    def data_array(name, a):
        nonlocal appended
        a = a.reshape(n, -1).astype("<f4")
        comps = a.shape[1]
        head = f'<DataArray type="Float32" Name="{name}" NumberOfComponents="{comps}"'
        raw = a.tobytes()
        if encoding == "ascii":
            return head + ' format="ascii">' + " ".join(repr(float(x)) for x in a.ravel()) + "</DataArray>\n"
        if encoding == "base64":
            return head + ' format="binary">' + base64.b64encode(struct.pack("<I", len(raw)) + raw).decode() + \
                "</DataArray>\n"
        if encoding == "zlib":
            z = zlib.compress(raw)
            header = struct.pack("<4I", 1, len(raw), len(raw), len(z))
            return head + ' format="binary">' + base64.b64encode(header).decode() + \
                base64.b64encode(z).decode() + "</DataArray>\n"
        offset = len(appended)
        appended += struct.pack("<I", len(raw)) + raw
        return head + f' format="appended" offset="{offset}"/>\n'

    points = data_array("Points", arrays[0][1])
    pdata = "".join(data_array(name, a) for name, a in arrays[1:])
    conn = " ".join(str(i) for i in range(n))
    offs = " ".join(str(i + 1) for i in range(n))
    types = " ".join("1" for _ in range(n))
    comp = ' compressor="vtkZLibDataCompressor"' if encoding == "zlib" else ""
    text = (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            f'byte_order="LittleEndian" header_type="UInt32"{comp}>\n<UnstructuredGrid>\n'
            f'<Piece NumberOfPoints="{n}" NumberOfCells="{n}">\n<PointData>\n{pdata}</PointData>\n'
            f'<Points>\n{points}</Points>\n<Cells>\n'
            f'<DataArray type="Int32" Name="connectivity" format="ascii">{conn}</DataArray>\n'
            f'<DataArray type="Int32" Name="offsets" format="ascii">{offs}</DataArray>\n'
            f'<DataArray type="UInt8" Name="types" format="ascii">{types}</DataArray>\n'
            '</Cells>\n</Piece>\n</UnstructuredGrid>\n')
    data = text.encode()
    if encoding == "appended":
        data += b'<AppendedData encoding="raw">\n_' + appended + b"\n</AppendedData>\n"
    data += b"</VTKFile>\n"
    with open(path, "wb") as f:
        f.write(data)


def write_bgeo(path, p, attrs, compress=False):
    """Classic bgeo ("BgeoV" 5), as Partio writes it: points, no primitives, 00 ff."""
    n = len(p)
    out = [b"BgeoV", struct.pack(">9i", 5, n, 0, 0, 0, len(attrs), 0, 0, 0)]
    cols = [p.reshape(n, 3), np.ones((n, 1), np.float32)]
    for name, a in attrs.items():
        a = a.reshape(n, -1)
        size = a.shape[1]
        out.append(struct.pack(">H", len(name)) + name.encode() + struct.pack(">Hi", size, 5 if size == 3 else 0))
        out.append(b"\0" * (4 * size))
        cols.append(a)
    out.append(np.hstack(cols).astype(">f4").tobytes())
    out.append(b"\x00\xff")
    data = b"".join(out)
    with open(path, "wb") as f:
        f.write(gzip.compress(data, mtime=0) if compress else data)


#: Every form the tests write: (file name suffix, writer).
FORMATS = {
    ".ply": write_ply,
    ".vtk": write_vtk,
    ".binary.vtk": lambda path, p, a: write_vtk(path, p, a, binary=True),
    ".vtu": write_vtu,
    ".base64.vtu": lambda path, p, a: write_vtu(path, p, a, "base64"),
    ".appended.vtu": lambda path, p, a: write_vtu(path, p, a, "appended"),
    ".zlib.vtu": lambda path, p, a: write_vtu(path, p, a, "zlib"),
    ".bgeo": write_bgeo,
    ".bgeo.gz": lambda path, p, a: write_bgeo(path, p, a, compress=True),
}


def read_ascii_ply(path):
    """(positions (V, 3), {property: (V,)}, faces (F, 3)) of an ASCII PLY mesh."""
    with open(path) as f:
        lines = f.read().split("\n")
    props, nv, nf, i = [], 0, 0, 0
    while lines[i] != "end_header":
        w = lines[i].split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif w[0] == "property" and w[1] != "list":
            props.append(w[2])
        i += 1
    rows = np.array([[float(x) for x in lines[i + 1 + k].split()] for k in range(nv)]).reshape(nv, len(props))
    faces = np.array([[int(x) for x in lines[i + 1 + nv + k].split()[1:]] for k in range(nf)]).reshape(nf, 3)
    cols = {q: rows[:, j] for j, q in enumerate(props)}
    return np.column_stack([cols["x"], cols["y"], cols["z"]]), cols, faces
