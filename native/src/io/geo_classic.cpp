// Houdini's classic ASCII geometry (.geo before Houdini 12's JSON; "PGEOMETRY V5"), as
// Partio and older Houdini write particle caches:
//
//   PGEOMETRY V5
//   NPoints 5 NPrims 1
//   NPointGroups 0 NPrimGroups 0
//   NPointAttrib 2 NVertexAttrib 0 NPrimAttrib 1 NAttrib 0
//   PointAttrib
//   life 2 float 0 0                       name, size, type, defaults
//   id 1 int 0                             (index: name size index count strings...)
//   0 0.1 0.2 1 (-1.2 10 0)                x y z w, then the attributes' values in ( )
//   ...                                    primitives, groups, detail: not read
//
// What comes back is what the classic binary bgeo reader gives (bgeo_reader.cpp): x y z,
// every float / int / vector attribute under its Houdini name, "N" (3 floats) as the normals,
// index (string) attributes not carried but named in not_read. Written by hand: no Debian package reads it (Partio,
// which does, is not packaged).
#include "io/geo_classic.h"

#include <string>
#include <vector>

#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

class ClassicGeoReader {
 public:
  ClassicGeoReader(DecompressedStream& in, const std::string& path) : in_(in), path_(path) {}

  FileContents read() {
    // "PGEO" is read already: the rest of the magic word and the version.
    word("the header");
    if (token_ != "METRY") fail("not a classic .geo file (it does not start with 'PGEOMETRY')");
    word("the header");
    if (token_ != "V5") fail("classic .geo version '" + shown(token_) + "' (only V5 is read)");
    const uint64_t points = count("NPoints");
    count("NPrims");
    count("NPointGroups");
    count("NPrimGroups");
    const uint64_t attributes = count("NPointAttrib");
    count("NVertexAttrib");
    count("NPrimAttrib");
    count("NAttrib");
    std::vector<Attribute> attrs;
    size_t values = 4;  // x y z w
    if (attributes > 0) {
      word("the header");
      if (token_ != "PointAttrib") fail("'" + shown(token_) + "' where PointAttrib was expected");
      for (uint64_t k = 0; k < attributes; ++k) {
        attrs.push_back(definition());
        values += attrs.back().size;
      }
    }
    for (Attribute& a : attrs) {
      if (a.index) {  // indices into the attribute's strings: no per-particle number
        note_not_read(out_, "point attribute '" + shown(a.name) + "' (strings)");
        continue;
      }
      if (a.name == "N" && a.size == 3 && !a.integer && !has_normals_) {
        has_normals_ = true;
        a.target = -2;
        continue;
      }
      a.target = int(out_.attributes.size());
      out_.attributes.push_back({unique_attribute_name(out_, a.name), int(a.size), {}});
    }
    std::vector<double> v(values);
    for (uint64_t i = 0; i < points; ++i) {
      for (size_t k = 0; k < values; ++k) {
        if (!word(nullptr))
          fail("truncated: the file ends in point " + std::to_string(i) + " of the " + std::to_string(points) +
               " the header promises");
        if (parse_number(token_, v[k]) != NumberText::Ok)
          fail("point " + std::to_string(i) + ": '" + shown(token_) + "' is not a number");
      }
      out_.positions.push_back({v[0], v[1], v[2]});
      size_t at = 4;
      for (const Attribute& a : attrs) {
        if (a.target == -2) out_.normals.push_back({v[at], v[at + 1], v[at + 2]});
        else if (a.target >= 0)
          for (size_t c = 0; c < a.size; ++c) out_.attributes[size_t(a.target)].values.push_back(float(v[at + c]));
        at += a.size;
      }
    }
    return std::move(out_);
  }

 private:
  struct Attribute {
    std::string name;
    size_t size = 0;
    bool integer = false, index = false;
    int target = -1;  ///< index in out_.attributes, -2 = the normals, -1 = not carried
  };

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + path_ + "': " + problem);
  }

  /// The next word into token_ ('(' and ')' around a point's attribute values separate words
  /// like white space); false at the end of the stream (an error naming `where` unless null).
  bool word(const char* where) {
    token_.clear();
    unsigned char c;
    while (in_.read(&c, 1)) {
      const bool space = c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '(' || c == ')';
      if (space) {
        if (!token_.empty()) return true;
        continue;
      }
      if (token_.size() >= 4096) fail("a word longer than 4096 bytes");
      token_.push_back(char(c));
    }
    if (!token_.empty()) return true;
    if (where) fail(std::string("truncated: the file ends in ") + where);
    return false;
  }

  uint64_t count(const char* name) {
    word("the header");
    if (token_ != name) fail("'" + shown(token_) + "' where " + name + " was expected in the header");
    word("the header");
    uint64_t n = 0;
    if (!parse_count(token_, n)) fail(std::string(name) + " is '" + shown(token_) + "', not a count");
    return n;
  }

  Attribute definition() {
    Attribute a;
    word("the point attribute definitions");
    a.name = token_;
    word("the point attribute definitions");
    uint64_t size = 0;
    if (!parse_count(token_, size) || size == 0 || size > 65535)
      fail("point attribute '" + shown(a.name) + "' has size '" + shown(token_) + "'");
    a.size = size_t(size);
    word("the point attribute definitions");
    const std::string type = token_;
    if (type == "index") {
      // index: a count of strings, the strings (no default follows).
      a.index = true;
      word("the point attribute definitions");
      uint64_t strings = 0;
      if (!parse_count(token_, strings)) fail("index attribute '" + shown(a.name) + "' has '" + shown(token_) + "' strings");
      for (uint64_t s = 0; s < strings; ++s) word("the point attribute definitions");
      return a;
    }
    if (type != "float" && type != "int" && type != "vector")
      fail("point attribute '" + shown(a.name) + "' has type '" + shown(type) + "' (read: float, int, vector, index)");
    a.integer = type == "int";
    for (size_t k = 0; k < a.size; ++k) word("the point attribute definitions");  // the defaults
    return a;
  }

  DecompressedStream& in_;
  const std::string& path_;
  std::string token_;
  FileContents out_;
  bool has_normals_ = false;
};

}  // namespace

FileContents read_geo_classic(DecompressedStream& in, const std::string& path) { return ClassicGeoReader(in, path).read(); }

}  // namespace particlemesh::detail
