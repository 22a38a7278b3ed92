#include "nbv/planner/anytime.hpp"

#include "nbv/errors.hpp"
#include "nbv/fork_join.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace nbv::planner {

using ig::Strata;
using ig::StratifiedSample;
using kernels::ViewTotals;

// --- options -------------------------------------------------------------------------------------

std::vector<ig::Metric> DecisionUtility::metrics() const { return metricsOf(terms); }

void DecisionUtility::validate(std::size_t candidates) const {
  if (terms.empty()) throw InvalidArgument("the utility names no metric");
  for (const MetricWeight& t : terms) {
    if (!(std::isfinite(t.weight) && t.weight > 0.0)) {
      throw InvalidArgument("metric weight " + numberText(t.weight) + " must be finite and positive");
    }
  }
  if (!(gamma >= 0.0 && gamma <= 1.0)) throw InvalidArgument("gamma " + numberText(gamma) + " must lie in [0, 1]");
  if (!costs.empty() && costs.size() != candidates) {
    throw InvalidArgument(std::to_string(costs.size()) + " costs for " + std::to_string(candidates) + " candidates");
  }
  if (gamma > 0.0 && costs.empty()) throw InvalidArgument("gamma > 0 needs the candidates' costs");
}

void DecideOptions::validate() const {
  const DecideOptions& c = *this;
#define NBV_DECIDE_CHECK(...) NBV_OPTION_CHECK("anytime", __VA_ARGS__)
  NBV_DECIDE_OPTIONS(NBV_DECIDE_CHECK)
#undef NBV_DECIDE_CHECK
  if (max_rays && *max_rays == 0) throw InvalidArgument("max_rays must be at least 1");
  if (first_strata == 0) throw InvalidArgument("first_strata must be at least 1");
}

std::span<const DecideOption> decideOptions() {
#define NBV_DECIDE_ROW(...) NBV_OPTION_ROW(DecideOptions, __VA_ARGS__)
  static constexpr DecideOption kOptions[] = {NBV_DECIDE_OPTIONS(NBV_DECIDE_ROW)};
#undef NBV_DECIDE_ROW
  return kOptions;
}

const DecideOption* decideOption(std::string_view name) { return optionRow(decideOptions(), name); }

const char* decisionEndName(DecisionEnd end) {
  switch (end) {
    case DecisionEnd::OneLeft: return "one_left";
    case DecisionEnd::Epsilon: return "epsilon";
    case DecisionEnd::Exact: return "exact";
    case DecisionEnd::Budget: return "budget";
  }
  return "?";
}

// --- the decision --------------------------------------------------------------------------------

namespace {

/// The utility of one candidate as a function of its view totals, with the plug-in constants
/// shared by all candidates (the sums a normalised weighting divides by, Eq. 12's totals).
class UtilityModel {
 public:
  UtilityModel(const DecisionUtility& u, std::size_t candidates) : u_(u), candidates_(candidates) {
    normalize_ = u.weighting == Weighting::Normalized && u.terms.size() > 1;
    scale_.assign(u.terms.size(), 1.0);
  }

  /// Sets the plug-in constants from every candidate's current totals.
  void refresh(const std::vector<ViewTotals>& totals) {
    for (std::size_t t = 0; t < u_.terms.size() && normalize_; ++t) {
      double sum = 0.0;
      for (std::size_t c = 0; c < candidates_; ++c) sum += term(totals[c], c, t);
      scale_[t] = sum != 0.0 ? 1.0 / sum : 0.0;
    }
    gain_total_ = cost_total_ = 0.0;
    for (std::size_t c = 0; c < candidates_; ++c) {
      gain_total_ += gain(totals[c], c);
      if (!u_.costs.empty()) cost_total_ += u_.costs[c];
    }
  }

  /// Whether a candidate's utility depends on the other candidates' totals.
  bool shared() const { return normalize_ || u_.gamma != 0.0; }

  /// Eq. 12 (with gamma 0: the gain itself, which orders the views as Eq. 12 does).
  double operator()(const ViewTotals& totals, std::size_t c) const {
    const double g = gain(totals, c);
    if (u_.gamma == 0.0) return g;
    const double gain_term = gain_total_ != 0.0 ? g / gain_total_ : 0.0;
    const double cost_term = cost_total_ != 0.0 ? u_.costs[c] / cost_total_ : 0.0;
    return (1.0 - u_.gamma) * gain_term - u_.gamma * cost_term;
  }

 private:
  double term(const ViewTotals& totals, std::size_t c, std::size_t t) const {
    const ig::Metric m = u_.terms[t].metric;
    return m == ig::Metric::Random ? kernels::randomScore(u_.random_seed, c) : kernels::metricValue(totals, m);
  }
  double gain(const ViewTotals& totals, std::size_t c) const {
    double g = 0.0;
    for (std::size_t t = 0; t < u_.terms.size(); ++t) g += u_.terms[t].weight * (normalize_ ? term(totals, c, t) * scale_[t] : term(totals, c, t));
    return g;
  }

  const DecisionUtility& u_;
  std::size_t candidates_;
  bool normalize_ = false;
  std::vector<double> scale_;
  double gain_total_ = 0.0, cost_total_ = 0.0;
};

/// Whether stratum h of a level keeps the ray of its parent in the level before (`before`;
/// empty at level 0), whose sums it then inherits instead of walking the ray again.
bool inherits(const Strata& before, const Strata& level,
              std::size_t h) {
  return !before.empty() && level[h].size > 0 && before[h / 2].size > 0 && before[h / 2].ray == level[h].ray;
}

/// The rays a level walks: the drawn ray of each non-empty stratum that does not inherit, and
/// the stratum it is drawn for.
struct FreshRays {
  std::vector<std::uint32_t> rays, strata;
};

FreshRays freshRays(const Strata& before, const Strata& level) {
  FreshRays fresh;
  for (std::size_t h = 0; h < level.size(); ++h) {
    if (level[h].size == 0 || inherits(before, level, h)) continue;
    fresh.rays.push_back(level[h].ray);
    fresh.strata.push_back(static_cast<std::uint32_t>(h));
  }
  return fresh;
}

/// One candidate's sums per stratum of a level: inherited from the level before (`sums`, per
/// stratum of `before`) or walked now (`walked`, per ray of `fresh`).
std::vector<kernels::RayResult> levelSums(const Strata& before,
                                        const Strata& level,
                                        const std::vector<kernels::RayResult>& sums, const FreshRays& fresh,
                                        const std::vector<kernels::RayResult>& walked) {
  std::vector<kernels::RayResult> out(level.size());
  for (std::size_t h = 0; h < level.size(); ++h) {
    if (inherits(before, level, h)) out[h] = sums[h / 2];
  }
  for (std::size_t f = 0; f < fresh.strata.size(); ++f) out[fresh.strata[f]] = walked[f];
  return out;
}

/// The levels a decision samples at most: up to the first whose strata hold an eighth of the
/// rays (the decision then finishes on every ray), or to the last.
std::size_t sampledLevels(const StratifiedSample& sample) {
  std::size_t l = 0;
  while (l + 1 < sample.levels() && 8 * (sample.firstStrata() << l) < sample.rays()) ++l;
  return l + 1;
}

/// The candidates still in, in index order.
std::vector<std::size_t> stillIn(const std::vector<bool>& alive) {
  std::vector<std::size_t> in;
  for (std::size_t c = 0; c < alive.size(); ++c) {
    if (alive[c]) in.push_back(c);
  }
  return in;
}

/// The poses of `candidates`, in their order.
std::vector<Eigen::Isometry3d> posesOf(std::span<const Eigen::Isometry3d> T_world_cameras,
                                       const std::vector<std::size_t>& candidates) {
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(candidates.size());
  for (const std::size_t c : candidates) poses.push_back(T_world_cameras[c]);
  return poses;
}

/// task(i) for i in [0, count): in TBB tasks, or in order on the calling thread if `walk` is
/// serial.
template <class Task>
void forEachCandidate(std::size_t count, const ig::WalkOptions& walk, const Task& task) {
  if (walk.serial) {
    for (std::size_t i = 0; i < count; ++i) task(i);
  } else {
    ForkJoin::parallelFor(count, task);
  }
}

/// The candidate still in with the best estimate, the lowest index on ties.
std::size_t leaderOf(const std::vector<CandidateEstimate>& candidates, const std::vector<bool>& alive) {
  std::size_t leader = candidates.size();
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    if (alive[c] && (leader == candidates.size() || candidates[c].estimate > candidates[leader].estimate)) leader = c;
  }
  return leader;
}

/// One anytime decision in progress (SEMANTICS.md "Anytime decisions"): the candidates'
/// samples, totals, intervals and states, with the steps of the decision's loop as methods.
///
/// Each candidate climbs the levels on its own: a round walks the next level of the candidates
/// that keep the decision from ending (the leader and every rival whose upper bound the
/// leader's lower bound does not yet reach within epsilon); a rival it reaches waits at its
/// level, its interval standing, until the leader's lower bound falls back.
class Decision {
 public:
  /// A decision over the candidates `poses` with the options checked by the caller; the
  /// evaluator's snapshot as last refreshed is the map every step sees.
  Decision(ig::IgEvaluator& evaluator, const StratifiedSample& sample, std::span<const Eigen::Isometry3d> poses,
           std::span<const Eigen::Vector3d> directions, const DecisionUtility& utility, const ig::WalkOptions& walk,
           const DecideOptions& options)
      : evaluator_(evaluator), sample_(sample), poses_(poses), directions_(directions), walk_(walk),
        options_(options), table_options_{utility.metrics(), utility.random_seed},
        // (A ratio the snapshot makes 0 for every ray, kr on a map without an occupied voxel, has none.)
        denominators_(ig::ratioDenominators(table_options_.metrics, evaluator.lastSnapshotUpdate().flags)),
        model_(utility, poses.size()), totals_(poses.size()), alive_(poses.size(), true),
        waiting_(poses.size(), false), reached_(poses.size(), 0), sums_(poses.size()),
        estimates_(poses.size()), fresh_(sample.levels()), sampled_levels_(sampledLevels(sample)),
        // Every interval of every candidate at every level it may sample holds with
        // probability 1 - delta_each: together (Bonferroni) all hold with probability at
        // least 1 - delta.
        z_(ig::normalQuantile(options.delta / static_cast<double>(poses.size() * sampled_levels_))),
        finish_exact_(options.epsilon == 0.0 && !options.max_rays && !options.max_ms) {
    result_.candidates.resize(poses.size());
    result_.rays_exhaustive = static_cast<std::uint64_t>(poses.size()) * directions.size();
  }

  /// One round: the next level of every candidate left that does not wait, walked, and the
  /// intervals it moved. Returns whether some candidate walked the last level a decision
  /// samples (past an eighth of the rays it finishes on every ray: sampling on would cast
  /// about as many rays again, and a tie or a near tie never resolves by samples).
  bool walkRound();
  /// Elimination: a candidate whose upper bound lies below the best lower bound cannot win.
  /// Returns the candidates left.
  std::size_t eliminate();
  /// A rival waits while the leader's lower bound reaches its upper bound less epsilon of it.
  /// Returns whether every rival left waits: the decision is then within epsilon (the
  /// leader's own upper bound bounds no rival).
  bool settle();
  /// Why the decision ends after a round, if it does.
  std::optional<DecisionEnd> end(std::size_t left, bool within_epsilon, bool last_level, double elapsed_ms) const;
  /// On every ray (the exhaustive bits): every candidate left when epsilon is 0; else the
  /// leader and the rivals that do not wait, and again for a new leader, until the leader is
  /// exact and every rival left on samples waits.
  void finishOnEveryRay();
  /// The decision ended by `end`, which took `seconds`.
  AnytimeDecision result(DecisionEnd end, double seconds) && {
    result_.chosen = leaderOf(result_.candidates, alive_);
    result_.end = end;
    result_.seconds = seconds;
    return std::move(result_);
  }

 private:
  /// The sample's level `l`, drawn when some candidate first reaches it.
  const Strata& strataOf(std::size_t l) {
    while (levels_.size() <= l) levels_.push_back(sample_.level(levels_.size(), options_.seed));
    return levels_[l];
  }
  /// Candidate c's estimate and interval from its totals (its level's sample, or every ray).
  void setInterval(std::size_t c);
  /// After the totals of `changed` moved: the plug-in sums, then the intervals of those, and
  /// of every candidate left when a candidate's utility depends on the others' totals (a
  /// normalised weighting, Eq. 12's cost term).
  void reestimate(const std::vector<std::size_t>& changed);

  ig::IgEvaluator& evaluator_;
  const StratifiedSample& sample_;
  std::span<const Eigen::Isometry3d> poses_;
  std::span<const Eigen::Vector3d> directions_;
  const ig::WalkOptions& walk_;
  const DecideOptions& options_;
  const ig::TableOptions table_options_;  ///< what the walks sum and the exact finish's table hold
  const std::vector<std::vector<std::size_t>> denominators_;
  UtilityModel model_;
  std::vector<ViewTotals> totals_;  ///< per candidate, of its level's sample or of every ray
  std::vector<bool> alive_, waiting_;
  std::vector<std::size_t> reached_;  ///< per candidate, the levels it has walked
  std::vector<std::vector<kernels::RayResult>> sums_;  ///< per candidate, per stratum of its level
  std::vector<ig::SampleTotals> estimates_;
  std::vector<Strata> levels_;  ///< the sample's levels as far as some candidate reached
  std::vector<std::optional<FreshRays>> fresh_;  ///< per level, what it walks
  const Strata none_;
  const std::size_t sampled_levels_;
  const double z_;
  const bool finish_exact_;
  AnytimeDecision result_;
};

void Decision::setInterval(std::size_t c) {
  CandidateEstimate& e = result_.candidates[c];
  e.estimate = e.lower = e.upper = model_(totals_[c], c);
  if (e.exact) return;
  const ig::ValueOfTotals f{[&](const ViewTotals& t) { return model_(t, c); }, denominators_};
  const double half = z_ * std::sqrt(ig::deltaMethodVariance(estimates_[c], levels_[reached_[c] - 1], f));
  e.lower = e.estimate - half;
  e.upper = e.estimate + half;
}

void Decision::reestimate(const std::vector<std::size_t>& changed) {
  model_.refresh(totals_);
  const std::vector<std::size_t> updated = model_.shared() ? stillIn(alive_) : changed;
  forEachCandidate(updated.size(), walk_, [&](std::size_t u) { setInterval(updated[u]); });
}

bool Decision::walkRound() {
  // The candidates to walk, those at the same level side by side (walkChosen sorts a list once
  // for the views that share it).
  std::vector<std::size_t> walked;
  for (std::size_t c = 0; c < poses_.size(); ++c) {
    if (alive_[c] && !waiting_[c]) walked.push_back(c);
  }
  std::stable_sort(walked.begin(), walked.end(), [&](std::size_t a, std::size_t b) { return reached_[a] < reached_[b]; });
  std::vector<std::vector<std::uint32_t>> lists;
  lists.reserve(walked.size());
  for (const std::size_t c : walked) {
    const std::size_t l = reached_[c];
    if (!fresh_[l]) fresh_[l] = freshRays(l > 0 ? strataOf(l - 1) : none_, strataOf(l));
    lists.push_back(fresh_[l]->rays);
  }
  std::vector<std::vector<kernels::RayResult>> out;
  evaluator_.walkChosen(posesOf(poses_, walked), directions_, lists, table_options_.metrics, walk_, out);
  // Each candidate's sums per stratum and estimates: one candidate per task, each written to
  // its own place, so the thread count changes nothing.
  forEachCandidate(walked.size(), walk_, [&](std::size_t w) {
    const std::size_t c = walked[w], l = reached_[c];
    sums_[c] = levelSums(l > 0 ? levels_[l - 1] : none_, levels_[l], sums_[c], *fresh_[l], out[w]);
    estimates_[c] = ig::SampleTotals(levels_[l], sums_[c]);
    totals_[c] = estimates_[c].totals;
  });
  bool last_level = false;
  for (const std::size_t c : walked) {
    const std::size_t l = reached_[c]++;
    result_.candidates[c].rays += fresh_[l]->rays.size();
    result_.rays_cast += fresh_[l]->rays.size();
    result_.levels = std::max(result_.levels, l + 1);
    last_level = last_level || l + 1 >= sampled_levels_;
  }
  reestimate(walked);
  return last_level;
}

std::size_t Decision::eliminate() {
  double best_lower = -std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < poses_.size(); ++c) {
    if (alive_[c]) best_lower = std::max(best_lower, result_.candidates[c].lower);
  }
  std::size_t left = 0;
  for (std::size_t c = 0; c < poses_.size(); ++c) {
    if (!alive_[c]) continue;
    if (result_.candidates[c].upper < best_lower) {
      alive_[c] = false;
      result_.candidates[c].eliminated = true;
    } else {
      ++left;
    }
  }
  return left;
}

bool Decision::settle() {
  const std::size_t leader = leaderOf(result_.candidates, alive_);
  bool all = true;
  for (std::size_t c = 0; c < poses_.size(); ++c) {
    if (!alive_[c]) continue;
    const double upper = result_.candidates[c].upper;
    waiting_[c] = c != leader && result_.candidates[leader].lower >= upper - options_.epsilon * std::abs(upper);
    all = all && (c == leader || waiting_[c]);
  }
  return all;
}

std::optional<DecisionEnd> Decision::end(std::size_t left, bool within_epsilon, bool last_level,
                                         double elapsed_ms) const {
  if ((options_.max_rays && result_.rays_cast >= *options_.max_rays) || (options_.max_ms && elapsed_ms >= *options_.max_ms)) {
    return DecisionEnd::Budget;
  }
  if (!finish_exact_ && left == 1) return DecisionEnd::OneLeft;
  if (!finish_exact_ && options_.epsilon > 0.0 && within_epsilon) return DecisionEnd::Epsilon;
  if (finish_exact_ ? (left == 1 || last_level) : last_level) return DecisionEnd::Exact;
  return std::nullopt;
}

void Decision::finishOnEveryRay() {
  for (;;) {
    std::vector<std::size_t> finalists;
    for (std::size_t c = 0; c < poses_.size(); ++c) {
      if (alive_[c] && !result_.candidates[c].exact && (finish_exact_ || !waiting_[c])) finalists.push_back(c);
    }
    if (finalists.empty()) return;
    const ig::IgTable table = evaluator_.evaluate(posesOf(poses_, finalists), directions_, table_options_, walk_);
    for (std::size_t f = 0; f < finalists.size(); ++f) {
      totals_[finalists[f]] = ViewTotals::of(table.sums[f]);
      result_.candidates[finalists[f]].rays += directions_.size();
      result_.candidates[finalists[f]].exact = true;
    }
    result_.rays_cast += static_cast<std::uint64_t>(finalists.size()) * directions_.size();
    reestimate(finalists);
    settle();
  }
}

}  // namespace

const ig::SnapshotUpdate& AnytimeDecider::refresh(const grid::OccupancyMap& map, const DecisionUtility& utility,
                                                  const ig::SnapshotOptions& options) {
  return evaluator_.refresh(map, ig::snapshotFor(utility.metrics(), options));
}

AnytimeDecision AnytimeDecider::decide(std::span<const Eigen::Isometry3d> T_world_cameras,
                                       std::span<const Eigen::Vector3d> directions, const DecisionUtility& utility,
                                       const ig::WalkOptions& walk, const DecideOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed_ms = [&] { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(); };
  options.validate();
  if (T_world_cameras.empty()) throw InvalidArgument("a decision needs at least one candidate");
  utility.validate(T_world_cameras.size());
  walk.validate();
  if (directions.empty()) throw InvalidArgument("no ray direction given: the ray set is empty");
  if (!sample_ || !sample_->isOf(directions, options.first_strata)) {
    sample_ = StratifiedSample::shared(directions, options.first_strata);
  }
  Decision decision(evaluator_, *sample_, T_world_cameras, directions, utility, walk, options);
  std::optional<DecisionEnd> end;
  while (!end) {
    const bool last_level = decision.walkRound();
    const std::size_t left = decision.eliminate();
    const bool within_epsilon = decision.settle();
    end = decision.end(left, within_epsilon, last_level, elapsed_ms());
  }
  if (*end == DecisionEnd::Exact) decision.finishOnEveryRay();
  return std::move(decision).result(*end, elapsed_ms() / 1e3);
}

}  // namespace nbv::planner
