// PLY (Turk 1994): ASCII and binary in either byte order, read in one pass.
//
// Written by hand: Debian 12 packages no stand-alone C++ PLY library, and the readers inside
// the libraries we use keep float32 positions and trust the header (OpenMesh's read an ASCII
// file promising 2e9 vertices as complete with made-up ones, and looped forever on several
// malformed headers; PCL's crashed on others). This one reads every value exactly (integer,
// float32 and double properties alike), takes nothing from a header on trust (counts are only
// believed as far as the bytes really there), reads the elements in the order the header
// declares them (faces before vertices is valid PLY), and refuses what it cannot read with
// the element, the property and the value named.
//
// What it reads: the "vertex" element's x y z (any numeric type; upper-case X Y Z too, when
// no lower-case one is declared), nx ny nz or normal_x normal_y normal_z (all three, or
// they are kept as plain attributes), red green blue (-> the "color" attribute in [0, 1]:
// 8-bit values / 255, 16-bit / 65535, float as stored), every other scalar vertex property as
// a one-component attribute of its name, except that properties name_0, name_1, .., name_k
// declared one after another (as our writers write a vector channel; or vx vy vz, name_x
// name_y name_z, as vector_component reads them) are one (k + 1)-component attribute "name";
// and the "face" element's vertex_indices (or vertex_index) lists, fanned into triangles (or,
// in a file without faces, the "tristrips" element's lists: triangle strips, -1 restarting a
// strip, as the Stanford repository's older models hold them), with MeshLab's "texcoord" face
// list (u v per corner, fanned with the face) as the corner attribute "uv". List
// properties anywhere (a vertex element with a list, an "edge" or "material" element) are
// walked and skipped (a vertex list is named in not_read). After the last element the file must end
// (whitespace aside): data beyond what the header declares means a count is wrong.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/scalar_types.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

using Type = ScalarType;  // PLY has no 64-bit integers

Type type_of(std::string_view t) {
  if (t == "char" || t == "int8") return Type::I8;
  if (t == "uchar" || t == "uint8") return Type::U8;
  if (t == "short" || t == "int16") return Type::I16;
  if (t == "ushort" || t == "uint16") return Type::U16;
  if (t == "int" || t == "int32") return Type::I32;
  if (t == "uint" || t == "uint32") return Type::U32;
  if (t == "float" || t == "float32") return Type::F32;
  if (t == "double" || t == "float64") return Type::F64;
  return Type::None;
}

// What a property is read into.
enum Role : int { kSkip = -1, kX = 0, kY, kZ, kNX, kNY, kNZ, kRed, kGreen, kBlue, kIndices, kAttribute, kTexcoord };

struct Property {
  std::string name;
  Type type = Type::None;  ///< the scalar's type, or the list items' type
  bool list = false;
  Type count_type = Type::None;
  int role = kSkip;
  size_t attribute = 0;  ///< index into FileContents::attributes for kAttribute
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  bool has_list = false;
  uint64_t record = 0;  ///< bytes of one element without lists' items (binary)
};

enum class Encoding { None, Ascii, BinaryLE, BinaryBE };

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> w;
  split_words(line, w);
  return w;
}

std::string plural(uint64_t n, const std::string& what) {
  return std::to_string(n) + " '" + what + "' element" + (n == 1 ? "" : "s");
}

uint64_t mul_add(uint64_t a, uint64_t b, uint64_t c) {  // saturating a * b + c
  if (b != 0 && a > (UINT64_MAX - c) / b) return UINT64_MAX;
  return a * b + c;
}

class PlyReader {
 public:
  PlyReader(const std::string& path, ReadPurpose purpose) : in_(path), purpose_(purpose) {}

  FileContents read() {
    if (in_.peek() < 0) fail("the file is empty");
    read_header();
    assign_roles();
    for (Element& e : elements_) read_element(e);
    if (!in_.only_whitespace_left())
      fail("more data after the " + declared() +
           " the header declares (at byte " + std::to_string(in_.offset() - 1) +
           "): a count in the header is too small, or the file is not one PLY file");
    merge_component_runs();
    if (face_ && texcoord_) {
      if (uv_mismatch_ == 0)
        out_.corner_attributes.push_back({"uv", 2, std::move(corner_uvs_)});
      else
        note_not_read(out_, face_->name + " property 'texcoord' (" + std::to_string(uv_mismatch_) +
                                " faces' lists do not hold a u and a v for each corner)");
    }
    if (!colors_.empty()) {
      VertexAttribute color{"color", 3, std::move(colors_)};
      out_.attributes.insert(out_.attributes.begin(), std::move(color));
    }
    return std::move(out_);
  }

 private:
  // Properties name_0, name_1, .., name_k declared one after another (two or more) become one
  // attribute "name" of k + 1 components, interleaved per vertex: write_mesh writes a vector
  // channel (velocity) that way, so a PLY round trip gives back the channel it was. So do the
  // other namings of a vector's components the text reader knows (vector_component: vx vy vz,
  // name_x name_y name_z, ..). Left as they are where "name" is itself a property's or
  // attribute's name.
  void merge_component_runs() {
    auto& attrs = out_.attributes;
    std::vector<std::string> names;  // every vertex property's name, and the colour channel's
    for (const Property& p : vertex_->properties) names.push_back(p.name);
    if (has_colors_) names.push_back("color");
    auto taken = [&](const std::string& name, const std::vector<VertexAttribute>& so_far) {
      for (const VertexAttribute& a : so_far)
        if (a.name == name) return true;
      return std::find(names.begin(), names.end(), name) != names.end();
    };
    std::vector<size_t> declared_at(attrs.size());  // each attribute's place among the properties
    for (size_t k = 0; k < vertex_->properties.size(); ++k)
      if (vertex_->properties[k].role == kAttribute) declared_at[vertex_->properties[k].attribute] = k;
    std::vector<VertexAttribute> merged;
    merged.reserve(attrs.size());
    for (size_t i = 0; i < attrs.size();) {
      size_t run = 0;
      std::string base, next;
      if (vector_component(attrs[i].name, base) == 0) {
        run = 1;
        while (i + run < attrs.size() && declared_at[i + run] == declared_at[i] + run &&
               vector_component(attrs[i + run].name, next) == int(run) && next == base)
          ++run;
        if (run < 2 || taken(base, merged)) run = 0;
        if (run > 0) {
          const size_t n = attrs[i].values.size();
          VertexAttribute v{base, int(run), {}};
          v.values.resize(n * run);
          for (size_t c = 0; c < run; ++c) {
            const std::vector<float>& from = attrs[i + c].values;
            for (size_t k = 0; k < n; ++k) v.values[k * run + c] = from[k];
            std::vector<float>().swap(attrs[i + c].values);  // freed as it goes: no third copy
          }
          merged.push_back(std::move(v));
          i += run;
          continue;
        }
      }
      merged.push_back(std::move(attrs[i]));
      ++i;
    }
    attrs = std::move(merged);
  }

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }

  std::string declared() const {
    std::string s;
    for (const Element& e : elements_) s += (s.empty() ? "" : ", ") + plural(e.count, e.name);
    return s.empty() ? "no elements" : s;
  }

  // ---- header ---------------------------------------------------------------------------
  void read_header() {
    constexpr size_t kMaxLine = 1 << 16;
    constexpr uint64_t kMaxHeader = 1 << 20;
    std::string_view line;
    if (!in_.line(line, kMaxLine)) fail("the file is empty");
    const auto magic = words(line);
    if (magic.size() != 1 || !equals_ignoring_case(magic[0], "ply"))
      fail("not a PLY file (it does not start with the line 'ply')");
    bool first = true, ended = false;
    while (in_.offset() <= kMaxHeader && in_.line(line, kMaxLine)) {
      const auto w = words(line);
      if (w.empty()) continue;
      const std::string shown_line = shown(line.substr(0, 80));
      auto bad = [&](const std::string& why) { fail("bad PLY header line '" + shown_line + "' (" + why + ")"); };
      if (first && (w[0] != "format" || w.size() != 3))
        bad("the line after 'ply' must be: format TYPE VERSION");
      first = false;
      if (w[0] == "comment" || w[0] == "obj_info") continue;
      if (w[0] == "end_header") {
        if (w.size() != 1) bad("end_header alone");
        ended = true;
        break;
      }
      if (w[0] == "format") {
        if (encoding_ != Encoding::None) fail("bad PLY header: a second format line");
        if (w.size() != 3) bad("format TYPE VERSION");
        encoding_ = w[1] == "ascii"                  ? Encoding::Ascii
                    : w[1] == "binary_little_endian" ? Encoding::BinaryLE
                    : w[1] == "binary_big_endian"    ? Encoding::BinaryBE
                                                     : Encoding::None;
        if (encoding_ == Encoding::None) fail("PLY format '" + shown(w[1]) + "' is not ascii or binary");
        double version = 0;
        if (parse_number(w[2], version) != NumberText::Ok || !std::isfinite(version))
          bad("format TYPE VERSION, e.g. 1.0");
      } else if (w[0] == "element") {
        Element e;
        if (w.size() != 3 || !parse_count(w[2], e.count)) bad("element NAME COUNT");
        e.name = std::string(w[1].substr(0, 64));
        elements_.push_back(std::move(e));
      } else if (w[0] == "property") {
        if (elements_.empty()) fail("bad PLY header: a property before any element");
        Property p;
        if (w.size() == 5 && w[1] == "list") {
          p.list = true;
          p.count_type = type_of(w[2]);
          p.type = type_of(w[3]);
          p.name = std::string(w[4].substr(0, 64));
          if (p.count_type == Type::None || p.type == Type::None || !is_integer(p.count_type))
            bad("unknown list types: property list COUNT_TYPE ITEM_TYPE NAME, the count an integer type");
        } else if (w.size() == 3) {
          p.type = type_of(w[1]);
          p.name = std::string(w[2].substr(0, 64));
          if (p.type == Type::None) bad("unknown type '" + shown(w[1]) + "'");
        } else {
          bad("property TYPE NAME or property list COUNT_TYPE ITEM_TYPE NAME");
        }
        Element& e = elements_.back();
        for (const Property& q : e.properties)
          if (q.name == p.name) bad("a second property named '" + shown(p.name) + "'");
        e.has_list |= p.list;
        e.record += uint64_t(p.list ? scalar_size(p.count_type) : scalar_size(p.type));
        e.properties.push_back(std::move(p));
      } else {
        bad("unknown keyword '" + shown(w[0]) + "'");
      }
    }
    if (!ended) {
      if (in_.offset() > kMaxHeader) fail("no end_header in the first MiB: not a PLY file");
      fail("truncated PLY header (no end_header)");
    }
    if (encoding_ == Encoding::None) fail("bad PLY header: no format line");
  }

  // Which property of the vertex element is x, y, z, ...: an exact match first, then one
  // in another case (X Y Z). The face element's vertex_indices list.
  void assign_roles() {
    Element* vertex = nullptr;
    Element* face = nullptr;
    for (Element& e : elements_) {
      if (!vertex && equals_ignoring_case(e.name, "vertex")) vertex = &e;
      if (!face && equals_ignoring_case(e.name, "face")) face = &e;
    }
    if (!face)
      for (Element& e : elements_)
        if (equals_ignoring_case(e.name, "tristrips")) {
          face = &e;
          strips_ = true;
          break;
        }
    if (!vertex) fail("no 'vertex' element (the header declares " + declared() + ")");
    vertex_ = vertex;
    static const char* const kNames[9] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
    auto find = [&](const char* name) -> Property* {
      for (Property& p : vertex->properties)
        if (!p.list && p.role == kSkip && p.name == name) return &p;
      for (Property& p : vertex->properties)
        if (!p.list && p.role == kSkip && equals_ignoring_case(p.name, name)) return &p;
      return nullptr;
    };
    Property* found[9] = {};
    for (int k = 0; k < 9; ++k)
      if ((found[k] = find(kNames[k]))) found[k]->role = k;
    // Else normal_x normal_y normal_z (PCL's names of the fields, which the text reader reads too).
    if (!(found[kNX] && found[kNX + 1] && found[kNX + 2])) {
      static const char* const kPclNormals[3] = {"normal_x", "normal_y", "normal_z"};
      Property* pcl[3] = {find(kPclNormals[0]), find(kPclNormals[1]), find(kPclNormals[2])};
      if (pcl[0] && pcl[1] && pcl[2])
        for (int k = 0; k < 3; ++k) {
          if (found[kNX + k]) found[kNX + k]->role = kSkip;
          found[kNX + k] = pcl[k];
          pcl[k]->role = kNX + k;
        }
    }
    for (int k = 0; k < 3; ++k)
      if (!found[k]) {
        std::string has;
        for (const Property& p : vertex->properties) has += " " + shown(p.name);
        fail("the 'vertex' element has no '" + std::string(kNames[k]) + "' property (it has:" +
             (has.empty() ? std::string(" none") : has) + ")");
      }
    // Normals and colours come in threes; a partial set stays plain attributes.
    for (int group : {3, 6})
      if (!(found[group] && found[group + 1] && found[group + 2]))
        for (int k = group; k < group + 3; ++k)
          if (found[k]) found[k]->role = kSkip;
    has_normals_ = found[kNX] && found[kNX]->role == kNX;
    has_colors_ = found[kRed] && found[kRed]->role == kRed;
    for (Property& p : vertex->properties) {
      if (p.role != kSkip) continue;
      if (p.list) {  // no channel of one value per vertex
        note_not_read(out_, vertex->name + " list property '" + shown(p.name) + "' (lists)");
        continue;
      }
      if (has_colors_ && p.name == "color") {  // the colour channel's name is taken
        note_not_read(out_, vertex->name + " property 'color' (the red, green and blue properties are the channel "
                                             "\"color\")");
        continue;
      }
      p.role = kAttribute;
      p.attribute = out_.attributes.size();
      out_.attributes.push_back({p.name, 1, {}});
    }
    if (face) {
      for (Property& p : face->properties)
        if (p.list && (equals_ignoring_case(p.name, "vertex_indices") || equals_ignoring_case(p.name, "vertex_index"))) {
          if (purpose_ == ReadPurpose::Points) break;  // walked, not read
          if (!is_integer(p.type))
            fail("the '" + face->name + "' element's " + p.name + " list holds non-integer values (indices must be integers)");
          p.role = kIndices;
          face_ = face;
          break;
        }
      // MeshLab's texture coordinates per face corner (a triangle strip has none).
      if (face_ && purpose_ == ReadPurpose::Mesh && !strips_)
        for (Property& p : face->properties)
          if (p.list && p.name == "texcoord" && !is_integer(p.type) && !texcoord_) {
            p.role = kTexcoord;
            texcoord_ = true;
          }
      if (!face_ && purpose_ == ReadPurpose::Mesh && face->count > 0)
        fail("the '" + face->name + "' element has no vertex_indices list");
    }
    if (purpose_ == ReadPurpose::Mesh) {
      // What a mesh read here does not carry: the faces' other properties (a colour, a
      // texture's corners), and other elements (edges, materials, ...).
      if (face_)
        for (const Property& p : face_->properties)
          if (p.role != kIndices && p.role != kTexcoord)
            note_not_read(out_, face_->name + " property '" + shown(p.name) + "'" + (p.list ? " (a list)" : ""));
      for (const Element& e : elements_)
        if (&e != vertex_ && &e != face && e.count > 0)
          note_not_read(out_, "element '" + shown(e.name) + "' (" + std::to_string(e.count) + ")");
    }
  }

  // ---- data -----------------------------------------------------------------------------
  uint64_t bytes_left() const { return in_.size() < 0 ? UINT64_MAX : uint64_t(in_.size()) - std::min<uint64_t>(in_.offset(), uint64_t(in_.size())); }

  [[noreturn]] void truncated(const Element& e, uint64_t i) const {
    fail("truncated: the header promises " + plural(e.count, e.name) + ", the file ends in element " + std::to_string(i));
  }

  // How many elements the rest of the file can hold at least (for reserve): never more than
  // its bytes allow, so that a lying count allocates nothing.
  size_t plausible(const Element& e) const {
    const uint64_t left = bytes_left();
    const uint64_t per = encoding_ == Encoding::Ascii ? 2 * std::max<size_t>(1, e.properties.size()) : std::max<uint64_t>(1, e.record);
    // A FIFO's length is unknown: a modest start (the vectors grow with what really comes),
    // shared by the element's properties (each may be an attribute array).
    const uint64_t most = left == UINT64_MAX ? (uint64_t(1) << 16) / std::max<size_t>(1, e.properties.size()) : left / per;
    return size_t(std::min(e.count, most));
  }

  void read_element(Element& e) {
    const bool binary = encoding_ != Encoding::Ascii;
    if (binary) {
      const uint64_t least = mul_add(e.count, e.record, 0);
      if (least > bytes_left())
        fail("truncated: the header promises " + plural(e.count, e.name) + " (at least " + std::to_string(least) +
             " bytes), the file holds " + std::to_string(bytes_left()) + " bytes for them");
    }
    const bool is_vertex = &e == vertex_, is_face = &e == face_ && purpose_ == ReadPurpose::Mesh;
    if (is_vertex) {
      const size_t n = plausible(e);
      out_.positions.reserve(n);
      if (has_normals_) out_.normals.reserve(n);
      if (has_colors_) colors_.reserve(3 * n);
      for (VertexAttribute& a : out_.attributes) a.values.reserve(n);
    }
    if (is_face) {
      out_.faces = e.count;
      out_.triangles.reserve(plausible(e));
    }
    // Binary elements without lists that nothing is read from: one skip.
    if (binary && !e.has_list && !is_vertex) {
      if (!in_.skip(mul_add(e.count, e.record, 0))) truncated(e, 0);
      return;
    }
    // Binary vertices without lists in a file of known size (checked above to hold them all):
    // read in blocks of records and decoded a property at a time, with the type's and the
    // role's switches outside the loop (a million x y z nx ny nz floats: ~15 ms, where a
    // read and two switches per value took ~90 ms). The same values as the loop below.
    if (binary && !e.has_list && is_vertex && in_.size() >= 0) {
      read_vertex_records(e);
      return;
    }
    // Binary faces of vertex indices only (a list of uchar count, int or uint items), as nearly
    // every mesh writer has them: parsed a buffer at a time (two million triangles ~3x faster).
    if (binary && is_face && !strips_ && e.properties.size() == 1 && e.properties[0].list &&
        e.properties[0].role == kIndices && e.properties[0].count_type == Type::U8 &&
        (e.properties[0].type == Type::I32 || e.properties[0].type == Type::U32)) {
      read_index_faces(e);
      return;
    }
    for (uint64_t i = 0; i < e.count; ++i) read_record(e, i, is_vertex);
    if (is_face && strips_) out_.faces = out_.triangles.size();  // the faces are the strips' triangles
  }

  // The faces of read_element's fast path: the records whole in the file's look-ahead (4096
  // bytes; a record of a uchar count is at most 1021) and plain (3 or more corners, each an
  // index the general path takes) are parsed from it directly, each fanned as the general path
  // fans it; any other record (fewer corners, a negative or too large index, one cut by the end
  // of the file) is read by the general path, which takes it or names what is wrong with it.
  void read_index_faces(const Element& e) {
    const bool big_endian = encoding_ == Encoding::BinaryBE, is_signed = e.properties[0].type == Type::I32;
    for (uint64_t i = 0; i < e.count;) {
      const std::string_view view = in_.look_ahead(4096);
      const auto* b = reinterpret_cast<const unsigned char*>(view.data());
      size_t at = 0;
      while (i < e.count && at < view.size()) {
        const size_t n = b[at];
        if (n < 3 || at + 1 + 4 * n > view.size()) break;
        corners_.clear();
        bool plain = true;
        for (size_t k = 0; k < n && plain; ++k) {
          const unsigned char* r = b + at + 1 + 4 * k;
          const uint32_t v = big_endian ? (uint32_t(r[0]) << 24) | (uint32_t(r[1]) << 16) | (uint32_t(r[2]) << 8) | r[3]
                                        : load_little<uint32_t>(r);
          plain = is_signed ? v <= uint32_t(INT32_MAX) : v <= UINT32_MAX - 1;
          corners_.push_back(v);
        }
        if (!plain) break;
        for (size_t k = 1; k + 1 < n; ++k) out_.triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
        at += 1 + 4 * n;
        ++i;
      }
      if (at > 0) {
        in_.skip(at);
      } else {
        read_record(e, i, false);
        ++i;
      }
    }
  }

  // Element e's record i by the general path (a vertex: its position, normal and colour slots
  // are added first).
  void read_record(const Element& e, uint64_t i, bool is_vertex) {
    const bool binary = encoding_ != Encoding::Ascii;
    if (is_vertex) {
      out_.positions.emplace_back();
      if (has_normals_) out_.normals.emplace_back();
      if (has_colors_) colors_.insert(colors_.end(), 3, 0.0f);
    }
    const bool face_uvs = texcoord_ && &e == face_ && purpose_ == ReadPurpose::Mesh;
    if (face_uvs) face_uv_.clear();
    const size_t first_triangle = out_.triangles.size();
    for (const Property& p : e.properties) {
      if (!p.list) {
        const double v = scalar(e, i, p);
        if (is_vertex) store(p, v);
        continue;
      }
      const uint64_t n = list_count(e, i, p);
      if (binary && mul_add(n, uint64_t(scalar_size(p.type)), 0) > bytes_left())
        fail("'" + e.name + "' element " + std::to_string(i) + " has a list of " + std::to_string(n) +
             " items, more than the rest of the file holds");
      if (p.role == kIndices && strips_) {
        read_strips(e, i, p, n);
      } else if (p.role == kIndices) {
        if (n < 3)
          fail("'" + e.name + "' element " + std::to_string(i) + " has " + std::to_string(n) +
               " corner" + (n == 1 ? "" : "s") + " (a face needs at least 3)");
        corners_.clear();
        for (uint64_t k = 0; k < n; ++k) {
          const double v = scalar(e, i, p);
          if (v < 0)
            fail("'" + e.name + "' element " + std::to_string(i) + " refers to vertex " + format(v) +
                 " (indices start at 0)");
          if (v > double(UINT32_MAX - 1))
            fail("'" + e.name + "' element " + std::to_string(i) + " refers to vertex " + format(v) +
                 ", beyond 2^32 - 2");
          corners_.push_back(uint32_t(v));
        }
        for (size_t k = 1; k + 1 < corners_.size(); ++k)
          out_.triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
      } else if (p.role == kTexcoord) {
        for (uint64_t k = 0; k < n; ++k) face_uv_.push_back(scalar(e, i, p));
      } else if (binary) {
        if (!in_.skip(mul_add(n, uint64_t(scalar_size(p.type)), 0))) truncated(e, i);
      } else {
        for (uint64_t k = 0; k < n; ++k) scalar(e, i, p);
      }
    }
    if (face_uvs) fan_texcoords(first_triangle);
  }

  // The record's texture coordinates (face_uv_, u v per corner of corners_) for the triangles
  // it was fanned into from first_triangle on; a list of another length, or values beyond
  // float, counted in uv_mismatch_ (the coordinates are then not read).
  void fan_texcoords(size_t first_triangle) {
    bool fits = face_uv_.size() == 2 * corners_.size();
    for (double x : face_uv_) fits = fits && std::isfinite(x) && std::abs(x) <= double(FLT_MAX);
    if (!fits) ++uv_mismatch_;
    if (uv_mismatch_ > 0) {
      corner_uvs_.clear();
      return;
    }
    for (size_t t = first_triangle, k = 1; t < out_.triangles.size(); ++t, ++k)
      for (const size_t j : {size_t(0), k, k + 1})
        corner_uvs_.insert(corner_uvs_.end(), {float(face_uv_[2 * j]), float(face_uv_[2 * j + 1])});
  }

  void read_vertex_records(const Element& e) {
    std::vector<size_t> offset;
    size_t at = 0;
    for (const Property& p : e.properties) {
      offset.push_back(at);
      at += size_t(scalar_size(p.type));
    }
    const bool big_endian = encoding_ == Encoding::BinaryBE;
    const size_t record = size_t(e.record), block = std::max<size_t>(1, (size_t(1) << 20) / std::max<size_t>(1, record));
    std::vector<unsigned char> buf;
    for (uint64_t first = 0; first < e.count;) {
      const size_t m = size_t(std::min<uint64_t>(block, e.count - first));
      buf.resize(m * record);
      if (!in_.read(buf.data(), buf.size())) truncated(e, first);
      const size_t base = out_.positions.size();
      out_.positions.resize(base + m);
      if (has_normals_) out_.normals.resize(base + m);
      if (has_colors_) colors_.resize(3 * (base + m), 0.0f);
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        const unsigned char* raw = buf.data() + offset[k];
        with_scalar_type(p.type, [&](auto zero) {
          using T = decltype(zero);
          const auto value = [&](size_t r) {
            return big_endian ? scalar_at<T>(raw + r * record, true) : to_double(load_little<T>(raw + r * record));
          };
          switch (p.role) {
            case kX: for (size_t r = 0; r < m; ++r) out_.positions[base + r].x = value(r); return;
            case kY: for (size_t r = 0; r < m; ++r) out_.positions[base + r].y = value(r); return;
            case kZ: for (size_t r = 0; r < m; ++r) out_.positions[base + r].z = value(r); return;
            case kNX: for (size_t r = 0; r < m; ++r) out_.normals[base + r].x = value(r); return;
            case kNY: for (size_t r = 0; r < m; ++r) out_.normals[base + r].y = value(r); return;
            case kNZ: for (size_t r = 0; r < m; ++r) out_.normals[base + r].z = value(r); return;
            case kAttribute: {
              std::vector<float>& values = out_.attributes[p.attribute].values;
              for (size_t r = 0; r < m; ++r) values.push_back(float(value(r)));
              return;
            }
            case kRed: case kGreen: case kBlue:
              for (size_t r = 0; r < m; ++r) store_color(p, base + r, value(r));
              return;
            default: return;  // not read
          }
        });
      }
      first += m;
    }
  }

  // A list of triangle strips, each ended by -1 (or by the list's end): triangle k of a strip
  // is (s_k, s_k+1, s_k+2), every other one turned (s_k+1, s_k, s_k+2) to keep the strip's
  // orientation; triangles with a repeated corner (the joins strippers put between strips)
  // are dropped.
  void read_strips(const Element& e, uint64_t i, const Property& p, uint64_t n) {
    corners_.clear();
    auto flush = [&] {
      for (size_t k = 0; k + 2 < corners_.size(); ++k) {
        const uint32_t a = corners_[k], b = corners_[k + 1], c = corners_[k + 2];
        if (a == b || b == c || a == c) continue;
        out_.triangles.push_back(k % 2 ? Triangle{b, a, c} : Triangle{a, b, c});
      }
      corners_.clear();
    };
    for (uint64_t k = 0; k < n; ++k) {
      const double v = scalar(e, i, p);
      if (v == -1) {
        flush();
        continue;
      }
      if (v < 0)
        fail("'" + e.name + "' element " + std::to_string(i) + " refers to vertex " + format(v) +
             " (indices start at 0; -1 ends a strip)");
      if (v > double(UINT32_MAX - 1))
        fail("'" + e.name + "' element " + std::to_string(i) + " refers to vertex " + format(v) + ", beyond 2^32 - 2");
      corners_.push_back(uint32_t(v));
    }
    flush();
  }

  static std::string format(double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.0f", v);
    return s;
  }

  uint64_t list_count(const Element& e, uint64_t i, const Property& p) {
    if (encoding_ == Encoding::Ascii) {
      if (!in_.token(token_, 64)) truncated(e, i);
      uint64_t n = 0;
      if (!parse_count(token_, n))
        fail("'" + e.name + "' element " + std::to_string(i) + ": list count '" + shown(token_) +
             "' is not a non-negative integer");
      return n;
    }
    unsigned char raw[8];
    const int size = scalar_size(p.count_type);
    if (!in_.read(raw, size_t(size))) truncated(e, i);
    const double n = decode(raw, p.count_type);
    if (n < 0) fail("'" + e.name + "' element " + std::to_string(i) + " has a negative list count");
    return uint64_t(n);
  }

  double scalar(const Element& e, uint64_t i, const Property& p) {
    if (encoding_ == Encoding::Ascii) {
      if (!in_.token(token_, 128)) truncated(e, i);
      auto where = [&] { return "'" + e.name + "' element " + std::to_string(i) + ": "; };
      if (is_integer(p.type)) {
        int64_t v = 0;
        if (!parse_integer(token_, v)) fail(where() + "'" + shown(token_) + "' is not an integer");
        return double(v);
      }
      double v = 0;
      switch (parse_number(token_, v)) {
        case NumberText::Ok: return v;
        case NumberText::NotANumber: fail(where() + "'" + shown(token_) + "' is not a number");
        case NumberText::Overflow:
          fail(where() + p.name + " = " + shown(token_) + " is beyond the range of double (1.8e308)");
      }
      return v;
    }
    unsigned char raw[8];
    if (!in_.read(raw, size_t(scalar_size(p.type)))) truncated(e, i);
    return decode(raw, p.type);
  }

  // A binary value in the file's byte order, exactly (every PLY type fits a double).
  double decode(const unsigned char* raw, Type t) const {
    return decode_scalar(t, raw, encoding_ == Encoding::BinaryBE);
  }

  void store(const Property& p, double v) {
    switch (p.role) {
      case kX: out_.positions.back().x = v; return;
      case kY: out_.positions.back().y = v; return;
      case kZ: out_.positions.back().z = v; return;
      case kNX: out_.normals.back().x = v; return;
      case kNY: out_.normals.back().y = v; return;
      case kNZ: out_.normals.back().z = v; return;
      case kRed: case kGreen: case kBlue: store_color(p, colors_.size() / 3 - 1, v); return;
      case kAttribute: out_.attributes[p.attribute].values.push_back(float(v)); return;
      default: return;
    }
  }

  /// Vertex i's colour channel from property p (red, green or blue; any other role: nothing).
  void store_color(const Property& p, size_t i, double v) {
    if (p.role != kRed && p.role != kGreen && p.role != kBlue) return;
    const double scale = scalar_size(p.type) == 1 ? 1.0 / 255 : scalar_size(p.type) == 2 ? 1.0 / 65535
                         : is_integer(p.type)   ? 1.0 / 255 : 1.0;
    colors_[3 * i + size_t(p.role - kRed)] = float(v * scale);
  }

  FileReader in_;
  ReadPurpose purpose_;
  Encoding encoding_ = Encoding::None;
  std::vector<Element> elements_;
  const Element* vertex_ = nullptr;
  const Element* face_ = nullptr;
  bool strips_ = false;  // face_ is a "tristrips" element
  bool texcoord_ = false;          // face_ has a "texcoord" list (kTexcoord)
  std::vector<double> face_uv_;    // the record's texcoord values
  std::vector<float> corner_uvs_;  // u v per triangle corner, while every face's list fits
  uint64_t uv_mismatch_ = 0;       // faces whose texcoord list does not fit their corners
  bool has_normals_ = false, has_colors_ = false;
  FileContents out_;
  std::vector<float> colors_;
  std::vector<uint32_t> corners_;
  std::string token_;
};

}  // namespace

FileContents read_ply(const std::string& path, ReadPurpose purpose) { return PlyReader(path, purpose).read(); }

}  // namespace particlemesh::detail
