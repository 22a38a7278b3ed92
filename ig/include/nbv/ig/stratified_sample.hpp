#pragma once
/// \file Estimates of a view's information gain from a sample of its rays (SEMANTICS.md
/// "Anytime decisions"): nested stratified samples of a ray set, the expansion estimate of a
/// view's totals from one ray per stratum, and the interval of any function of those totals
/// (delta method, collapsed strata, normal). A planner's anytime decision is built on these.

#include "nbv/kernels/information_gain.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace nbv::ig {

using kernels::Metric;

/// Nested stratified samples of a ray set: the rays, placed by where they cross the image
/// plane, split in halves along the longer side, again and again, into a tree of compact
/// tiles; level l has 2^(k + l) strata, each holding one ray drawn uniformly from it with the
/// seed, and each level keeps the rays of the one before. Immutable; thread-safe.
class StratifiedSample {
 public:
  /// \throws InvalidArgument for no direction.
  StratifiedSample(std::span<const Eigen::Vector3d> directions_camera, std::size_t first_strata);

  std::size_t rays() const { return order_.size(); }
  std::size_t firstStrata() const { return std::size_t{1} << first_log2_; }
  /// Levels until every stratum holds one ray.
  std::size_t levels() const { return levels_; }
  /// One stratum of a level: its ray count and its drawn ray (an index into the directions;
  /// none for an empty stratum). Strata 2j and 2j + 1 are siblings (halves of one tile).
  struct Stratum {
    std::uint32_t size = 0;
    std::uint32_t ray = 0;
  };
  static constexpr std::uint32_t kNoRay = 0xFFFFFFFFu;
  /// The strata of level `l` with the rays `seed` draws. \throws InvalidArgument for l >= levels().
  std::vector<Stratum> level(std::size_t l, std::uint64_t seed) const;
  /// The first-level strata a sample built with `first_strata` has (the next power of two).
  static std::size_t roundedStrata(std::size_t first_strata);
  /// Whether this is the sample of `directions_camera` (the same bits) with `first_strata`.
  bool isOf(std::span<const Eigen::Vector3d> directions_camera, std::size_t first_strata) const;
  /// The sample of `directions_camera` with `first_strata`, shared: the last few built in the
  /// process are kept, so that every decider of a process (one per reconstruction) builds the
  /// sample of a ray set once (the full set's takes tens of milliseconds). Thread-safe.
  /// \throws InvalidArgument for no direction.
  static std::shared_ptr<const StratifiedSample> shared(std::span<const Eigen::Vector3d> directions_camera,
                                                        std::size_t first_strata);

 private:
  std::uint32_t bound(std::size_t depth, std::size_t tile) const { return bounds_[(std::size_t{1} << depth) - 1 + depth + tile]; }
  std::vector<Eigen::Vector3d> directions_;  ///< the directions it was built from
  std::vector<std::uint32_t> order_;   ///< ray indices, every tile a contiguous range
  std::vector<std::uint32_t> bounds_;  ///< per depth d, the 2^d + 1 bounds of its tiles in order_
  std::size_t first_log2_ = 0;
  std::size_t levels_ = 0;
};

using Strata = std::vector<StratifiedSample::Stratum>;

/// The expansion estimate of a view's totals from one level's sample, sum over strata of
/// N_h y_h (`sums[h]`: the drawn ray of stratum h), and the per-ray totals y_h an interval is
/// built from (zero for an empty stratum). \throws InvalidArgument if the sizes differ.
struct SampleTotals {
  SampleTotals() = default;
  SampleTotals(const Strata& strata, const std::vector<kernels::RayResult>& sums);
  kernels::ViewTotals totals;
  std::vector<kernels::ViewTotals> per_ray;
};

/// What an interval is built for: a view's value as a function of its totals, and the ratio
/// denominators it divides by (fields of ViewTotals summed, as the metric table's rows give
/// them), whose estimates must be good before the delta method is trusted.
struct ValueOfTotals {
  std::function<double(const kernels::ViewTotals&)> value;
  std::vector<std::vector<std::size_t>> denominators;
};

/// The denominators of the ratio metrics among `metrics` (kr its surface voxels, vg its
/// classified rays), one entry per ratio metric, but for those a snapshot holding only the
/// voxel flags `held` (SnapshotUpdate::flags) makes 0 for every ray (Denominator::needs): such
/// a metric is exactly 0 for every view, an estimate without variance.
std::vector<std::vector<std::size_t>> ratioDenominators(std::span<const Metric> metrics,
                                                        std::uint64_t held = ~std::uint64_t{0});

/// The variance of value(estimate) by the delta method: the value linearised at the estimate
/// (numerical gradient), the variance of the linearised per-ray values by collapsed strata
/// (siblings 2j, 2j + 1 as one stratum of two draws; an overestimate when their means differ).
/// Infinite while some denominator's relative standard error is above 5 % (or it is not
/// positive): a ratio is then too unstable for the delta method.
double deltaMethodVariance(const SampleTotals& sample, const Strata& strata, const ValueOfTotals& f);

/// z with P(|N(0, 1)| > z) = p: the half-width, in standard deviations, of a two-sided normal
/// interval at level 1 - p.
double normalQuantile(double p);

/// A value estimated from a sample and its confidence interval.
struct Interval {
  double estimate = 0.0;
  double lower = 0.0;
  double upper = 0.0;
};

/// The estimate of one metric's view value from one level's sample, and its interval at level
/// 1 - p. \throws InvalidArgument if the sizes differ, p is not in (0, 1) or the metric is random.
Interval estimateMetric(const Strata& strata, const std::vector<kernels::RayResult>& sums, Metric metric, double p);

}  // namespace nbv::ig
