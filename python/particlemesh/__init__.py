"""particlemesh: particles to surfaces, on numpy arrays.

    import particlemesh as pm
    points = pm.read_points("scan.ply")              # .positions (N, 3) float64, .normals
    mesh = pm.triangulate(points.positions, points.normals)
    print(pm.topology(mesh)["closed"], mesh.stats["spacing"])
    pm.write_mesh(pm.smooth(mesh, levels=2), "smooth.ply")

Surface particles (evenly spaced samples of a surface) are triangulated with Tonnesen's
smallest-sphere test into a finished, oriented surface (`triangulate`); volume particles
(a fluid simulation's) become the iso-surface of a summed kernel field (`polygonize`); any
triangle mesh is refined by Loop or modified-butterfly subdivision (`smooth`, or a `Smoother`
that refines once for many frames with the same triangles).

Options are keyword arguments named as the fields of the C ABI's options structs
(particlemesh.h), with the library's own defaults (`defaults("triangulate")` lists them).
Failures raise `Error` with the library's message. The long calls release the GIL, report
progress to `progress=callback(stage, fraction)` (return False to cancel), and stop on Ctrl-C
(KeyboardInterrupt) or `Progress.cancel()` from another thread.

This package is a ctypes binding of the C library libparticlemesh, which it finds in its own
lib/ folder, at $PARTICLEMESH_LIBRARY, or on the system's library path. It never imports bpy:
the Blender add-on carries this same package."""

import ctypes
import os
import warnings
from ctypes import c_double, c_float, c_size_t, c_uint32, c_uint64

import numpy as np

from . import _abi, _library, _options
from ._data import (Mesh, Points, channels, new_cloud, new_mesh, path_bytes, per_point, ptr, vec3,
                    vertex_indices, read_cloud_handle, read_mesh_handle, struct_dict)
from ._errors import (CancelledError, Error, LibraryNotFoundError, NotReadWarning, NotWrittenWarning,
                      PclBridgeNotFoundError)
from ._progress import Hook, Progress

__all__ = [
    "read_points", "read_mesh", "read_frame_collection", "is_frame_collection", "write_mesh",
    "preprocess_scan", "triangulate", "polygonize",
    "polygonize_attributes",
    "smooth", "Smoother",
    "topology", "components",
    "estimate_spacing", "thin", "triangle_edges", "ray_crossings", "default_radius", "particle_grid_radius", "lattice_field", "defaults", "version",
    "library_path", "pcl_bridge_path", "Mesh", "Points", "Progress", "Error", "CancelledError",
    "LibraryNotFoundError", "PclBridgeNotFoundError", "NotReadWarning", "NotWrittenWarning",
]

#: pm_status values (Error.status).
STATUS_INVALID_ARGUMENT = _abi.PM_STATUS_INVALID_ARGUMENT
STATUS_INVALID_INPUT = _abi.PM_STATUS_INVALID_INPUT
STATUS_IO_ERROR = _abi.PM_STATUS_IO_ERROR
STATUS_FORMAT_ERROR = _abi.PM_STATUS_FORMAT_ERROR
STATUS_OUT_OF_MEMORY = _abi.PM_STATUS_OUT_OF_MEMORY
STATUS_CANCELLED = _abi.PM_STATUS_CANCELLED
STATUS_LIMIT_EXCEEDED = _abi.PM_STATUS_LIMIT_EXCEEDED
STATUS_INTERNAL = _abi.PM_STATUS_INTERNAL

#: The names enum options take, e.g. KERNELS["poly6"] == 2.
NORMAL_SOURCES = _options.enum_names("PM_NORMALS_")
KERNELS = _options.enum_names("PM_KERNEL_")
SCHEMES = _options.enum_names("PM_SMOOTH_")
DOWNSAMPLINGS = _options.enum_names("PM_PCL_DOWNSAMPLE_")


# ---- the library ----------------------------------------------------------------------------

def version():
    """The native library's version ("0.1.0"); LibraryNotFoundError when it does not load."""
    return _library.load().version


def library_path():
    """The file libparticlemesh was loaded from."""
    return _library.load().path


def pcl_bridge_path():
    """The file the PCL bridge (needed for .pcd only) was loaded from;
    PclBridgeNotFoundError saying why when it is absent or does not load."""
    return _library.load_pcl().path


def defaults(function):
    """{keyword: the library's default} of the options of "triangulate", "polygonize",
    "smooth" or "preprocess_scan" (the PCL bridge's), read from its pm_*_options_init (enum
    options by name)."""
    try:
        spec = _options.SPECS[function]
    except KeyError:
        raise ValueError(f"no options for {function!r}; one of "
                         f"{', '.join(_options.SPECS)}") from None
    return spec.defaults(_library.load_pcl() if spec is _options.PCL_PREPROCESS else _library.load())


# ---- files ----------------------------------------------------------------------------------

def read_points(path):
    """Particles from a file: .ply (any numeric vertex properties, normals, vertex colours as
    the "color" attribute), .xyz, .pts, .txt and .csv (text; columns by a header line, as
    ParaView's CSV export names them, or by their count),
    VTK .vtk/.vtu/.vtp/.pvtu/.pvtp, lidar .las, Krakatoa .prt and Houdini .bgeo/.geo (plain,
    .gz or Blosc-compressed .sc; every point-data array / point attribute in `attributes`)
    through the library; .pcd (ascii, binary, compressed)
    through the PCL bridge, which drops points with a NaN coordinate and counts them in
    `info`. Coordinates keep their full precision. Returns Points; for the library's formats
    `info["not_read"]` lists, a line each, what the file holds per particle that is not read
    (string attributes, list properties, a LAS file's other fields), and a warning
    (NotReadWarning) names them."""
    lib = _library.load()
    if str(path).lower().endswith(".pcd"):
        bridge = _library.load_pcl()
        handle = _abi.pm_cloud_p()
        info = _abi.pm_pcl_read_info(struct_size=ctypes.sizeof(_abi.pm_pcl_read_info))
        status = bridge.pm_pcl_read_cloud(path_bytes(path), ctypes.byref(handle),
                                          ctypes.byref(info))
        if status != _abi.PM_OK:
            message = bridge.pm_pcl_last_error_message().decode(errors="replace")
            raise Error(message or lib.pm_status_string(status).decode(), status)
        details = struct_dict(info)
        for flag in ("has_normals", "has_color", "has_intensity"):
            details[flag] = bool(details[flag])
        details["format"] = "pcd"
    else:
        handle = _abi.pm_cloud_p()
        lib.check(lib.pm_cloud_read(path_bytes(path), ctypes.byref(handle)))
        details = {"not_read": _not_read(lib, handle)}
        if details["not_read"]:
            warnings.warn(f"{os.fspath(path)}: not read: {'; '.join(details['not_read'])}",
                          NotReadWarning, stacklevel=2)
    try:
        return read_cloud_handle(lib, handle, details)
    finally:
        lib.pm_cloud_destroy(handle)


def _not_read(lib, handle, kind="cloud"):
    """The lines of pm_cloud_get_not_read (kind "mesh": pm_mesh_get_not_read)."""
    count = ctypes.c_size_t(0)
    lib.check(getattr(lib, f"pm_{kind}_get_not_read_count")(handle, ctypes.byref(count)))
    lines = []
    for i in range(count.value):
        text = ctypes.c_char_p()
        lib.check(getattr(lib, f"pm_{kind}_get_not_read")(handle, i, ctypes.byref(text)))
        lines.append(text.value.decode(errors="replace"))
    return lines


def preprocess_scan(positions, normals=None, *, attributes=None, viewpoint=None, **options):
    """Clean up a scan with PCL's filters before triangulating it, through the PCL bridge (the
    command-line tool's --remove-outliers, --voxel-grid / --uniform-sampling, --mls and
    --estimate-normals). Each step is off unless asked; they run in this order:

    1. remove_outliers=True: pcl::StatisticalOutlierRemoval drops points whose mean distance
       to their outlier_mean_k nearest (50) lies beyond outlier_stddev_mul (1) standard
       deviations of the mean;
    2. downsampling="uniform" (pcl::UniformSampling: per voxel the point nearest its centre)
       or "voxel-grid" (pcl::VoxelGrid: the point nearest the voxel's centroid), voxels of
       edge leaf_size;
    3. mls_radius=R: pcl::MovingLeastSquares moves each point onto the polynomial
       (mls_order, 2) fitted to its neighbours within R (a few spacings): takes out a
       scanner's noise across the surface;
    4. estimate_normals=True: pcl::NormalEstimationOMP over normal_k (20) neighbours, each
       normal facing viewpoint=(x, y, z) (the scanner; default the origin).

    threads (0 = all cores): the output is the same for any count. positions: (N, 3) or
    Points (its normals and attributes come with it). Returns Points: the kept points in input
    order, each with its normal and attributes; .info holds what each step did
    (pm_pcl_preprocess_report) and "kept", (M,) int64: the input index of each output point.
    Raises PclBridgeNotFoundError without the bridge, Error naming a bad parameter."""
    lib = _library.load()
    bridge = _library.load_pcl()
    positions, normals, attributes = _points_args(positions, normals, attributes)
    opt = _options.PCL_PREPROCESS.build(bridge, options)
    if viewpoint is not None:
        v = np.asarray(viewpoint, dtype=np.float64).reshape(-1)
        if v.size != 3 or not np.all(np.isfinite(v)):
            raise Error(f"viewpoint must be 3 finite numbers (x, y, z), got {viewpoint!r}",
                        _abi.PM_STATUS_INVALID_ARGUMENT)
        opt.viewpoint[:] = [float(x) for x in v]
    report = _abi.pm_pcl_preprocess_report(struct_size=ctypes.sizeof(_abi.pm_pcl_preprocess_report))
    cloud = new_cloud(lib, positions, normals, attributes)
    out = _abi.pm_cloud_p()
    try:
        kept = np.empty(len(np.asarray(positions)), dtype=np.uint32)
        status = bridge.pm_pcl_preprocess(cloud, ctypes.byref(opt), ctypes.byref(out),
                                          kept.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)),
                                          ctypes.byref(report))
        if status != _abi.PM_OK:
            message = bridge.pm_pcl_last_error_message().decode(errors="replace")
            raise Error(message or lib.pm_status_string(status).decode(), status)
        details = struct_dict(report)
        details["normals_estimated"] = bool(details["normals_estimated"])
        details["kept"] = kept[:details["output_points"]].astype(np.int64)
        return read_cloud_handle(lib, out, details)
    finally:
        lib.pm_cloud_destroy(cloud)
        lib.pm_cloud_destroy(out)


def is_frame_collection(path):
    """Whether a sequence input names a ParaView collection (.pvd, .series, any case) rather
    than a frame pattern (it holds no '{' or '}'): frame n is then the n-th file it lists by
    time, in the command-line tool, particlemesh.distributed.map_frames and the Blender
    add-on alike."""
    text = os.fspath(path) if not isinstance(path, str) else path
    return "{" not in text and "}" not in text and text.lower().endswith((".pvd", ".series"))


def read_frame_collection(path):
    """The frames a ParaView collection lists (.pvd: VTK XML, <DataSet timestep= file=>;
    .series: JSON, {"files": [{"name", "time"}]}) by ascending time: a list of (time, path),
    each path joined to the collection's folder (files are taken only from that folder or
    below it). Whether the files exist is not checked. Raises Error (STATUS_FORMAT_ERROR)
    naming what is wrong: an entry outside the folder, two at one time, one without a file or
    a finite time, none."""
    lib = _library.load()
    handle = _abi.pm_frame_collection_p()
    lib.check(lib.pm_frame_collection_read(path_bytes(path), ctypes.byref(handle)))
    try:
        count = c_size_t(0)
        lib.check(lib.pm_frame_collection_get_count(handle, ctypes.byref(count)))
        frames = []
        for i in range(count.value):
            time, name = c_double(0), ctypes.c_char_p()
            lib.check(lib.pm_frame_collection_get_frame(handle, i, ctypes.byref(time),
                                                        ctypes.byref(name)))
            frames.append((time.value, os.fsdecode(name.value)))
        return frames
    finally:
        lib.pm_frame_collection_destroy(handle)


def read_mesh(path):
    """A triangle mesh from .ply, .obj, .off or .stl (polygons are fanned into triangles).
    Returns Mesh; what the file holds but the mesh does not carry (texture coordinates, face
    properties, other elements) is listed in its stats["not_read"] and named by a
    NotReadWarning."""
    lib = _library.load()
    handle = _abi.pm_mesh_p()
    lib.check(lib.pm_mesh_read(path_bytes(path), ctypes.byref(handle)))
    try:
        not_read = _not_read(lib, handle, "mesh")
        mesh = read_mesh_handle(lib, handle)  # (takes the handle over)
    finally:
        lib.pm_mesh_destroy(handle)
    if not_read:
        mesh.stats["not_read"] = not_read
        warnings.warn(f"{os.fspath(path)}: not read: {'; '.join(not_read)}", NotReadWarning, stacklevel=2)
    return mesh


def write_mesh(mesh, path):
    """Write a Mesh as .ply (binary, float32 unless far from the origin), .obj, .vtk, .vtu or
    .vtp, with its normals and attributes, atomically: under a temporary name, renamed when
    complete. An .obj holds a colour per vertex ("color", 3 components) and texture
    coordinates (the corner attribute "uv", 2 components) and no other channel; .ply holds
    texture coordinates too, .vtk, .vtu and .vtp no corner attribute: a NotWrittenWarning
    names what a format leaves out."""
    lib = _library.load()
    handle = new_mesh(lib, mesh)
    try:
        lib.check(lib.pm_mesh_write(handle, path_bytes(path)))
    finally:
        lib.pm_mesh_destroy(handle)
    obj = os.fspath(path).lower().endswith(".obj")
    if obj:
        left = [name for name, values in mesh.attributes.items()
                if not (name == "color" and np.shape(values)[-1:] == (3,))]
        if left:
            warnings.warn(f"{os.fspath(path)}: not written: {', '.join(left)} (OBJ holds a colour per vertex "
                          "only; .ply, .vtk, .vtu and .vtp hold every channel)", NotWrittenWarning, stacklevel=2)
    ply = os.fspath(path).lower().endswith(".ply")
    corners = [f"{name} (per corner)" for name, values in getattr(mesh, "corner_attributes", {}).items()
               if not ((obj or ply) and name == "uv" and np.shape(values)[-1:] == (2,))]
    if corners:
        warnings.warn(f"{os.fspath(path)}: not written: {', '.join(corners)} (only .obj and .ply hold "
                      "texture coordinates (uv), and no other value per corner)", NotWrittenWarning, stacklevel=2)


# ---- meshing --------------------------------------------------------------------------------

def _points_args(positions, normals, attributes):
    """Points, or arrays: (positions, normals, attributes)."""
    if isinstance(positions, Points):
        p = positions
        return (p.positions, p.normals if normals is None else normals,
                p.attributes if attributes is None else attributes)
    return positions, normals, attributes


def triangulate(positions, normals=None, *, attributes=None, raw=None, repair=None, orient=None,
                local_spacing=None, viewpoint=None, progress=None, **options):
    """Triangulate surface particles: by default the finished surface (a consistently oriented
    2-manifold whose closed parts face outward, with per-vertex normals); raw=True gives the
    smallest-sphere test's exact triangle set instead. repair=False skips hole filling and
    unpinching, orient=False keeps closed parts as the normals face. local_spacing=False gives
    every particle one edge limit (max_edge_factor x spacing) instead of its own from the
    sampling around it (the default, for unevenly sampled scans); viewpoint=(x, y, z) is where a
    scan was taken from, so that no triangle bridges a depth jump (taken only where the points
    look scanned from it: mesh.stats["viewpoint_used"]).

    positions: (N, 3) or Points (its normals and attributes come with it); normals: (N, 3) or
    None; attributes: {name: (N, C)} carried to the vertices. Vertex i of the result is
    particle i. Options (pm_triangulate_options, defaults from the library): spacing (0 =
    estimate), max_edge_factor, threads, max_neighbors, normal_angle, fill_holes,
    fill_edge_factor, normal_source ("auto", "input", "estimate"; the C field `normals`),
    max_triplets_per_point, min_component_triangles (remove pieces of fewer triangles; 0 keeps
    every piece). Returns Mesh; mesh.stats holds pm_triangulate_stats."""
    lib = _library.load()
    positions, normals, attributes = _points_args(positions, normals, attributes)
    opt = _options.TRIANGULATE.build(lib, options)
    for value, flag, when in ((raw, _abi.PM_TRIANGULATE_RAW, True),
                              (repair, _abi.PM_TRIANGULATE_NO_REPAIR, False),
                              (orient, _abi.PM_TRIANGULATE_NO_ORIENT, False),
                              (local_spacing, _abi.PM_TRIANGULATE_GLOBAL_SPACING, False)):
        if value is not None:
            opt.flags = (opt.flags | flag) if bool(value) == when else (opt.flags & ~flag)
    if viewpoint is not None:
        v = np.asarray(viewpoint, dtype=np.float64).reshape(-1)
        if v.size != 3 or not np.all(np.isfinite(v)):
            raise Error(f"viewpoint must be 3 finite numbers (x, y, z), got {viewpoint!r}",
                        _abi.PM_STATUS_INVALID_ARGUMENT)
        opt.flags |= _abi.PM_TRIANGULATE_VIEWPOINT
        opt.viewpoint[:] = [float(x) for x in v]
    stats = _abi.pm_triangulate_stats(struct_size=ctypes.sizeof(_abi.pm_triangulate_stats))
    cloud = new_cloud(lib, positions, normals, attributes)
    mesh = _abi.pm_mesh_p()  # NULL unless the call succeeds; destroying NULL is a no-op
    try:
        with Hook(progress) as hook:
            opt.progress = hook.c_function
            status = lib.pm_triangulate(cloud, ctypes.byref(opt), ctypes.byref(mesh),
                                        ctypes.byref(stats))
        hook.finish(lib, status)
        return read_mesh_handle(lib, mesh, struct_dict(stats))
    finally:
        lib.pm_cloud_destroy(cloud)
        lib.pm_mesh_destroy(mesh)


def _tile_options(opt, domain_min, cells):
    """Write polygonize's tile arguments (domain_min=, cells=) into the options struct."""
    if domain_min is not None:
        d = np.asarray(domain_min, dtype=np.float64).reshape(-1)
        if d.size != 3:
            raise Error(f"domain_min must be 3 numbers (x, y, z), got {d.size}",
                        _abi.PM_STATUS_INVALID_ARGUMENT)
        opt.flags |= _abi.PM_POLYGONIZE_DOMAIN_MIN
        opt.domain_min[:] = [float(v) for v in d]
    if cells is not None:
        try:
            low, high = (np.asarray(c) for c in cells)
        except (TypeError, ValueError):
            raise Error("cells must be ((i0, j0, k0), (i1, j1, k1))",
                        _abi.PM_STATUS_INVALID_ARGUMENT) from None
        for name, c in (("cells[0]", low), ("cells[1]", high)):
            if c.shape != (3,) or c.dtype.kind not in "iu":
                raise Error(f"{name} must be 3 integers, got {c.tolist()!r}",
                            _abi.PM_STATUS_INVALID_ARGUMENT)
        limits = np.iinfo(np.int64)
        for c in (low, high):
            if any(not limits.min <= int(v) <= limits.max for v in c):
                raise Error(f"cells {c.tolist()} out of the int64 range",
                            _abi.PM_STATUS_INVALID_ARGUMENT)
        opt.flags |= _abi.PM_POLYGONIZE_CELL_RANGE
        opt.cell_min[:] = [int(v) for v in low]
        opt.cell_max[:] = [int(v) for v in high]


def _polygonize_options(lib, function, radius, threshold, kernel, cell, domain_min, cells,
                        lattice_anchor, options):
    """pm_polygonize_options from polygonize()'s keywords (`function` names the caller)."""
    if cell is not None:
        if options.get("cell_size") is not None:
            raise TypeError(f"{function}() got both cell and cell_size (the same option)")
        options["cell_size"] = cell
    options.update(radius=radius, threshold=threshold, kernel=kernel)
    opt = _options.POLYGONIZE.build(lib, options)
    _tile_options(opt, domain_min, cells)
    if lattice_anchor not in ("particles", "space"):
        raise Error(f"lattice_anchor must be 'particles' or 'space', not {lattice_anchor!r}",
                    _abi.PM_STATUS_INVALID_ARGUMENT)
    if lattice_anchor == "space":
        opt.flags |= _abi.PM_POLYGONIZE_ANCHOR_IN_SPACE
    return opt


def polygonize(positions, radius=None, threshold=None, kernel=None, cell=None, *, radii=None,
               strengths=None, attributes=None, domain_min=None, cells=None,
               lattice_anchor="particles", progress=None, **options):
    """The iso-surface F(x) = threshold of volume particles, F(x) = sum_i w_i g(|x - p_i|^2 /
    R_i^2), by marching cubes on a sparse grid: a closed, outward mesh with normals from the
    field's gradient (no vertex when the field stays below the threshold).

    positions: (N, 3) or Points; radius R (None = default_radius: 2 x the median spacing, or
    more when that leaves over a tenth of the particles outside the surface) or radii, one per
    particle; strengths w_i (None = 1; |w_i| <= 1e30); threshold T (None = half the field
    inside evenly packed particles); kernel "wyvill", "poly4", "poly6" or "blinn"; cell the grid cell (the C
    field cell_size; None = R / 4); attributes {name: (N, C)} interpolated onto the vertices
    with the normalised kernel weights. lattice_anchor "particles" (the lattice at the
    particles' box) or "space" (its nodes at multiples of the cell: the frames of a sequence
    do not shimmer; what the command-line tool uses). Other options (pm_polygonize_options):
    threads, max_grid_bytes, domain_max_radius, domain_grid_radius.

    A tile of a larger cloud (what particlemesh.distributed.polygonize_tiled runs):
    domain_min=(x, y, z), the whole cloud's lower corner, anchors the lattice and the particle
    grid as for the whole cloud; domain_max_radius its largest radius and, with radii,
    domain_grid_radius its particle_grid_radius(radii); cells=((i0, j0, k0),
    (i1, j1, k1)) meshes only the lattice cells in that range (stats["origin"] is the
    lattice's node 0). Returns Mesh; mesh.stats holds pm_polygonize_stats."""
    lib = _library.load()
    positions, _, attributes = _points_args(positions, None, attributes)
    opt = _polygonize_options(lib, "polygonize", radius, threshold, kernel, cell, domain_min,
                              cells, lattice_anchor, options)
    stats = _abi.pm_polygonize_stats(struct_size=ctypes.sizeof(_abi.pm_polygonize_stats))
    cloud = new_cloud(lib, positions, None, attributes)
    mesh = _abi.pm_mesh_p()
    try:
        count = c_size_t(0)
        lib.check(lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
        r = per_point(radii, "radii", count.value)
        s = per_point(strengths, "strengths", count.value)
        with Hook(progress) as hook:
            opt.progress = hook.c_function
            status = lib.pm_polygonize_ex(cloud, ptr(r, c_double), ptr(s, c_double),
                                          ctypes.byref(opt), ctypes.byref(mesh),
                                          ctypes.byref(stats))
        hook.finish(lib, status)
        return read_mesh_handle(lib, mesh, struct_dict(stats))
    finally:
        lib.pm_cloud_destroy(cloud)
        lib.pm_mesh_destroy(mesh)


def polygonize_attributes(positions, points, radius=None, threshold=None, kernel=None, cell=None,
                          *, radii=None, strengths=None, attributes=None, domain_min=None,
                          cells=None, lattice_anchor="particles", progress=None, **options):
    """The particles' attributes at `points` ((M, 3)), interpolated exactly as polygonize()
    interpolates them at its vertices (sum_i w_i a_i / sum_i w_i with the field's kernel
    weights; 0 where no kernel reaches): called with polygonize()'s arguments and the float64
    vertices of its mesh, it gives that mesh's attributes bit for bit. So a caller can mesh
    without attributes first and ask for them later. Takes every argument polygonize() takes
    (only those of the field, threads and progress matter here). attributes {name: (N, C)}
    (or those of `positions` given as Points). Returns {name: (M, C) float32}, empty
    without attributes."""
    lib = _library.load()
    positions, _, attributes = _points_args(positions, None, attributes)
    points = vec3(points, "points")
    opt = _polygonize_options(lib, "polygonize_attributes", radius, threshold, kernel, cell,
                              domain_min, cells, lattice_anchor, options)
    cloud = new_cloud(lib, positions, None, attributes)
    try:
        count = c_size_t(0)
        lib.check(lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
        r = per_point(radii, "radii", count.value)
        s = per_point(strengths, "strengths", count.value)
        shapes = [(name, channels(values, name, count.value).shape[1])
                  for name, values in (attributes or {}).items()]
        out = np.empty(len(points) * sum(c for _, c in shapes), dtype=np.float32)
        with Hook(progress) as hook:
            opt.progress = hook.c_function
            status = lib.pm_polygonize_attributes(cloud, ptr(r, c_double), ptr(s, c_double),
                                                  ctypes.byref(opt), ptr(points, c_double),
                                                  len(points), ptr(out, c_float), out.size)
        hook.finish(lib, status)
    finally:
        lib.pm_cloud_destroy(cloud)
    values, start = {}, 0
    for name, components in shapes:
        end = start + len(points) * components
        values[name] = out[start:end].reshape(len(points), components)
        start = end
    return values


def _smooth_options(lib, mesh, scheme, levels, crease_edges, crease_sharpness, options):
    """pm_smooth_options from smooth()'s keywords, and the arrays it points into (kept alive
    by the caller until the call returns)."""
    options.update(scheme=scheme, levels=levels)
    opt = _options.SMOOTH.build(lib, options)
    edges = sharpness = None
    if crease_edges is not None:
        edges = np.asarray(crease_edges)
        if edges.size == 0:
            edges = edges.reshape(0, 2).astype(np.int32)
        edges = vertex_indices(edges, "crease_edges", 2, rows="K", item=("crease edge", "end"))
        opt.crease_count = len(edges)
        opt.crease_edges = ptr(edges, ctypes.c_int32)
        if crease_sharpness is not None:
            sharpness = per_point(crease_sharpness, "crease_sharpness", len(edges), np.float32)
            opt.crease_sharpness = ptr(sharpness, ctypes.c_float)
    elif crease_sharpness is not None:
        raise Error("crease_sharpness needs crease_edges", _abi.PM_STATUS_INVALID_ARGUMENT)
    return opt, (edges, sharpness)


def smooth(mesh, scheme=None, levels=None, *, crease_edges=None, crease_sharpness=None,
           progress=None, **options):
    """Subdivide a triangle mesh into a smooth one: scheme "loop" (approximating, through
    OpenSubdiv; with limit=True, the default, every vertex at its exact limit position with
    the exact limit normal) or "butterfly" (interpolating, through OpenMesh: the original
    vertices stay). Each of `levels` splits every triangle into four (input triangle f's
    children are triangles f x 4^levels onward). Normals and every attribute are carried
    through, and every corner attribute (texture coordinates) linearly over each input
    triangle.

    crease_edges: (K, 2) vertex pairs that stay sharp (Loop), crease_sharpness: K values
    (None = infinitely sharp). Other options (pm_smooth_options): limit, boundary
    ("edge-and-corner", "edge-only"), crease_method ("uniform", "chaikin"), threads,
    max_triangles. Loop takes non-manifold meshes (an edge in more than two triangles stays
    an infinitely sharp crease, as in OpenSubdiv); butterfly needs a 2-manifold. Returns Mesh. For many meshes with the
    same triangles (frames of an animation), a Smoother refines them once."""
    lib = _library.load()
    opt, _keep = _smooth_options(lib, mesh, scheme, levels, crease_edges, crease_sharpness, options)
    source = new_mesh(lib, mesh)
    out = _abi.pm_mesh_p()
    try:
        with Hook(progress) as hook:
            opt.progress = hook.c_function
            status = lib.pm_smooth(source, ctypes.byref(opt), ctypes.byref(out))
        hook.finish(lib, status)
        return read_mesh_handle(lib, out)
    finally:
        lib.pm_mesh_destroy(source)
        lib.pm_mesh_destroy(out)


class Smoother:
    """Refine once, evaluate many: smooth() for meshes that share their triangles (frames of
    an animation, a simulation's steps) while their vertices move.

        smoother = pm.Smoother(mesh, levels=2)            # checks and refines once
        for frame in frames:
            if smoother.matches(frame):                   # same triangles, same vertex count
                out = smoother.evaluate(frame)            # == pm.smooth(frame, levels=2)

    The constructor takes smooth()'s arguments (scheme, levels, crease_edges,
    crease_sharpness, progress for its own work, and the pm_smooth_options keywords) and
    refuses what smooth() refuses. evaluate(mesh) gives exactly what smooth(mesh, ...) would
    with the same arguments, from the mesh's vertices and attributes (the corner attributes,
    texture coordinates, are the constructor's mesh's: they belong to the triangles): with
    Loop, several times faster (OpenSubdiv's refinement and its weights are kept: about 60 bytes per output
    triangle while the Smoother lives); with butterfly, the whole subdivision again. A mesh
    with other triangles raises Error (status STATUS_INVALID_ARGUMENT). close() (or a with
    block) frees it at once."""

    def __init__(self, mesh, scheme=None, levels=None, *, crease_edges=None,
                 crease_sharpness=None, progress=None, **options):
        self._lib = _library.load()
        self._handle = None
        opt, _keep = _smooth_options(self._lib, mesh, scheme, levels, crease_edges,
                                     crease_sharpness, options)
        # (the corner attributes belong to the triangles: evaluate() gives these)
        source = new_mesh(self._lib, mesh, with_attributes=False, with_corner_attributes=True)
        handle = _abi.pm_smoother_p()
        try:
            with Hook(progress) as hook:
                opt.progress = hook.c_function
                status = self._lib.pm_smoother_create(source, ctypes.byref(opt),
                                                      ctypes.byref(handle))
            hook.finish(self._lib, status)
        except BaseException:
            self._lib.pm_smoother_destroy(handle)
            raise
        finally:
            self._lib.pm_mesh_destroy(source)
        self._handle = handle
        self.vertex_count = len(mesh.vertices)
        self.triangle_count = len(mesh.triangles)

    def _live(self):
        if self._handle is None:
            raise Error("the Smoother is closed", _abi.PM_STATUS_INVALID_ARGUMENT)
        return self._handle

    def matches(self, mesh):
        """Whether `mesh` has this smoother's triangles (in the same order) and vertex count."""
        handle = self._live()
        if len(mesh.vertices) != self.vertex_count or len(mesh.triangles) != self.triangle_count:
            return False
        source = new_mesh(self._lib, mesh, with_attributes=False)
        try:
            out = ctypes.c_int32(0)
            self._lib.check(self._lib.pm_smoother_matches(handle, source, ctypes.byref(out)))
            return bool(out.value)
        finally:
            self._lib.pm_mesh_destroy(source)

    def evaluate(self, mesh):
        """The smooth mesh of `mesh` (this smoother's triangles, new vertices and attributes):
        what smooth() gives for it. Returns Mesh."""
        handle = self._live()
        source = new_mesh(self._lib, mesh, with_corner_attributes=False)
        out = _abi.pm_mesh_p()
        try:
            self._lib.check(self._lib.pm_smoother_evaluate(handle, source, ctypes.byref(out)))
            return read_mesh_handle(self._lib, out)
        finally:
            self._lib.pm_mesh_destroy(source)
            self._lib.pm_mesh_destroy(out)

    def close(self):
        """Free the smoother now (evaluate and matches then raise Error)."""
        if self._handle is not None:
            self._lib.pm_smoother_destroy(self._handle)
            self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *_exc):
        self.close()

    def __del__(self):
        if getattr(self, "_handle", None) is not None:
            self.close()


def topology(mesh):
    """The library's topology report of a mesh as a dict: vertices, triangles, vertices_used,
    edges, boundary_edges, manifold_edges, nonmanifold_edges, nonmanifold_vertices,
    degenerate_triangles, duplicate_triangles, orientation_conflicts, boundary_loops,
    components, closed_components, euler_characteristic, and the booleans manifold, closed,
    consistently_oriented, outward (every closed part faces away from the solid it bounds:
    positive volume, or negative for a closed part inside another, a cavity's wall)."""
    lib = _library.load()
    handle = new_mesh(lib, mesh, with_attributes=False)
    try:
        report = _abi.pm_topology_report(struct_size=ctypes.sizeof(_abi.pm_topology_report))
        lib.check(lib.pm_mesh_report(handle, ctypes.byref(report)))
    finally:
        lib.pm_mesh_destroy(handle)
    out = struct_dict(report)
    for flag in ("manifold", "closed", "consistently_oriented", "outward"):
        out[flag] = bool(out[flag])
    return out


def components(mesh):
    """The mesh's connected pieces (triangles that share vertices), numbered in the order of
    their first triangle, as a dict of numpy arrays: "vertex" (V,) int64, each vertex's piece
    (-1 for a vertex no triangle uses; a triangle's piece is its corners'), and per piece
    "triangles" (C,) int64, "area" (C,) and "volume" (C,) float64 (the volume it encloses: exact
    for a closed, consistently oriented piece, positive when it faces outward). E.g. the
    droplets of a fluid surface: keep = c["volume"][c["vertex"][mesh.triangles[:, 0]]] > v."""
    lib = _library.load()
    handle = new_mesh(lib, mesh, with_attributes=False)
    try:
        count = c_size_t(0)
        lib.check(lib.pm_mesh_components(handle, ctypes.byref(count), None, None, None, None, 0))
        n = count.value
        vertex = np.empty(len(mesh.vertices), dtype=np.uint32)
        triangles = np.empty(n, dtype=np.uint64)
        area = np.empty(n, dtype=np.float64)
        volume = np.empty(n, dtype=np.float64)
        lib.check(lib.pm_mesh_components(handle, ctypes.byref(count), ptr(vertex, c_uint32),
                                         ptr(triangles, c_uint64), ptr(area, c_double),
                                         ptr(volume, c_double), n))
    finally:
        lib.pm_mesh_destroy(handle)
    labels = vertex.astype(np.int64)
    labels[vertex == np.iinfo(np.uint32).max] = -1
    return {"vertex": labels, "triangles": triangles.astype(np.int64), "area": area, "volume": volume}


# ---- helpers --------------------------------------------------------------------------------

def estimate_spacing(positions, max_samples=None, threads=0):
    """The median nearest-neighbour distance of the distinct points (what triangulate takes
    for spacing=0), or with max_samples that of an evenly strided sample of at most that many
    points (within about 1 % on even particles, for previews)."""
    lib = _library.load()
    cloud = new_cloud(lib, positions)
    try:
        out = c_double(0)
        if max_samples is None:
            lib.check(lib.pm_estimate_spacing(cloud, int(threads), ctypes.byref(out)))
        else:
            lib.check(lib.pm_estimate_spacing_sampled(cloud, int(max_samples), int(threads),
                                                      ctypes.byref(out)))
        return out.value
    finally:
        lib.pm_cloud_destroy(cloud)


def thin(positions, min_distance):
    """Indices (ascending, int64) of an even subset of the points: no two kept points closer
    than min_distance, every dropped one within min_distance of a kept one."""
    lib = _library.load()
    cloud = new_cloud(lib, positions)
    try:
        count = c_size_t(0)
        lib.check(lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
        out = np.empty(count.value, dtype=np.uint32)
        lib.check(lib.pm_cloud_thin(cloud, float(min_distance), ptr(out, c_uint32), out.size,
                                    ctypes.byref(count)))
        return out[:count.value].astype(np.int64)
    finally:
        lib.pm_cloud_destroy(cloud)


def triangle_edges(triangles, vertex_count, threads=0, out=None):
    """The edges of a triangle list: (E, 2) uint32, each edge once as (a, b) with a < b,
    ordered; and (3 T,) uint32, per triangle corner the edge to the next corner (what hosts
    that store edges, such as Blender, need). `out`: (edges, corners), C-contiguous uint32
    arrays of at least (3 T, 2) and (3 T,) to write into (the results are views of them): a
    caller numbering frame after frame keeps its pages instead of faulting in fresh ones."""
    lib = _library.load()
    # Unsigned like the C ABI (and Blender's corner arrays), checked here so that a negative
    # index is named as passed, not as its 32-bit wrap.
    tris = vertex_indices(triangles, "triangles", 3, dtype=np.uint32)
    if int(vertex_count) < 0:
        raise Error(f"vertex_count must not be negative, got {int(vertex_count)}",
                    _abi.PM_STATUS_INVALID_ARGUMENT)
    nt = len(tris)
    if out is None:
        edges = np.empty((3 * nt, 2), dtype=np.uint32)
        corners = np.empty(3 * nt, dtype=np.uint32)
    else:
        if not isinstance(out, (tuple, list)) or len(out) != 2:
            raise Error(f"out must be a pair (edges, corners) of arrays, got {type(out).__name__}",
                        _abi.PM_STATUS_INVALID_ARGUMENT)
        edges, corners = out
        for name, a, shape in (("edges", edges, (3 * nt, 2)), ("corners", corners, (3 * nt,))):
            if (not isinstance(a, np.ndarray) or a.dtype != np.uint32 or not a.flags.c_contiguous
                    or not a.flags.writeable or a.ndim != len(shape) or a.shape[0] < shape[0]
                    or a.shape[1:] != shape[1:]):
                raise Error(f"out's {name} must be a writable C-contiguous uint32 array of at least "
                            f"shape {shape}, got {getattr(a, 'dtype', type(a).__name__)} "
                            f"{getattr(a, 'shape', '')}", _abi.PM_STATUS_INVALID_ARGUMENT)
        if np.may_share_memory(edges, corners) or any(np.may_share_memory(a, tris) for a in (edges, corners)):
            raise Error("out's edges and corners must not overlap each other or the triangles",
                        _abi.PM_STATUS_INVALID_ARGUMENT)
        edges, corners = edges[:3 * nt], corners[:3 * nt]
    count = c_size_t(0)
    lib.check(lib.pm_triangle_edges(ptr(tris, c_uint32), nt, int(vertex_count), int(threads),
                                    ptr(edges, c_uint32), len(edges), ptr(corners, c_uint32),
                                    ctypes.byref(count)))
    return edges[:count.value], corners


def ray_crossings(mesh, points, threads=0):
    """Per point, how many of the mesh's triangles the ray from it straight up (+z) crosses:
    (N,) uint64. A point is inside a closed surface when its count is odd, whatever the
    winding. Watertight (a ray through an edge or vertex counts once, each edge's test
    evaluated from its lower-numbered end), so meshes cut from one surface, their vertices
    numbered in the same relative order, give counts that add up to the whole one's."""
    lib = _library.load()
    q = vec3(points, "points")
    handle = new_mesh(lib, mesh, with_attributes=False)
    try:
        out = np.zeros(len(q), dtype=np.uint64)
        lib.check(lib.pm_mesh_ray_crossings(handle, ptr(q, c_double), len(q), int(threads),
                                            ptr(out, c_uint64)))
    finally:
        lib.pm_mesh_destroy(handle)
    return out


def default_radius(positions, strengths=None, kernel=None, threads=0):
    """The radius polygonize takes for radius=None (spherical kernels of one radius): 2 x the
    median particle spacing, or, when that leaves over a tenth of the particles outside the
    surface, the larger radius their packing asks for (up to twice as much: SPH particles in
    motion sit closer than their rest spacing). For callers that mesh a cloud in pieces and
    must give every piece the whole cloud's radius."""
    lib = _library.load()
    k = _options.POLYGONIZE.convert("kernel", "kernel", kernel or "wyvill")
    cloud = new_cloud(lib, positions)
    try:
        count = c_size_t(0)
        lib.check(lib.pm_cloud_get_count(cloud, ctypes.byref(count)))
        s = per_point(strengths, "strengths", count.value)
        out = c_double(0)
        lib.check(lib.pm_default_radius(cloud, ptr(s, c_double), k, int(threads), ctypes.byref(out)))
        return out.value
    finally:
        lib.pm_cloud_destroy(cloud)


def particle_grid_radius(radii):
    """The radius the field's particle grid is sized by for per-particle radii (polygonize's
    radii=): the largest, or, where a few are far larger than the rest (one particle 20 times
    the others), a smaller one, the particles above it kept apart and visited by every
    evaluation. For callers that mesh a cloud in tiles: give every tile
    domain_grid_radius=particle_grid_radius(all radii) with domain_max_radius=max(all radii)."""
    lib = _library.load()
    r = np.ascontiguousarray(radii, dtype=np.float64).reshape(-1)
    out = c_double(0)
    lib.check(lib.pm_particle_grid_radius(ptr(r, c_double), len(r), ctypes.byref(out)))
    return out.value


def lattice_field(kernel, radius, spacing):
    """The field deep inside a simple cubic lattice of unit-strength particles with this
    spacing and radius: polygonize's default threshold is half of it, and an iso level given
    as a fraction of the rest density is that fraction of lattice_field(kernel, R, rest
    spacing)."""
    lib = _library.load()
    k = _options.POLYGONIZE.convert("kernel", "kernel", kernel)
    out = c_double(0)
    lib.check(lib.pm_lattice_field(k, float(radius), float(spacing), ctypes.byref(out)))
    return out.value

