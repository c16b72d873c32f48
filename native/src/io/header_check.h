// Internal: checks a mesh file's header against the data that follows it, before OpenMesh
// reads it. OpenMesh's readers trust the counts in a header: an ASCII PLY or text OFF file
// that promises more elements than it holds is read as if complete (the missing elements
// are made up) or makes the reader loop and allocate once per promised element, and a list
// count in a binary PLY face is used as an allocation size. These checks cost one pass over
// the file at most and make such files a FormatError naming the file and what is missing.
#pragma once

#include <string>

namespace particlemesh::detail {

/// PLY: every element the header declares must be present (ASCII: token by token, list
/// counts included; binary: sizes, list counts walked). OFF: at least 3 values per vertex and
/// 4 per face. STL: a binary file (not starting with "solid") must hold the 50 bytes per
/// triangle its header counts. OBJ: every face corner is v, v/vt, v//vn or v/vt/vn with
/// integer indices. Other extensions: nothing to check.
/// @throws Error(FormatError) naming the file, the element and the counts.
void check_mesh_file_header(const std::string& path, const std::string& lower_extension);

}  // namespace particlemesh::detail
