// Internal: checks a mesh file's header against the data that follows it, before OpenMesh
// reads it. OpenMesh's readers trust the counts in a header: an ASCII PLY or text OFF file
// that promises more elements than it holds is read as if complete (the missing elements
// are made up) or makes the reader loop and allocate once per promised element, and a list
// count in a binary PLY face is used as an allocation size. These checks cost one pass over
// the file at most and make such files a FormatError naming the file and what is missing.
#pragma once

#include <string>
#include <vector>

#include "particlemesh/core/vec3.h"

namespace particlemesh::detail {

/// A file's vertex coordinates (and normals), read exactly. OpenMesh's readers keep positions
/// and normals as float32: they round `double` coordinates and text ones with more digits (a
/// georeferenced scan at 5e6 m then sits on a 0.5 m lattice), and the PLY reader reads binary
/// integer ones as 0. So the check, which walks the data anyway, reads them: PLY x y z (and
/// nx ny nz) when their type is not float32, text OBJ and OFF positions always. The caller
/// puts them in place of OpenMesh's. Empty when OpenMesh's are exact.
struct ExactVertices {
  std::vector<Vec3> positions;  ///< x y z (absent ones 0), one per vertex
  std::vector<Vec3> normals;    ///< nx ny nz, when the file has all three and one is not float32
  bool integer_types = false;   ///< a PLY x y z or nx ny nz has an integer type
};

/// PLY: every element the header declares must be present (ASCII: token by token, list
/// counts included; binary: sizes, list counts walked). OFF: at least 3 values per vertex and
/// 4 per face. STL: a binary file (not starting with "solid") must hold the 50 bytes per
/// triangle its header counts. OBJ: every face corner is v, v/vt, v//vn or v/vt/vn with
/// integer indices. Other extensions: nothing to check.
/// With `exact` (PLY, OBJ, OFF): see ExactVertices.
/// @throws Error(FormatError) naming the file, the element and the counts.
void check_mesh_file_header(const std::string& path, const std::string& lower_extension,
                            ExactVertices* exact = nullptr);

}  // namespace particlemesh::detail
