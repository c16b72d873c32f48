#include "io/header_check.h"

#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "particlemesh/core/error.h"

namespace particlemesh::detail {

namespace {

// Hand-written rather than taken from a PLY library: the point is to check a file before the
// reader we use (OpenMesh's) trusts it, with the same reading of the header.

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw Error(Status::FormatError, "'" + path + "': " + problem);
}

constexpr size_t kMaxHeader = 1 << 20;

/// Sequential reader over a file: whitespace-separated tokens and raw bytes.
class Reader {
 public:
  Reader(const std::string& path, uint64_t offset) : in_(path, std::ios::binary), buf_(1 << 16) {
    if (!in_) throw Error(Status::IoError, "'" + path + "': cannot open for reading");
    in_.seekg(std::streamoff(offset));
  }

  /// The next token, or false at the end of the file. Tokens longer than 64 bytes are
  /// truncated (only their first bytes matter here).
  bool token(std::string& out) {
    out.clear();
    int c;
    do {
      c = get();
      if (c < 0) return false;
    } while (std::isspace(c));
    while (c >= 0 && !std::isspace(c)) {
      if (out.size() < 64) out.push_back(char(c));
      c = get();
    }
    line_start_ = c == '\n';
    return true;
  }

  /// Whether the last token() ended its line (it consumed the newline after it).
  bool at_line_start() const { return line_start_; }

  /// Skip the rest of the current line.
  void skip_line() {
    int c;
    do c = get();
    while (c >= 0 && c != '\n');
  }

  /// Skip `n` whitespace-separated tokens; returns how many were there.
  uint64_t skip_tokens(uint64_t n) {
    uint64_t k = 0;
    bool in_token = false;
    while (k < n) {
      const int c = get();
      if (c < 0) return k + (in_token ? 1 : 0);
      const bool space = std::isspace(c);
      if (in_token && space) ++k;
      in_token = !space;
    }
    return k;
  }

  /// Read `n` raw bytes into `out` (false if the file ends first).
  bool bytes(void* out, size_t n) {
    auto* o = static_cast<unsigned char*>(out);
    while (n > 0) {
      if (pos_ == end_ && get() >= 0) --pos_;  // refill, and put the byte back
      if (pos_ == end_) return false;
      const size_t k = std::min(n, end_ - pos_);
      std::memcpy(o, buf_.data() + pos_, k);
      pos_ += k;
      o += k;
      n -= k;
    }
    return true;
  }

  /// Skip `n` raw bytes (false if the file ends first).
  bool skip_bytes(uint64_t n) {
    const uint64_t buffered = uint64_t(end_ - pos_);
    if (n <= buffered) {
      pos_ += n;
      return true;
    }
    n -= buffered;
    pos_ = end_ = 0;
    const std::streamoff here = in_.tellg();
    in_.seekg(0, std::ios::end);
    const std::streamoff size = in_.tellg();
    if (here < 0 || size < 0 || uint64_t(size - here) < n) return false;
    in_.seekg(here + std::streamoff(n));
    return true;
  }

 private:
  int get() {
    if (pos_ == end_) {
      in_.read(buf_.data(), std::streamsize(buf_.size()));
      end_ = size_t(in_.gcount());
      pos_ = 0;
      if (end_ == 0) return -1;
    }
    return static_cast<unsigned char>(buf_[pos_++]);
  }

  std::ifstream in_;
  std::vector<char> buf_;
  size_t pos_ = 0, end_ = 0;
  bool line_start_ = false;
};

std::string read_prefix(const std::string& path, size_t limit, uint64_t* file_size) {
  std::error_code ec;
  *file_size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(Status::IoError, "'" + path + "': cannot read (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(Status::IoError, "'" + path + "': cannot open for reading");
  std::string s(size_t(std::min<uint64_t>(limit, *file_size)), '\0');
  in.read(s.data(), std::streamsize(s.size()));
  s.resize(size_t(in.gcount()));
  return s;
}

bool parse_u64(std::string_view s, uint64_t& v) {
  if (s.empty() || s[0] == '-' || s[0] == '+') return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

/// A token that OpenMesh's readers (`istream >> value`) read whole: an integer (optional sign,
/// digits) or, unless `integer`, a decimal floating-point number. Anything else fails their
/// stream, or leaves the rest of the token for the next read; they check neither, and loop
/// on stale counts after it (found by fuzzing: GBs allocated from a 3 kB PLY or OFF file).
bool numeric_token(std::string_view t, bool integer) {
  if (t.empty() || t.size() >= 64) return false;  // Reader::token keeps 64 bytes at most
  const size_t start = (t[0] == '-' || t[0] == '+') ? 1 : 0;
  if (start == t.size() || !(std::isdigit(static_cast<unsigned char>(t[start])) || (!integer && t[start] == '.')))
    return false;  // also refuses "inf" and "nan", which istream >> does not read
  const char* end = t.data() + t.size();
  if (integer) {
    for (size_t i = start; i < t.size(); ++i)
      if (!std::isdigit(static_cast<unsigned char>(t[i]))) return false;
    return true;
  }
  double v = 0;
  const auto r = std::from_chars(t.data() + (t[0] == '+' ? 1 : 0), end, v);
  return r.ptr == end && (r.ec == std::errc() || r.ec == std::errc::result_out_of_range);
}

/// Saturating a * b + c.
uint64_t mul_add(uint64_t a, uint64_t b, uint64_t c) {
  if (b != 0 && a > (std::numeric_limits<uint64_t>::max() - c) / b) return std::numeric_limits<uint64_t>::max();
  return a * b + c;
}

// ---- PLY ----------------------------------------------------------------------------

int ply_type_size(std::string_view t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

bool ply_integer_type(std::string_view t) {
  return ply_type_size(t) != 0 && t != "float" && t != "float32" && t != "double" && t != "float64";
}

enum class PlyScalar : uint8_t { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

PlyScalar ply_scalar(std::string_view t) {
  if (t == "char" || t == "int8") return PlyScalar::Int8;
  if (t == "uchar" || t == "uint8") return PlyScalar::Uint8;
  if (t == "short" || t == "int16") return PlyScalar::Int16;
  if (t == "ushort" || t == "uint16") return PlyScalar::Uint16;
  if (t == "int" || t == "int32") return PlyScalar::Int32;
  if (t == "uint" || t == "uint32") return PlyScalar::Uint32;
  if (t == "float" || t == "float32") return PlyScalar::Float32;
  return PlyScalar::Float64;
}

struct PlyProperty {
  std::string name;                       ///< a scalar's name (x, nx, red, ...)
  PlyScalar scalar = PlyScalar::Float32;  ///< a scalar's type
  bool list = false;
  bool integer = false;  ///< the scalar or list item type is an integer type
  int size = 0;          ///< scalar size, or list item size
  int count_size = 0;  ///< list count size
  bool count_signed = false;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) w.push_back(line.substr(i, j - i));
    i = j;
  }
  return w;
}

std::string plural(uint64_t n, const std::string& what) {
  return std::to_string(n) + " '" + what + "' element" + (n == 1 ? "" : "s");
}

/// A binary scalar (size bytes at raw, in the file's byte order) as a double.
double ply_binary_value(const unsigned char* raw, PlyScalar type, int size, bool big_endian) {
  unsigned char b[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < size; ++i) b[i] = raw[big_endian ? size - 1 - i : i];  // little-endian host
  auto as = [&](auto v) {
    std::memcpy(&v, b, sizeof v);
    return double(v);
  };
  switch (type) {
    case PlyScalar::Int8: return as(int8_t{});
    case PlyScalar::Uint8: return as(uint8_t{});
    case PlyScalar::Int16: return as(int16_t{});
    case PlyScalar::Uint16: return as(uint16_t{});
    case PlyScalar::Int32: return as(int32_t{});
    case PlyScalar::Uint32: return as(uint32_t{});
    case PlyScalar::Float32: return as(float{});
    case PlyScalar::Float64: break;
  }
  return as(double{});
}

/// A number token (already checked by numeric_token) as a double.
double ply_ascii_value(const std::string& t) {
  const char* b = t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
  double v = 0;
  const auto r = std::from_chars(b, t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range) return std::strtod(t.c_str(), nullptr);  // +-inf or 0, as OpenMesh
  return v;
}

void check_ply(const std::string& path, ExactVertices* exact) {
  uint64_t file_size = 0;
  const std::string head = read_prefix(path, kMaxHeader, &file_size);
  // OpenMesh takes "PLY" in any case and after any whitespace (it reads a word), and then loops
  // forever on a header without end_header (both found by fuzzing): check whatever it reads.
  size_t m = 0;
  while (m < head.size() && std::isspace(static_cast<unsigned char>(head[m]))) ++m;
  if (head.size() < m + 3 || std::tolower(static_cast<unsigned char>(head[m])) != 'p' ||
      std::tolower(static_cast<unsigned char>(head[m + 1])) != 'l' ||
      std::tolower(static_cast<unsigned char>(head[m + 2])) != 'y')
    return;  // not a PLY header: OpenMesh says so
  enum class Format { None, Ascii, BinaryLE, BinaryBE } format = Format::None;
  std::vector<PlyElement> elements;
  // OpenMesh takes the three words after the magic line as "format TYPE VERSION", whatever
  // they are; a version it cannot read leaves its stream failed, and it then loops forever
  // looking for end_header (found by fuzzing). The format line must come first.
  size_t pos = head.find('\n', m);
  pos = pos == std::string::npos ? head.size() : pos + 1;
  bool first = true;
  uint64_t data_offset = 0;
  bool ended = false;
  while (pos < head.size()) {
    size_t eol = head.find('\n', pos);
    if (eol == std::string::npos) break;
    const std::string_view line(head.data() + pos, eol - pos);
    pos = eol + 1;
    const auto w = split_words(line);
    if (w.empty()) continue;
    if (first && (w[0] != "format" || w.size() != 3))
      fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) +
                     "' (the line after 'ply' must be: format TYPE VERSION)");
    first = false;
    // OpenMesh reads the header word by word, not line by line: a keyword anywhere is a
    // keyword to it (only "comment" eats the rest of its line), and one read out of place
    // makes it take end_header for an argument and loop forever at the end of the stream
    // (found by fuzzing: "x property float" before end_header). Keep its words and ours in
    // step: keywords start lines and take exactly their arguments.
    const bool keyword_line = w[0] == "end_header" || w[0] == "format" || w[0] == "element" ||
                              w[0] == "property" || w[0] == "comment";
    if (!keyword_line)
      for (size_t k = 1; k < w.size() && w[k] != "comment"; ++k)
        if (w[k] == "end_header" || w[k] == "element" || w[k] == "property")
          fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' ('" + std::string(w[k]) +
                         "' inside a line: keywords start lines)");
    if (w[0] == "end_header") {
      if (w.size() != 1) fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' (end_header alone)");
      data_offset = pos;
      ended = true;
      break;
    }
    if (w[0] == "format" && w.size() >= 2) {
      if (format != Format::None) fail(path, "bad PLY header: a second format line");
      format = w[1] == "ascii" ? Format::Ascii
               : w[1] == "binary_little_endian" ? Format::BinaryLE
               : w[1] == "binary_big_endian" ? Format::BinaryBE
                                               : Format::None;
      if (format == Format::None) fail(path, "PLY format '" + std::string(w[1].substr(0, 40)) + "' is not ascii or binary");
      // OpenMesh's reader loops forever on a version it cannot parse ("format ascii ..0",
      // found by fuzzing): the version must be a number.
      double version = 0;
      const auto r = w.size() == 3 ? std::from_chars(w[2].data(), w[2].data() + w[2].size(), version)
                                   : std::from_chars_result{nullptr, std::errc::invalid_argument};
      if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size())
        fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' (format TYPE VERSION, e.g. 1.0)");
    } else if (w[0] == "element") {
      PlyElement e;
      if (w.size() != 3 || !parse_u64(w[2], e.count))
        fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' (element NAME COUNT)");
      e.name = std::string(w[1].substr(0, 40));
      elements.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (elements.empty()) fail(path, "bad PLY header: a property before any element");
      PlyProperty p;
      if (w.size() == 5 && w[1] == "list") {
        p.list = true;
        p.count_size = ply_type_size(w[2]);
        p.count_signed = w[2] == "char" || w[2] == "int8" || w[2] == "short" || w[2] == "int16" || w[2] == "int" ||
                         w[2] == "int32";
        p.size = ply_type_size(w[3]);
        p.integer = ply_integer_type(w[3]);
        if (p.count_size == 0 || p.size == 0 || p.count_size == 8)
          fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' (unknown list types)");
      } else if (w.size() == 3) {
        p.scalar = ply_scalar(w[1]);
        p.name = std::string(w[2].substr(0, 40));
        p.size = ply_type_size(w[1]);
        p.integer = ply_integer_type(w[1]);
        if (p.size == 0) fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "' (unknown type)");
      } else {
        fail(path, "bad PLY header line '" + std::string(line.substr(0, 80)) + "'");
      }
      elements.back().properties.push_back(p);
    }
  }
  if (!ended) {
    if (file_size > head.size()) fail(path, "no end_header in the first MiB: not a PLY file");
    fail(path, "truncated PLY header (no end_header)");
  }
  if (format == Format::None) fail(path, "bad PLY header: no format line");

  // The vertex element's x y z and nx ny nz, read exactly unless all are float32 (see
  // ExactVertices): slot[k] is the property index of the k-th of them, or -1.
  const PlyElement* vertex = nullptr;
  int slot[6] = {-1, -1, -1, -1, -1, -1};
  bool exact_positions = false, exact_normals = false;
  if (exact) {
    *exact = ExactVertices{};
    for (const PlyElement& e : elements)
      if (e.name == "vertex") {
        vertex = &e;
        break;
      }
    if (vertex) {
      static const char* const kNames[6] = {"x", "y", "z", "nx", "ny", "nz"};
      for (int k = 0; k < 6; ++k)
        for (size_t i = 0; i < vertex->properties.size(); ++i)
          if (!vertex->properties[i].list && vertex->properties[i].name == kNames[k]) {
            slot[k] = int(i);
            break;
          }
      auto not_float32 = [&](int k) {
        return slot[k] >= 0 && vertex->properties[size_t(slot[k])].scalar != PlyScalar::Float32;
      };
      exact_positions = not_float32(0) || not_float32(1) || not_float32(2);
      exact_normals = slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0 && (not_float32(3) || not_float32(4) || not_float32(5));
      for (int k = 0; k < 6; ++k)
        exact->integer_types |= slot[k] >= 0 && vertex->properties[size_t(slot[k])].scalar != PlyScalar::Float32 &&
                                vertex->properties[size_t(slot[k])].scalar != PlyScalar::Float64;
    }
  }
  // Where a vertex property goes: 0-2 a position's coordinate, 3-5 a normal's, -1 nowhere.
  auto target = [&](const PlyElement& e, size_t property) {
    if (&e != vertex) return -1;
    for (int k = 0; k < 6; ++k)
      if (slot[k] == int(property) && (k < 3 ? exact_positions : exact_normals)) return k;
    return -1;
  };
  // Grown as the data is read: an ASCII file's count is only known to hold at its end.
  auto store = [&](uint64_t i, int k, double v) {
    std::vector<Vec3>& list = k < 3 ? exact->positions : exact->normals;
    if (list.size() <= i) list.resize(size_t(i) + 1);
    Vec3& q = list[size_t(i)];
    (k % 3 == 0 ? q.x : k % 3 == 1 ? q.y : q.z) = v;
  };

  const uint64_t available = file_size - data_offset;
  if (format == Format::Ascii) {
    Reader r(path, data_offset);
    std::string tok;
    for (const PlyElement& e : elements) {
      for (uint64_t i = 0; i < e.count; ++i) {
        for (size_t pi = 0; pi < e.properties.size(); ++pi) {
          const PlyProperty& p = e.properties[pi];
          auto value = [&](const std::string& t) {
            if (!numeric_token(t, p.integer))
              fail(path, "'" + e.name + "' element " + std::to_string(i) + ": '" + t + "' is not " +
                             (p.integer ? "an integer" : "a number"));
          };
          if (!p.list) {
            if (r.token(tok)) {
              value(tok);
              if (const int k = target(e, pi); k >= 0) store(i, k, ply_ascii_value(tok));
              continue;
            }
          } else if (r.token(tok)) {
            uint64_t n = 0;
            if (!parse_u64(tok, n))
              fail(path, "'" + e.name + "' element " + std::to_string(i) + ": list count '" + tok +
                             "' is not a non-negative integer");
            uint64_t k = 0;
            for (; k < n && r.token(tok); ++k) value(tok);
            if (k == n) continue;
          }
          fail(path, "truncated: the header promises " + plural(e.count, e.name) + ", the file ends in element " +
                         std::to_string(i));
        }
      }
    }
    return;
  }

  // Binary: fixed-size elements by arithmetic, elements with lists by walking their counts.
  Reader r(path, data_offset);
  uint64_t used = 0;
  for (const PlyElement& e : elements) {
    bool has_list = false;
    uint64_t fixed = 0;
    for (const PlyProperty& p : e.properties) {
      has_list |= p.list;
      fixed += uint64_t(p.list ? p.count_size : p.size);
    }
    const uint64_t least = mul_add(e.count, fixed, used);
    if (least > available)
      fail(path, "truncated: the header promises " + plural(e.count, e.name) + " (at least " +
                     std::to_string(mul_add(e.count, fixed, 0)) + " bytes), the file holds " +
                     std::to_string(available - std::min(used, available)) + " bytes for them");
    const bool collect = &e == vertex && (exact_positions || exact_normals);
    if (!has_list && !collect) {
      if (!r.skip_bytes(mul_add(e.count, fixed, 0))) fail(path, "truncated data in the '" + e.name + "' elements");
      used = least;
      continue;
    }
    for (uint64_t i = 0; i < e.count; ++i) {
      bool complete = true;
      for (size_t pi = 0; pi < e.properties.size(); ++pi) {
        const PlyProperty& p = e.properties[pi];
        if (!p.list) {
          if (const int k = collect ? target(e, pi) : -1; k >= 0) {
            unsigned char raw[8];
            complete = r.bytes(raw, size_t(p.size));
            if (complete) store(i, k, ply_binary_value(raw, p.scalar, p.size, format == Format::BinaryBE));
          } else {
            complete = r.skip_bytes(uint64_t(p.size));
          }
          if (!complete) break;
          used += uint64_t(p.size);
          continue;
        }
        unsigned char raw[4] = {0, 0, 0, 0};
        complete = r.bytes(raw, size_t(p.count_size));
        if (!complete) break;
        used += uint64_t(p.count_size);
        if (format == Format::BinaryBE)
          for (int a = 0, b = p.count_size - 1; a < b; ++a, --b) std::swap(raw[a], raw[b]);
        uint64_t n = 0;
        std::memcpy(&n, raw, size_t(p.count_size));  // little-endian host (x86-64, aarch64)
        if (p.count_signed && (raw[p.count_size - 1] & 0x80))
          fail(path, "'" + e.name + "' element " + std::to_string(i) + " has a negative list count");
        const uint64_t bytes = mul_add(n, uint64_t(p.size), 0);
        if (bytes > available - std::min(used, available))
          fail(path, "'" + e.name + "' element " + std::to_string(i) + " has a list of " + std::to_string(n) +
                         " items, more than the rest of the file holds");
        complete = r.skip_bytes(bytes);
        if (!complete) break;
        used += bytes;
      }
      if (!complete)
        fail(path, "truncated: the header promises " + plural(e.count, e.name) + ", the file ends in element " +
                       std::to_string(i));
    }
  }
}

// ---- OFF ----------------------------------------------------------------------------

// OpenMesh's OFF reader takes the line after the keyword's for the counts, then reads every
// vertex (3 coordinates, 3 more with N, the rest of the line for colours / texture
// coordinates) and every face (a corner count, then that many indices) without checking that
// a read succeeded: a file that ends early, or a token that is not a number, leaves the stream
// failed and the loops running on stale values (a corner count of 4e9 pushes 4e9 handles;
// found by fuzzing). So the file is walked here the way the reader walks it, before it runs.
void check_off(const std::string& path, ExactVertices* exact) {
  uint64_t file_size = 0;
  const std::string head = read_prefix(path, 4096, &file_size);
  // The first line holds the keyword ([ST][C][N][4][n]OFF, optionally BINARY).
  const size_t eol = head.find('\n');
  const std::string_view first(head.data(), eol == std::string::npos ? head.size() : eol);
  const size_t off = first.find("OFF");
  if (off == std::string_view::npos) return;  // not an OFF header: OpenMesh refuses the file
  if (eol == std::string::npos) fail(path, "OFF file without vertex and face counts (it ends on its first line)");
  const std::string_view prefix = first.substr(0, off);
  const bool tex = prefix.substr(0, 2) == "ST", normals = prefix.find('N') != std::string_view::npos;
  const bool colors = prefix.find('C') != std::string_view::npos;
  const bool binary = first.find("BINARY") != std::string_view::npos;
  Reader r(path, eol + 1);
  uint64_t counts[3] = {0, 0, 0};
  if (binary) {
    // Little-endian uint32 counts, then per vertex 4-byte values: 3 + 3 (N) + 3 (C) + 2 (ST).
    uint32_t c[3];
    if (!r.bytes(c, sizeof c)) fail(path, "truncated binary OFF header (no vertex and face counts)");
    const uint64_t vertex_bytes = 4 * (3 + (normals ? 3 : 0) + (colors ? 3 : 0) + (tex ? 2 : 0));
    if (!r.skip_bytes(mul_add(c[0], vertex_bytes, 0)))
      fail(path, "truncated: the binary OFF header promises " + std::to_string(c[0]) + " vertices and " +
                     std::to_string(c[1]) + " faces, the file ends in the vertices");
    for (uint64_t f = 0; f < c[1]; ++f) {
      uint32_t k = 0;
      if (!r.bytes(&k, 4) || !r.skip_bytes(uint64_t(k) * 4))
        fail(path, "truncated: the binary OFF header promises " + std::to_string(c[1]) + " faces, the file ends in face " +
                       std::to_string(f) + (k ? " (" + std::to_string(k) + " corners)" : std::string()));
    }
    return;
  }
  std::string tok;
  for (int got = 0; got < 3; ++got) {
    if (!r.token(tok)) {
      if (got < 2) fail(path, "truncated OFF header (no vertex and face counts)");
      break;
    }
    if (tok[0] == '#') fail(path, "a comment before the OFF counts (OpenMesh's reader cannot read it)");
    if (!numeric_token(tok, true) || !parse_u64(tok, counts[got]))
      fail(path, "bad OFF header: '" + tok + "' is not a vertex/face/edge count");
  }
  auto truncated = [&](const std::string& where) {
    fail(path, "truncated: the header promises " + std::to_string(counts[0]) + " vertices and " +
                   std::to_string(counts[1]) + " faces, the file ends in " + where);
  };
  for (uint64_t v = 0; v < counts[0]; ++v) {
    double c[3] = {0, 0, 0};
    for (int i = 0; i < (normals ? 6 : 3); ++i) {
      if (!r.token(tok)) truncated("vertex " + std::to_string(v));
      if (!numeric_token(tok, false)) fail(path, "vertex " + std::to_string(v) + ": '" + tok + "' is not a number");
      if (i < 3) c[i] = ply_ascii_value(tok);
    }
    if (exact) exact->positions.push_back({c[0], c[1], c[2]});  // as written (see ExactVertices)
    if (!r.at_line_start()) r.skip_line();  // colours, texture coordinates: the rest of the line
  }
  for (uint64_t f = 0; f < counts[1]; ++f) {
    uint64_t k = 0;
    if (!r.token(tok)) truncated("face " + std::to_string(f));
    if (!numeric_token(tok, true) || !parse_u64(tok, k))
      fail(path, "face " + std::to_string(f) + ": corner count '" + tok + "' is not a number");
    for (uint64_t i = 0; i < k; ++i) {
      if (!r.token(tok)) truncated("face " + std::to_string(f) + " (" + std::to_string(k) + " corners)");
      if (!numeric_token(tok, true) || tok[0] == '-') fail(path, "face " + std::to_string(f) + ": corner '" + tok + "' is not an index");
    }
    if (colors && !r.at_line_start()) r.skip_line();  // a face colour
  }
}

// ---- OBJ ----------------------------------------------------------------------------

/// An integer index that fits an int (OpenMesh reads an int), or, where `may_be_empty`, nothing.
bool obj_index(std::string_view s, bool may_be_empty) {
  if (s.empty()) return may_be_empty;
  int v = 0;
  return numeric_token(s, true) && std::from_chars(s.data() + (s[0] == '+'), s.data() + s.size(), v).ec == std::errc();
}

// OpenMesh's OBJ reader asserts (an abort in Debian's build) on a face corner whose vertex
// index is missing ("f /1 2 3", "f //4 ..."), and reads an uninitialized index for one that is
// not a number ("f x 2 3"). Every corner must be v, v/vt, v//vn or v/vt/vn with integers;
// vertex indices out of range are caught after reading (the importer checks them).
void check_obj(const std::string& path, ExactVertices* exact) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  uint64_t number = 0;
  bool exact_ok = exact != nullptr;  // every v line so far has three numbers
  while (std::getline(in, line)) {
    ++number;
    const auto w = split_words(line);
    if (exact_ok && !w.empty() && w[0] == "v") {
      // OpenMesh's OBJ reader keeps float32 too: the positions as written (see ExactVertices).
      double c[3] = {0, 0, 0};
      for (size_t k = 0; k < 3 && exact_ok; ++k) {
        exact_ok = k + 1 < w.size() && numeric_token(w[k + 1], false);
        if (exact_ok) c[k] = ply_ascii_value(std::string(w[k + 1]));
      }
      if (exact_ok) exact->positions.push_back({c[0], c[1], c[2]});
    }
    if (w.empty() || w[0] != "f") continue;
    for (size_t i = 1; i < w.size(); ++i) {
      const std::string_view corner = w[i];
      const size_t a = corner.find('/');
      bool ok = obj_index(corner.substr(0, a), false);
      if (ok && a != std::string_view::npos) {
        const std::string_view rest = corner.substr(a + 1);
        const size_t b = rest.find('/');
        ok = obj_index(rest.substr(0, b), true) && (b == std::string_view::npos || obj_index(rest.substr(b + 1), true));
      }
      if (!ok)
        fail(path, "line " + std::to_string(number) + ": face corner '" + std::string(corner.substr(0, 40)) +
                       "' is not v, v/vt, v//vn or v/vt/vn with integer indices");
    }
  }
  if (exact && !exact_ok) exact->positions.clear();  // then OpenMesh's, whatever it made of them
}

// ---- STL ----------------------------------------------------------------------------

void check_stl(const std::string& path) {
  uint64_t file_size = 0;
  const std::string head = read_prefix(path, 84, &file_size);
  if (file_size < 84) {
    if (head.compare(0, 5, "solid") == 0) return;  // a short ASCII file
    fail(path, "not an STL file: " + std::to_string(file_size) + " bytes, no 'solid' and no binary header");
  }
  uint32_t triangles = 0;
  std::memcpy(&triangles, head.data() + 80, 4);
  const uint64_t need = 84 + 50 * uint64_t(triangles);
  if (head.compare(0, 5, "solid") == 0 && file_size != need) return;  // ASCII
  if (file_size < need)
    fail(path, "truncated binary STL: the header promises " + std::to_string(triangles) + " triangles (" +
                   std::to_string(need) + " bytes), the file has " + std::to_string(file_size));
}

}  // namespace

void check_mesh_file_header(const std::string& path, const std::string& ext, ExactVertices* exact) {
  if (exact) *exact = ExactVertices{};
  if (ext == ".ply") check_ply(path, exact);
  else if (ext == ".off") check_off(path, exact);
  else if (ext == ".stl") check_stl(path);
  else if (ext == ".obj") check_obj(path, exact);
}

}  // namespace particlemesh::detail
