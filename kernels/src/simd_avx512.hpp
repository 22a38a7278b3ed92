#pragma once
// Private, for the AVX-512 sources only, included inside their target pragma: the lanes of an
// 8-ray packet, with the names of simd_avx2.hpp (see there). Masks are mask registers.
// With NBV_EMULATE_AVX512 the same names are simd_emulated.hpp's plain C++ lanes.

#ifdef NBV_EMULATE_AVX512
#include "simd_emulated.hpp"

namespace nbv::kernels::detail {
using Avx512Lanes = EmulatedAvx512Lanes;
}  // namespace nbv::kernels::detail
#else
#include <immintrin.h>

#include <cstdint>

namespace nbv::kernels::detail {

struct Avx512Lanes {
  static constexpr int kLanes = 8;
  using D = __m512d;
  using I = __m512i;
  using M = __mmask8;
  using F = __m256;
  using O = __m256i;  ///< a byte offset per lane, as a 32-bit integer (see toOffsets())
  /// Border crossings a run takes per axis between two tests of whether it is over (the IG
  /// walk's runs; tuned on the bunny-3 full set: docs/PERFORMANCE.md, "Tried and dropped").
  static constexpr int kRunBlock = 6;

  static D load(const double* p) { return _mm512_load_pd(p); }
  static void store(double* p, D v) { _mm512_store_pd(p, v); }
  static I loadI(const std::int64_t* p) { return _mm512_load_si512(p); }
  static void storeI(std::int64_t* p, I v) { _mm512_store_si512(p, v); }
  static M loadM(const std::int64_t* p) { return _mm512_movepi64_mask(loadI(p)); }
  static void storeM(std::int64_t* p, M m) { storeI(p, _mm512_movm_epi64(m)); }

  static D set1(double x) { return _mm512_set1_pd(x); }
  static I set1I(std::int64_t x) { return _mm512_set1_epi64(x); }
  static D zero() { return _mm512_setzero_pd(); }

  static D add(D a, D b) { return _mm512_add_pd(a, b); }
  static D sub(D a, D b) { return _mm512_sub_pd(a, b); }
  static D mul(D a, D b) { return _mm512_mul_pd(a, b); }
  static D min(D a, D b) { return _mm512_maskz_min_pd(0xFF, a, b); }  // (see sqrt())
  static D max(D a, D b) { return _mm512_maskz_max_pd(0xFF, a, b); }
  static D div(D a, D b) { return _mm512_div_pd(a, b); }
  // (The zero-masking forms with every lane set: the plain ones start from
  // _mm512_undefined_pd(), which GCC 12 reports as used uninitialised where they are inlined
  // into lambdas of a sanitizer build.)
  static D sqrt(D a) { return _mm512_maskz_sqrt_pd(0xFF, a); }
  static D floor(D a) { return _mm512_maskz_roundscale_pd(0xFF, a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }
  static D round(D a) { return _mm512_maskz_roundscale_pd(0xFF, a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC); }
  static D abs(D a) { return _mm512_abs_pd(a); }
  static F loadF(const float* p) { return _mm256_load_ps(p); }
  static F set1F(float x) { return _mm256_set1_ps(x); }
  static F addF(F a, F b) { return _mm256_add_ps(a, b); }
  static F subF(F a, F b) { return _mm256_sub_ps(a, b); }
  static F mulF(F a, F b) { return _mm256_mul_ps(a, b); }
  static F divF(F a, F b) { return _mm256_div_ps(a, b); }
  static D toDouble(F a) { return _mm512_maskz_cvtps_pd(0xFF, a); }
  static F toSingle(D a) { return _mm512_maskz_cvtpd_ps(0xFF, a); }

  static M lt(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_LT_OQ); }
  static M gt(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_GT_OQ); }
  static M eq(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_EQ_OQ); }
  static M le(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ); }
  static M notM(M a) { return _knot_mask8(a); }
  static M both(M a, M b) { return _kand_mask8(a, b); }
  static M either(M a, M b) { return _kor_mask8(a, b); }
  static M butNot(M a, M b) { return _kandn_mask8(a, b); }

  static D zeroUnless(M m, D v) { return _mm512_maskz_mov_pd(m, v); }
  static D addWhere(M m, D a, D b) { return _mm512_mask_add_pd(a, m, a, b); }
  static D subWhere(M m, D a, D b) { return _mm512_mask_sub_pd(a, m, a, b); }
  static D addOrZero(M m, D a, D b) { return _mm512_maskz_add_pd(m, a, b); }
  static D addUnless(M m, D a, D b) { return _mm512_mask_add_pd(a, _knot_mask8(m), a, b); }
  static D subUnless(M m, D a, D b) { return _mm512_mask_sub_pd(a, _knot_mask8(m), a, b); }
  static D select(M m, D a, D b) { return _mm512_mask_blend_pd(m, b, a); }
  static I selectI(M m, I a, I b) { return _mm512_mask_blend_epi64(m, b, a); }

  /// Byte offsets: exact integers below 2^31 in doubles, moved to 32-bit integer lanes, which
  /// the mark walk adds, selects and compares in one instruction each and stores as they are.
  static O toOffsets(D offset) { return _mm512_cvttpd_epi32(offset); }
  static O add(O a, O b) { return _mm256_add_epi32(a, b); }
  static O select(M m, O a, O b) { return _mm256_mask_blend_epi32(m, b, a); }
  static M eq(O a, O b) { return _mm256_cmpeq_epi32_mask(a, b); }

  static M eqI(I a, I b) { return _mm512_cmpeq_epi64_mask(a, b); }
  static M has(I flags, I bit) { return _mm512_test_epi64_mask(flags, bit); }
  static M hasNone(I flags, I bits) { return _mm512_testn_epi64_mask(flags, bits); }
  static I bitsOf(D d) { return _mm512_castpd_si512(d); }
  static D fromBits(I i) { return _mm512_castsi512_pd(i); }
  static I subI(I a, I b) { return _mm512_sub_epi64(a, b); }
  static I andI(I a, I b) { return _mm512_and_si512(a, b); }
  static I orI(I a, I b) { return _mm512_or_si512(a, b); }
  static I shiftRightI(I a, I shift) { return _mm512_srlv_epi64(a, shift); }
  template <int kShift>
  static I shiftLeftI(I a) {
    return _mm512_maskz_slli_epi64(0xFF, a, kShift);  // (see sqrt())
  }

  static unsigned bits(M m) { return static_cast<unsigned>(m); }
  static M mask(unsigned lanes) { return static_cast<M>(lanes); }

  /// The entries voxels[offset] of the lanes, in e[] and as a vector.
  static I loadEntries(const std::uint64_t* voxels, D offset, std::uint64_t e[kLanes]) {
    alignas(32) std::int32_t at[kLanes];
    offsets(offset, at);
    for (int i = 0; i < kLanes; ++i) e[i] = voxels[at[i]];
    return _mm512_set_epi64(static_cast<std::int64_t>(e[7]), static_cast<std::int64_t>(e[6]),
                            static_cast<std::int64_t>(e[5]), static_cast<std::int64_t>(e[4]),
                            static_cast<std::int64_t>(e[3]), static_cast<std::int64_t>(e[2]),
                            static_cast<std::int64_t>(e[1]), static_cast<std::int64_t>(e[0]));
  }

  /// The lanes' offsets (doubles holding integers below 2^31, or offset lanes) as 32-bit
  /// integers.
  static void offsets(D offset, std::int32_t out[kLanes]) { offsets(toOffsets(offset), out); }
  static void offsets(O offset, std::int32_t out[kLanes]) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), offset);
  }
  /// visit(base + offset) for the lanes of `lanes`, offsets as unsigned 32-bit values. They
  /// leave the register through memory, one 32-byte store read back as 4-byte loads, which
  /// beats extracting eight lanes.
  template <class Visit>
  static void forEachAt(std::uint8_t* base, O offset, unsigned lanes, Visit&& visit) {
    alignas(32) std::int32_t at[kLanes];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), offset);
    const auto byte = [base](std::int32_t o) { return base + static_cast<std::uint32_t>(o); };
    if (lanes == 0xFFu) {
      for (int i = 0; i < kLanes; ++i) visit(byte(at[i]));
      return;
    }
    for (unsigned left = lanes; left != 0; left &= left - 1) visit(byte(at[__builtin_ctz(left)]));
  }

  /// Rows of four doubles, row[i] for lane i, transposed: column c of every row in out[c].
  static void transposeRows(const double* const row[kLanes], D out[4]) {
    // Pairs of rows: {c0 c1 c2 c3 | c0 c1 c2 c3} of lanes (0, 1), (2, 3), ...
    const __m512d z0 = _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(row[0])), _mm256_loadu_pd(row[1]), 1);
    const __m512d z1 = _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(row[2])), _mm256_loadu_pd(row[3]), 1);
    const __m512d z2 = _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(row[4])), _mm256_loadu_pd(row[5]), 1);
    const __m512d z3 = _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(row[6])), _mm256_loadu_pd(row[7]), 1);
    // Per 128-bit block: lanes (0, 2) of columns 0 and 2, then lanes (1, 3).
    const __m512d even01 = _mm512_unpacklo_pd(z0, z1);  // c0: l0 l2, c2: l0 l2, c0: l1 l3, c2: l1 l3
    const __m512d odd01 = _mm512_unpackhi_pd(z0, z1);   // the same for columns 1 and 3
    const __m512d even23 = _mm512_unpacklo_pd(z2, z3);  // lanes 4..7
    const __m512d odd23 = _mm512_unpackhi_pd(z2, z3);
    const __m512i first = _mm512_set_epi64(13, 9, 12, 8, 5, 1, 4, 0);   // columns 0 and 1
    const __m512i second = _mm512_set_epi64(15, 11, 14, 10, 7, 3, 6, 2);  // columns 2 and 3
    out[0] = _mm512_permutex2var_pd(even01, first, even23);
    out[1] = _mm512_permutex2var_pd(odd01, first, odd23);
    out[2] = _mm512_permutex2var_pd(even01, second, even23);
    out[3] = _mm512_permutex2var_pd(odd01, second, odd23);
  }
};

}  // namespace nbv::kernels::detail
#endif  // NBV_EMULATE_AVX512
