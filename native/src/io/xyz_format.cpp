#include "io/xyz_format.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

#include "io/atomic_file.h"
#include "particlemesh/core/error.h"

namespace particlemesh::detail {

namespace {

// strtod accepts "nan"/"inf" as well, which we want to read and then reject by index with a
// clear message (validate_point_cloud) rather than call a format error.
bool parse_double(const char*& s, const char* end, double& out) {
  while (s < end && (*s == ' ' || *s == '\t' || *s == ',' || *s == '\r')) ++s;
  if (s >= end) return false;
  auto r = std::from_chars(s, end, out);
  if (r.ec == std::errc() ) {
    s = r.ptr;
    return true;
  }
  if (r.ec == std::errc::result_out_of_range) {
    out = std::strtod(std::string(s, size_t(r.ptr - s)).c_str(), nullptr);
    s = r.ptr;
    return true;
  }
  // "+1.5" and friends: from_chars does not take a leading '+'.
  if (*s == '+') {
    ++s;
    return parse_double(s, end, out);
  }
  return false;
}

}  // namespace

PointCloud read_xyz(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(Status::IoError, "'" + path + "': cannot open for reading");
  PointCloud cloud;
  std::string line;
  size_t line_no = 0;
  int columns = -1;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    const char* s = line.data();
    const char* end = s + line.size();
    double v[7];
    int count = 0;
    while (true) {
      const char* before = s;
      while (s < end && (*s == ' ' || *s == '\t' || *s == ',' || *s == '\r')) ++s;
      if (s >= end) break;
      if (count == 7 || !parse_double(s, end, v[count])) {
        const char* tok_end = before;
        while (tok_end < end && *tok_end == ' ') ++tok_end;
        std::string token(tok_end, std::min<size_t>(size_t(end - tok_end), 20));
        throw Error(Status::FormatError, "'" + path + "' line " + std::to_string(line_no) +
                                             (count == 7 ? ": more than 6 values"
                                                         : ": not a number: '" + token + "'"));
      }
      ++count;
    }
    if (count == 0) continue;
    if (count != 3 && count != 6)
      throw Error(Status::FormatError, "'" + path + "' line " + std::to_string(line_no) + ": " +
                                           std::to_string(count) + " values, expected 3 (x y z) or 6 (x y z nx ny nz)");
    if (columns == -1) columns = count;
    if (count != columns)
      throw Error(Status::FormatError, "'" + path + "' line " + std::to_string(line_no) + ": " +
                                           std::to_string(count) + " values where earlier lines have " +
                                           std::to_string(columns));
    cloud.positions.push_back({v[0], v[1], v[2]});
    if (count == 6) cloud.normals.push_back({v[3], v[4], v[5]});
  }
  if (in.bad()) throw Error(Status::IoError, "'" + path + "': read error");
  return cloud;
}

void write_xyz(const PointCloud& cloud, const std::string& path) {
  AtomicFile file(path);
  {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.temp_path().c_str(), "wb"), &std::fclose);
    if (!f) throw Error(Status::IoError, "cannot write '" + path + "': " + std::strerror(errno));
    const bool normals = cloud.has_normals();
    for (size_t i = 0; i < cloud.size(); ++i) {
      const Vec3& p = cloud.positions[i];
      int ok;
      if (normals) {
        const Vec3& n = cloud.normals[i];
        ok = std::fprintf(f.get(), "%.17g %.17g %.17g %.9g %.9g %.9g\n", p.x, p.y, p.z, n.x, n.y, n.z);
      } else {
        ok = std::fprintf(f.get(), "%.17g %.17g %.17g\n", p.x, p.y, p.z);
      }
      if (ok < 0) throw Error(Status::IoError, "cannot write '" + path + "': " + std::strerror(errno));
    }
    if (std::fflush(f.get()) != 0) throw Error(Status::IoError, "cannot write '" + path + "': " + std::strerror(errno));
  }
  file.commit();
}

}  // namespace particlemesh::detail
