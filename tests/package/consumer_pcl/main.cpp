// Uses the installed PCL bridge the way a PCL program would.
#include <cmath>
#include <cstdio>

#include <pcl/point_types.h>
#include <particlemesh_pcl/particle_triangulation.h>

int main() {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i) cloud->push_back(pcl::PointXYZ(0.1f * i + 0.05f * (j % 2), 0.0866f * j, 0.f));
  particlemesh_pcl::ParticleTriangulation<pcl::PointXYZ> pt;
  pt.setInputCloud(cloud);
  pcl::PolygonMesh mesh;
  pt.reconstruct(mesh);
  std::printf("%zu triangles\n", mesh.polygons.size());
  return mesh.polygons.size() < 600;  // a 20 x 20 hexagonal patch: 2 x 19 x 19 = 722
}
