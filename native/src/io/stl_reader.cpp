// STL, binary and ASCII. The triangles' corners are joined into shared vertices where their
// coordinates are equal (as OpenMesh's reader, the one we had, and every STL importer do):
// topology needs shared vertices. Written by hand (a few dozen lines; OpenMesh's reader
// trusted a binary file's triangle count and kept float32 for ASCII coordinates).
#include <cmath>
#include <cstring>
#include <string>
#include <unordered_map>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

struct Key {
  uint64_t x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (k.y + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= (k.z + 0x165667B19E3779F9ull) * 0x85EBCA77C2B2AE63ull;
    return size_t(h ^ (h >> 29));
  }
};

class StlReader {
 public:
  StlReader(const std::string& path, ReadPurpose purpose) : in_(path), purpose_(purpose) {}

  FileContents read() {
    const std::string_view look = in_.look_ahead(84);
    const auto* head = reinterpret_cast<const unsigned char*>(look.data());
    const size_t got = look.size();
    if (got == 0) fail("the file is empty");
    size_t s = 0;
    while (s < got && (head[s] == ' ' || head[s] == '\t' || head[s] == '\r' || head[s] == '\n')) ++s;
    const bool solid = got - s >= 5 && std::memcmp(head + s, "solid", 5) == 0;
    uint32_t count = 0;
    if (got == 84) std::memcpy(&count, head + 80, 4);
    const uint64_t need = 84 + 50 * uint64_t(count);
    // A binary file may start with "solid" too: its size then matches its count exactly.
    const bool binary = got == 84 && (!solid || (in_.size() >= 0 && uint64_t(in_.size()) == need));
    if (binary) read_binary(count, need);
    else if (solid) read_ascii();
    else fail("not an STL file: " + std::to_string(in_.size() >= 0 ? uint64_t(in_.size()) : got) +
              " bytes, no 'solid' and no binary header");
    out_.faces = triangles_;
    return std::move(out_);
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }

  uint32_t vertex(double x, double y, double z) {
    if (std::isnan(x) || std::isnan(y) || std::isnan(z))
      fail("triangle " + std::to_string(triangles_) + " has a NaN coordinate");
    x += 0.0, y += 0.0, z += 0.0;  // -0 and 0 are one point
    Key k;
    std::memcpy(&k.x, &x, 8);
    std::memcpy(&k.y, &y, 8);
    std::memcpy(&k.z, &z, 8);
    const auto [it, added] = index_.try_emplace(k, uint32_t(out_.positions.size()));
    if (added) out_.positions.push_back({x, y, z});
    return it->second;
  }

  void read_binary(uint32_t count, uint64_t need) {
    if (in_.size() >= 0 && uint64_t(in_.size()) < need)
      fail("truncated binary STL: the header promises " + std::to_string(count) + " triangles (" + std::to_string(need) +
           " bytes), the file has " + std::to_string(in_.size()));
    if (in_.size() >= 0 && uint64_t(in_.size()) > need)
      fail("binary STL with more data than its header's " + std::to_string(count) + " triangles (" +
           std::to_string(need) + " bytes): the file has " + std::to_string(in_.size()));
    if (in_.size() >= 0) {
      out_.positions.reserve(count / 2 + 3);
      if (purpose_ == ReadPurpose::Mesh) out_.triangles.reserve(count);
    }
    in_.skip(84);
    for (uint32_t t = 0; t < count; ++t) {
      unsigned char rec[50];
      if (!in_.read(rec, sizeof rec))
        fail("truncated binary STL: the header promises " + std::to_string(count) + " triangles, the file ends in triangle " +
             std::to_string(t));
      float f[9];
      std::memcpy(f, rec + 12, sizeof f);  // after the facet normal; little-endian, as the format says
      Triangle tri;
      for (int c = 0; c < 3; ++c) tri[size_t(c)] = vertex(f[3 * c], f[3 * c + 1], f[3 * c + 2]);
      ++triangles_;
      if (purpose_ == ReadPurpose::Mesh) out_.triangles.push_back(tri);
    }
    if (!in_.only_whitespace_left()) fail("binary STL with more data than its header's triangles");
  }

  // ASCII: solid NAME / facet normal nx ny nz / outer loop / vertex x y z (3 or more) /
  // endloop / endfacet / ... / endsolid NAME; several solids may follow one another.
  void read_ascii() {
    std::string tok;
    std::vector<uint32_t> corners;
    bool in_loop = false;
    auto number = [&](const char* what) {
      if (!in_.token(tok, 128)) fail("truncated ASCII STL in triangle " + std::to_string(triangles_));
      double v = 0;
      const NumberText r = parse_number(tok, v);
      if (r != NumberText::Ok)
        fail("triangle " + std::to_string(triangles_) + ": " + what + " '" + shown(tok) + "' is " +
             (r == NumberText::Overflow ? "beyond the range of double (1.8e308)" : "not a number"));
      return v;
    };
    bool ended = false;  // the token ended its line (then there is no rest of the line to skip)
    while (in_.token(tok, 256, &ended)) {
      if (tok == "vertex") {
        if (!in_loop) fail("'vertex' outside an 'outer loop' (triangle " + std::to_string(triangles_) + ")");
        const double x = number("x"), y = number("y"), z = number("z");
        corners.push_back(vertex(x, y, z));
      } else if (tok == "facet") {
        if (in_loop) fail("'facet' inside a loop (triangle " + std::to_string(triangles_) + ")");
        if (!ended) in_.skip_line();  // normal nx ny nz: recomputed from the corners by whoever needs it
      } else if (tok == "outer") {
        if (!in_.token(tok, 256) || tok != "loop") fail("'outer' without 'loop'");
        in_loop = true;
        corners.clear();
      } else if (tok == "endloop") {
        if (!in_loop) fail("'endloop' without 'outer loop'");
        if (corners.size() < 3)
          fail("triangle " + std::to_string(triangles_) + " has " + std::to_string(corners.size()) + " corners");
        if (purpose_ == ReadPurpose::Mesh)
          for (size_t k = 1; k + 1 < corners.size(); ++k) out_.triangles.push_back({corners[0], corners[k], corners[k + 1]});
        ++triangles_;
        in_loop = false;
      } else if (tok == "endfacet") {
      } else if (tok == "endsolid" || tok == "solid") {
        if (!ended) in_.skip_line();  // the name
      } else {
        fail("unexpected '" + shown(tok) + "' in ASCII STL (triangle " + std::to_string(triangles_) + ")");
      }
    }
    if (in_loop) fail("truncated ASCII STL in triangle " + std::to_string(triangles_));
  }

  FileReader in_;
  ReadPurpose purpose_;
  FileContents out_;
  uint64_t triangles_ = 0;
  std::unordered_map<Key, uint32_t, KeyHash> index_;
};

}  // namespace

FileContents read_stl(const std::string& path, ReadPurpose purpose) { return StlReader(path, purpose).read(); }

}  // namespace particlemesh::detail
