/* The volume C ABI used from plain C99: polygonize one particle and read the mesh back. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "particlemesh/particlemesh.h"

int main(void) {
  const double centre[3] = {0.1, 0.2, 0.3};
  const double strength = 1.0; /* one strength per particle */
  pm_cloud* cloud = NULL;
  pm_mesh* mesh = NULL;
  pm_polygonize_options opt;
  pm_polygonize_stats stats;
  size_t nv = 0, nt = 0, i;
  float* normals;
  double* positions;
  double lattice = 0;
  if (pm_cloud_create(centre, NULL, 1, &cloud) != PM_OK) return 1;
  pm_polygonize_options_init(&opt);
  opt.kernel = PM_KERNEL_POLY4;
  opt.radius = 1.0;
  opt.threshold = 0.25; /* (1 - s)^2 = 1/4 at s = 1/2: the sphere of radius sqrt(1/2) */
  opt.cell_size = 0.1;
  stats.struct_size = sizeof(stats);
  if (pm_polygonize_ex(cloud, NULL, &strength, &opt, &mesh, &stats) != PM_OK) {
    fprintf(stderr, "%s\n", pm_last_error_message());
    return 2;
  }
  if (pm_mesh_get_counts(mesh, &nv, &nt) != PM_OK || nv == 0 || nt != 2 * nv - 4) return 3;
  if (stats.vertices != nv || stats.triangles != nt) return 4;
  positions = (double*)malloc(3 * nv * sizeof(double));
  normals = (float*)malloc(3 * nv * sizeof(float));
  if (pm_mesh_copy_positions(mesh, positions, nv) != PM_OK) return 5;
  if (pm_mesh_copy_normals_f32(mesh, normals, nv) != PM_OK) return 6;
  for (i = 0; i < nv; ++i) {
    const double dx = positions[3 * i] - centre[0], dy = positions[3 * i + 1] - centre[1],
                 dz = positions[3 * i + 2] - centre[2];
    const double r = sqrt(dx * dx + dy * dy + dz * dz);
    if (fabs(r - sqrt(0.5)) > 1e-3) return 7;
    if ((dx * normals[3 * i] + dy * normals[3 * i + 1] + dz * normals[3 * i + 2]) / r < 0.999) return 8;
  }
  if (pm_lattice_field(PM_KERNEL_WYVILL, 0.1, 0.05, &lattice) != PM_OK || !(lattice > 1)) return 9;
  /* Anisotropic kernels (appended fields): one particle has no neighbours and keeps its
   * sphere; the statistics say how many particles got an ellipsoid. */
  pm_mesh_destroy(mesh);
  mesh = NULL;
  opt.anisotropic = 1;
  opt.taubin_iterations = 2;
  if (pm_polygonize_ex(cloud, NULL, &strength, &opt, &mesh, &stats) != PM_OK) {
    fprintf(stderr, "%s\n", pm_last_error_message());
    return 11;
  }
  if (stats.anisotropic != 1 || stats.anisotropic_particles != 0 || stats.triangles != nt) return 12;
  opt.aniso_max_stretch = 0.5;
  if (pm_polygonize(cloud, NULL, NULL, &opt, &mesh) != PM_STATUS_INVALID_ARGUMENT) return 13;
  opt.anisotropic = 0;
  opt.aniso_max_stretch = 4;
  opt.kernel = 42;
  if (pm_polygonize(cloud, NULL, NULL, &opt, &mesh) != PM_STATUS_INVALID_ARGUMENT) return 10;
  free(positions);
  free(normals);
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
  printf("C ABI polygonize ok: %u vertices, %u triangles\n", (unsigned)nv, (unsigned)nt);
  return 0;
}
