/* The ray-casting C ABI used from plain C99: first hits and all hits of a few rays on one
 * particle, read back with query-then-copy. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "particlemesh/particlemesh.h"

int main(void) {
  const double centre[3] = {0.1, 0.2, 0.3};
  /* Three rays along +x: through the centre, off by 0.5, and missing. */
  const double origins[9] = {-5, 0.2, 0.3, -5, 0.7, 0.3, -5, 2.0, 0.3};
  const double directions[9] = {2, 0, 0, 1, 0, 0, 1, 0, 0};
  const double rs = sqrt(0.5); /* Poly4, R = 1, T = 1/4: (1 - s)^2 = 1/4 at s = 1/2 */
  pm_cloud* cloud = NULL;
  pm_field* field = NULL;
  pm_ray_hits* hits = NULL;
  pm_field_options fo;
  pm_raycast_options ro;
  double t[3], pos[9], nrm[9];
  int32_t entering[3];
  size_t hit_count = 0, rays = 0, total = 0, i;
  uint64_t offsets[4];
  double* all_t;
  int32_t* all_entering;
  if (pm_cloud_create(centre, NULL, 1, &cloud) != PM_OK) return 1;
  pm_field_options_init(&fo);
  fo.kernel = PM_KERNEL_POLY4;
  fo.radius = 1.0;
  fo.threshold = 0.25;
  if (pm_field_create(cloud, NULL, NULL, &fo, &field) != PM_OK) {
    fprintf(stderr, "%s\n", pm_last_error_message());
    return 2;
  }
  pm_raycast_options_init(&ro);
  if (pm_raycast_first(field, origins, directions, 3, &ro, t, pos, nrm, entering, &hit_count) != PM_OK) return 3;
  if (hit_count != 2 || !isinf(t[2]) || entering[0] != 1 || entering[2] != 0) return 4;
  if (fabs(t[0] - (5.1 - rs) / 2) > 1e-12) return 5; /* t in units of the direction's length */
  if (fabs(pos[3] - (0.1 - sqrt(rs * rs - 0.25))) > 1e-12 || nrm[0] > -0.99) return 6;
  if (pm_raycast_all(field, origins, directions, 3, NULL, &hits) != PM_OK) return 7;
  if (pm_ray_hits_get_counts(hits, &rays, &total) != PM_OK || rays != 3 || total != 4) return 8;
  all_t = (double*)malloc(total * sizeof(double));
  all_entering = (int32_t*)malloc(total * sizeof(int32_t));
  if (pm_ray_hits_copy_offsets(hits, offsets, 4) != PM_OK) return 9;
  if (pm_ray_hits_copy(hits, all_t, NULL, NULL, all_entering, total) != PM_OK) return 10;
  if (offsets[0] != 0 || offsets[1] != 2 || offsets[2] != 4 || offsets[3] != 4) return 11;
  for (i = 0; i < total; ++i)
    if (all_entering[i] != (i % 2 == 0)) return 12;
  if (all_t[0] != t[0] || !(all_t[1] > all_t[0])) return 13;
  if (pm_raycast_csg(field, field, 9, origins, directions, 3, NULL, &hits) != PM_STATUS_INVALID_ARGUMENT) return 14;
  free(all_t);
  free(all_entering);
  pm_ray_hits_destroy(hits);
  pm_field_destroy(field);
  pm_cloud_destroy(cloud);
  printf("C ABI ray casting ok: %u hits on %u rays\n", (unsigned)total, (unsigned)rays);
  return 0;
}
