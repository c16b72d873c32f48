"""Blender meshes from and to numpy arrays, in bulk (foreach_get / foreach_set; no per-vertex
Python), as io_mesh_ply does."""

import ctypes
import threading

import bpy
import numpy as np

from . import mesh_arrays
from . import particlemesh as pm

# Blender 4.0 made MeshPolygon.loop_total read-only (sizes follow from loop_start);
# 4.1 removed Mesh.use_auto_smooth (custom normals no longer need it).
_SET_LOOP_TOTAL = bpy.app.version < (4, 0, 0)

#: The POINT attribute holding particle normals on point-cloud meshes.
NORMAL_ATTRIBUTE = "point_normal"

#: Blender declares loop vertex indices, loop starts and totals, edge and loop-triangle
#: vertices as unsigned ints. foreach_get / foreach_set copy in bulk only when the buffer's
#: format matches the property's ('I' here); any other walks the array item by item as a
#: Python sequence, about ten times slower (bench/RESULTS.md).
INDEX = np.uint32

_ATTRIBUTE_TYPES = {1: ("FLOAT", "value"), 2: ("FLOAT2", "vector"), 3: ("FLOAT_VECTOR", "vector"),
                    4: ("FLOAT_COLOR", "color")}


def write(mesh, data, *, custom_normals=True, attributes=True, keep_arrays=False):
    """Replace the geometry of `mesh` with the particlemesh.Mesh `data`, in place.

    Materials stay (clear_geometry keeps them), faces are smooth shaded, the library's
    normals become custom split normals (unless they are the angle-weighted face normals
    Blender computes itself: data.stats["normals_are_face_weighted"]), and per-vertex
    channels (velocity, colour...) become POINT attributes named as in data.attributes. When
    the mesh already has exactly these triangles (live mode on a stable topology), only the
    vertices move. `keep_arrays`: the working arrays are kept for the next such write (live
    mode's frame after frame; see _kept)."""
    positions = _float32_positions(data.vertices, keep_arrays)
    triangles = np.ascontiguousarray(data.triangles, dtype=np.int32)
    nv, nt = len(positions), len(triangles)
    rebuild = not _same_triangles(mesh, nv, triangles)
    calc_edges = rebuild
    if not rebuild:
        mesh.vertices.foreach_set("co", positions.ravel())
    else:
        # The same bits as unsigned (the library's indices are >= 0): no copy for Blender's
        # unsigned corners or the library's edge numbering.
        corners = triangles.view(INDEX)
        # The library numbers the edges in a thread of its own (ctypes lets go of the GIL)
        # while Blender takes the vertices, corners and faces. Blender's own edge pass, which
        # update(calc_edges=True) runs, was most of the time of writing a mesh.
        out = _edge_buffers(nt) if keep_arrays else None
        edges = _InThread(pm.triangle_edges, corners, nv, 0, out) if nt else None
        loops = None  # the corners' (vertex, edge) fields, where written in bulk
        try:
            mesh.clear_geometry()
            mesh.vertices.add(nv)
            mesh.vertices.foreach_set("co", positions.ravel())
            if nt:
                mesh.loops.add(3 * nt)
                loops = _index_fields(mesh.loops, 3 * nt, _MLOOP_SIZE, _probe_loop)
                if loops is not None:
                    loops[:, 0] = corners.ravel()
                else:
                    mesh.loops.foreach_set("vertex_index", corners.ravel())
                mesh.polygons.add(nt)
                faces = _index_fields(mesh.polygons, nt, _MPOLY_SIZE, _probe_face)
                if faces is not None:
                    faces[:, 0] = mesh_arrays.loop_starts(nt)
                    faces[:, 1] = 3
                else:
                    mesh.polygons.foreach_set("loop_start", mesh_arrays.loop_starts(nt))
                    if _SET_LOOP_TOTAL:
                        mesh.polygons.foreach_set("loop_total", np.full(nt, 3, dtype=INDEX))
                shade_smooth(mesh)
        finally:
            if edges is not None:
                edges.join()
        if edges is not None:
            edge_vertices, corner_edges = edges.result()
            mesh.edges.add(len(edge_vertices))
            fields = _index_fields(mesh.edges, len(edge_vertices), _MEDGE_SIZE, _probe_edge)
            if fields is not None:
                fields[:, :2] = edge_vertices
            else:
                mesh.edges.foreach_set("vertices", edge_vertices.ravel())
            if loops is not None and mesh.loops[0].as_pointer() == loops.__array_interface__["data"][0]:
                loops[:, 1] = corner_edges
            else:
                mesh.loops.foreach_set("edge_index", corner_edges)
            calc_edges = False
    mesh.update(calc_edges=calc_edges)
    set_normals(mesh, data, custom_normals=custom_normals)
    if attributes:
        for name, values in data.attributes.items():
            set_point_attribute(mesh, name, values)
    return mesh


#: Arrays write() keeps from one mesh to the next, by name (see _kept).
_kept_arrays = {}

#: The most memory _kept holds: the arrays of a mesh of about 8M triangles.
_KEPT_BYTES = 300 << 20


def _kept(name, shape, dtype):
    """An uninitialised array of `shape` and `dtype`: a view of the one kept under `name` by
    the last write(keep_arrays=True), grown when too small. Live mode writes a new frame after frame, and
    fresh arrays of tens of MB come with fresh pages to fault in each time (the edge
    numbering's output arrays: a third of its time inside Blender). None (the caller
    allocates its own) where the kept arrays would pass _KEPT_BYTES; release_buffers() lets
    them go."""
    size = int(np.prod(shape))
    have = _kept_arrays.get(name)
    if have is None or have.dtype != dtype or have.size < size:
        _kept_arrays.pop(name, None)
        # An eighth more room: a live frame's counts grow a little from one frame to the next.
        room = size + size // 8
        used = sum(a.nbytes for a in _kept_arrays.values())
        if used + room * np.dtype(dtype).itemsize > _KEPT_BYTES:
            return None
        have = _kept_arrays[name] = np.empty(room, dtype=dtype)
    return have[:size].reshape(shape)


def _edge_buffers(nt):
    """pm.triangle_edges' out= arrays for nt triangles (or None)."""
    edges, corners = _kept("edges", (3 * nt, 2), INDEX), _kept("corners", (3 * nt,), INDEX)
    return None if edges is None or corners is None else (edges, corners)


def _float32_positions(vertices, keep):
    """The vertices as Blender takes them (float32), in a kept array where one fits (`keep`)."""
    vertices = np.asarray(vertices)
    out = _kept("positions", vertices.shape, np.float32) if keep and vertices.ndim == 2 else None
    if out is None:
        return np.ascontiguousarray(vertices, dtype=np.float32)
    np.copyto(out, vertices, casting="unsafe")
    return out


def release_buffers():
    """Let go of the arrays write() keeps from one mesh to the next (live mode calls it once
    no object's cache is left)."""
    _kept_arrays.clear()


def shade_smooth(mesh):
    """Every face of `mesh` smooth shaded. foreach_set("use_smooth") sets a bit of each face's
    flags one face at a time (no bulk path for bit flags): 0.1-0.2 s for 1.5M faces, the
    largest part of writing a big live frame (bench/RESULTS.md). Blender 4.1+ has
    Mesh.shade_smooth(); before 3.6 the faces are MPoly structs {loopstart, totloop, mat_nr,
    flag} in one array, whose smooth bits are set here in bulk where the layout is checked to
    be that one (stride, contiguity, the first and last faces' loop fields); anywhere else
    foreach_set."""
    nt = len(mesh.polygons)
    if nt == 0:
        return
    if hasattr(mesh, "shade_smooth"):
        mesh.shade_smooth()
        return
    flags = _mpoly_flags(mesh, nt) if bpy.app.version < (3, 6, 0) else None
    if flags is None:
        mesh.polygons.foreach_set("use_smooth", np.ones(nt, dtype=bool))
        return
    flags |= _ME_SMOOTH


#: MPoly (DNA_meshdata_types.h, Blender 2.8-3.5): int loopstart, int totloop, short mat_nr,
#: char flag, char _pad; ME_SMOOTH is bit 0 of flag.
_MPOLY_SIZE = 12
_MPOLY_FLAG = 10
_ME_SMOOTH = 1
#: MLoop: unsigned int v, e. MEdge: unsigned int v1, v2; char crease, bweight; short flag.
_MLOOP_SIZE = 8
_MEDGE_SIZE = 12


def _index_fields(collection, count, size, probe):
    """The index fields of the first `count` items of a mesh's corners, faces or edges, as a
    (count, size // 4) uint32 numpy view of their structs, for write() to fill in bulk: before
    Blender 3.6 they are arrays of MLoop, MPoly and MEdge structs, and foreach_set copies an
    index property item by item through RNA (20 ms for the 4.4M corners of a 1.47M-triangle
    frame, where numpy's strided copy takes 2). None where they are not laid out so: the
    items' addresses, and `probe(item, k)`, which sets distinct values through RNA on the first
    (k = 0) and last (k = 1) item and returns them, read back as the first fields."""
    if bpy.app.version >= (3, 6, 0) or count == 0:
        return None
    raw = _struct_rows(collection, count, size)
    if raw is None:
        return None
    fields = raw.view(np.uint32)
    for k, item in ((0, collection[0]), (1, collection[count - 1])):
        expected = probe(item, k)
        if tuple(int(x) for x in fields[0 if k == 0 else count - 1, :len(expected)]) != expected:
            return None
    return fields


def _struct_rows(collection, count, size):
    """The first `count` (> 0) items of `collection` as a (count, size) uint8 numpy view of
    their structs, or None where their addresses say they are not one array of `size`-byte
    structs (the first, second and last item checked)."""
    base = collection[0].as_pointer()
    if base == 0 or collection[count - 1].as_pointer() != base + size * (count - 1):
        return None
    if count > 1 and collection[1].as_pointer() != base + size:
        return None
    raw = np.ctypeslib.as_array((ctypes.c_uint8 * (size * count)).from_address(base))
    return raw.reshape(count, size)


def _probe_loop(loop, k):
    loop.vertex_index, loop.edge_index = 1 + k, 3 + k
    return (1 + k, 3 + k)


def _probe_face(face, k):
    face.loop_start, face.loop_total = 3 * k, 3
    return (3 * k, 3)


def _probe_edge(edge, k):
    edge.vertices = (1 + k, 3 + k)
    return (1 + k, 3 + k)


def _mpoly_flags(mesh, nt):
    """A numpy view of the flag bytes of the mesh's MPoly array, or None where the faces are
    not laid out as MPoly structs in one array (checked on the first and last faces)."""
    polygons = mesh.polygons
    raw = _struct_rows(polygons, nt, _MPOLY_SIZE)
    if raw is None:
        return None
    for index, face in ((0, polygons[0]), (nt - 1, polygons[nt - 1])):
        start, total = raw[index, :8].view(np.int32)
        if (start, total) != (face.loop_start, face.loop_total):
            return None
        if bool(raw[index, _MPOLY_FLAG] & _ME_SMOOTH) != face.use_smooth:
            return None
    return raw[:, _MPOLY_FLAG]


def has_custom_normals(data, custom_normals=True):
    """Whether write() gives a mesh of `data` the library's normals as custom split normals
    (what makes writing and evaluating a big mesh about four times slower)."""
    return bool(custom_normals and data.normals is not None and data.triangle_count
                and not data.stats.get("normals_are_face_weighted", False))


def set_normals(mesh, data, *, custom_normals=True):
    """The library's normals of `data` as the custom split normals of `mesh` (written from
    `data`), or Blender's own normals, as write() leaves them. Live mode calls it on its own
    to finish a frame first written with custom_normals=False."""
    if has_custom_normals(data, custom_normals):
        if hasattr(mesh, "use_auto_smooth"):
            mesh.use_auto_smooth = True
            mesh.auto_smooth_angle = np.pi
        mesh.normals_split_custom_set_from_vertices(np.asarray(data.normals, dtype=np.float64))
    else:
        _clear_custom_normals(mesh)
        if hasattr(mesh, "use_auto_smooth"):
            mesh.use_auto_smooth = False


class _InThread(threading.Thread):
    """fn(*args) run in a thread of its own; result() waits for it and returns its value or
    raises its exception."""

    def __init__(self, fn, *args):
        super().__init__(name="particlemesh", daemon=True)
        self._call = (fn, args)
        self._value = self._error = None
        self.start()

    def run(self):
        fn, args = self._call
        try:
            self._value = fn(*args)
        except BaseException as e:  # handed to the caller by result()
            self._error = e

    def result(self):
        self.join()
        if self._error is not None:
            raise self._error
        return self._value


def _same_triangles(mesh, nv, triangles):
    """Whether the mesh is made of exactly these triangles over nv vertices (cheap check)."""
    nt = len(triangles)
    if nt == 0 or len(mesh.vertices) != nv or len(mesh.polygons) != nt or len(mesh.loops) != 3 * nt:
        return False
    loops = np.empty(3 * nt, dtype=INDEX)
    mesh.loops.foreach_get("vertex_index", loops)
    return np.array_equal(loops, triangles.ravel())


def _clear_custom_normals(mesh):
    """Drop custom split normals without an operator (mesh.customdata_custom_splitnormals_clear
    needs a context)."""
    if mesh.has_custom_normals:
        mesh.normals_split_custom_set_from_vertices(
            np.zeros((len(mesh.vertices), 3), dtype=np.float64))


def set_point_attribute(mesh, name, values):
    """Write (V, C) values as a POINT attribute: FLOAT, FLOAT2, FLOAT_VECTOR or FLOAT_COLOR by
    C; a one-component `id` (simulators' particle ids) becomes Blender's own integer `id`
    attribute, which its name reserves. None when Blender refuses the name or C."""
    values = np.ascontiguousarray(values, dtype=np.float32).reshape(len(mesh.vertices), -1)
    kind, field = _ATTRIBUTE_TYPES.get(values.shape[1], (None, None))
    if name == "id" and values.shape[1] == 1:
        kind, field = "INT", "value"
        values = np.rint(values).astype(np.int32)
    if kind is None:
        return None
    attribute = mesh.attributes.get(name)
    if attribute is not None and (attribute.data_type != kind or attribute.domain != "POINT"):
        mesh.attributes.remove(attribute)
        attribute = None
    if attribute is None:
        attribute = mesh.attributes.new(name, kind, "POINT")
        if attribute is None:  # a name Blender reserves for another type
            return None
    attribute.data.foreach_set(field, values.ravel())
    return attribute


def get_point_attribute(mesh, name):
    """(V, C) float32 values of a float POINT attribute, or None."""
    attribute = mesh.attributes.get(name)
    if attribute is None or attribute.domain != "POINT":
        return None
    for components, (kind, field) in _ATTRIBUTE_TYPES.items():
        if attribute.data_type == kind:
            out = np.empty(len(mesh.vertices) * components, dtype=np.float32)
            attribute.data.foreach_get(field, out)
            return out.reshape(-1, components)
    return None


def float_point_attributes(mesh, skip=()):
    """Every float POINT attribute of the mesh (user channels to carry through smoothing)."""
    out = {}
    for attribute in mesh.attributes:
        if attribute.name in skip or attribute.name.startswith(".") or attribute.name == "position":
            continue
        values = get_point_attribute(mesh, attribute.name)
        if values is not None:
            out[attribute.name] = values
    return out


def positions(mesh):
    out = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)


def triangles(mesh):
    """The mesh's triangles (F, 3) int32: its own faces when all are triangles, else Blender's
    tessellation (loop_triangles) of its polygons."""
    return triangle_corners(mesh)[0]


def triangle_corners(mesh):
    """(triangles (F, 3) int32, loops (F, 3) int64, polygon (F,) int64): triangles() with
    each corner's loop and each triangle's polygon (what belongs to a face or a corner)."""
    polys = len(mesh.polygons)
    if polys == 0:
        return np.zeros((0, 3), dtype=np.int32), np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64)
    sizes = np.empty(polys, dtype=INDEX)
    mesh.polygons.foreach_get("loop_total", sizes)
    if np.all(sizes == 3):
        corners = np.empty(len(mesh.loops), dtype=INDEX)
        mesh.loops.foreach_get("vertex_index", corners)
        starts = np.empty(polys, dtype=INDEX)
        mesh.polygons.foreach_get("loop_start", starts)
        loops = starts.astype(np.int64)[:, None] + np.arange(3)
        return corners[loops].astype(np.int32), loops, np.arange(polys, dtype=np.int64)
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    out = np.empty(n * 3, dtype=INDEX)
    mesh.loop_triangles.foreach_get("vertices", out)
    loops = np.empty(n * 3, dtype=INDEX)
    mesh.loop_triangles.foreach_get("loops", loops)
    polygon = np.empty(n, dtype=np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", polygon)
    return (out.reshape(-1, 3).astype(np.int32), loops.reshape(-1, 3).astype(np.int64),
            polygon.astype(np.int64))


def vertex_normals(mesh):
    out = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    if hasattr(mesh, "vertex_normals"):
        mesh.vertex_normals.foreach_get("vector", out)
    else:
        mesh.vertices.foreach_get("normal", out)
    return out.reshape(-1, 3)


def new_point_cloud_mesh(name, positions, normals=None, colors=None, attributes=None):
    """A vertex-only mesh: particles as vertices, normals as the `point_normal` POINT attribute
    (Blender reserves `normal`), colours as the `Col` colour attribute (RGBA float)."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(positions, dtype=np.float32).ravel())
    if normals is not None:
        set_point_attribute(mesh, NORMAL_ATTRIBUTE, normals)
    if colors is not None:
        c = np.asarray(colors, dtype=np.float32).reshape(len(positions), -1)
        if c.shape[1] == 3:
            c = np.concatenate([c, np.ones((len(c), 1), np.float32)], axis=1)
        set_point_attribute(mesh, "Col", c)
    for name_, values in (attributes or {}).items():
        set_point_attribute(mesh, name_, values)
    mesh.update()
    return mesh
