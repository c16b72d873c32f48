/*
 * Files: PCD in (ASCII, binary, binary_compressed), read once: our header check and
 * pcl::PCDReader's header and binary-body decoding work on the same bytes in memory, an ASCII
 * body is parsed once by our check into PCL's cloud layout. PLY meshes out through
 * pcl::io::savePLYFileBinary.
 *
 * PCL's reader trusts the header (in PCL 1.13 it crashes on an empty or non-PCD file and
 * reads a cloud without x/y/z as if nothing were wrong), so every file is checked first by a
 * small header parser of our own that names the file and the problem: not a PCD file,
 * truncated header or data, missing x/y/z, entries of SIZE/TYPE/COUNT that do not match
 * FIELDS, WIDTH x HEIGHT != POINTS, a compressed block whose size does not match.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/PolygonMesh.h>

#include <particlemesh/io/output_file.h>
#include <particlemesh/mesh/point_cloud.h>
#include <particlemesh_pcl/conversions.h>

namespace particlemesh_pcl
{
  /** \brief The header of a PCD file, as checked by checkPCDFile. */
  struct PCDHeader
  {
    std::string version;               ///< "0.7", ".5", ...
    std::vector<std::string> fields;
    std::vector<int> sizes;            ///< bytes per element: 1, 2, 4 or 8
    std::vector<char> types;           ///< 'F', 'U' or 'I'
    std::vector<int> counts;           ///< elements per field (1 when COUNT is absent)
    std::uint32_t width = 0;
    std::uint32_t height = 1;
    std::size_t points = 0;
    float viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  ///< tx ty tz qw qx qy qz
    std::string data;                  ///< "ascii", "binary" or "binary_compressed"
    std::size_t data_offset = 0;       ///< byte offset of the data section
    std::size_t point_size = 0;        ///< bytes per point (binary layouts)
  };

  /** \brief Parse and check a PCD file's header and the size of its data section without
    * reading the points.
    * \throws particlemesh::Error(IoError) "<path>: no such file" / unreadable;
    *         particlemesh::Error(FormatError) "<path>: <problem>".
    */
  PCDHeader
  checkPCDFile (const std::string &path);

  /** \brief A PCD file read by PCL. */
  struct PCDFile
  {
    PCDHeader header;
    pcl::PCLPointCloud2 cloud;
    float origin[4] = {0, 0, 0, 0};       ///< sensor origin (VIEWPOINT translation)
    float orientation[4] = {1, 0, 0, 0};  ///< sensor orientation quaternion w x y z
  };

  /** \brief checkPCDFile, then pcl::PCDReader::read.
    * \throws particlemesh::Error(IoError | FormatError) naming the file and the problem.
    */
  PCDFile
  loadPCDFile (const std::string &path);

  /** \brief What loadParticles read and dropped. */
  struct LoadReport
  {
    std::string format;       ///< "pcd" or what particlemesh::read_point_cloud read ("ply", "xyz")
    std::string encoding;     ///< PCD DATA: "ascii", "binary", "binary_compressed" ("" otherwise)
    ConversionReport conversion;  ///< points, invalid points dropped, organized, channels
    float origin[3] = {0, 0, 0};  ///< the PCD's sensor origin (0 for other formats)
  };

  /** \brief Particles from a file: .pcd through loadPCDFile + toParticles (invalid points
    * dropped and counted, index_map back to the file's points), anything else through
    * particlemesh::read_point_cloud (.ply, .xyz).
    * \param[out] report if not null, what was read
    * \param[out] index_map if not null, index_map[i] = point index in the file of particle i
    * \throws particlemesh::Error naming the file and the problem; Error(InvalidInput) if the
    * file holds no valid point.
    */
  particlemesh::PointCloud
  loadParticles (const std::string &path, LoadReport *report = nullptr,
                 pcl::Indices *index_map = nullptr);

  /** \brief Write a pcl::PolygonMesh as binary PLY with pcl::io::savePLYFileBinary (the
    * format PCL's pcl::io::loadPLYFile and pcl_viewer read), through a particlemesh::OutputFile
    * (a temporary file in the same folder, read back complete, then renamed into place; a
    * device or FIFO written straight through), so a failed write leaves no partial file.
    * \throws particlemesh::Error(IoError) naming the file.
    */
  void
  savePLYFile (const std::string &path, const pcl::PolygonMesh &mesh);

  /** \brief The same into `out`, which the caller commits with the run's other outputs. */
  void
  savePLYFile (particlemesh::OutputFile &out, const pcl::PolygonMesh &mesh);
}
