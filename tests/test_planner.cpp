// The planner (SEMANTICS.md "The planner", "Simulation and evaluation"): utility and termination on hand-made IG tables, the Fibonacci
// viewspace, the scores of a reconstruction (coverage, entropy, AUC), and a short
// reconstruction of an analytic sphere.
#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/experiment.hpp"
#include "nbv/planner/experiment_folder.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/utility.hpp"

#include "nbv/errors.hpp"

#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <set>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <regex>
#include <thread>

namespace nbv::planner {
namespace {

TEST(Utility, Eq12WithoutCostIsTheShareOfGain) {
  const std::vector<double> gains = {1.0, 2.0, 3.0, 2.0}, costs = {1.0, 1.0, 1.0, 1.0};
  const auto u = utilities(gains, costs, 0.0);
  EXPECT_DOUBLE_EQ(u[0], 1.0 / 8.0);
  EXPECT_DOUBLE_EQ(u[2], 3.0 / 8.0);
  EXPECT_EQ(argmaxFirst(u), 2u);
}

TEST(Utility, Eq12CostCanOutweighGain) {
  // gamma 0.5: U = 0.5 G / 8 - 0.5 C / 40 = {0.0625, 0, -0.1875, 0.125}.
  const std::vector<double> gains = {1.0, 2.0, 3.0, 2.0}, costs = {0.0, 10.0, 30.0, 0.0};
  const auto u = utilities(gains, costs, 0.5);
  EXPECT_DOUBLE_EQ(u[0], 0.0625);
  EXPECT_DOUBLE_EQ(u[1], 0.0);
  EXPECT_DOUBLE_EQ(u[2], -0.1875);
  EXPECT_DOUBLE_EQ(u[3], 0.125);
  EXPECT_EQ(argmaxFirst(u), 3u);
  EXPECT_EQ(argmaxFirst(utilities(gains, costs, 1.0)), 0u);  // cost only: the nearest, first of ties
}

TEST(Utility, TiesZerosAndNaN) {
  EXPECT_EQ(argmaxFirst(std::vector<double>{2.0, 3.0, 3.0}), 1u);  // the first index wins a tie
  const auto zeros = utilities(std::vector<double>{0.0, 0.0}, std::vector<double>{0.0, 0.0}, 0.3);
  EXPECT_EQ(zeros, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(argmaxFirst(zeros), 0u);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(argmaxFirst(std::vector<double>{nan, 1.0, nan}), 1u);
  EXPECT_FALSE(argmaxFirst(std::vector<double>{}).has_value());
  EXPECT_THROW(utilities(std::vector<double>{1.0}, std::vector<double>{1.0}, 1.5), std::invalid_argument);
  EXPECT_THROW(utilities(std::vector<double>{1.0}, std::vector<double>{}, 0.0), std::invalid_argument);
}

TEST(Utility, MetricSumsParseAsWritten) {
  const auto terms = parseMetricSum("0.5*pc + vg*0.25 +kr");
  ASSERT_EQ(terms.size(), 3u);
  EXPECT_EQ(terms[0].metric, ig::Metric::ProximityCount);
  EXPECT_EQ(terms[0].weight, 0.5);
  EXPECT_EQ(terms[1].metric, ig::Metric::AreaFactor);
  EXPECT_EQ(terms[1].weight, 0.25);
  EXPECT_EQ(terms[2].metric, ig::Metric::AverageEntropy);
  EXPECT_EQ(terms[2].weight, 1.0);
  EXPECT_EQ(parseMetricSum("oa").size(), 1u);
  for (const char* bad : {"", "pc+", "+pc", "pc++vg", "pc+pc", "0.5*pc+2*pc", "0*pc", "-1*pc", "nan*pc", "inf*pc",
                          "x*pc", "pc*", "bogus", "0.5*bogus", "1e400*pc"}) {
    EXPECT_THROW(parseMetricSum(bad), InvalidArgument) << bad;
  }
}

TEST(Utility, NormalizedWeightsCompareMetricsOfDifferentScales) {
  // Two candidates, columns pc and vg: pc's values are a thousand times vg's scale. Candidate 0
  // has the slightly larger pc, candidate 1 by far the larger vg.
  const std::vector<double> values = {1000.0, 0.1,   //
                                      990.0, 0.9};
  const std::vector<MetricWeight> pc_only = {{ig::Metric::ProximityCount, 1.0}};
  const std::vector<MetricWeight> both = {{ig::Metric::ProximityCount, 0.5}, {ig::Metric::AreaFactor, 0.5}};
  const std::vector<double> pc_column = {1000.0, 990.0};
  EXPECT_EQ(argmaxFirst(combinedGains(pc_column, pc_only, Weighting::Normalized)), 0u);
  const auto normalized = combinedGains(values, both, Weighting::Normalized);
  EXPECT_DOUBLE_EQ(normalized[0], 0.5 * (1000.0 / 1990.0) + 0.5 * (0.1 / 1.0));
  EXPECT_DOUBLE_EQ(normalized[1], 0.5 * (990.0 / 1990.0) + 0.5 * (0.9 / 1.0));
  EXPECT_EQ(argmaxFirst(normalized), 1u);  // the weights now mean something: vg decides
  const auto raw = combinedGains(values, both, Weighting::Raw);
  EXPECT_DOUBLE_EQ(raw[0], 500.05);
  EXPECT_EQ(argmaxFirst(raw), 0u);  // the released behaviour: pc drowns vg
  // One metric keeps its own units; a column summing to 0 adds nothing.
  EXPECT_EQ(combinedGains(pc_column, pc_only, Weighting::Normalized), pc_column);
  const auto zero_vg = combinedGains(std::vector<double>{1.0, 0.0, 3.0, 0.0}, both, Weighting::Normalized);
  EXPECT_DOUBLE_EQ(zero_vg[1], 0.5 * 0.75);
  EXPECT_THROW(combinedGains(std::vector<double>{1.0, 2.0, 3.0}, both, Weighting::Normalized), InvalidArgument);
  EXPECT_EQ(weightingFromName("raw"), Weighting::Raw);
  EXPECT_THROW(weightingFromName("sum"), InvalidArgument);
}

TEST(Utility, Eq14Threshold) {
  EXPECT_TRUE(allBelow(std::vector<double>{0.1, 0.2}, 0.3));
  EXPECT_FALSE(allBelow(std::vector<double>{0.1, 0.3}, 0.3));
  EXPECT_TRUE(allBelow(std::vector<double>{}, 0.3));
}

TEST(Utility, TravelCostIsTheDistance) {
  EXPECT_DOUBLE_EQ(travelCost(lookAt({3, 0, 1}, {0, 0, 0}), lookAt({0, 4, 1}, {0, 0, 0})), 5.0);
}

TEST(Evaluation, AreaUnderHandMadeCurves) {
  // Coverage 0 at iteration 0, then 0.5 and 1: trapezoids 0.25 + 0.75 over 2 iterations.
  EXPECT_DOUBLE_EQ(areaUnderCurve(std::vector<double>{0.5, 1.0}, 0.0, 1.0), 0.5);
  // Entropy 100 (the maximum) at 0, then 80 and 60: (90 + 70) / 2 / 100.
  EXPECT_DOUBLE_EQ(areaUnderCurve(std::vector<double>{80.0, 60.0}, 100.0, 100.0), 0.8);
  EXPECT_DOUBLE_EQ(areaUnderCurve(std::vector<double>{1.0, 1.0, 1.0, 1.0}, 0.0, 1.0), 0.875);
  EXPECT_EQ(areaUnderCurve(std::vector<double>{}, 0.0, 1.0), 0.0);
  EXPECT_THROW(areaUnderCurve(std::vector<double>{1.0}, 0.0, 0.0), std::invalid_argument);
}

TEST(Evaluation, SurfaceCoverageCountsPointsWithinTheRegistrationDistance) {
  std::vector<Eigen::Vector3f> truth;
  for (int i = 0; i < 10; ++i) truth.emplace_back(0.01f * static_cast<float>(i), 0.0f, 0.0f);  // 1 cm apart
  SurfaceCoverage coverage(truth, 0.005);
  EXPECT_EQ(coverage.coverage(), 0.0);
  coverage.addScan(std::vector<Eigen::Vector3f>{{0.0f, 0.004f, 0.0f}});  // 4 mm from point 0 only
  EXPECT_DOUBLE_EQ(coverage.coverage(), 0.1);
  coverage.addScan(std::vector<Eigen::Vector3f>{{0.0f, 0.004f, 0.0f}, {0.034f, 0.0f, 0.0f}});  // again, and 3
  EXPECT_EQ(coverage.coveredPoints(), 2u);
  coverage.addScan(std::vector<Eigen::Vector3f>{{0.09f, 0.0f, 0.006f}, {std::nanf(""), 0.0f, 0.0f}});  // 6 mm: no
  EXPECT_EQ(coverage.coveredPoints(), 2u);
  EXPECT_THROW(SurfaceCoverage(std::vector<Eigen::Vector3f>{}, 0.005), std::invalid_argument);
  // A moved coverage keeps its KD-tree over the same points (it once read the moved-from vector).
  SurfaceCoverage moved(std::move(coverage));
  SurfaceCoverage assigned(std::vector<Eigen::Vector3f>{{5.0f, 5.0f, 5.0f}}, 0.005);
  assigned = std::move(moved);
  assigned.addScan(std::vector<Eigen::Vector3f>{{0.09f, 0.0f, 0.0f}});
  EXPECT_EQ(assigned.coveredPoints(), 3u);
}

TEST(Evaluation, TheGainOfAScanIsTheShareOfItsPointsNotCoveredYet) {
  std::vector<Eigen::Vector3f> truth;
  for (int i = 0; i < 8; ++i) truth.emplace_back(0.01f * static_cast<float>(i), 0.0f, 0.0f);
  SurfaceCoverage coverage(truth, 0.005);
  const std::vector<std::uint32_t> first{0, 1, 2}, second{2, 3}, again{0, 1};
  EXPECT_EQ(coverage.gainOf(first), 3.0 / 8.0);  // nothing covered yet
  coverage.addCovered(first);
  EXPECT_EQ(coverage.gainOf(second), 1.0 / 8.0);  // point 2 is covered already
  EXPECT_EQ(coverage.gainOf(again), 0.0);
  EXPECT_EQ(coverage.gainOf({}), 0.0);
  EXPECT_THROW(coverage.gainOf(std::vector<std::uint32_t>{8}), InvalidArgument);
  // What it promised is what the scan adds.
  const double before = coverage.coverage();
  const double gain = coverage.gainOf(second);
  coverage.addCovered(second);
  EXPECT_EQ(coverage.coverage() - before, gain);
}

TEST(Evaluation, MapEntropyCountsUnmeasuredVoxelsAsOneBit) {
  grid::OccupancyMap map(grid::MapConfig{});
  const Eigen::Vector3d centre(0.0, 0.0, 0.25);
  EXPECT_DOUBLE_EQ(maxMapEntropyBits(map), 2097152.0);  // 128^3
  EXPECT_DOUBLE_EQ(mapEntropyBits(map, centre), 2097152.0);
  // A voxel at P = 0.97 inside the cube: H2(0.97) = 0.194392 bits instead of 1.
  map.setLogOdds(map.worldToIndex(centre), grid::OccupancyMap::logOddsOf(0.97));
  EXPECT_NEAR(mapEntropyBits(map, centre), 2097152.0 - 1.0 + 0.194392, 1e-5);
  // One outside the cube (more than 0.64 m away) changes nothing.
  map.setLogOdds(map.worldToIndex(Eigen::Vector3d(0.0, 0.0, 1.0)), grid::OccupancyMap::logOddsOf(0.12));
  EXPECT_NEAR(mapEntropyBits(map, centre), 2097152.0 - 1.0 + 0.194392, 1e-5);
}

// The sum adds the measured voxels' entropies in (i, j, k) order, one bit per unmeasured voxel
// after them: bit for bit, for a cube larger than the measured region and one smaller.
TEST(Evaluation, MapEntropyAddsMeasuredVoxelsInIndexOrder) {
  grid::OccupancyMap map(grid::MapConfig{});
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coordinate(-110, 110);
  std::uniform_real_distribution<float> log_odds(-2.0f, 3.5f);
  for (int v = 0; v < 20000; ++v) map.setLogOdds({coordinate(rng), coordinate(rng), coordinate(rng)}, log_odds(rng));
  const Eigen::Vector3d centre(0.0, 0.0, 0.0);
  for (const double edge : {0.64, 1.28, 2.56}) {
    const int n = static_cast<int>(std::round(edge / map.config().resolution));
    const grid::Index3 first = grid::Index3::Constant(-n / 2);
    const Eigen::AlignedBox3i cube(first, first + grid::Index3::Constant(n - 1));
    double bits = 0.0;
    std::size_t measured = 0;
    for (const grid::MeasuredVoxel& v : map.measuredVoxels()) {
      if (!cube.contains(v.ijk)) continue;
      bits += kernels::entropyNats(grid::OccupancyMap::probabilityOf(v.log_odds)) / std::log(2.0);
      ++measured;
    }
    const double expected = bits + (static_cast<double>(n) * n * n - static_cast<double>(measured));
    EXPECT_EQ(mapEntropyBits(map, centre, edge), expected) << "edge " << edge << " m";
  }
}

// The largest cube allowed (4096 voxels per side, 6.9e10 voxels) is read only where the map
// has measured voxels, a slab at a time: its value is exact and needs no cube-sized buffer.
TEST(Evaluation, MapEntropyOfTheLargestCubeReadsOnlyTheMeasuredRegion) {
  grid::OccupancyMap map(grid::MapConfig{});
  EXPECT_EQ(mapEntropyBits(map, Eigen::Vector3d::Zero(), 40.96), 4096.0 * 4096.0 * 4096.0);
  map.setLogOdds({3, -5, 9}, grid::OccupancyMap::logOddsOf(0.97));
  map.setLogOdds({40, 60, -30}, grid::OccupancyMap::logOddsOf(0.5));  // 1 bit: no change
  map.setLogOdds({2100, 0, 0}, grid::OccupancyMap::logOddsOf(0.97));  // outside the cube
  const double h = kernels::entropyNats(0.97) / std::log(2.0);
  EXPECT_NEAR(mapEntropyBits(map, Eigen::Vector3d::Zero(), 40.96), 4096.0 * 4096.0 * 4096.0 - 1.0 + h, 1e-3);
  try {
    mapEntropyBits(map, Eigen::Vector3d::Zero(), 41.0);
    ADD_FAILURE() << "a cube of 4100 voxels per side was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "entropy cube of 41 m holds 4100 voxels per side at 0.01 m; expected 1 to 4096");
  }
}

TEST(Viewspace, FibonacciSphereLooksAtItsCentre) {
  const Eigen::Vector3d target(0.0, 0.0, 0.25);
  const auto views = fibonacciSphere(100, 0.6, target);
  ASSERT_EQ(views.size(), 100u);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const View& v : views) {
    const Eigen::Vector3d p = v.T_world_camera.translation();
    EXPECT_NEAR((p - target).norm(), 0.6, 1e-12);
    const Eigen::Vector3d z = v.T_world_camera.linear().col(2);
    EXPECT_NEAR(z.dot((target - p).normalized()), 1.0, 1e-12);
    mean += p / 100.0;
  }
  EXPECT_LT((mean - target).norm(), 0.01);  // spread evenly: the centroid is the centre
  EXPECT_THROW(fibonacciSphere(0, 0.6, target), std::invalid_argument);
  EXPECT_THROW(fibonacciSphere(10, -1.0, target), std::invalid_argument);
}

// A sphere of radius 0.25 m resting on z = 0, seen from the dome. One view sees at most the
// cap within acos(r / d) of the camera direction: at d = 0.61 m (ring 1) that is 29% of the
// sphere; Proximity Count should add a largely new cap at each of the first views, so after 5
// scans at least 60% (a bit over two full caps' worth) must be covered, and coverage can
// never fall.
TEST(Reconstruction, SphereCoverageRisesMonotonically) {
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 40);
  ReconstructionConfig config;
  config.max_iterations = 5;
  config.ground_truth_points = 20000;
  config.seed = 3;
  const ReconstructionResult result = reconstruct(sphere, dome48(), config);
  ASSERT_EQ(result.iterations.size(), 5u);
  EXPECT_EQ(result.stop, StopReason::MaxIterations);
  double previous = 0.0;
  for (const IterationRecord& r : result.iterations) {
    EXPECT_GT(r.coverage, previous) << "iteration " << r.iteration;
    EXPECT_LE(r.coverage, 0.294 * static_cast<double>(r.iteration) + 1e-9) << "more than the visible caps";
    previous = r.coverage;
  }
  EXPECT_GT(result.iterations.back().coverage, 0.6);
  // Every view is scanned once; the last iteration evaluates nothing.
  for (std::size_t i = 0; i + 1 < result.iterations.size(); ++i) {
    EXPECT_EQ(result.iterations[i].gains.size(), 48u);
    EXPECT_TRUE(std::isnan(result.iterations[i].gains[result.iterations[i].view]));
  }
  EXPECT_TRUE(result.iterations.back().gains.empty());
  // The same seed gives the same run.
  const ReconstructionResult again = reconstruct(sphere, dome48(), config);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(again.iterations[i].view, result.iterations[i].view);
    EXPECT_EQ(again.iterations[i].coverage, result.iterations[i].coverage);
  }
  EXPECT_GT(result.auc_coverage, 0.0);
  EXPECT_LT(result.auc_entropy, 1.0);
}

TEST(Reconstruction, StopsWhenNoViewIsLeftOrEveryGainIsBelowTheThreshold) {
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 20);
  const std::vector<View> dome = dome48();
  const std::vector<View> three(dome.begin(), dome.begin() + 3);
  ReconstructionConfig config;
  config.ground_truth_points = 2000;
  const ReconstructionResult all_seen = reconstruct(sphere, three, config);
  EXPECT_EQ(all_seen.stop, StopReason::NoViewsLeft);
  EXPECT_EQ(all_seen.iterations.size(), 3u);
  config.g_thresh = 1e30;  // no view can gain that much
  const ReconstructionResult below = reconstruct(sphere, dome, config);
  EXPECT_EQ(below.stop, StopReason::BelowThreshold);
  EXPECT_EQ(below.iterations.size(), 1u);
  EXPECT_THROW(reconstruct(sphere, {}, config), std::invalid_argument);
}

TEST(Reconstruction, StopsAfterTheScanThatEndsPastMaxSeconds) {
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 20);
  ReconstructionConfig config;
  config.ground_truth_points = 2000;
  config.max_iterations = 5;
  config.max_seconds = 1e-9;  // over once the first scan is in
  const ReconstructionResult result = reconstruct(sphere, dome48(), config);
  EXPECT_EQ(result.stop, StopReason::TimeLimit);
  EXPECT_STREQ(stopReasonName(result.stop), "max_seconds");
  ASSERT_EQ(result.iterations.size(), 1u);
  EXPECT_TRUE(result.iterations[0].gains.empty());  // no decision followed
  config.max_seconds = 3600.0;  // far off: the scan budget ends the run
  EXPECT_EQ(reconstruct(sphere, dome48(), config).stop, StopReason::MaxIterations);
}

TEST(ReconstructionConfig, EveryOptionIsARowThatValidationNamesWithItsRule) {
  std::string names;
  for (const ReconstructionOption& option : reconstructionOptions()) names += std::string(names.empty() ? "" : ",") + option.name;
  EXPECT_EQ(names, "gamma,g_thresh,max_ray_depth,max_seconds");
  const ReconstructionConfig defaults;
  for (const ReconstructionOption& option : reconstructionOptions()) {
    SCOPED_TRACE(option.name);
    EXPECT_EQ(reconstructionOption(option.name), &option);
    // set() and get() reach the member: a value each check takes, read back.
    ReconstructionConfig config;
    option.set(config, 0.5);
    EXPECT_EQ(option.get(config), std::optional<double>(0.5));
    EXPECT_NO_THROW(config.validate());
    // None: off for an optional option (its default), refused for another.
    if (option.optional) {
      EXPECT_EQ(option.get(defaults), std::nullopt);
      option.set(config, std::nullopt);
      EXPECT_EQ(option.get(config), std::nullopt);
    } else {
      EXPECT_THROW(option.set(config, std::nullopt), InvalidArgument);
    }
    // NaN fails every check, and the error names the option, the value and the rule.
    option.set(config, std::numeric_limits<double>::quiet_NaN());
    try {
      config.validate();
      ADD_FAILURE() << "NaN accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_EQ(std::string(e.what()), "invalid reconstruction option: " + std::string(option.name) + " = nan (" + option.rule + ")");
    }
  }
  EXPECT_EQ(reconstructionOption("gama"), nullptr);
  EXPECT_EQ(reconstructionOption("gamma")->get(defaults), std::optional<double>(0.0));
  EXPECT_EQ(reconstructionOption("max_ray_depth")->get(defaults), std::optional<double>(defaults.walk.max_ray_depth));
}

/// A cheap run: a camera of a quarter of the pixels per side, 2 cm voxels, few ground-truth points.
ReconstructionConfig coarseConfig(std::size_t ground_truth_points, std::size_t scans) {
  ReconstructionConfig config;
  config.camera.camera = {188, 120, 112.0, 112.0, 94.0, 60.0};
  config.map.resolution = 0.02;
  config.ground_truth_points = ground_truth_points;
  config.max_iterations = scans;
  return config;
}

TEST(Reconstruction, TheOracleTakesTheCandidateWhoseScanAddsTheMostCoverage) {
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 20);
  ReconstructionConfig config = coarseConfig(3000, 6);
  setPlanner(config, "oracle");
  EXPECT_EQ(config.planner, Planner::Oracle);
  const SimulatedObject object(sphere, dome48(), config);
  const ReconstructionResult result = reconstruct(object, config);
  ASSERT_EQ(result.iterations.size(), 6u);
  // Replay the run: before each decision, every open candidate's gain is what its scan would
  // add to the points covered so far, and the view taken has the largest (the first on a tie).
  std::vector<bool> covered(config.ground_truth_points, false);
  for (std::size_t k = 0; k + 1 < result.iterations.size(); ++k) {
    const IterationRecord& r = result.iterations[k];
    for (const std::uint32_t i : object.scan(r.view).covered) covered[i] = true;
    double best = -1.0;
    std::size_t best_view = 0;
    for (std::size_t v = 0; v < r.gains.size(); ++v) {
      if (std::isnan(r.gains[v])) continue;  // visited
      std::size_t added = 0;
      for (const std::uint32_t i : object.scan(v).covered) added += covered[i] ? 0 : 1;
      EXPECT_EQ(r.gains[v], static_cast<double>(added) / static_cast<double>(config.ground_truth_points)) << v;
      if (r.gains[v] > best) best = r.gains[v], best_view = v;
    }
    EXPECT_EQ(result.iterations[k + 1].view, best_view);
    EXPECT_NEAR(result.iterations[k + 1].coverage - r.coverage, best, 1e-12);
    EXPECT_EQ(r.rays, 0u);  // the oracle casts no IG ray
  }
  // No anytime decision for it; a misspelt planner is a metric sum that does not parse.
  config.anytime = DecideOptions{};
  EXPECT_THROW(config.validate(), InvalidArgument);
  EXPECT_THROW(setPlanner(config, "oracel"), InvalidArgument);
  setPlanner(config, "0.5*pc+0.5*vg");
  EXPECT_EQ(config.planner, Planner::Utility);
  EXPECT_EQ(config.metrics.size(), 2u);
}

TEST(Reconstruction, APlannerOfOnesOwnThatReturnsPcIsThePcRun) {
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 20);
  ReconstructionConfig config = coarseConfig(2000, 5);
  config.seed = 3;
  const ReconstructionResult pc = reconstruct(sphere, dome48(), config);
  // The same gains through the state: the run chooses alike and casts the same rays.
  std::vector<std::size_t> seen_taken;
  ReconstructionConfig own = config;
  own.planner = Planner::Custom;
  own.scorer = [&](const DecisionState& state) {
    EXPECT_EQ(state.taken.size(), state.iteration);
    EXPECT_EQ(state.taken.size() + state.candidates.size(), state.viewspace.size());
    seen_taken = state.taken;
    const ig::Metric metric = ig::Metric::ProximityCount;
    return state.evaluate(std::span<const ig::Metric>(&metric, 1)).values;
  };
  const ReconstructionResult mine = reconstruct(sphere, dome48(), own);
  ASSERT_EQ(mine.iterations.size(), pc.iterations.size());
  for (std::size_t i = 0; i < pc.iterations.size(); ++i) {
    EXPECT_EQ(mine.iterations[i].view, pc.iterations[i].view);
    EXPECT_EQ(mine.iterations[i].rays, pc.iterations[i].rays);
    ASSERT_EQ(mine.iterations[i].gains.size(), pc.iterations[i].gains.size());
    for (std::size_t v = 0; v < pc.iterations[i].gains.size(); ++v) {
      const double a = mine.iterations[i].gains[v], b = pc.iterations[i].gains[v];
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  EXPECT_EQ(seen_taken.size(), 4u);  // the last decision followed the fourth scan
  EXPECT_EQ(seen_taken.front(), pc.iterations.front().view);
  // Wrong answers are errors naming what is wrong; the scorer's own error reaches the caller.
  own.scorer = [](const DecisionState& state) { return std::vector<double>(state.candidates.size() + 1, 1.0); };
  EXPECT_THROW(reconstruct(sphere, dome48(), own), InvalidArgument);
  own.scorer = [](const DecisionState& state) {
    std::vector<double> gains(state.candidates.size(), 1.0);
    gains[1] = std::numeric_limits<double>::quiet_NaN();
    return gains;
  };
  EXPECT_THROW(reconstruct(sphere, dome48(), own), InvalidArgument);
  own.scorer = [](const DecisionState&) -> std::vector<double> { throw std::runtime_error("mine"); };
  EXPECT_THROW(reconstruct(sphere, dome48(), own), std::runtime_error);
  own.scorer = nullptr;
  EXPECT_THROW(own.validate(), InvalidArgument);
}

TEST(Utility, DecisionMarginCountsTiesAndTheGap) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Margin m = decisionMargin(std::vector<double>{0.2, 0.5, 0.1, 0.45});
  EXPECT_EQ(m.ties, 1u);
  EXPECT_DOUBLE_EQ(m.gap, 0.5 - 0.45);
  m = decisionMargin(std::vector<double>{0.5, 0.1, nan, 0.5, 0.5});
  EXPECT_EQ(m.ties, 3u);
  EXPECT_EQ(m.gap, 0.0);
  m = decisionMargin(std::vector<double>{0.7, nan});
  EXPECT_EQ(m.ties, 1u);
  EXPECT_TRUE(std::isnan(m.gap));  // one candidate: no second value
  EXPECT_EQ(decisionMargin(std::vector<double>{}).ties, 0u);
}

TEST(SceneConditions, PresetsAndNames) {
  EXPECT_EQ(sceneNamed("bare"), SceneConditions{});
  const SceneConditions released = sceneNamed("released");
  EXPECT_TRUE(released.ground_plane);
  ASSERT_TRUE(released.crop.has_value());
  EXPECT_EQ(released.crop->min(), Eigen::Vector3d(-0.6, -0.6, -0.01));
  EXPECT_EQ(released.crop->max(), Eigen::Vector3d(0.6, 0.6, 0.6));
  EXPECT_EQ(released.no_return, NoReturn::Drop);
  EXPECT_THROW(sceneNamed("gazebo"), InvalidArgument);
  // paper: the ground plane alone, the models upright on it; the others place models as stored.
  SceneConditions ground;
  ground.ground_plane = true;
  EXPECT_EQ(sceneNamed("paper"), ground);
  EXPECT_EQ(sceneUp("paper"), "auto");
  EXPECT_EQ(sceneUp("bare"), "z");
  EXPECT_EQ(sceneUp("released"), "z");
  EXPECT_THROW(sceneUp("gazebo"), InvalidArgument);
  EXPECT_EQ(noReturnFromName("clear"), NoReturn::Clear);
  EXPECT_THROW(noReturnFromName("keep"), InvalidArgument);
}

TEST(SceneConditions, ALabelIsThePresetAndWhatDiffersFromIt) {
  EXPECT_EQ(sceneLabel("bare", SceneConditions{}, "z"), "bare");
  EXPECT_EQ(sceneLabel("paper", sceneNamed("paper"), "auto"), "paper");
  SceneConditions scene = sceneNamed("paper");
  scene.ground_plane = false;
  scene.no_return = NoReturn::Clear;
  EXPECT_EQ(sceneLabel("paper", scene, "z"), "paper+noground+clear+up=z");
  scene = sceneNamed("released");
  scene.crop.reset();
  EXPECT_EQ(sceneLabel("released", scene, "z"), "released+nocrop");
  scene.crop = Eigen::AlignedBox3d(Eigen::Vector3d(-0.6, -0.6, 0.0), Eigen::Vector3d(0.6, 0.6, 0.6));
  EXPECT_EQ(sceneLabel("released", scene, "y"), "released+crop+up=y");  // another box
  scene = SceneConditions{};
  scene.ground_plane = true;
  scene.crop = sceneNamed("released").crop;
  EXPECT_EQ(sceneLabel("bare", scene, "z"), "bare+ground+crop");
  EXPECT_THROW(sceneLabel("gazebo", SceneConditions{}, "z"), InvalidArgument);
}

/// The bunny as stored (lying on its side) and the dome's view 0, looking at it horizontally
/// from 0.6 m: the plane behind and below it fills the lower part of the image.
struct BunnyScan {
  static sensor::TriangleMesh placedBunny() {
    sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel("bunny"));
    sensor::normalizeMesh(mesh);
    return mesh;
  }
  sensor::TriangleMesh mesh = placedBunny();
  Eigen::Isometry3d T_world_camera = dome48()[0].T_world_camera;
};

TEST(SceneConditions, GroundHitsAreIntegratedAndNeverCover) {
  const BunnyScan b;
  ReconstructionConfig bare, ground;
  ground.scene.ground_plane = true;
  ground.ground_truth_points = 50000;
  const sensor::DepthCamera camera;
  const sensor::DepthScan without = camera.render(sensor::RayScene(b.mesh), b.T_world_camera);
  const sensor::DepthScan with = camera.render(sensor::RayScene(b.mesh, {true}), b.T_world_camera);
  const ScanPoints p_without = scanPoints(without, b.T_world_camera, bare);
  const ScanPoints p_with = scanPoints(with, b.T_world_camera, ground);
  // Every hit is integrated, the plane's too; only object hits cover.
  EXPECT_EQ(p_with.integrated.size(), with.points_world.size());
  EXPECT_GT(p_with.integrated.size(), p_without.integrated.size());
  std::vector<Eigen::Vector3f> ground_hits, occluded;
  for (std::size_t i = 0; i < with.surfaces.size(); ++i) {
    if (with.surfaces[i] == sensor::Surface::Ground) ground_hits.push_back(with.points_world[i]);
  }
  ASSERT_FALSE(ground_hits.empty());
  EXPECT_EQ(p_with.on_object.size() + ground_hits.size(), p_with.integrated.size());
  // Pixel by pixel: where both see the object they see the same point; object pixels that see
  // the plane instead are the plane's occlusion.
  std::size_t i_without = 0, i_with = 0;
  for (std::size_t pixel = 0; pixel < with.depth_m.size(); ++pixel) {
    const bool hit_without = without.depth_m[pixel] > 0.0f, hit_with = with.depth_m[pixel] > 0.0f;
    if (hit_without) {
      ASSERT_TRUE(hit_with) << "the plane cannot take a hit away";
      if (with.surfaces[i_with] == sensor::Surface::Object) {
        EXPECT_EQ(with.points_world[i_with], without.points_world[i_without]);
      } else {
        occluded.push_back(without.points_world[i_without]);
      }
    }
    i_without += hit_without ? 1 : 0;
    i_with += hit_with ? 1 : 0;
  }
  // Coverage with the plane: what the same scan without it covers, less what the plane occludes.
  const GroundTruth truth(sensor::sampleSurface(b.mesh, 50000, 0));
  const std::vector<std::uint32_t> covered_with = truth.coveredBy(p_with.on_object);
  EXPECT_EQ(truth.coveredBy(p_without.on_object), truth.coveredBy(p_with.on_object.empty() ? occluded : [&] {
              std::vector<Eigen::Vector3f> all = p_with.on_object;
              all.insert(all.end(), occluded.begin(), occluded.end());
              return all;
            }()));
  // Ground hits lie close to the bunny's lowest points: counted, they would cover some.
  std::vector<std::uint32_t> by_ground = truth.coveredBy(ground_hits), only_ground;
  std::set_difference(by_ground.begin(), by_ground.end(), covered_with.begin(), covered_with.end(),
                      std::back_inserter(only_ground));
  EXPECT_FALSE(only_ground.empty()) << "the test needs ground hits near the object";
  // And the run's coverage is that of the object hits alone.
  SimulatedObject object(b.mesh, {View{b.T_world_camera}}, ground);
  EXPECT_EQ(object.scan(0).covered, covered_with);
}

TEST(SceneConditions, NoReturnClearCarvesFreeSpaceWithoutHits) {
  const BunnyScan b;
  ReconstructionConfig drop, clear;
  clear.scene.no_return = NoReturn::Clear;
  const sensor::DepthScan scan = sensor::DepthCamera().render(sensor::RayScene(b.mesh), b.T_world_camera);
  const ScanPoints p_drop = scanPoints(scan, b.T_world_camera, drop), p_clear = scanPoints(scan, b.T_world_camera, clear);
  const std::size_t no_return = scan.depth_m.size() - scan.points_world.size();
  ASSERT_GT(no_return, 0u);
  EXPECT_EQ(p_clear.integrated.size(), p_drop.integrated.size() + no_return);
  EXPECT_EQ(p_clear.on_object, p_drop.on_object);
  grid::OccupancyMap dropped, cleared;
  const Eigen::Vector3f origin = b.T_world_camera.translation().cast<float>();
  dropped.integrate(p_drop.integrated, origin);
  cleared.integrate(p_clear.integrated, origin);
  EXPECT_EQ(cleared.octomapOccupiedCount(), dropped.octomapOccupiedCount());  // no hit added
  EXPECT_GT(cleared.measuredCount(), 3 * dropped.measuredCount());
  // The top-left pixel sees nothing: its ray is free up to the map's range, and unknown beyond.
  const Eigen::Vector3d ray = b.T_world_camera.linear() * sensor::PinholeCamera{}.rayDirectionCamera(0, 0);
  const Eigen::Vector3d at_1m = b.T_world_camera.translation() + 1.0 * ray;
  EXPECT_FALSE(dropped.isMeasured(at_1m));
  EXPECT_LT(cleared.probability(at_1m), 0.5);
  EXPECT_FALSE(cleared.isMeasured(Eigen::Vector3d(b.T_world_camera.translation() + 1.6 * ray)));
  // The clear points lie twice the map's max_range away, whatever that range.
  clear.map.max_range = 1.0;
  const ScanPoints shorter = scanPoints(scan, b.T_world_camera, clear);
  EXPECT_NEAR((shorter.integrated.back().cast<double>() - b.T_world_camera.translation()).norm(), 2.0, 1e-5);
}

TEST(SceneConditions, TheCropBoxDropsPointsBeforeIntegrationAndCoverage) {
  const BunnyScan b;
  ReconstructionConfig crop;
  crop.scene.crop = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0.1), Eigen::Vector3d(1, 1, 1));
  const sensor::DepthScan scan = sensor::DepthCamera().render(sensor::RayScene(b.mesh), b.T_world_camera);
  const ScanPoints kept = scanPoints(scan, b.T_world_camera, crop);
  std::size_t inside = 0;
  for (const Eigen::Vector3f& p : scan.points_world) inside += p.z() >= 0.1f ? 1 : 0;
  ASSERT_GT(inside, 0u);
  ASSERT_LT(inside, scan.points_world.size());
  EXPECT_EQ(kept.integrated.size(), inside);
  EXPECT_EQ(kept.on_object.size(), inside);
  for (const Eigen::Vector3f& p : kept.integrated) EXPECT_GE(p.z(), 0.1f);
}

TEST(Reconstruction, ASharedObjectGivesTheRunsOfOwnObjects) {
  // Runs on one SimulatedObject, two of them at once, and one after the other on one
  // AnytimeDecider (the second reuses the first's snapshot memory), against runs that build
  // their own. A
  // camera of a quarter of the pixels per side and 2 cm voxels keep the runs cheap under the
  // sanitizers (the ground plane's carved space is large).
  const sensor::TriangleMesh sphere = test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 30);
  ReconstructionConfig config;
  config.camera.camera = {188, 120, 112.0, 112.0, 94.0, 60.0};
  config.map.resolution = 0.02;
  config.max_iterations = 6;
  config.ground_truth_points = 20000;
  config.scene.ground_plane = true;
  const SimulatedObject shared(sphere, dome48(), config);
  std::vector<ReconstructionConfig> configs(2, config);
  for (std::uint64_t seed = 0; seed < 2; ++seed) {
    configs[seed].seed = seed;
    configs[seed].metrics = {{seed == 0 ? ig::Metric::ProximityCount : ig::Metric::RearSideEntropy, 1.0}};
  }
  std::vector<ReconstructionResult> own(2), together(2), one_decider(2);
  for (int run = 0; run < 2; ++run) own[run] = reconstruct(sphere, dome48(), configs[run]);
  std::thread second([&] { together[1] = reconstruct(shared, configs[1]); });
  together[0] = reconstruct(shared, configs[0]);
  second.join();
  AnytimeDecider decider;
  one_decider[1] = reconstruct(shared, configs[1], decider);
  one_decider[0] = reconstruct(shared, configs[0], decider);
  for (int run = 0; run < 4; ++run) {
    const ReconstructionResult& tried = run < 2 ? together[run] : one_decider[run - 2];
    const ReconstructionResult& expected = own[run % 2];
    ASSERT_EQ(expected.iterations.size(), tried.iterations.size());
    for (std::size_t i = 0; i < expected.iterations.size(); ++i) {
      const IterationRecord &a = expected.iterations[i], &b = tried.iterations[i];
      EXPECT_EQ(a.view, b.view);
      EXPECT_EQ(a.coverage, b.coverage);
      EXPECT_EQ(a.entropy_bits, b.entropy_bits);
      EXPECT_EQ(a.ties, b.ties);
      ASSERT_EQ(a.gains.size(), b.gains.size());
      for (std::size_t v = 0; v < a.gains.size(); ++v) {
        EXPECT_TRUE(a.gains[v] == b.gains[v] || (std::isnan(a.gains[v]) && std::isnan(b.gains[v])));
      }
    }
  }
  ReconstructionConfig other = config;
  other.scene.ground_plane = false;
  EXPECT_THROW(reconstruct(shared, other), InvalidArgument);  // built for another scene
}

TEST(Experiment, ShardsAreDisjointAndMakeTheWhole) {
  const std::vector<std::string> metrics = {"pc", "0.5*pc+0.5*vg"};
  const std::vector<ExperimentRun> whole = experimentRuns(3, metrics, 5);
  ASSERT_EQ(whole.size(), 3u * 2u * 5u);
  EXPECT_EQ(whole[7].model, 0u);  // model, then metric, then trial
  EXPECT_EQ(whole[7].metric, "0.5*pc+0.5*vg");
  EXPECT_EQ(whole[7].trial, 2u);
  std::multiset<std::tuple<std::size_t, std::string, std::uint64_t>> shards, expected;
  for (const ExperimentRun& r : whole) expected.insert({r.model, r.metric, r.trial});
  for (std::size_t k = 1; k <= 4; ++k) {
    for (const ExperimentRun& r : experimentRuns(3, metrics, 5, k, 4)) shards.insert({r.model, r.metric, r.trial});
  }
  EXPECT_EQ(shards, expected);
  EXPECT_THROW(experimentRuns(3, metrics, 5, 0, 4), InvalidArgument);
  EXPECT_THROW(experimentRuns(3, metrics, 5, 5, 4), InvalidArgument);
}

/// Two small spheres, a camera of a quarter of the pixels per side and 2 cm voxels: runs cheap
/// enough for the sanitizers.
struct SmallExperiment {
  std::vector<sensor::TriangleMesh> meshes = {test::sphereMesh({0.0f, 0.0f, 0.25f}, 0.25f, 20),
                                              test::sphereMesh({0.0f, 0.05f, 0.2f}, 0.15f, 20)};
  ReconstructionConfig config = [] {
    ReconstructionConfig c;
    c.camera.camera = {188, 120, 112.0, 112.0, 94.0, 60.0};
    c.map.resolution = 0.02;
    c.max_iterations = 4;
    c.ground_truth_points = 5000;
    return c;
  }();
  std::vector<ExperimentRun> runs = experimentRuns(2, {"pc", "rse"}, 2);
};

TEST(Experiment, EachRunIsItsReconstructionWhateverTheThreads) {
  const SmallExperiment e;
  for (const int threads : {1, 2}) {
    std::vector<ReconstructionResult> results(e.runs.size());
    std::vector<std::size_t> models_done;
    std::atomic<int> calls{0};
    runExperiment(
        e.meshes, dome48(), e.config, e.runs, threads,
        [&](std::size_t i, ReconstructionResult&& result) {
          results[i] = std::move(result);
          ++calls;
          return true;
        },
        [&](std::size_t model, const SimulatedObject& object) {
          models_done.push_back(model);
          EXPECT_EQ(object.mesh().vertices.size(), e.meshes[model].vertices.size());
        });
    EXPECT_EQ(calls.load(), static_cast<int>(e.runs.size()));
    EXPECT_EQ(models_done, (std::vector<std::size_t>{0, 1}));
    for (std::size_t i = 0; i < e.runs.size(); ++i) {
      ReconstructionConfig config = e.config;
      config.metrics = parseMetricSum(e.runs[i].metric);
      config.seed = e.runs[i].trial;
      const ReconstructionResult own = reconstruct(e.meshes[e.runs[i].model], dome48(), config);
      ASSERT_EQ(own.iterations.size(), results[i].iterations.size()) << i;
      for (std::size_t k = 0; k < own.iterations.size(); ++k) {
        EXPECT_EQ(own.iterations[k].view, results[i].iterations[k].view) << i;
        EXPECT_EQ(own.iterations[k].coverage, results[i].iterations[k].coverage) << i;
        EXPECT_EQ(own.iterations[k].entropy_bits, results[i].iterations[k].entropy_bits) << i;
      }
    }
  }
}

TEST(Experiment, AFalseOrAnErrorStartsNoFurtherRun) {
  const SmallExperiment e;
  int calls = 0, models_done = 0;
  const auto model_done = [&](std::size_t, const SimulatedObject&) { ++models_done; };
  runExperiment(e.meshes, dome48(), e.config, e.runs, 1, [&](std::size_t, ReconstructionResult&&) { return ++calls > 1; },
                model_done);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(models_done, 0);
  calls = 0;
  const auto throwing = [&](std::size_t, ReconstructionResult&&) -> bool {
    ++calls;
    throw std::runtime_error("from done");
  };
  EXPECT_THROW(runExperiment(e.meshes, dome48(), e.config, e.runs, 1, throwing, model_done), std::runtime_error);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(models_done, 0);
  // Bad runs stop it before any run.
  const auto counting = [&](std::size_t, ReconstructionResult&&) { return ++calls > 0; };
  calls = 0;
  const std::vector<ExperimentRun> unknown = {{0, "pc", 0}, {0, "bogus", 0}}, outside = {{2, "pc", 0}};
  EXPECT_THROW(runExperiment(e.meshes, dome48(), e.config, unknown, 1, counting), InvalidArgument);
  EXPECT_THROW(runExperiment(e.meshes, dome48(), e.config, outside, 1, counting), InvalidArgument);
  EXPECT_THROW(runExperiment(e.meshes, dome48(), e.config, e.runs, -1, counting), InvalidArgument);
  EXPECT_EQ(calls, 0);
}

TEST(Experiment, ResultsCsvReadsBackEveryField) {
  std::vector<ExperimentRow> rows = {
      {"sphere", "pc", std::uint64_t{1} << 40, 1, 7, 0.1 + 0.2, 12345.678, 20000.5, 0.25, 1e-9, 0.0, 0, std::nan(""), 0, 0.0},
      {"sphere", "oa", 3, 1, 0, 1.0 / 3.0, 1.0, 20000.5, 0.0, 0.0, 0.0125, 2, 1e-300, 45600, 1.0},
      {"bunny", "0.5*pc+0.5*vg", 0, 1, 47, 0.0, 5e-324, 1.0, 3.0, 4.0, 5.0, 1, 0.5, 1, 1.0 / 45600.0}};
  sortRows(rows);
  EXPECT_EQ(rows[0].model, "bunny");
  EXPECT_EQ(rows[1].metric, "oa");  // the metrics' order, then weighted sums by name
  test::TempDir dir;
  const auto path = dir.path() / "results.csv";
  std::ofstream(path) << resultsCsv(rows);
  const std::vector<ExperimentRow> read = readResultsCsv(path);
  ASSERT_EQ(read.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ExperimentRow &a = rows[i], &b = read[i];
    EXPECT_EQ(std::tie(a.model, a.metric, a.trial), std::tie(b.model, b.metric, b.trial));
    // Every field of the record's table, bit for bit (NaN: none, as none).
#define NBV_EXPECT_SAME(name, type, kind, help) \
  EXPECT_TRUE(a.name == b.name || (std::isnan(static_cast<double>(a.name)) && std::isnan(static_cast<double>(b.name)))) << #name;
    NBV_ITERATION_FIELDS(NBV_EXPECT_SAME)
#undef NBV_EXPECT_SAME
  }
  // A field that is not wholly its number names the line, the column and the text.
  const std::string header = resultsCsv({}), good = "bunny,pc,0,1,0,0.5,10,20,0,0,0,0,,0,1";
  for (const auto& [line, message] : std::vector<std::pair<std::string, std::string>>{
           {"bunny,pc,-1,1,0,0.5,10,20,0,0,0,0,,0,1", ":3: trial '-1' is not a non-negative integer in range"},
           {"bunny,pc,0,1,0,0.5x,10,20,0,0,0,0,,0,1", ":3: coverage '0.5x' is not a number"},
           {"bunny,pc,0,1,0,0.5,10,20,0,0,0,0,,99999999999999999999,1", ":3: rays '99999999999999999999' is not a non-negative"},
           {"bunny,pc,0,1,0,0.5,10,20,0,0,0,0,,0", ":3: expected 15 fields"},
           {"bunny,pc,0,3,0,0.5,10,20,0,0,0,0,,0,1", ":3: bunny pc trial 0: iteration 2 is missing"},
           {"bunny,pc,0,1,0,0.5,10,20,0,0,0,0,,0,1", ":3: bunny pc trial 0: iteration 1 again"},
           {"bunny,oa,0,2,0,0.5,10,20,0,0,0,0,,0,1", ":3: bunny oa trial 0: iteration 1 is missing"}}) {
    std::ofstream(path) << header << good << '\n' << line << '\n';
    try {
      readResultsCsv(path);
      ADD_FAILURE() << line;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(Experiment, AResultsCsvOfAnEarlierVersionReadsItsLaterColumnsAsTheirInitialValues) {
  // results.csv before the rays column (13 columns) and before ray_share (14): the columns it
  // has are read, the later ones keep their initial values; a header that is no prefix of the
  // table's from gap on is refused.
  test::TempDir dir;
  const auto path = dir.path() / "results.csv";
  const std::string header = resultsCsvHeader();
  const std::string without_rays = header.substr(0, header.find(",rays")), without_share = header.substr(0, header.find(",ray_share"));
  std::ofstream(path) << without_rays << "\nbunny,pc,0,1,3,0.5,10,20,0.1,0.2,0.3,1,0.25\n";
  std::vector<ExperimentRow> rows = readResultsCsv(path);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].view, 3u);
  EXPECT_EQ(rows[0].gap, 0.25);
  EXPECT_EQ(rows[0].rays, 0u);
  EXPECT_EQ(rows[0].ray_share, 0.0);
  std::ofstream(path) << without_share << "\nbunny,pc,0,1,3,0.5,10,20,0.1,0.2,0.3,1,,45600\n";
  rows = readResultsCsv(path);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_TRUE(std::isnan(rows[0].gap));
  EXPECT_EQ(rows[0].rays, 45600u);
  EXPECT_EQ(rows[0].ray_share, 0.0);
  std::ofstream(path) << header.substr(0, header.find(",gap")) << "\nbunny,pc,0,1,3,0.5,10,20,0.1,0.2,0.3,1\n";
  EXPECT_THROW(readResultsCsv(path), InvalidArgument);
}

TEST(Experiment, ARunFileOfAnEarlierVersionReadsItsLaterFieldsAsTheirInitialValues) {
  // A run kept in an experiment folder, its file then stripped of the fields the table added
  // after its first version (rays, ray_share): it reads back with those at their initial
  // values; a file without a field of the first version (gap) is refused, naming the file.
  test::TempDir dir;
  Sweep sweep;
  sweep.models = sweep.labels = {"bunny"};
  sweep.metrics = {"pc"};
  sweep.seeds = {0};
  const ExperimentFolder folder(dir.path() / "ex", sweep, false);
  ReconstructionResult result;
  result.max_entropy_bits = 100.0;
  IterationRecord& record = result.iterations.emplace_back();
  record.iteration = 1;
  record.view = 4;
  record.coverage = 0.5;
  record.ties = 1;
  record.gap = 0.25;
  record.rays = 5;
  record.ray_share = 0.5;
  folder.keep(0, result);
  const auto file = dir.path() / "ex" / "runs" / std::filesystem::directory_iterator(dir.path() / "ex" / "runs")->path().filename();
  const auto strip = [&](const std::string& pattern) {
    std::ifstream in(file);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string stripped = std::regex_replace(text, std::regex(pattern), "");
    ASSERT_NE(stripped, text) << pattern;
    std::ofstream(file) << stripped;
  };
  EXPECT_EQ(folder.kept().at(0).result.iterations.at(0).ray_share, 0.5);
  strip(R"("ray_share":[^,}]*,)");
  strip(R"("rays":[^,}]*,)");
  const IterationRecord read = folder.kept().at(0).result.iterations.at(0);
  EXPECT_EQ(read.view, 4u);
  EXPECT_EQ(read.gap, 0.25);
  EXPECT_EQ(read.rays, 0u);
  EXPECT_EQ(read.ray_share, 0.0);
  strip(R"("gap":[^,}]*,)");
  EXPECT_THROW(folder.kept(), FileError);
}

}  // namespace
}  // namespace nbv::planner
