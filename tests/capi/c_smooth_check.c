/* Smoothing and attributes used from plain C99: an octahedron with a per-vertex channel,
 * one Loop level at the limit, the channel read back. */
#include <math.h>
#include <stdio.h>

#include "particlemesh/particlemesh.h"

int main(void) {
  const double pos[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  const int32_t tris[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  const float heat[] = {1, 1, 1, 1, 1, 1};
  float out[6 + 12];
  pm_mesh* mesh = NULL;
  pm_mesh* smooth = NULL;
  pm_mesh* again = NULL;
  pm_smoother* smoother = NULL;
  int32_t matches = 0;
  pm_smooth_options opt;
  size_t nv = 0, nt = 0, i;
  int32_t comps = 0;
  if (pm_mesh_create(pos, 6, tris, 8, NULL, &mesh) != PM_OK) return 1;
  if (pm_mesh_set_attribute(mesh, "heat", 1, heat, 6) != PM_OK) return 2;
  pm_smooth_options_init(&opt);
  opt.scheme = PM_SMOOTH_LOOP;
  opt.levels = 1;
  opt.boundary = PM_BOUNDARY_EDGE_AND_CORNER;
  if (pm_smooth(mesh, &opt, &smooth) != PM_OK) {
    fprintf(stderr, "%s\n", pm_last_error_message());
    return 3;
  }
  if (pm_mesh_get_counts(smooth, &nv, &nt) != PM_OK || nv != 18 || nt != 32) return 4;
  if (pm_mesh_get_attribute_components(smooth, "heat", &comps) != PM_OK || comps != 1) return 5;
  if (pm_mesh_copy_attribute(smooth, "heat", out, nv) != PM_OK) return 6;
  for (i = 0; i < nv; ++i)
    if (fabsf(out[i] - 1.0f) > 1e-6f) return 7;
  if (pm_mesh_get_attribute_components(smooth, "none", &comps) != PM_STATUS_INVALID_ARGUMENT) return 8;
  /* Refine once, evaluate many: the same mesh again. */
  if (pm_smoother_create(mesh, &opt, &smoother) != PM_OK) return 9;
  if (pm_smoother_matches(smoother, mesh, &matches) != PM_OK || matches != 1) return 10;
  if (pm_smoother_evaluate(smoother, mesh, &again) != PM_OK) return 11;
  if (pm_mesh_get_counts(again, &nv, &nt) != PM_OK || nv != 18 || nt != 32) return 12;
  pm_mesh_destroy(again);
  pm_smoother_destroy(smoother);
  pm_mesh_destroy(smooth);
  pm_mesh_destroy(mesh);
  printf("C ABI smoothing ok: %u vertices, %u triangles\n", (unsigned)nv, (unsigned)nt);
  return 0;
}
