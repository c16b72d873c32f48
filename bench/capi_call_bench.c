/* The C side of bench/python_overhead.py: the same work as the Python package's
 * triangulate() and polygonize(), through the C ABI directly, timed per repetition:
 * create the cloud from caller arrays, run the call with default options (and a progress
 * callback, as the package always installs one), copy the vertices, triangles and normals
 * out in double precision, destroy the handles.
 *
 *   capi_call_bench POINTS.f64 REPETITIONS triangulate|polygonize
 *
 * POINTS.f64: N x 3 little-endian doubles. Prints one line per repetition:
 * "seconds TOTAL MAIN TRIANGLES", MAIN being the time in pm_triangulate / pm_polygonize_ex. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "particlemesh/particlemesh.h"

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int on_progress(void* user_data, const char* stage, double fraction) {
  (void)user_data;
  (void)stage;
  (void)fraction;
  return 0;
}

static int fail(const char* what) {
  fprintf(stderr, "capi_call_bench: %s: %s\n", what, pm_last_error_message());
  return 1;
}

int main(int argc, char** argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: capi_call_bench POINTS.f64 REPETITIONS triangulate|polygonize\n");
    return 2;
  }
  FILE* f = fopen(argv[1], "rb");
  if (!f) return fail("cannot open the points");
  fseek(f, 0, SEEK_END);
  const size_t count = (size_t)ftell(f) / (3 * sizeof(double));
  fseek(f, 0, SEEK_SET);
  double* points = malloc(count * 3 * sizeof(double));
  if (!points || fread(points, sizeof(double), 3 * count, f) != 3 * count) return fail("short read");
  fclose(f);
  const int repetitions = atoi(argv[2]);
  const int polygonize = strcmp(argv[3], "polygonize") == 0;
  for (int r = 0; r < repetitions; ++r) {
    const double start = now();
    pm_cloud* cloud = NULL;
    pm_mesh* mesh = NULL;
    if (pm_cloud_create(points, NULL, count, &cloud) != PM_OK) return fail("pm_cloud_create");
    const double main_start = now();
    if (polygonize) {
      pm_polygonize_options options;
      pm_polygonize_options_init(&options);
      options.progress = on_progress;
      pm_polygonize_stats stats;
      stats.struct_size = sizeof stats;
      if (pm_polygonize_ex(cloud, NULL, NULL, &options, &mesh, &stats) != PM_OK) return fail("pm_polygonize_ex");
    } else {
      pm_triangulate_options options;
      pm_triangulate_options_init(&options);
      options.progress = on_progress;
      pm_triangulate_stats stats;
      stats.struct_size = sizeof stats;
      if (pm_triangulate(cloud, &options, &mesh, &stats) != PM_OK) return fail("pm_triangulate");
    }
    const double main_seconds = now() - main_start;
    pm_cloud_destroy(cloud);
    size_t nv = 0, nt = 0;
    int32_t has_normals = 0;
    pm_mesh_get_counts(mesh, &nv, &nt);
    pm_mesh_has_normals(mesh, &has_normals);
    double* vertices = malloc(nv * 3 * sizeof(double));
    double* normals = malloc(nv * 3 * sizeof(double));
    int32_t* triangles = malloc(nt * 3 * sizeof(int32_t));
    if (pm_mesh_copy_positions(mesh, vertices, nv) != PM_OK ||
        pm_mesh_copy_triangles(mesh, triangles, nt) != PM_OK ||
        (has_normals && pm_mesh_copy_normals(mesh, normals, nv) != PM_OK))
      return fail("copy");
    pm_mesh_destroy(mesh);
    const double seconds = now() - start;
    printf("seconds %.6f %.6f %zu\n", seconds, main_seconds, nt);
    free(vertices);
    free(normals);
    free(triangles);
  }
  free(points);
  return 0;
}
