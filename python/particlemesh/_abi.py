"""ctypes mirror of the C ABI: native/include/particlemesh/particlemesh.h and the PCL bridge's
pcl_bridge/include/particlemesh_pcl/particlemesh_pcl_c.h.

Everything here is named exactly as in the headers (structs, fields, #defines, functions), so
that a test can compare it with them mechanically: a C program built with the tests prints the
size and offset of every struct and field and the value of every #define, and the test
compares those, and every function's argument and result types parsed from the headers, with
this module (tests/python/test_abi.py). A field appended to a header's options struct is
appended here (the test fails until it is), and becomes a keyword argument of the matching
Python function with the library's default (see _options.py)."""

from ctypes import (CFUNCTYPE, POINTER, Structure, c_char_p, c_double, c_float, c_int, c_int32,
                    c_int64, c_size_t, c_uint32, c_uint64, c_void_p)

# ---- library ------------------------------------------------------------------------------

PM_ABI_VERSION = 1

# pm_status (an enum: int-sized)
pm_status = c_int
PM_OK = 0
PM_STATUS_INVALID_ARGUMENT = 1
PM_STATUS_INVALID_INPUT = 2
PM_STATUS_IO_ERROR = 3
PM_STATUS_FORMAT_ERROR = 4
PM_STATUS_OUT_OF_MEMORY = 5
PM_STATUS_CANCELLED = 6
PM_STATUS_LIMIT_EXCEEDED = 7
PM_STATUS_INTERNAL = 8

# Opaque handles.
pm_cloud_p = c_void_p
pm_mesh_p = c_void_p
pm_field_p = c_void_p
pm_ray_hits_p = c_void_p
pm_smoother_p = c_void_p
pm_frame_collection_p = c_void_p

pm_progress_fn = CFUNCTYPE(c_int, c_void_p, c_char_p, c_double)

# ---- triangulation ------------------------------------------------------------------------

PM_TRIANGULATE_RAW = 0x1
PM_TRIANGULATE_NO_REPAIR = 0x2
PM_TRIANGULATE_NO_ORIENT = 0x4
PM_TRIANGULATE_GLOBAL_SPACING = 0x8
PM_TRIANGULATE_VIEWPOINT = 0x10

PM_NORMALS_AUTO = 0
PM_NORMALS_INPUT = 1
PM_NORMALS_ESTIMATE = 2


class pm_triangulate_options(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("spacing", c_double),
        ("max_edge_factor", c_double),
        ("threads", c_int32),
        ("max_neighbors", c_uint32),
        ("flags", c_uint32),
        ("progress", pm_progress_fn),
        ("progress_user_data", c_void_p),
        ("normal_angle", c_double),
        ("fill_holes", c_uint32),
        ("fill_edge_factor", c_double),
        ("normals", c_int32),
        ("max_triplets_per_point", c_uint32),
        ("viewpoint", c_double * 3),
        ("min_component_triangles", c_uint32),
    ]


class pm_triangulate_stats(Structure):
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
        ("holes_filled", c_uint64),
        ("holes_left", c_uint64),
        ("largest_hole_left", c_uint64),
        ("pinches_resolved", c_uint64),
        ("unused_points", c_uint64),
        ("normals_estimated", c_int32),
        ("triplets", c_uint64),
        ("rejected_conormal", c_uint64),
        ("local_spacing", c_double * 5),
        ("viewpoint_used", c_int32),
        ("rejected_shadow", c_uint64),
        ("looks_like_volume", c_int32),
        ("narrow_loops", c_uint64),
        ("narrow_loop_width", c_double),
        ("narrow_loop_edges", c_uint64),
        ("sampling_irregularity", c_double),
        ("reach_factor", c_double),
        ("sampling_thickness", c_double),
        ("components_removed", c_uint64),
        ("component_triangles_removed", c_uint64),
        ("stray_pieces", c_uint64),
        ("stray_piece_triangles", c_uint64),
        ("stray_piece_largest", c_uint64),
        ("small_handles_removed", c_uint64),
        ("shortened_limits", c_uint64),
        ("near_duplicates", c_uint64),
        ("flat_pieces_opened", c_uint64),
        ("nearly_closed_turned", c_uint64),
        ("folded_triangles", c_uint64),
        ("uncapped_spacing_p90", c_double),
        ("capped_spacing_over_nn", c_double),
    ]


# ---- meshes -------------------------------------------------------------------------------

class pm_topology_report(Structure):
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


# ---- smoothing ----------------------------------------------------------------------------

PM_SMOOTH_LOOP = 0
PM_SMOOTH_BUTTERFLY = 1
PM_BOUNDARY_EDGE_AND_CORNER = 0
PM_BOUNDARY_EDGE_ONLY = 1
PM_CREASE_UNIFORM = 0
PM_CREASE_CHAIKIN = 1
PM_CREASE_INFINITE = 10.0


class pm_smooth_options(Structure):
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
        ("progress", pm_progress_fn),
        ("progress_user_data", c_void_p),
    ]


# ---- volume particles ---------------------------------------------------------------------

PM_KERNEL_WYVILL = 0
PM_KERNEL_POLY4 = 1
PM_KERNEL_POLY6 = 2
PM_KERNEL_BLINN = 3


class pm_polygonize_options(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("kernel", c_int32),
        ("radius", c_double),
        ("threshold", c_double),
        ("cell_size", c_double),
        ("threads", c_int32),
        ("max_grid_bytes", c_uint64),
        ("progress", pm_progress_fn),
        ("progress_user_data", c_void_p),
        ("anisotropic", c_int32),
        ("aniso_neighbor_radius", c_double),
        ("aniso_max_stretch", c_double),
        ("aniso_min_neighbors", c_int32),
        ("aniso_smoothing", c_double),
        ("min_component_volume", c_double),
        ("min_component_particles", c_double),
        ("taubin_iterations", c_int32),
        ("taubin_lambda", c_double),
        ("taubin_mu", c_double),
        ("flags", c_uint32),
        ("domain_min", c_double * 3),
        ("domain_max_radius", c_double),
        ("cell_min", c_int64 * 3),
        ("cell_max", c_int64 * 3),
        ("collapse_edges", c_double),
        ("domain_grid_radius", c_double),
    ]


PM_POLYGONIZE_DOMAIN_MIN = 0x1
PM_POLYGONIZE_CELL_RANGE = 0x2
PM_POLYGONIZE_ANCHOR_IN_SPACE = 0x4


class pm_polygonize_stats(Structure):
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
        ("anisotropic", c_int32),
        ("anisotropic_particles", c_uint64),
        ("components_removed", c_uint64),
        ("calibration_ratio", c_double),
        ("origin", c_double * 3),
        ("enclosed_fraction", c_double),
        ("density_radius", c_double),
        ("edges_collapsed", c_uint64),
    ]


class pm_field_options(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("kernel", c_int32),
        ("radius", c_double),
        ("threshold", c_double),
        ("threads", c_int32),
        ("progress", pm_progress_fn),
        ("progress_user_data", c_void_p),
        ("anisotropic", c_int32),
        ("aniso_neighbor_radius", c_double),
        ("aniso_max_stretch", c_double),
        ("aniso_min_neighbors", c_int32),
        ("aniso_smoothing", c_double),
    ]


class pm_raycast_options(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("t_min", c_double),
        ("t_max", c_double),
        ("threads", c_int32),
        ("progress", pm_progress_fn),
        ("progress_user_data", c_void_p),
    ]


PM_CSG_UNION = 0
PM_CSG_INTERSECTION = 1
PM_CSG_DIFFERENCE = 2

# ---- functions ----------------------------------------------------------------------------

_f32p = POINTER(c_float)
_f64p = POINTER(c_double)
_i32p = POINTER(c_int32)
_u32p = POINTER(c_uint32)
_u64p = POINTER(c_uint64)
_sizep = POINTER(c_size_t)
_cloudpp = POINTER(pm_cloud_p)
_meshpp = POINTER(pm_mesh_p)

#: name: (restype, argtypes) of every function particlemesh.h declares.
FUNCTIONS = {
    "pm_abi_version": (c_uint32, []),
    "pm_version_string": (c_char_p, []),
    "pm_status_string": (c_char_p, [pm_status]),
    "pm_last_error_message": (c_char_p, []),
    # point clouds
    "pm_cloud_create": (pm_status, [_f64p, _f64p, c_size_t, _cloudpp]),
    "pm_cloud_create_f32": (pm_status, [_f32p, _f32p, c_size_t, _cloudpp]),
    "pm_cloud_read": (pm_status, [c_char_p, _cloudpp]),
    "pm_cloud_get_count": (pm_status, [pm_cloud_p, _sizep]),
    "pm_cloud_has_normals": (pm_status, [pm_cloud_p, _i32p]),
    "pm_cloud_copy_positions_f32": (pm_status, [pm_cloud_p, _f32p, c_size_t]),
    "pm_cloud_copy_normals_f32": (pm_status, [pm_cloud_p, _f32p, c_size_t]),
    "pm_cloud_copy_positions": (pm_status, [pm_cloud_p, _f64p, c_size_t]),
    "pm_cloud_copy_normals": (pm_status, [pm_cloud_p, _f64p, c_size_t]),
    "pm_cloud_destroy": (None, [pm_cloud_p]),
    "pm_estimate_spacing": (pm_status, [pm_cloud_p, c_int32, _f64p]),
    "pm_estimate_spacing_sampled": (pm_status, [pm_cloud_p, c_size_t, c_int32, _f64p]),
    "pm_cloud_thin": (pm_status, [pm_cloud_p, c_double, _u32p, c_size_t, _sizep]),
    # frame collections
    "pm_frame_collection_read": (pm_status, [c_char_p, POINTER(pm_frame_collection_p)]),
    "pm_frame_collection_get_count": (pm_status, [pm_frame_collection_p, _sizep]),
    "pm_frame_collection_get_frame": (pm_status, [pm_frame_collection_p, c_size_t, _f64p,
                                                  POINTER(c_char_p)]),
    "pm_frame_collection_destroy": (None, [pm_frame_collection_p]),
    # triangulation
    "pm_triangulate_options_init": (None, [POINTER(pm_triangulate_options)]),
    "pm_triangulate": (pm_status, [pm_cloud_p, POINTER(pm_triangulate_options), _meshpp,
                                   POINTER(pm_triangulate_stats)]),
    # meshes
    "pm_mesh_create": (pm_status, [_f64p, c_size_t, _i32p, c_size_t, _f64p, _meshpp]),
    "pm_mesh_read": (pm_status, [c_char_p, _meshpp]),
    "pm_mesh_write": (pm_status, [pm_mesh_p, c_char_p]),
    "pm_mesh_get_counts": (pm_status, [pm_mesh_p, _sizep, _sizep]),
    "pm_mesh_has_normals": (pm_status, [pm_mesh_p, _i32p]),
    "pm_mesh_copy_positions": (pm_status, [pm_mesh_p, _f64p, c_size_t]),
    "pm_mesh_copy_positions_f32": (pm_status, [pm_mesh_p, _f32p, c_size_t]),
    "pm_mesh_copy_normals_f32": (pm_status, [pm_mesh_p, _f32p, c_size_t]),
    "pm_mesh_copy_normals": (pm_status, [pm_mesh_p, _f64p, c_size_t]),
    "pm_mesh_copy_triangles": (pm_status, [pm_mesh_p, _i32p, c_size_t]),
    "pm_mesh_lend_arrays": (pm_status, [pm_mesh_p, POINTER(_f64p), POINTER(_f64p), POINTER(_u32p)]),
    "pm_mesh_destroy": (None, [pm_mesh_p]),
    "pm_mesh_report": (pm_status, [pm_mesh_p, POINTER(pm_topology_report)]),
    "pm_triangle_edges": (pm_status, [_u32p, c_size_t, c_size_t, c_int32, _u32p, c_size_t, _u32p,
                                      _sizep]),
    "pm_mesh_ray_crossings": (pm_status, [pm_mesh_p, _f64p, c_size_t, c_int32, POINTER(c_uint64)]),
    # per-vertex attributes
    "pm_mesh_set_attribute": (pm_status, [pm_mesh_p, c_char_p, c_int32, _f32p, c_size_t]),
    "pm_mesh_get_attribute_components": (pm_status, [pm_mesh_p, c_char_p, _i32p]),
    "pm_mesh_copy_attribute": (pm_status, [pm_mesh_p, c_char_p, _f32p, c_size_t]),
    "pm_mesh_lend_attribute": (pm_status, [pm_mesh_p, c_char_p, POINTER(_f32p)]),
    "pm_mesh_get_attribute_count": (pm_status, [pm_mesh_p, _sizep]),
    "pm_mesh_get_attribute_name": (pm_status, [pm_mesh_p, c_size_t, POINTER(c_char_p)]),
    "pm_mesh_set_corner_attribute": (pm_status, [pm_mesh_p, c_char_p, c_int32, _f32p, c_size_t]),
    "pm_mesh_get_corner_attribute_count": (pm_status, [pm_mesh_p, _sizep]),
    "pm_mesh_get_corner_attribute_name": (pm_status, [pm_mesh_p, c_size_t, POINTER(c_char_p)]),
    "pm_mesh_get_corner_attribute_components": (pm_status, [pm_mesh_p, c_char_p, _i32p]),
    "pm_mesh_copy_corner_attribute": (pm_status, [pm_mesh_p, c_char_p, _f32p, c_size_t]),
    "pm_cloud_set_attribute": (pm_status, [pm_cloud_p, c_char_p, c_int32, _f32p, c_size_t]),
    # smoothing
    "pm_smooth_options_init": (None, [POINTER(pm_smooth_options)]),
    "pm_smooth": (pm_status, [pm_mesh_p, POINTER(pm_smooth_options), _meshpp]),
    "pm_smoother_create": (pm_status, [pm_mesh_p, POINTER(pm_smooth_options),
                                       POINTER(pm_smoother_p)]),
    "pm_smoother_matches": (pm_status, [pm_smoother_p, pm_mesh_p, _i32p]),
    "pm_smoother_evaluate": (pm_status, [pm_smoother_p, pm_mesh_p, _meshpp]),
    "pm_smoother_destroy": (None, [pm_smoother_p]),
    # volume particles: polygonize
    "pm_polygonize_options_init": (None, [POINTER(pm_polygonize_options)]),
    "pm_polygonize": (pm_status, [pm_cloud_p, _f64p, _f64p, POINTER(pm_polygonize_options),
                                  _meshpp]),
    "pm_polygonize_ex": (pm_status, [pm_cloud_p, _f64p, _f64p, POINTER(pm_polygonize_options),
                                     _meshpp, POINTER(pm_polygonize_stats)]),
    "pm_polygonize_attributes": (pm_status, [pm_cloud_p, _f64p, _f64p,
                                             POINTER(pm_polygonize_options), _f64p, c_size_t,
                                             _f32p, c_size_t]),
    "pm_lattice_field": (pm_status, [c_int32, c_double, c_double, _f64p]),
    "pm_default_radius": (pm_status, [pm_cloud_p, _f64p, c_int32, c_int32, _f64p]),
    "pm_particle_grid_radius": (pm_status, [_f64p, c_size_t, _f64p]),
    # volume particles: ray casting
    "pm_field_options_init": (None, [POINTER(pm_field_options)]),
    "pm_field_create": (pm_status, [pm_cloud_p, _f64p, _f64p, POINTER(pm_field_options),
                                    POINTER(pm_field_p)]),
    "pm_field_get_params": (pm_status, [pm_field_p, _f64p, _f64p]),
    "pm_field_values": (pm_status, [pm_field_p, _f64p, c_size_t, _f64p]),
    "pm_field_destroy": (None, [pm_field_p]),
    "pm_raycast_options_init": (None, [POINTER(pm_raycast_options)]),
    "pm_raycast_first": (pm_status, [pm_field_p, _f64p, _f64p, c_size_t,
                                     POINTER(pm_raycast_options), _f64p, _f64p, _f64p, _i32p,
                                     _sizep]),
    "pm_raycast_all": (pm_status, [pm_field_p, _f64p, _f64p, c_size_t,
                                   POINTER(pm_raycast_options), POINTER(pm_ray_hits_p)]),
    "pm_raycast_csg": (pm_status, [pm_field_p, pm_field_p, c_int32, _f64p, _f64p, c_size_t,
                                   POINTER(pm_raycast_options), POINTER(pm_ray_hits_p)]),
    "pm_ray_hits_get_counts": (pm_status, [pm_ray_hits_p, _sizep, _sizep]),
    "pm_ray_hits_copy_offsets": (pm_status, [pm_ray_hits_p, _u64p, c_size_t]),
    "pm_ray_hits_copy_starts_inside": (pm_status, [pm_ray_hits_p, _i32p, c_size_t]),
    "pm_ray_hits_copy": (pm_status, [pm_ray_hits_p, _f64p, _f64p, _f64p, _i32p, c_size_t]),
    "pm_ray_hits_destroy": (None, [pm_ray_hits_p]),
    # a cloud's attributes, read back
    "pm_cloud_get_attribute_count": (pm_status, [pm_cloud_p, _sizep]),
    "pm_cloud_get_attribute_name": (pm_status, [pm_cloud_p, c_size_t, POINTER(c_char_p)]),
    "pm_cloud_get_attribute_components": (pm_status, [pm_cloud_p, c_char_p, _i32p]),
    "pm_cloud_copy_attribute": (pm_status, [pm_cloud_p, c_char_p, _f32p, c_size_t]),
    "pm_mesh_components": (pm_status, [pm_mesh_p, _sizep, _u32p, _u64p, _f64p, _f64p, c_size_t]),
    "pm_cloud_get_not_read_count": (pm_status, [pm_cloud_p, _sizep]),
    "pm_mesh_get_not_read_count": (pm_status, [pm_mesh_p, _sizep]),
    "pm_mesh_get_not_read": (pm_status, [pm_mesh_p, c_size_t, POINTER(c_char_p)]),
    "pm_cloud_get_not_read": (pm_status, [pm_cloud_p, c_size_t, POINTER(c_char_p)]),
}

# ---- the PCL bridge (libparticlemesh_pcl: .pcd files) -------------------------------------

PM_PCL_ABI_VERSION = 1


class pm_pcl_read_info(Structure):
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


PM_PCL_DOWNSAMPLE_NONE = 0
PM_PCL_DOWNSAMPLE_UNIFORM = 1
PM_PCL_DOWNSAMPLE_VOXEL_GRID = 2


class pm_pcl_preprocess_options(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("remove_outliers", c_int32),
        ("outlier_mean_k", c_int32),
        ("outlier_stddev_mul", c_double),
        ("downsampling", c_int32),
        ("leaf_size", c_double),
        ("mls_radius", c_double),
        ("mls_order", c_int32),
        ("estimate_normals", c_int32),
        ("normal_k", c_int32),
        ("viewpoint", c_float * 3),
        ("threads", c_int32),
    ]


class pm_pcl_preprocess_report(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("input_points", c_uint64),
        ("outliers_removed", c_uint64),
        ("downsampled_away", c_uint64),
        ("smoothed", c_uint64),
        ("smoothing_skipped", c_uint64),
        ("smoothing_mean_shift", c_double),
        ("smoothing_max_shift", c_double),
        ("output_points", c_uint64),
        ("normals_estimated", c_int32),
        ("normals_failed", c_uint64),
        ("seconds", c_double),
    ]


#: name: (restype, argtypes) of every function particlemesh_pcl_c.h declares.
PCL_FUNCTIONS = {
    "pm_pcl_abi_version": (c_uint32, []),
    "pm_pcl_last_error_message": (c_char_p, []),
    "pm_pcl_read_cloud": (pm_status, [c_char_p, _cloudpp, POINTER(pm_pcl_read_info)]),
    "pm_pcl_preprocess_options_init": (None, [POINTER(pm_pcl_preprocess_options)]),
    "pm_pcl_preprocess": (pm_status, [pm_cloud_p, POINTER(pm_pcl_preprocess_options), _cloudpp,
                                      POINTER(c_uint32), POINTER(pm_pcl_preprocess_report)]),
}
