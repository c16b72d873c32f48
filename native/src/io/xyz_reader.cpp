// The plain-text .xyz particle format: "x y z" or "x y z nx ny nz" per line (spaces, tabs or
// commas between values), '#' starts a comment, blank lines are skipped, every data line has
// the same number of values. A UTF-8 byte order mark at the start is skipped (editors on
// Windows write one). Lines are at most 64 KiB: a file that never ends a line (/dev/zero,
// a binary file renamed) is refused after that much, not read into memory whole.
#include <algorithm>
#include <string>
#include <string_view>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

FileContents read_xyz(const std::string& path, ReadPurpose) {
  constexpr size_t kMaxLine = size_t(1) << 16;
  FileReader in(path);
  if (in.peek() < 0) throw Error(Status::FormatError, "'" + path + "': the file is empty");
  if (in.look_ahead(3) == "\xEF\xBB\xBF") in.skip(3);
  FileContents out;
  if (in.size() > 0) out.positions.reserve(size_t(std::min<int64_t>(in.size() / 24, 1 << 20)));  // ~24 bytes a point at least
  int columns = -1;
  std::string_view line;
  auto fail = [&](const std::string& problem) {
    throw Error(Status::FormatError, "'" + path + "' line " + std::to_string(in.line_number()) + ": " + problem);
  };
  auto separator = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; };
  while (in.line(line, kMaxLine)) {
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    double v[6];
    int count = 0;
    size_t i = 0;
    while (true) {
      while (i < line.size() && separator(line[i])) ++i;
      if (i >= line.size()) break;
      size_t j = i;
      while (j < line.size() && !separator(line[j])) ++j;
      const std::string_view t = line.substr(i, j - i);
      if (count == 6) fail("more than 6 values");
      // NaN and inf are read here and refused by name with the point's index
      // (validate_point_cloud: "positions[7].x is NaN"); overflowing text is named here.
      switch (parse_number(t, v[count])) {
        case NumberText::Ok: break;
        case NumberText::NotANumber: fail("not a number: '" + shown(t) + "'"); break;
        case NumberText::Overflow: fail("'" + shown(t) + "' is beyond the range of double (1.8e308)"); break;
      }
      ++count;
      i = j;
    }
    if (count == 0) continue;
    if (count != 3 && count != 6)
      fail(std::to_string(count) + " values, expected 3 (x y z) or 6 (x y z nx ny nz)");
    if (columns == -1) columns = count;
    if (count != columns)
      fail(std::to_string(count) + " values where earlier lines have " + std::to_string(columns));
    out.positions.push_back({v[0], v[1], v[2]});
    if (count == 6) out.normals.push_back({v[3], v[4], v[5]});
  }
  return out;
}

}  // namespace particlemesh::detail
