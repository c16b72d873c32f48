/* The C ABI used from C: triangulate a regular tetrahedron and read it back. */
#include <stdio.h>
#include <string.h>

#include "particlemesh/particlemesh.h"

int main(void) {
  const double pts[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  pm_cloud* cloud = NULL;
  pm_mesh* mesh = NULL;
  pm_triangulate_options opt;
  size_t nv = 0, nt = 0;
  int32_t tris[12];
  if (pm_abi_version() != PM_ABI_VERSION) return 1;
  if (pm_cloud_create(pts, NULL, 4, &cloud) != PM_OK) return 2;
  pm_triangulate_options_init(&opt);
  opt.flags = PM_TRIANGULATE_RAW;
  if (pm_triangulate(cloud, &opt, &mesh, NULL) != PM_OK) {
    fprintf(stderr, "%s\n", pm_last_error_message());
    return 3;
  }
  if (pm_mesh_get_counts(mesh, &nv, &nt) != PM_OK || nv != 4 || nt != 4) return 4;
  if (pm_mesh_copy_triangles(mesh, tris, 4) != PM_OK) return 5;
  if (pm_cloud_create(pts, NULL, 0, &cloud) != PM_STATUS_INVALID_INPUT) return 6;
  if (strlen(pm_last_error_message()) == 0) return 7;
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
  pm_cloud_destroy(NULL);
  printf("C ABI %s ok: %u triangles\n", pm_version_string(), (unsigned)nt);
  return 0;
}
