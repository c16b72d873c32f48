// Internal: Houdini's classic ASCII geometry ("PGEOMETRY V5", .geo before Houdini 12): the
// points' positions, normals and numeric point attributes (geo_classic.cpp says what is read).
#pragma once

#include <string>

#include "io/compressed.h"
#include "io/formats.h"

namespace PM_NAMESPACE::detail {

/// The points of a classic ASCII .geo whose first four bytes ("PGEO") `in` has already read.
/// `path` names the file in errors.
/// @throws Error(FormatError) naming the file and what was wrong.
FileContents read_geo_classic(DecompressedStream& in, const std::string& path);

}  // namespace particlemesh::detail
