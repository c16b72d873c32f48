// Internal: the binary scalar types of the formats read here (PLY, VTK legacy and XML): their
// sizes and their values, decoded exactly from either byte order. Each reader maps its own
// type names (PLY's "uchar", legacy VTK's "unsigned_char", VTK XML's "UInt8") onto these.
#pragma once

#include "particlemesh/core/config.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace PM_NAMESPACE::detail {

static_assert(std::endian::native == std::endian::little, "decode_scalar assumes a little-endian host");

/// Bit and String are VTK array types that are not numbers per value (size 0, like None).
enum class ScalarType : uint8_t { I8, U8, I16, U16, I32, U32, I64, U64, F16, F32, F64, Bit, String, None };

/// Bytes of one value; 0 for Bit, String and None.
inline int scalar_size(ScalarType t) {
  switch (t) {
    case ScalarType::I8: case ScalarType::U8: return 1;
    case ScalarType::I16: case ScalarType::U16: case ScalarType::F16: return 2;
    case ScalarType::I32: case ScalarType::U32: case ScalarType::F32: return 4;
    case ScalarType::I64: case ScalarType::U64: case ScalarType::F64: return 8;
    default: return 0;
  }
}

inline bool is_integer(ScalarType t) {
  return scalar_size(t) > 0 && t != ScalarType::F16 && t != ScalarType::F32 && t != ScalarType::F64;
}

/// IEEE 754 half precision to double (exact).
inline double half_to_double(uint16_t h) {
  const int exponent = (h >> 10) & 0x1f, mantissa = h & 0x3ff;
  const double sign = (h & 0x8000) ? -1.0 : 1.0;
  if (exponent == 0) return sign * std::ldexp(double(mantissa), -24);
  if (exponent == 31) return mantissa ? NAN : sign * INFINITY;
  return sign * std::ldexp(double(mantissa + 1024), exponent - 25);
}

/// The value of type T stored at `raw` in little-endian order (the host's, asserted above).
template <class T>
T load_little(const unsigned char* raw) {
  T v;
  std::memcpy(&v, raw, sizeof v);
  return v;
}

/// The bits of an IEEE half, standing for ScalarType::F16 in with_scalar_type.
struct Half {
  uint16_t bits;
};
static_assert(sizeof(Half) == 2);
inline double to_double(Half h) { return half_to_double(h.bits); }
template <class T>
double to_double(T v) {
  return double(v);
}

/// Calls f(T{}) with the C++ type that holds a value of `t` (Half for F16); returns false,
/// calling nothing, for the types without a size. The one switch over the numeric types.
template <class F>
bool with_scalar_type(ScalarType t, F&& f) {
  switch (t) {
    case ScalarType::I8: f(int8_t{}); return true;
    case ScalarType::U8: f(uint8_t{}); return true;
    case ScalarType::I16: f(int16_t{}); return true;
    case ScalarType::U16: f(uint16_t{}); return true;
    case ScalarType::I32: f(int32_t{}); return true;
    case ScalarType::U32: f(uint32_t{}); return true;
    case ScalarType::I64: f(int64_t{}); return true;
    case ScalarType::U64: f(uint64_t{}); return true;
    case ScalarType::F16: f(Half{}); return true;
    case ScalarType::F32: f(float{}); return true;
    case ScalarType::F64: f(double{}); return true;
    default: return false;
  }
}

/// One value of type T (a with_scalar_type type) at `raw`, in big- or little-endian order.
template <class T>
double scalar_at(const unsigned char* raw, bool big_endian) {
  unsigned char b[sizeof(T)];
  for (size_t k = 0; k < sizeof(T); ++k) b[k] = raw[big_endian ? sizeof(T) - 1 - k : k];  // to the host's order
  return to_double(load_little<T>(b));
}

/// The value of scalar_size(t) bytes at `raw`, stored in big- or little-endian order, as a
/// double: exact for every type but 64-bit integers beyond 2^53 (rounded to nearest). 0 for
/// the types without a size.
inline double decode_scalar(ScalarType t, const unsigned char* raw, bool big_endian) {
  double out = 0;
  with_scalar_type(t, [&](auto zero) { out = scalar_at<decltype(zero)>(raw, big_endian); });
  return out;
}

/// `count` values of type `t` from `raw` into `out`, as decode_scalar gives each, with the
/// type's switch outside the loop (a million float32 triples: ~8 ms instead of ~35 ms).
inline void decode_scalars(ScalarType t, const unsigned char* raw, size_t count, bool big_endian, double* out) {
  const bool sized = with_scalar_type(t, [&](auto zero) {
    using T = decltype(zero);
    if (big_endian)
      for (size_t i = 0; i < count; ++i) out[i] = scalar_at<T>(raw + i * sizeof(T), true);
    else
      for (size_t i = 0; i < count; ++i) out[i] = to_double(load_little<T>(raw + i * sizeof(T)));
  });
  if (!sized)
    for (size_t i = 0; i < count; ++i) out[i] = 0;
}

/// Bytes holding `count` values of a Bit array (eight to a byte).
inline uint64_t bit_bytes(uint64_t count) { return count / 8 + (count % 8 != 0); }

/// `count` values of a Bit array from `raw` into `out` as 0 / 1: VTK packs them eight to a
/// byte, the first in the highest bit (vtkBitArray, in legacy and XML files alike).
inline void decode_bits(const unsigned char* raw, size_t count, double* out) {
  for (size_t i = 0; i < count; ++i) out[i] = (raw[i / 8] >> (7 - i % 8)) & 1;
}

/// a * b, or UINT64_MAX where that overflows: sizes from a file's header compared with what
/// the file holds.
inline uint64_t saturating_mul(uint64_t a, uint64_t b) { return b != 0 && a > UINT64_MAX / b ? UINT64_MAX : a * b; }

}  // namespace particlemesh::detail
