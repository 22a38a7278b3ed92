#include "nbv/kernels/information_gain.hpp"

#include "nbv/errors.hpp"


namespace nbv::kernels {

namespace {
constexpr std::array<const char*, kMetricCount> kNames = {"entropy", "oa", "uv",  "rsv",   "rse",
                                                          "pc",      "vg", "kr",  "random"};
}  // namespace

const char* metricName(Metric metric) { return kNames[static_cast<std::size_t>(metric)]; }

std::optional<Metric> metricFromName(std::string_view name) {
  for (Metric metric : kAllMetrics) {
    if (name == metricName(metric)) return metric;
  }
  return std::nullopt;
}

const char* visibilityName(Visibility visibility) { return visibility == Visibility::Released ? "released" : "paper"; }

Visibility visibilityFromName(std::string_view name) {
  if (name == "paper") return Visibility::Paper;
  if (name == "released") return Visibility::Released;
  throw InvalidArgument("visibility '" + std::string(name) + "' is not 'paper' or 'released'");
}

VoxelTerms voxelTerms(const VoxelModel& model, bool measured, float log_odds, std::int32_t mark) {
  VoxelTerms t;
  // SEMANTICS.md "The map": an unmeasured voxel reads as the prior, whatever is stored.
  const double p = measured ? occupancyProbability(log_odds) : 0.5;
  t.entropy = entropyNats(p);
  t.keep = model.visibility == Visibility::Paper ? 1.0 - p : p;  // Eq. 5 (or issue #9)
  if (measured) {
    t.flags |= voxel_flag::kMeasured;
    if (log_odds >= 0.0f) t.flags |= voxel_flag::kStop;  // OctoMap's isNodeOccupied
  } else if (mark > 0) {
    t.flags |= voxel_flag::kMarked;
    t.proximity = model.proximity_max - static_cast<double>(mark);  // Eq. 11
  }
  if (p > model.occupied_threshold) {
    t.flags |= voxel_flag::kOccupied;
  } else if (p < model.free_threshold) {
    t.flags |= voxel_flag::kFree;
  } else {
    t.flags |= voxel_flag::kUnknown;
  }
  return t;
}

double areaFactorTerm(double alpha, double alpha_desired) {
  const double a = alpha, d = alpha_desired;
  if (a <= d) {  // Eq. 19
    return -2.0 / (d * d * d) * a * a * a + 3.0 / (d * d) * a * a;
  }
  const double c = (d - 1.0) * (d - 1.0) * (d - 1.0);  // Eq. 20
  return -2.0 / c * a * a * a + 3.0 * (d + 1.0) / c * a * a - 6.0 * d / c * a + (3.0 * d - 1.0) / c;
}

double metricValue(const ViewTotals& sums, Metric metric) {
  switch (metric) {
    case Metric::Entropy: return sums.entropy;
    case Metric::OcclusionAware: return sums.oa;
    case Metric::UnobservedVoxel: return sums.uv;
    case Metric::RearSideVoxel: return sums.rsv;
    case Metric::RearSideEntropy: return sums.rse;
    case Metric::ProximityCount: return sums.pc;
    case Metric::AreaFactor: {  // Eq. 17 over the classified rays
      const double classified = sums.area_occupied + sums.area_occplane + sums.area_unobserved;
      if (!(classified > 0.0)) return 0.0;
      return areaFactorTerm(sums.area_occupied / classified, kAreaOccupiedDesired) +
             areaFactorTerm(sums.area_occplane / classified, kAreaOccplaneDesired);
    }
    case Metric::AverageEntropy:  // Eq. 4
      return sums.kr_voxels > 0.0 ? sums.kr_entropy / sums.kr_voxels : 0.0;
    case Metric::Random: break;
  }
  throw InvalidArgument("metric 'random' has no ray sums; it is drawn from a seed");
}

double randomScore(std::uint64_t seed, std::uint64_t view_index) {
  // SplitMix64 of (seed, view): a counter-based generator.
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + view_index + 1;
  for (int round = 0; round < 2; ++round) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z = z ^ (z >> 31);
  }
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

}  // namespace nbv::kernels
