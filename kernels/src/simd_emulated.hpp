#pragma once
// Private: the lanes of simd_avx512.hpp in plain C++ (kWidth of them: 8 as AVX-512, 4 for the
// lane-ops test beside simd_avx2.hpp), one loop over the lanes per operation. Each lane is
// computed as the AVX-512 instruction computes it: masks are bits, with merge and zero masking;
// min/max take the second operand unless the first is below (above) it; truncating conversions
// give INT32_MIN out of range; shifts of 64 or more give 0. NBV_EMULATE_AVX512 builds the
// AVX-512 walks over these lanes, so that their width and bit masks run and are checked on a
// CPU without AVX-512; the lane-ops test checks the intrinsics against them where the CPU has
// AVX-512. Slow: never for real work.

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace nbv::kernels::detail {

template <int kWidth>
struct EmulatedLanes {
  static_assert(kWidth == 4 || kWidth == 8);
  static constexpr int kLanes = kWidth;
  struct alignas(8 * kLanes) D {
    double v[kLanes];
  };
  struct alignas(8 * kLanes) I {
    std::int64_t v[kLanes];
  };
  using M = std::uint8_t;  ///< bit i: lane i, as __mmask8; the bits above kLanes stay clear
  struct alignas(4 * kLanes) F {
    float v[kLanes];
  };
  /// A byte offset per lane as a 32-bit integer, as the AVX-512 walk's offset lanes.
  struct alignas(4 * kLanes) O {
    std::int32_t v[kLanes];
  };
  /// As the hardware lanes of this width (simd_avx512.hpp, simd_avx2.hpp), so that the walks
  /// take their path.
  static constexpr int kRunBlock = kWidth == 8 ? 6 : 4;
  static constexpr unsigned kAllLanes = (1u << kLanes) - 1u;

  static D load(const double* p) {
    return each<D>([p](int i) { return p[i]; });
  }
  static void store(double* p, D v) {
    for (int i = 0; i < kLanes; ++i) p[i] = v.v[i];
  }
  static I loadI(const std::int64_t* p) {
    return each<I>([p](int i) { return p[i]; });
  }
  static void storeI(std::int64_t* p, I v) {
    for (int i = 0; i < kLanes; ++i) p[i] = v.v[i];
  }
  /// _mm512_movepi64_mask: the sign bits. _mm512_movm_epi64: -1 or 0 per lane.
  static M loadM(const std::int64_t* p) {
    return maskOf([p](int i) { return p[i] < 0; });
  }
  static void storeM(std::int64_t* p, M m) {
    for (int i = 0; i < kLanes; ++i) p[i] = in(m, i) ? -1 : 0;
  }

  static D set1(double x) {
    return each<D>([x](int) { return x; });
  }
  static I set1I(std::int64_t x) {
    return each<I>([x](int) { return x; });
  }
  static D zero() { return set1(0.0); }

  static D add(D a, D b) {
    return each<D>([&](int i) { return a.v[i] + b.v[i]; });
  }
  static D sub(D a, D b) {
    return each<D>([&](int i) { return a.v[i] - b.v[i]; });
  }
  static D mul(D a, D b) {
    return each<D>([&](int i) { return a.v[i] * b.v[i]; });
  }
  static D div(D a, D b) {
    return each<D>([&](int i) { return a.v[i] / b.v[i]; });
  }
  /// VMINPD / VMAXPD: the first operand only where it is below (above) the second.
  static D min(D a, D b) {
    return each<D>([&](int i) { return a.v[i] < b.v[i] ? a.v[i] : b.v[i]; });
  }
  static D max(D a, D b) {
    return each<D>([&](int i) { return a.v[i] > b.v[i] ? a.v[i] : b.v[i]; });
  }
  static D sqrt(D a) {
    return each<D>([&](int i) { return std::sqrt(a.v[i]); });
  }
  static D floor(D a) {
    return each<D>([&](int i) { return std::floor(a.v[i]); });
  }
  /// Ties to even, as VRNDSCALEPD under the default rounding mode.
  static D round(D a) {
    return each<D>([&](int i) { return std::nearbyint(a.v[i]); });
  }
  static D abs(D a) {
    return each<D>([&](int i) { return std::fabs(a.v[i]); });
  }
  static F loadF(const float* p) {
    return each<F>([p](int i) { return p[i]; });
  }
  static F set1F(float x) {
    return each<F>([x](int) { return x; });
  }
  static F addF(F a, F b) {
    return each<F>([&](int i) { return a.v[i] + b.v[i]; });
  }
  static F subF(F a, F b) {
    return each<F>([&](int i) { return a.v[i] - b.v[i]; });
  }
  static F mulF(F a, F b) {
    return each<F>([&](int i) { return a.v[i] * b.v[i]; });
  }
  static F divF(F a, F b) {
    return each<F>([&](int i) { return a.v[i] / b.v[i]; });
  }
  static D toDouble(F a) {
    return each<D>([&](int i) { return static_cast<double>(a.v[i]); });
  }
  static F toSingle(D a) {
    return each<F>([&](int i) { return static_cast<float>(a.v[i]); });
  }

  /// Ordered comparisons: false where either lane is NaN.
  static M lt(D a, D b) {
    return maskOf([&](int i) { return a.v[i] < b.v[i]; });
  }
  static M gt(D a, D b) {
    return maskOf([&](int i) { return a.v[i] > b.v[i]; });
  }
  static M eq(D a, D b) {
    return maskOf([&](int i) { return a.v[i] == b.v[i]; });
  }
  static M le(D a, D b) {
    return maskOf([&](int i) { return a.v[i] <= b.v[i]; });
  }
  static M notM(M a) { return static_cast<M>(~a & kAllLanes); }
  static M both(M a, M b) { return static_cast<M>(a & b); }
  static M either(M a, M b) { return static_cast<M>(a | b); }
  /// b and not a (KANDNB).
  static M butNot(M a, M b) { return static_cast<M>(~a & b & kAllLanes); }

  /// Zero masking (m ? v : +0) and merge masking (lanes outside m keep a, bit for bit).
  static D zeroUnless(M m, D v) {
    return each<D>([&](int i) { return in(m, i) ? v.v[i] : 0.0; });
  }
  static D addWhere(M m, D a, D b) {
    return each<D>([&](int i) { return in(m, i) ? a.v[i] + b.v[i] : a.v[i]; });
  }
  static D subWhere(M m, D a, D b) {
    return each<D>([&](int i) { return in(m, i) ? a.v[i] - b.v[i] : a.v[i]; });
  }
  static D addOrZero(M m, D a, D b) {
    return each<D>([&](int i) { return in(m, i) ? a.v[i] + b.v[i] : 0.0; });
  }
  static D addUnless(M m, D a, D b) { return addWhere(notM(m), a, b); }
  static D subUnless(M m, D a, D b) { return subWhere(notM(m), a, b); }
  static D select(M m, D a, D b) {
    return each<D>([&](int i) { return in(m, i) ? a.v[i] : b.v[i]; });
  }
  static I selectI(M m, I a, I b) {
    return each<I>([&](int i) { return in(m, i) ? a.v[i] : b.v[i]; });
  }

  /// VCVTTPD2DQ (see offsets()); VPADDD wraps; VPBLENDMD; VPCMPEQD.
  static O toOffsets(D offset) {
    O out;
    offsets(offset, out.v);
    return out;
  }
  static O add(O a, O b) {
    return each<O>([&](int i) {
      return static_cast<std::int32_t>(static_cast<std::uint32_t>(a.v[i]) + static_cast<std::uint32_t>(b.v[i]));
    });
  }
  static O select(M m, O a, O b) {
    return each<O>([&](int i) { return in(m, i) ? a.v[i] : b.v[i]; });
  }
  static M eq(O a, O b) {
    return maskOf([&](int i) { return a.v[i] == b.v[i]; });
  }

  static M eqI(I a, I b) {
    return maskOf([&](int i) { return a.v[i] == b.v[i]; });
  }
  /// VPTESTMQ and VPTESTNMQ.
  static M has(I flags, I bit) {
    return maskOf([&](int i) { return (flags.v[i] & bit.v[i]) != 0; });
  }
  static M hasNone(I flags, I bits) {
    return maskOf([&](int i) { return (flags.v[i] & bits.v[i]) == 0; });
  }
  static I bitsOf(D d) {
    return each<I>([&](int i) { return std::bit_cast<std::int64_t>(d.v[i]); });
  }
  static D fromBits(I b) {
    return each<D>([&](int i) { return std::bit_cast<double>(b.v[i]); });
  }
  /// Integer lanes wrap, as the instructions do (computed unsigned: no signed overflow).
  static I subI(I a, I b) {
    return each<I>([&](int i) { return static_cast<std::int64_t>(unsigned64(a.v[i]) - unsigned64(b.v[i])); });
  }
  static I andI(I a, I b) {
    return each<I>([&](int i) { return a.v[i] & b.v[i]; });
  }
  static I orI(I a, I b) {
    return each<I>([&](int i) { return a.v[i] | b.v[i]; });
  }
  /// VPSRLVQ: logical, 0 for a count of 64 or more.
  static I shiftRightI(I a, I shift) {
    return each<I>([&](int i) {
      const std::uint64_t count = unsigned64(shift.v[i]);
      return count > 63 ? std::int64_t{0} : static_cast<std::int64_t>(unsigned64(a.v[i]) >> count);
    });
  }
  template <int kShift>
  static I shiftLeftI(I a) {
    static_assert(kShift >= 0 && kShift < 64);
    return each<I>([&](int i) { return static_cast<std::int64_t>(unsigned64(a.v[i]) << kShift); });
  }

  static unsigned bits(M m) { return m; }
  static M mask(unsigned lanes) { return static_cast<M>(lanes & kAllLanes); }

  /// The entries voxels[offset] of the lanes, in e[] and as a vector.
  static I loadEntries(const std::uint64_t* voxels, D offset, std::uint64_t e[kLanes]) {
    std::int32_t at[kLanes];
    offsets(offset, at);
    return each<I>([&](int i) {
      e[i] = voxels[at[i]];
      return static_cast<std::int64_t>(e[i]);
    });
  }
  /// VCVTTPD2DQ: truncated toward zero; NaN and values out of range give INT32_MIN.
  static void offsets(D offset, std::int32_t out[kLanes]) {
    for (int i = 0; i < kLanes; ++i) {
      const double x = offset.v[i];
      const bool fits = x > -2147483649.0 && x < 2147483648.0;  // false for NaN
      out[i] = fits ? static_cast<std::int32_t>(x) : std::numeric_limits<std::int32_t>::min();
    }
  }
  static void offsets(O offset, std::int32_t out[kLanes]) {
    for (int i = 0; i < kLanes; ++i) out[i] = offset.v[i];
  }
  template <class Visit>
  static void forEachAt(std::uint8_t* base, O offset, unsigned lanes, Visit&& visit) {
    for (int i = 0; i < kLanes; ++i) {
      if (((lanes >> i) & 1u) != 0) visit(base + static_cast<std::uint32_t>(offset.v[i]));
    }
  }
  static void transposeRows(const double* const row[kLanes], D out[4]) {
    for (int c = 0; c < 4; ++c) out[c] = each<D>([&](int i) { return row[i][c]; });
  }

 private:
  /// The lanes op(0), ..., op(kLanes - 1); the mask of the lanes where test(i) holds.
  template <class T, class Op>
  static T each(Op op) {
    T out;
    for (int i = 0; i < kLanes; ++i) out.v[i] = op(i);
    return out;
  }
  template <class Test>
  static M maskOf(Test test) {
    unsigned m = 0;
    for (int i = 0; i < kLanes; ++i) m |= (test(i) ? 1u : 0u) << i;
    return static_cast<M>(m);
  }
  static bool in(M m, int lane) { return ((m >> lane) & 1u) != 0; }
  static std::uint64_t unsigned64(std::int64_t x) { return static_cast<std::uint64_t>(x); }
};

using EmulatedAvx512Lanes = EmulatedLanes<8>;

}  // namespace nbv::kernels::detail
