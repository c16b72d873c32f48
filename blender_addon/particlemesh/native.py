"""ctypes binding of the particlemesh C ABI (native/include/particlemesh/particlemesh.h).

This module never imports bpy: it runs inside Blender and in plain Python (its pytest suite
runs outside Blender). Arrays cross the boundary as numpy buffers (float32 positions and
normals, int32 triangles); no per-vertex Python loop anywhere.

Rules kept here (STYLE.md section 8):
  - every foreign function has argtypes and restype declared;
  - the library's ABI version is checked when it is loaded;
  - PARTICLEMESH_LIBRARY overrides where the library is loaded from, and a missing library
    gives one clear message saying where we looked;
  - a non-OK status becomes a ParticlemeshError carrying pm_last_error_message();
  - every opaque handle is destroyed in a `finally`.

Functions that newer libraries add (pm_polygonize, pm_smooth, attribute channels) are bound
when the symbols exist; `has_polygonize()` / `has_smooth()` say so, and calling them on an
older library raises NotAvailableError ("needs a newer particlemesh library").

.pcd files are read by the PCL bridge, a second library (libparticlemesh_pcl, next to
libparticlemesh in the add-on's lib/), loaded lazily on the first .pcd: everything else works
without it, and a .pcd without it gives one clear message (PclBridgeNotFoundError).
PARTICLEMESH_PCL_LIBRARY overrides where it is loaded from.
"""

import ctypes
import ctypes.util
import glob
import os
import sys
import threading
from ctypes import (CFUNCTYPE, POINTER, Structure, c_char_p, c_double, c_float, c_int, c_int32,
                    c_size_t, c_uint32, c_uint64, c_int64, c_void_p)

import numpy as np

#: The C ABI version this binding is written against (PM_ABI_VERSION in particlemesh.h).
ABI_VERSION = 1

# pm_status
OK = 0
STATUS_INVALID_ARGUMENT = 1
STATUS_INVALID_INPUT = 2
STATUS_IO_ERROR = 3
STATUS_FORMAT_ERROR = 4
STATUS_OUT_OF_MEMORY = 5
STATUS_CANCELLED = 6
STATUS_LIMIT_EXCEEDED = 7
STATUS_INTERNAL = 8

TRIANGULATE_RAW = 0x1        # the seed's exact triangle set instead of the finished surface
TRIANGULATE_NO_REPAIR = 0x2  # skip hole filling / unpinching
TRIANGULATE_NO_ORIENT = 0x4  # do not turn closed components outward
TRIANGULATE_GLOBAL_SPACING = 0x8  # one longest edge for all particles, not each one's own
TRIANGULATE_VIEWPOINT = 0x10  # options.viewpoint is the scan's sensor position

# Where the finished surface's normals come from (PM_NORMALS_*).
NORMALS_AUTO = 0
NORMALS_INPUT = 1
NORMALS_ESTIMATE = 2
NORMAL_SOURCES = {"AUTO": NORMALS_AUTO, "INPUT": NORMALS_INPUT, "ESTIMATE": NORMALS_ESTIMATE}

# Kernels of pm_polygonize (particlemesh.h, issue 7).
KERNEL_WYVILL = 0
KERNEL_POLY4 = 1
KERNEL_POLY6 = 2
KERNEL_BLINN = 3
KERNELS = {"WYVILL": KERNEL_WYVILL, "POLY4": KERNEL_POLY4, "POLY6": KERNEL_POLY6, "BLINN": KERNEL_BLINN}

# Schemes of pm_smooth (particlemesh.h, issue 4).
SMOOTH_LOOP = 0
SMOOTH_BUTTERFLY = 1
SCHEMES = {"LOOP": SMOOTH_LOOP, "BUTTERFLY": SMOOTH_BUTTERFLY}

LIBRARY_ENV = "PARTICLEMESH_LIBRARY"
PCL_LIBRARY_ENV = "PARTICLEMESH_PCL_LIBRARY"

#: The bridge's C ABI version this binding is written against (PM_PCL_ABI_VERSION in
#: pcl_bridge/include/particlemesh_pcl/particlemesh_pcl_c.h).
PCL_ABI_VERSION = 1


# ---- errors ---------------------------------------------------------------------------------

class ParticlemeshError(Exception):
    """A particlemesh call failed. `status` is the pm_status, str(e) the library's message."""

    def __init__(self, message, status=STATUS_INTERNAL):
        super().__init__(message)
        self.status = status


class CancelledError(ParticlemeshError):
    """The progress callback asked to stop (Esc in Blender)."""

    def __init__(self, message="cancelled"):
        super().__init__(message, STATUS_CANCELLED)


class LibraryNotFoundError(ParticlemeshError):
    """The native library could not be found or loaded."""

    def __init__(self, message):
        super().__init__(message, STATUS_IO_ERROR)


class PclBridgeNotFoundError(ParticlemeshError):
    """The PCL bridge library (needed for .pcd files only) could not be found or loaded."""

    def __init__(self, message):
        super().__init__(message, STATUS_IO_ERROR)


class NotAvailableError(ParticlemeshError):
    """The loaded library predates a function this add-on offers."""

    def __init__(self, function):
        super().__init__(f"needs a newer particlemesh library (this one has no {function})",
                         STATUS_INVALID_ARGUMENT)


# ---- C structures ---------------------------------------------------------------------------

PROGRESS_FN = CFUNCTYPE(c_int, c_void_p, c_char_p, c_double)


class TriangulateOptions(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("spacing", c_double),
        ("max_edge_factor", c_double),
        ("threads", c_int32),
        ("max_neighbors", c_uint32),
        ("flags", c_uint32),
        ("progress", PROGRESS_FN),
        ("progress_user_data", c_void_p),
        # finishing stages (ignored with TRIANGULATE_RAW)
        ("normal_angle", c_double),
        ("fill_holes", c_uint32),
        ("fill_edge_factor", c_double),
        ("normals", c_int32),
        # appended (issue 9)
        ("max_triplets_per_point", c_uint32),
        # appended
        ("viewpoint", c_double * 3),
    ]


class TriangulateStats(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("spacing", c_double),
        ("max_edge", c_double),
        ("spacing_estimated", c_int32),
        ("points", c_uint64),
        ("duplicate_points", c_uint64),
        ("max_neighbors_seen", c_uint64),
        ("candidates", c_uint64),
        ("kept", c_uint64),
        # finishing stages (0 with TRIANGULATE_RAW)
        ("holes_filled", c_uint64),
        ("holes_left", c_uint64),
        ("largest_hole_left", c_uint64),
        ("pinches_resolved", c_uint64),
        ("unused_points", c_uint64),
        ("normals_estimated", c_int32),
        # appended (issue 9)
        ("triplets", c_uint64),
        ("rejected_conormal", c_uint64),
        # appended
        ("local_spacing", c_double * 5),
        ("viewpoint_used", c_int32),
        ("rejected_shadow", c_uint64),
    ]


class TopologyReport(Structure):
    _fields_ = [("struct_size", c_uint32)] + [
        (name, c_uint64) for name in (
            "vertices", "triangles", "vertices_used", "edges",
            "boundary_edges", "manifold_edges", "nonmanifold_edges", "nonmanifold_vertices",
            "degenerate_triangles", "duplicate_triangles", "orientation_conflicts",
            "boundary_loops", "components", "closed_components")
    ] + [
        ("euler_characteristic", c_int64),
        ("manifold", c_int32), ("closed", c_int32),
        ("consistently_oriented", c_int32), ("outward", c_int32),
    ]


class PolygonizeOptions(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("kernel", c_int32),
        ("radius", c_double),
        ("threshold", c_double),
        ("cell_size", c_double),
        ("threads", c_int32),
        ("max_grid_bytes", c_uint64),
        ("progress", PROGRESS_FN),
        ("progress_user_data", c_void_p),
    ]


class PolygonizeStats(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("radius", c_double),
        ("threshold", c_double),
        ("cell_size", c_double),
        ("spacing", c_double),
        ("particles", c_uint64),
        ("sampled_blocks", c_uint64),
        ("grid_bytes", c_uint64),
        ("vertices", c_uint64),
        ("triangles", c_uint64),
    ]


class SmoothOptions(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("scheme", c_int32),
        ("levels", c_int32),
        ("limit", c_int32),
        ("boundary", c_int32),
        ("crease_method", c_int32),
        ("threads", c_int32),
        ("max_triangles", c_uint64),
        ("crease_count", c_size_t),
        ("crease_edges", POINTER(c_int32)),
        ("crease_sharpness", POINTER(c_float)),
        ("progress", PROGRESS_FN),
        ("progress_user_data", c_void_p),
    ]


class PclReadInfo(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("input_points", c_uint64),
        ("valid_points", c_uint64),
        ("invalid_points", c_uint64),
        ("invalid_normals", c_uint64),
        ("width", c_uint32),
        ("height", c_uint32),
        ("has_normals", c_int32),
        ("has_color", c_int32),
        ("has_intensity", c_int32),
        ("origin", c_float * 3),
    ]


_cloud_p = c_void_p
_mesh_p = c_void_p
_f32p = POINTER(c_float)
_f64p = POINTER(c_double)
_i32p = POINTER(c_int32)

# name: (restype, argtypes). Every function this binding may call.
_REQUIRED = {
    "pm_abi_version": (c_uint32, []),
    "pm_version_string": (c_char_p, []),
    "pm_status_string": (c_char_p, [c_int]),
    "pm_last_error_message": (c_char_p, []),
    "pm_cloud_create": (c_int, [_f64p, _f64p, c_size_t, POINTER(_cloud_p)]),
    "pm_cloud_create_f32": (c_int, [_f32p, _f32p, c_size_t, POINTER(_cloud_p)]),
    "pm_cloud_read": (c_int, [c_char_p, POINTER(_cloud_p)]),
    "pm_cloud_get_count": (c_int, [_cloud_p, POINTER(c_size_t)]),
    "pm_cloud_has_normals": (c_int, [_cloud_p, POINTER(c_int32)]),
    "pm_cloud_copy_positions_f32": (c_int, [_cloud_p, _f32p, c_size_t]),
    "pm_cloud_copy_normals_f32": (c_int, [_cloud_p, _f32p, c_size_t]),
    "pm_cloud_destroy": (None, [_cloud_p]),
    "pm_estimate_spacing": (c_int, [_cloud_p, c_int32, POINTER(c_double)]),
    "pm_triangulate_options_init": (None, [POINTER(TriangulateOptions)]),
    "pm_triangulate": (c_int, [_cloud_p, POINTER(TriangulateOptions), POINTER(_mesh_p),
                               POINTER(TriangulateStats)]),
    "pm_mesh_create": (c_int, [_f64p, c_size_t, _i32p, c_size_t, _f64p, POINTER(_mesh_p)]),
    "pm_mesh_read": (c_int, [c_char_p, POINTER(_mesh_p)]),
    "pm_mesh_write": (c_int, [_mesh_p, c_char_p]),
    "pm_mesh_get_counts": (c_int, [_mesh_p, POINTER(c_size_t), POINTER(c_size_t)]),
    "pm_mesh_has_normals": (c_int, [_mesh_p, POINTER(c_int32)]),
    "pm_mesh_copy_positions_f32": (c_int, [_mesh_p, _f32p, c_size_t]),
    "pm_mesh_copy_normals_f32": (c_int, [_mesh_p, _f32p, c_size_t]),
    "pm_mesh_copy_triangles": (c_int, [_mesh_p, _i32p, c_size_t]),
    "pm_mesh_destroy": (None, [_mesh_p]),
    "pm_mesh_report": (c_int, [_mesh_p, POINTER(TopologyReport)]),
}

# Bound only when present (other issues add them).
_OPTIONAL = {
    "pm_polygonize_options_init": (None, [POINTER(PolygonizeOptions)]),
    "pm_polygonize": (c_int, [_cloud_p, _f64p, _f64p, POINTER(PolygonizeOptions),
                              POINTER(_mesh_p)]),
    "pm_polygonize_ex": (c_int, [_cloud_p, _f64p, _f64p, POINTER(PolygonizeOptions),
                                 POINTER(_mesh_p), POINTER(PolygonizeStats)]),
    "pm_lattice_field": (c_int, [c_int32, c_double, c_double, POINTER(c_double)]),
    "pm_smooth_options_init": (None, [POINTER(SmoothOptions)]),
    "pm_smooth": (c_int, [_mesh_p, POINTER(SmoothOptions), POINTER(_mesh_p)]),
    # Per-vertex float channels, vertex-major: (handle, name, components, values, vertex count).
    "pm_cloud_set_attribute": (c_int, [_cloud_p, c_char_p, c_int32, _f32p, c_size_t]),
    "pm_mesh_set_attribute": (c_int, [_mesh_p, c_char_p, c_int32, _f32p, c_size_t]),
    "pm_mesh_get_attribute_components": (c_int, [_mesh_p, c_char_p, POINTER(c_int32)]),
    "pm_mesh_copy_attribute": (c_int, [_mesh_p, c_char_p, _f32p, c_size_t]),
    "pm_mesh_get_attribute_count": (c_int, [_mesh_p, POINTER(c_size_t)]),
    "pm_mesh_get_attribute_name": (c_int, [_mesh_p, c_size_t, POINTER(c_char_p)]),
    # A cloud's channels read back (what a file's colours became).
    "pm_cloud_get_attribute_count": (c_int, [_cloud_p, POINTER(c_size_t)]),
    "pm_cloud_get_attribute_name": (c_int, [_cloud_p, c_size_t, POINTER(c_char_p)]),
    "pm_cloud_get_attribute_components": (c_int, [_cloud_p, c_char_p, POINTER(c_int32)]),
    "pm_cloud_copy_attribute": (c_int, [_cloud_p, c_char_p, _f32p, c_size_t]),
    # An even subset of a cloud (the coarse viewport preview, issue 6).
    "pm_cloud_thin": (c_int, [_cloud_p, c_double, POINTER(c_uint32), c_size_t, POINTER(c_size_t)]),
    "pm_estimate_spacing_sampled": (c_int, [_cloud_p, c_size_t, c_int32, POINTER(c_double)]),
    # A triangle list's edges, for Blender's edge list (the mesh write, issue 6).
    "pm_triangle_edges": (c_int, [POINTER(c_uint32), c_size_t, c_size_t, c_int32, POINTER(c_uint32),
                                  c_size_t, POINTER(c_uint32), POINTER(c_size_t)]),
}

# The PCL bridge's C entry points (libparticlemesh_pcl).
_PCL_FUNCTIONS = {
    "pm_pcl_abi_version": (c_uint32, []),
    "pm_pcl_last_error_message": (c_char_p, []),
    "pm_pcl_read_cloud": (c_int, [c_char_p, POINTER(_cloud_p), POINTER(PclReadInfo)]),
}


# ---- loading --------------------------------------------------------------------------------

def _candidate_paths():
    """Where the library is looked for, in order (PARTICLEMESH_LIBRARY first)."""
    env = os.environ.get(LIBRARY_ENV)
    if env:
        return [env]
    here = os.path.dirname(os.path.abspath(__file__))
    lib_dir = os.path.join(here, "lib")
    if sys.platform == "win32":
        patterns = ["particlemesh.dll"]
    elif sys.platform == "darwin":
        patterns = ["libparticlemesh.dylib", "libparticlemesh.*.dylib"]
    else:
        patterns = ["libparticlemesh.so", "libparticlemesh.so.*"]
    paths = []
    for pattern in patterns:
        paths.extend(sorted(glob.glob(os.path.join(lib_dir, pattern))))
    system = ctypes.util.find_library("particlemesh")
    if system:
        paths.append(system)
    return paths


class Library:
    """The loaded native library with every signature declared."""

    def __init__(self, path):
        try:
            self.cdll = ctypes.CDLL(path)
        except OSError as e:
            raise LibraryNotFoundError(f"cannot load the particlemesh library {path}: {e}") from e
        self.path = path
        missing = [name for name in _REQUIRED if not hasattr(self.cdll, name)]
        if missing:
            raise LibraryNotFoundError(
                f"{path} is not a usable particlemesh library (missing {', '.join(missing)})")
        for table in (_REQUIRED, _OPTIONAL):
            for name, (restype, argtypes) in table.items():
                if hasattr(self.cdll, name):
                    fn = getattr(self.cdll, name)
                    fn.restype = restype
                    fn.argtypes = argtypes
        self.abi_version = int(self.cdll.pm_abi_version())
        if self.abi_version != ABI_VERSION:
            raise LibraryNotFoundError(
                f"{path} has particlemesh ABI version {self.abi_version}; this add-on needs "
                f"version {ABI_VERSION} (install the matching add-on build)")
        self.version = self.cdll.pm_version_string().decode()

    def has(self, name):
        return hasattr(self.cdll, name)

    def __getattr__(self, name):
        if name.startswith("pm_"):
            if not hasattr(self.cdll, name):
                raise NotAvailableError(name)
            return getattr(self.cdll, name)
        raise AttributeError(name)


_library = None
_lock = threading.Lock()


def load(path=None):
    """Load (once) and return the Library. `path` or $PARTICLEMESH_LIBRARY override the
    search of the add-on's lib/ folder and the system's library path."""
    global _library
    with _lock:
        if path is None and _library is not None:
            return _library
        paths = [path] if path else _candidate_paths()
        if not paths:
            here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib")
            raise LibraryNotFoundError(
                f"the particlemesh native library was not found (looked in {here} and the "
                f"system library path; set {LIBRARY_ENV} to the library file)")
        errors = []
        for candidate in paths:
            if not os.path.exists(candidate) and os.sep in candidate:
                errors.append(f"{candidate} does not exist")
                continue
            try:
                lib = Library(candidate)
            except LibraryNotFoundError as e:
                errors.append(str(e))
                continue
            if path is None:
                _library = lib
            return lib
        raise LibraryNotFoundError("; ".join(errors))


def available():
    """(True, version) if the library loads, else (False, the reason)."""
    try:
        return True, load().version
    except ParticlemeshError as e:
        return False, str(e)


# ---- the PCL bridge (.pcd), loaded on demand ------------------------------------------------

def _pcl_candidate_paths(core_path):
    """Where the bridge is looked for: $PARTICLEMESH_PCL_LIBRARY, else next to the loaded
    libparticlemesh, the add-on's lib/ and the system's library path."""
    env = os.environ.get(PCL_LIBRARY_ENV)
    if env:
        return [env], []
    if sys.platform == "win32":
        patterns = ["particlemesh_pcl.dll"]
    elif sys.platform == "darwin":
        patterns = ["libparticlemesh_pcl.dylib", "libparticlemesh_pcl.*.dylib"]
    else:
        patterns = ["libparticlemesh_pcl.so", "libparticlemesh_pcl.so.*"]
    folders = []
    if core_path and os.sep in core_path:
        folders.append(os.path.dirname(os.path.abspath(core_path)))
    folders.append(os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
    paths = []
    for folder in dict.fromkeys(folders):
        for pattern in patterns:
            paths.extend(sorted(glob.glob(os.path.join(folder, pattern))))
    system = ctypes.util.find_library("particlemesh_pcl")
    if system:
        paths.append(system)
    return paths, folders


class PclBridge:
    """The loaded PCL bridge with its signatures declared. It uses the libparticlemesh that
    is already loaded (the dynamic loader matches its soname), so load() comes first."""

    def __init__(self, path):
        try:
            self.cdll = ctypes.CDLL(path)
        except OSError as e:
            raise PclBridgeNotFoundError(
                f"reading .pcd needs the PCL bridge library, and {path} does not load: {e} "
                f"(it needs PCL 1.13's libraries, e.g. Debian's libpcl-io1.13)") from e
        self.path = path
        missing = [name for name in _PCL_FUNCTIONS if not hasattr(self.cdll, name)]
        if missing:
            raise PclBridgeNotFoundError(
                f"{path} is not a usable PCL bridge library (missing {', '.join(missing)})")
        for name, (restype, argtypes) in _PCL_FUNCTIONS.items():
            fn = getattr(self.cdll, name)
            fn.restype = restype
            fn.argtypes = argtypes
        self.abi_version = int(self.cdll.pm_pcl_abi_version())
        if self.abi_version != PCL_ABI_VERSION:
            raise PclBridgeNotFoundError(
                f"{path} has PCL bridge ABI version {self.abi_version}; this add-on needs "
                f"version {PCL_ABI_VERSION}")

    def __getattr__(self, name):
        if name.startswith("pm_pcl_"):
            return getattr(self.cdll, name)
        raise AttributeError(name)


_pcl = {}


def load_pcl(path=None):
    """Load (once per path) and return the PCL bridge; PclBridgeNotFoundError with a clear
    message when it is absent or does not load."""
    core = load()
    with _lock:
        if path is None and core.path in _pcl:
            return _pcl[core.path]
        if path:
            paths, folders = [path], []
        else:
            paths, folders = _pcl_candidate_paths(core.path)
        errors = []
        for candidate in paths:
            if os.sep in candidate and not os.path.exists(candidate):
                errors.append(f"{candidate} does not exist")
                continue
            try:
                bridge = PclBridge(candidate)
            except PclBridgeNotFoundError as e:
                errors.append(str(e))
                continue
            if path is None:
                _pcl[core.path] = bridge
            return bridge
        if errors:
            raise PclBridgeNotFoundError("; ".join(errors))
        raise PclBridgeNotFoundError(
            "reading .pcd needs the PCL bridge library libparticlemesh_pcl, which was not "
            f"found (looked in {', '.join(folders)} and the system library path; set "
            f"{PCL_LIBRARY_ENV} to the library file)")


def has_pcd():
    """(True, path) if .pcd files can be read (the PCL bridge loads), else (False, reason)."""
    try:
        return True, load_pcl().path
    except ParticlemeshError as e:
        return False, str(e)


def has_polygonize():
    return load().has("pm_polygonize")


def has_smooth():
    return load().has("pm_smooth")


def has_mesh_attributes():
    lib = load()
    return lib.has("pm_mesh_set_attribute") and lib.has("pm_mesh_copy_attribute") and lib.has(
        "pm_mesh_get_attribute_components")


def version():
    return load().version


# ---- helpers --------------------------------------------------------------------------------

def _check(lib, status):
    if status == OK:
        return
    message = lib.pm_last_error_message().decode(errors="replace")
    if not message:
        message = lib.pm_status_string(status).decode()
    if status == STATUS_CANCELLED:
        raise CancelledError(message)
    raise ParticlemeshError(message, status)


def _vec3(array, name, dtype=np.float32):
    """A C-contiguous (N, 3) array of `dtype` (a copy only when needed)."""
    a = np.asarray(array)
    if a.ndim == 1:
        if a.size % 3:
            raise ParticlemeshError(f"{name} has {a.size} values, not a multiple of 3",
                                    STATUS_INVALID_ARGUMENT)
        a = a.reshape(-1, 3)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ParticlemeshError(f"{name} must have shape (N, 3), got {a.shape}",
                                STATUS_INVALID_ARGUMENT)
    return np.ascontiguousarray(a, dtype=dtype)


def _ptr(array, ctype):
    return array.ctypes.data_as(POINTER(ctype)) if array is not None else None


class Progress:
    """Progress and cancellation shared between a worker thread and the UI.

    The library calls back on the thread that made the call; `callback` (optional) gets
    (stage, fraction) there and returns False to cancel. `cancel()` may be called from any
    thread (Esc in Blender's modal loop) and stops the native call at its next report."""

    def __init__(self, callback=None):
        self.callback = callback
        self.stage = ""
        self.fraction = 0.0
        self._cancel = threading.Event()
        self.error = None

        def trampoline(_user, stage, fraction):
            try:
                self.stage = stage.decode(errors="replace") if stage else ""
                self.fraction = float(fraction)
                if self._cancel.is_set():
                    return 1
                if self.callback is not None and self.callback(self.stage, self.fraction) is False:
                    self._cancel.set()
                    return 1
                return 0
            except BaseException as e:  # never let an exception unwind through C
                self.error = e
                self._cancel.set()
                return 1

        self.c_function = PROGRESS_FN(trampoline)

    def cancel(self):
        self._cancel.set()

    @property
    def cancelled(self):
        return self._cancel.is_set()


def _progress_fn(progress):
    if progress is None:
        return PROGRESS_FN()  # NULL
    if not isinstance(progress, Progress):
        raise TypeError("progress must be a native.Progress")
    return progress.c_function


class MeshData:
    """A triangle mesh as numpy arrays: positions (V, 3) float32, triangles (F, 3) int32,
    normals (V, 3) float32 or None, attributes {name: (V, C) float32}, stats (dict)."""

    __slots__ = ("positions", "triangles", "normals", "attributes", "stats")

    def __init__(self, positions, triangles, normals=None, attributes=None, stats=None):
        self.positions = positions
        self.triangles = triangles
        self.normals = normals
        self.attributes = attributes if attributes is not None else {}
        self.stats = stats if stats is not None else {}

    @property
    def vertex_count(self):
        return len(self.positions)

    @property
    def triangle_count(self):
        return len(self.triangles)

    def nbytes(self):
        n = self.positions.nbytes + self.triangles.nbytes
        if self.normals is not None:
            n += self.normals.nbytes
        return n + sum(a.nbytes for a in self.attributes.values())


class CloudData:
    """Particles as numpy arrays: positions (N, 3) float32, normals (N, 3) float32 or None,
    attributes {name: (N, C) float32} (a file's colours: "color", (N, 3) in [0, 1]), info
    (dict: what a .pcd reader read and dropped, e.g. invalid_points; empty otherwise)."""

    __slots__ = ("positions", "normals", "attributes", "info")

    def __init__(self, positions, normals=None, attributes=None, info=None):
        self.positions = positions
        self.normals = normals
        self.attributes = attributes if attributes is not None else {}
        self.info = info if info is not None else {}


def _new_cloud(lib, positions, normals=None):
    p = _vec3(positions, "positions")
    n = _vec3(normals, "normals") if normals is not None else None
    if n is not None and len(n) != len(p):
        raise ParticlemeshError(f"normals has {len(n)} rows but positions has {len(p)}",
                                STATUS_INVALID_ARGUMENT)
    handle = c_void_p()
    _check(lib, lib.pm_cloud_create_f32(_ptr(p, c_float), _ptr(n, c_float), len(p),
                                        ctypes.byref(handle)))
    return handle


def _set_cloud_attributes(lib, cloud, attributes, count):
    if not attributes:
        return
    if not lib.has("pm_cloud_set_attribute"):
        return  # older library: attributes are simply not carried through
    for name, values in attributes.items():
        a = np.ascontiguousarray(values, dtype=np.float32)
        a = a.reshape(count, -1)
        _check(lib, lib.pm_cloud_set_attribute(cloud, name.encode(), a.shape[1], _ptr(a, c_float),
                                               count))


def _new_mesh(lib, positions, triangles, normals=None):
    p = _vec3(positions, "positions", np.float64)
    t = np.ascontiguousarray(np.asarray(triangles).reshape(-1, 3), dtype=np.int32)
    n = _vec3(normals, "normals", np.float64) if normals is not None else None
    handle = c_void_p()
    _check(lib, lib.pm_mesh_create(_ptr(p, c_double), len(p), _ptr(t, c_int32), len(t),
                                   _ptr(n, c_double), ctypes.byref(handle)))
    return handle


def _set_mesh_attributes(lib, mesh, attributes, count):
    if not attributes or not lib.has("pm_mesh_set_attribute"):
        return
    for name, values in attributes.items():
        a = np.ascontiguousarray(values, dtype=np.float32).reshape(count, -1)
        _check(lib, lib.pm_mesh_set_attribute(mesh, name.encode(), a.shape[1], _ptr(a, c_float),
                                              count))


def _mesh_attribute_names(lib, mesh):
    if not (lib.has("pm_mesh_get_attribute_count") and lib.has("pm_mesh_get_attribute_name")):
        return ()
    n = c_size_t(0)
    _check(lib, lib.pm_mesh_get_attribute_count(mesh, ctypes.byref(n)))
    names = []
    for i in range(n.value):
        name = c_char_p()
        _check(lib, lib.pm_mesh_get_attribute_name(mesh, i, ctypes.byref(name)))
        names.append(name.value.decode(errors="replace"))
    return tuple(names)


def _mesh_attributes(lib, mesh, count):
    """Every per-vertex channel the library put on the mesh, {name: (V, C) float32}."""
    out = {}
    if not (lib.has("pm_mesh_get_attribute_components") and lib.has("pm_mesh_copy_attribute")):
        return out
    for name in _mesh_attribute_names(lib, mesh):
        components = c_int32(0)
        _check(lib, lib.pm_mesh_get_attribute_components(mesh, name.encode(),
                                                         ctypes.byref(components)))
        a = np.empty((count, components.value), dtype=np.float32)
        if count:
            _check(lib, lib.pm_mesh_copy_attribute(mesh, name.encode(), _ptr(a, c_float), count))
        out[name] = a
    return out


def _mesh_to_data(lib, mesh):
    nv, nt = c_size_t(0), c_size_t(0)
    _check(lib, lib.pm_mesh_get_counts(mesh, ctypes.byref(nv), ctypes.byref(nt)))
    nv, nt = nv.value, nt.value
    positions = np.empty((nv, 3), dtype=np.float32)
    triangles = np.empty((nt, 3), dtype=np.int32)
    if nv:
        _check(lib, lib.pm_mesh_copy_positions_f32(mesh, _ptr(positions, c_float), nv))
    if nt:
        _check(lib, lib.pm_mesh_copy_triangles(mesh, _ptr(triangles, c_int32), nt))
    has = c_int32(0)
    _check(lib, lib.pm_mesh_has_normals(mesh, ctypes.byref(has)))
    normals = None
    if has.value and nv:
        normals = np.empty((nv, 3), dtype=np.float32)
        _check(lib, lib.pm_mesh_copy_normals_f32(mesh, _ptr(normals, c_float), nv))
    return MeshData(positions, triangles, normals, _mesh_attributes(lib, mesh, nv))


def _cloud_to_data(lib, cloud):
    count = c_size_t(0)
    _check(lib, lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
    n = count.value
    positions = np.empty((n, 3), dtype=np.float32)
    if n:
        _check(lib, lib.pm_cloud_copy_positions_f32(cloud, _ptr(positions, c_float), n))
    has = c_int32(0)
    _check(lib, lib.pm_cloud_has_normals(cloud, ctypes.byref(has)))
    normals = None
    if has.value and n:
        normals = np.empty((n, 3), dtype=np.float32)
        _check(lib, lib.pm_cloud_copy_normals_f32(cloud, _ptr(normals, c_float), n))
    return CloudData(positions, normals, _cloud_attributes(lib, cloud, n))


def _cloud_attributes(lib, cloud, count):
    """Every per-point channel of a cloud, {name: (N, C) float32} (empty on a library
    without the read-back functions)."""
    out = {}
    if not all(lib.has(f) for f in ("pm_cloud_get_attribute_count", "pm_cloud_get_attribute_name",
                                    "pm_cloud_get_attribute_components",
                                    "pm_cloud_copy_attribute")):
        return out
    n = c_size_t(0)
    _check(lib, lib.pm_cloud_get_attribute_count(cloud, ctypes.byref(n)))
    for i in range(n.value):
        name = c_char_p()
        _check(lib, lib.pm_cloud_get_attribute_name(cloud, i, ctypes.byref(name)))
        key = name.value
        components = c_int32(0)
        _check(lib, lib.pm_cloud_get_attribute_components(cloud, key, ctypes.byref(components)))
        a = np.empty((count, components.value), dtype=np.float32)
        if count:
            _check(lib, lib.pm_cloud_copy_attribute(cloud, key, _ptr(a, c_float), count))
        out[key.decode(errors="replace")] = a
    return out


# ---- the API the add-on uses ----------------------------------------------------------------

def read_cloud(path):
    """Read particles from a file: .ply (normals, vertex colours) and .xyz through the
    library, .pcd through the PCL bridge (points with a NaN coordinate dropped and counted in
    `info`, normals, rgb/rgba as "color", intensity). Returns CloudData."""
    lib = load()
    if os.path.splitext(os.fspath(path))[1].lower() == ".pcd":
        return _read_pcd(lib, path)
    cloud = c_void_p()
    _check(lib, lib.pm_cloud_read(os.fsencode(path), ctypes.byref(cloud)))
    try:
        return _cloud_to_data(lib, cloud)
    finally:
        lib.pm_cloud_destroy(cloud)


def _read_pcd(lib, path):
    bridge = load_pcl()
    cloud = c_void_p()
    info = PclReadInfo()
    info.struct_size = ctypes.sizeof(PclReadInfo)
    status = bridge.pm_pcl_read_cloud(os.fsencode(path), ctypes.byref(cloud), ctypes.byref(info))
    if status != OK:
        message = bridge.pm_pcl_last_error_message().decode(errors="replace")
        raise ParticlemeshError(message or lib.pm_status_string(status).decode(), status)
    try:
        data = _cloud_to_data(lib, cloud)
    finally:
        lib.pm_cloud_destroy(cloud)
    data.info = {name: getattr(info, name) for name, _ in PclReadInfo._fields_[1:]}
    data.info["origin"] = tuple(info.origin)
    for flag in ("has_normals", "has_color", "has_intensity"):
        data.info[flag] = bool(data.info[flag])
    data.info["format"] = "pcd"
    return data


def estimate_spacing(positions, threads=0, max_samples=None):
    """Median nearest-neighbour distance of the distinct points (the library's r0 estimate),
    or, with max_samples, of an evenly strided sample of at most that many (a quick one for
    previews; pm_estimate_spacing_sampled)."""
    lib = load()
    if max_samples is not None and not lib.has("pm_estimate_spacing_sampled"):
        raise NotAvailableError("pm_estimate_spacing_sampled")
    cloud = _new_cloud(lib, positions)
    try:
        out = c_double(0)
        if max_samples is None:
            _check(lib, lib.pm_estimate_spacing(cloud, int(threads), ctypes.byref(out)))
        else:
            _check(lib, lib.pm_estimate_spacing_sampled(cloud, int(max_samples), int(threads),
                                                        ctypes.byref(out)))
        return out.value
    finally:
        lib.pm_cloud_destroy(cloud)


def thin(positions, min_distance):
    """Indices (ascending, int64) of an even subset of the points: no two kept ones closer than
    min_distance, every dropped one within min_distance of a kept one (pm_cloud_thin)."""
    lib = load()
    if not lib.has("pm_cloud_thin"):
        raise NotAvailableError("pm_cloud_thin")
    cloud = _new_cloud(lib, positions)
    try:
        count = c_size_t(0)
        _check(lib, lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
        out = np.empty(count.value, dtype=np.uint32)
        _check(lib, lib.pm_cloud_thin(cloud, float(min_distance), _ptr(out, c_uint32), out.size,
                                      ctypes.byref(count)))
        return out[:count.value].astype(np.int64)
    finally:
        lib.pm_cloud_destroy(cloud)


def has_triangle_edges():
    return load().has("pm_triangle_edges")


def triangle_edges(triangles, vertex_count, threads=0):
    """The edges of a triangle list (pm_triangle_edges): (E, 2) uint32, each edge once as
    (a, b) with a < b, ordered; and (3 T,) uint32, per triangle corner the edge to the next
    corner. What Blender's loops and edges need, without its own edge pass."""
    lib = load()
    if not lib.has("pm_triangle_edges"):
        raise NotAvailableError("pm_triangle_edges")
    tris = np.ascontiguousarray(triangles, dtype=np.uint32)
    if tris.ndim != 2 or tris.shape[1] != 3:
        raise ParticlemeshError(f"triangles must have shape (T, 3), got {tris.shape}",
                                STATUS_INVALID_ARGUMENT)
    nt = len(tris)
    edges = np.empty((3 * nt, 2), dtype=np.uint32)
    corners = np.empty(3 * nt, dtype=np.uint32)
    count = c_size_t(0)
    _check(lib, lib.pm_triangle_edges(_ptr(tris, c_uint32), nt, int(vertex_count), int(threads),
                                      _ptr(edges, c_uint32), len(edges), _ptr(corners, c_uint32),
                                      ctypes.byref(count)))
    return edges[:count.value], corners


def triangulate(positions, normals=None, spacing=0.0, max_edge_factor=2.0, threads=0,
                max_neighbors=256, raw=False, normal_angle=None, fill_holes=None,
                fill_edge_factor=None, normal_source=None, repair=True, orient=True,
                progress=None, local_spacing=True):
    """Triangulate surface particles: by default the library's finished surface (a
    consistently oriented 2-manifold, closed parts facing outward, per-vertex normals); with
    raw=True the seed's exact triangle set. None keeps the library's default of an option.
    local_spacing=False: one longest edge for all particles (PM_TRIANGULATE_GLOBAL_SPACING).
    Output vertex i is particle i. Returns MeshData whose `stats` holds the library's
    pm_triangulate_stats as a dict."""
    lib = load()
    opt = TriangulateOptions()
    lib.pm_triangulate_options_init(ctypes.byref(opt))
    opt.spacing = float(spacing)
    opt.max_edge_factor = float(max_edge_factor)
    opt.threads = int(threads)
    opt.max_neighbors = int(max_neighbors)
    opt.flags = ((TRIANGULATE_RAW if raw else 0) | (0 if repair else TRIANGULATE_NO_REPAIR)
                 | (0 if orient else TRIANGULATE_NO_ORIENT)
                 | (0 if local_spacing else TRIANGULATE_GLOBAL_SPACING))
    if normal_angle is not None:
        opt.normal_angle = float(normal_angle)
    if fill_holes is not None:
        if not 0 <= int(fill_holes) < 2 ** 32:
            raise ParticlemeshError(f"fill_holes is {fill_holes}; it must be 0..2^32-1",
                                    STATUS_INVALID_ARGUMENT)
        opt.fill_holes = int(fill_holes)
    if fill_edge_factor is not None:
        opt.fill_edge_factor = float(fill_edge_factor)
    if normal_source is not None:
        opt.normals = NORMAL_SOURCES[normal_source] if isinstance(normal_source, str) else int(normal_source)
    opt.progress = _progress_fn(progress)
    stats = TriangulateStats()
    stats.struct_size = ctypes.sizeof(TriangulateStats)
    cloud = _new_cloud(lib, positions, normals)
    try:
        mesh = c_void_p()
        _check(lib, lib.pm_triangulate(cloud, ctypes.byref(opt), ctypes.byref(mesh),
                                       ctypes.byref(stats)))
        try:
            data = _mesh_to_data(lib, mesh)
        finally:
            lib.pm_mesh_destroy(mesh)
    finally:
        lib.pm_cloud_destroy(cloud)
    data.stats = {name: (list(v) if isinstance(v, ctypes.Array) else v)
                  for name, v in ((name, getattr(stats, name)) for name, _ in TriangulateStats._fields_[1:])}
    data.stats["raw"] = bool(raw)
    return data


def polygonize(positions, radii=None, strengths=None, kernel=KERNEL_WYVILL, radius=0.0,
               threshold=0.0, cell_size=0.0, threads=0, attributes=None, progress=None):
    """Iso-surface of volume particles (pm_polygonize). Zero radius/threshold/cell_size mean
    the library's defaults. `attributes` {name: (N, C)} are carried to the mesh's vertices
    when the library supports attribute channels."""
    lib = load()
    if not lib.has("pm_polygonize"):
        raise NotAvailableError("pm_polygonize")
    opt = PolygonizeOptions()
    lib.pm_polygonize_options_init(ctypes.byref(opt))
    opt.kernel = int(kernel)
    if radius > 0:
        opt.radius = float(radius)
    if threshold > 0:
        opt.threshold = float(threshold)
    if cell_size > 0:
        opt.cell_size = float(cell_size)
    opt.threads = int(threads)
    opt.progress = _progress_fn(progress)
    p = _vec3(positions, "positions")
    r = s = None
    if radii is not None:
        r = np.ascontiguousarray(radii, dtype=np.float64).reshape(-1)
        if len(r) != len(p):
            raise ParticlemeshError(f"radii has {len(r)} values for {len(p)} particles",
                                    STATUS_INVALID_ARGUMENT)
    if strengths is not None:
        s = np.ascontiguousarray(strengths, dtype=np.float64).reshape(-1)
        if len(s) != len(p):
            raise ParticlemeshError(f"strengths has {len(s)} values for {len(p)} particles",
                                    STATUS_INVALID_ARGUMENT)
    stats = PolygonizeStats()
    stats.struct_size = ctypes.sizeof(PolygonizeStats)
    cloud = _new_cloud(lib, p)
    try:
        _set_cloud_attributes(lib, cloud, attributes, len(p))
        mesh = c_void_p()
        if lib.has("pm_polygonize_ex"):
            _check(lib, lib.pm_polygonize_ex(cloud, _ptr(r, c_double), _ptr(s, c_double),
                                             ctypes.byref(opt), ctypes.byref(mesh),
                                             ctypes.byref(stats)))
        else:
            _check(lib, lib.pm_polygonize(cloud, _ptr(r, c_double), _ptr(s, c_double),
                                          ctypes.byref(opt), ctypes.byref(mesh)))
        try:
            data = _mesh_to_data(lib, mesh)
        finally:
            lib.pm_mesh_destroy(mesh)
    finally:
        lib.pm_cloud_destroy(cloud)
    if lib.has("pm_polygonize_ex"):
        data.stats = {name: getattr(stats, name) for name, _ in PolygonizeStats._fields_[1:]}
    return data


def lattice_field(kernel, radius, spacing):
    """The field deep inside a simple cubic lattice of unit-strength particles
    (pm_lattice_field): an iso level as a fraction of the rest density is that fraction of
    lattice_field(kernel, R, rest spacing)."""
    lib = load()
    if not lib.has("pm_lattice_field"):
        raise NotAvailableError("pm_lattice_field")
    out = c_double(0)
    _check(lib, lib.pm_lattice_field(int(kernel), float(radius), float(spacing), ctypes.byref(out)))
    return out.value


def smooth(positions, triangles, scheme=SMOOTH_LOOP, levels=1, normals=None, attributes=None,
           threads=0, progress=None):
    """Loop or butterfly subdivision (pm_smooth). Returns a new MeshData; `attributes`
    {name: (V, C)} are interpolated when the library supports attribute channels."""
    lib = load()
    if not lib.has("pm_smooth"):
        raise NotAvailableError("pm_smooth")
    opt = SmoothOptions()
    lib.pm_smooth_options_init(ctypes.byref(opt))
    opt.scheme = int(scheme)
    opt.levels = int(levels)
    opt.threads = int(threads)
    opt.progress = _progress_fn(progress)
    mesh = _new_mesh(lib, positions, triangles, normals)
    try:
        _set_mesh_attributes(lib, mesh, attributes, len(positions))
        out = c_void_p()
        _check(lib, lib.pm_smooth(mesh, ctypes.byref(opt), ctypes.byref(out)))
        try:
            return _mesh_to_data(lib, out)
        finally:
            lib.pm_mesh_destroy(out)
    finally:
        lib.pm_mesh_destroy(mesh)


def read_mesh(path):
    """Read a triangle mesh (.ply/.obj/.off/.stl) into MeshData."""
    lib = load()
    mesh = c_void_p()
    _check(lib, lib.pm_mesh_read(os.fsencode(path), ctypes.byref(mesh)))
    try:
        return _mesh_to_data(lib, mesh)
    finally:
        lib.pm_mesh_destroy(mesh)


def write_mesh(data, path):
    """Write MeshData as .ply (binary) or .obj, atomically."""
    lib = load()
    mesh = _new_mesh(lib, data.positions, data.triangles, data.normals)
    try:
        _check(lib, lib.pm_mesh_write(mesh, os.fsencode(path)))
    finally:
        lib.pm_mesh_destroy(mesh)


def mesh_report(positions, triangles):
    """The library's topology report of a mesh, as a dict (manifold, closed, outward, ...)."""
    lib = load()
    mesh = _new_mesh(lib, positions, triangles)
    try:
        rep = TopologyReport()
        rep.struct_size = ctypes.sizeof(TopologyReport)
        _check(lib, lib.pm_mesh_report(mesh, ctypes.byref(rep)))
    finally:
        lib.pm_mesh_destroy(mesh)
    out = {name: getattr(rep, name) for name, _ in TopologyReport._fields_[1:]}
    for flag in ("manifold", "closed", "consistently_oriented", "outward"):
        out[flag] = bool(out[flag])
    return out
