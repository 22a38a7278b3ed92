#include "nbv/ig/stratified_sample.hpp"

#include "nbv/errors.hpp"
#include "recently_built.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace nbv::ig {

namespace {

using kernels::ViewTotals;

/// SplitMix64: the counter-based draws of the samples (seed, depth, node), independent of the
/// order in which anything is computed.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

std::size_t ceilLog2(std::size_t n) {
  std::size_t k = 0;
  while ((std::size_t{1} << k) < n) ++k;
  return k;
}

/// The collapsed-strata variance of an expansion estimate whose per-ray values `value(h)`
/// gives: siblings 2j, 2j + 1 as one stratum of two draws, (N/2)^2 (z_a - z_b)^2; strata of at
/// most one ray are exact.
template <class Value>
double collapsedVariance(const Strata& strata, Value value) {
  double variance = 0.0;
  for (std::size_t h = 0; h + 1 < strata.size(); h += 2) {
    if (strata[h].size <= 1 && strata[h + 1].size <= 1) continue;
    const double half = 0.5 * static_cast<double>(strata[h].size + strata[h + 1].size);
    const double diff = value(h) - value(h + 1);
    variance += half * half * diff * diff;
  }
  return variance;
}

/// The largest relative standard error of a ratio's denominator for which the delta method's
/// interval is used: with fewer rays ending on the surface (kr) or classified (vg) the ratio is
/// too unstable for it, and the interval is unbounded until a later level.
constexpr double kMaxDenominatorError = 0.05;

}  // namespace

// --- the nested stratified sample --------------------------------------------------------------

std::size_t StratifiedSample::roundedStrata(std::size_t first_strata) {
  return std::size_t{1} << ceilLog2(std::max<std::size_t>(first_strata, 1));
}

StratifiedSample::StratifiedSample(std::span<const Eigen::Vector3d> directions, std::size_t first_strata) {
  if (directions.empty()) throw InvalidArgument("a stratified sample needs at least one ray");
  const std::size_t n = directions.size();
  directions_.assign(directions.begin(), directions.end());
  // Where each ray crosses the image plane z = 1 (rays that do not look forward: their x, y),
  // kept beside the ray's index and reordered with it, so that every tile's rays lie together.
  struct Placed {
    Eigen::Vector2d at;
    std::uint32_t ray;
  };
  std::vector<Placed> placed(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& d = directions[i];
    placed[i].at = d.z() > 1e-9 ? Eigen::Vector2d(d.x() / d.z(), d.y() / d.z()) : Eigen::Vector2d(d.x(), d.y());
    placed[i].ray = static_cast<std::uint32_t>(i);
  }
  levels_ = ceilLog2(n);  // depth at which every tile holds at most one ray
  first_log2_ = std::min(ceilLog2(std::max<std::size_t>(first_strata, 1)), levels_);
  // Depth d holds 2^d tiles; tile j spans order_[bounds at d, j .. j + 1). Each tile splits at
  // its middle along its longer side, so every tile is compact and halves differ by one ray.
  bounds_.assign((std::size_t{2} << levels_) + levels_ + 1, 0);  // depth d's 2^d + 1 bounds start at 2^d - 1 + d
  auto bound = [&](std::size_t d, std::size_t j) -> std::uint32_t& { return bounds_[(std::size_t{1} << d) - 1 + d + j]; };
  bound(0, 0) = 0;
  bound(0, 1) = static_cast<std::uint32_t>(n);
  for (std::size_t d = 0; d < levels_; ++d) {
    for (std::size_t j = 0; j < (std::size_t{1} << d); ++j) {
      const std::uint32_t lo = bound(d, j), hi = bound(d, j + 1);
      const std::uint32_t mid = lo + (hi - lo) / 2;
      bound(d + 1, 2 * j) = lo;
      bound(d + 1, 2 * j + 1) = mid;
      if (hi - lo >= 2) {
        Eigen::Vector2d min = placed[lo].at, max = min;
        for (std::uint32_t k = lo; k < hi; ++k) {
          min = min.cwiseMin(placed[k].at);
          max = max.cwiseMax(placed[k].at);
        }
        const int axis = (max - min).x() >= (max - min).y() ? 0 : 1;
        std::nth_element(placed.begin() + lo, placed.begin() + mid, placed.begin() + hi, [axis](const Placed& a, const Placed& b) {
          return a.at[axis] < b.at[axis] || (a.at[axis] == b.at[axis] && a.ray < b.ray);
        });
      }
    }
    bound(d + 1, std::size_t{2} << d) = static_cast<std::uint32_t>(n);
  }
  order_.resize(n);
  for (std::size_t i = 0; i < n; ++i) order_[i] = placed[i].ray;
  levels_ = levels_ - first_log2_ + 1;
}

bool StratifiedSample::isOf(std::span<const Eigen::Vector3d> directions, std::size_t first_strata) const {
  return firstStrata() == roundedStrata(first_strata) && directions.size() == directions_.size() &&
         std::memcmp(directions.data(), directions_.data(), directions.size_bytes()) == 0;
}

std::shared_ptr<const StratifiedSample> StratifiedSample::shared(std::span<const Eigen::Vector3d> directions,
                                                                 std::size_t first_strata) {
  static detail::RecentlyBuilt<StratifiedSample, 4> kept;
  return kept.get([&](const StratifiedSample& s) { return s.isOf(directions, first_strata); },
                  [&] { return std::make_shared<const StratifiedSample>(directions, first_strata); });
}

std::vector<StratifiedSample::Stratum> StratifiedSample::level(std::size_t l, std::uint64_t seed) const {
  if (l >= levels_) throw InvalidArgument("level " + std::to_string(l) + " of a sample of " + std::to_string(levels_));
  // A tile's drawn position: its parent's when that falls in it, else a uniform draw of its own.
  auto draw = [&](std::size_t d, std::size_t j, std::uint32_t inherited) -> std::uint32_t {
    const std::uint32_t lo = bound(d, j), hi = bound(d, j + 1);
    if (hi == lo) return kNoRay;
    if (inherited != kNoRay && inherited >= lo && inherited < hi) return inherited;
    const std::uint64_t r = mix(seed ^ mix((static_cast<std::uint64_t>(d) << 40) ^ j));
    return lo + static_cast<std::uint32_t>(r % (hi - lo));
  };
  std::vector<std::uint32_t> positions(std::size_t{1} << first_log2_);
  for (std::size_t j = 0; j < positions.size(); ++j) positions[j] = draw(first_log2_, j, kNoRay);
  for (std::size_t d = first_log2_; d < first_log2_ + l; ++d) {
    std::vector<std::uint32_t> children(positions.size() * 2);
    for (std::size_t j = 0; j < positions.size(); ++j) {
      children[2 * j] = draw(d + 1, 2 * j, positions[j]);
      children[2 * j + 1] = draw(d + 1, 2 * j + 1, positions[j]);
    }
    positions = std::move(children);
  }
  std::vector<Stratum> strata(positions.size());
  const std::size_t d = first_log2_ + l;
  for (std::size_t j = 0; j < strata.size(); ++j) {
    strata[j].size = bound(d, j + 1) - bound(d, j);
    strata[j].ray = positions[j] == kNoRay ? kNoRay : order_[positions[j]];
  }
  return strata;
}

// --- estimates and intervals ---------------------------------------------------------------------

SampleTotals::SampleTotals(const Strata& strata, const std::vector<kernels::RayResult>& sums) {
  if (strata.size() != sums.size()) throw InvalidArgument("a sample's totals need one ray's sums per stratum");
  per_ray.resize(strata.size());
  std::array<double, ViewTotals::kFields> total{};
  for (std::size_t h = 0; h < strata.size(); ++h) {
    if (strata[h].size == 0) continue;
    kernels::ViewSums one;
    one.add(sums[h]);
    per_ray[h] = ViewTotals::of(one);
    const auto f = per_ray[h].fields();
    for (std::size_t k = 0; k < f.size(); ++k) total[k] += static_cast<double>(strata[h].size) * f[k];  // N_h y_h
  }
  totals = ViewTotals::fromFields(total);
}

std::vector<std::vector<std::size_t>> ratioDenominators(std::span<const Metric> metrics, std::uint64_t held) {
  std::vector<std::vector<std::size_t>> out;
  for (const Metric m : metrics) {
    const kernels::Denominator& d = kernels::metricRow(m).denominator;
    if (d.count == 0 || (d.needs != 0 && (held & d.needs) == 0)) continue;
    std::vector<std::size_t>& fields = out.emplace_back();
    for (std::size_t k = 0; k < d.count; ++k) fields.push_back(static_cast<std::size_t>(d.fields[k]));
  }
  return out;
}

double deltaMethodVariance(const SampleTotals& sample, const Strata& strata, const ValueOfTotals& f) {
  for (const std::vector<std::size_t>& fields : f.denominators) {
    auto denominator = [&](const ViewTotals& t) {
      const auto values = t.fields();
      double d = 0.0;
      for (const std::size_t k : fields) d += values[k];
      return d;
    };
    const double d = denominator(sample.totals);
    const double se = std::sqrt(collapsedVariance(strata, [&](std::size_t h) { return denominator(sample.per_ray[h]); }));
    if (!(d > 0.0) || se > kMaxDenominatorError * d) return std::numeric_limits<double>::infinity();
  }
  const auto at = sample.totals.fields();
  std::array<double, ViewTotals::kFields> gradient{};
  for (std::size_t k = 0; k < at.size(); ++k) {
    const double step = 1e-6 * std::max(1.0, std::abs(at[k]));
    auto plus = at, minus = at;
    plus[k] += step;
    minus[k] -= step;
    gradient[k] = (f.value(ViewTotals::fromFields(plus)) - f.value(ViewTotals::fromFields(minus))) / (2.0 * step);
  }
  auto linear = [&](const ViewTotals& y) {
    const auto values = y.fields();
    double z = 0.0;
    for (std::size_t k = 0; k < values.size(); ++k) z += gradient[k] * values[k];
    return z;
  };
  return collapsedVariance(strata, [&](std::size_t h) { return linear(sample.per_ray[h]); });
}

double normalQuantile(double p) {
  // Bisection on erfc, to 1e-12.
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Interval estimateMetric(const Strata& strata, const std::vector<kernels::RayResult>& sums, Metric metric, double p) {
  if (strata.size() != sums.size()) throw InvalidArgument("estimateMetric: one ray's sums per stratum");
  if (!(p > 0.0 && p < 1.0)) throw InvalidArgument("estimateMetric: p " + numberText(p) + " must lie in (0, 1)");
  if (metric == Metric::Random) throw InvalidArgument("estimateMetric: 'random' has no rays to estimate from");
  const SampleTotals sample(strata, sums);
  const Metric one[] = {metric};
  const ValueOfTotals f{[metric](const ViewTotals& t) { return kernels::metricValue(t, metric); }, ratioDenominators(one)};
  Interval out;
  out.estimate = f.value(sample.totals);
  const double half = normalQuantile(p) * std::sqrt(deltaMethodVariance(sample, strata, f));
  out.lower = out.estimate - half;
  out.upper = out.estimate + half;
  return out;
}

}  // namespace nbv::ig
