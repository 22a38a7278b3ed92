#pragma once
// Private to the tests: every operation of a lane type S (simd_avx2.hpp, simd_avx512.hpp)
// against EmulatedLanes of its width (simd_emulated.hpp), on lanes drawn from special values
// (signed zeros, infinities, NaNs, rounding ties, subnormals, the limits of 32-bit offsets)
// and random ones. Included after S's header, inside the target options of the source that
// instantiates it.

#include "lanes_check.hpp"
#include "simd_emulated.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace nbv::test {

/// How S's masked additions treat the lanes outside the mask: merge masking keeps them bit
/// for bit (AVX-512); adding a masked zero may turn -0 into +0 there (AVX2, as simd_avx2.hpp
/// states). Nothing else may differ but the sign and payload of a NaN that arithmetic on two
/// NaNs gives: the compiler may swap the operands of an addition or multiplication.
enum class OutsideLanes { Exact, SignOfZeroFree };

template <class S, OutsideLanes kOutside>
class LaneOpsCheck {
  static constexpr int kLanes = S::kLanes;
  static constexpr unsigned kAll = (1u << kLanes) - 1u;
  using R = kernels::detail::EmulatedLanes<kLanes>;
  template <class T>
  using Column = std::array<T, kLanes>;

 public:
  explicit LaneOpsCheck(std::uint32_t seed) : rng_(seed) {}

  /// One line per operation and lane that differs, over `rounds` draws of the inputs.
  std::vector<std::string> run(int rounds) {
    for (int r = 0; r < rounds && differences_.size() < 50; ++r) {
      draw();
      arithmetic();
      comparisonsAndMasks();
      maskedArithmetic();
      integerOps();
      offsetOps();
      memory();
    }
    return differences_;
  }

 private:
  void draw() {
    for (int i = 0; i < kLanes; ++i) {
      a_[i] = anyDouble();
      b_[i] = anyDouble();
      fa_[i] = static_cast<float>(anyDouble());
      fb_[i] = static_cast<float>(anyDouble());
      ia_[i] = anyInteger();
      ib_[i] = anyInteger();
      bit_[i] = static_cast<std::int64_t>(std::uint64_t{1} << (rng_() % 64));
      // Shift counts: mostly 0..69, some far out of range (negative ones read as huge).
      count_[i] = rng_() % 4 == 0 ? static_cast<std::int64_t>(rng_()) - (1ll << 31)
                                  : static_cast<std::int64_t>(rng_() % 70);
      at_[i] = static_cast<double>(rng_() % kTable);
      oa_[i] = anyOffset();
      ob_[i] = anyOffset();
    }
    m_ = rng_() & kAll;
    n_ = rng_() & kAll;
  }

  double anyDouble() {
    using Limits = std::numeric_limits<double>;
    static const double kSpecial[] = {0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 1.5, 2.5, -2.5, 3.5, 1.0 / 3.0,
                                      Limits::infinity(), -Limits::infinity(), Limits::quiet_NaN(),
                                      -Limits::quiet_NaN(), Limits::denorm_min(), -Limits::denorm_min(),
                                      Limits::min(), Limits::max(), 2147483647.0, 2147483648.0, -2147483648.0,
                                      -2147483649.0, 4503599627370496.0, 4503599627370495.5, 1e300, -1e-300,
                                      3.4e38, 1e39};
    switch (rng_() % 3) {
      case 0:
        return kSpecial[rng_() % std::size(kSpecial)];
      case 1:
        return std::uniform_real_distribution<double>(-1e3, 1e3)(rng_);
      default:  // integers and halves, where rounding ties
        return static_cast<double>(static_cast<int>(rng_() % 4001) - 2000) * 0.5;
    }
  }

  std::int64_t anyInteger() {
    static const std::int64_t kSpecial[] = {0, 1, -1, std::numeric_limits<std::int64_t>::min(),
                                            std::numeric_limits<std::int64_t>::max(), 1ll << 52, 0x7FF0000000000000ll};
    if (rng_() % 3 == 0) return kSpecial[rng_() % std::size(kSpecial)];
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(rng_()) << 32) | rng_());
  }

  /// A byte offset or offset step as the packet walks carry it: an integer in a double, here
  /// within +-2^30 so that the sum of two fits 32 bits.
  double anyOffset() {
    static const double kSpecial[] = {0.0, 1.0, -1.0, 1073741823.0, -1073741823.0, 1073741824.0, -1073741824.0};
    if (rng_() % 4 == 0) return kSpecial[rng_() % std::size(kSpecial)];
    return static_cast<double>(static_cast<std::int32_t>(rng_()) / 2);
  }

  /// What may differ besides the bits: the sign of a zero in some lanes, which NaN.
  struct Loose {
    unsigned zero_sign_lanes = 0;
    bool any_nan = false;
  };
  static constexpr Loose kArithmetic{0, true};

  /// Lane i of got and want: equal bits, or what `loose` lets differ.
  void compare(const char* op, const Column<double>& got, const Column<double>& want, Loose loose = {}) {
    for (int i = 0; i < kLanes; ++i) {
      if (std::bit_cast<std::uint64_t>(got[i]) == std::bit_cast<std::uint64_t>(want[i])) continue;
      if (((loose.zero_sign_lanes >> i) & 1u) != 0 && got[i] == 0.0 && want[i] == 0.0) continue;
      if (loose.any_nan && std::isnan(got[i]) && std::isnan(want[i])) continue;
      std::ostringstream what;
      what << std::hexfloat << got[i] << " instead of " << want[i];
      note(op, i, what.str());
    }
  }
  /// Integer lanes (64-bit lanes, 32-bit offsets, gathered entries): equal.
  template <class T>
  void compare(const char* op, const Column<T>& got, const Column<T>& want) {
    static_assert(std::is_integral_v<T>);
    for (int i = 0; i < kLanes; ++i) {
      if (got[i] != want[i]) note(op, i, std::to_string(got[i]) + " instead of " + std::to_string(want[i]));
    }
  }
  void compareMask(const char* op, unsigned got, unsigned want) {
    if (got != want) note(op, -1, "mask " + std::to_string(got) + " instead of " + std::to_string(want));
  }
  /// One line: the operation, the lane (-1: the whole mask), what differs, and the inputs.
  void note(const char* op, int lane, const std::string& what) {
    std::ostringstream line;
    line << op << " lane " << lane << ": " << what << "; a/b:" << std::hexfloat;
    for (int i = 0; i < kLanes; ++i) line << ' ' << a_[i] << '/' << b_[i];
    line << "; masks " << m_ << ", " << n_;
    differences_.push_back(line.str());
  }

  /// An operation giving doubles, run as S and as R: `f.template operator()<L>()`.
  template <class Op>
  void doubles(const char* name, Op f, Loose loose = {}) {
    alignas(64) Column<double> got, want;
    S::store(got.data(), f.template operator()<S>());
    R::store(want.data(), f.template operator()<R>());
    compare(name, got, want, loose);
  }
  template <class Op>
  void integers(const char* name, Op f) {
    alignas(64) Column<std::int64_t> got, want;
    S::storeI(got.data(), f.template operator()<S>());
    R::storeI(want.data(), f.template operator()<R>());
    compare(name, got, want);
  }
  template <class Op>
  void masks(const char* name, Op f) {
    compareMask(name, S::bits(f.template operator()<S>()), R::bits(f.template operator()<R>()));
  }
  /// An operation giving offset lanes (S::O), compared as 32-bit integers.
  template <class Op>
  void offsetLanes(const char* name, Op f) {
    alignas(64) Column<std::int32_t> got, want;
    S::offsets(f.template operator()<S>(), got.data());
    R::offsets(f.template operator()<R>(), want.data());
    compare(name, got, want);
  }
  /// Floats, compared through the exact conversion to double (itself checked on loadF()).
  template <class Op>
  void floats(const char* name, Op f, Loose loose = {}) {
    doubles(name, [&]<class L>() { return L::toDouble(f.template operator()<L>()); }, loose);
  }

  void arithmetic() {
    doubles("load/store", [&]<class L>() { return L::load(a_.data()); });
    doubles("set1", [&]<class L>() { return L::set1(a_[0]); });
    doubles("zero", []<class L>() { return L::zero(); });
    doubles("add", [&]<class L>() { return L::add(L::load(a_.data()), L::load(b_.data())); }, kArithmetic);
    doubles("sub", [&]<class L>() { return L::sub(L::load(a_.data()), L::load(b_.data())); }, kArithmetic);
    doubles("mul", [&]<class L>() { return L::mul(L::load(a_.data()), L::load(b_.data())); }, kArithmetic);
    doubles("div", [&]<class L>() { return L::div(L::load(a_.data()), L::load(b_.data())); }, kArithmetic);
    doubles("min", [&]<class L>() { return L::min(L::load(a_.data()), L::load(b_.data())); });
    doubles("max", [&]<class L>() { return L::max(L::load(a_.data()), L::load(b_.data())); });
    doubles("sqrt", [&]<class L>() { return L::sqrt(L::load(a_.data())); });
    doubles("floor", [&]<class L>() { return L::floor(L::load(a_.data())); });
    doubles("round", [&]<class L>() { return L::round(L::load(a_.data())); });
    doubles("abs", [&]<class L>() { return L::abs(L::load(a_.data())); });
    floats("loadF/toDouble", [&]<class L>() { return L::loadF(fa_.data()); });
    floats("set1F", [&]<class L>() { return L::set1F(fa_[0]); });
    floats("addF", [&]<class L>() { return L::addF(L::loadF(fa_.data()), L::loadF(fb_.data())); }, kArithmetic);
    floats("subF", [&]<class L>() { return L::subF(L::loadF(fa_.data()), L::loadF(fb_.data())); }, kArithmetic);
    floats("mulF", [&]<class L>() { return L::mulF(L::loadF(fa_.data()), L::loadF(fb_.data())); }, kArithmetic);
    floats("divF", [&]<class L>() { return L::divF(L::loadF(fa_.data()), L::loadF(fb_.data())); }, kArithmetic);
    floats("toSingle", [&]<class L>() { return L::toSingle(L::load(a_.data())); });
  }

  void comparisonsAndMasks() {
    masks("lt", [&]<class L>() { return L::lt(L::load(a_.data()), L::load(b_.data())); });
    masks("gt", [&]<class L>() { return L::gt(L::load(a_.data()), L::load(b_.data())); });
    masks("eq", [&]<class L>() { return L::eq(L::load(a_.data()), L::load(b_.data())); });
    masks("le", [&]<class L>() { return L::le(L::load(a_.data()), L::load(b_.data())); });
    compareMask("mask/bits", S::bits(S::mask(m_)), m_);
    masks("notM", [&]<class L>() { return L::notM(L::mask(m_)); });
    masks("both", [&]<class L>() { return L::both(L::mask(m_), L::mask(n_)); });
    masks("either", [&]<class L>() { return L::either(L::mask(m_), L::mask(n_)); });
    masks("butNot", [&]<class L>() { return L::butNot(L::mask(m_), L::mask(n_)); });
  }

  void maskedArithmetic() {
    const bool sign_free = kOutside == OutsideLanes::SignOfZeroFree;
    const Loose outside{sign_free ? ~m_ & kAll : 0u, true}, inside{sign_free ? m_ : 0u, true};
    doubles("zeroUnless", [&]<class L>() { return L::zeroUnless(L::mask(m_), L::load(a_.data())); });
    doubles("addWhere", [&]<class L>() { return L::addWhere(L::mask(m_), L::load(a_.data()), L::load(b_.data())); },
            outside);
    doubles("subWhere", [&]<class L>() { return L::subWhere(L::mask(m_), L::load(a_.data()), L::load(b_.data())); },
            outside);
    doubles("addOrZero", [&]<class L>() { return L::addOrZero(L::mask(m_), L::load(a_.data()), L::load(b_.data())); },
            kArithmetic);
    doubles("addUnless", [&]<class L>() { return L::addUnless(L::mask(m_), L::load(a_.data()), L::load(b_.data())); },
            inside);
    doubles("subUnless", [&]<class L>() { return L::subUnless(L::mask(m_), L::load(a_.data()), L::load(b_.data())); },
            inside);
    doubles("select", [&]<class L>() { return L::select(L::mask(m_), L::load(a_.data()), L::load(b_.data())); });
    integers("selectI", [&]<class L>() { return L::selectI(L::mask(m_), L::loadI(ia_.data()), L::loadI(ib_.data())); });
  }

  void integerOps() {
    integers("loadI/storeI", [&]<class L>() { return L::loadI(ia_.data()); });
    integers("set1I", [&]<class L>() { return L::set1I(ia_[0]); });
    integers("subI", [&]<class L>() { return L::subI(L::loadI(ia_.data()), L::loadI(ib_.data())); });
    integers("andI", [&]<class L>() { return L::andI(L::loadI(ia_.data()), L::loadI(ib_.data())); });
    integers("orI", [&]<class L>() { return L::orI(L::loadI(ia_.data()), L::loadI(ib_.data())); });
    integers("shiftRightI", [&]<class L>() { return L::shiftRightI(L::loadI(ia_.data()), L::loadI(count_.data())); });
    integers("shiftLeftI<3>", [&]<class L>() { return L::template shiftLeftI<3>(L::loadI(ia_.data())); });
    integers("shiftLeftI<52>", [&]<class L>() { return L::template shiftLeftI<52>(L::loadI(ia_.data())); });
    integers("bitsOf", [&]<class L>() { return L::bitsOf(L::load(a_.data())); });
    doubles("fromBits", [&]<class L>() { return L::fromBits(L::loadI(ia_.data())); });
    masks("eqI", [&]<class L>() {  // equal in the lanes of m_
      return L::eqI(L::loadI(ia_.data()), L::selectI(L::mask(m_), L::loadI(ia_.data()), L::loadI(ib_.data())));
    });
    masks("has", [&]<class L>() { return L::has(L::loadI(ia_.data()), L::loadI(bit_.data())); });
    masks("hasNone", [&]<class L>() { return L::hasNone(L::loadI(ia_.data()), L::loadI(ib_.data())); });
  }

  /// The offset lanes of the mark walk, whose type differs by width (doubles for AVX2).
  void offsetOps() {
    offsetLanes("toOffsets", [&]<class L>() { return L::toOffsets(L::load(oa_.data())); });
    offsetLanes("add (offsets)", [&]<class L>() {
      return L::add(L::toOffsets(L::load(oa_.data())), L::toOffsets(L::load(ob_.data())));
    });
    offsetLanes("select (offsets)", [&]<class L>() {
      return L::select(L::mask(m_), L::toOffsets(L::load(oa_.data())), L::toOffsets(L::load(ob_.data())));
    });
    masks("eq (offsets)", [&]<class L>() {  // equal in the lanes of m_ and where oa_ and ob_ agree
      const typename L::O a = L::toOffsets(L::load(oa_.data()));
      return L::eq(a, L::select(L::mask(m_), a, L::toOffsets(L::load(ob_.data()))));
    });
  }

  /// Masks kept in memory, offsets, gathers, the visit of lanes' bytes and the transposition.
  void memory() {
    alignas(64) Column<std::int64_t> stored_s, stored_r;
    S::storeM(stored_s.data(), S::mask(m_));
    R::storeM(stored_r.data(), R::mask(m_));
    compare("storeM", stored_s, stored_r);
    compareMask("loadM", S::bits(S::loadM(stored_r.data())), m_);

    alignas(64) Column<std::int32_t> at_s, at_r;
    S::offsets(S::load(a_.data()), at_s.data());
    R::offsets(R::load(a_.data()), at_r.data());
    compare("offsets", at_s, at_r);

    std::uint64_t table[kTable];
    for (std::uint64_t& t : table) t = (static_cast<std::uint64_t>(rng_()) << 32) | rng_();
    Column<std::uint64_t> e_s, e_r;
    alignas(64) Column<std::int64_t> v_s, v_r;
    S::storeI(v_s.data(), S::loadEntries(table, S::load(at_.data()), e_s.data()));
    R::storeI(v_r.data(), R::loadEntries(table, R::load(at_.data()), e_r.data()));
    compare("loadEntries", v_s, v_r);
    compare("loadEntries e[]", e_s, e_r);

    std::uint8_t bytes[kTable];
    for (const unsigned lanes : {m_, kAll}) {
      std::vector<std::uint8_t*> visited_s, visited_r;
      S::forEachAt(bytes, S::toOffsets(S::load(at_.data())), lanes, [&](std::uint8_t* p) { visited_s.push_back(p); });
      R::forEachAt(bytes, R::toOffsets(R::load(at_.data())), lanes, [&](std::uint8_t* p) { visited_r.push_back(p); });
      if (visited_s != visited_r) note("forEachAt", -1, "other bytes or order");
    }

    double rows[kLanes][4];
    const double* row[kLanes];
    for (int i = 0; i < kLanes; ++i) {
      for (double& x : rows[i]) x = anyDouble();
      row[i] = rows[i];
    }
    typename S::D out_s[4];
    typename R::D out_r[4];
    S::transposeRows(row, out_s);
    R::transposeRows(row, out_r);
    for (int c = 0; c < 4; ++c) {
      alignas(64) Column<double> got, want;
      S::store(got.data(), out_s[c]);
      R::store(want.data(), out_r[c]);
      compare("transposeRows", got, want);
    }
  }

  static constexpr int kTable = 64;
  std::mt19937 rng_;
  alignas(64) Column<double> a_{}, b_{}, at_{}, oa_{}, ob_{};
  alignas(64) Column<float> fa_{}, fb_{};
  alignas(64) Column<std::int64_t> ia_{}, ib_{}, bit_{}, count_{};
  unsigned m_ = 0, n_ = 0;
  std::vector<std::string> differences_;
};

}  // namespace nbv::test
