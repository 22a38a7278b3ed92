#pragma once
/// \file Volumetric information (SEMANTICS.md "Volumetric information", paper Sec. 2): the terms of one voxel, the sums of
/// one ray, the sums of one view, and the metric values made from them.
///
/// One set of definitions serves every evaluator: the OctoMap reference evaluator (grid/),
/// the scalar snapshot walk and the packet walks (ig_rays.hpp) all feed voxels, in ray
/// order, into a RayAccumulator or into its lane-wise copy, whose arithmetic is the same
/// operation for operation.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace nbv::kernels {

/// How visibility decays along a ray (SEMANTICS.md "Volumetric information").
enum class Visibility {
  Paper,     ///< Eq. 5: P_v(x_{i+1}) = P_v(x_i) * (1 - P_o(x_i)); the default
  Released,  ///< the released code's P_v(x_{i+1}) = P_v(x_i) * P_o(x_i) (its issue #9)
};

/// The metrics of SEMANTICS.md "Volumetric information", in the order of its table.
enum class Metric : std::uint8_t {
  Entropy,          ///< `entropy`, Eq. 3
  OcclusionAware,   ///< `oa`, Eq. 6
  UnobservedVoxel,  ///< `uv`, Eq. 8
  RearSideVoxel,    ///< `rsv`, Eq. 9
  RearSideEntropy,  ///< `rse`, Eq. 10
  ProximityCount,   ///< `pc`, Eq. 11
  AreaFactor,       ///< `vg`, Eqs. 17-20
  AverageEntropy,   ///< `kr`, Eq. 4
  Random,           ///< `random`: a seeded uniform score, the planner's baseline
};
inline constexpr std::size_t kMetricCount = 9;

/// Every metric, in the order of SEMANTICS.md "Volumetric information".
inline constexpr std::array<Metric, kMetricCount> kAllMetrics = {
    Metric::Entropy,        Metric::OcclusionAware, Metric::UnobservedVoxel,
    Metric::RearSideVoxel,  Metric::RearSideEntropy, Metric::ProximityCount,
    Metric::AreaFactor,     Metric::AverageEntropy, Metric::Random};

/// The short name ("entropy", "oa", "uv", "rsv", "rse", "pc", "vg", "kr", "random").
const char* metricName(Metric metric);
/// The metric of a short name; empty if there is none.
std::optional<Metric> metricFromName(std::string_view name);

/// "paper" or "released".
const char* visibilityName(Visibility visibility);
/// The visibility named "paper" or "released". \throws InvalidArgument for another name.
Visibility visibilityFromName(std::string_view name);

/// What the per-voxel terms depend on besides the voxel. Defaults: SEMANTICS.md "The map", "Volumetric information".
struct VoxelModel {
  double occupied_threshold = 0.8;  ///< class occupied: P_o above this
  double free_threshold = 0.2;      ///< class free: P_o below this
  double proximity_max = 60.0;      ///< M of Eq. 11: 2 * proximity_range / resolution
  Visibility visibility = Visibility::Paper;
};

/// Bits of VoxelTerms::flags.
namespace voxel_flag {
inline constexpr std::uint64_t kStop = 1;      ///< ends a ray: measured with L >= 0 (OctoMap occupied)
inline constexpr std::uint64_t kOccupied = 2;  ///< P_o > occupied_threshold
inline constexpr std::uint64_t kFree = 4;      ///< P_o < free_threshold
inline constexpr std::uint64_t kUnknown = 8;   ///< neither
inline constexpr std::uint64_t kMeasured = 16;
inline constexpr std::uint64_t kMarked = 32;   ///< unmeasured with a proximity mark
}  // namespace voxel_flag

/// Everything the metrics need from one voxel, in 32 bytes: a packet walk loads a voxel's
/// terms as one row of the palette.
struct VoxelTerms {
  double entropy = 0.0;    ///< H(P_o) [nats]
  double keep = 0.0;       ///< visibility factor to the next voxel: 1 - P_o (paper) or P_o
  double proximity = 0.0;  ///< M - d for a marked voxel, else 0 (Eq. 11)
  std::uint64_t flags = 0; ///< voxel_flag bits
};

/// Occupancy probability of log-odds L: 1 / (1 + exp(-L)) (SEMANTICS.md "The map"), in double precision.
inline double occupancyProbability(float log_odds) {
  return 1.0 / (1.0 + std::exp(-static_cast<double>(log_odds)));
}

/// H(p) = -p ln p - (1 - p) ln(1 - p) [nats], 0 at p = 0 or 1.
inline double entropyNats(double p) {
  double h = 0.0;
  if (p > 0.0) h -= p * std::log(p);
  if (p < 1.0) h -= (1.0 - p) * std::log(1.0 - p);
  return h;
}

/// The terms of one voxel. `log_odds` is ignored for an unmeasured voxel (it reads P_o = 0.5);
/// `mark` is its proximity distance in voxel steps, 0 for none (ignored if measured).
/// Thread-safe.
VoxelTerms voxelTerms(const VoxelModel& model, bool measured, float log_odds, std::int32_t mark);

/// Area Factor class of a ray (SEMANTICS.md "Volumetric information", Vasquez-Gomez et al.).
enum class AreaClass : std::uint8_t { Pending, Occupied, Occplane, Unobserved, None };

/// 2^-n, exactly: from its exponent bits while it is a normal double (as the packet walk forms
/// it), else through std::ldexp, a library call kept off the common path.
inline double powerOfHalf(std::uint32_t n) {
  if (n > 1022) return std::ldexp(1.0, -static_cast<int>(std::min<std::uint32_t>(n, 2000)));  // 2^-2000: 0
  return std::bit_cast<double>(static_cast<std::uint64_t>(1023 - n) << 52);
}

/// The sums of one ray, after its end voxel.
struct RaySums {
  double entropy = 0.0;   ///< sum of H over x_0..x_n
  double oa = 0.0;        ///< Eq. 6
  double uv = 0.0;        ///< Eq. 8
  double rse = 0.0;       ///< Eq. 10
  double pc = 0.0;        ///< Eq. 11
  std::uint32_t voxels = 0;    ///< n + 1
  bool end_occupied = false;   ///< the end voxel is occupied (P_o > occupied_threshold)
  bool rear_side = false;      ///< Eq. 9
  AreaClass area = AreaClass::Unobserved;
};

/// The state of RayAccumulator, one X(name, type, initial value, lane kind) per field: the one
/// list from which the accumulator, the packet walks' lanes and their copies follow. The lane
/// kind says how a packet walk holds the field: D a double lane, I a 64-bit integer lane, M a
/// flag lane (0 or -1).
#define NBV_RAY_ACCUMULATOR_FIELDS(X)                                                             \
  X(visibility, double, 1.0, D)    /* P_v of the next voxel (Eq. 5) */                            \
  X(entropy, double, 0.0, D)                                                                     \
  X(oa, double, 0.0, D)                                                                          \
  X(uv, double, 0.0, D)                                                                          \
  X(pc, double, 0.0, D)                                                                          \
  X(run, double, 0.0, D)           /* P_v * H over the current unbroken run of unknown voxels */  \
  X(run_before, double, 0.0, D)    /* `run` before the last voxel */                              \
  X(last_term, double, 0.0, D)     /* P_v * H of the last voxel */                                \
  X(voxels, double, 0.0, D)        /* voxels so far (a double, as in the packet walk) */          \
  X(last_flags, std::uint64_t, 0, I)                                                             \
  X(previous_flags, std::uint64_t, 0, I)                                                         \
  X(seen_measured, bool, false, M) /* a measured voxel was among those so far */                  \
  X(previous_free, bool, false, M) /* Area Factor's "free" for the last voxel */                  \
  X(area, AreaClass, AreaClass::Pending, I)

/// Walks one ray's voxels x_0..x_n in order and accumulates every metric at once.
/// The state is public so that a packet walk can hand a ray over lane by lane.
struct RayAccumulator {
#define NBV_DECLARE_FIELD(name, type, initial, lane) type name = initial;
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_DECLARE_FIELD)
#undef NBV_DECLARE_FIELD

  /// Adds the next voxel.
  void add(const VoxelTerms& t) {
    const double term = visibility * t.entropy;
    const bool unknown = (t.flags & voxel_flag::kUnknown) != 0;
    entropy += t.entropy;
    oa += term;                           // Eq. 6
    uv += unknown ? term : 0.0;           // Eq. 8
    run_before = run;
    run = unknown ? run + term : 0.0;     // Eq. 10's run of unknown voxels
    last_term = term;
    pc += t.proximity;                    // Eq. 11
    if (area == AreaClass::Pending) {     // Eqs. 17-20: classify the ray once
      if ((t.flags & voxel_flag::kMarked) != 0) {
        area = AreaClass::Occplane;
      } else if ((t.flags & voxel_flag::kOccupied) != 0) {
        area = voxels > 0.0 && previous_free ? AreaClass::Occupied : AreaClass::None;
      }
    }
    const bool measured = (t.flags & voxel_flag::kMeasured) != 0;
    seen_measured = seen_measured || measured;
    previous_free = (t.flags & voxel_flag::kFree) != 0 ||
                    ((t.flags & (voxel_flag::kMeasured | voxel_flag::kMarked)) == 0 && !seen_measured);
    previous_flags = last_flags;
    last_flags = t.flags;
    voxels += 1.0;
    visibility = visibility * t.keep;     // Eq. 5
  }

  /// Adds `count` voxels of the uniform terms `t` (unmeasured, unmarked) in closed form:
  /// the same sums as `count` calls of add() up to rounding.
  void addUniform(const VoxelTerms& t, std::uint32_t count) {
    if (count == 0) return;
    add(t);  // the first sets the per-voxel state; the other count - 1 follow in closed form
    addRepeats(t, count - 1);
  }

  /// Adds `count` more voxels of the terms `t` of the voxel just added, in closed form: the
  /// same sums as `count` calls of add(t) up to rounding (the per-voxel state, the Area Factor
  /// class included, cannot change while the terms stay the same). The packet walk repeats
  /// these operations lane by lane for keep = 0.5, so both give the same bits.
  void addRepeats(const VoxelTerms& t, std::uint32_t count) {
    if (count == 0) return;
    const double n = static_cast<double>(count);
    // Geometric series of the visibility: sum_{i<n} P_v keep^i H and P_v keep^n. keep is 0.5
    // for an unmeasured voxel with either visibility model: a power of two, exactly.
    auto power = [&t](double exponent) {
      return t.keep == 0.5 ? powerOfHalf(static_cast<std::uint32_t>(exponent)) : std::pow(t.keep, exponent);
    };
    const double keep_n = power(n);
    const double decay_sum = t.keep == 1.0 ? n : (1.0 - keep_n) / (1.0 - t.keep);
    const double terms = visibility * t.entropy * decay_sum;
    const bool unknown = (t.flags & voxel_flag::kUnknown) != 0;
    entropy += n * t.entropy;
    oa += terms;
    uv += unknown ? terms : 0.0;
    // The last voxel's own term and the run before it.
    const double last_visibility = visibility * power(n - 1.0);
    last_term = last_visibility * t.entropy;
    run = unknown ? run + terms : 0.0;
    run_before = unknown ? run - last_term : 0.0;
    pc += n * t.proximity;
    previous_flags = t.flags;
    voxels += n;
    visibility = visibility * keep_n;
  }

  /// The ray's sums; call after its end voxel.
  RaySums finish() const {
    RaySums sums;
    sums.entropy = entropy;
    sums.oa = oa;
    sums.uv = uv;
    sums.pc = pc;
    sums.voxels = static_cast<std::uint32_t>(voxels);
    sums.end_occupied = (last_flags & voxel_flag::kOccupied) != 0;
    // Eq. 9: the end voxel occupied and the one before it unknown.
    sums.rear_side = sums.end_occupied && voxels > 1.0 && (previous_flags & voxel_flag::kUnknown) != 0;
    // Eq. 10: the unknown run before an occupied end voxel, plus the end voxel.
    sums.rse = sums.end_occupied ? run_before + last_term : 0.0;
    sums.area = area == AreaClass::Pending ? AreaClass::Unobserved : area;
    return sums;
  }
};

/// The sums of one view over its rays, in a fixed order.
struct ViewSums {
  double entropy = 0.0, oa = 0.0, uv = 0.0, rse = 0.0, pc = 0.0;
  double kr_entropy = 0.0;           ///< sum of H over rays ending in an occupied voxel
  std::uint64_t kr_voxels = 0;       ///< their voxel count
  std::uint64_t rsv = 0;             ///< rays with a rear side (Eq. 9)
  std::uint64_t area_occupied = 0, area_occplane = 0, area_unobserved = 0;
  std::uint64_t rays = 0;
  std::uint64_t voxels = 0;          ///< voxels of all rays (x_0..x_n each)

  void add(const RaySums& ray) {
    entropy += ray.entropy;
    oa += ray.oa;
    uv += ray.uv;
    rse += ray.rse;
    pc += ray.pc;
    if (ray.end_occupied) {  // Eq. 4 keeps only rays that end on the surface
      kr_entropy += ray.entropy;
      kr_voxels += ray.voxels;
    }
    rsv += ray.rear_side ? 1 : 0;
    area_occupied += ray.area == AreaClass::Occupied ? 1 : 0;
    area_occplane += ray.area == AreaClass::Occplane ? 1 : 0;
    area_unobserved += ray.area == AreaClass::Unobserved ? 1 : 0;
    ++rays;
    voxels += ray.voxels;
  }
  void add(const ViewSums& other) {
    entropy += other.entropy;
    oa += other.oa;
    uv += other.uv;
    rse += other.rse;
    pc += other.pc;
    kr_entropy += other.kr_entropy;
    kr_voxels += other.kr_voxels;
    rsv += other.rsv;
    area_occupied += other.area_occupied;
    area_occplane += other.area_occplane;
    area_unobserved += other.area_unobserved;
    rays += other.rays;
    voxels += other.voxels;
  }
};

/// The sums of a view in double precision, field for field: what an estimate from part of
/// the view's rays gives (counts scaled up are not whole numbers).
struct ViewTotals {
  double entropy = 0.0, oa = 0.0, uv = 0.0, rse = 0.0, pc = 0.0;
  double kr_entropy = 0.0, kr_voxels = 0.0;
  double rsv = 0.0;
  double area_occupied = 0.0, area_occplane = 0.0, area_unobserved = 0.0;
  double rays = 0.0, voxels = 0.0;

  static constexpr std::size_t kFields = 13;
  /// The fields in the order above, for estimators that treat them alike.
  std::array<double, kFields> fields() const {
    return {entropy, oa, uv, rse, pc, kr_entropy, kr_voxels, rsv, area_occupied, area_occplane, area_unobserved, rays, voxels};
  }
  static ViewTotals fromFields(const std::array<double, kFields>& f) {
    return {f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9], f[10], f[11], f[12]};
  }
  /// The sums as they are (counts converted exactly: they stay below 2^53).
  static ViewTotals of(const ViewSums& s) {
    return {s.entropy, s.oa, s.uv, s.rse, s.pc, s.kr_entropy, static_cast<double>(s.kr_voxels),
            static_cast<double>(s.rsv), static_cast<double>(s.area_occupied), static_cast<double>(s.area_occplane),
            static_cast<double>(s.area_unobserved), static_cast<double>(s.rays), static_cast<double>(s.voxels)};
  }
};

/// Eqs. 18-20: f(alpha, alpha_des), 1 where alpha = alpha_des, 0 at alpha = 0 and 1.
double areaFactorTerm(double alpha, double alpha_desired);

/// Desired fractions of Area Factor (Vasquez-Gomez et al.): occupied 0.2, occplane 0.8.
inline constexpr double kAreaOccupiedDesired = 0.2;
inline constexpr double kAreaOccplaneDesired = 0.8;

/// The value of `metric` for one view's totals (exact or estimated). Metric::Random has no
/// sums: it throws InvalidArgument (the evaluators draw it from a seed instead).
double metricValue(const ViewTotals& totals, Metric metric);
/// metricValue() of a view's exact sums.
inline double metricValue(const ViewSums& sums, Metric metric) { return metricValue(ViewTotals::of(sums), metric); }

/// The seeded uniform score in [0, 1) of view `view_index` for Metric::Random: a counter-based
/// hash, so it depends on neither the thread count nor the evaluation order.
double randomScore(std::uint64_t seed, std::uint64_t view_index);

}  // namespace nbv::kernels
