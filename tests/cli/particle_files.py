"""Writers of simulators' particle files for the tests: the same particles as PLY, VTK legacy
(ASCII, BINARY), VTK XML .vtu (ascii, base64, raw appended, zlib, LZMA) and parallel .pvtu
(pieces in a folder beside it), Krakatoa's .prt, ASPRS LAS, Houdini's classic bgeo
(plain, gzip) and Houdini 12+'s binary-JSON bgeo (paged, tuples and arrays layouts, either
byte order, token strings, constant pages, gzip), ASCII .geo, each also as Houdini's
Blosc-compressed .sc (write_sc), and text columns (ParaView's CSV
export, a .txt with a header line). Values are multiples of 1/1024 so that every text form is exact in float32."""

import base64
import gzip
import json
import lzma
import struct
import zlib
from pathlib import Path

import numpy as np


def fibonacci_sphere(n):
    """n points of the unit sphere along the Fibonacci spiral: an even surface sampling."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = i * np.pi * (3 - np.sqrt(5))
    ring = np.sqrt(1 - z * z)
    return np.c_[ring * np.cos(phi), ring * np.sin(phi), z]


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
    """encoding: ascii, base64, appended (raw), zlib or lzma (base64, compressed as
    vtkZLibDataCompressor / vtkLZMADataCompressor write)."""
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
        if encoding in ("zlib", "lzma"):
            z = zlib.compress(raw) if encoding == "zlib" else lzma.compress(raw, check=lzma.CHECK_CRC64)
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
    comp = {"zlib": ' compressor="vtkZLibDataCompressor"',
            "lzma": ' compressor="vtkLZMADataCompressor"'}.get(encoding, "")
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


def write_pvtu(path, p, attrs, pieces=3):
    """A parallel .pvtu listing `pieces` raw appended .vtu files (the particles split in order)
    in a folder beside it, as ParaView writes one piece per process."""
    path = Path(path)
    folder = path.parent / path.name.split(".")[0]
    folder.mkdir(exist_ok=True)
    sources = []
    for k, rows in enumerate(np.array_split(np.arange(len(p)), pieces)):
        piece = folder / f"{folder.name}_{k}.vtu"
        write_vtu(piece, p[rows], {name: a.reshape(len(p), -1)[rows] for name, a in attrs.items()}, "appended")
        sources.append(f"{folder.name}/{piece.name}")
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0" '
                    'byte_order="LittleEndian" header_type="UInt32">\n<PUnstructuredGrid GhostLevel="0">\n' +
                    "".join(f'<Piece Source="{s}"/>\n' for s in sources) + "</PUnstructuredGrid>\n</VTKFile>\n")


def write_prt(path, p, attrs, half_velocity=False):
    """Krakatoa's .prt: Position float32[3], Velocity float32[3] (or float16[3]), Density
    float32, one zlib stream of the records (as Partio and Krakatoa write it)."""
    n = len(p)
    channels = [("Position", 4, 3, p.reshape(n, 3).astype("<f4"))]
    for name, a in attrs.items():
        a = a.reshape(n, -1)
        half = half_velocity and name == "velocity"
        channels.append((name.capitalize(), 3 if half else 4, a.shape[1], a.astype("<f2" if half else "<f4")))
    defs, offset = [], 0
    for name, code, arity, a in channels:
        defs.append(name.encode().ljust(32, b"\0") + struct.pack("<3i", code, arity, offset))
        offset += a.itemsize * arity
    records = np.zeros(n, dtype=[(f"c{k}", c[3].dtype, (c[2],)) for k, c in enumerate(channels)])
    for k, c in enumerate(channels):
        records[f"c{k}"] = c[3]
    header = (bytes([0xC0]) + b"PRT\r\n\x1a\n" + struct.pack("<i", 56) + b"Extensible Particle Format".ljust(32, b"\0")
              + struct.pack("<iq", 1, n) + struct.pack("<3i", 4, len(channels), 44))
    with open(path, "wb") as f:
        f.write(header + b"".join(defs) + zlib.compress(records.tobytes()))


def write_las(path, p, intensity, rgb=None, point_format=2, minor=2, extra_bytes=0, vlr=b"", laz=False,
              scale=1 / 1024):
    """An ASPRS LAS file (1.2 or 1.4 header), point format 0-3 or 6-8, with a VLR and extra
    bytes per record if asked; coordinates as integers of `scale`."""
    n = len(p)
    layouts = {0: (20, 0), 1: (28, 0), 2: (26, 20), 3: (34, 28), 6: (30, 0), 7: (36, 30), 8: (38, 30)}
    size, colour_at = layouts[point_format]
    record = size + extra_bytes
    header_size = 375 if minor >= 4 else 227
    vlrs = b""
    if vlr:
        vlrs = struct.pack("<H16sHH32s", 0, b"particlemesh", 1, len(vlr), b"test record") + vlr
    offset = header_size + len(vlrs)
    lo, hi = p.min(axis=0), p.max(axis=0)
    h = bytearray(header_size)
    h[0:4] = b"LASF"
    h[24], h[25] = 1, minor
    struct.pack_into("<HIIBHI", h, 94, header_size, offset, 1 if vlr else 0, point_format | (0x80 if laz else 0),
                     record, n if minor < 4 or point_format < 6 else 0)
    struct.pack_into("<3d3d6d", h, 131, scale, scale, scale, 0.0, 0.0, 0.0, hi[0], lo[0], hi[1], lo[1], hi[2], lo[2])
    if minor >= 4:
        struct.pack_into("<Q", h, 247, n)
    recs = bytearray(n * record)
    q = np.round(np.asarray(p, np.float64) / scale).astype("<i4")
    for i in range(n):
        at = i * record
        struct.pack_into("<3iH", recs, at, *q[i], int(intensity[i]))
        if point_format >= 6:
            recs[at + 16] = 2  # classification: ground
        else:
            recs[at + 15] = 2
        if colour_at:
            struct.pack_into("<3H", recs, at + colour_at, *(int(c) for c in rgb[i]))
    with open(path, "wb") as f:
        f.write(bytes(h) + vlrs + bytes(recs))


def write_bgeo(path, p, attrs, compress=False, names=None):
    """Classic bgeo ("BgeoV" 5), as Partio writes it: points, no primitives, 00 ff. `names`
    (a list of strings): also an index (string) attribute "name", point i taking names[i % len]."""
    n = len(p)
    out = [b"BgeoV", struct.pack(">9i", 5, n, 0, 0, 0, len(attrs) + bool(names), 0, 0, 0)]
    cols = [p.reshape(n, 3).astype(">f4").view(">u4"), np.ones((n, 1), ">f4").view(">u4")]
    if names:
        out.append(struct.pack(">H", 4) + b"name" + struct.pack(">Hii", 1, 4, len(names)))
        out.extend(struct.pack(">H", len(t)) + t.encode() for t in names)
        cols.append((np.arange(n) % len(names)).astype(">u4").reshape(n, 1))
    for name, a in attrs.items():
        a = a.reshape(n, -1)
        size = a.shape[1]
        out.append(struct.pack(">H", len(name)) + name.encode() + struct.pack(">Hi", size, 5 if size == 3 else 0))
        out.append(b"\0" * (4 * size))
        cols.append(a.astype(">f4").view(">u4"))
    out.append(np.hstack(cols).astype(">u4").tobytes())
    out.append(b"\x00\xff")
    data = b"".join(out)
    with open(path, "wb") as f:
        f.write(gzip.compress(data, mtime=0) if compress else data)


def write_geo_classic(path, p, attrs, compress=False, names=None):
    """Classic ASCII .geo ("PGEOMETRY V5"), as Partio writes it: the points with their
    attributes in parentheses, one particle-system primitive, an empty extra block. Values as
    the shortest text of their float32 (read back exactly). `names`: also an index (string)
    attribute "name", first, point i taking names[i % len]."""
    n = len(p)
    cols = [a.reshape(n, -1) for a in attrs.values()]
    text = [f"PGEOMETRY V5\nNPoints {n} NPrims 1\nNPointGroups 0 NPrimGroups 0\n"
            f"NPointAttrib {len(attrs) + bool(names)} NVertexAttrib 0 NPrimAttrib 1 NAttrib 0\nPointAttrib\n"]
    if names:
        text.append(f"name 1 index {len(names)} " + " ".join(names) + "\n")
    for name, c in zip(attrs, cols):
        kind = "vector" if c.shape[1] == 3 else "float"
        text.append(f"{name} {c.shape[1]} {kind} " + " ".join(["0"] * c.shape[1]) + "\n")

    def num(x):
        return repr(float(np.float32(x)))
    for i in range(n):
        values = " ".join(([str(i % len(names))] if names else []) + [num(x) for c in cols for x in c[i]])
        text.append(" ".join(num(x) for x in p[i]) + " 1" + (f" ({values})" if cols else "") + "\n")
    text.append("PrimitiveAttrib\ngenerator 1 index 1 papi\nPart " + str(n) + " " +
                " ".join(str(i) for i in range(n)) + " [0]\nbeginExtra\nendExtra\n")
    data = "".join(text).encode()
    with open(path, "wb") as f:
        f.write(gzip.compress(data, mtime=0) if compress else data)


def _length(n, e):
    """Binary JSON's encoded length (UT_JSONDefines.h)."""
    if n < 0xF1:
        return bytes([n])
    if n < 1 << 16:
        return b"\xf2" + struct.pack(e + "H", n)
    if n < 1 << 32:
        return b"\xf4" + struct.pack(e + "I", n)
    return b"\xf8" + struct.pack(e + "q", n)


class _BinaryJson:
    """Houdini's binary JSON, token by token."""

    def __init__(self, big, tokens):
        self.e = ">" if big else "<"
        self.out = [b"\x7f" + (b"bJSN" if big else b"NSJb")]
        self.tokens = {} if tokens else None

    def string(self, text):
        raw = text.encode()
        if self.tokens is None:
            self.out.append(b"\x27" + _length(len(raw), self.e) + raw)
            return
        if text not in self.tokens:  # defined on first use, then referenced
            self.tokens[text] = len(self.tokens)
            self.out.append(b"\x2b" + _length(self.tokens[text], self.e) + _length(len(raw), self.e) + raw)
        self.out.append(b"\x26" + _length(self.tokens[text], self.e))

    def value(self, v):
        if isinstance(v, str):
            self.string(v)
        elif isinstance(v, bool):
            self.out.append(b"\x31" if v else b"\x30")
        elif isinstance(v, int):
            self.out.append(b"\x13" + struct.pack(self.e + "i", v))
        elif isinstance(v, float):
            self.out.append(b"\x1a" + struct.pack(self.e + "d", v))
        elif isinstance(v, dict):
            self.out.append(b"{")
            for k, x in v.items():
                self.string(k)
                self.value(x)
            self.out.append(b"}")
        elif isinstance(v, np.ndarray):  # a uniform array
            if v.dtype == bool:
                words = np.zeros((len(v) + 31) // 32, dtype=np.uint32)
                for i, flag in enumerate(v):
                    words[i // 32] |= np.uint32(int(flag) << (i % 32))
                self.out.append(b"\x40\x10" + _length(len(v), self.e) + words.astype(self.e + "u4").tobytes())
            else:
                code = {"f4": b"\x19", "f8": b"\x1a", "i4": b"\x13"}[v.dtype.str[1:]]
                self.out.append(b"\x40" + code + _length(len(v), self.e) + v.astype(self.e + v.dtype.str[1:]).tobytes())
        else:  # a list
            self.out.append(b"[")
            for x in v:
                self.value(x)
            self.out.append(b"]")


def _paged(a, page, packing):
    """An attribute's values as "rawpagedata": page by page, sub-vector by sub-vector, a page's
    sub-vector stored once where it is constant (what Houdini writes)."""
    n, width = a.shape
    pages = (n + page - 1) // page
    flags = [np.zeros(pages, dtype=bool) for _ in packing]
    raw = []
    for pg in range(pages):
        c0 = 0
        for k, w in enumerate(packing):
            block = a[pg * page:(pg + 1) * page, c0:c0 + w]
            if len(block) > 1 and (block == block[0]).all():
                flags[k][pg] = True
                raw.append(block[0])
            else:
                raw.append(block.ravel())
            c0 += w
    data = np.concatenate(raw).astype(np.float32) if raw else np.zeros(0, np.float32)
    values = ["size", width, "storage", "fpreal32", "packing", list(packing), "pagesize", page]
    if any(f.any() for f in flags):
        values += ["constantpageflags", [f if f.any() else np.zeros(0, dtype=bool) for f in flags]]
    return values + ["rawpagedata", data]


def write_bgeo_json(path, p, attrs, big=False, tokens=True, layout="paged", page=1024, compress=False,
                    ascii=False):
    """Houdini 12+'s binary-JSON bgeo (`ascii`: its text .geo) of the particles: P and each channel as a numeric point
    attribute in `layout` ("paged": rawpagedata, vectors packed [1, 2] when page < 1024;
    "tuples"; "arrays" for one-value channels, tuples otherwise), plus a string attribute
    and an info map that a reader must walk past."""
    n = len(p)
    channels = {"P": p.reshape(n, 3)}
    channels.update({name: a.reshape(n, -1) for name, a in attrs.items()})
    entries = []
    for name, a in channels.items():
        width = a.shape[1]
        if layout == "paged":
            values = _paged(a, page, [width] if page >= 1024 or width == 1 else [1, width - 1])
        elif layout == "arrays" and width == 1:
            values = ["size", 1, "storage", "fpreal32", "arrays", [a[:, 0].astype(np.float32)]]
        else:
            values = ["size", width, "storage", "fpreal32", "tuples", [row.astype(np.float32) for row in a]]
        definition = ["scope", "public", "type", "numeric", "name", name, "options", {}]
        entries.append([definition, ["size", width, "storage", "fpreal32",
                                     "defaults", ["size", 1, "storage", "fpreal64", "values", [0.0]],
                                     "values", values]])
    entries.append([["scope", "public", "type", "string", "name", "name"],
                    ["size", 1, "storage", "int32", "strings", ["fluid"],
                     "indices", ["size", 1, "storage", "int32", "arrays", [np.zeros(n, dtype="i4")]]]])
    doc = ["fileversion", "19.5.303", "hasindex", False, "pointcount", n, "vertexcount", 0,
           "primitivecount", 0, "info", {"software": "particlemesh tests", "bounds": [0.0, 1.0]},
           "topology", ["pointref", ["indices", np.zeros(0, dtype="i4")]],
           "attributes", ["pointattributes", entries], "primitives", []]
    if ascii:  # Houdini's ASCII .geo: the same document as text JSON
        def plain(v):
            if isinstance(v, np.ndarray):
                return [bool(x) for x in v] if v.dtype == bool else [float(x) if v.dtype.kind == "f" else int(x) for x in v]
            if isinstance(v, list):
                return [plain(x) for x in v]
            if isinstance(v, dict):
                return {k: plain(x) for k, x in v.items()}
            return v
        data = json.dumps(plain(doc), indent=1).encode()
    else:
        w = _BinaryJson(big, tokens)
        w.value(doc)
        data = b"".join(w.out)
    with open(path, "wb") as f:
        f.write(gzip.compress(data, mtime=0) if compress else data)


def scf(data, block=65536, cname="lz4", metadata=b""):
    """`data` in SideFX's SCF container, as Houdini writes a .bgeo.sc: "scf1", the metadata's
    length and the metadata, Blosc chunks of `block` bytes (level 9, byte shuffle on 4-byte
    items), the seek index (each chunk's end but the last's, relative to the first chunk; the
    chunk size; the last chunk's size) and its length (big-endian uint64s), "1fcs"."""
    import blosc  # Debian's python3-blosc (the set-up installs it)
    chunks = [blosc.compress(data[i:i + block], typesize=4, clevel=9, shuffle=blosc.SHUFFLE, cname=cname)
              for i in range(0, len(data), block)]
    ends = np.cumsum([len(c) for c in chunks])[:-1]
    index = b"".join(struct.pack(">Q", int(e)) for e in ends)
    index += struct.pack(">QQ", block, len(data) - (len(chunks) - 1) * block)
    return (b"scf1" + struct.pack(">Q", len(metadata)) + metadata + b"".join(chunks) + index
            + struct.pack(">Q", len(index)) + b"1fcs")


def write_sc(writer, **scf_options):
    """A writer of the same file wrapped in SCF (Houdini's .bgeo.sc, .geo.sc)."""
    def write(path, p, attrs):
        writer(path, p, attrs)
        Path(path).write_bytes(scf(Path(path).read_bytes(), **scf_options))
    return write


def write_csv(path, p, attrs, style="paraview"):
    """Text columns as ParaView's CSV export writes them (quoted names, a vector's components
    as "name:k", the points last) or as a whitespace .txt names them ("x y z vx vy vz ...")."""
    cols, names = [], []
    if style == "paraview":
        for name, a in attrs.items():
            a = a.reshape(len(p), -1)
            cols.append(a)
            names += [f'"{name}:{k}"' for k in range(a.shape[1])] if a.shape[1] > 1 else [f'"{name}"']
        cols.append(p.reshape(-1, 3))
        names += ['"Points:0"', '"Points:1"', '"Points:2"']
        sep = ","
    else:
        cols.append(p.reshape(-1, 3))
        names += ["x", "y", "z"]
        for name, a in attrs.items():
            a = a.reshape(len(p), -1)
            cols.append(a)
            names += ["vx", "vy", "vz"] if name == "velocity" else [name]
        sep = " "
    table = np.hstack([c.astype(np.float64) for c in cols])
    with open(path, "w") as f:
        f.write(sep.join(names) + "\n")
        for row in table:
            f.write(sep.join(repr(float(v)) for v in row) + "\n")


#: Every form the tests write: (file name suffix, writer).
FORMATS = {
    ".ply": write_ply,
    ".vtk": write_vtk,
    ".binary.vtk": lambda path, p, a: write_vtk(path, p, a, binary=True),
    ".vtu": write_vtu,
    ".base64.vtu": lambda path, p, a: write_vtu(path, p, a, "base64"),
    ".appended.vtu": lambda path, p, a: write_vtu(path, p, a, "appended"),
    ".zlib.vtu": lambda path, p, a: write_vtu(path, p, a, "zlib"),
    ".lzma.vtu": lambda path, p, a: write_vtu(path, p, a, "lzma"),
    ".pvtu": write_pvtu,
    ".prt": write_prt,
    ".half.prt": lambda path, p, a: write_prt(path, p, a, half_velocity=True),
    ".bgeo": write_bgeo,
    ".bgeo.gz": lambda path, p, a: write_bgeo(path, p, a, compress=True),
    ".json.bgeo": write_bgeo_json,
    ".json-big-endian-pages.bgeo": lambda path, p, a: write_bgeo_json(path, p, a, big=True, page=50),
    ".json-tuples.bgeo.gz": lambda path, p, a: write_bgeo_json(path, p, a, tokens=False, layout="tuples",
                                                                compress=True),
    ".json-arrays.bgeo": lambda path, p, a: write_bgeo_json(path, p, a, layout="arrays"),
    ".geo": lambda path, p, a: write_bgeo_json(path, p, a, page=50, ascii=True),
    ".tuples.geo.gz": lambda path, p, a: write_bgeo_json(path, p, a, layout="tuples", ascii=True, compress=True),
    ".bgeo.sc": write_sc(write_bgeo),
    ".json.bgeo.sc": write_sc(write_bgeo_json, block=1000, cname="zstd", metadata=b'{"compression": "blosc"}'),
    ".geo.sc": write_sc(lambda path, p, a: write_bgeo_json(path, p, a, ascii=True), block=4096, cname="blosclz"),
    ".classic.geo": write_geo_classic,
    ".classic.geo.gz": lambda path, p, a: write_geo_classic(path, p, a, compress=True),
    ".csv": write_csv,
    ".txt": lambda path, p, a: write_csv(path, p, a, style="columns"),
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
