// Internal: the plain-text .xyz particle format: "x y z" or "x y z nx ny nz" per line.
#pragma once

#include <string>

#include "particlemesh/mesh/point_cloud.h"

namespace particlemesh::detail {

/// Blank lines and text after '#' are ignored. Every data line must have the same number of
/// values, 3 or 6. @throws Error(FormatError) naming the file and line.
PointCloud read_xyz(const std::string& path);

/// Atomic (temporary file + rename); 17 significant digits, so doubles round-trip exactly.
void write_xyz(const PointCloud& cloud, const std::string& path);

}  // namespace particlemesh::detail
