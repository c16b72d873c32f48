// Tutorial: swap pcl::GreedyProjectionTriangulation for particlemesh's ParticleTriangulation.
//
// Tutorial description: this program loads a point cloud from a PCD file, meshes it with
// particlemesh_pcl::ParticleTriangulation the way PCL's "Fast triangulation of unordered
// point clouds" tutorial meshes bun0.pcd with greedy projection, and saves the
// pcl::PolygonMesh as PLY. Only the class and its parameters differ from that tutorial: no
// normals and no kd-tree are needed (the triangulation uses its own neighbour grid).
//
//   particle_triangulation_tutorial [input.pcd] [output.ply]     (defaults: bun0.pcd mesh.ply)
#include <iostream>

#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <particlemesh_pcl/particle_triangulation.h>

int
main (int argc, char **argv)
{
  const std::string input = argc > 1 ? argv[1] : "bun0.pcd";
  const std::string output = argc > 2 ? argv[2] : "mesh.ply";

  // Load input file into a PointCloud<T> with an appropriate type
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud (new pcl::PointCloud<pcl::PointXYZ>);
  pcl::PCLPointCloud2 cloud_blob;
  if (pcl::io::loadPCDFile (input, cloud_blob) < 0)
  {
    std::cerr << "could not read " << input << std::endl;
    return (1);
  }
  pcl::fromPCLPointCloud2 (cloud_blob, *cloud);
  //* the data should be available in cloud

  // Initialize objects
  particlemesh_pcl::ParticleTriangulation<pcl::PointXYZ> pt;
  pcl::PolygonMesh triangles;

  // Set the longest edge as a multiple of the particle spacing (which is estimated as the
  // median nearest-neighbour distance, since none is given with setSpacing)
  pt.setMaxEdgeFactor (2.0);

  // Get result
  pt.setInputCloud (cloud);
  pt.reconstruct (triangles);
  if (triangles.polygons.empty ())
  {
    std::cerr << "reconstruction failed: " << pt.getReport ().error << std::endl;
    return (1);
  }

  // What happened
  const particlemesh_pcl::ReconstructionReport &report = pt.getReport ();
  std::cout << input << ": " << report.input.input_points << " points ("
            << report.input.invalid_points << " invalid), spacing " << report.spacing
            << (report.spacing_estimated ? " (estimated)" : "") << ", "
            << triangles.polygons.size () << " triangles" << std::endl;

  // Save; pcl_viewer and pcl::io::loadPLYFile read it back
  if (pcl::io::savePLYFileBinary (output, triangles) < 0)
  {
    std::cerr << "could not write " << output << std::endl;
    return (1);
  }
  std::cout << "saved " << output << std::endl;

  // Finish
  return (0);
}
