"""Files written by VTK's own writers (Debian's python3-vtk9: the writers ParaView and the
simulators call), read by read_points and read_mesh: every XML data mode and encoding, each
of ParaView's compressors (zlib, LZ4, LZMA), both header types and byte orders, several
compressed blocks per array, and the legacy ASCII and binary files. Every value must come
back exactly; a damaged compressed block is refused naming the file and the codec."""
import re

import numpy as np
import pytest
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

# 12 000 points: 144 000 bytes of Float32 positions, five of VTK's 32 KiB compressed blocks.
N = 12000


def cloud():
    rng = np.random.default_rng(7)
    p = rng.normal(size=(N, 3)) * [1.0, 2.0, 0.5] + [10.0, -3.0, 0.25]
    density = rng.uniform(900.0, 1100.0, N)
    velocity = rng.normal(size=(N, 3))
    return p.astype(np.float32), density.astype(np.float64), velocity.astype(np.float32)


def point_set(kind):
    """The particles as a vtkUnstructuredGrid of vertex cells or a vtkPolyData of vertices,
    with two point-data arrays (Float64 and Float32)."""
    p, density, velocity = cloud()
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(p, deep=True))
    data = vtk.vtkUnstructuredGrid() if kind == "grid" else vtk.vtkPolyData()
    data.SetPoints(pts)
    verts = vtk.vtkCellArray()
    for i in range(N):
        verts.InsertNextCell(1)
        verts.InsertCellPoint(i)
    if kind == "grid":
        data.SetCells(vtk.VTK_VERTEX, verts)
    else:
        data.SetVerts(verts)
    for name, values in (("density", density), ("velocity", velocity)):
        a = numpy_to_vtk(values, deep=True)
        a.SetName(name)
        data.GetPointData().AddArray(a)
    return data


XML_WRITERS = {"grid": (vtk.vtkXMLUnstructuredGridWriter, ".vtu"), "poly": (vtk.vtkXMLPolyDataWriter, ".vtp")}
# (data mode, appended data base64-encoded)
MODES = [("Ascii", False), ("Binary", False), ("Appended", False), ("Appended", True)]
COMPRESSORS = ["None", "ZLib", "LZ4", "LZMA"]


def write_xml(path, data, kind, mode, encode, compressor, header64=False, big_endian=False):
    cls, _ = XML_WRITERS[kind]
    w = cls()
    w.SetInputData(data)
    w.SetFileName(str(path))
    getattr(w, "SetDataModeTo" + mode)()
    w.SetEncodeAppendedData(encode)
    getattr(w, "SetCompressorTypeTo" + compressor)()
    if header64:
        w.SetHeaderTypeToUInt64()
    if big_endian:
        w.SetByteOrderToBigEndian()
    assert w.Write() == 1, path
    return path


def check_points(pm, path, rtol=0.0):
    """The positions exactly (or to `rtol`), the channels as the library keeps them (float32)."""
    p, density, velocity = cloud()
    c = pm.read_points(path)
    assert c.positions.shape == (N, 3), path
    np.testing.assert_allclose(c.positions, p.astype(np.float64), rtol=rtol, atol=0, err_msg=str(path))
    assert set(c.attributes) == {"density", "velocity"}, path
    np.testing.assert_allclose(c.attributes["density"].ravel(), density.astype(np.float32), rtol=rtol, atol=0,
                               err_msg=str(path))
    np.testing.assert_allclose(c.attributes["velocity"].reshape(N, 3), velocity, rtol=rtol, atol=1e-6 * (rtol > 0),
                               err_msg=str(path))


@pytest.mark.parametrize("kind", ["grid", "poly"])
def test_every_xml_mode_and_compressor_reads_exactly(pm, tmp_path, kind):
    data = point_set(kind)
    ext = XML_WRITERS[kind][1]
    for mode, encode in MODES:
        for compressor in COMPRESSORS:
            if mode == "Ascii" and compressor != "None":
                continue  # VTK writes ASCII arrays uncompressed whatever the compressor
            path = tmp_path / f"{mode}{'64' if encode else ''}_{compressor}{ext}"
            check_points(pm, write_xml(path, data, kind, mode, encode, compressor))
    # UInt64 headers and big-endian values, with each compressor.
    for compressor in COMPRESSORS:
        check_points(pm, write_xml(tmp_path / f"h64_{compressor}{ext}", data, kind, "Appended", False, compressor,
                                   header64=True))
        check_points(pm, write_xml(tmp_path / f"be_{compressor}{ext}", data, kind, "Binary", False, compressor,
                                   big_endian=True))


def test_legacy_ascii_and_binary(pm, tmp_path):
    for kind, cls in (("grid", vtk.vtkUnstructuredGridWriter), ("poly", vtk.vtkPolyDataWriter)):
        for binary in (False, True):
            path = tmp_path / f"{kind}_{'binary' if binary else 'ascii'}.vtk"
            w = cls()
            w.SetInputData(point_set(kind))
            w.SetFileName(str(path))
            w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
            assert w.Write() == 1
            # VTK's legacy ASCII writer prints 6 significant digits.
            check_points(pm, path, rtol=0 if binary else 5e-6)


def test_compressed_meshes_keep_their_triangles(pm, tmp_path):
    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(80)
    sphere.SetPhiResolution(60)
    sphere.Update()
    poly = sphere.GetOutput()
    points = vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
    tris = vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    for compressor in ("LZ4", "LZMA"):
        path = write_xml(tmp_path / f"sphere_{compressor}.vtp", poly, "poly", "Appended", False, compressor)
        m = pm.read_mesh(path)
        np.testing.assert_array_equal(m.vertices, points)
        np.testing.assert_array_equal(m.triangles, tris)
        assert m.triangle_count == poly.GetNumberOfPolys() == 9280


def damage(path, marker, offset_in_block):
    """Flip a byte `offset_in_block` bytes into the first compressed block of the first raw
    appended array (after its header of 4 UInt32 words for a single block)."""
    raw = bytearray(path.read_bytes())
    start = raw.index(b'<AppendedData encoding="raw">')
    at = raw.index(b"_", start) + 1
    blocks = int.from_bytes(raw[at:at + 4], "little")
    data = at + 4 * (3 + blocks)
    raw[data + offset_in_block] ^= marker
    path.write_bytes(bytes(raw))


def test_damaged_compressed_blocks_are_refused_by_name(pm, tmp_path):
    data = point_set("grid")
    lz4 = write_xml(tmp_path / "lz4.vtu", data, "grid", "Appended", False, "LZ4")
    damage(lz4, 0xFF, 0)  # the first token: its literal run now overruns the block
    with pytest.raises(pm.Error, match=r"lz4\.vtu.*block 0: the LZ4 data is corrupt") as e:
        pm.read_points(lz4)
    assert e.value.status_name == "format error"

    xz = write_xml(tmp_path / "xz.vtu", data, "grid", "Appended", False, "LZMA")
    damage(xz, 0x01, 0)  # the .xz magic bytes
    with pytest.raises(pm.Error, match=r"xz\.vtu.*block 0: the xz data is corrupt \(it does not start"):
        pm.read_points(xz)
    xz = write_xml(tmp_path / "xz2.vtu", data, "grid", "Appended", False, "LZMA")
    damage(xz, 0x40, 200)  # inside the compressed data: the stream's check fails
    with pytest.raises(pm.Error, match=r"xz2\.vtu.*block 0: the xz data is corrupt"):
        pm.read_points(xz)

    other = tmp_path / "other.vtu"
    text = write_xml(tmp_path / "z.vtu", data, "grid", "Appended", False, "ZLib").read_bytes()
    other.write_bytes(text.replace(b"vtkZLibDataCompressor", b"vtkZstdDataCompressor"))
    with pytest.raises(pm.Error, match=r"compressor 'vtkZstdDataCompressor' is not read \(read: vtkZLib"):
        pm.read_points(other)


def vtk_read(path):
    """Positions and density as VTK's own reader for the file's kind gives them."""
    reader = {".pvtu": vtk.vtkXMLPUnstructuredGridReader, ".pvtp": vtk.vtkXMLPPolyDataReader}[path.suffix]()
    reader.SetFileName(str(path))
    reader.Update()
    out = reader.GetOutput()
    return (vtk_to_numpy(out.GetPoints().GetData()).astype(np.float64),
            vtk_to_numpy(out.GetPointData().GetArray("density")).astype(np.float32))


@pytest.mark.parametrize("kind", ["grid", "poly"])
def test_parallel_files_read_their_pieces(pm, tmp_path, kind):
    """A .pvtu / .pvtp from VTK's parallel writers (three pieces in a subfolder, as ParaView
    writes them for three processes, LZ4-compressed) gives the points VTK's parallel reader
    gives, in its order."""
    data = point_set(kind)
    if kind == "grid":
        split = vtk.vtkExtractUnstructuredGridPiece()
        writer, ext = vtk.vtkXMLPUnstructuredGridWriter(), ".pvtu"
    else:
        split = vtk.vtkExtractPolyDataPiece()
        writer, ext = vtk.vtkXMLPPolyDataWriter(), ".pvtp"
    split.SetInputData(data)
    path = tmp_path / f"sim{ext}"
    writer.SetInputConnection(split.GetOutputPort())
    writer.SetFileName(str(path))
    writer.SetNumberOfPieces(3)
    writer.SetStartPiece(0)
    writer.SetEndPiece(2)
    writer.SetUseSubdirectory(True)
    writer.SetCompressorTypeToLZ4()
    assert writer.Write() == 1
    assert len(list((tmp_path / "sim").iterdir())) == 3
    positions, density = vtk_read(path)
    assert len(positions) >= N
    c = pm.read_points(path)
    np.testing.assert_array_equal(c.positions, positions)
    np.testing.assert_array_equal(c.attributes["density"].ravel(), density)
    assert set(c.attributes) == {"density", "velocity"}


def test_parallel_file_pieces_stay_inside_its_folder(pm, tmp_path):
    data = point_set("grid")
    write_xml(tmp_path / "a.vtu", data, "grid", "Appended", False, "None")
    write_xml(tmp_path / "b.vtp", point_set("poly"), "poly", "Appended", False, "None")
    (tmp_path / "sub").mkdir()
    write_xml(tmp_path / "sub" / "c.vtu", data, "grid", "Appended", False, "ZLib")

    def pvtu(name, *sources):
        pieces = "".join(f'<Piece Source="{s}"/>' for s in sources)
        path = tmp_path / name
        path.write_text('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1">'
                        f"<PUnstructuredGrid>{pieces}</PUnstructuredGrid></VTKFile>\n")
        return path

    two = pm.read_points(pvtu("two.pvtu", "a.vtu", "sub\\c.vtu"))  # a Windows separator too
    assert two.positions.shape == (2 * N, 3)
    np.testing.assert_array_equal(two.positions[:N], two.positions[N:])
    for name, sources, message in [
            ("abs.pvtu", ["/etc/passwd"], "piece 0's Source '/etc/passwd' is not a path inside"),
            ("up.pvtu", ["a.vtu", "sub/../../x.vtu"], "piece 1's Source 'sub/../../x.vtu' is not a path inside"),
            ("upw.pvtu", ["a.vtu", "..\\x.vtu"], "piece 1's Source '..\\x.vtu' is not a path inside"),
            ("twice.pvtu", ["a.vtu", "sub/c.vtu", "a.vtu"], "piece 2 repeats the Source 'a.vtu'"),
            ("missing.pvtu", ["a.vtu", "gone.vtu"], "piece 1's Source 'gone.vtu' does not exist"),
            ("folder.pvtu", ["sub"], "piece 0's Source 'sub' is not a regular file"),
            ("kind.pvtu", ["b.vtp"], "b.vtp': VTKFile type 'PolyData', but the parallel file"),
            ("nested.pvtu", ["two.pvtu"], "two.pvtu': a piece of a parallel file is itself a parallel file"),
            ("none.pvtu", [], "lists no <Piece Source"),
    ]:
        with pytest.raises(pm.Error, match=re.escape(message)) as e:
            pm.read_points(pvtu(name, *sources))
        assert e.value.status_name == "format error", name


def test_legacy_files_read_as_vtks_own_reader_reads_them(pm, tmp_path):
    """Active unsigned-char scalars (which VTK writes as COLOR_SCALARS: a type id or an RGB
    colour), bit arrays and string arrays, as vtkPolyDataWriter / vtkUnstructuredGridWriter
    write them in ASCII and BINARY: every numeric array comes back as vtkDataReader gives it
    (unsigned chars 0..255, bits 0 / 1), string arrays (per point and the data set's own) are
    skipped (the per-point one named in info["not_read"]), and the particles are read."""
    n = 13  # bits: not a whole number of bytes
    rng = np.random.default_rng(3)
    p = rng.normal(size=(n, 3)).astype(np.float32)
    for kind, cls in (("grid", vtk.vtkUnstructuredGridWriter), ("poly", vtk.vtkPolyDataWriter)):
        for active in ("type", "Colors"):
            data = vtk.vtkUnstructuredGrid() if kind == "grid" else vtk.vtkPolyData()
            pts = vtk.vtkPoints()
            pts.SetData(numpy_to_vtk(p, deep=True))
            data.SetPoints(pts)
            comps = 1 if active == "type" else 3
            scalars = numpy_to_vtk(rng.integers(0, 256, size=(n, comps)).astype(np.uint8), deep=True,
                                   array_type=vtk.VTK_UNSIGNED_CHAR)
            scalars.SetName(active)
            data.GetPointData().SetScalars(scalars)
            label = vtk.vtkStringArray()
            label.SetName("label")
            for i in range(n):  # empty, escaped and long (2-byte binary lengths) values
                label.InsertNextValue("" if i % 4 == 0 else f"p {i}\t%" * (i * 9))
            data.GetPointData().AddArray(label)
            flag = vtk.vtkBitArray()
            flag.SetName("flag")
            for i in range(n):
                flag.InsertNextValue(int(i % 3 == 1))
            data.GetPointData().AddArray(flag)
            density = numpy_to_vtk(rng.uniform(900, 1100, n), deep=True)
            density.SetName("density")
            data.GetPointData().AddArray(density)
            case = vtk.vtkStringArray()
            case.SetName("CaseName")
            case.InsertNextValue("dam break")
            field = vtk.vtkFieldData()
            field.AddArray(case)
            data.SetFieldData(field)
            for binary in (False, True):
                path = tmp_path / f"{kind}_{active}_{'binary' if binary else 'ascii'}.vtk"
                w = cls()
                w.SetInputData(data)
                w.SetFileName(str(path))
                w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
                assert w.Write() == 1
                text = path.read_bytes()
                assert b"COLOR_SCALARS" in text and b" bit" in text and b" string" in text, path
                reader = vtk.vtkUnstructuredGridReader() if kind == "grid" else vtk.vtkPolyDataReader()
                reader.SetFileName(str(path))
                reader.Update()
                theirs = reader.GetOutput().GetPointData()
                with pytest.warns(pm.NotReadWarning, match="'label'"):
                    c = pm.read_points(path)
                np.testing.assert_allclose(c.positions, p.astype(np.float64), rtol=0 if binary else 5e-6,
                                           err_msg=str(path))
                assert set(c.attributes) == {active, "flag", "density"}, path
                # The string array per point is named; the data set's own FIELD (CaseName) is not per point.
                assert c.info["not_read"] == ["POINT_DATA FIELD array 'label' (strings)"], path
                for name in (active, "flag"):
                    a = theirs.GetAbstractArray(name)
                    values = [a.GetValue(i) for i in range(a.GetNumberOfValues())]
                    np.testing.assert_array_equal(c.attributes[name].ravel(), np.array(values, np.float32),
                                                  err_msg=f"{path} {name}")
                ours = c.attributes["density"].ravel()
                np.testing.assert_allclose(ours, vtk_to_numpy(theirs.GetArray("density")).astype(np.float32),
                                           rtol=0 if binary else 5e-6, err_msg=str(path))


@pytest.mark.parametrize("kind", ["grid", "poly"])
def test_bit_arrays_in_every_xml_mode(pm, tmp_path, kind):
    """A vtkBitArray per point (a flag) comes back as 0 / 1 in every data mode and with every
    compressor, as VTK's own XML reader gives it; a string array beside it is skipped and named."""
    data = point_set(kind)
    flag = vtk.vtkBitArray()
    flag.SetName("flag")
    flag.SetNumberOfComponents(2)
    expected = [int((i * 7) % 5 < 2) for i in range(2 * N)]
    for v in expected:
        flag.InsertNextValue(v)
    data.GetPointData().AddArray(flag)
    label = vtk.vtkStringArray()
    label.SetName("label")
    for i in range(N):
        label.InsertNextValue(f"particle {i}")
    data.GetPointData().AddArray(label)
    ext = XML_WRITERS[kind][1]
    for mode, encode in MODES:
        for compressor in COMPRESSORS:
            if mode == "Ascii" and compressor != "None":
                continue
            path = write_xml(tmp_path / f"{mode}{'64' if encode else ''}_{compressor}{ext}", data, kind, mode, encode,
                             compressor)
            reader = vtk.vtkXMLUnstructuredGridReader() if kind == "grid" else vtk.vtkXMLPolyDataReader()
            reader.SetFileName(str(path))
            reader.Update()
            theirs = reader.GetOutput().GetPointData().GetAbstractArray("flag")
            assert [theirs.GetValue(i) for i in range(2 * N)] == expected, path
            with pytest.warns(pm.NotReadWarning, match="PointData array 'label'"):
                c = pm.read_points(path)
            assert set(c.attributes) == {"density", "velocity", "flag"}, path
            assert c.info["not_read"] == ["PointData array 'label' (strings)"], path
            np.testing.assert_array_equal(c.attributes["flag"].reshape(N, 2).ravel(), np.array(expected, np.float32),
                                          err_msg=str(path))
