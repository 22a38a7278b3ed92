// Anytime decisions (SEMANTICS.md "Anytime decisions"): the nested stratified samples, the
// unbiased estimator and its intervals over many seeds, and decisions equal to the exhaustive
// argmax on bunny-3 and random maps, whatever the thread count.
#include "nbv/errors.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include "random_scene.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

namespace nbv::planner {
namespace {

using ig::estimateMetric;
using ig::StratifiedSample;
using Stratum = StratifiedSample::Stratum;

std::vector<Eigen::Vector3d> raysOf(int stride) {
  return sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling{stride, 1.0});
}

TEST(StratifiedSample, LevelsAreNestedCompactAndCoverEveryRay) {
  const std::vector<Eigen::Vector3d> rays = raysOf(10);  // 76 x 48 = 3,648 rays
  const StratifiedSample sample(rays, 100);
  EXPECT_EQ(sample.firstStrata(), 128u);
  EXPECT_EQ(sample.levels(), 12u - 7u + 1u);  // 2^12 >= 3,648 rays: one per tile at the last
  std::set<std::uint32_t> previous;
  for (std::size_t l = 0; l < sample.levels(); ++l) {
    const std::vector<Stratum> strata = sample.level(l, 42);
    ASSERT_EQ(strata.size(), std::size_t{128} << l);
    std::size_t total = 0;
    std::set<std::uint32_t> drawn;
    for (std::size_t h = 0; h < strata.size(); ++h) {
      total += strata[h].size;
      if (h % 2 == 0) {
        EXPECT_LE(std::abs(int(strata[h].size) - int(strata[h + 1].size)), 1) << "halves of one tile";
      }
      if (strata[h].size == 0) {
        EXPECT_EQ(strata[h].ray, StratifiedSample::kNoRay);
        continue;
      }
      ASSERT_LT(strata[h].ray, rays.size());
      EXPECT_TRUE(drawn.insert(strata[h].ray).second) << "a ray drawn twice";
    }
    EXPECT_EQ(total, rays.size());
    for (const std::uint32_t r : previous) EXPECT_TRUE(drawn.count(r)) << "level " << l << " dropped ray " << r;
    previous = drawn;
  }
  EXPECT_EQ(previous.size(), rays.size());  // the last level is every ray
  // Compact tiles: the rays of a first-level stratum lie close together in the image.
  EXPECT_NE(sample.level(0, 42)[0].ray, sample.level(0, 43)[0].ray);  // another seed, other rays
  EXPECT_EQ(sample.level(2, 42)[5].ray, sample.level(2, 42)[5].ray);
  EXPECT_THROW(sample.level(sample.levels(), 1), InvalidArgument);
  EXPECT_THROW(StratifiedSample({}, 16), InvalidArgument);
  // The process keeps the samples it built: one ray set and first level, one sample, equal to
  // one built alone.
  const auto shared = StratifiedSample::shared(rays, 100);
  EXPECT_EQ(shared.get(), StratifiedSample::shared(rays, 128).get());
  EXPECT_NE(shared.get(), StratifiedSample::shared(rays, 64).get());
  for (std::size_t l = 0; l < sample.levels(); ++l) {
    const std::vector<Stratum> a = sample.level(l, 3), b = shared->level(l, 3);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t h = 0; h < a.size(); ++h) EXPECT_TRUE(a[h].size == b[h].size && a[h].ray == b[h].ray) << l << " " << h;
  }
}

/// A decision as a planner makes it: the decider refreshed from `map`, then its decision.
AnytimeDecision decideOn(AnytimeDecider& decider, const grid::OccupancyMap& map, std::span<const Eigen::Isometry3d> views,
                         std::span<const Eigen::Vector3d> rays, const DecisionUtility& utility,
                         const DecideOptions& options = DecideOptions{}) {
  decider.refresh(map, utility);
  return decider.decide(views, rays, utility, ig::WalkOptions{}, options);
}

/// The sums of every ray of one view, walked once (index: the ray).
std::vector<kernels::RayResult> everyRay(ig::IgEvaluator& evaluator, const grid::OccupancyMap& map,
                                       const Eigen::Isometry3d& view, const std::vector<Eigen::Vector3d>& rays) {
  std::vector<std::uint32_t> all(rays.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<std::vector<kernels::RayResult>> out;
  const std::vector<std::vector<std::uint32_t>> chosen = {all};
  evaluator.refresh(map);
  evaluator.walkChosen(std::vector{view}, rays, chosen, {}, ig::WalkOptions{}, out);
  return out[0];
}

std::vector<kernels::RayResult> drawn(const std::vector<Stratum>& strata, const std::vector<kernels::RayResult>& every) {
  std::vector<kernels::RayResult> sums(strata.size());
  for (std::size_t h = 0; h < strata.size(); ++h) {
    if (strata[h].size > 0) sums[h] = every[strata[h].ray];
  }
  return sums;
}

struct Bunny3 {
  Workload workload = makeWorkload("bunny-3");
  std::vector<Eigen::Isometry3d> views() const {
    std::vector<Eigen::Isometry3d> v;
    for (const View& view : workload.candidates) v.push_back(view.T_world_camera);
    return v;
  }
};

// Over many seeds, a level's estimate averages to the exact value, within four standard errors
// of the mean (the released ray set: 950 rays; level 5 holds strata of one and of two rays).
TEST(AnytimeEstimates, TheExpansionEstimatorIsUnbiased) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays =
      sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::released());
  ig::IgEvaluator evaluator;
  const Eigen::Isometry3d view = b.views()[7];
  const std::vector<kernels::RayResult> every = everyRay(evaluator, b.workload.map, view, rays);
  const ig::IgTable exact = ig::evaluate(evaluator, b.workload.map, std::vector{view}, rays);
  const StratifiedSample sample(rays, 16);
  for (const ig::Metric metric : {ig::Metric::ProximityCount, ig::Metric::OcclusionAware, ig::Metric::RearSideVoxel}) {
    for (const std::size_t level : {std::size_t{0}, std::size_t{5}}) {
      const double truth = kernels::metricValue(exact.sums[0], metric);
      double sum = 0.0, sum_sq = 0.0;
      const int seeds = 3000;
      for (int seed = 0; seed < seeds; ++seed) {
        const std::vector<Stratum> strata = sample.level(level, static_cast<std::uint64_t>(seed));
        const double e = estimateMetric(strata, drawn(strata, every), metric, 0.05).estimate;
        sum += e;
        sum_sq += e * e;
      }
      const double mean = sum / seeds;
      const double sd = std::sqrt(std::max(0.0, sum_sq / seeds - mean * mean));
      const double tolerance = 4.0 * sd / std::sqrt(static_cast<double>(seeds)) + 1e-9 * std::abs(truth);
      EXPECT_NEAR(mean, truth, tolerance) << kernels::metricName(metric) << " at level " << level;
    }
  }
}

// The intervals hold: over seeds, views and levels, the share of 90% intervals (no Bonferroni
// correction here) that contain the exact value is at least 0.90 less a tolerance of 0.03. A
// ratio's interval stays unbounded until its denominator is estimated well; those are left
// out of the count (they cannot miss).
TEST(AnytimeEstimates, IntervalsHoldAtTheirLevel) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays = raysOf(4);  // 22,560 rays: 256 strata of 88 at the first level
  ig::IgEvaluator evaluator;
  const ig::IgTable exact = ig::evaluate(evaluator, b.workload.map, b.views(), rays);
  const StratifiedSample sample(rays, 256);
  std::size_t intervals = 0, held = 0, unbounded = 0;
  for (const std::size_t v : {1, 7, 20, 26, 40, 45}) {
    const std::vector<kernels::RayResult> every = everyRay(evaluator, b.workload.map, b.views()[v], rays);
    for (const ig::Metric metric : {ig::Metric::ProximityCount, ig::Metric::OcclusionAware,
                                      ig::Metric::RearSideEntropy, ig::Metric::AverageEntropy,
                                      ig::Metric::AreaFactor}) {
      const double truth = kernels::metricValue(exact.sums[v], metric);
      const double slack = 1e-9 * std::abs(truth);  // the order of additions, not the sample
      for (std::size_t level = 0; level < 4; ++level) {
        for (int seed = 0; seed < 60; ++seed) {
          const std::vector<Stratum> strata = sample.level(level, static_cast<std::uint64_t>(seed));
          const ig::Interval e = estimateMetric(strata, drawn(strata, every), metric, 0.10);
          if (!std::isfinite(e.upper - e.lower)) {
            ++unbounded;
            continue;
          }
          ++intervals;
          held += (e.lower - slack <= truth && truth <= e.upper + slack) ? 1 : 0;
        }
      }
    }
  }
  const double share = static_cast<double>(held) / static_cast<double>(intervals);
  EXPECT_GE(share, 0.90 - 0.03) << held << " of " << intervals << " (" << unbounded << " unbounded)";
  EXPECT_LT(share, 0.995) << "intervals so wide that they never miss say nothing";
  EXPECT_LT(unbounded, intervals / 4);
}

// An estimator must be unbiased whatever the rays' values: here a value of 1 on exactly the
// rays of the strata that hold one ray, 0 elsewhere, at a level mixing strata of one and two
// rays. Weighting each stratum by its own ray count gives the total; weighting all alike by
// N / n (forgetting the unequal strata) would be off by a quarter of it.
TEST(AnytimeEstimates, UnequalStrataKeepTheirWeights) {
  const std::vector<Eigen::Vector3d> rays =
      sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::released());  // 950
  const StratifiedSample sample(rays, 16);
  const std::size_t level = 5;  // 512 strata of 1 or 2 rays
  const std::vector<Stratum> shape = sample.level(level, 0);
  std::vector<kernels::RayResult> every(rays.size());
  double truth = 0.0;
  std::size_t singles = 0;
  for (std::size_t h = 0; h < shape.size(); ++h) {
    if (shape[h].size != 1) continue;
    every[shape[h].ray].sums.pc = 1.0;  // a stratum of one ray holds that ray whatever the seed
    truth += 1.0;
    ++singles;
  }
  ASSERT_GT(singles, 20u);
  ASSERT_LT(singles, shape.size() - 20u);
  double sum = 0.0, unweighted = 0.0;
  const int seeds = 200;
  for (int seed = 0; seed < seeds; ++seed) {
    const std::vector<Stratum> strata = sample.level(level, static_cast<std::uint64_t>(seed));
    sum += estimateMetric(strata, drawn(strata, every), ig::Metric::ProximityCount, 0.05).estimate;
    double plain = 0.0;
    for (std::size_t h = 0; h < strata.size(); ++h) plain += strata[h].size > 0 ? every[strata[h].ray].sums.pc : 0.0;
    unweighted += plain * static_cast<double>(rays.size()) / static_cast<double>(strata.size());
  }
  EXPECT_NEAR(sum / seeds, truth, 1e-9 * truth);  // exact: the singles are certain, the pairs hold 0
  EXPECT_GT(std::abs(unweighted / seeds - truth), 0.25 * truth);
}

/// The exhaustive utility of every candidate, as the planner computes it (Eq. 12, gamma 0).
std::vector<double> exhaustiveGains(ig::IgEvaluator& evaluator, const grid::OccupancyMap& map,
                                    const std::vector<Eigen::Isometry3d>& views, const std::vector<Eigen::Vector3d>& rays,
                                    const DecisionUtility& utility) {
  ig::EvaluateOptions options;
  options.table.metrics = utility.metrics();
  const ig::IgTable table = ig::evaluate(evaluator, map, views, rays, options);
  return combinedGains(table.values, utility.terms, utility.weighting);
}

void expectExhaustiveArgmax(const grid::OccupancyMap& map, const std::vector<Eigen::Isometry3d>& views,
                            const std::vector<Eigen::Vector3d>& rays, const DecisionUtility& utility, const std::string& what) {
  AnytimeDecider decider;
  DecideOptions options;
  options.epsilon = 0.0;
  options.delta = 1e-6;
  const AnytimeDecision d = decideOn(decider, map, views, rays, utility, options);
  const std::vector<double> gains = exhaustiveGains(decider.evaluator(), map, views, rays, utility);
  EXPECT_EQ(d.chosen, *argmaxFirst(gains)) << what;
  EXPECT_EQ(d.end, DecisionEnd::Exact) << what;
  for (std::size_t c = 0; c < views.size(); ++c) {
    if (!d.candidates[c].exact) continue;
    if (utility.terms.size() == 1) {
      EXPECT_EQ(d.candidates[c].estimate, gains[c]) << what << ": finalist " << c << " is not the exhaustive bits";
    }
  }
  EXPECT_TRUE(d.candidates[d.chosen].exact) << what;
}

TEST(AnytimeDecisions, EpsilonZeroIsTheExhaustiveArgmaxOnBunny3) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays = raysOf(8);
  for (const ig::Metric metric : kernels::kAllMetrics) {
    if (metric == ig::Metric::Random) continue;
    DecisionUtility utility;
    utility.terms = {{metric, 1.0}};
    expectExhaustiveArgmax(b.workload.map, b.views(), rays, utility, kernels::metricName(metric));
  }
  DecisionUtility sum;
  sum.terms = parseMetricSum("0.5*pc+0.5*vg");
  expectExhaustiveArgmax(b.workload.map, b.views(), rays, sum, "0.5*pc+0.5*vg");
  sum.weighting = Weighting::Raw;
  expectExhaustiveArgmax(b.workload.map, b.views(), rays, sum, "0.5*pc+0.5*vg raw");
  // And it casts fewer rays than the exhaustive evaluation.
  AnytimeDecider decider;
  DecisionUtility pc;
  const AnytimeDecision d = decideOn(decider, b.workload.map, b.views(), rays, pc);
  EXPECT_LT(d.rays_cast, d.rays_exhaustive / 4);
}

TEST(AnytimeDecisions, EpsilonZeroIsTheExhaustiveArgmaxOnRandomMaps) {
  for (unsigned seed : {11u, 12u, 13u}) {
    const test::RandomScene s = test::randomScene(seed);
    for (const ig::Metric metric : {ig::Metric::OcclusionAware, ig::Metric::ProximityCount,
                                      ig::Metric::RearSideEntropy, ig::Metric::AverageEntropy}) {
      DecisionUtility utility;
      utility.terms = {{metric, 1.0}};
      expectExhaustiveArgmax(s.map, s.views, s.directions, utility,
                             std::string(kernels::metricName(metric)) + " on random map " + std::to_string(seed));
    }
  }
}

// After one scan every hit voxel holds P = 0.7, none P > 0.8: no ray ends on an occupied voxel,
// so kr (Eq. 4) is 0 for every view. The decision knows it from the snapshot and ends after the
// first level, with the exhaustive argmax (the first view), instead of sampling a ratio whose
// denominator never leaves 0 (its interval stayed unbounded to the exact finish on every view).
TEST(AnytimeDecisions, KrIsZeroForEveryViewOfAMapWithoutAnOccupiedVoxel) {
  grid::OccupancyMap map;
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 4000; ++i) {  // a sphere of radius 0.1 m around (0, 0, 0.25), Fibonacci points
    const double z = 1.0 - (2.0 * i + 1.0) / 4000.0, r = std::sqrt(1.0 - z * z), phi = 2.399963229728653 * i;
    points.emplace_back(Eigen::Vector3d(0.1 * r * std::cos(phi), 0.1 * r * std::sin(phi), 0.25 + 0.1 * z).cast<float>());
  }
  const Eigen::Vector3f origin(0.6f, 0.0f, 0.25f);
  map.integrate(points, origin);
  ASSERT_EQ(map.occupiedCount(), 0u);
  ASSERT_GT(map.measuredCount(), 1000u);
  std::vector<Eigen::Isometry3d> views;
  for (const View& v : dome48()) views.push_back(v.T_world_camera);
  const std::vector<Eigen::Vector3d> rays = raysOf(8);
  DecisionUtility kr;
  kr.terms = {{ig::Metric::AverageEntropy, 1.0}};
  AnytimeDecider decider;
  const AnytimeDecision d = decideOn(decider, map, views, rays, kr);
  const std::vector<double> gains = exhaustiveGains(decider.evaluator(), map, views, rays, kr);
  for (const double g : gains) ASSERT_EQ(g, 0.0);
  EXPECT_EQ(d.chosen, *argmaxFirst(gains));
  EXPECT_EQ(d.end, DecisionEnd::Epsilon);
  EXPECT_EQ(d.levels, 1u);
  EXPECT_EQ(d.rays_cast, views.size() * StratifiedSample::roundedStrata(DecideOptions{}.first_strata));
  for (const CandidateEstimate& e : d.candidates) {
    EXPECT_EQ(e.estimate, 0.0);
    EXPECT_EQ(e.lower, 0.0);
    EXPECT_EQ(e.upper, 0.0);
  }
  // In a sum the other term decides, as on any map: pc's ranking, kr adding 0.
  DecisionUtility sum;
  sum.terms = parseMetricSum("0.5*kr+0.5*pc");
  DecisionUtility pc;
  pc.terms = parseMetricSum("pc");
  DecideOptions exact;
  exact.epsilon = 0.0;
  EXPECT_EQ(decideOn(decider, map, views, rays, sum, exact).chosen, *argmaxFirst(exhaustiveGains(decider.evaluator(), map, views, rays, pc)));
  // A second scan from the same place: the hit voxels reach P = 0.84, kr is a ratio again,
  // sampled until its denominator is known well enough (more than one level).
  map.integrate(points, origin);
  ASSERT_GT(map.occupiedCount(), 0u);
  const AnytimeDecision again = decideOn(decider, map, views, rays, kr);
  EXPECT_GT(again.levels, 1u);
  EXPECT_GT(std::count_if(again.candidates.begin(), again.candidates.end(), [](const CandidateEstimate& e) { return e.estimate > 0.0; }), 0);
}

/// Decisions with `epsilon` on bunny-3 for each utility of `texts` and seeds 0..7, each checked
/// within epsilon of the exact best, then handed to `check(d, utility, gains, what)` (gains:
/// the exact utilities).
template <class Check>
void eachDecision(const std::vector<Eigen::Vector3d>& rays, std::initializer_list<const char*> texts, double epsilon,
                  const Check& check) {
  const Bunny3 b;
  for (const char* text : texts) {
    DecisionUtility utility;
    utility.terms = parseMetricSum(text);
    AnytimeDecider decider;
    const std::vector<double> gains = exhaustiveGains(decider.evaluator(), b.workload.map, b.views(), rays, utility);
    const double best = gains[*argmaxFirst(gains)];
    for (std::uint64_t seed = 0; seed < 8; ++seed) {
      DecideOptions options;
      options.epsilon = epsilon;
      options.seed = seed;
      const AnytimeDecision d = decideOn(decider, b.workload.map, b.views(), rays, utility, options);
      const std::string what = std::string(text) + " seed " + std::to_string(seed);
      EXPECT_GE(gains[d.chosen], (1.0 - epsilon) * best) << what;
      check(d, utility, gains, what);
    }
  }
}

// The epsilon end (SEMANTICS.md "Anytime decisions", the end): the leader's lower bound against
// the largest upper bound of the other candidates left, for the best view is either the leader
// or one of them. The leader's own upper bound bounds no rival, so a decision may end while
// the leader's interval is still wider than epsilon of it; and a rival whose upper bound the
// leader's lower bound reaches waits at its level while the others walk on, so candidates left
// at the end may have cast different numbers of rays. The chosen view is within epsilon of
// the exact best all the same.
TEST(AnytimeDecisions, TheEpsilonEndWeighsTheLeaderAgainstItsRivalsUpperBounds) {
  const double epsilon = 0.05;
  int epsilon_ends = 0, wide_leaders = 0, rivals_waited = 0;
  eachDecision(raysOf(4), {"pc", "oa", "vg", "0.5*pc+0.5*vg"}, epsilon,
               [&](const AnytimeDecision& d, const DecisionUtility&, const std::vector<double>&, const std::string& what) {
    if (d.end != DecisionEnd::Epsilon) return;
    ++epsilon_ends;
    const CandidateEstimate& leader = d.candidates[d.chosen];
    double rivals_upper = -std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < d.candidates.size(); ++c) {
      if (c != d.chosen && !d.candidates[c].eliminated) rivals_upper = std::max(rivals_upper, d.candidates[c].upper);
    }
    EXPECT_GE(leader.lower, rivals_upper - epsilon * std::abs(rivals_upper)) << what;
    if (leader.lower < leader.upper - epsilon * std::abs(leader.upper)) ++wide_leaders;
    rivals_waited += std::any_of(d.candidates.begin(), d.candidates.end(), [&](const CandidateEstimate& e) {
      return !e.eliminated && e.rays < leader.rays;
    }) ? 1 : 0;
  });
  EXPECT_GT(epsilon_ends, 8);
  EXPECT_GT(wide_leaders, 0);  // ended on the rivals' bounds before the leader's own was narrow
  EXPECT_GT(rivals_waited, 0);  // a rival left had cast fewer rays than the leader
}

// With few rays (1,410: the first level of 256 tiles already holds an eighth of them) a
// decision that does not end on its samples finishes on every ray: the leader and the rivals
// it does not reach within epsilon, not the rivals that wait (SEMANTICS.md "Anytime
// decisions", the end). The chosen view is exact and within epsilon of the exact best.
TEST(AnytimeDecisions, AnExactFinishWalksTheLeaderAndTheRivalsItDoesNotReach) {
  const std::vector<Eigen::Vector3d> rays = raysOf(16);
  ASSERT_EQ(rays.size(), 1410u);
  const double epsilon = 0.05;
  int exact_ends = 0, left_on_samples = 0;
  eachDecision(rays, {"pc", "oa", "vg", "rse", "0.5*pc+0.5*vg"}, epsilon,
               [&](const AnytimeDecision& d, const DecisionUtility& utility, const std::vector<double>& gains,
                   const std::string& what) {
    if (d.end != DecisionEnd::Exact) return;
    ++exact_ends;
    const CandidateEstimate& leader = d.candidates[d.chosen];
    EXPECT_TRUE(leader.exact) << what;
    if (utility.terms.size() == 1) {
      EXPECT_EQ(leader.estimate, gains[d.chosen]) << what;  // one metric: its bits
    }
    bool sampled = false;
    for (std::size_t c = 0; c < d.candidates.size(); ++c) {
      const CandidateEstimate& e = d.candidates[c];
      if (e.eliminated || e.exact) continue;
      sampled = true;
      EXPECT_GE(leader.lower, e.upper - epsilon * std::abs(e.upper)) << what << " rival " << c;
    }
    left_on_samples += sampled ? 1 : 0;
  });
  EXPECT_GT(exact_ends, 4);
  EXPECT_GT(left_on_samples, 0);  // a rival left that waited was not walked on every ray
}

TEST(AnytimeDecisions, TheSameSeedGivesTheSameDecisionAtAnyThreadCount) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays = raysOf(4);
  DecisionUtility utility;
  utility.terms = parseMetricSum("pc+vg");
  std::vector<AnytimeDecision> decisions;
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    AnytimeDecider decider;
    arena.execute([&] { decisions.push_back(decideOn(decider, b.workload.map, b.views(), rays, utility)); });
  }
  EXPECT_EQ(decisions[0].chosen, decisions[1].chosen);
  EXPECT_EQ(decisions[0].rays_cast, decisions[1].rays_cast);
  for (std::size_t c = 0; c < decisions[0].candidates.size(); ++c) {
    EXPECT_EQ(decisions[0].candidates[c].estimate, decisions[1].candidates[c].estimate);
    EXPECT_EQ(decisions[0].candidates[c].upper, decisions[1].candidates[c].upper);
  }
  // Another seed draws other rays.
  DecideOptions other;
  other.seed = 99;
  AnytimeDecider decider;
  const AnytimeDecision d = decideOn(decider, b.workload.map, b.views(), rays, utility, other);
  EXPECT_NE(d.candidates[0].estimate, decisions[0].candidates[0].estimate);
}

TEST(AnytimeDecisions, BudgetsEndTheDecision) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays = raysOf(2);
  DecisionUtility utility;
  utility.terms = {{ig::Metric::AverageEntropy, 1.0}};
  DecideOptions options;
  options.epsilon = 0.0;
  options.max_rays = 1;  // spent by the first level
  AnytimeDecider decider;
  const AnytimeDecision d = decideOn(decider, b.workload.map, b.views(), rays, utility, options);
  EXPECT_EQ(d.end, DecisionEnd::Budget);
  EXPECT_EQ(d.levels, 1u);
  EXPECT_EQ(d.rays_cast, 48u * 256u);
  EXPECT_FALSE(d.candidates[d.chosen].exact);
  EXPECT_LE(d.candidates[d.chosen].lower, d.candidates[d.chosen].estimate);
  options.max_rays.reset();
  options.epsilon = 1.5;
  EXPECT_THROW(decideOn(decider, b.workload.map, b.views(), rays, utility, options), InvalidArgument);
}

/// The message of the InvalidArgument that `call` throws.
template <class Call>
std::string refusal(Call&& call) {
  try {
    call();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

// A decision's intervals hold together over the levels it may sample (SEMANTICS.md "Anytime
// decisions", the intervals): 5,640 rays in 256 first tiles, whose third level (1,024 tiles)
// holds an eighth of the rays, so z is the quantile for delta / (48 candidates x 3 levels),
// though the sample has 6 levels to every ray.
TEST(AnytimeDecisions, TheIntervalsHoldTogetherOverTheLevelsADecisionMaySample) {
  const Bunny3 b;
  const std::vector<Eigen::Vector3d> rays = raysOf(8);
  const StratifiedSample sample(rays, 256);
  ASSERT_EQ(rays.size(), 5640u);
  ASSERT_EQ(sample.levels(), 6u);
  DecisionUtility pc;
  ASSERT_EQ(pc.metrics(), std::vector<ig::Metric>{ig::Metric::ProximityCount});
  DecideOptions options;
  options.max_rays = 1;  // the first level's intervals
  AnytimeDecider decider;
  const AnytimeDecision d = decideOn(decider, b.workload.map, b.views(), rays, pc, options);
  ASSERT_EQ(d.levels, 1u);
  ASSERT_EQ(b.views().size(), 48u);
  const std::vector<Stratum> strata = sample.level(0, options.seed);
  ig::IgEvaluator evaluator;
  for (const std::size_t v : {0, 13, 31}) {
    const std::vector<kernels::RayResult> every = everyRay(evaluator, b.workload.map, b.views()[v], rays);
    const ig::Interval e = estimateMetric(strata, drawn(strata, every), ig::Metric::ProximityCount, options.delta / (48.0 * 3.0));
    ASSERT_GT(e.upper, e.lower);
    const double slack = 1e-9 * std::abs(e.estimate);
    EXPECT_NEAR(d.candidates[v].estimate, e.estimate, slack) << v;
    EXPECT_NEAR(d.candidates[v].lower, e.lower, slack) << v;
    EXPECT_NEAR(d.candidates[v].upper, e.upper, slack) << v;
  }
}

TEST(AnytimeDecisions, BadOptionsAreRefusedNamingTheValue) {
  DecisionUtility utility;
  utility.terms = {{ig::Metric::ProximityCount, 1.0}};
  utility.gamma = 1.5;
  EXPECT_EQ(refusal([&] { utility.validate(4); }), "gamma 1.5 must lie in [0, 1]");
  utility.gamma = 0.0;
  utility.terms[0].weight = -0.25;
  EXPECT_EQ(refusal([&] { utility.validate(4); }), "metric weight -0.25 must be finite and positive");
  DecideOptions options;
  options.delta = 1e-20;
  EXPECT_NO_THROW(options.validate());
  options.delta = 0.0;
  EXPECT_EQ(refusal([&] { options.validate(); }), "invalid anytime option: delta = 0 (must be in (0, 1))");
  options.delta = 0.01;
  options.max_ms = -1.5;
  EXPECT_EQ(refusal([&] { options.validate(); }), "invalid anytime option: budget_ms = -1.5 (must be finite and > 0)");
  const std::vector<Stratum> strata{{1, 0}};
  const std::vector<kernels::RayResult> sums(1);
  EXPECT_EQ(refusal([&] { estimateMetric(strata, sums, ig::Metric::ProximityCount, 0.0); }),
            "estimateMetric: p 0 must lie in (0, 1)");
  EXPECT_EQ(refusal([&] { estimateMetric(strata, sums, ig::Metric::ProximityCount, 1.0625); }),
            "estimateMetric: p 1.0625 must lie in (0, 1)");
}

}  // namespace
}  // namespace nbv::planner
