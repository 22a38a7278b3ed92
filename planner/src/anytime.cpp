#include "nbv/planner/anytime.hpp"

#include "nbv/errors.hpp"
#include "nbv/fork_join.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
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
  if (!(epsilon >= 0.0 && epsilon < 1.0)) throw InvalidArgument("epsilon " + numberText(epsilon) + " must lie in [0, 1)");
  if (!(delta > 0.0 && delta < 1.0)) throw InvalidArgument("delta " + numberText(delta) + " must lie in (0, 1)");
  if (max_rays && *max_rays == 0) throw InvalidArgument("max_rays must be at least 1");
  if (max_ms && !(*max_ms > 0.0 && std::isfinite(*max_ms))) {
    throw InvalidArgument("time budget " + numberText(*max_ms) + " ms must be finite and > 0");
  }
  if (first_strata == 0) throw InvalidArgument("first_strata must be at least 1");
}

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
  const std::size_t k_count = T_world_cameras.size();
  if (k_count == 0) throw InvalidArgument("a decision needs at least one candidate");
  utility.validate(k_count);
  walk.validate();
  // What the walks sum and the exact finish's table hold: the utility's metrics.
  const ig::TableOptions table_options{utility.metrics(), utility.random_seed};
  // (A ratio the snapshot makes 0 for every ray, kr on a map without an occupied voxel, has none.)
  const std::vector<std::vector<std::size_t>> denominators =
      ig::ratioDenominators(table_options.metrics, evaluator_.lastSnapshotUpdate().flags);

  if (directions.empty()) throw InvalidArgument("no ray direction given: the ray set is empty");
  if (!sample_ || !sample_->isOf(directions, options.first_strata)) {
    sample_ = StratifiedSample::shared(directions, options.first_strata);
  }
  const StratifiedSample& sample = *sample_;
  const std::size_t n = directions.size();
  AnytimeDecision decision;
  decision.candidates.resize(k_count);
  decision.rays_exhaustive = static_cast<std::uint64_t>(k_count) * n;
  UtilityModel model(utility, k_count);
  std::vector<ViewTotals> totals(k_count);
  std::vector<bool> alive(k_count, true);
  // Every interval of every candidate at every level holds with probability 1 - delta_each:
  // together (Bonferroni) all hold with probability at least 1 - delta.
  const double z = ig::normalQuantile(options.delta / static_cast<double>(k_count * sample.levels()));
  const bool finish_exact = options.epsilon == 0.0 && !options.max_rays && !options.max_ms;

  std::vector<std::vector<kernels::RayResult>> sums(k_count);  // per candidate, per stratum of the level
  Strata strata;
  std::optional<DecisionEnd> end;
  for (std::size_t level = 0; !end; ++level) {
    // Walk the level's new rays (all strata at level 0, then the sibling that did not inherit)
    // for the candidates still in.
    const Strata next = sample.level(level, options.seed);
    const FreshRays fresh = freshRays(strata, next);
    const std::vector<std::size_t> walked = stillIn(alive);
    std::vector<std::vector<kernels::RayResult>> out;
    evaluator_.walkChosen(posesOf(T_world_cameras, walked), directions,
                          std::vector<std::vector<std::uint32_t>>(walked.size(), fresh.rays), table_options.metrics, walk,
                          out);
    // Each candidate's sums per stratum and estimates, then its interval: one candidate per
    // task, each written to its own place, so the thread count changes nothing.
    std::vector<ig::SampleTotals> estimates(k_count);
    forEachCandidate(walked.size(), walk, [&](std::size_t w) {
      const std::size_t c = walked[w];
      sums[c] = levelSums(strata, next, sums[c], fresh, out[w]);
      estimates[c] = ig::SampleTotals(next, sums[c]);
      totals[c] = estimates[c].totals;
    });
    for (const std::size_t c : walked) {
      decision.candidates[c].rays += fresh.rays.size();
      decision.rays_cast += fresh.rays.size();
    }
    strata = next;
    decision.levels = level + 1;
    model.refresh(totals);
    forEachCandidate(walked.size(), walk, [&](std::size_t w) {
      const std::size_t c = walked[w];
      CandidateEstimate& e = decision.candidates[c];
      e.estimate = model(totals[c], c);
      const ig::ValueOfTotals f{[&](const ViewTotals& t) { return model(t, c); }, denominators};
      const double half = z * std::sqrt(ig::deltaMethodVariance(estimates[c], strata, f));
      e.lower = e.estimate - half;
      e.upper = e.estimate + half;
    });
    double best_lower = -std::numeric_limits<double>::infinity();
    for (const std::size_t c : walked) best_lower = std::max(best_lower, decision.candidates[c].lower);
    // Elimination: a candidate whose upper bound lies below the best lower bound cannot win.
    std::size_t left = 0;
    double max_upper = -std::numeric_limits<double>::infinity();
    for (const std::size_t c : walked) {
      if (decision.candidates[c].upper < best_lower) {
        alive[c] = false;
        decision.candidates[c].eliminated = true;
      } else {
        ++left;
        max_upper = std::max(max_upper, decision.candidates[c].upper);
      }
    }
    // The end: one left, all within epsilon, the budget spent, or the full set next.
    const std::size_t leader = leaderOf(decision.candidates, alive);
    const bool within_epsilon = decision.candidates[leader].lower >= max_upper - options.epsilon * std::abs(max_upper);
    // Past an eighth of the rays, the candidates left are evaluated on every ray: sampling on
    // would cast about as many rays again, and a tie or a near tie never resolves by samples.
    const bool last_level = level + 1 >= sample.levels() || 8 * strata.size() >= n;
    if ((options.max_rays && decision.rays_cast >= *options.max_rays) || (options.max_ms && elapsed_ms() >= *options.max_ms)) {
      end = DecisionEnd::Budget;
    } else if (!finish_exact && left == 1) {
      end = DecisionEnd::OneLeft;
    } else if (!finish_exact && options.epsilon > 0.0 && within_epsilon) {
      end = DecisionEnd::Epsilon;
    } else if (finish_exact ? (left == 1 || last_level) : last_level) {
      end = DecisionEnd::Exact;
    }
  }

  if (*end == DecisionEnd::Exact) {  // the candidates left, on every ray: the exhaustive bits
    const std::vector<std::size_t> finalists = stillIn(alive);
    const ig::IgTable table = evaluator_.evaluate(posesOf(T_world_cameras, finalists), directions, table_options, walk);
    for (std::size_t f = 0; f < finalists.size(); ++f) {
      totals[finalists[f]] = ViewTotals::of(table.sums[f]);
      decision.candidates[finalists[f]].rays += n;
      decision.candidates[finalists[f]].exact = true;
    }
    decision.rays_cast += static_cast<std::uint64_t>(finalists.size()) * n;
    model.refresh(totals);
    for (const std::size_t c : finalists) {
      CandidateEstimate& e = decision.candidates[c];
      e.estimate = e.lower = e.upper = model(totals[c], c);
    }
  }
  decision.chosen = leaderOf(decision.candidates, alive);
  decision.end = *end;
  decision.seconds = elapsed_ms() / 1e3;
  return decision;
}

}  // namespace nbv::planner
