// Internal: Houdini 12+'s geometry in binary JSON (.bgeo, .bgeo.gz, .bgeo.sc) and as text (ASCII .geo,
// .geo.gz): the points' positions, normals and numeric point attributes (bgeo_json.cpp says
// what is read and how).
#pragma once

#include <string>
#include <string_view>

#include "io/compressed.h"
#include "io/formats.h"

namespace PM_NAMESPACE::detail {

/// The geometry of a binary-JSON bgeo whose first five bytes (0x7f and the four magic bytes)
/// `in` has already read; `big_endian` from those magic bytes. `path` names the file in errors.
/// @throws Error(FormatError) naming the file and what was wrong.
FileContents read_bgeo_binary_json(DecompressedStream& in, const std::string& path, bool big_endian);

/// The geometry of an ASCII (text JSON) .geo whose first bytes, `read_already`, `in` has
/// already read.
FileContents read_geo_text_json(DecompressedStream& in, const std::string& path, std::string_view read_already);

}  // namespace particlemesh::detail
