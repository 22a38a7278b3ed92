#pragma once
// Private: value types over the lanes of a register type S (simd_avx2.hpp, simd_avx512.hpp,
// simd_emulated.hpp) with the scalar code's operators, so that a packet walk reads as the
// scalar walk it repeats lane by lane: a + b is S::add(a, b), a < b is S::lt(a, b), m & n is
// S::both(m, n), ~m is S::notM(m). Each operator and function is one function of S, so the walk performs the
// same operations, in the same order, as when it called them by name: the same bits.
// Each type converts from and to S's own, so that S's functions and the lanes' DDA take them.
// Included inside the target options of the source that instantiates it, as S is.

#include <cstdint>

namespace nbv::kernels::detail {

/// A flag per lane (S::M: a mask register, or a lane of all ones or zeros).
template <class S>
struct LaneMask {
  typename S::M raw;

  LaneMask() = default;
  LaneMask(typename S::M m) : raw(m) {}  // NOLINT(google-explicit-constructor): S's results
  operator typename S::M() const { return raw; }  // NOLINT: S's arguments
  /// The lanes of the bits set in `lanes` (bit i: lane i).
  static LaneMask of(unsigned lanes) { return S::mask(lanes); }
  /// Bit i set where lane i is.
  unsigned bits() const { return S::bits(raw); }
};

/// A 64-bit integer per lane (S::I).
template <class S>
struct LaneInts {
  typename S::I raw;

  LaneInts() = default;
  LaneInts(typename S::I i) : raw(i) {}  // NOLINT(google-explicit-constructor)
  operator typename S::I() const { return raw; }  // NOLINT
  /// `x` in every lane.
  explicit LaneInts(std::int64_t x) : raw(S::set1I(x)) {}
};

/// A double per lane (S::D).
template <class S>
struct LaneDoubles {
  typename S::D raw;

  LaneDoubles() = default;
  LaneDoubles(typename S::D d) : raw(d) {}  // NOLINT(google-explicit-constructor)
  operator typename S::D() const { return raw; }  // NOLINT
  /// `x` in every lane.
  explicit LaneDoubles(double x) : raw(S::set1(x)) {}
  LaneDoubles& operator+=(LaneDoubles b) { return *this = S::add(raw, b.raw); }
  LaneDoubles& operator-=(LaneDoubles b) { return *this = S::sub(raw, b.raw); }
  LaneDoubles& operator*=(LaneDoubles b) { return *this = S::mul(raw, b.raw); }
};

// The operators and functions, as function templates: they take the lane types alone
// (deduction converts nothing), so that an expression mixing them with S's own types is an
// error, not a choice between these and the compiler's operators on vector types. Each is one
// function of S.
#define NBV_LANE_UNARY(Result, name, Operand, function) \
  template <class S>                                    \
  Result<S> name(Operand<S> a) {                        \
    return S::function(a.raw);                          \
  }
#define NBV_LANE_BINARY(Result, name, Operand, function) \
  template <class S>                                     \
  Result<S> name(Operand<S> a, Operand<S> b) {           \
    return S::function(a.raw, b.raw);                    \
  }
// A masked operation: m ? a + b : a (addWhere: the other lanes keep a), m ? a - b : a
// (subWhere), m ? a : a + b (addUnless), m ? a : a - b (subUnless), m ? a + b : 0 (addOrZero),
// m ? a : b (select).
#define NBV_LANE_MASKED(Result, name, function)                     \
  template <class S>                                                \
  Result<S> name(LaneMask<S> m, Result<S> a, Result<S> b) {         \
    return S::function(m.raw, a.raw, b.raw);                        \
  }

NBV_LANE_BINARY(LaneMask, operator&, LaneMask, both)
NBV_LANE_BINARY(LaneMask, operator|, LaneMask, either)
NBV_LANE_UNARY(LaneMask, operator~, LaneMask, notM)
NBV_LANE_BINARY(LaneInts, operator-, LaneInts, subI)
NBV_LANE_BINARY(LaneInts, operator&, LaneInts, andI)
NBV_LANE_BINARY(LaneInts, operator|, LaneInts, orI)
NBV_LANE_BINARY(LaneInts, operator>>, LaneInts, shiftRightI)  // logical, by each lane's count
NBV_LANE_BINARY(LaneMask, operator==, LaneInts, eqI)
NBV_LANE_BINARY(LaneDoubles, operator+, LaneDoubles, add)
NBV_LANE_BINARY(LaneDoubles, operator-, LaneDoubles, sub)
NBV_LANE_BINARY(LaneDoubles, operator*, LaneDoubles, mul)
NBV_LANE_BINARY(LaneDoubles, operator/, LaneDoubles, div)
// Ordered comparisons: false in a lane holding a NaN, as the scalar ones.
NBV_LANE_BINARY(LaneMask, operator<, LaneDoubles, lt)
NBV_LANE_BINARY(LaneMask, operator>, LaneDoubles, gt)
NBV_LANE_BINARY(LaneMask, operator<=, LaneDoubles, le)
NBV_LANE_BINARY(LaneMask, operator==, LaneDoubles, eq)

NBV_LANE_MASKED(LaneDoubles, select, select)
NBV_LANE_MASKED(LaneInts, select, selectI)
NBV_LANE_MASKED(LaneDoubles, addWhere, addWhere)
NBV_LANE_MASKED(LaneDoubles, subWhere, subWhere)
NBV_LANE_MASKED(LaneDoubles, addUnless, addUnless)
NBV_LANE_MASKED(LaneDoubles, subUnless, subUnless)
NBV_LANE_MASKED(LaneDoubles, addOrZero, addOrZero)

// std::min(a, b) and std::max(a, b): the second operand unless the first is below (above) it.
NBV_LANE_BINARY(LaneDoubles, min, LaneDoubles, min)
NBV_LANE_BINARY(LaneDoubles, max, LaneDoubles, max)
NBV_LANE_UNARY(LaneDoubles, abs, LaneDoubles, abs)
NBV_LANE_UNARY(LaneDoubles, floor, LaneDoubles, floor)
NBV_LANE_UNARY(LaneDoubles, round, LaneDoubles, round)  // to nearest, ties to even (std::nearbyint)
// The bits of a double as an integer, and back (std::bit_cast).
NBV_LANE_UNARY(LaneInts, bitsOf, LaneDoubles, bitsOf)
NBV_LANE_UNARY(LaneDoubles, fromBits, LaneInts, fromBits)
// (flags & bit) != 0 and (flags & bits) == 0.
NBV_LANE_BINARY(LaneMask, has, LaneInts, has)
NBV_LANE_BINARY(LaneMask, hasNone, LaneInts, hasNone)

#undef NBV_LANE_UNARY
#undef NBV_LANE_BINARY
#undef NBV_LANE_MASKED

/// a & ~b in one operation.
template <class S>
LaneMask<S> andNot(LaneMask<S> a, LaneMask<S> b) {
  return S::butNot(b.raw, a.raw);
}
/// m ? a : 0.
template <class S>
LaneDoubles<S> zeroUnless(LaneMask<S> m, LaneDoubles<S> a) {
  return S::zeroUnless(m.raw, a.raw);
}
/// a << kBits in each lane.
template <int kBits, class S>
LaneInts<S> shiftLeft(LaneInts<S> a) {
  return S::template shiftLeftI<kBits>(a.raw);
}

}  // namespace nbv::kernels::detail
