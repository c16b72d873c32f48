// VTK's legacy format, .vtk (ASCII and BINARY, which is big-endian): POLYDATA and
// UNSTRUCTURED_GRID data sets, as SPlisHSPlasH, DualSPHysics, PySPH and ParaView write them.
//
// Written by hand rather than through VTK's vtkDataReader (libvtk9, which PCL pulls in):
//  - a truncated or inconsistent file must be refused with the file, the section and the
//    problem named. VTK's legacy readers print a warning on stderr and return what they
//    got: a BINARY frame cut short came back as its 4732 points with garbage and no arrays,
//    and a CELLS count raised to 94 million allocated for a minute before giving up
//    (measured on the shared SPH frames with Debian's VTK 9.1);
//  - the core library is loaded into Blender and packed with its libraries into the
//    add-on's zip: VTK's IO modules bring 24 libraries (27 MB), for a format of a few
//    keywords.
// Its readers serve as the reference in the tests instead (tests/cli/test_simulation_files.py
// compares every array with VTK's reading of the same file).
//
// What is read: POINTS (any numeric type, exactly), POINT_DATA's SCALARS, VECTORS, NORMALS
// (the first one: the normals), TEXTURE_COORDINATES, TENSORS, COLOR_SCALARS and FIELD arrays
// (any numeric type, bit arrays as 0 / 1; one attribute each, named as in the file with %XX
// escapes decoded; COLOR_SCALARS as VTK's reader gives them: unsigned chars 0..255, which is
// how VTK writes any unsigned-char array set as the active scalars, a material or type id as
// much as a colour), string arrays walked and skipped (they are no per-particle number; named
// in not_read), and
// for meshes POLYGONS and TRIANGLE_STRIPS (POLYDATA) or triangle, polygon and quad CELLS
// (UNSTRUCTURED_GRID), fanned. Cells in both layouts (the classic counts-and-ids list and
// version 5.1's OFFSETS / CONNECTIVITY), CELL_DATA, lookup tables, METADATA and field data
// outside POINT_DATA are walked and skipped. Every count is checked against the data.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/scalar_types.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

using Type = ScalarType;

Type type_of(const std::string& word) {
  std::string t;
  for (char c : word) t.push_back(char(std::tolower(static_cast<unsigned char>(c))));
  if (t == "unsigned_char") return Type::U8;
  if (t == "char") return Type::I8;
  if (t == "unsigned_short") return Type::U16;
  if (t == "short") return Type::I16;
  if (t == "unsigned_int") return Type::U32;
  if (t == "int" || t == "vtkidtype") return Type::I32;  // legacy files store vtkIdType as int
  if (t == "unsigned_long" || t == "vtktypeuint64") return Type::U64;
  if (t == "long" || t == "vtktypeint64") return Type::I64;
  if (t == "float") return Type::F32;
  if (t == "double") return Type::F64;
  if (t == "bit") return Type::Bit;
  if (t == "string" || t == "utf8_string") return Type::String;
  return Type::None;
}

std::string upper(std::string s) {
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// VTK writes special characters of array names as %XX.
std::string decode_name(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out.push_back(char(std::stoi(s.substr(i + 1, 2), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

void set_axis(Vec3& p, int axis, double v) { (axis == 0 ? p.x : axis == 1 ? p.y : p.z) = v; }

class VtkLegacyReader {
 public:
  VtkLegacyReader(const std::string& path, ReadPurpose purpose) : in_(path), purpose_(purpose) {}

  FileContents read() {
    constexpr size_t kMaxLine = 1 << 16;
    std::string_view line;
    if (!in_.line(line, kMaxLine)) fail("the file is empty");
    if (line.size() >= 5 && line.substr(0, 5) == "<?xml")
      fail("this is a VTK XML file, not a legacy .vtk file (name it .vtu or .vtp)");
    if (line.substr(0, 6) != "# vtk " || !equals_ignoring_case(std::string(line.substr(6, 8)), "datafile"))
      fail("not a legacy VTK file (the first line is not '# vtk DataFile Version ...')");
    if (!in_.line(line, kMaxLine)) fail("truncated: no title line");
    // Blank lines before it are skipped, as vtkDataReader does (some of VTK's own sample
    // files have one).
    do {
      if (!in_.line(line, kMaxLine)) fail("truncated: no ASCII / BINARY line");
    } while (trim(line).empty());
    const std::string mode = upper(std::string(trim(line)));
    if (mode == "BINARY") binary_ = true;
    else if (mode != "ASCII") fail("the line after the title is '" + shown(line) + "', not ASCII or BINARY");

    std::string kw;
    if (!word(kw)) fail("no DATASET");
    while (upper(kw) == "FIELD") {  // field data of the data set before it: skipped
      read_field(false);
      if (!word(kw)) fail("no DATASET");
    }
    if (upper(kw) != "DATASET") fail("'" + shown(kw) + "' where DATASET was expected");
    std::string type;
    if (!word(type)) fail("truncated after DATASET");
    type = upper(type);
    // A structured grid lists its points too (their cells are implied by DIMENSIONS: read as
    // particles); structured points and rectilinear grids give only the axes of a lattice.
    if (type != "POLYDATA" && type != "UNSTRUCTURED_GRID" && type != "STRUCTURED_GRID")
      fail("DATASET " + shown(type) + " lists no points (read: POLYDATA, UNSTRUCTURED_GRID, STRUCTURED_GRID)");
    polydata_ = type == "POLYDATA";
    const bool structured = type == "STRUCTURED_GRID";

    bool have_points = false;
    while (word(kw)) {
      const std::string k = upper(kw);
      if (k == "POINTS") {
        if (have_points) fail("a second POINTS section");
        have_points = true;
        read_points();
      } else if (k == "DIMENSIONS" && structured) {
        std::string t;
        uint64_t d = 0;
        for (int a = 0; a < 3; ++a)
          if (!word(t) || !parse_count(t, d)) fail("DIMENSIONS needs three counts");
      } else if ((k == "VERTICES" || k == "LINES" || k == "POLYGONS" || k == "TRIANGLE_STRIPS" || k == "CELLS") &&
                 !structured) {
        if ((k == "CELLS") == polydata_) fail(k + " in a " + type + " data set");
        read_cells(k);
      } else if (k == "CELL_TYPES" && !structured) {
        read_cell_types();
      } else if (k == "POINT_DATA" || k == "CELL_DATA") {
        uint64_t n = 0;
        std::string t;
        if (!word(t) || !parse_count(t, n)) fail(k + " needs a count");
        section_ = k == "POINT_DATA" ? Section::Points : Section::Cells;
        count_ = n;
        if (section_ == Section::Points) {
          if (!have_points) fail("POINT_DATA before POINTS");
          if (n != out_.positions.size())
            fail("POINT_DATA " + std::to_string(n) + " for " + std::to_string(out_.positions.size()) + " points");
        }
      } else if (k == "FIELD") {
        read_field(section_ == Section::Points);
      } else if (k == "SCALARS" || k == "VECTORS" || k == "NORMALS" || k == "TEXTURE_COORDINATES" || k == "TENSORS" ||
                 k == "TENSORS6" || k == "COLOR_SCALARS" || k == "GLOBAL_IDS" || k == "PEDIGREE_IDS") {
        if (section_ == Section::None) fail(k + " outside POINT_DATA and CELL_DATA");
        read_attribute(k);
      } else if (k == "LOOKUP_TABLE") {
        read_lookup_table();
      } else if (k == "METADATA") {
        skip_metadata();
      } else {
        fail("unknown keyword '" + shown(kw) + "' at byte " + std::to_string(in_.offset()));
      }
    }
    if (!have_points) fail("no POINTS section");
    make_triangles();
    return std::move(out_);
  }

 private:
  enum class Section { None, Points, Cells };

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }

  static std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    return s;
  }

  /// The next word of a header line; ended_ says whether it ended its line.
  bool word(std::string& out) { return in_.token(out, 4096, &ended_); }
  /// Past the end of the current header line (where BINARY data starts).
  void end_line() {
    if (!ended_) in_.skip_line();
    ended_ = true;
  }

  uint64_t bytes_left() const {
    return in_.size() < 0 ? UINT64_MAX : uint64_t(in_.size()) - std::min<uint64_t>(in_.offset(), uint64_t(in_.size()));
  }

  /// Takes values first, first + 1, ... first + k - 1 of an array, decoded, at v.
  using ValueSink = std::function<void(uint64_t first, const double* v, size_t k)>;

  /// A ValueSink calling f(index, value) for each value: one call through std::function per
  /// run of values, the per-value work inlined.
  template <class F>
  static ValueSink each(F f) {
    return [f](uint64_t first, const double* v, size_t k) mutable {
      for (size_t j = 0; j < k; ++j) f(first + j, v[j]);
    };
  }

  /// Read `count` values of `type`, handing them to sink in order (a run of binary values
  /// decoded at once, text values one by one); an empty sink skips them. Nothing is
  /// allocated here; the sink's vectors grow with what is really read.
  void values(Type type, uint64_t count, const std::string& what, const ValueSink& sink) {
    if (type == Type::None) fail(what + ": unknown data type");
    if (type == Type::String) {
      if (sink) fail(what + ": a string array is not a channel of numbers");
      skip_strings(count, what);
      return;
    }
    if (type == Type::Bit && binary_) {
      bits(count, what, sink);
      return;
    }
    if (binary_) {
      end_line();
      const int size = scalar_size(type);
      if (saturating_mul(count, uint64_t(size)) > bytes_left())
        fail("truncated: " + what + " needs " + std::to_string(count) + " values of " + std::to_string(size) +
             " bytes, the file has " + std::to_string(bytes_left()) + " bytes left");
      unsigned char buf[16384];
      const uint64_t per = sizeof buf / uint64_t(size);
      if (sink) decoded_.resize(size_t(per));
      for (uint64_t i = 0; i < count;) {
        const uint64_t k = std::min(per, count - i);
        if (!in_.read(buf, size_t(k) * size_t(size)))
          fail("truncated: the file ends in " + what + " (value " + std::to_string(i) + " of " + std::to_string(count) + ")");
        if (sink) {
          decode_scalars(type, buf, size_t(k), true, decoded_.data());
          sink(i, decoded_.data(), size_t(k));
        }
        i += k;
      }
      return;
    }
    if (saturating_mul(count, 2) > bytes_left() + 1)
      fail("truncated: " + what + " needs " + std::to_string(count) + " values, more than the " +
           std::to_string(bytes_left()) + " bytes left can hold");
    std::string t;
    for (uint64_t i = 0; i < count; ++i) {
      if (!in_.token(t, 512))
        fail("truncated: the file ends in " + what + " (value " + std::to_string(i) + " of " + std::to_string(count) + ")");
      double v = 0;
      const NumberText r = parse_number(t, v);
      if (r == NumberText::NotANumber) fail(what + ", value " + std::to_string(i) + ": not a number: '" + shown(t) + "'");
      if (r == NumberText::Overflow) fail(what + ", value " + std::to_string(i) + ": '" + shown(t) + "' is beyond the range of double");
      if (sink) sink(i, &v, 1);
    }
    ended_ = false;
  }

  /// A binary bit array (decode_bits), a run of bytes at a time, handed on as 0 / 1.
  void bits(uint64_t count, const std::string& what, const ValueSink& sink) {
    end_line();
    const uint64_t bytes = bit_bytes(count);
    if (bytes > bytes_left())
      fail("truncated: " + what + " needs " + std::to_string(bytes) + " bytes of bits, the file has " +
           std::to_string(bytes_left()) + " bytes left");
    unsigned char buf[2048];
    if (sink) decoded_.resize(8 * sizeof buf);
    for (uint64_t i = 0; i < bytes;) {
      const size_t k = size_t(std::min<uint64_t>(sizeof buf, bytes - i));
      if (!in_.read(buf, k)) fail("truncated: the file ends in " + what);
      if (sink) {
        const uint64_t first = 8 * i, n = std::min<uint64_t>(8 * uint64_t(k), count - first);
        decode_bits(buf, size_t(n), decoded_.data());
        sink(first, decoded_.data(), size_t(n));
      }
      i += k;
    }
  }

  /// A string array, skipped: ASCII holds one value per line (%XX-escaped, so an empty value
  /// is an empty line); BINARY a big-endian length before each value, its top two bits
  /// saying its size (11: 1 byte, 10: 2, 01: 4, 00: 8; vtkDataWriter's layout).
  void skip_strings(uint64_t count, const std::string& what) {
    end_line();
    auto truncated = [&](uint64_t i) {
      fail("truncated: the file ends in " + what + " (string " + std::to_string(i) + " of " + std::to_string(count) + ")");
    };
    if (!binary_) {
      std::string_view line;
      for (uint64_t i = 0; i < count; ++i)
        if (!in_.line(line, 1 << 20)) truncated(i);
      return;
    }
    for (uint64_t i = 0; i < count; ++i) {
      unsigned char b[8];
      if (!in_.read(b, 1)) truncated(i);
      const int size = b[0] >> 6 == 3 ? 1 : b[0] >> 6 == 2 ? 2 : b[0] >> 6 == 1 ? 4 : 8;
      if (size > 1 && !in_.read(b + 1, size_t(size - 1))) truncated(i);
      uint64_t length = b[0] & (size == 8 ? 0xff : 0x3f);
      for (int j = 1; j < size; ++j) length = length << 8 | b[j];
      if (length > bytes_left()) truncated(i);
      if (!in_.skip(length)) truncated(i);
    }
  }

  Type data_type(const std::string& what) {
    std::string t;
    if (!word(t)) fail("truncated: " + what + " has no data type");
    const Type type = type_of(t);
    if (type == Type::None) fail(what + ": unknown data type '" + shown(t) + "'");
    return type;
  }

  void read_points() {
    std::string t;
    uint64_t n = 0;
    if (!word(t) || !parse_count(t, n)) fail("POINTS needs a count");
    const Type type = data_type("POINTS");
    out_.positions.reserve(size_t(std::min<uint64_t>(n, bytes_left() / (binary_ ? 3 * uint64_t(std::max(1, scalar_size(type))) : 6))));
    values(type, saturating_mul(n, 3), "POINTS", each([&](uint64_t i, double v) {
      if (i % 3 == 0) out_.positions.emplace_back();
      set_axis(out_.positions.back(), int(i % 3), v);
    }));
  }

  /// A cell list: the classic "n size" + size ids (each cell: count, ids), or version 5.1's
  /// "offsets connectivity" + OFFSETS and CONNECTIVITY arrays.
  void read_cells(const std::string& k) {
    std::string t;
    uint64_t a = 0, b = 0;
    if (!word(t) || !parse_count(t, a) || !word(t) || !parse_count(t, b)) fail(k + " needs two counts");
    const bool wanted = purpose_ == ReadPurpose::Mesh && (k == "POLYGONS" || k == "TRIANGLE_STRIPS" || k == "CELLS");
    Cells cells;
    cells.kind = k;
    // Binary data starts on the next line; text values may follow the counts on their own
    // line (VTK's sample data writes "LINES 1 348 347"): vtkDataReader reads them as words.
    if (binary_) end_line();
    // Version 5.1: OFFSETS follows (binary data would start right here).
    std::string_view ahead = in_.look_ahead(16);
    if (!binary_)
      while (!ahead.empty() && std::isspace(static_cast<unsigned char>(ahead[0]))) {
        in_.get();
        ahead = in_.look_ahead(16);
      }
    if (ahead.size() >= 7 && upper(std::string(ahead.substr(0, 7))) == "OFFSETS") {
      word(t);
      const Type ot = data_type(k + " OFFSETS");
      values(ot, a, k + " OFFSETS", each([&](uint64_t, double v) {
        if (wanted) cells.offsets.push_back(v);
      }));
      if (!word(t) || upper(t) != "CONNECTIVITY") fail(k + ": CONNECTIVITY expected after OFFSETS");
      const Type ct = data_type(k + " CONNECTIVITY");
      values(ct, b, k + " CONNECTIVITY", each([&](uint64_t, double v) {
        if (wanted) cells.ids.push_back(v);
      }));
      if (wanted) {
        if (a == 0 ? b != 0 : (cells.offsets.front() != 0 || cells.offsets.back() != double(b)))
          fail(k + ": the offsets do not span the " + std::to_string(b) + " connectivity entries");
        for (size_t i = 1; i < cells.offsets.size(); ++i)
          if (cells.offsets[i] < cells.offsets[i - 1]) fail(k + ": offset " + std::to_string(i) + " decreases");
        cells.count = a == 0 ? 0 : a - 1;
      }
    } else {
      // Classic: `a` cells in `b` integers, each cell its size then its ids.
      ended_ = true;
      uint64_t next = 0, cell = 0;
      values(Type::I32, b, k, each([&](uint64_t i, double v) {
        if (i == next) {
          if (!(v >= 0 && v <= double(b))) fail(k + ": cell " + std::to_string(cell) + " has " + format_number(v) + " points");
          next = i + 1 + uint64_t(v);
          ++cell;
          if (wanted) cells.offsets.push_back(double(cells.ids.size()));
        } else if (wanted) {
          cells.ids.push_back(v);
        }
      }));
      if (next != b || cell != a)
        fail(k + " declares " + std::to_string(a) + " cells in " + std::to_string(b) + " integers, but they hold " +
             std::to_string(cell) + " cells" + (next != b ? " and a cut-off one" : ""));
      if (wanted) {
        cells.offsets.push_back(double(cells.ids.size()));
        cells.count = a;
      }
    }
    if (wanted) cells_.push_back(std::move(cells));
  }

  void read_cell_types() {
    std::string t;
    uint64_t n = 0;
    if (!word(t) || !parse_count(t, n)) fail("CELL_TYPES needs a count");
    const bool wanted = purpose_ == ReadPurpose::Mesh;
    values(Type::I32, n, "CELL_TYPES", each([&](uint64_t, double v) {
      if (wanted) cell_types_.push_back(int(v));
    }));
  }

  void read_attribute(const std::string& k) {
    std::string name, t;
    if (!word(name)) fail("truncated: " + k + " has no name");
    name = decode_name(name);
    const std::string what = k + " '" + shown(name) + "'";
    int components = 1;
    Type type = Type::None;
    bool ascii_colours = false;  // COLOR_SCALARS as text: 0..1, stored as round(255 v)
    if (k == "COLOR_SCALARS") {
      uint64_t c = 0;
      if (!word(t) || !parse_count(t, c) || c < 1 || c > 65535) fail(what + " needs a component count");
      components = int(c);
      type = binary_ ? Type::U8 : Type::F32;
      ascii_colours = !binary_;
    } else if (k == "TEXTURE_COORDINATES") {
      uint64_t c = 0;
      if (!word(t) || !parse_count(t, c) || c < 1 || c > 3) fail(what + " needs a dimension 1, 2 or 3");
      components = int(c);
      type = data_type(what);
    } else {
      type = data_type(what);
      components = k == "VECTORS" || k == "NORMALS" ? 3 : k == "TENSORS" ? 9 : k == "TENSORS6" ? 6 : 1;
      if (k == "SCALARS") {
        if (!ended_) {
          uint64_t c = 0;
          if (!word(t) || !parse_count(t, c) || c < 1 || c > 65535) fail(what + ": bad component count '" + shown(t) + "'");
          components = int(c);
        }
        // "LOOKUP_TABLE name" follows (optional for some writers).
        std::string_view ahead = in_.look_ahead(64);
        size_t skip = 0;
        while (skip < ahead.size() && std::isspace(static_cast<unsigned char>(ahead[skip]))) ++skip;
        if (ahead.size() >= skip + 12 && upper(std::string(ahead.substr(skip, 12))) == "LOOKUP_TABLE") {
          word(t);
          if (!word(t)) fail(what + ": LOOKUP_TABLE needs a name");
        }
      }
    }
    const uint64_t n = count_;
    const bool keep = section_ == Section::Points && type != Type::String;
    if (section_ == Section::Points && type == Type::String) note_not_read(out_, "POINT_DATA " + what + " (strings)");
    if (section_ == Section::Cells && purpose_ == ReadPurpose::Mesh) note_not_read(out_, "CELL_DATA " + what);
    if (!keep) {
      values(type, saturating_mul(n, uint64_t(components)), what, {});
      return;
    }
    const bool as_normals = k == "NORMALS" && out_.normals.empty() && !normals_read_;
    if (as_normals) {
      normals_read_ = true;
      out_.normals.reserve(size_t(std::min<uint64_t>(n, out_.positions.size())));
      values(type, saturating_mul(n, 3), what, each([&](uint64_t i, double v) {
        if (i % 3 == 0) out_.normals.emplace_back();
        set_axis(out_.normals.back(), int(i % 3), v);
      }));
      return;
    }
    VertexAttribute a{unique_attribute_name(out_, name), components, {}};
    a.values.reserve(size_t(std::min<uint64_t>(saturating_mul(n, uint64_t(components)), saturating_mul(out_.positions.size(), uint64_t(components)))));
    values(type, saturating_mul(n, uint64_t(components)), what, each([&](uint64_t, double v) {
      // vtkDataReader's conversion of text colours to unsigned chars.
      a.values.push_back(ascii_colours ? float(std::floor(std::clamp(255.0 * v + 0.5, 0.0, 255.0))) : float(v));
    }));
    out_.attributes.push_back(std::move(a));
  }

  void read_lookup_table() {
    std::string name, t;
    uint64_t n = 0;
    if (!word(name) || !word(t) || !parse_count(t, n)) fail("LOOKUP_TABLE needs a name and a size");
    values(binary_ ? Type::U8 : Type::F32, saturating_mul(n, 4), "LOOKUP_TABLE '" + shown(name) + "'", {});
  }

  /// FIELD name count, then per array: name components tuples type, data (or NULL_ARRAY).
  void read_field(bool keep) {
    std::string name, t;
    uint64_t arrays = 0;
    if (!word(name) || !word(t) || !parse_count(t, arrays)) fail("FIELD needs a name and an array count");
    for (uint64_t i = 0; i < arrays; ++i) {
      std::string array;
      if (!word(array)) fail("truncated: FIELD '" + shown(name) + "' declares " + std::to_string(arrays) + " arrays, the file ends after " + std::to_string(i));
      if (upper(array) == "METADATA") {
        skip_metadata();
        --i;
        continue;
      }
      if (upper(array) == "NULL_ARRAY") continue;
      array = decode_name(array);
      uint64_t components = 0, tuples = 0;
      const std::string what = "FIELD array '" + shown(array) + "'";
      if (!word(t) || !parse_count(t, components) || !word(t) || !parse_count(t, tuples))
        fail(what + " needs: components tuples type");
      const Type type = data_type(what);
      const bool take = keep && section_ == Section::Points && type != Type::String;
      if (keep && section_ == Section::Points && type == Type::String)
        note_not_read(out_, "POINT_DATA " + what + " (strings)");
      if (section_ == Section::Cells && purpose_ == ReadPurpose::Mesh) note_not_read(out_, "CELL_DATA " + what);
      if (take && tuples != out_.positions.size())
        fail(what + " has " + std::to_string(tuples) + " tuples for " + std::to_string(out_.positions.size()) + " points");
      if (take && (components < 1 || components > 65535)) fail(what + " has " + std::to_string(components) + " components");
      if (!take) {
        values(type, saturating_mul(components, tuples), what, {});
        continue;
      }
      VertexAttribute a{unique_attribute_name(out_, array), int(components), {}};
      a.values.reserve(size_t(saturating_mul(components, tuples)));
      values(type, saturating_mul(components, tuples), what, each([&](uint64_t, double v) { a.values.push_back(float(v)); }));
      out_.attributes.push_back(std::move(a));
    }
  }

  /// METADATA blocks (VTK 8.1+): lines up to an empty one.
  void skip_metadata() {
    end_line();
    std::string_view line;
    while (in_.line(line, 1 << 16))
      if (trim(line).empty()) return;
  }

  struct Cells {
    std::string kind;
    uint64_t count = 0;
    std::vector<double> offsets;  ///< count + 1
    std::vector<double> ids;
  };

  void make_triangles() {
    if (purpose_ != ReadPurpose::Mesh) return;
    const double n = double(out_.positions.size());
    auto corner = [&](double v, const std::string& kind, uint64_t c) -> uint32_t {
      if (!(v >= 0 && v < n))
        fail(kind + " cell " + std::to_string(c) + " refers to point " + format_number(v) + " (the file has " +
             format_number(n) + " points)");
      return uint32_t(v);
    };
    for (const Cells& cells : cells_) {
      const bool strips = cells.kind == "TRIANGLE_STRIPS";
      const bool grid = cells.kind == "CELLS";
      if (grid && cell_types_.size() != cells.count)
        fail("CELL_TYPES lists " + std::to_string(cell_types_.size()) + " types for " + std::to_string(cells.count) + " cells");
      for (uint64_t c = 0; c < cells.count; ++c) {
        const size_t b = size_t(cells.offsets[c]), e = size_t(cells.offsets[c + 1]);
        if (grid) {
          const int ct = cell_types_[c];
          if (ct != 5 && ct != 7 && ct != 9) continue;  // triangle, polygon, quad
        }
        ++out_.faces;
        if (e - b < 3) continue;
        if (strips) {
          for (size_t i = b; i + 2 < e; ++i) {
            const uint32_t p = corner(cells.ids[i], cells.kind, c), q = corner(cells.ids[i + 1], cells.kind, c),
                           r = corner(cells.ids[i + 2], cells.kind, c);
            if ((i - b) % 2 == 0) out_.triangles.push_back({p, q, r});
            else out_.triangles.push_back({q, p, r});
          }
        } else {
          const uint32_t first = corner(cells.ids[b], cells.kind, c);
          for (size_t i = b + 1; i + 1 < e; ++i)
            out_.triangles.push_back({first, corner(cells.ids[i], cells.kind, c), corner(cells.ids[i + 1], cells.kind, c)});
        }
      }
    }
  }

  static std::string format_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
  }

  FileReader in_;
  ReadPurpose purpose_;
  FileContents out_;
  bool binary_ = false;
  bool polydata_ = false;
  bool ended_ = true;
  std::vector<double> decoded_;  // a run of binary values, decoded (values())
  bool normals_read_ = false;
  Section section_ = Section::None;
  uint64_t count_ = 0;
  std::vector<Cells> cells_;
  std::vector<int> cell_types_;
};

}  // namespace

FileContents read_vtk_legacy(const std::string& path, ReadPurpose purpose) {
  return VtkLegacyReader(path, purpose).read();
}

}  // namespace particlemesh::detail
