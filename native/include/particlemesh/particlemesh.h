/* particlemesh C ABI: the stable interface for Blender (ctypes), other languages and hosts.
 *
 * Rules that hold for every function here:
 *  - Every call returns a pm_status (PM_OK = 0) except pm_abi_version, pm_version_string,
 *    pm_status_string, pm_last_error_message and the NULL-tolerant pm_*_destroy.
 *  - No C++ exception ever crosses this boundary and nothing aborts: bad input gives a
 *    status and pm_last_error_message() says which argument (and which point index) was wrong.
 *  - On failure, outputs are left untouched (out-pointers are not written).
 *  - Options structs start with struct_size and are filled by pm_<x>_options_init(); new
 *    fields are only ever appended, so a caller built against an older header keeps working.
 *    A struct_size that ends inside a pointer field (no version of a struct ever did) is
 *    refused with PM_STATUS_INVALID_ARGUMENT.
 *  - Variable-size results: query the counts, then copy into caller-owned memory.
 *  - Long calls take a progress callback (called on the calling thread only); returning
 *    non-zero from it cancels the call, which then returns PM_STATUS_CANCELLED promptly.
 *  - Output is identical for any thread count.
 */
#ifndef PARTICLEMESH_H
#define PARTICLEMESH_H

#include <stddef.h>
#include <stdint.h>

#include "particlemesh/core/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Bumped when a function or struct changes incompatibly; appending does not bump it. */
#define PM_ABI_VERSION 1

typedef enum pm_status {
  PM_OK = 0,
  PM_STATUS_INVALID_ARGUMENT = 1, /**< a parameter is out of range, a pointer is NULL, a size is wrong */
  PM_STATUS_INVALID_INPUT = 2,    /**< the data is unusable: NaN coordinate, empty cloud, ... */
  PM_STATUS_IO_ERROR = 3,         /**< a file could not be opened, read or written */
  PM_STATUS_FORMAT_ERROR = 4,     /**< a file's contents are malformed */
  PM_STATUS_OUT_OF_MEMORY = 5,
  PM_STATUS_CANCELLED = 6,        /**< the progress callback returned non-zero */
  PM_STATUS_LIMIT_EXCEEDED = 7,   /**< a resource limit was hit (see the message) */
  PM_STATUS_INTERNAL = 8          /**< a bug in particlemesh; please report the message */
} pm_status;

typedef struct pm_cloud pm_cloud; /**< particles: positions and optional normals */
typedef struct pm_mesh pm_mesh;   /**< an indexed triangle mesh */

/** Progress: stage name and overall fraction 0..1. Return 0 to go on, non-zero to cancel. */
typedef int (*pm_progress_fn)(void* user_data, const char* stage, double fraction);

/* ---- library ------------------------------------------------------------------------ */

PM_EXPORT uint32_t pm_abi_version(void);
PM_EXPORT const char* pm_version_string(void);
/** Static text for a status ("invalid argument", ...). */
PM_EXPORT const char* pm_status_string(pm_status status);
/** Message of the last failed call on this thread ("" if none). Valid until the next call. */
PM_EXPORT const char* pm_last_error_message(void);

/* ---- point clouds ------------------------------------------------------------------- */

/** Copy `count` particles: positions are count*3 doubles (x y z ...), normals NULL or
 *  count*3 doubles. Every value must be finite (the message names the first bad index). */
PM_EXPORT pm_status pm_cloud_create(const double* positions, const double* normals, size_t count,
                                    pm_cloud** out_cloud);
/** The same from float32 arrays (numpy / Blender buffers). */
PM_EXPORT pm_status pm_cloud_create_f32(const float* positions, const float* normals, size_t count,
                                        pm_cloud** out_cloud);
/** Read a file of particles, once and exactly (any format read_point_cloud reads, see
 *  particlemesh/io/mesh_io.h); a malformed file is PM_STATUS_FORMAT_ERROR naming the file and
 *  the element or line. What the file holds per particle but is not read (string attributes,
 *  list properties, LAS fields) is named by pm_cloud_get_not_read. */
PM_EXPORT pm_status pm_cloud_read(const char* path, pm_cloud** out_cloud);
/** How many lines pm_cloud_get_not_read has: per-particle data in the file pm_cloud_read
 *  did not carry (PointCloud::not_read); 0 for a cloud not read from a file. */
PM_EXPORT pm_status pm_cloud_get_not_read_count(const pm_cloud* cloud, size_t* out_count);
/** Line `index` (0-based) of what was not read, naming it and why, e.g. "point attribute
 *  'name' (strings)"; the string stays valid until the cloud is destroyed.
 *  PM_STATUS_INVALID_ARGUMENT when index >= the count. */
PM_EXPORT pm_status pm_cloud_get_not_read(const pm_cloud* cloud, size_t index, const char** out_text);
PM_EXPORT pm_status pm_cloud_get_count(const pm_cloud* cloud, size_t* out_count);
/** 1 if the cloud carries normals, else 0. */
PM_EXPORT pm_status pm_cloud_has_normals(const pm_cloud* cloud, int32_t* out_has_normals);
/** Copy positions / normals into `out` (capacity in points: 3*capacity floats). */
PM_EXPORT pm_status pm_cloud_copy_positions_f32(const pm_cloud* cloud, float* out, size_t capacity);
PM_EXPORT pm_status pm_cloud_copy_normals_f32(const pm_cloud* cloud, float* out, size_t capacity);
/** The same in full precision (capacity in points: 3*capacity doubles). */
PM_EXPORT pm_status pm_cloud_copy_positions(const pm_cloud* cloud, double* out, size_t capacity);
PM_EXPORT pm_status pm_cloud_copy_normals(const pm_cloud* cloud, double* out, size_t capacity);
PM_EXPORT void pm_cloud_destroy(pm_cloud* cloud);

/** Median nearest-neighbour distance of the distinct points (threads: 0 = all cores). */
PM_EXPORT pm_status pm_estimate_spacing(const pm_cloud* cloud, int32_t threads, double* out_spacing);
/** The same over an evenly strided sample of at most max_samples (>= 1) points, each one's
 *  nearest neighbour searched among all: within about 1 % on even particles, a fraction of
 *  the cost on big clouds (previews). max_samples >= the count gives the exact estimate. */
PM_EXPORT pm_status pm_estimate_spacing_sampled(const pm_cloud* cloud, size_t max_samples, int32_t threads,
                                                double* out_spacing);

/** Thin the cloud (a coarser preview of a big particle set): the indices, ascending, of a
 *  subset in which no two points are closer than min_distance (> 0, finite) and every dropped
 *  point lies within min_distance of a kept one, so even particles stay even. Points are
 *  taken greedily in input order: the result depends on the points only. out_indices must
 *  have room for `capacity` >= the cloud's count entries; *out_count receives how many were
 *  kept. */
PM_EXPORT pm_status pm_cloud_thin(const pm_cloud* cloud, double min_distance, uint32_t* out_indices,
                                  size_t capacity, size_t* out_count);

/* ---- frame collections: ParaView's .pvd and .series ---------------------------------- */

/* A collection lists a simulation's frame files with their times (particlemesh/io/
 * frame_collection.h): frames come back by ascending time, each file joined to the
 * collection's folder; files outside that folder, two entries at one time, entries without a
 * file or a finite time are PM_STATUS_FORMAT_ERROR naming them. */
typedef struct pm_frame_collection pm_frame_collection;

PM_EXPORT pm_status pm_frame_collection_read(const char* path, pm_frame_collection** out_collection);
PM_EXPORT pm_status pm_frame_collection_get_count(const pm_frame_collection* collection, size_t* out_count);
/** Frame `index` (< count): its time and its file's path (valid until the collection is
 *  destroyed). */
PM_EXPORT pm_status pm_frame_collection_get_frame(const pm_frame_collection* collection, size_t index,
                                                  double* out_time, const char** out_path);
PM_EXPORT void pm_frame_collection_destroy(pm_frame_collection* collection);

/* ---- triangulation of surface particles --------------------------------------------- */

/** Return the exact triangle set of Tonnesen's smallest-sphere test (not a surface) instead of
 *  the finished surface. */
#define PM_TRIANGULATE_RAW 0x1u
/** Skip the repair stage (hole filling, unpinching, inserting passed-by particles). */
#define PM_TRIANGULATE_NO_REPAIR 0x2u
/** Do not turn closed components to face outward. */
#define PM_TRIANGULATE_NO_ORIENT 0x4u
/** One edge limit L = max_edge_factor x spacing for the whole cloud, instead of each particle's
 *  own from the sampling around it (the default; see SurfaceOptions::local_spacing). */
#define PM_TRIANGULATE_GLOBAL_SPACING 0x8u
/** options->viewpoint is where the scan was taken from: no triangle bridges a depth jump
 *  (see SurfaceOptions::viewpoint). */
#define PM_TRIANGULATE_VIEWPOINT 0x10u

/** Where the surface's normals come from (see particlemesh/surface/reconstruct.h). */
#define PM_NORMALS_AUTO 0     /**< plane fits, facing as the cloud's normals say (if any) */
#define PM_NORMALS_INPUT 1    /**< the cloud's normals as they are */
#define PM_NORMALS_ESTIMATE 2 /**< plane fits and a spanning tree only */

typedef struct pm_triangulate_options {
  uint32_t struct_size;     /**< sizeof(pm_triangulate_options), set by _init */
  double spacing;           /**< r0 in world units; 0 = estimate (median NN distance) */
  double max_edge_factor;   /**< L = factor * r0 (default 2) */
  int32_t threads;          /**< 0 = all cores */
  uint32_t max_neighbors;   /**< per-point neighbour cap within L (default 256) */
  uint32_t flags;           /**< PM_TRIANGULATE_* */
  pm_progress_fn progress;  /**< may be NULL */
  void* progress_user_data;
  /* -- finishing stages (ignored with PM_TRIANGULATE_RAW) -- */
  double normal_angle;      /**< co-normality limit in degrees (default 120) */
  uint32_t fill_holes;      /**< fill boundary loops of up to this many edges (default 100, 0 = none) */
  double fill_edge_factor;  /**< fill edges at most this x L: wider openings stay open (default 1.5;
                                 above 1.5 only the loops left open by the other repair steps are
                                 filled that wide) */
  int32_t normals;          /**< PM_NORMALS_* (default PM_NORMALS_AUTO) */
  /* -- appended -- */
  uint32_t max_triplets_per_point; /**< fail with PM_STATUS_LIMIT_EXCEEDED before the test when the
                                        candidate triplets average more per point (default 4096; 0 = no limit) */
  /* -- appended -- */
  double viewpoint[3];      /**< the scan's sensor position, read with PM_TRIANGULATE_VIEWPOINT */
  /* -- appended -- */
  uint32_t min_component_triangles; /**< remove pieces of fewer triangles (a scan's stray
                                         triangles); their particles are then unused (default 0:
                                         keep every piece; ignored with PM_TRIANGULATE_RAW) */
} pm_triangulate_options;

typedef struct pm_triangulate_stats {
  uint32_t struct_size;     /**< set by the caller to sizeof(pm_triangulate_stats) */
  double spacing;           /**< r0 used */
  double max_edge;          /**< L used */
  int32_t spacing_estimated;
  uint64_t points;
  uint64_t duplicate_points;
  uint64_t max_neighbors_seen;
  uint64_t candidates;      /**< triplets the smallest-sphere test examined */
  uint64_t kept;            /**< triangles the smallest-sphere test kept */
  /* -- finishing stages (0 with PM_TRIANGULATE_RAW) -- */
  uint64_t holes_filled;
  uint64_t holes_left;      /**< boundary loops left open (real openings) */
  uint64_t largest_hole_left; /**< edges of the largest loop left open */
  uint64_t pinches_resolved;
  uint64_t unused_points;   /**< distinct particles in no triangle */
  int32_t normals_estimated;
  /* -- appended -- */
  uint64_t triplets;        /**< candidate triplets the test examined (see max_triplets_per_point) */
  /* -- appended -- */
  uint64_t rejected_conormal; /**< raw triangles dropped by co-normality (see looks_like_volume) */
  /* -- appended -- */
  double local_spacing[5];  /**< the particles' local spacings in units of r0: smallest, 10th
                                 percentile, median, 90th percentile, largest (all 1 with
                                 PM_TRIANGULATE_GLOBAL_SPACING) */
  int32_t viewpoint_used;   /**< the viewpoint was given and taken (the cloud looks scanned from it) */
  uint64_t rejected_shadow; /**< raw triangles dropped for bridging a depth jump */
  /* -- appended -- */
  int32_t looks_like_volume; /**< 1: loops were left open, and co-normality dropped over 35 % of
                                  the raw triangles or the sampling thickness is at least 0.45:
                                  the particles probably fill a volume (pm_polygonize meshes
                                  those) rather than sample a surface */
  /* -- appended -- */
  uint64_t narrow_loops;    /**< loops left open at most 3 L across that the fill did not try
                                 (wider than fill_edge_factor or longer than fill_holes): gaps
                                 in the sampling, not openings */
  double narrow_loop_width; /**< the widest of them, in L: fill_edge_factor >= it reaches them all */
  uint64_t narrow_loop_edges; /**< the longest of them: fill_holes >= it reaches them all */
  /* -- appended -- */
  double sampling_irregularity; /**< with local spacing: the coefficient of variation of the
                                     nearest-neighbour distances around a point, median over the
                                     points (even samplings 0 to 0.3, particles at random ~0.5) */
  double reach_factor;      /**< every edge limit was lengthened by this for an irregular sampling
                                 (1 on an even one; at most 1.75); local_spacing includes it */
  /* -- appended -- */
  double sampling_thickness; /**< with local spacing: how far the particles scatter across the
                                  surface, sqrt(lambda0 / lambda1) of each one's neighbourhood,
                                  median (clean surfaces under 0.2, noisy scans 0.25 and more,
                                  a volume ~0.85) */
  /* -- appended -- */
  uint64_t components_removed; /**< pieces removed for min_component_triangles */
  uint64_t component_triangles_removed; /**< their triangles */
  uint64_t stray_pieces;    /**< pieces of fewer than 10 triangles left, counted when loops are
                                 left open (a scan's stray triangles) */
  uint64_t stray_piece_triangles; /**< their triangles */
  uint64_t stray_piece_largest;   /**< the most triangles of one: min_component_triangles of
                                       one more removes them all */
  /* -- appended -- */
  uint64_t small_handles_removed; /**< handles smaller than the sampling taken out (a part
                                       thinner than the spacing joined across) */
  /* -- appended -- */
  uint64_t shortened_limits; /**< particles whose edge limit was shortened to hold at most
                                  max_neighbors neighbours (local spacing, r0 estimated) */
  uint64_t near_duplicates; /**< near copies set aside (local spacing; at least a
                                 quarter of the points with a neighbour ten times nearer than
                                 every other: each such pair is one particle) */
  uint64_t flat_pieces_opened; /**< closed pieces that enclosed no volume (a patch and its
                                    reversed copy, on particles exactly in one plane), opened:
                                    the side facing as the particles' normals kept */
  /* -- appended -- */
  uint64_t nearly_closed_turned; /**< open components closed but for small openings turned to
                                      face outward as closed ones are (normals estimated and
                                      oriented by the spanning tree alone, no viewpoint) */
  uint64_t folded_triangles; /**< triangles of the surface first built that faced into the
                                  solid their closed (or nearly closed) part bounds, the surface
                                  then built again over normals turned to match (the tree
                                  crossed between a thin part's sides); 0: not built again */
  /* -- appended -- */
  double uncapped_spacing_p90; /**< with local spacing, where at least a tenth of the local
                                    spacings were held to the cap of 3 r0: their 90th
                                    percentile before the cap, in r0; 0 otherwise */
  double capped_spacing_over_nn; /**< with local spacing: over the particles whose local spacing
                                      lies past the cap, the median of it over the nearest-
                                      neighbour distance around them (2 and more: rows far apart
                                      for their spacing along them; about 1: parts sampled
                                      sparser all round); 0 where none does */
} pm_triangulate_stats;

PM_EXPORT void pm_triangulate_options_init(pm_triangulate_options* options);
/** Triangulate: by default the finished surface (a consistently oriented 2-manifold, closed
 *  components facing outward, with per-vertex normals); with PM_TRIANGULATE_RAW the smallest-sphere test's
 *  exact triangle set. `options` may be NULL (defaults); `out_stats` may be NULL. The mesh's
 *  vertices are the cloud's particles, in order. */
PM_EXPORT pm_status pm_triangulate(const pm_cloud* cloud, const pm_triangulate_options* options,
                                   pm_mesh** out_mesh, pm_triangulate_stats* out_stats);

/* ---- meshes ------------------------------------------------------------------------- */

/** Copy a mesh: positions nv*3 doubles, triangles nt*3 vertex indices, normals NULL or nv*3. */
PM_EXPORT pm_status pm_mesh_create(const double* positions, size_t vertex_count,
                                   const int32_t* triangles, size_t triangle_count,
                                   const double* normals, pm_mesh** out_mesh);
/** Read .ply / .obj / .off (ASCII) / .stl, once and exactly. */
PM_EXPORT pm_status pm_mesh_read(const char* path, pm_mesh** out_mesh);
/** What pm_mesh_read found in the file but does not carry (texture coordinates, face
 *  properties, other elements, cell data), as pm_cloud_get_not_read: a count, then line
 *  `index`, valid until the mesh is destroyed; 0 lines for a mesh not read from a file. */
PM_EXPORT pm_status pm_mesh_get_not_read_count(const pm_mesh* mesh, size_t* out_count);
PM_EXPORT pm_status pm_mesh_get_not_read(const pm_mesh* mesh, size_t index, const char** out_text);
/** Write .ply (binary) or .obj: a regular file through an exclusively created temporary in
 *  its folder, renamed into place when complete (an existing file keeps its mode); a device
 *  or FIFO written straight through (PLY when the name has no .ply / .obj extension). */
PM_EXPORT pm_status pm_mesh_write(const pm_mesh* mesh, const char* path);
PM_EXPORT pm_status pm_mesh_get_counts(const pm_mesh* mesh, size_t* out_vertex_count,
                                       size_t* out_triangle_count);
PM_EXPORT pm_status pm_mesh_has_normals(const pm_mesh* mesh, int32_t* out_has_normals);
/** Copy into caller memory; capacity counts vertices (3 values each) or triangles. */
PM_EXPORT pm_status pm_mesh_copy_positions(const pm_mesh* mesh, double* out, size_t capacity);
PM_EXPORT pm_status pm_mesh_copy_positions_f32(const pm_mesh* mesh, float* out, size_t capacity);
PM_EXPORT pm_status pm_mesh_copy_normals_f32(const pm_mesh* mesh, float* out, size_t capacity);
PM_EXPORT pm_status pm_mesh_copy_normals(const pm_mesh* mesh, double* out, size_t capacity);
PM_EXPORT pm_status pm_mesh_copy_triangles(const pm_mesh* mesh, int32_t* out, size_t capacity);
/** The mesh's own arrays, lent without a copy (a binding's arrays over them need no second
 *  copy of a big mesh): positions and normals 3 doubles per vertex, triangles 3 vertex indices
 *  each; NULL where the array is empty (normals: where the mesh has none). They stay valid, and
 *  writable, until the mesh is destroyed. A vector with more than a quarter of its room unused
 *  is trimmed first (one copy), so what is lent is what the mesh holds. */
PM_EXPORT pm_status pm_mesh_lend_arrays(pm_mesh* mesh, double** out_positions, double** out_normals,
                                        uint32_t** out_triangles);
PM_EXPORT void pm_mesh_destroy(pm_mesh* mesh);

typedef struct pm_topology_report {
  uint32_t struct_size;  /**< set by the caller to sizeof(pm_topology_report) */
  uint64_t vertices, triangles, vertices_used, edges;
  uint64_t boundary_edges, manifold_edges, nonmanifold_edges, nonmanifold_vertices;
  uint64_t degenerate_triangles, duplicate_triangles, orientation_conflicts;
  uint64_t boundary_loops, components, closed_components;
  int64_t euler_characteristic;
  int32_t manifold, closed, consistently_oriented, outward;
} pm_topology_report;

PM_EXPORT pm_status pm_mesh_report(const pm_mesh* mesh, pm_topology_report* out_report);

/** The edges of a triangle list (no mesh handle: `triangles` holds 3 x triangle_count vertex
 *  indices < vertex_count), for hosts that store edges (Blender): each edge once as (a, b),
 *  a < b, ordered by a then b, into out_edges (room for 2 x edge_capacity indices; 3 x
 *  triangle_count edges always suffice), and per triangle corner the edge from that corner
 *  to the next into out_corner_edges (3 x triangle_count). *out_edge_count receives the edge
 *  count; with too small an edge_capacity it is the count needed and the call fails. Keeps up
 *  to 64 MiB of working memory (8 bytes a corner) for the next call, which a host numbering
 *  every frame's edges reuses instead of faulting in fresh pages. */
PM_EXPORT pm_status pm_triangle_edges(const uint32_t* triangles, size_t triangle_count, size_t vertex_count,
                                      int32_t threads, uint32_t* out_edges, size_t edge_capacity,
                                      uint32_t* out_corner_edges, size_t* out_edge_count);

/** Per point (3 doubles each), how many of the mesh's triangles the ray from it straight up
 *  (+z) crosses, into out_crossings (point_count values): a point lies inside a closed surface
 *  when its count is odd, whatever the winding. Watertight: a ray through an edge or a vertex
 *  is counted once, each edge's test evaluated from its lower-numbered end, so each triangle's
 *  share depends on it alone; meshes cut from one surface, their vertices numbered in the same
 *  relative order, give counts that add up to the whole one's. `threads`: 0 = all. */
PM_EXPORT pm_status pm_mesh_ray_crossings(const pm_mesh* mesh, const double* points, size_t point_count,
                                          int32_t threads, uint64_t* out_crossings);

/** The mesh's connected pieces (triangles that share vertices), numbered in the order of their
 *  first triangle: *out_component_count receives their number; out_vertex_component (NULL,
 *  or vertex_count values) each vertex's piece, UINT32_MAX for a vertex no triangle uses; and
 *  per piece (each output NULL, or room for `capacity` pieces, at least the count, else
 *  PM_STATUS_INVALID_ARGUMENT with the count still set) its triangle count, area and enclosed
 *  volume (the divergence theorem over its triangles: exact for a closed, consistently
 *  oriented piece, positive when it faces outward; for an open one the cone over it from its
 *  first corner). A triangle's piece is its corners'. */
PM_EXPORT pm_status pm_mesh_components(const pm_mesh* mesh, size_t* out_component_count,
                                       uint32_t* out_vertex_component, uint64_t* out_triangles,
                                       double* out_area, double* out_volume, size_t capacity);

/* ---- per-vertex attributes ---------------------------------------------------------- */

/* Named float channels per vertex (colour, velocity, radius, ...): `components` floats per
 * vertex, vertex-major (values[v * components + c]). Smoothing carries them through; the
 * triangulation copies a cloud's attributes onto its mesh (whose vertices are the particles). */

/** Set (or replace) attribute `name` on a mesh: vertex_count must equal the mesh's vertex
 *  count, components is 1..4096, every value finite. */
PM_EXPORT pm_status pm_mesh_set_attribute(pm_mesh* mesh, const char* name, int32_t components,
                                          const float* values, size_t vertex_count);
/** Components of attribute `name`; PM_STATUS_INVALID_ARGUMENT naming it when the mesh has none. */
PM_EXPORT pm_status pm_mesh_get_attribute_components(const pm_mesh* mesh, const char* name,
                                                     int32_t* out_components);
/** Copy attribute `name` into `out` (capacity_vertices * components floats). */
PM_EXPORT pm_status pm_mesh_copy_attribute(const pm_mesh* mesh, const char* name, float* out,
                                           size_t capacity_vertices);
/** Attribute `name`'s values lent without a copy (vertex count * components floats; NULL for a
 *  mesh without vertices), valid and writable until the attribute is replaced or the mesh is
 *  destroyed. */
PM_EXPORT pm_status pm_mesh_lend_attribute(pm_mesh* mesh, const char* name, float** out_values);
/** Number of attributes on a mesh, and the name of attribute `index` (0-based; the string
 *  stays valid until the mesh is changed or destroyed). */
PM_EXPORT pm_status pm_mesh_get_attribute_count(const pm_mesh* mesh, size_t* out_count);
PM_EXPORT pm_status pm_mesh_get_attribute_name(const pm_mesh* mesh, size_t index, const char** out_name);

/* ---- per-corner attributes ---------------------------------------------------------- */

/* Named float values per triangle corner, face-varying (a vertex on a texture seam has one
 * per side): `components` floats per corner, values[(3 * t + c) * components + k] for corner
 * c of triangle t. "uv" (2 components) holds texture coordinates: pm_mesh_read takes them from
 * an OBJ's vt or a PLY's texcoord face lists, pm_mesh_write writes them to .obj and .ply.
 * pm_smooth carries every one, linearly over each input triangle. */

/** Set (or replace) corner attribute `name`: triangle_count must equal the mesh's, components
 *  is 1..64, every value finite. */
PM_EXPORT pm_status pm_mesh_set_corner_attribute(pm_mesh* mesh, const char* name, int32_t components,
                                                 const float* values, size_t triangle_count);
PM_EXPORT pm_status pm_mesh_get_corner_attribute_count(const pm_mesh* mesh, size_t* out_count);
PM_EXPORT pm_status pm_mesh_get_corner_attribute_name(const pm_mesh* mesh, size_t index, const char** out_name);
/** Components of corner attribute `name`; PM_STATUS_INVALID_ARGUMENT naming it when the mesh has none. */
PM_EXPORT pm_status pm_mesh_get_corner_attribute_components(const pm_mesh* mesh, const char* name,
                                                            int32_t* out_components);
/** Copy corner attribute `name` into `out` (capacity_triangles * 3 * components floats). */
PM_EXPORT pm_status pm_mesh_copy_corner_attribute(const pm_mesh* mesh, const char* name, float* out,
                                                  size_t capacity_triangles);
/** Set (or replace) attribute `name` on a cloud (vertex_count = the cloud's point count). */
PM_EXPORT pm_status pm_cloud_set_attribute(pm_cloud* cloud, const char* name, int32_t components,
                                           const float* values, size_t vertex_count);

/* ---- smoothing: Loop (OpenSubdiv) and modified butterfly (OpenMesh) -------------------- */

#define PM_SMOOTH_LOOP 0      /**< approximating; exact limit positions and normals */
#define PM_SMOOTH_BUTTERFLY 1 /**< interpolating: the original vertices stay exactly in place */

/** Loop boundary rules (OpenSubdiv's Sdc::Options::VtxBoundaryInterpolation; its NONE
 *  equals EDGE_ONLY under uniform refinement and is not offered, see smooth/subdivide.h). */
#define PM_BOUNDARY_EDGE_AND_CORNER 0 /**< boundary = B-spline curve, corners pinned (default) */
#define PM_BOUNDARY_EDGE_ONLY 1       /**< boundary = B-spline curve, corners smoothed too */

/** Loop crease softening (Sdc::Options::CreasingMethod). */
#define PM_CREASE_UNIFORM 0
#define PM_CREASE_CHAIKIN 1

/** Marks "infinitely sharp" in pm_smooth_options.crease_sharpness (any value >= 10 does). */
#define PM_CREASE_INFINITE 10.0f

typedef struct pm_smooth_options {
  uint32_t struct_size;        /**< sizeof(pm_smooth_options), set by _init */
  int32_t scheme;              /**< PM_SMOOTH_LOOP (default) or PM_SMOOTH_BUTTERFLY */
  int32_t levels;              /**< 0..10, default 1; each level multiplies the triangles by 4 */
  int32_t limit;               /**< Loop: 1 = exact limit positions, normals, attributes (default) */
  int32_t boundary;            /**< Loop: PM_BOUNDARY_* (default EDGE_AND_CORNER) */
  int32_t crease_method;       /**< Loop: PM_CREASE_* (default UNIFORM) */
  int32_t threads;             /**< 0 = all cores; the output does not depend on it */
  uint64_t max_triangles;      /**< refuse larger results before allocating (default 2^25) */
  size_t crease_count;         /**< Loop: number of crease edges (default 0) */
  const int32_t* crease_edges; /**< crease_count vertex-index pairs (2 per crease), or NULL */
  const float* crease_sharpness; /**< crease_count values, or NULL = all infinitely sharp */
  pm_progress_fn progress;     /**< may be NULL */
  void* progress_user_data;
} pm_smooth_options;

PM_EXPORT void pm_smooth_options_init(pm_smooth_options* options);
/** Subdivide `mesh` into a new smooth mesh (with normals and every attribute carried
 *  through). `options` may be NULL (one Loop level at the limit). Butterfly's input must be a
 *  2-manifold; Loop keeps an edge in more than two triangles as an infinitely sharp crease
 *  (OpenSubdiv's rule); unreferenced vertices are dropped and inconsistent orientation is
 *  repaired (see smooth/subdivide.h); anything else unusable gives PM_STATUS_INVALID_INPUT
 *  naming the edge, vertex or triangle, and a result over max_triangles
 *  PM_STATUS_LIMIT_EXCEEDED. */
PM_EXPORT pm_status pm_smooth(const pm_mesh* mesh, const pm_smooth_options* options, pm_mesh** out_mesh);

/* Refine once, evaluate many (particlemesh/smooth/smoother.h): for a mesh whose vertices move
 * while its triangles stay (frames of an animation), the checks and OpenSubdiv's refinement
 * are done once by pm_smoother_create; each pm_smoother_evaluate then gives exactly what
 * pm_smooth would for the same triangles and the new positions and attributes, for a fraction
 * of its cost (Loop; butterfly subdivides again). */
typedef struct pm_smoother pm_smoother;

/** Check `mesh` and refine its topology as pm_smooth(mesh, options) would (the same statuses
 *  and messages; options->progress reports this work, and crease indices refer to `mesh`).
 *  `options` may be NULL (one Loop level at the limit). */
PM_EXPORT pm_status pm_smoother_create(const pm_mesh* mesh, const pm_smooth_options* options,
                                       pm_smoother** out_smoother);
/** *out_matches = 1 when `mesh` has the smoother's triangles (same order) and vertex count,
 *  else 0. */
PM_EXPORT pm_status pm_smoother_matches(const pm_smoother* smoother, const pm_mesh* mesh, int32_t* out_matches);
/** The smooth mesh of `mesh`'s positions and attributes through the smoother (normals and
 *  attributes as pm_smooth gives them; corner attributes from the mesh the smoother was made
 *  from, which they belong to with its triangles). PM_STATUS_INVALID_ARGUMENT when `mesh` does not
 *  match (pm_smoother_matches); PM_STATUS_INVALID_INPUT for a non-finite or too large
 *  coordinate or attribute value (naming the vertex). Safe to call from several threads. */
PM_EXPORT pm_status pm_smoother_evaluate(const pm_smoother* smoother, const pm_mesh* mesh, pm_mesh** out_mesh);
PM_EXPORT void pm_smoother_destroy(pm_smoother* smoother);

/* ---- volume particles: implicit surfaces, polygonized --------------------------------- */

/* The surface F(x) = T of F(x) = sum_i w_i g(|x - p_i|^2 / R_i^2), polygonized by marching
 * cubes on a sparse grid of blocks: only blocks some particle's support reaches are
 * considered, and of those, blocks that bounds of the summed kernels prove wholly inside or
 * outside are not sampled unless next to a crossing, so memory and time follow the occupied
 * volume and the surface, not the bounding box (see
 * particlemesh/volume/polygonize.h).
 * Kernels g, as functions of s = r^2 / R^2 on 0 <= s < 1 (0 beyond): */
#define PM_KERNEL_WYVILL 0 /**< 1 - 22/9 s + 17/9 s^2 - 4/9 s^3 (Wyvill's soft objects), C1 at R */
#define PM_KERNEL_POLY4 1  /**< (1 - s)^2, C1 at R */
#define PM_KERNEL_POLY6 2  /**< (1 - s)^3, C2 at R */
#define PM_KERNEL_BLINN 3  /**< (exp(-k s) - 1e-3) / (1 - 1e-3), k = ln 1000: Blinn's blob cut at 1e-3, C0 */

typedef struct pm_polygonize_options {
  uint32_t struct_size;     /**< sizeof(pm_polygonize_options), set by _init */
  int32_t kernel;           /**< PM_KERNEL_* (default PM_KERNEL_WYVILL) */
  double radius;            /**< R in world units; 0 = the default (pm_default_radius): 2 x the
                                 median particle spacing, or the larger R the packing asks for */
  double threshold;         /**< T > 0; 0 = half the field inside an evenly packed volume at
                                 R = 2 spacings (3.33 Wyvill, 3.94 poly4, 2.58 poly6, 1.23 Blinn) */
  double cell_size;         /**< grid cell h in world units; 0 = R / 4 */
  int32_t threads;          /**< 0 = all cores; the output does not depend on it */
  uint64_t max_grid_bytes;  /**< fail with PM_STATUS_LIMIT_EXCEEDED before the block search,
                                 the sparse grid, or the grid with the output mesh would need
                                 more (default 4 GiB); 0 = no limit */
  pm_progress_fn progress;  /**< may be NULL */
  void* progress_user_data;
  /* Appended (a caller built against an older header gets the defaults below): */
  int32_t anisotropic;            /**< non-zero: anisotropic kernels (Yu and Turk 2013, see
                                       particlemesh/volume/anisotropy.h); default 0 */
  double aniso_neighbor_radius;   /**< PCA neighbourhood radius, x R, in (0, 10] (default 2) */
  double aniso_max_stretch;       /**< k_r: longest / shortest axis at most, [1, 100] (default 4) */
  int32_t aniso_min_neighbors;    /**< N_eps: fewer neighbours keep a sphere (default 25) */
  double aniso_smoothing;         /**< lambda: kernel-centre smoothing, [0, 1] (default 0: off) */
  double min_component_volume;    /**< drop pieces enclosing less volume (world units^3); 0 = keep all */
  double min_component_particles; /**< drop pieces enclosing less than N x spacing^3; 0 = keep all */
  int32_t taubin_iterations;      /**< Taubin lambda|mu smoothing of the mesh; 0 = off (default) */
  double taubin_lambda;           /**< in (0, 1] (default 0.5) */
  double taubin_mu;               /**< in [-1, -lambda) (default -0.53) */
  /* -- appended: one tile of a cloud polygonized in tiles (particlemesh.distributed). The
   *    lattice's node (i, j, k) lies at origin + h (i, j, k), origin = (lower - R_max) - 9 h per
   *    axis, lower = the particles' smallest coordinates, R_max = the largest radius (see
   *    particlemesh/volume/polygonize.h). A tile given its cloud's domain_min and
   *    domain_max_radius, its cell range and every particle within R_max of those cells (in
   *    their order in the cloud) yields exactly the cloud's triangles in those cells. -- */
  uint32_t flags;           /**< PM_POLYGONIZE_DOMAIN_MIN | PM_POLYGONIZE_CELL_RANGE |
                                 PM_POLYGONIZE_ANCHOR_IN_SPACE (default 0) */
  double domain_min[3];     /**< with PM_POLYGONIZE_DOMAIN_MIN: the whole cloud's lower corner,
                                 used as `lower` (at or below every particle) */
  double domain_max_radius; /**< 0, or the whole cloud's largest radius, used as R_max (at least
                                 every radius given) */
  int64_t cell_min[3];      /**< with PM_POLYGONIZE_CELL_RANGE: only the cells with
                                 cell_min <= (i, j, k) < cell_max are meshed */
  int64_t cell_max[3];
  /* -- appended -- */
  double collapse_edges;    /**< collapse every edge shorter than this x h into one vertex on
                                 the surface where the surface stays a closed 2-manifold
                                 (marching cubes' slivers), in [0, 0.5]; 0 = off (default) */
  /* -- appended -- */
  double domain_grid_radius; /**< with domain_max_radius and per-particle radii: 0 (default),
                                  or the whole cloud's pm_particle_grid_radius (a tile then
                                  keeps the few far larger particles apart as the cloud does) */
} pm_polygonize_options;

/** pm_polygonize_options.flags: anchor the lattice and the particle grid at domain_min. */
#define PM_POLYGONIZE_DOMAIN_MIN 0x1u
/** pm_polygonize_options.flags: mesh only the cells in [cell_min, cell_max). */
#define PM_POLYGONIZE_CELL_RANGE 0x2u
/** pm_polygonize_options.flags: anchor the lattice in space: its origin rounded down to a
 *  multiple of the cell size on each axis, so that every node lies at an integer multiple of
 *  h (frames of a sequence are sampled at the same points: no shimmer). Tiles given this
 *  flag with their cloud's domain_min round the same origin. What the command-line tool uses. */
#define PM_POLYGONIZE_ANCHOR_IN_SPACE 0x4u

typedef struct pm_polygonize_stats {
  uint32_t struct_size;     /**< set by the caller to sizeof(pm_polygonize_stats) */
  double radius;            /**< R used (median of the radii when per particle) */
  double threshold;         /**< T used */
  double cell_size;         /**< h used */
  double spacing;           /**< median particle spacing, when the default radius needed it (else 0) */
  uint64_t particles;
  uint64_t sampled_blocks;  /**< blocks of 8^3 grid nodes sampled (those not proven inside or outside) */
  uint64_t grid_bytes;      /**< memory of the sparse grid and the output mesh (what
                                 max_grid_bytes bounds) */
  uint64_t vertices;
  uint64_t triangles;
  /* Appended: */
  int32_t anisotropic;            /**< 1 when anisotropic kernels were used */
  uint64_t anisotropic_particles; /**< particles that got an ellipsoid (the rest kept spheres) */
  uint64_t components_removed;    /**< pieces dropped by min_component_volume / _particles */
  double calibration_ratio;       /**< anisotropic default threshold: the R / spacing it was
                                       calibrated for (else 0) */
  /* -- appended -- */
  double origin[3];         /**< the lattice's node (0, 0, 0) */
  /* -- appended -- */
  double enclosed_fraction; /**< share of the particles inside the surface (F >= T at their
                                 centres, up to 4096 sampled): low when R is too small for how
                                 sparsely they are packed */
  double density_radius;    /**< spherical kernels of one radius: the R their packing suggests
                                 (2 spacings of a lattice as dense; R itself for packed
                                 particles at the default radius), else 0 */
  /* -- appended -- */
  uint64_t edges_collapsed; /**< short edges collapsed by collapse_edges (vertices removed) */
} pm_polygonize_stats;

PM_EXPORT void pm_polygonize_options_init(pm_polygonize_options* options);
/** Polygonize the particles' iso-surface. `radii` (one R_i > 0 per particle) and
 *  `strengths` (one finite w_i per particle, |w_i| <= 1e30) are NULL for one radius /
 *  strength 1. `options` may be NULL (defaults). The mesh is closed, consistently oriented (counter-clockwise seen
 *  from outside) and carries per-vertex normals from the field gradient, and the cloud's
 *  attributes interpolated with the normalised kernel weights (sum w_i a_i / sum w_i,
 *  w_i = |strength_i| g(s_i), isotropic or anisotropic kernels); it has no vertex when
 *  F >= T nowhere on the grid. */
PM_EXPORT pm_status pm_polygonize(const pm_cloud* cloud, const double* radii, const double* strengths,
                                  const pm_polygonize_options* options, pm_mesh** out_mesh);
/** The same, also filling `out_stats` (may be NULL). */
PM_EXPORT pm_status pm_polygonize_ex(const pm_cloud* cloud, const double* radii, const double* strengths,
                                     const pm_polygonize_options* options, pm_mesh** out_mesh,
                                     pm_polygonize_stats* out_stats);
/** The cloud's attributes at `count` points (count x 3 doubles), interpolated exactly as
 *  pm_polygonize interpolates them at its vertices (sum w_i a_i / sum w_i in the field's
 *  particle order; 0 where no kernel reaches): given the vertices pm_polygonize placed (before
 *  taubin_iterations move them; with collapse_edges, where the merged ones end up), the
 *  values are bit for bit its own. For a caller that meshes
 *  without attributes first (a cloud without them) and asks for them later. `cloud`, `radii`,
 *  `strengths` and `options` as given to pm_polygonize: the field is built from its field
 *  options (kernel, radius, threshold, the anisotropic ones, PM_POLYGONIZE_DOMAIN_MIN with
 *  domain_min, domain_max_radius) as pm_polygonize builds it, with `threads` and `progress`;
 *  the others are checked as there but not used. out_values receives the cloud's attributes
 *  one after the other in the cloud's order (pm_cloud_get_attribute_name), count x components
 *  floats each, point by point; out_capacity is the number of floats out_values holds, at
 *  least count x the sum of the components (PM_STATUS_INVALID_ARGUMENT otherwise). A cloud
 *  without attributes writes nothing. PM_STATUS_INVALID_INPUT for a non-finite point (named)
 *  and as pm_polygonize for the cloud; the results do not depend on the thread count. */
PM_EXPORT pm_status pm_polygonize_attributes(const pm_cloud* cloud, const double* radii, const double* strengths,
                                             const pm_polygonize_options* options, const double* points,
                                             size_t count, float* out_values, size_t out_capacity);
/** The field deep inside a simple cubic lattice of unit-strength particles with the given
 *  spacing and radius (the sum of g over the lattice points within R). The default threshold
 *  is half of it; an SPH iso level given as a fraction of the rest density maps to
 *  T = fraction x pm_lattice_field(kernel, R, rest spacing). */
PM_EXPORT pm_status pm_lattice_field(int32_t kernel, double radius, double spacing, double* out_value);
/** The radius pm_polygonize and pm_field_create take for radius 0 (spherical kernels of one
 *  radius): 2 x the median particle spacing, or, when that leaves over a tenth of the particles
 *  outside the surface, the larger radius their packing asks for (density_radius). For callers that cut a cloud into pieces and must give every piece
 *  the whole cloud's radius. `strengths`: NULL or one per particle (their median scales the
 *  field the packing is read from). PM_STATUS_INVALID_INPUT when the spacing cannot be
 *  estimated (fewer than two distinct particles). */
PM_EXPORT pm_status pm_default_radius(const pm_cloud* cloud, const double* strengths, int32_t kernel,
                                      int32_t threads, double* out_radius);
/** The radius the field's particle grid is sized by for per-particle radii (count values > 0):
 *  the largest, or, where a few are far larger than the rest (one particle 20 times the
 *  others), a smaller one, the particles above it kept apart from the grid's cells and
 *  visited by every evaluation (particlemesh/volume/field.h, particle_grid_radius). For
 *  callers that cut a cloud into tiles: pm_polygonize_options.domain_grid_radius.
 *  PM_STATUS_INVALID_ARGUMENT for a radius that is not a finite length > 0 (naming it). */
PM_EXPORT pm_status pm_particle_grid_radius(const double* radii, size_t count, double* out_radius);

/* ---- volume particles: exact ray casting of the iso-surface --------------------------- */

/* Every crossing of a ray o + t d with the surface F(x) = T (see particlemesh/volume/raycast.h):
 * the ray is cut into intervals where a fixed set of particles contributes, and each
 * interval's polynomial is solved exactly (closed form for PM_KERNEL_POLY4, certified
 * Bernstein isolation for WYVILL and POLY6; a proven bracketing march for BLINN). A ray that
 * only touches the surface reports no hit there. Normals are -grad F / |grad F| (outward). */

typedef struct pm_field pm_field;       /**< particles, field parameters and their ray hierarchy */
typedef struct pm_ray_hits pm_ray_hits; /**< all hits of a batch of rays */

typedef struct pm_field_options {
  uint32_t struct_size;     /**< sizeof(pm_field_options), set by _init */
  int32_t kernel;           /**< PM_KERNEL_* (default PM_KERNEL_WYVILL) */
  double radius;            /**< R in world units; 0 = the default (pm_default_radius): 2 x the
                                 median particle spacing, or the larger R the packing asks for */
  double threshold;         /**< T > 0; 0 = half the field inside an evenly packed volume */
  int32_t threads;          /**< 0 = all cores (for the spacing estimate) */
  pm_progress_fn progress;  /**< may be NULL */
  void* progress_user_data;
  /* Appended, as in pm_polygonize_options: */
  int32_t anisotropic;            /**< non-zero: anisotropic kernels; default 0 */
  double aniso_neighbor_radius;   /**< default 2 */
  double aniso_max_stretch;       /**< default 4 */
  int32_t aniso_min_neighbors;    /**< default 25 */
  double aniso_smoothing;         /**< default 0 (off) */
} pm_field_options;

PM_EXPORT void pm_field_options_init(pm_field_options* options);
/** Build a field for ray queries. `radii` / `strengths` are NULL or one value per particle,
 *  as in pm_polygonize. Reuse the field for many batches: building costs O(N log N). */
PM_EXPORT pm_status pm_field_create(const pm_cloud* cloud, const double* radii, const double* strengths,
                                    const pm_field_options* options, pm_field** out_field);
/** The radius (median of the radii when per particle) and threshold in use. Either may be NULL. */
PM_EXPORT pm_status pm_field_get_params(const pm_field* field, double* out_radius, double* out_threshold);
/** F at `count` points (count*3 doubles) into out_values (count doubles). */
PM_EXPORT pm_status pm_field_values(const pm_field* field, const double* points, size_t count, double* out_values);
PM_EXPORT void pm_field_destroy(pm_field* field);

typedef struct pm_raycast_options {
  uint32_t struct_size;     /**< sizeof(pm_raycast_options), set by _init */
  double t_min;             /**< hits with t_min <= t <= t_max only (default 0 and +infinity) */
  double t_max;
  int32_t threads;          /**< 0 = all cores; the results do not depend on it */
  pm_progress_fn progress;  /**< may be NULL */
  void* progress_user_data;
} pm_raycast_options;

PM_EXPORT void pm_raycast_options_init(pm_raycast_options* options);

/** First hit of each of `count` rays: origins and directions are count*3 doubles (directions
 *  non-zero, any length; t is in units of the direction's length). Outputs, each NULL or
 *  caller memory: out_t (count doubles, +infinity for a miss), out_positions and out_normals
 *  (count*3 doubles, zero for a miss), out_entering (count values: 1 the ray enters the
 *  inside, 0 it leaves it or misses), out_hit_count (rays with a hit). */
PM_EXPORT pm_status pm_raycast_first(const pm_field* field, const double* origins, const double* directions,
                                     size_t count, const pm_raycast_options* options, double* out_t,
                                     double* out_positions, double* out_normals, int32_t* out_entering,
                                     size_t* out_hit_count);

/** All hits of each of `count` rays, into a new pm_ray_hits (query the counts, then copy). */
PM_EXPORT pm_status pm_raycast_all(const pm_field* field, const double* origins, const double* directions,
                                   size_t count, const pm_raycast_options* options, pm_ray_hits** out_hits);

/** CSG of two fields along rays: all hits of the surface of A op B. */
#define PM_CSG_UNION 0        /**< inside A or inside B */
#define PM_CSG_INTERSECTION 1 /**< inside A and inside B */
#define PM_CSG_DIFFERENCE 2   /**< inside A and not inside B (normals of B's part flipped) */
PM_EXPORT pm_status pm_raycast_csg(const pm_field* a, const pm_field* b, int32_t op, const double* origins,
                                   const double* directions, size_t count, const pm_raycast_options* options,
                                   pm_ray_hits** out_hits);

/** Number of rays and of hits in all. */
PM_EXPORT pm_status pm_ray_hits_get_counts(const pm_ray_hits* hits, size_t* out_ray_count, size_t* out_hit_count);
/** offsets: ray_count + 1 values; the hits of ray i are [offsets[i], offsets[i + 1]).
 *  capacity counts values (must be >= ray_count + 1). */
PM_EXPORT pm_status pm_ray_hits_copy_offsets(const pm_ray_hits* hits, uint64_t* out_offsets, size_t capacity);
/** Per ray: 1 if the ray starts inside (F >= T at t_min), else 0. capacity >= ray_count. */
PM_EXPORT pm_status pm_ray_hits_copy_starts_inside(const pm_ray_hits* hits, int32_t* out, size_t capacity);
/** Per hit, in order (each output NULL or caller memory; capacity counts hits, >= hit_count):
 *  t, position (3 doubles), normal (3 doubles), entering (1) or leaving (0). */
PM_EXPORT pm_status pm_ray_hits_copy(const pm_ray_hits* hits, double* out_t, double* out_positions,
                                     double* out_normals, int32_t* out_entering, size_t capacity);
PM_EXPORT void pm_ray_hits_destroy(pm_ray_hits* hits);

/* ---- point-cloud attributes, read back ------------------------------------------------- */

/* The per-point float channels a cloud carries, as the mesh functions above give them for a
 * mesh: what pm_cloud_set_attribute stored, or what a reader found in the file. pm_cloud_read
 * gives a PLY file's vertex colours (red green blue, any numeric type; uchar scaled by 1/255)
 * as "color", 3 floats per point in [0, 1]; the PCL bridge's pm_pcl_read_cloud
 * (particlemesh_pcl/particlemesh_pcl_c.h) gives a PCD file's rgb/rgba as "color" and its
 * intensity as "intensity" (1 float per point, as stored). */

/** Number of attributes on a cloud. */
PM_EXPORT pm_status pm_cloud_get_attribute_count(const pm_cloud* cloud, size_t* out_count);
/** Name of attribute `index` (0-based); the string stays valid until the cloud is changed or
 *  destroyed. PM_STATUS_INVALID_ARGUMENT when index >= the count. */
PM_EXPORT pm_status pm_cloud_get_attribute_name(const pm_cloud* cloud, size_t index, const char** out_name);
/** Components of attribute `name`; PM_STATUS_INVALID_ARGUMENT naming it when the cloud has none. */
PM_EXPORT pm_status pm_cloud_get_attribute_components(const pm_cloud* cloud, const char* name,
                                                      int32_t* out_components);
/** Copy attribute `name` into `out` (capacity_points * components floats, point-major). */
PM_EXPORT pm_status pm_cloud_copy_attribute(const pm_cloud* cloud, const char* name, float* out,
                                            size_t capacity_points);

#ifdef __cplusplus
}
#endif

#endif /* PARTICLEMESH_H */
