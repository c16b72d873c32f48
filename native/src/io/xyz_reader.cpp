// Plain-text point files, one point per line: .xyz, .txt, .csv (and the .pts of Leica scanners
// and CloudCompare). Values are separated by spaces, tabs, commas or semicolons; '#' starts a
// comment; blank lines are skipped; every data line has the same number of values. A UTF-8
// byte order mark at the start is skipped (editors on Windows write one); UTF-16 text (a
// byte order mark FF FE or FE FF, or NUL bytes in a line), lines ended by CR alone (classic
// Mac OS) and decimal commas ("0,5;1,25;2", as spreadsheets in many locales write them: the
// comma would split each value in two) are refused by name. Lines are at most 64 KiB: a file
// that never ends a line (/dev/zero, a binary file renamed) is refused after that much, not
// read into memory whole.
//
// What the columns are:
//  - A header line names them, when the first line that is not a comment starts with a word
//    rather than a number ("x y z nx ny nz red green blue", CloudCompare's "//X,Y,Z,R,G,B",
//    PDAL's "\"X\",\"Y\",\"Z\",\"Intensity\"", ParaView's CSV export
//    "\"Velocity:0\",\"Velocity:1\",\"Velocity:2\",\"Points:0\",\"Points:1\",\"Points:2\"").
//    Its names are split at its first comma or semicolon outside quotes (so a name may
//    hold spaces: "Point ID"), or else at spaces and tabs; quotes, and a unit in brackets
//    after a name ("Pos.x [m]"), are dropped. Single columns: x, y, z;
//    nx, ny, nz (or normal_x ... or normalx ...) the normals; r, g, b (or red, green, blue)
//    the colour (values in [0, 1] as they are, up to 255 as 8-bit, above as 16-bit colours).
//    Vectors: columns name:0, name:1, .. or name_0, name_1, .. (ParaView's CSV, our own PLY
//    naming), or name_x name_y name_z (also name.x ..: DualSPHysics' "Pos.x"; name[x] ..
//    and Cd[r] ..: Houdini's table export), one after another, are one vector `name`:
//    Points / Position / Pos / P / Coordinates of 3 the positions (where no x, y, z columns
//    are named), Normals / Normal / N the normals, Color / Colour / RGB / Cd the colour; any
//    other (vx vy vz as "v") a channel of its name and that many components (V, Vel or
//    Velocity of 3 then becomes the channel "velocity", as in every format:
//    name_the_velocity). Every other column is a channel of its name, but for one whose first
//    value is a word (a label, a material: "water"), which is not read and is named in
//    not_read.
//  - Without a header, by their count and values (the conventions of scanners and of
//    CloudCompare's two column orders, "point, colour, scalars, normal" and, in .pts,
//    "point, scalars, colour, normal"):
//      3  x y z
//      4  x y z intensity
//      6  x y z nx ny nz, or x y z r g b where the last three are plainly colours (whole
//         numbers from 0 to 255 with one above 1, or values in [0, 1] that are not unit
//         vectors); otherwise normals, as before colours were told apart
//      7  .xyz: x y z r g b intensity; .pts: x y z intensity r g b (either only where those
//         three are colours)
//      9  x y z r g b nx ny nz or x y z nx ny nz r g b (whichever three are unit vectors,
//         the other three colours)
//     Any other count, or a 7 or 9 whose values fit neither order, keeps x y z and reads
//     every further column as a channel "column_4", "column_5", ... (nothing is guessed and
//     nothing is lost; a header line names them).
//  - .pts: a line holding one whole number (the point count Leica's files start each scan
//    with) is skipped.
// A .xyz whose first 4 KiB are binary rather than text (control characters, not UTF-16) is
// splashsurf's binary .xyz: each particle's x y z as little-endian float32, nothing else.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <initializer_list>
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

constexpr size_t kMaxLine = size_t(1) << 16;
constexpr int kMaxColumns = 64;

bool separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r'; }

/// Whether a line writes decimals with a comma: between spaces, tabs or semicolons it has a
/// word like "-0,0294" (digits, one comma, digits, no '.'), and no word that starts or ends
/// with a comma (in "1, 2,3" commas separate the values). Returns that word, or empty.
std::string_view decimal_comma(std::string_view line) {
  if (line.find(',') == std::string_view::npos) return {};
  auto strong = [](char c) { return c == ' ' || c == '\t' || c == ';' || c == '\r'; };
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  std::string_view found;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && strong(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !strong(line[j])) ++j;
    const std::string_view w = line.substr(i, j - i);
    i = j;
    if (w.empty()) continue;
    if (w.front() == ',' || w.back() == ',') return {};
    const size_t c = w.find(',');
    if (c == std::string_view::npos || !found.empty()) continue;
    if (w.find(',', c + 1) == std::string_view::npos && w.find('.') == std::string_view::npos && c > 0 &&
        digit(w[c - 1]) && c + 1 < w.size() && digit(w[c + 1]))
      found = w;
  }
  return found;
}

/// The words of a line, split at separators.
void split(std::string_view line, std::vector<std::string_view>& words) {
  words.clear();
  size_t i = 0;
  while (true) {
    while (i < line.size() && separator(line[i])) ++i;
    if (i >= line.size()) return;
    size_t j = i;
    while (j < line.size() && !separator(line[j])) ++j;
    words.push_back(line.substr(i, j - i));
    i = j;
  }
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

using Columns = std::array<int, 3>;
constexpr Columns kNoColumns = {-1, -1, -1};
/// Three consecutive columns from `first`.
constexpr Columns from(int first) { return {first, first + 1, first + 2}; }

/// A channel: `components` columns from `column` on.
struct Channel {
  std::string name;
  int column = 0;
  int components = 1;
};

/// What each column of the file is.
struct Layout {
  Columns xyz = from(0);
  Columns normal = kNoColumns;  ///< nx ny nz, or none
  Columns color = kNoColumns;   ///< r g b, or none
  std::vector<Channel> channels;
};

bool one_of(const std::string& lowered, std::initializer_list<const char*> names) {
  return std::any_of(names.begin(), names.end(), [&](const char* n) { return lowered == n; });
}

class XyzReader {
 public:
  explicit XyzReader(const std::string& path)
      : in_(path), pts_(lower_extension(path) == ".pts"), xyz_(lower_extension(path) == ".xyz") {}

  FileContents read() {
    if (in_.peek() < 0) fail_file("the file is empty");
    if (in_.look_ahead(3) == "\xEF\xBB\xBF") in_.skip(3);
    if (const std::string_view bom = in_.look_ahead(2); bom == "\xFF\xFE" || bom == "\xFE\xFF")
      fail_file("the file is UTF-16 text (it starts with the byte order mark " + std::string(bom[0] == '\xFF' ? "FF FE" : "FE FF") +
                "): save it as UTF-8 or ASCII text");
    if (xyz_ && binary(in_.look_ahead(4096))) return read_binary_positions();
    if (const std::string_view start = in_.look_ahead(4096);
        start.find('\n') == std::string_view::npos && start.find('\r') != std::string_view::npos)
      fail_file("its lines end with CR alone (classic Mac OS text): convert the line ends to LF (or CR LF)");
    if (in_.size() > 0) values_.reserve(size_t(std::min<int64_t>(in_.size() / 8, 1 << 22)));
    std::string_view line;
    std::vector<std::string_view> words;
    bool first = true;
    std::vector<std::string> header;
    while (in_.line(line, kMaxLine)) {
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      if (line.find('\0') != std::string_view::npos)
        fail("NUL bytes: UTF-16 text (save it as UTF-8 or ASCII text) or not a text file");
      if (const std::string_view w = decimal_comma(line); !w.empty())
        fail("'" + shown(w) + "' is a number with a decimal comma; write decimals with '.' (a comma separates values)");
      split(line, words);
      if (words.empty()) continue;
      if (first) {
        first = false;
        double v = 0;
        std::string_view w0 = words[0];
        if (w0.substr(0, 2) == "//") w0.remove_prefix(2);
        if (w0.empty() || parse_number(w0, v) == NumberText::NotANumber) {
          header = header_names(line);
          header_text_ = std::string(line.substr(0, 200));
          columns_ = int(header.size());
          continue;
        }
      }
      if (pts_ && words.size() == 1 && columns_ != 1) {
        double v = 0;
        if (parse_number(words[0], v) == NumberText::Ok && v >= 0 && v == std::floor(v)) continue;  // a scan's count
      }
      if (words.size() > size_t(kMaxColumns)) fail("more than " + std::to_string(kMaxColumns) + " values");
      const int count = int(words.size());
      if (columns_ == -1) {
        if (count < 3) fail(std::to_string(count) + " values, expected at least 3 (x y z)");
        columns_ = count;
      }
      if (count != columns_)
        fail(std::to_string(count) + " values where " + (header.empty() ? "earlier lines have " : "the header names ") +
             std::to_string(columns_));
      if (!header.empty() && text_.empty()) {
        // A column the header names whose first value is a word ("water", "rock": a CSV's
        // label or type column) is text: not read, and named, rather than the whole file
        // refused. A column of numbers with a word further down is still an error.
        text_.assign(size_t(columns_), false);
        for (size_t c = 0; c < words.size(); ++c) {
          double v = 0;
          if (parse_number(words[c], v) == NumberText::NotANumber) {
            const std::string n = lower(header[c]);
            if (n == "x" || n == "y" || n == "z")
              fail("the column '" + shown(header[c]) + "' holds '" + shown(words[c]) + "', not a coordinate");
            text_[c] = true;
          }
        }
      }
      for (size_t c = 0; c < words.size(); ++c) {
        const std::string_view t = words[c];
        double v = 0;
        if (!text_.empty() && text_[c]) {  // a text column: its place kept, its words not read
          values_.push_back(0);
          continue;
        }
        // NaN and inf are read here and refused by name with the point's index
        // (validate_point_cloud: "positions[7].x is NaN"); overflowing text is named here.
        switch (parse_number(t, v)) {
          case NumberText::Ok: break;
          case NumberText::NotANumber: fail("not a number: '" + shown(t) + "'");
          case NumberText::Overflow: fail("'" + shown(t) + "' is beyond the range of double (1.8e308)");
        }
        values_.push_back(v);
      }
    }
    if (columns_ <= 0 || values_.empty()) return {};
    FileContents out = contents(header.empty() ? guess() : named(header));
    for (size_t c = 0; c < text_.size(); ++c)
      if (text_[c]) note_not_read(out, "column '" + shown(header[c]) + "' (text)");
    return out;
  }

 private:
  [[noreturn]] void fail_file(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "' line " + std::to_string(in_.line_number()) + ": " + problem);
  }

  /// Whether a file's first bytes are binary rather than text: a control character other than
  /// the white space ones and DOS's end-of-file mark, and not UTF-16 text without a byte order
  /// mark (a zero in every other byte; refused by name as text below).
  static bool binary(std::string_view start) {
    const bool control = std::any_of(start.begin(), start.end(), [](char ch) {
      const auto c = static_cast<unsigned char>(ch);
      return c < 0x20 && c != '\t' && c != '\n' && c != '\v' && c != '\f' && c != '\r' && c != 0x1a;
    });
    if (!control) return false;
    bool even_zero = start.size() >= 2, odd_zero = start.size() >= 2;
    for (size_t i = 0; i < start.size(); ++i) (i % 2 ? odd_zero : even_zero) &= start[i] == '\0';
    return !even_zero && !odd_zero;
  }

  /// splashsurf's binary .xyz (what it reads and writes under that name): nothing but each
  /// particle's x y z as little-endian float32, 12 bytes a particle.
  FileContents read_binary_positions() {
    FileContents out;
    if (in_.size() > 0) out.positions.reserve(size_t(std::min<int64_t>(in_.size() / 12, 1 << 22)));
    unsigned char raw[12];
    double xyz[3];
    while (in_.peek() >= 0) {
      if (!in_.read(raw, sizeof raw))
        fail_file("binary (not text), " + std::to_string(in_.offset()) + " bytes: read as splashsurf's binary " +
                  ".xyz (x y z as little-endian float32, 12 bytes a particle), but that is not a whole number " +
                  "of particles; a text .xyz has one point per line");
      decode_scalars(ScalarType::F32, raw, 3, false, xyz);
      out.positions.push_back({xyz[0], xyz[1], xyz[2]});
    }
    return out;
  }

  size_t rows() const { return values_.size() / size_t(columns_); }
  double at(size_t row, int column) const { return values_[row * size_t(columns_) + size_t(column)]; }

  /// The header's column names: split at the line's first comma or semicolon outside double
  /// quotes (a CSV's names may hold spaces), or else at runs of spaces and tabs; "//" and the
  /// quotes around each name dropped. A CSV's empty name is column_K (K from 1; pandas writes
  /// its index column unnamed, ",x,y,z"), except at the end of the line (a trailing delimiter).
  /// A unit in brackets after a name, "Pos.x [m]", is dropped.
  std::vector<std::string> header_names(std::string_view line) const {
    std::string_view text = line;
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
    if (text.substr(0, 2) == "//") text.remove_prefix(2);
    char delimiter = 0;
    bool quoted = false;
    for (char c : text) {
      if (c == '"') quoted = !quoted;
      else if (!quoted && (c == ',' || c == ';')) {
        delimiter = c;
        break;
      }
    }
    std::vector<std::string> fields(1);
    quoted = false;
    for (char c : text) {
      if (c == '"') quoted = !quoted;
      else if (!quoted && (delimiter ? c == delimiter : (c == ' ' || c == '\t' || c == '\r')))
        fields.emplace_back();
      else
        fields.back().push_back(c);
    }
    auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\''; };
    std::vector<std::string> names;
    for (std::string_view w : fields) {
      while (!w.empty() && blank(w.front())) w.remove_prefix(1);
      while (!w.empty() && blank(w.back())) w.remove_suffix(1);
      // A unit after the name ("Pos.x [m]", "Vel.x (m/s)") is not part of it.
      if (!w.empty() && (w.back() == ']' || w.back() == ')')) {
        const size_t open = w.find_last_of(w.back() == ']' ? '[' : '(');
        if (open != std::string_view::npos && open > 0 && blank(w[open - 1])) {
          std::string_view name = w.substr(0, open);
          while (!name.empty() && blank(name.back())) name.remove_suffix(1);
          if (!name.empty()) w = name;
        }
      }
      if (!w.empty()) names.emplace_back(w);
      else if (delimiter != 0) names.emplace_back();  // named below, or dropped at the end
    }
    while (!names.empty() && names.back().empty()) names.pop_back();
    for (size_t c = 0; c < names.size(); ++c)
      if (names[c].empty()) names[c] = "column_" + std::to_string(c + 1);
    if (names.size() > size_t(kMaxColumns)) fail("the header names more than " + std::to_string(kMaxColumns) + " columns");
    return names;
  }

  /// The layout a header line names; the positions (x, y, z, or a vector of 3 named as
  /// positions) are required.
  Layout named(const std::vector<std::string>& names) const {
    Layout l;
    Columns xyz = kNoColumns, normal = kNoColumns, color = kNoColumns;
    static const char* const kAxis[3] = {"x", "y", "z"};
    static const char* const kColour[3][2] = {{"r", "red"}, {"g", "green"}, {"b", "blue"}};
    const int count = int(names.size());
    // Vectors first: runs of two or more columns base + component 0, 1, ...
    std::vector<Channel> vectors;
    std::vector<bool> in_vector(size_t(count), false);
    auto text = [&](int c) { return !text_.empty() && text_[size_t(c)]; };
    for (int c = 0; c < count;) {
      std::string base, next;
      int run = 0;
      if (!text(c) && vector_component(names[size_t(c)], base) == 0) {
        run = 1;
        while (c + run < count && !text(c + run) && vector_component(names[size_t(c + run)], next) == run && next == base)
          ++run;
      }
      if (run < 2) {
        ++c;
        continue;
      }
      vectors.push_back({base, c, run});
      for (int k = 0; k < run; ++k) in_vector[size_t(c + k)] = true;
      c += run;
    }
    // Single columns.
    for (int c = 0; c < count; ++c) {
      if (in_vector[size_t(c)] || text(c)) continue;
      const std::string n = lower(names[size_t(c)]);
      bool taken = false;
      for (int k = 0; k < 3 && !taken; ++k) {
        const std::string a = kAxis[k];
        int* slot = nullptr;
        if (n == a) slot = &xyz[k];
        else if (n == "n" + a || n == "normal_" + a || n == "normal" + a) slot = &normal[k];
        else if (n == kColour[k][0] || n == kColour[k][1]) slot = &color[k];
        if (slot && *slot < 0) *slot = c, taken = true;
      }
      if (!taken) l.channels.push_back({names[size_t(c)], c, 1});
    }
    // Normals and colours need all three of their columns; a partial set stays channels.
    auto complete = [](const Columns& t) { return t[0] >= 0 && t[1] >= 0 && t[2] >= 0; };
    auto partial_to_channels = [&](Columns& t) {
      if (complete(t)) return;
      for (int c : t)
        if (c >= 0) l.channels.push_back({names[size_t(c)], c, 1});
      t = kNoColumns;
    };
    partial_to_channels(normal);
    partial_to_channels(color);
    Columns positions = kNoColumns;  // a vector named as the positions
    for (Channel& v : vectors) {
      const std::string b = lower(v.name);
      Columns* role = nullptr;
      if (v.components == 3) {
        if (one_of(b, {"points", "point", "position", "positions", "pos", "p", "coordinates", "coords"}))
          role = &positions;
        else if (one_of(b, {"normals", "normal", "n"})) role = &normal;
        else if (one_of(b, {"color", "colour", "colors", "colours", "rgb", "cd"})) role = &color;
      }
      if (role == &positions && complete(xyz)) role = nullptr;  // x y z columns are named
      if (role && !complete(*role)) *role = from(v.column);
      else l.channels.push_back(std::move(v));
    }
    if (!complete(xyz) && complete(positions)) {
      partial_to_channels(xyz);
      xyz = positions;
    }
    for (int k = 0; k < 3; ++k)
      if (xyz[k] < 0)
        fail_file("its first line ('" + shown(header_text_) + "') starts with a word, so it is read as a header line " +
                  "naming the columns, but it names no '" + kAxis[k] + "' column (nor the positions as a vector, " +
                  "Points:0 Points:1 Points:2)");
    l.xyz = xyz;
    l.normal = normal;
    l.color = color;
    std::sort(l.channels.begin(), l.channels.end(), [](const Channel& a, const Channel& b) { return a.column < b.column; });
    return l;
  }

  /// Whether columns c..c+2 hold unit vectors (or zero vectors: points without a normal).
  bool unit(int c) const {
    for (size_t r = 0; r < rows(); ++r) {
      const double x = at(r, c), y = at(r, c + 1), z = at(r, c + 2);
      const double n2 = x * x + y * y + z * z;
      if (n2 != 0 && !(n2 > 0.81 && n2 < 1.21)) return false;
    }
    return true;
  }

  /// Whether columns c..c+2 are plainly colours: whole numbers from 0 to 255, one of them
  /// above 1; or values in [0, 1] that are not all unit vectors.
  bool colour(int c) const {
    bool whole = true, unit_range = true, above_one = false;
    for (size_t r = 0; r < rows(); ++r)
      for (int k = 0; k < 3; ++k) {
        const double v = at(r, c + k);
        if (!(v >= 0 && v <= 255)) return false;
        whole = whole && v == std::floor(v);
        unit_range = unit_range && v <= 1;
        above_one = above_one || v > 1;
      }
    return (whole && above_one) || (unit_range && !unit(c));
  }

  Layout guess() {
    Layout l;
    auto rest = [&](int from) {
      for (int c = from; c < columns_; ++c) l.channels.push_back({"column_" + std::to_string(c + 1), c, 1});
    };
    switch (columns_) {
      case 3: return l;
      case 4: l.channels.push_back({"intensity", 3, 1}); return l;
      case 6:
        if (colour(3)) l.color = from(3);
        else l.normal = from(3);
        return l;
      case 7:
        if (!pts_ && colour(3)) {
          l.color = from(3);
          l.channels.push_back({"intensity", 6, 1});
          return l;
        }
        if (pts_ && colour(4)) {
          l.channels.push_back({"intensity", 3, 1});
          l.color = from(4);
          return l;
        }
        break;
      case 9:
        if (colour(3) && unit(6)) {
          l.color = from(3), l.normal = from(6);
          return l;
        }
        if (unit(3) && colour(6)) {
          l.normal = from(3), l.color = from(6);
          return l;
        }
        break;
      default: break;
    }
    rest(3);
    return l;
  }

  FileContents contents(const Layout& l) const {
    const size_t n = rows();
    auto vec = [&](size_t r, const Columns& c) { return Vec3{at(r, c[0]), at(r, c[1]), at(r, c[2])}; };
    FileContents out;
    out.positions.resize(n);
    for (size_t r = 0; r < n; ++r) out.positions[r] = vec(r, l.xyz);
    if (l.normal != kNoColumns) {
      out.normals.resize(n);
      for (size_t r = 0; r < n; ++r) out.normals[r] = vec(r, l.normal);
    }
    if (l.color != kNoColumns) {
      // [0, 1] as is, up to 255 as 8-bit, up to 65535 as 16-bit colours (as in LAS).
      double top = 0;
      for (size_t r = 0; r < n; ++r)
        for (int c : l.color) top = std::max(top, at(r, c));
      const double scale = top <= 1 ? 1.0 : top <= 255 ? 1.0 / 255.0 : 1.0 / 65535.0;
      VertexAttribute color{"color", 3, {}};
      color.values.resize(3 * n);
      for (size_t r = 0; r < n; ++r)
        for (int k = 0; k < 3; ++k)
          color.values[3 * r + size_t(k)] = float(std::clamp(at(r, l.color[size_t(k)]) * scale, 0.0, 1.0));
      out.attributes.push_back(std::move(color));
    }
    for (const Channel& ch : l.channels) {
      VertexAttribute a{unique_attribute_name(out, ch.name), ch.components, {}};
      const auto k = size_t(ch.components);
      a.values.resize(k * n);
      for (size_t r = 0; r < n; ++r)
        for (size_t j = 0; j < k; ++j) a.values[k * r + j] = float(at(r, ch.column + int(j)));
      out.attributes.push_back(std::move(a));
    }
    return out;
  }

  FileReader in_;
  bool pts_;
  bool xyz_;  ///< may be splashsurf's binary .xyz
  std::string header_text_;
  int columns_ = -1;
  std::vector<double> values_;  ///< rows x columns_
  std::vector<bool> text_;      ///< per column a header names: text (not read), told by the first data line
};

}  // namespace

FileContents read_xyz(const std::string& path, ReadPurpose) { return XyzReader(path).read(); }

}  // namespace particlemesh::detail
