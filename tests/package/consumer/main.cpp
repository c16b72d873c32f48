// Uses both the C++ API and the C ABI of an installed particlemesh.
#include <cstdio>

#include <particlemesh/particlemesh.h>
#include <particlemesh/sample/shapes.h>
#include <particlemesh/surface/triangulate.h>

int main() {
  const particlemesh::PointCloud c = particlemesh::fibonacci_sphere(1000);
  const auto r = particlemesh::triangulate_raw(c);
  std::printf("%zu triangles, ABI %u\n", r.mesh.triangles.size(), pm_abi_version());
  return r.mesh.triangles.empty() || pm_abi_version() != PM_ABI_VERSION;
}
