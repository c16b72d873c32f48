"""Meshes and particles as numpy arrays, and their way in and out of the library's handles
(pm_cloud, pm_mesh): one copy in, none out for meshes (their arrays are the library's,
lent), no per-point Python."""

import ctypes
import os
from ctypes import POINTER, c_char_p, c_double, c_float, c_int32, c_size_t, c_uint32, c_void_p

import numpy as np

from . import _abi
from ._errors import Error


def _invalid(message):
    return Error(message, _abi.PM_STATUS_INVALID_ARGUMENT)


def vec3(array, name, dtype=np.float64):
    """A C-contiguous (N, 3) array of `dtype` from (N, 3) or flat (3N,) input; a copy only
    when needed."""
    a = np.asarray(array)
    if a.ndim == 1:
        if a.size % 3:
            raise _invalid(f"{name} has {a.size} values, not a multiple of 3")
        a = a.reshape(-1, 3)
    if a.ndim != 2 or a.shape[1] != 3:
        raise _invalid(f"{name} must have shape (N, 3), got {a.shape}")
    if a.dtype.kind not in "fiu":
        raise _invalid(f"{name} must hold numbers, not {a.dtype}")
    return np.ascontiguousarray(a, dtype=dtype)


def per_point(array, name, count, dtype=np.float64):
    """A C-contiguous (count,) array (one value per point), or None."""
    if array is None:
        return None
    a = np.ascontiguousarray(np.asarray(array, dtype=dtype).reshape(-1))
    if len(a) != count:
        raise _invalid(f"{name} has {len(a)} values for {count} points")
    return a


def channels(values, name, count):
    """An attribute as C-contiguous (count, C) float32."""
    a = np.asarray(values, dtype=np.float32)
    if a.ndim == 1:
        a = a.reshape(-1, 1)
    if a.ndim != 2 or a.shape[0] != count:
        raise _invalid(f"attribute '{name}' has shape {a.shape}; it needs {count} rows "
                       "(one per point, up to 4096 components)")
    return np.ascontiguousarray(a)


def corner_values(values, name, triangles):
    """A corner attribute as C-contiguous (T, 3, C) float32 from (T, 3, C), (T, 3) (one
    component) or (3T, C)."""
    a = np.asarray(values, dtype=np.float32)
    if a.ndim == 2 and a.shape == (triangles, 3):
        a = a.reshape(triangles, 3, 1)
    elif a.ndim == 2 and a.shape[0] == 3 * triangles:
        a = a.reshape(triangles, 3, -1)
    if a.ndim != 3 or a.shape[:2] != (triangles, 3):
        raise _invalid(f"corner attribute '{name}' has shape {a.shape}; it needs ({triangles}, 3, C): "
                       "one row of C values per triangle corner")
    return np.ascontiguousarray(a)


def vertex_indices(array, name, columns, dtype=np.int32, rows="T", item=("triangle", "corner")):
    """A C-contiguous (N, columns) array of `dtype` vertex indices: `rows` names N in messages,
    `item` what a row and a column are (a triangle and its corners, an edge and its ends).
    Checked before the conversion so that an error names the value the caller passed: numpy
    would wrap -1 to 4294967295 in an unsigned array and 2^32 to 0 in any 32-bit one, and
    the library would then name, or accept, the wrapped value."""
    a = np.asarray(array)
    if a.ndim != 2 or a.shape[1] != columns:
        raise _invalid(f"{name} must have shape ({rows}, {columns}), got {a.shape}")
    if a.dtype.kind not in "iu":
        raise _invalid(f"{name} must hold integer vertex indices, not {a.dtype}")
    limits = np.iinfo(dtype)
    if a.size and a.dtype != dtype and (a.min() < limits.min or a.max() > limits.max):
        i, j = (int(k[0]) for k in np.nonzero((a < limits.min) | (a > limits.max)))
        v = int(a[i, j])
        why = "negative" if v < 0 else f"beyond the largest index {limits.max}"
        raise _invalid(f"{item[0]} {i} {item[1]} {j} ({name}[{i}][{j}]) has vertex index {v}, "
                       f"which is {why}")
    return np.ascontiguousarray(a, dtype=dtype)


def ptr(array, ctype):
    return array.ctypes.data_as(POINTER(ctype)) if array is not None else None


class Points:
    """Particles: `positions` (N, 3) float64, `normals` (N, 3) float64 or None, `attributes`
    {name: (N, C) float32} (a PLY file's vertex colours: "color", (N, 3) in [0, 1]; a .pcd's
    rgb as "color" and intensity as "intensity"), `info` (dict; for .pcd files what was read
    and dropped, e.g. invalid_points)."""

    __slots__ = ("positions", "normals", "attributes", "info")

    def __init__(self, positions, normals=None, attributes=None, info=None):
        self.positions = positions
        self.normals = normals
        self.attributes = attributes if attributes is not None else {}
        self.info = info if info is not None else {}

    def __len__(self):
        return len(self.positions)

    def __repr__(self):
        extra = ", normals" if self.normals is not None else ""
        if self.attributes:
            extra += ", attributes " + ", ".join(self.attributes)
        return f"<particlemesh.Points {len(self.positions)} points{extra}>"


class Mesh:
    """A triangle mesh: `vertices` (V, 3) float64, `triangles` (T, 3) int32 vertex indices
    (counter-clockwise seen from outside where the mesh is oriented), `normals` (V, 3) float64
    or None, `attributes` {name: (V, C) float32} per-vertex channels, `stats` (dict: what the
    call that made it measured; empty for a mesh made here, and for one read_mesh read but for
    "not_read", the lines naming what the file held that the mesh does not carry), and
    `corner_attributes` {name: (T, 3, C) float32} values per triangle corner (face-varying:
    "uv", texture coordinates, from an OBJ's vt or a PLY's texcoord lists; smooth() carries
    them, linear over each input triangle, and write_mesh writes "uv" to .obj and .ply)."""

    __slots__ = ("vertices", "triangles", "normals", "attributes", "stats", "corner_attributes")

    def __init__(self, vertices, triangles, normals=None, attributes=None, stats=None, corner_attributes=None):
        self.vertices = vertices
        self.triangles = triangles
        self.normals = normals
        self.attributes = attributes if attributes is not None else {}
        self.stats = stats if stats is not None else {}
        self.corner_attributes = corner_attributes if corner_attributes is not None else {}

    @property
    def vertex_count(self):
        return len(self.vertices)

    @property
    def triangle_count(self):
        return len(self.triangles)

    @property
    def nbytes(self):
        """Bytes held by the arrays."""
        arrays = [self.vertices, self.triangles, self.normals, *self.attributes.values(),
                  *self.corner_attributes.values()]
        return sum(np.asarray(a).nbytes for a in arrays if a is not None)

    def __repr__(self):
        extra = ", normals" if self.normals is not None else ""
        if self.attributes:
            extra += ", attributes " + ", ".join(self.attributes)
        if self.corner_attributes:
            extra += ", corner attributes " + ", ".join(self.corner_attributes)
        return (f"<particlemesh.Mesh {self.vertex_count} vertices, {self.triangle_count} "
                f"triangles{extra}>")


# ---- handles in -----------------------------------------------------------------------------

def new_cloud(lib, positions, normals=None, attributes=None):
    """A pm_cloud handle from numpy arrays (float32 input crosses as float32, anything else as
    float64). The caller destroys it."""
    a = np.asarray(positions)
    single = a.dtype == np.float32 and (normals is None or np.asarray(normals).dtype == np.float32)
    dtype, ctype = (np.float32, c_float) if single else (np.float64, c_double)
    p = vec3(a, "positions", dtype)
    n = vec3(normals, "normals", dtype) if normals is not None else None
    if n is not None and len(n) != len(p):
        raise _invalid(f"normals has {len(n)} rows but positions has {len(p)}")
    create = lib.pm_cloud_create_f32 if single else lib.pm_cloud_create
    handle = _abi.pm_cloud_p()
    lib.check(create(ptr(p, ctype), ptr(n, ctype), len(p), ctypes.byref(handle)))
    try:
        for name, values in (attributes or {}).items():
            v = channels(values, name, len(p))
            lib.check(lib.pm_cloud_set_attribute(handle, name.encode(), v.shape[1],
                                                 ptr(v, c_float), len(p)))
    except BaseException:
        lib.pm_cloud_destroy(handle)
        raise
    return handle


def mesh_parts(mesh):
    """(vertices, triangles, normals, attributes) of a Mesh or anything with .vertices and
    .triangles."""
    try:
        vertices, triangles = mesh.vertices, mesh.triangles
    except AttributeError:
        raise TypeError("expected a particlemesh.Mesh (an object with .vertices and .triangles), "
                        f"not {type(mesh).__name__!r}") from None
    return vertices, triangles, getattr(mesh, "normals", None), getattr(mesh, "attributes", None)


def new_mesh(lib, mesh, with_attributes=True, with_corner_attributes=None):
    """A pm_mesh handle from a Mesh (its attributes and corner attributes with
    with_attributes, or the corner attributes as with_corner_attributes says). The caller
    destroys it."""
    vertices, triangles, normals, attributes = mesh_parts(mesh)
    v = vec3(vertices, "vertices")
    t = np.asarray(triangles)
    if t.ndim == 1 and t.size % 3 == 0:
        t = t.reshape(-1, 3)
    t = vertex_indices(t, "triangles", 3)
    n = vec3(normals, "normals") if normals is not None else None
    handle = _abi.pm_mesh_p()
    lib.check(lib.pm_mesh_create(ptr(v, c_double), len(v), ptr(t, c_int32), len(t),
                                 ptr(n, c_double), ctypes.byref(handle)))
    try:
        for name, values in ((attributes or {}).items() if with_attributes else ()):
            a = channels(values, name, len(v))
            lib.check(lib.pm_mesh_set_attribute(handle, name.encode(), a.shape[1],
                                                ptr(a, c_float), len(v)))
        corners = with_attributes if with_corner_attributes is None else with_corner_attributes
        corners = getattr(mesh, "corner_attributes", None) if corners else None
        for name, values in (corners or {}).items():
            a = corner_values(values, name, len(t))
            lib.check(lib.pm_mesh_set_corner_attribute(handle, name.encode(), a.shape[2],
                                                       ptr(a, c_float), len(t)))
    except BaseException:
        lib.pm_mesh_destroy(handle)
        raise
    return handle


# ---- handles out ----------------------------------------------------------------------------

def _attributes(lib, handle, count, kind, read=None):
    """Every per-point channel of a cloud or mesh handle: {name: (count, C) float32}, each
    read(name, C) (default: a copy)."""
    get_count = getattr(lib, f"pm_{kind}_get_attribute_count")
    get_name = getattr(lib, f"pm_{kind}_get_attribute_name")
    get_components = getattr(lib, f"pm_{kind}_get_attribute_components")
    copy = getattr(lib, f"pm_{kind}_copy_attribute")
    n = c_size_t(0)
    lib.check(get_count(handle, ctypes.byref(n)))
    out = {}
    for i in range(n.value):
        name = c_char_p()
        lib.check(get_name(handle, i, ctypes.byref(name)))
        key = name.value
        components = c_int32(0)
        lib.check(get_components(handle, key, ctypes.byref(components)))
        if read is not None:
            values = read(key, components.value)
        else:
            values = np.empty((count, components.value), dtype=np.float32)
            if count:
                lib.check(copy(handle, key, ptr(values, c_float), count))
        out[key.decode(errors="replace")] = values
    return out


class _MeshHandle:
    """Owns a pm_mesh whose arrays numpy arrays are lent (pm_mesh_lend_arrays): destroyed when
    the last of those arrays is (they hold it through _Lent, their base)."""

    __slots__ = ("_destroy", "_handle", "__weakref__")

    def __init__(self, lib, handle):
        self._destroy = lib.pm_mesh_destroy
        self._handle = handle

    def __del__(self):
        handle, self._handle = self._handle, None
        if handle is not None and handle.value:
            self._destroy(handle)


class _Lent:
    """The numpy array interface of memory a _MeshHandle owns: np.asarray() of it is an array
    over that memory whose base keeps the handle alive."""

    def __init__(self, owner, address, shape, dtype):
        self.owner = owner
        self.__array_interface__ = {"data": (address, False), "shape": shape,
                                    "typestr": np.dtype(dtype).str, "version": 3}


def _address(pointer):
    return ctypes.cast(pointer, c_void_p).value


def _lent(owner, address, shape, dtype):
    if not address:
        return np.empty(shape, dtype=dtype)
    return np.asarray(_Lent(owner, address, shape, dtype))


def read_mesh_handle(lib, handle, stats=None):
    """A Mesh over the pm_mesh handle's own arrays, without copying them: the handle (a
    pm_mesh_p) is taken over - set to NULL, so that the caller's pm_mesh_destroy does nothing -
    and destroyed once the Mesh's arrays are all gone. A big mesh is then never held twice,
    and its pages are not written a second time (a polygonized 1.5M-triangle frame: 60 MB)."""
    owner = _MeshHandle(lib, _abi.pm_mesh_p(handle.value))
    handle.value = None
    nv, nt = c_size_t(0), c_size_t(0)
    lib.check(lib.pm_mesh_get_counts(owner._handle, ctypes.byref(nv), ctypes.byref(nt)))
    nv, nt = nv.value, nt.value
    positions, normals, triangles = POINTER(c_double)(), POINTER(c_double)(), POINTER(c_uint32)()
    lib.check(lib.pm_mesh_lend_arrays(owner._handle, ctypes.byref(positions), ctypes.byref(normals),
                                      ctypes.byref(triangles)))
    vertices = _lent(owner, _address(positions), (nv, 3), np.float64)
    normals = _lent(owner, _address(normals), (nv, 3), np.float64) if normals else None
    if nv <= 2**31 - 1:  # the library's uint32 indices read as the int32 they then are
        triangles = _lent(owner, _address(triangles), (nt, 3), np.int32)
    else:  # only to raise the library's error: the indices do not fit int32
        triangles = np.empty((nt, 3), dtype=np.int32)
        lib.check(lib.pm_mesh_copy_triangles(owner._handle, ptr(triangles, c_int32), nt))

    def lend_attribute(key, components):
        values = POINTER(c_float)()
        lib.check(lib.pm_mesh_lend_attribute(owner._handle, key, ctypes.byref(values)))
        return _lent(owner, _address(values), (nv, components), np.float32)

    attributes = _attributes(lib, owner._handle, nv, "mesh", read=lend_attribute)
    return Mesh(vertices, triangles, normals, attributes, stats, _corner_attributes(lib, owner._handle, nt))


def _corner_attributes(lib, handle, triangles):
    """Every corner attribute of a pm_mesh handle: {name: (T, 3, C) float32}, copied."""
    n = c_size_t(0)
    lib.check(lib.pm_mesh_get_corner_attribute_count(handle, ctypes.byref(n)))
    out = {}
    for i in range(n.value):
        name = c_char_p()
        lib.check(lib.pm_mesh_get_corner_attribute_name(handle, i, ctypes.byref(name)))
        key = name.value
        components = c_int32(0)
        lib.check(lib.pm_mesh_get_corner_attribute_components(handle, key, ctypes.byref(components)))
        values = np.empty((triangles, 3, components.value), dtype=np.float32)
        if triangles:
            lib.check(lib.pm_mesh_copy_corner_attribute(handle, key, ptr(values, c_float), triangles))
        out[key.decode(errors="replace")] = values
    return out


def read_cloud_handle(lib, handle, info=None):
    """Points with copies of everything the pm_cloud handle holds."""
    count = c_size_t(0)
    lib.check(lib.pm_cloud_get_count(handle, ctypes.byref(count)))
    n = count.value
    positions = np.empty((n, 3), dtype=np.float64)
    if n:
        lib.check(lib.pm_cloud_copy_positions(handle, ptr(positions, c_double), n))
    has = c_int32(0)
    lib.check(lib.pm_cloud_has_normals(handle, ctypes.byref(has)))
    normals = None
    if has.value and n:
        normals = np.empty((n, 3), dtype=np.float64)
        lib.check(lib.pm_cloud_copy_normals(handle, ptr(normals, c_double), n))
    return Points(positions, normals, _attributes(lib, handle, n, "cloud"), info)


def struct_dict(struct, skip=("struct_size",)):
    """A ctypes Structure's fields as a dict (arrays as tuples)."""
    out = {}
    for name, _ in struct._fields_:
        if name in skip:
            continue
        value = getattr(struct, name)
        out[name] = tuple(value) if isinstance(value, ctypes.Array) else value
    return out


def path_bytes(path):
    return os.fsencode(path)
