// Internal: words and numbers in text files (PLY ASCII, OBJ, OFF, STL ASCII, XYZ), numbers
// read exactly.
//
// std::from_chars rounds correctly: a 17-digit coordinate comes back as the double that was
// written, which is what "coordinates keep their full precision" rests on. (strtod does too,
// but depends on the locale; istream >> float, as OpenMesh read, does not keep doubles.)
#pragma once

#include "particlemesh/core/config.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace PM_NAMESPACE::detail {

enum class NumberText {
  Ok,
  NotANumber,  ///< not a decimal number
  Overflow,    ///< a number beyond +-DBL_MAX (out = +-inf)
};

/// The words of a line separated by blanks (spaces, tabs, a carriage return), into `out`
/// (cleared first; the views point into `line`).
inline void split_words(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
}

inline bool equals_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const char x = a[i] >= 'A' && a[i] <= 'Z' ? char(a[i] + 32) : a[i];
    const char y = b[i] >= 'A' && b[i] <= 'Z' ? char(b[i] + 32) : b[i];
    if (x != y) return false;
  }
  return true;
}

/// A decimal number (optional sign, digits, a point, an exponent; or nan / inf / infinity
/// in any case, which come back as NaN / inf for the caller to name). Values below the
/// smallest subnormal become 0 (or -0), as strtod makes them.
inline NumberText parse_number(std::string_view t, double& out) {
  if (t.empty()) return NumberText::NotANumber;
  const bool plus = t[0] == '+';
  std::string_view body = plus ? t.substr(1) : t;
  if (body.empty() || body[0] == '+' || (plus && body[0] == '-')) return NumberText::NotANumber;
  const auto r = std::from_chars(body.data(), body.data() + body.size(), out, std::chars_format::general);
  if (r.ptr != body.data() + body.size()) {
    // from_chars reads "nan(...)" and "infinity" too, but stops early on "nan(" garbage.
    return NumberText::NotANumber;
  }
  if (r.ec == std::errc()) return NumberText::Ok;
  if (r.ec != std::errc::result_out_of_range) return NumberText::NotANumber;
  // Out of range: overflow (inf, an error for the caller) or underflow (a subnormal or 0).
  out = std::strtod(std::string(t).c_str(), nullptr);
  return std::isinf(out) ? NumberText::Overflow : NumberText::Ok;
}

/// A non-negative decimal integer (optional '+').
inline bool parse_count(std::string_view t, uint64_t& out) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  if (t.empty() || t[0] == '-' || t[0] == '+') return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

/// A decimal integer with an optional sign.
inline bool parse_integer(std::string_view t, int64_t& out) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  if (t.empty() || t[0] == '+') return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

/// A token for a message: at most 24 bytes, printable.
inline std::string shown(std::string_view t) {
  std::string s;
  for (char c : t.substr(0, 24)) s.push_back(c >= 32 && c < 127 ? c : '?');
  if (t.size() > 24) s += "...";
  return s;
}

}  // namespace particlemesh::detail
