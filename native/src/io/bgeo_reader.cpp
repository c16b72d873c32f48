// Houdini's classic binary geometry, .bgeo ("BgeoV", version 5), plain or gzip-compressed:
// what SPlisHSPlasH, Partio, FLIP Fluids and older Houdini write for particle caches. A file
// that starts with binary JSON's 0x7f (Houdini 12+'s .bgeo), or with '[' or '{' (its ASCII .geo),
// goes to bgeo_json.cpp. Each may also come gzip-compressed or in SideFX's Blosc-compressed SCF
// container (.bgeo.sc, .geo.sc: the File Cache node's default), unpacked by
// DecompressedStream (compressed.h) before the first byte is looked at.
//
// Written by hand: no library packaged for Debian reads bgeo (Partio, which does, is not
// packaged, aborts on some attribute types and trusts every count). Layout (all big-endian):
//
//   "Bgeo" 'V' int32 version (5)
//   int32 points, primitives, point groups, primitive groups, point attributes,
//         vertex attributes, primitive attributes, detail attributes
//   per point attribute: uint16 name length, name, uint16 size (values per point),
//         int32 type (0 float, 1 int, 5 vector: `size` 32-bit defaults follow; 4 index
//         (string table): int32 count, then that many uint16-length strings)
//   per point: float32 x y z w, then each attribute's `size` 32-bit values
//   primitives, groups, detail attributes, and the bytes 00 ff at the end.
//
// What comes back: the points' x y z (exact float32 values), every float / int / vector
// attribute under its Houdini name (P's w and index (string) attributes are not carried; the
// latter are named in not_read),
// "N" (3 floats) as the normals ("v" becomes the channel "velocity": name_the_velocity).
// After the points, primitive and detail sections are read when they hold only what Partio
// writes (particle-system primitives, detail attributes, no groups), so that a truncated file
// is refused; anything else after the points is left unread (the points are complete).
// Houdini's classic ASCII geometry ("PGEOMETRY V5") goes to geo_classic.cpp.
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "io/bgeo_json.h"
#include "io/compressed.h"
#include "io/file_reader.h"
#include "io/formats.h"
#include "io/geo_classic.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

uint32_t be32(const unsigned char* b) { return uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | b[3]; }

float be_float(const unsigned char* b) {
  const uint32_t u = be32(b);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

const char* const kSupported =
    "particlemesh reads Houdini 12+'s bgeo (binary JSON) and .geo (ASCII JSON), classic bgeo (\"BgeoV\" version 5: "
    ".bhclassic, Partio, SPlisHSPlasH) and classic ASCII .geo (\"PGEOMETRY V5\"), plain, gzip- or Blosc-compressed (.bgeo, .bgeo.gz, .bgeo.sc, .geo, .geo.gz, "
    ".geo.sc); save the cache in one of those, or as .vtk or .ply";

class BgeoReader {
 public:
  BgeoReader(const std::string& path, ReadPurpose) : file_(path), in_(file_) {}

  FileContents read() {
    unsigned char magic[5];
    if (in_.at_end()) fail(in_.compressed() ? "it holds nothing once decompressed" : "the file is empty");
    if (!in_.read(magic, 4)) fail("too short for a bgeo file (" + std::to_string(in_.offset()) + " bytes)");
    if (magic[0] == 0x7f) {  // Houdini 12+'s binary JSON: 0x7f, then the magic number's bytes
      unsigned char last;
      if (!in_.read(&last, 1)) fail("too short for a binary-JSON bgeo file");
      const bool little = std::memcmp(magic + 1, "NSJ", 3) == 0 && last == 'b';
      const bool big = std::memcmp(magic + 1, "bJS", 3) == 0 && last == 'N';
      if (!little && !big) fail("starts with 0x7f but not with binary JSON's magic number (NSJb)");
      return read_bgeo_binary_json(in_, file_.path(), big);
    }
    if (magic[0] == '[' || magic[0] == '{')  // Houdini 12+'s ASCII geometry: the same schema as text
      return read_geo_text_json(in_, file_.path(), std::string_view(reinterpret_cast<const char*>(magic), 4));
    if (std::memcmp(magic, "PGEO", 4) == 0) return read_geo_classic(in_, file_.path());  // classic ASCII .geo
    if (std::memcmp(magic, "Bgeo", 4) != 0)
      fail(std::string("not a bgeo file (it does not start with 'Bgeo'") + (in_.compressed() ? " once decompressed" : "") +
           "); " + kSupported);
    if (!in_.read(magic + 4, 1) || magic[4] != 'V') fail("not a classic bgeo file ('Bgeo' is not followed by 'V')");
    int32_t h[9];
    for (int32_t& v : h) v = int32();
    const int32_t version = h[0];
    if (version != 5) unsupported("classic bgeo version " + std::to_string(version) + " (only version 5 is read)");
    const char* const kNames[9] = {"version", "points", "primitives", "point groups", "primitive groups",
                                   "point attributes", "vertex attributes", "primitive attributes", "detail attributes"};
    for (int k = 1; k < 9; ++k)
      if (h[k] < 0) fail("the header's count of " + std::string(kNames[k]) + " is " + std::to_string(h[k]));
    const uint64_t points = uint64_t(h[1]);
    const int32_t primitives = h[2], point_groups = h[3], primitive_groups = h[4];
    const int32_t vertex_attributes = h[6], primitive_attributes = h[7], detail_attributes = h[8];

    std::vector<Attribute> attrs = read_definitions(h[5], "point");
    size_t words = 4;  // x y z w
    for (const Attribute& a : attrs) words += a.size;
    read_points(points, attrs, words);

    // After the points: what Partio and SPlisHSPlasH write (no groups, particle-system
    // primitives, detail attributes, then 00 ff). Anything else is left unread.
    if (point_groups == 0 && primitive_groups == 0 && vertex_attributes == 0) {
      const std::vector<Attribute> prim_attrs = read_definitions(primitive_attributes, "primitive");
      size_t prim_words = 0;
      for (const Attribute& a : prim_attrs) prim_words += a.size;
      bool known = true;
      for (int32_t p = 0; p < primitives && known; ++p) {
        const uint32_t type = uint32_t(int32("in the primitives"));
        if (type != 0x8000) {
          known = false;  // polygons, volumes ...: not walked
          break;
        }
        const int32_t n = int32("in the primitives");
        if (n < 0) fail("primitive " + std::to_string(p) + " lists " + std::to_string(n) + " points");
        // Point numbers are 16-bit when there are fewer than 65536 points.
        if (!in_.skip(uint64_t(n) * (points < 65536 ? 2 : 4) + 4 * uint64_t(prim_words)))
          truncated("in primitive " + std::to_string(p));
      }
      if (known) {
        const std::vector<Attribute> detail = read_definitions(detail_attributes, "detail");
        size_t detail_words = 0;
        for (const Attribute& a : detail) detail_words += a.size;
        if (!in_.skip(4 * uint64_t(detail_words))) truncated("in the detail attributes' values");
        unsigned char extra[2];
        if (!in_.read(extra, 2)) truncated("before the end marker (00 ff)");
        if (extra[0] != 0x00 || extra[1] != 0xff)
          fail("the end marker after the points is not 00 ff (the header's counts do not match the data)");
        if (!in_.at_end()) fail("more data after the end marker (00 ff): the header's counts do not match the data");
      }
    }
    return std::move(out_);
  }

 private:
  struct Attribute {
    std::string name;
    uint16_t size = 0;
    int32_t type = 0;
    int target = -1;  ///< index in out_.attributes, -2 = the normals, -1 = not carried
  };

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + file_.path() + "': " + problem);
  }
  [[noreturn]] void unsupported(const std::string& what) const { fail(what + "; " + kSupported); }
  [[noreturn]] void truncated(const std::string& where) const {
    fail("truncated: the file ends " + where + " (after " + std::to_string(in_.offset()) + " bytes" +
         (in_.compressed() ? " of decompressed data" : "") + ")");
  }

  int32_t int32(const char* where = "in the header") {
    unsigned char b[4];
    if (!in_.read(b, 4)) truncated(where);
    return int32_t(be32(b));
  }
  uint16_t uint16(const char* where) {
    unsigned char b[2];
    if (!in_.read(b, 2)) truncated(where);
    return uint16_t(b[0] << 8 | b[1]);
  }

  std::vector<Attribute> read_definitions(int32_t count, const char* kind) {
    std::vector<Attribute> attrs;
    const std::string where = std::string("in the ") + kind + " attribute definitions";
    for (int32_t i = 0; i < count; ++i) {
      Attribute a;
      const uint16_t length = uint16(where.c_str());
      a.name.resize(length);
      if (!in_.read(a.name.data(), length)) truncated(where);
      a.size = uint16(where.c_str());
      unsigned char t[4];
      if (!in_.read(t, 4)) truncated(where);
      a.type = int32_t(be32(t));
      const std::string named = std::string(kind) + " attribute '" + shown(a.name) + "'";
      if (a.type == 0 || a.type == 1 || a.type == 5) {
        if (!in_.skip(4 * uint64_t(a.size))) truncated(where);  // defaults
      } else if (a.type == 4) {
        const int32_t strings = int32(where.c_str());
        if (strings < 0) fail(named + " has " + std::to_string(strings) + " strings");
        for (int32_t s = 0; s < strings; ++s)
          if (!in_.skip(uint16(where.c_str()))) truncated(where);
      } else {
        fail(named + " has type " + std::to_string(a.type) +
             (a.type == 2 ? " (string), which classic bgeo readers do not read" : ", which is not a classic bgeo type") +
             " (read: 0 float, 1 int, 4 index, 5 vector)");
      }
      attrs.push_back(std::move(a));
    }
    return attrs;
  }

  void read_points(uint64_t points, std::vector<Attribute>& attrs, size_t words) {
    // One point's bytes (at most 8 + 65535 x attributes x 4): refused beyond 64 MiB.
    if (words > (uint64_t(1) << 24))
      fail("a point of " + std::to_string(words) + " values (the attribute sizes are not plausible)");
    const uint64_t record = 4 * uint64_t(words);
    // Nothing is sized from the header alone: a plain file must hold the points' bytes, and
    // a compressed one grows its arrays as the data comes.
    if (!in_.compressed() && file_.size() >= 0 && points > uint64_t(file_.size()) / record)
      fail("truncated: the header promises " + std::to_string(points) + " points (" + std::to_string(points * record) +
           " bytes), the file has " + std::to_string(file_.size()) + " bytes");
    const size_t plausible = size_t(std::min<uint64_t>(points, in_.compressed() ? (1u << 16) : points));
    for (Attribute& a : attrs) {
      if (a.size == 0) continue;
      if (a.type == 4) {  // indices into the attribute's strings: no per-particle number
        note_not_read(out_, "point attribute '" + shown(a.name) + "' (strings)");
        continue;
      }
      if (a.name == "N" && a.size == 3 && a.type != 1 && out_.normals.empty() && !has_normals_) {
        has_normals_ = true;
        a.target = -2;
        continue;
      }
      a.target = int(out_.attributes.size());
      out_.attributes.push_back({unique_attribute_name(out_, a.name), int(a.size), {}});
      out_.attributes.back().values.reserve(plausible * a.size);
    }
    out_.positions.reserve(plausible);
    if (has_normals_) out_.normals.reserve(plausible);
    std::vector<unsigned char> buf(record);
    for (uint64_t i = 0; i < points; ++i) {
      if (!in_.read(buf.data(), record))
        truncated("in point " + std::to_string(i) + " of the " + std::to_string(points) + " the header promises");
      out_.positions.push_back({double(be_float(&buf[0])), double(be_float(&buf[4])), double(be_float(&buf[8]))});
      size_t w = 4;
      for (const Attribute& a : attrs) {
        const unsigned char* v = &buf[4 * w];
        if (a.target == -2) {
          out_.normals.push_back({double(be_float(v)), double(be_float(v + 4)), double(be_float(v + 8))});
        } else if (a.target >= 0) {
          auto& values = out_.attributes[size_t(a.target)].values;
          for (size_t c = 0; c < a.size; ++c)
            values.push_back(a.type == 1 ? float(int32_t(be32(v + 4 * c))) : be_float(v + 4 * c));
        }
        w += a.size;
      }
    }
  }

  FileReader file_;
  DecompressedStream in_;
  FileContents out_;
  bool has_normals_ = false;
};

}  // namespace

FileContents read_bgeo(const std::string& path, ReadPurpose purpose) { return BgeoReader(path, purpose).read(); }

}  // namespace particlemesh::detail
