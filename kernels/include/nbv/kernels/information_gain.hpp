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
#include <iterator>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace nbv::kernels {

/// How visibility decays along a ray (SEMANTICS.md "Volumetric information").
enum class Visibility {
  Paper,     ///< Eq. 5: P_v(x_{i+1}) = P_v(x_i) * (1 - P_o(x_i)); the default
  Released,  ///< the released code's P_v(x_{i+1}) = P_v(x_i) * P_o(x_i) (its issue #9)
};

/// The metrics of SEMANTICS.md "Volumetric information", in the order of its table; each has
/// its row in kMetricTable (below).
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
  UnknownCount,     ///< `uc`: unknown voxels traversed (Connolly 1985; Banta et al. 2000)
  FrontierVoxels,   ///< `fv`: frontier voxels traversed (Yamauchi 1997)
};

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
  /// Whether voxels carry voxel_flag::kFrontier, which depends on their neighbours (fv reads
  /// it): a snapshot flags them only when asked.
  bool frontier = false;
};

/// Bits of VoxelTerms::flags.
namespace voxel_flag {
inline constexpr std::uint64_t kStop = 1;      ///< ends a ray: measured with L >= 0 (OctoMap occupied)
inline constexpr std::uint64_t kOccupied = 2;  ///< P_o > occupied_threshold
inline constexpr std::uint64_t kFree = 4;      ///< P_o < free_threshold
inline constexpr std::uint64_t kUnknown = 8;   ///< neither
inline constexpr std::uint64_t kMeasured = 16;
inline constexpr std::uint64_t kMarked = 32;   ///< unmeasured with a proximity mark
inline constexpr std::uint64_t kFrontier = 64; ///< unknown with a free face neighbour (VoxelModel::frontier)
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

/// The most voxels a run crossed in one step repeats (RunDistanceField: at most
/// kMaxRunDistance - 1 crossings along each of three axes) is below 2^kRunPowerBits.
inline constexpr unsigned kRunPowerBits = 7;

/// keep^n for a run's repeated voxels (n < 2^kRunPowerBits), by squaring: keep^(2^k) for the
/// set bits k of n multiplied from the lowest. The packet walks form it with the same
/// products lane by lane, so every instruction set gives the same bits; exact for keep = 0.5
/// (powers of two), where it equals powerOfHalf().
inline double runPower(double keep, std::uint32_t n) {
  double power = 1.0, square = keep;
  for (unsigned k = 0; k < kRunPowerBits; ++k) {
    if (((n >> k) & 1u) != 0) power = power * square;
    square = square * square;
  }
  return power;
}

/// keep^n as RayAccumulator::addRepeats() takes it: runPower() for a run; for the longer
/// uniform stretches before and after a snapshot's box (keep = 0.5, an unmeasured voxel),
/// powerOfHalf(), which stays exact past the normal doubles; std::pow otherwise.
inline double repeatPower(double keep, std::uint32_t n) {
  if (keep == 0.5) return powerOfHalf(n);
  return n < (1u << kRunPowerBits) ? runPower(keep, n) : std::pow(keep, static_cast<double>(n));
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

/// The voxel counts of one ray that the counting formulations read (metric_reads::kCounts). A
/// walk writes them only when asked, beside the RaySums: a walk that does not need them keeps
/// its output as small as the paper's metrics need.
struct RayCounts {
  std::uint32_t unknown = 0;   ///< unknown voxels among x_0..x_n (uc)
  std::uint32_t frontier = 0;  ///< frontier voxels among them (fv)
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

/// The counts of RayAccumulator (RayCounts), in the form of NBV_RAY_ACCUMULATOR_FIELDS: a walk
/// without counts does not keep them in its registers.
#define NBV_RAY_COUNT_FIELDS(X)                                 \
  X(unknown, double, 0.0, D)  /* unknown voxels so far (uc) */   \
  X(frontier, double, 0.0, D) /* frontier voxels so far (fv) */

/// Walks one ray's voxels x_0..x_n in order and accumulates every metric at once.
/// The state is public so that a packet walk can hand a ray over lane by lane.
struct RayAccumulator {
#define NBV_DECLARE_FIELD(name, type, initial, lane) type name = initial;
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_DECLARE_FIELD)
  NBV_RAY_COUNT_FIELDS(NBV_DECLARE_FIELD)
#undef NBV_DECLARE_FIELD

  /// Adds the next voxel.
  void add(const VoxelTerms& t) {
    const double term = visibility * t.entropy;
    const bool is_unknown = (t.flags & voxel_flag::kUnknown) != 0;
    entropy += t.entropy;
    oa += term;                           // Eq. 6
    uv += is_unknown ? term : 0.0;        // Eq. 8
    unknown += is_unknown ? 1.0 : 0.0;    // uc
    frontier += (t.flags & voxel_flag::kFrontier) != 0 ? 1.0 : 0.0;  // fv
    run_before = run;
    run = is_unknown ? run + term : 0.0;  // Eq. 10's run of unknown voxels
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
  /// class included, cannot change while the terms stay the same). The packet walks repeat
  /// these operations lane by lane, so both give the same bits.
  void addRepeats(const VoxelTerms& t, std::uint32_t count) {
    if (count == 0) return;
    addRepeats(t, static_cast<double>(count), repeatPower(t.keep, count), repeatPower(t.keep, count - 1));
  }

  /// addRepeats() of n = `count` voxels with keep^n = `keep_n` and keep^(n - 1) = `keep_n1`
  /// given (repeatPower()).
  void addRepeats(const VoxelTerms& t, double n, double keep_n, double keep_n1) {
    // Geometric series of the visibility: sum_{i<n} P_v keep^i H and P_v keep^n.
    const double decay_sum = t.keep == 1.0 ? n : (1.0 - keep_n) / (1.0 - t.keep);
    const double terms = visibility * t.entropy * decay_sum;
    const bool is_unknown = (t.flags & voxel_flag::kUnknown) != 0;
    entropy += n * t.entropy;
    oa += terms;
    uv += is_unknown ? terms : 0.0;
    unknown += is_unknown ? n : 0.0;
    frontier += (t.flags & voxel_flag::kFrontier) != 0 ? n : 0.0;
    // The last voxel's own term and the run before it.
    const double last_visibility = visibility * keep_n1;
    last_term = last_visibility * t.entropy;
    run = is_unknown ? run + terms : 0.0;
    run_before = is_unknown ? run - last_term : 0.0;
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
  /// The ray's counts; call after its end voxel.
  RayCounts counts() const { return {static_cast<std::uint32_t>(unknown), static_cast<std::uint32_t>(frontier)}; }
};

/// A ray's sums and counts together, for those who keep rays one by one (anytime decisions).
struct RayResult {
  RaySums sums;
  RayCounts counts;
};

/// The sums of one view over its rays, one X(name, type) per field: ViewSums holds them as
/// `type`, ViewTotals in double precision, ViewField names their places. A new sum is one line
/// here and its update in ViewSums::add().
#define NBV_VIEW_SUM_FIELDS(X)                                                             \
  X(entropy, double)                                                                       \
  X(oa, double)                                                                            \
  X(uv, double)                                                                            \
  X(rse, double)                                                                           \
  X(pc, double)                                                                            \
  X(kr_entropy, double)            /* sum of H over rays ending in an occupied voxel */     \
  X(kr_voxels, std::uint64_t)      /* their voxel count */                                 \
  X(rsv, std::uint64_t)            /* rays with a rear side (Eq. 9) */                     \
  X(area_occupied, std::uint64_t)  /* rays of each Area Factor class */                    \
  X(area_occplane, std::uint64_t)                                                          \
  X(area_unobserved, std::uint64_t)                                                        \
  X(rays, std::uint64_t)                                                                   \
  X(voxels, std::uint64_t)         /* voxels of all rays (x_0..x_n each) */                \
  X(uc, std::uint64_t)             /* unknown voxels of all rays */                       \
  X(fv, std::uint64_t)             /* frontier voxels of all rays */

/// The place of each field of NBV_VIEW_SUM_FIELDS in ViewTotals::fields().
enum class ViewField : std::size_t {
#define NBV_VIEW_FIELD_NAME(name, type) name,
  NBV_VIEW_SUM_FIELDS(NBV_VIEW_FIELD_NAME)
#undef NBV_VIEW_FIELD_NAME
};

/// The sums of one view over its rays, in a fixed order.
struct ViewSums {
#define NBV_VIEW_SUM_DECLARE(name, type) type name = 0;
  NBV_VIEW_SUM_FIELDS(NBV_VIEW_SUM_DECLARE)
#undef NBV_VIEW_SUM_DECLARE

  void add(const RaySums& ray, const RayCounts& counts = {}) {
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
    uc += counts.unknown;
    fv += counts.frontier;
  }
  void add(const RayResult& ray) { add(ray.sums, ray.counts); }
  void add(const ViewSums& other) {
#define NBV_VIEW_SUM_ADD(name, type) name += other.name;
    NBV_VIEW_SUM_FIELDS(NBV_VIEW_SUM_ADD)
#undef NBV_VIEW_SUM_ADD
  }
};

/// The sums of a view in double precision, field for field: what an estimate from part of
/// the view's rays gives (counts scaled up are not whole numbers).
struct ViewTotals {
#define NBV_VIEW_TOTAL_DECLARE(name, type) double name = 0.0;
  NBV_VIEW_SUM_FIELDS(NBV_VIEW_TOTAL_DECLARE)
#undef NBV_VIEW_TOTAL_DECLARE

#define NBV_VIEW_FIELD_COUNT(name, type) +1
  static constexpr std::size_t kFields = 0 NBV_VIEW_SUM_FIELDS(NBV_VIEW_FIELD_COUNT);
#undef NBV_VIEW_FIELD_COUNT
  /// The fields in the order of NBV_VIEW_SUM_FIELDS, for estimators that treat them alike.
  std::array<double, kFields> fields() const {
#define NBV_VIEW_FIELD_VALUE(name, type) name,
    return {NBV_VIEW_SUM_FIELDS(NBV_VIEW_FIELD_VALUE)};
#undef NBV_VIEW_FIELD_VALUE
  }
  static ViewTotals fromFields(const std::array<double, kFields>& f) {
    ViewTotals t;
#define NBV_VIEW_FIELD_FROM(name, type) t.name = f[static_cast<std::size_t>(ViewField::name)];
    NBV_VIEW_SUM_FIELDS(NBV_VIEW_FIELD_FROM)
#undef NBV_VIEW_FIELD_FROM
    return t;
  }
  /// The sums as they are (counts converted exactly: they stay below 2^53).
  static ViewTotals of(const ViewSums& s) {
    ViewTotals t;
#define NBV_VIEW_FIELD_OF(name, type) t.name = static_cast<double>(s.name);
    NBV_VIEW_SUM_FIELDS(NBV_VIEW_FIELD_OF)
#undef NBV_VIEW_FIELD_OF
    return t;
  }
};

/// Eqs. 18-20: f(alpha, alpha_des), 1 where alpha = alpha_des, 0 at alpha = 0 and 1.
double areaFactorTerm(double alpha, double alpha_desired);

/// Desired fractions of Area Factor (Vasquez-Gomez et al.): occupied 0.2, occplane 0.8.
inline constexpr double kAreaOccupiedDesired = 0.2;
inline constexpr double kAreaOccplaneDesired = 0.8;

/// What a formulation reads besides the ray's walk (MetricRow::reads): a formulation that
/// reads the proximity marks is 0 on a map without them (an OctoMap file).
namespace metric_reads {
inline constexpr unsigned kEntropy = 1;     ///< H(P_o) of the voxels
inline constexpr unsigned kVisibility = 2;  ///< P_v along the ray (Eq. 5)
inline constexpr unsigned kClasses = 4;     ///< occupied / free / unknown
inline constexpr unsigned kMarks = 8;       ///< the proximity marks
inline constexpr unsigned kCounts = 16;     ///< voxel counts a walk makes only when asked (RayCounts)
inline constexpr unsigned kNeighbours = 32; ///< the classes of a voxel's face neighbours (VoxelModel::frontier)
}  // namespace metric_reads

/// The ViewTotals fields a ratio metric divides by: an anytime decision's interval for it
/// needs their sum estimated well first (planner/anytime.cpp). Empty for a sum. `needs`: a
/// voxel_flag without which every ray's denominator is 0 (kr keeps only rays ending on an
/// occupied voxel): on a snapshot whose voxels hold none, the metric is 0 for every view.
struct Denominator {
  std::size_t count = 0;
  std::array<ViewField, 3> fields{};
  std::uint64_t needs = 0;
};

/// One formulation of volumetric information: a row of kMetricTable. Its names, help texts,
/// "known" lists, the warnings about maps without marks, the anytime decider's ratios and
/// Python's nbv.METRICS all follow from the table.
struct MetricRow {
  Metric metric;
  std::string_view name;      ///< short name: "oa"
  std::string_view title;     ///< "Occlusion Aware"
  std::string_view equation;  ///< the paper's equation(s): "Eq. 6"
  unsigned reads;             ///< metric_reads bits
  /// The view's value from its sums (exact or estimated); none for `random`, drawn from a seed.
  double (*value)(const ViewTotals&);
  Denominator denominator;
};

/// Eq. 17 over the classified rays (Area Factor).
inline double areaFactorValue(const ViewTotals& t) {
  const double classified = t.area_occupied + t.area_occplane + t.area_unobserved;
  if (!(classified > 0.0)) return 0.0;
  return areaFactorTerm(t.area_occupied / classified, kAreaOccupiedDesired) +
         areaFactorTerm(t.area_occplane / classified, kAreaOccplaneDesired);
}

/// Every formulation, in the order of SEMANTICS.md "Volumetric information" (row i is Metric i).
inline constexpr MetricRow kMetricTable[] = {
    {Metric::Entropy, "entropy", "plain entropy", "Eq. 3", metric_reads::kEntropy,
     [](const ViewTotals& t) { return t.entropy; }, {}},
    {Metric::OcclusionAware, "oa", "Occlusion Aware", "Eq. 6", metric_reads::kEntropy | metric_reads::kVisibility,
     [](const ViewTotals& t) { return t.oa; }, {}},
    {Metric::UnobservedVoxel, "uv", "Unobserved Voxel", "Eq. 8",
     metric_reads::kEntropy | metric_reads::kVisibility | metric_reads::kClasses, [](const ViewTotals& t) { return t.uv; }, {}},
    {Metric::RearSideVoxel, "rsv", "Rear Side Voxel", "Eq. 9", metric_reads::kClasses,
     [](const ViewTotals& t) { return t.rsv; }, {}},
    {Metric::RearSideEntropy, "rse", "Rear Side Entropy", "Eq. 10",
     metric_reads::kEntropy | metric_reads::kVisibility | metric_reads::kClasses, [](const ViewTotals& t) { return t.rse; }, {}},
    {Metric::ProximityCount, "pc", "Proximity Count", "Eq. 11", metric_reads::kMarks,
     [](const ViewTotals& t) { return t.pc; }, {}},
    {Metric::AreaFactor, "vg", "Area Factor", "Eqs. 17-20", metric_reads::kClasses | metric_reads::kMarks,
     areaFactorValue, {3, {ViewField::area_occupied, ViewField::area_occplane, ViewField::area_unobserved}}},
    {Metric::AverageEntropy, "kr", "Average Entropy", "Eq. 4", metric_reads::kEntropy | metric_reads::kClasses,
     [](const ViewTotals& t) { return t.kr_voxels > 0.0 ? t.kr_entropy / t.kr_voxels : 0.0; },
     {1, {ViewField::kr_voxels}, voxel_flag::kOccupied}},
    {Metric::Random, "random", "random", "the planner's baseline", 0, nullptr, {}},
    {Metric::UnknownCount, "uc", "Unknown Count", "Connolly 1985; Banta et al. 2000",
     metric_reads::kClasses | metric_reads::kCounts,
     [](const ViewTotals& t) { return t.uc; }, {}},
    {Metric::FrontierVoxels, "fv", "Frontier Voxels", "Yamauchi 1997",
     metric_reads::kClasses | metric_reads::kCounts | metric_reads::kNeighbours,
     [](const ViewTotals& t) { return t.fv; }, {}},
};
inline constexpr std::size_t kMetricCount = std::size(kMetricTable);

/// Every metric, in the table's order.
inline constexpr std::array<Metric, kMetricCount> kAllMetrics = [] {
  std::array<Metric, kMetricCount> all{};
  for (std::size_t i = 0; i < kMetricCount; ++i) all[i] = kMetricTable[i].metric;
  return all;
}();

/// The row of `metric`.
constexpr const MetricRow& metricRow(Metric metric) { return kMetricTable[static_cast<std::size_t>(metric)]; }

/// Whether any of `metrics` reads what `reads` (metric_reads bits) names.
inline bool readsAny(std::span<const Metric> metrics, unsigned reads) {
  return std::any_of(metrics.begin(), metrics.end(), [reads](Metric m) { return (metricRow(m).reads & reads) != 0; });
}

/// The short name ("entropy", "oa", ...).
const char* metricName(Metric metric);
/// The metric of a short name; empty if there is none.
std::optional<Metric> metricFromName(std::string_view name);
/// The metric of a short name. \throws InvalidArgument naming the name and the known ones.
Metric metricNamed(std::string_view name);
/// The short names, joined by `separator` ("entropy, oa, uv, ..."): for help texts and errors.
std::string metricNames(std::string_view separator = ", ");

/// The value of `metric` for one view's totals (exact or estimated). Metric::Random has no
/// sums: it throws InvalidArgument (the evaluators draw it from a seed instead).
double metricValue(const ViewTotals& totals, Metric metric);
/// metricValue() of a view's exact sums.
inline double metricValue(const ViewSums& sums, Metric metric) { return metricValue(ViewTotals::of(sums), metric); }

/// The seeded uniform score in [0, 1) of view `view_index` for Metric::Random: a counter-based
/// hash, so it depends on neither the thread count nor the evaluation order.
double randomScore(std::uint64_t seed, std::uint64_t view_index);

}  // namespace nbv::kernels
