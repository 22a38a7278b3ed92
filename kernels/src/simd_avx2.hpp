#pragma once
// Private, for the -mavx2 sources only: the lanes of a 4-ray packet, as the register types
// and operations the width-generic packet walks (ig_rays_packet.hpp) are written in. Every
// operation is one IEEE operation per lane, as its scalar counterpart, so a walk written in
// them gives the scalar walk's bits. simd_avx512.hpp has the same names for 8 lanes.

#include <immintrin.h>

#include <cstdint>

namespace nbv::kernels::detail {

struct Avx2Lanes {
  static constexpr int kLanes = 4;
  using D = __m256d;    ///< a double per lane
  using I = __m256i;    ///< a 64-bit integer per lane
  using M = __m256d;    ///< a lane mask: all bits set or clear per lane
  using F = __m128;     ///< a float per lane
  using O = __m256d;    ///< a byte offset per lane, as a double (see toOffsets())
  /// Border crossings a run takes per axis between two tests of whether it is over (the IG
  /// walk's runs; tuned on the bunny-3 full set: docs/PERFORMANCE.md, "Tried and dropped").
  static constexpr int kRunBlock = 4;

  static D load(const double* p) { return _mm256_load_pd(p); }
  static void store(double* p, D v) { _mm256_store_pd(p, v); }
  static I loadI(const std::int64_t* p) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(p)); }
  static void storeI(std::int64_t* p, I v) { _mm256_store_si256(reinterpret_cast<__m256i*>(p), v); }
  /// Masks kept in memory as 0 or -1 per lane.
  static M loadM(const std::int64_t* p) { return _mm256_castsi256_pd(loadI(p)); }
  static void storeM(std::int64_t* p, M m) { storeI(p, _mm256_castpd_si256(m)); }

  static D set1(double x) { return _mm256_set1_pd(x); }
  static I set1I(std::int64_t x) { return _mm256_set1_epi64x(x); }
  static D zero() { return _mm256_setzero_pd(); }

  static D add(D a, D b) { return _mm256_add_pd(a, b); }
  static D sub(D a, D b) { return _mm256_sub_pd(a, b); }
  static D mul(D a, D b) { return _mm256_mul_pd(a, b); }
  /// a < b ? a : b per lane (std::min(b, a), equal values included).
  static D min(D a, D b) { return _mm256_min_pd(a, b); }
  /// a > b ? a : b per lane.
  static D max(D a, D b) { return _mm256_max_pd(a, b); }
  static D div(D a, D b) { return _mm256_div_pd(a, b); }
  static D sqrt(D a) { return _mm256_sqrt_pd(a); }
  static D floor(D a) { return _mm256_floor_pd(a); }
  /// a rounded to the nearest integer (ties to even).
  static D round(D a) { return _mm256_round_pd(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC); }
  static D abs(D a) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a); }
  /// Single precision: IEEE float operations per lane, and the conversions (to double: exact).
  static F loadF(const float* p) { return _mm_load_ps(p); }
  static F set1F(float x) { return _mm_set1_ps(x); }
  static F addF(F a, F b) { return _mm_add_ps(a, b); }
  static F subF(F a, F b) { return _mm_sub_ps(a, b); }
  static F mulF(F a, F b) { return _mm_mul_ps(a, b); }
  static F divF(F a, F b) { return _mm_div_ps(a, b); }
  static D toDouble(F a) { return _mm256_cvtps_pd(a); }
  static F toSingle(D a) { return _mm256_cvtpd_ps(a); }

  static M lt(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_LT_OQ); }
  static M gt(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
  static M eq(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_EQ_OQ); }
  static M le(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_LE_OQ); }
  static M notM(M a) { return _mm256_xor_pd(a, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))); }
  static M both(M a, M b) { return _mm256_and_pd(a, b); }
  static M either(M a, M b) { return _mm256_or_pd(a, b); }
  /// b and not a.
  static M butNot(M a, M b) { return _mm256_andnot_pd(a, b); }

  /// m ? v : 0.
  static D zeroUnless(M m, D v) { return _mm256_and_pd(m, v); }
  /// a + (m ? b : 0) and a - (m ? b : 0): a lane outside m may read -0 as +0 (never matters
  /// to the walks, whose values there are border times and counts).
  static D addWhere(M m, D a, D b) { return _mm256_add_pd(a, _mm256_and_pd(m, b)); }
  static D subWhere(M m, D a, D b) { return _mm256_sub_pd(a, _mm256_and_pd(m, b)); }
  /// m ? a + b : 0.
  static D addOrZero(M m, D a, D b) { return _mm256_and_pd(m, _mm256_add_pd(a, b)); }
  /// a + (m ? 0 : b) and a - (m ? 0 : b).
  static D addUnless(M m, D a, D b) { return _mm256_add_pd(a, _mm256_andnot_pd(m, b)); }
  static D subUnless(M m, D a, D b) { return _mm256_sub_pd(a, _mm256_andnot_pd(m, b)); }
  /// m ? a : b.
  static D select(M m, D a, D b) { return _mm256_blendv_pd(b, a, m); }
  static I selectI(M m, I a, I b) { return _mm256_blendv_epi8(b, a, _mm256_castpd_si256(m)); }

  /// Byte offsets (exact integers below 2^31 in doubles) stay doubles: the masks are 64-bit
  /// lanes, and 32-bit offset lanes would need a mask conversion at every blend. add(),
  /// select() and eq() serve them.
  static O toOffsets(D offset) { return offset; }

  static I andI(I a, I b) { return _mm256_and_si256(a, b); }
  static I orI(I a, I b) { return _mm256_or_si256(a, b); }
  /// a >> shift, each lane by its own count.
  static I shiftRightI(I a, I shift) { return _mm256_srlv_epi64(a, shift); }
  static M eqI(I a, I b) { return _mm256_castsi256_pd(_mm256_cmpeq_epi64(a, b)); }
  /// (flags & bit) != 0 for a single-bit `bit`.
  static M has(I flags, I bit) { return eqI(andI(flags, bit), bit); }
  /// (flags & bits) == 0.
  static M hasNone(I flags, I bits) { return eqI(andI(flags, bits), _mm256_setzero_si256()); }
  /// Bits of double `d` as an integer lane and back.
  static I bitsOf(D d) { return _mm256_castpd_si256(d); }
  static D fromBits(I i) { return _mm256_castsi256_pd(i); }
  static I subI(I a, I b) { return _mm256_sub_epi64(a, b); }
  template <int kShift>
  static I shiftLeftI(I a) {
    return _mm256_slli_epi64(a, kShift);
  }

  /// Bit i of the result: lane i of m.
  static unsigned bits(M m) { return static_cast<unsigned>(_mm256_movemask_pd(m)); }
  /// The mask of the low kLanes bits of `lanes`.
  static M mask(unsigned lanes) {
    const __m256i bit = _mm256_set_epi64x(8, 4, 2, 1);
    const __m256i set = _mm256_and_si256(_mm256_set1_epi64x(static_cast<std::int64_t>(lanes)), bit);
    return _mm256_castsi256_pd(_mm256_cmpeq_epi64(set, bit));
  }

  /// The entries voxels[offset] of the lanes (offsets: doubles holding integers below 2^31),
  /// in e[] and as a vector. Scalar loads, not gathers (docs/PERFORMANCE.md, "Tried and dropped").
  static I loadEntries(const std::uint64_t* voxels, D offset, std::uint64_t e[kLanes]) {
    alignas(16) std::int32_t at[kLanes];
    offsets(offset, at);
    const std::uint64_t e0 = voxels[at[0]], e1 = voxels[at[1]], e2 = voxels[at[2]], e3 = voxels[at[3]];
    e[0] = e0;
    e[1] = e1;
    e[2] = e2;
    e[3] = e3;
    return _mm256_set_epi64x(static_cast<std::int64_t>(e3), static_cast<std::int64_t>(e2),
                             static_cast<std::int64_t>(e1), static_cast<std::int64_t>(e0));
  }

  /// The lanes' offsets (doubles holding integers below 2^31) as 32-bit integers.
  static void offsets(D offset, std::int32_t out[kLanes]) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_cvttpd_epi32(offset));
  }
  /// visit(base + offset) for the lanes of `lanes`, offsets as unsigned 32-bit values (which
  /// address without a sign extension). All four leave the register by extraction, not through
  /// memory (a 16-byte store forwarded to 4-byte loads stalls on some cores).
  template <class Visit>
  static void forEachAt(std::uint8_t* base, D offset, unsigned lanes, Visit&& visit) {
    const __m128i at = _mm256_cvttpd_epi32(offset);
    const auto byte = [base](int o) { return base + static_cast<std::uint32_t>(o); };
    if (lanes == 0xFu) {
      visit(byte(_mm_cvtsi128_si32(at)));
      visit(byte(_mm_extract_epi32(at, 1)));
      visit(byte(_mm_extract_epi32(at, 2)));
      visit(byte(_mm_extract_epi32(at, 3)));
      return;
    }
    alignas(16) std::int32_t o[kLanes];
    offsets(offset, o);
    for (unsigned left = lanes; left != 0; left &= left - 1) visit(byte(o[__builtin_ctz(left)]));
  }

  /// Rows of four doubles, row[i] for lane i, transposed: column c of every row in out[c].
  static void transposeRows(const double* const row[kLanes], D out[4]) {
    const __m256d r0 = _mm256_loadu_pd(row[0]), r1 = _mm256_loadu_pd(row[1]);
    const __m256d r2 = _mm256_loadu_pd(row[2]), r3 = _mm256_loadu_pd(row[3]);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    out[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
    out[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
    out[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
    out[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
  }
};

}  // namespace nbv::kernels::detail
