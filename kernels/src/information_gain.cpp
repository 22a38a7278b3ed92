#include "nbv/kernels/information_gain.hpp"

#include "nbv/errors.hpp"


namespace nbv::kernels {

static_assert([] {
  for (std::size_t i = 0; i < kMetricCount; ++i) {
    if (static_cast<std::size_t>(kMetricTable[i].metric) != i) return false;
  }
  return true;
}(), "row i of kMetricTable is the metric i");

const char* metricName(Metric metric) { return metricRow(metric).name.data(); }

Metric metricNamed(std::string_view name) {
  if (const auto metric = metricFromName(name)) return *metric;
  throw InvalidArgument("unknown metric '" + std::string(name) + "' (known: " + metricNames() + ")");
}

std::string metricNames(std::string_view separator) {
  std::string names;
  for (const MetricRow& row : kMetricTable) names += (names.empty() ? "" : std::string(separator)) + std::string(row.name);
  return names;
}

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
  const MetricRow& row = metricRow(metric);
  if (row.value == nullptr) throw InvalidArgument("metric '" + std::string(row.name) + "' has no ray sums; it is drawn from a seed");
  return row.value(sums);
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
