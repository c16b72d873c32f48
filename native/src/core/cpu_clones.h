// Internal: PM_CPU_CLONES, a hot function compiled once per x86-64 level and picked at load.
//
// The library is built for baseline x86-64 (SSE2), so that one build runs on every x86-64
// machine. A few loops run markedly faster with the newer levels' instructions (AVX-512's
// masks and the VEX three-operand forms: polygonize's gathered field sums, about 5 % of a
// polygonize, see bench/RESULTS.md). PM_CPU_CLONES on such a function has GCC compile it
// three times - x86-64-v4, x86-64-v3 and baseline - and the dynamic loader pick the one the
// machine runs (an ifunc, resolved once).
//
// The results are the same bits on every level: the library is compiled with
// -ffp-contract=off (no a * b + c fused where the level has FMA), the compiler reorders no
// floating-point sum without -ffast-math, and the clones are checked against the field's own
// (baseline) evaluations (Polygonize.GatheredAndDirectEvaluationsGiveTheSameMesh).
//
// Only with GCC on x86-64 glibc (ifuncs): Clang 14 refuses target_clones on member functions
// defined out of line, so the sanitizer and fuzzing builds (Clang) test the baseline code.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>  // (defines __GLIBC__ on glibc)

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__ELF__) && defined(__GLIBC__)
#define PM_CPU_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PM_CPU_CLONES
#endif

// A few filters need what no compiler vectorises on its own (a store that follows a running
// count, a loop that stops at the first hit): AVX-512's masks and compress, written with
// intrinsics in a function marked PM_TARGET_AVX512 and called only where cpu_has_avx512() (GCC
// and Clang on x86-64; elsewhere PM_HAVE_AVX512 is undefined and the scalar loop runs). Each
// such function keeps the scalar loop's arithmetic and order, so the results are the same bits.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define PM_HAVE_AVX512 1
#define PM_TARGET_AVX512 __attribute__((target("avx512f")))
namespace PM_NAMESPACE::detail {
/// Whether the processor runs AVX-512 Foundation (asked once).
inline bool cpu_has_avx512() {
  static const bool has = __builtin_cpu_supports("avx512f");
  return has;
}
}  // namespace PM_NAMESPACE::detail
#endif
