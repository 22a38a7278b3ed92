#pragma once
/// \file Anytime decisions (SEMANTICS.md "Anytime decisions"): the next best view from a
/// growing stratified sample of each candidate's rays, candidates dropped as soon as their
/// confidence interval shows they cannot win, the last ones evaluated on every ray.

#include "nbv/ig/evaluator.hpp"
#include "nbv/planner/utility.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace nbv::planner {

/// What a decision maximises: the gain of `terms` combined by `weighting` (a single metric is
/// its value), then Eq. 12 with `gamma` and the candidates' `costs` (empty: none).
struct DecisionUtility {
  std::vector<MetricWeight> terms = std::vector<MetricWeight>(1);  ///< default: Proximity Count alone
  Weighting weighting = Weighting::Normalized;
  double gamma = 0.0;
  std::vector<double> costs;    ///< one per candidate [m], or empty when gamma is 0
  std::uint64_t random_seed = 0;  ///< of Metric::Random, as ig::TableOptions::random_seed

  /// The terms' metrics, in order.
  std::vector<ig::Metric> metrics() const;
  /// \throws InvalidArgument for no term, a bad weight, gamma outside [0, 1] or a cost count
  /// that is not the candidate count.
  void validate(std::size_t candidates) const;
};

/// Options of an anytime decision. Defaults: SEMANTICS.md "Anytime decisions".
struct DecideOptions {
  double epsilon = 0.01;   ///< stop once every candidate left is within this share of the best
  double delta = 0.01;     ///< the chance that some interval misses its value, at most
  std::optional<std::uint64_t> max_rays;  ///< stop after casting this many rays (all candidates)
  std::optional<double> max_ms;           ///< stop after this many milliseconds
  std::uint64_t seed = 0;                 ///< fixes every sample
  std::size_t first_strata = 256;         ///< strata of the first level (rounded up to a power of two)

  /// \throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// One candidate at the end of a decision.
struct CandidateEstimate {
  double estimate = 0.0;  ///< its utility, estimated or exact
  double lower = 0.0;     ///< the confidence interval
  double upper = 0.0;
  bool exact = false;     ///< evaluated on every ray: estimate = lower = upper = the exhaustive value
  bool eliminated = false;  ///< left because its upper bound fell below the best lower bound
  std::uint64_t rays = 0;   ///< rays cast for it
};

/// Why a decision ended.
enum class DecisionEnd {
  OneLeft,  ///< every other candidate was eliminated
  Epsilon,  ///< every candidate left is within epsilon of the best
  Exact,    ///< the candidates left were evaluated on every ray
  Budget,   ///< max_rays or max_ms was spent
};
const char* decisionEndName(DecisionEnd end);

/// The result of an anytime decision.
struct AnytimeDecision {
  std::size_t chosen = 0;  ///< index into the candidates: the best estimate, lowest index on ties
  std::vector<CandidateEstimate> candidates;
  DecisionEnd end = DecisionEnd::OneLeft;
  std::uint64_t rays_cast = 0;        ///< all candidates, all levels, the exact finish included
  std::uint64_t rays_exhaustive = 0;  ///< what evaluating every candidate on every ray casts
  std::size_t levels = 0;             ///< sampled levels walked
  double seconds = 0.0;
};

/// Nested stratified samples of a ray set (SEMANTICS.md "Anytime decisions"): the rays, placed
/// by where they cross the image plane, split in halves along the longer side, again and
/// again, into a tree of compact tiles; level l has 2^(k + l) strata, each holding one ray
/// drawn uniformly from it with the seed, and each level keeps the rays of the one before.
/// Immutable; thread-safe.
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

 private:
  std::uint32_t bound(std::size_t depth, std::size_t tile) const { return bounds_[(std::size_t{1} << depth) - 1 + depth + tile]; }
  std::vector<std::uint32_t> order_;   ///< ray indices, every tile a contiguous range
  std::vector<std::uint32_t> bounds_;  ///< per depth d, the 2^d + 1 bounds of its tiles in order_
  std::size_t first_log2_ = 0;
  std::size_t levels_ = 0;
};

/// The step a decision repeats for each candidate, on its own: the expansion estimate of one
/// metric from one level's sample (`sums[h]`: the drawn ray of stratum h), and its interval at
/// level 1 - p (SEMANTICS.md "Anytime decisions": delta method, collapsed strata, normal).
/// \throws InvalidArgument if the sizes differ, p is not in (0, 1) or the metric is random.
CandidateEstimate estimateMetric(const std::vector<StratifiedSample::Stratum>& strata,
                                 const std::vector<kernels::RayResult>& sums, ig::Metric metric, double p);

/// Anytime decisions over one evaluator: keeps the evaluator (its snapshot of the map and its
/// ordered rays) and the sample tree of the last ray set, so a planner deciding again after
/// each scan pays for neither twice. Not thread-safe (one decision or evaluation at a time).
class AnytimeDecider {
 public:
  /// Chooses the candidate of `T_world_cameras` with the largest utility from samples of the
  /// rays `directions_camera` (unit, camera frame; their pixel layout is read from their
  /// directions), as SEMANTICS.md "Anytime decisions" defines it, on the evaluator's snapshot as
  /// last refreshed (refresh()): every level and the exact finish see one map state, and no map
  /// is read. The same inputs and seed give the same decision at any thread count; with epsilon
  /// 0 and no budget the choice is the exhaustive argmax unless an interval failed (probability
  /// at most delta). \throws InvalidArgument for bad options, utilities, views or directions;
  /// as IgEvaluator::evaluate() otherwise.
  AnytimeDecision decide(std::span<const Eigen::Isometry3d> T_world_cameras, std::span<const Eigen::Vector3d> directions_camera,
                         const DecisionUtility& utility, const ig::WalkOptions& walk = ig::WalkOptions{},
                         const DecideOptions& options = DecideOptions{});

  /// Brings the evaluator's snapshot up to `map` under `options`, with what `utility`'s metrics
  /// read (ig::snapshotFor()). \throws as IgEvaluator::refresh().
  const ig::SnapshotUpdate& refresh(const grid::OccupancyMap& map, const DecisionUtility& utility,
                                    const ig::SnapshotOptions& options = ig::SnapshotOptions{});

  /// The evaluator the decisions walk rays with; exhaustive evaluations may share it.
  ig::IgEvaluator& evaluator() { return evaluator_; }

 private:
  const StratifiedSample& sampleOf(std::span<const Eigen::Vector3d> directions_camera, std::size_t first_strata);

  ig::IgEvaluator evaluator_;
  std::unique_ptr<StratifiedSample> sample_;
  std::vector<Eigen::Vector3d> sample_directions_;  ///< the directions sample_ was built from
};

}  // namespace nbv::planner
