#pragma once
/// \file Anytime decisions (SEMANTICS.md "Anytime decisions"): the next best view from a
/// growing stratified sample of each candidate's rays (nbv/ig/stratified_sample.hpp),
/// candidates dropped as soon as their confidence interval shows they cannot win, the last
/// ones evaluated on every ray.

#include "nbv/ig/evaluator.hpp"
#include "nbv/option_table.hpp"
#include "nbv/ig/stratified_sample.hpp"
#include "nbv/planner/utility.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
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

/// The options of an anytime decision a user sets by name, as an option table
/// (nbv/option_table.hpp): X(name, type, member, unit, check, rule, help). A row is a flag of
/// `nbv decide`, and with --anytime of `nbv reconstruct` and `nbv experiment`, a keyword of
/// Python's Decider.decide() and (with anytime=True) reconstruct() and experiment(), a key of
/// a run's "anytime" object (JSON, Python, sweep.json) and a check of DecideOptions::validate().
#define NBV_DECIDE_OPTIONS(X)                                                                                    \
  X(epsilon, double, epsilon, "", v >= 0.0 && v < 1.0, "must be in [0, 1)",                                       \
    "stop once every candidate left is within this share of the best (0: the exhaustive argmax)")                 \
  X(delta, double, delta, "", v > 0.0 && v < 1.0, "must be in (0, 1)",                                            \
    "the chance that some confidence interval misses its value, at most")                                        \
  X(budget_ms, std::optional<double>, max_ms, "ms", !v || (std::isfinite(*v) && *v > 0.0), "must be finite and > 0", \
    "stop a decision after this many milliseconds (none: no limit)")

/// Options of an anytime decision. Defaults: SEMANTICS.md "Anytime decisions".
struct DecideOptions {
  double epsilon = 0.01;   ///< stop once every candidate left is within this share of the best
  double delta = 0.01;     ///< the chance that some interval misses its value, at most
  std::optional<std::uint64_t> max_rays;  ///< stop after casting this many rays (all candidates)
  std::optional<double> max_ms;           ///< stop after this many milliseconds (the option budget_ms)
  std::uint64_t seed = 0;                 ///< fixes every sample
  std::size_t first_strata = 256;         ///< strata of the first level (rounded up to a power of two)

  /// \throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// A row of NBV_DECIDE_OPTIONS as data.
using DecideOption = OptionRow<DecideOptions>;
/// The rows of NBV_DECIDE_OPTIONS, in its order.
std::span<const DecideOption> decideOptions();
/// The row named `name`, or null.
const DecideOption* decideOption(std::string_view name);

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
  Epsilon,  ///< the leader's lower bound is within epsilon of every other candidate's upper bound
  Exact,    ///< the leader and every rival it does not reach within epsilon were evaluated on every ray
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
  std::size_t levels = 0;             ///< sampled levels walked, by the candidate that walked most
  double seconds = 0.0;
};

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
  ig::IgEvaluator evaluator_;
  std::shared_ptr<const ig::StratifiedSample> sample_;  ///< of the last decision's ray set
};

}  // namespace nbv::planner
