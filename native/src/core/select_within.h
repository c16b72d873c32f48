// Internal: the positions (or values) of the distances within a range, in order - the filter
// that the neighbour searches run over every candidate of every point.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>

#include "core/cpu_clones.h"

namespace PM_NAMESPACE::detail {

/// Writes to `out`, for i < m in increasing order, where low < d2[i] <= high and (with
/// `values`) values[i] != exclude: values[i], or i without `values`; returns how many. `out`
/// has room for m + 16. (Ordered compares: a NaN distance is never within.) One at a time,
/// each written and kept or not without a branch (about half are kept, in no pattern a branch
/// predictor learns).
inline size_t select_within_scalar(const double* d2, size_t m, double low, double high, const uint32_t* values,
                                   uint32_t exclude, uint32_t* out) {
  size_t count = 0;
  if (values == nullptr) {
    for (size_t i = 0; i < m; ++i) {
      out[count] = uint32_t(i);
      count += size_t(d2[i] > low) & size_t(d2[i] <= high);
    }
  } else {
    for (size_t i = 0; i < m; ++i) {
      out[count] = values[i];
      count += size_t(d2[i] > low) & size_t(d2[i] <= high) & size_t(values[i] != exclude);
    }
  }
  return count;
}

#ifdef PM_HAVE_AVX512
/// select_within_scalar sixteen at a time (AVX-512): two compares of eight distances each, the
/// kept values compressed to the front of one vector and stored whole (up to 15 past the
/// count, in the room left for them). The same tests, so the same values in the same order.
/// Written with intrinsics because no compiler vectorises a filter whose store follows a
/// running count (the scalar loop was a fifth of the k nearest's own time).
template <bool kValues>
PM_TARGET_AVX512 size_t select_within_avx512(const double* d2, size_t m, double low, double high,
                                              const uint32_t* values, uint32_t exclude, uint32_t* out) {
  const __m512d lo_d = _mm512_set1_pd(low), hi_d = _mm512_set1_pd(high);
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i excluded = _mm512_set1_epi32(int(exclude));
  size_t count = 0;
  for (size_t i = 0; i < m; i += 16) {
    const size_t left = m - i;
    const __mmask8 lo = __mmask8(left >= 8 ? 0xff : (1u << left) - 1);
    const __mmask8 hi = __mmask8(left >= 16 ? 0xff : left > 8 ? (1u << (left - 8)) - 1 : 0);
    const __m512d a = _mm512_maskz_loadu_pd(lo, d2 + i), b = _mm512_maskz_loadu_pd(hi, d2 + i + 8);
    const __mmask8 ka = _mm512_mask_cmp_pd_mask(_mm512_mask_cmp_pd_mask(lo, a, lo_d, _CMP_GT_OQ), a, hi_d, _CMP_LE_OQ);
    const __mmask8 kb = _mm512_mask_cmp_pd_mask(_mm512_mask_cmp_pd_mask(hi, b, lo_d, _CMP_GT_OQ), b, hi_d, _CMP_LE_OQ);
    __mmask16 keep = __mmask16(unsigned(ka) | (unsigned(kb) << 8));
    __m512i v;
    if constexpr (!kValues) {
      v = _mm512_add_epi32(_mm512_set1_epi32(int(i)), lanes);
    } else {
      const __mmask16 all = __mmask16(left >= 16 ? 0xffffu : (1u << left) - 1);
      v = _mm512_maskz_loadu_epi32(all, values + i);
      keep = _mm512_mask_cmpneq_epi32_mask(keep, v, excluded);
    }
    _mm512_storeu_si512(out + count, _mm512_maskz_compress_epi32(keep, v));
    count += size_t(__builtin_popcount(keep));
  }
  return count;
}
#endif

/// select_within_scalar, sixteen at a time where the processor has AVX-512.
inline size_t select_within(const double* d2, size_t m, double low, double high, const uint32_t* values,
                            uint32_t exclude, uint32_t* out) {
#ifdef PM_HAVE_AVX512
  if (cpu_has_avx512())
    return values ? select_within_avx512<true>(d2, m, low, high, values, exclude, out)
                  : select_within_avx512<false>(d2, m, low, high, values, exclude, out);
#endif
  return select_within_scalar(d2, m, low, high, values, exclude, out);
}

}  // namespace PM_NAMESPACE::detail
