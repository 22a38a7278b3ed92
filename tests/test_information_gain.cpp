// SEMANTICS.md "Volumetric information" worked out on paper on tiny maps, and the evaluators (reference, fast scalar, fast
// AVX2 and AVX-512 where the CPU has them) against each other on random maps and edge rays.
#include "nbv/errors.hpp"
#include "nbv/grid/huge_pages.hpp"
#include "nbv/ig/evaluator.hpp"
#include "nbv/ig/map_snapshot.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include "evaluate_on.hpp"
#include "random_scene.hpp"
#include "ray_oracle.hpp"
#include "reached_voxels.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <tuple>

namespace nbv::ig {
namespace {

using grid::MapConfig;
using grid::allocateLarge;
using grid::freeLarge;
using grid::keptLargeBytes;
using grid::kKeptLargeBytes;
using grid::releaseKeptLarge;
using grid::kHugePageBytes;
using kernels::Isa;
using kernels::ViewSums;
using test::visibleVoxelsOn;

// Values of the paper computation: H(p) in nats.
constexpr double kLn2 = 0.6931471805599453;
constexpr double kH12 = 0.3669249912727096;  // H(0.12)
constexpr double kH97 = 0.13474216817976684; // H(0.97)

/// A map with 0.125 m voxels (exact in binary) and M = 2 * 0.375 / 0.125 = 6.
OccupancyMap tinyMap() {
  MapConfig config;
  config.resolution = 0.125;
  config.proximity_range = 0.375;
  return OccupancyMap(config);
}
float logOdds(double p) { return OccupancyMap::logOddsOf(p); }

/// The camera at the centre of voxel (0, 0, 0), camera axes = world axes.
Eigen::Isometry3d cameraAtOrigin() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d::Constant(0.0625);
  return T;
}

std::vector<Isa> isas() { return kernels::availableIsas(); }

/// Evaluates with the reference and with every instruction set of the fast evaluator; all
/// must agree (counts exactly, sums to 1e-9 relative on these tiny maps).
IgTable evaluateAll(const OccupancyMap& map, const std::vector<Eigen::Isometry3d>& views,
                    const std::vector<Eigen::Vector3d>& directions, EvaluateOptions options) {
  const IgTable reference = ReferenceEvaluator(map).evaluate(views, directions, options);
  for (Isa isa : isas()) {
    options.walk.isa = isa;
    IgEvaluator fast;
    const IgTable table = ig::evaluate(fast, map, views, directions, options);
    for (std::size_t v = 0; v < views.size(); ++v) {
      for (std::size_t m = 0; m < table.metrics.size(); ++m) {
        EXPECT_NEAR(table.value(v, m), reference.value(v, m), 1e-9 * (1.0 + std::abs(reference.value(v, m))))
            << kernels::isaName(isa) << " view " << v << " metric " << kernels::metricName(table.metrics[m]);
      }
      EXPECT_EQ(table.sums[v].voxels, reference.sums[v].voxels) << kernels::isaName(isa);
    }
  }
  return reference;
}

double value(const IgTable& table, Metric metric, std::size_t view = 0) {
  for (std::size_t m = 0; m < table.metrics.size(); ++m) {
    if (table.metrics[m] == metric) return table.value(view, m);
  }
  ADD_FAILURE() << "metric missing";
  return 0.0;
}

// One ray along +x: x0 unmeasured, x1 free (0.12), x2 unmeasured, x3 occupied (0.97).
OccupancyMap fourVoxelRay() {
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(1, 0, 0), logOdds(0.12));
  map.setLogOdds(Index3(3, 0, 0), logOdds(0.97));
  return map;
}

TEST(InformationGain, OneRayThroughUnknownFreeUnknownOccupied) {
  const OccupancyMap map = fourVoxelRay();
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  constexpr double kTol = 1e-6;  // log-odds are floats
  EXPECT_EQ(t.sums[0].voxels, 4u);
  // Eq. 3: ln2 + H(.12) + ln2 + H(.97).
  EXPECT_NEAR(value(t, Metric::Entropy), 1.887961520572367, kTol);
  // Eq. 5-6: P_v = 1, 0.5, 0.5 * 0.88 = 0.44, 0.44 * 0.5 = 0.22.
  EXPECT_NEAR(value(t, Metric::OcclusionAware), 1.0 * kLn2 + 0.5 * kH12 + 0.44 * kLn2 + 0.22 * kH97, kTol);
  EXPECT_NEAR(value(t, Metric::OcclusionAware), 1.2112377126422247, kTol);
  // Eq. 8: the unknown voxels x0 and x2 only.
  EXPECT_NEAR(value(t, Metric::UnobservedVoxel), 1.44 * kLn2, kTol);
  // Eq. 9: occupied end, unknown before it.
  EXPECT_EQ(value(t, Metric::RearSideVoxel), 1.0);
  // Eq. 10: the unknown run is x2 alone (x1 is free), plus the end voxel.
  EXPECT_NEAR(value(t, Metric::RearSideEntropy), 0.44 * kLn2 + 0.22 * kH97, kTol);
  EXPECT_EQ(value(t, Metric::ProximityCount), 0.0);
  // Eq. 4: the ray ends occupied; 4 voxels.
  EXPECT_NEAR(value(t, Metric::AverageEntropy), 1.887961520572367 / 4.0, kTol);
  // Area Factor: x2 (unmeasured after a measured voxel) is not free, so the ray has no class.
  EXPECT_EQ(t.sums[0].area_occupied + t.sums[0].area_occplane + t.sums[0].area_unobserved, 0u);
  EXPECT_EQ(value(t, Metric::AreaFactor), 0.0);
  // uc: the unknown voxels x0 and x2 (x1 is free, x3 occupied), unweighted.
  EXPECT_EQ(value(t, Metric::UnknownCount), 2.0);
  // fv: both are frontier voxels, each a face neighbour of the free x1.
  EXPECT_EQ(value(t, Metric::FrontierVoxels), 2.0);
}

TEST(InformationGain, FrontierVoxelsAreUnknownVoxelsBesideAFreeOne) {
  // One ray along +x through unmeasured x0..x3 and an occupied x4; the free voxel (1, 1, 0)
  // lies beside x1 only, and the free (3, 0, 1) beside x3 only: fv = 2, whoever evaluates.
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(4, 0, 0), logOdds(0.97));
  map.setLogOdds(Index3(1, 1, 0), logOdds(0.12));
  map.setLogOdds(Index3(3, 0, 1), logOdds(0.12));
  map.setLogOdds(Index3(2, 2, 0), logOdds(0.12));  // two voxels away: not a neighbour
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].voxels, 5u);
  EXPECT_EQ(value(t, Metric::UnknownCount), 4.0);
  EXPECT_EQ(value(t, Metric::FrontierVoxels), 2.0);
  // A free voxel makes no frontier of an occupied or a free neighbour: over x4 nothing changes.
  map.setLogOdds(Index3(4, 1, 0), logOdds(0.12));
  EXPECT_EQ(value(evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{}),
                  Metric::FrontierVoxels), 2.0);
}

// Visible voxels of the same ray: x0..x3 with P_v = 1, 0.5, 0.44, 0.22 (Eq. 5), the walk cut at
// the occupied x3; each reached once.
TEST(VisibleVoxels, OneRayThroughUnknownFreeUnknownOccupied) {
  const OccupancyMap map = fourVoxelRay();
  IgEvaluator evaluator;
  const std::vector<VisibleVoxel> voxels = visibleVoxelsOn(evaluator, map, cameraAtOrigin(), std::vector{Eigen::Vector3d::UnitX().eval()});
  ASSERT_EQ(voxels.size(), 4u);
  const double expected[] = {1.0, 0.5, 0.44, 0.22};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(voxels[i].ijk, Index3(i, 0, 0));
    EXPECT_NEAR(voxels[i].visibility, expected[i], 1e-6) << i;  // log-odds are floats
    EXPECT_EQ(voxels[i].rays, 1u);
  }
}

// Every view of the random scenes against the per-ray oracle: each ray walked on its own over
// OctoMap's keys with terms read from the map (not the snapshot), P_v multiplied voxel by voxel,
// then the greatest P_v and the ray count per voxel. Both visibility rules; one and two threads.
TEST(VisibleVoxels, EqualThePerRayOracle) {
  for (unsigned seed : {1u, 2u}) {
    const test::RandomScene s = test::randomScene(seed);
    for (Visibility visibility : {Visibility::Paper, Visibility::Released}) {
      EvaluateOptions options;
      options.snapshot.visibility = visibility;
      options.walk.max_ray_depth = 0.8;
      options.walk.rays_per_task = 64;  // several tasks per view
      const kernels::VoxelModel model = options.snapshotOptions().voxelModel(s.map.config());
      IgEvaluator evaluator;
      for (std::size_t v = 0; v < s.views.size(); ++v) {
        std::map<std::tuple<int, int, int>, std::pair<double, std::uint32_t>> oracle;
        const Eigen::Vector3f origin = s.views[v].translation().cast<float>();
        for (const Eigen::Vector3d& d : s.directions) {
          const Eigen::Vector3f end = igRay(s.views[v], d, options.walk.max_ray_depth).end;
          double visibility_here = 1.0;
          bool stopped = false;
          const auto visit = [&](const Index3& ijk) {
            if (stopped) return;
            auto& [best, rays] = oracle[{ijk.z(), ijk.y(), ijk.x()}];
            best = std::max(best, visibility_here);
            ++rays;
            const std::optional<std::int32_t> mark = s.map.proximity(ijk);
            const kernels::VoxelTerms t = kernels::voxelTerms(model, s.map.isMeasured(ijk), s.map.logOdds(ijk), mark.value_or(0));
            visibility_here *= t.keep;
            stopped = (t.flags & kernels::voxel_flag::kStop) != 0;
          };
          kernels::traverseRayKeys(origin, end, s.map.lattice(), visit);
          visit(s.map.worldToIndex(end.cast<double>()));
        }
        for (bool serial : {true, false}) {
          options.walk.serial = serial;
          const std::vector<VisibleVoxel> voxels = visibleVoxelsOn(evaluator, s.map, s.views[v], s.directions, options);
          ASSERT_EQ(voxels.size(), oracle.size()) << "seed " << seed << " view " << v;
          auto expected = oracle.begin();
          for (const VisibleVoxel& voxel : voxels) {  // ordered by z, y, x as the oracle's map
            const std::string what = "seed " + std::to_string(seed) + " view " + std::to_string(v);
            ASSERT_EQ((std::tuple{voxel.ijk.z(), voxel.ijk.y(), voxel.ijk.x()}), expected->first) << what;
            EXPECT_EQ(voxel.visibility, expected->second.first) << what;
            EXPECT_EQ(voxel.rays, expected->second.second) << what;
            ++expected;
          }
        }
      }
    }
  }
}

// A path of views: its voxels are those of its views merged (the greatest visibility, the rays
// added), at one and two threads; no view gives no voxel.
TEST(VisibleVoxels, APathOfViewsIsItsViewsMerged) {
  const test::RandomScene s = test::randomScene(4);
  EvaluateOptions options;
  options.walk.max_ray_depth = 0.8;
  options.walk.rays_per_task = 64;
  IgEvaluator evaluator;
  std::map<std::tuple<int, int, int>, std::pair<double, std::uint32_t>> merged;
  std::size_t each = 0;  // the views' voxels counted view by view
  for (const Eigen::Isometry3d& view : s.views) {
    for (const VisibleVoxel& voxel : visibleVoxelsOn(evaluator, s.map, view, s.directions, options)) {
      auto& [best, rays] = merged[{voxel.ijk.z(), voxel.ijk.y(), voxel.ijk.x()}];
      best = std::max(best, voxel.visibility);
      rays += voxel.rays;
      ++each;
    }
  }
  ASSERT_LT(merged.size(), each);  // the views share voxels
  for (bool serial : {true, false}) {
    options.walk.serial = serial;
    const std::vector<VisibleVoxel> path = visibleVoxelsOn(evaluator, s.map, std::span(s.views), s.directions, options);
    ASSERT_EQ(path.size(), merged.size());
    auto expected = merged.begin();
    for (const VisibleVoxel& voxel : path) {
      ASSERT_EQ((std::tuple{voxel.ijk.z(), voxel.ijk.y(), voxel.ijk.x()}), expected->first);
      EXPECT_EQ(voxel.visibility, expected->second.first);
      EXPECT_EQ(voxel.rays, expected->second.second);
      ++expected;
    }
  }
  EXPECT_TRUE(visibleVoxelsOn(evaluator, s.map, std::span<const Eigen::Isometry3d>(), s.directions, options).empty());
}

// A single ray's visible voxels give its OA value back: the sum of P_v * H (Eq. 6).
TEST(VisibleVoxels, OneRaysVoxelsSumToItsOcclusionAwareGain) {
  const test::RandomScene s = test::randomScene(3);
  EvaluateOptions options;
  options.table.metrics = {Metric::OcclusionAware};
  options.walk.max_ray_depth = 0.8;
  const kernels::VoxelModel model = options.snapshotOptions().voxelModel(s.map.config());
  IgEvaluator evaluator;
  for (std::size_t i = 0; i < s.directions.size(); i += 37) {
    const std::vector<Eigen::Vector3d> ray{s.directions[i]};
    double oa = 0.0;
    for (const VisibleVoxel& voxel : visibleVoxelsOn(evaluator, s.map, s.views[1], ray, options)) {
      const std::optional<std::int32_t> mark = s.map.proximity(voxel.ijk);
      oa += voxel.visibility * kernels::voxelTerms(model, s.map.isMeasured(voxel.ijk), s.map.logOdds(voxel.ijk), mark.value_or(0)).entropy;
    }
    EXPECT_NEAR(oa, ig::evaluate(evaluator, s.map, std::vector{s.views[1]}, ray, options).value(0, 0), 1e-12 * (1.0 + oa)) << "ray " << i;
  }
}

// The gathering behind visibleVoxels() against a map of voxel -> (greatest visibility, visits):
// random visits to a small block (so the recent-voxel table both merges and lets go), split
// among three gatherers that fold their lists every few entries, one settled half-way and
// gathering on; each settled, then merged into the first.
TEST(VisibleVoxels, GatheringEqualsAMapOfVoxelsWhateverTheFolds) {
  std::mt19937 random(11);
  std::uniform_int_distribution<int> coordinate(-20, 19);
  std::uniform_real_distribution<double> visibility(0.0, 1.0);
  for (const std::size_t fold_at : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, detail::ReachedVoxels::kFoldAt}) {
    std::map<std::tuple<int, int, int>, std::pair<double, std::uint32_t>> oracle;
    detail::ReachedVoxels a(0, fold_at), b(16, fold_at), c(0, fold_at);
    for (int i = 0; i < 200000; ++i) {
      if (i == 100000) b.settle();
      // A block of 44 x 40 x 40 voxels (70,400 for 200,000 visits), around z = -16,384.
      const Index3 ijk(coordinate(random) + i % 5, coordinate(random), coordinate(random) - 32768 / 2);
      const double v = visibility(random);
      auto& [best, visits] = oracle[{ijk.z(), ijk.y(), ijk.x()}];
      best = std::max(best, v);
      ++visits;
      (i % 3 == 0 ? a : i % 3 == 1 ? b : c).add(ijk, v);
    }
    for (detail::ReachedVoxels* part : {&a, &b, &c}) part->settle();
    a.merge(b);
    a.merge(c);
    EXPECT_TRUE(b.take().empty());
    EXPECT_TRUE(c.take().empty());
    const std::vector<VisibleVoxel> voxels = a.take();
    ASSERT_EQ(voxels.size(), oracle.size()) << "fold_at " << fold_at;
    auto expected = oracle.begin();
    for (const VisibleVoxel& voxel : voxels) {
      ASSERT_EQ((std::tuple{voxel.ijk.z(), voxel.ijk.y(), voxel.ijk.x()}), expected->first) << "fold_at " << fold_at;
      EXPECT_EQ(voxel.visibility, expected->second.first);
      EXPECT_EQ(voxel.rays, expected->second.second);
      ++expected;
    }
    EXPECT_TRUE(a.take().empty());
  }
}

TEST(VisibleVoxels, BadInputsAreRefused) {
  const OccupancyMap map = fourVoxelRay();
  IgEvaluator evaluator;
  EXPECT_THROW(visibleVoxelsOn(evaluator, map, cameraAtOrigin(), {}), InvalidArgument);
  Eigen::Isometry3d bad = cameraAtOrigin();
  bad.translation().x() = std::nan("");
  EXPECT_THROW(visibleVoxelsOn(evaluator, map, bad, std::vector{Eigen::Vector3d::UnitX().eval()}), InvalidArgument);
  EXPECT_THROW(visibleVoxelsOn(evaluator, map, cameraAtOrigin(), std::vector{Eigen::Vector3d(2, 0, 0)}), InvalidArgument);
  IgEvaluator fresh;
  EXPECT_THROW(fresh.visibleVoxels(std::vector{cameraAtOrigin()}, std::vector{Eigen::Vector3d::UnitX().eval()}),
               InvalidArgument);  // no refresh before
}

TEST(InformationGain, ReleasedVisibilityMultipliesByOccupancy) {
  const OccupancyMap map = fourVoxelRay();
  EvaluateOptions options;
  options.snapshot.visibility = Visibility::Released;
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, options);
  // P_v = 1, 0.5, 0.5 * 0.12 = 0.06, 0.06 * 0.5 = 0.03.
  EXPECT_NEAR(value(t, Metric::OcclusionAware), kLn2 + 0.5 * kH12 + 0.06 * kLn2 + 0.03 * kH97, 1e-6);
  EXPECT_NEAR(value(t, Metric::OcclusionAware), 0.9222407720752898, 1e-6);
}

TEST(InformationGain, MarkedVoxelsCountProximityAndMakeOccplane) {
  OccupancyMap map = tinyMap();
  map.setProximity(Index3(1, 0, 0), 2);
  map.setProximity(Index3(2, 0, 0), 5);
  EvaluateOptions options;
  options.walk.max_ray_depth = 0.5;  // end point x = 0.5625: voxels 0..4, nothing stops the ray
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, options);
  EXPECT_EQ(t.sums[0].voxels, 5u);
  EXPECT_NEAR(value(t, Metric::ProximityCount), (6 - 2) + (6 - 5), 1e-12);  // Eq. 11, M = 6
  EXPECT_NEAR(value(t, Metric::Entropy), 5 * kLn2, 1e-12);                  // marked: still 0.5
  EXPECT_NEAR(value(t, Metric::OcclusionAware), kLn2 * (1 + 0.5 + 0.25 + 0.125 + 0.0625), 1e-12);
  EXPECT_EQ(t.sums[0].area_occplane, 1u);
  EXPECT_EQ(value(t, Metric::RearSideVoxel), 0.0);
  EXPECT_EQ(value(t, Metric::AverageEntropy), 0.0);  // no ray ends occupied
  // One ray, occplane: a_op = 1, f(1, 0.8) = 0, f(0, 0.2) = 0.
  EXPECT_NEAR(value(t, Metric::AreaFactor), 0.0, 1e-12);
}

TEST(InformationGain, EachAreaFactorClass) {
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(1, 0, 0), logOdds(0.12));  // +x: free, then occupied -> occupied
  map.setLogOdds(Index3(2, 0, 0), logOdds(0.97));
  map.setProximity(Index3(0, 2, 0), 3);            // +y: a marked voxel -> occplane
  map.setLogOdds(Index3(-1, 0, 0), logOdds(0.4));  // -x: measured unknown, then occupied -> none
  map.setLogOdds(Index3(-2, 0, 0), logOdds(0.97));
  // +z: nothing -> unobserved; -y: an unmeasured voxel before any measured one counts as
  // free, then occupied -> occupied; -z: measured 0.6 stops the ray unclassified -> unobserved.
  map.setLogOdds(Index3(0, -1, 0), logOdds(0.97));
  map.setLogOdds(Index3(0, 0, -2), logOdds(0.6));
  const std::vector<Eigen::Vector3d> directions = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                                   -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(),
                                                   -Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ()};
  EvaluateOptions options;
  options.walk.max_ray_depth = 0.5;
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, directions, options);
  EXPECT_EQ(t.sums[0].area_occupied, 2u);
  EXPECT_EQ(t.sums[0].area_occplane, 1u);
  EXPECT_EQ(t.sums[0].area_unobserved, 2u);
  // a_oc = 2/5, a_op = 1/5: f(0.4, 0.2) by Eq. 20, f(0.2, 0.8) by Eq. 19.
  const double c = -0.512;  // (0.2 - 1)^3
  const double f_oc = (-2.0 * 0.064 + 3.0 * 1.2 * 0.16 - 6.0 * 0.2 * 0.4 + (0.6 - 1.0)) / c;
  const double f_op = -2.0 / 0.512 * 0.008 + 3.0 / 0.64 * 0.04;
  EXPECT_NEAR(f_oc, 0.84375, 1e-12);  // -0.432 / -0.512
  EXPECT_NEAR(f_op, 0.15625, 1e-12);
  EXPECT_NEAR(value(t, Metric::AreaFactor), f_oc + f_op, 1e-12);
  // Rear side: +x ends occupied after free (no), -x after measured unknown 0.4 (yes), -y
  // after the unmeasured camera voxel (yes).
  EXPECT_EQ(value(t, Metric::RearSideVoxel), 2.0);
}

TEST(InformationGain, AreaFactorOfThirds) {
  // One ray of each counted class: a_oc = a_op = 1/3.
  EXPECT_NEAR(kernels::areaFactorTerm(1.0 / 3.0, 0.2) + kernels::areaFactorTerm(1.0 / 3.0, 0.8),
              1.3020833333333333, 1e-12);
  EXPECT_NEAR(kernels::areaFactorTerm(0.2, 0.2), 1.0, 1e-12);
  EXPECT_NEAR(kernels::areaFactorTerm(0.8, 0.8), 1.0, 1e-12);
  EXPECT_NEAR(kernels::areaFactorTerm(1.0, 0.2), 0.0, 1e-12);
  EXPECT_NEAR(kernels::areaFactorTerm(0.0, 0.8), 0.0, 1e-12);
}

TEST(InformationGain, RayStartingInAnOccupiedVoxelIsThatVoxel) {
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(0, 0, 0), logOdds(0.97));
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].voxels, 1u);
  EXPECT_NEAR(value(t, Metric::Entropy), kH97, 1e-6);
  EXPECT_NEAR(value(t, Metric::RearSideEntropy), kH97, 1e-6);  // empty run + P_v H of the end
  EXPECT_EQ(value(t, Metric::RearSideVoxel), 0.0);              // nothing before it
  EXPECT_EQ(t.sums[0].area_occupied + t.sums[0].area_occplane + t.sums[0].area_unobserved, 0u);
}

TEST(InformationGain, AllUnknownRayInClosedForm) {
  // An empty map: every voxel is outside the (empty) snapshot. 1.5 m at 0.125 m from the
  // centre of voxel 0: the end point x = 1.5625 is in voxel 12, so 13 voxels.
  const OccupancyMap map = tinyMap();
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].voxels, 13u);
  EXPECT_NEAR(value(t, Metric::Entropy), 13 * kLn2, 1e-12);
  EXPECT_NEAR(value(t, Metric::OcclusionAware), 2.0 * kLn2 * (1.0 - std::ldexp(1.0, -13)), 1e-12);
  EXPECT_EQ(t.sums[0].area_unobserved, 1u);
  // uc counts every voxel of a ray through space never measured: entropy / ln 2, exactly.
  EXPECT_EQ(value(t, Metric::UnknownCount), 13.0);
  EXPECT_EQ(value(t, Metric::UnknownCount), std::round(value(t, Metric::Entropy) / kLn2));
}

TEST(InformationGain, UnknownCountOfAViewThatSeesNothingMeasuredIsItsEntropyOverLn2) {
  // The bunny's map seen from above it, looking up: every ray in space never measured (in
  // closed form); uc = entropy / ln 2 for every instruction set.
  const planner::Workload bunny3 = planner::makeWorkload("bunny-3");
  Eigen::Isometry3d away = Eigen::Isometry3d::Identity();  // z forward: world up
  away.translation() = Eigen::Vector3d(0.0, 0.0, 2.0);
  const auto directions = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling{8, 1.0});
  for (Isa isa : isas()) {
    EvaluateOptions options;
    options.table.metrics = {Metric::Entropy, Metric::UnknownCount};
    options.walk.isa = isa;
    const IgTable t = ig::evaluate(bunny3.map, std::vector<Eigen::Isometry3d>{away}, directions, options);
    EXPECT_EQ(t.sums[0].uc, t.sums[0].voxels) << kernels::isaName(isa);
    EXPECT_NEAR(t.value(0, 1), t.value(0, 0) / kLn2, 1e-9 * t.value(0, 1)) << kernels::isaName(isa);
    EXPECT_GT(t.value(0, 1), 1e6) << kernels::isaName(isa);
  }
}

TEST(InformationGain, RayWhoseWalkStopsOneVoxelShortOfItsEnd) {
  // 5 cm voxels, the camera on the voxel corner (0, 0, 0), one ray along +z over 1.5 m: the
  // end point z = 1.5 lies in voxel 30. OctoMap's walk adds t_delta = 0.05 thirty times,
  // which gives 1.5000000000000002 > 1.5 on the step into voxel 29, so computeRayKeys stops
  // there: voxels 0..28, then the end voxel 30; 30 voxels, voxel 29 never visited. (Found by
  // fuzz_integrate_evaluate: the closed form for the part outside the snapshot counted 31.)
  // Once with an empty map (no snapshot), once leaving a snapshot, once inside one.
  MapConfig config;
  config.resolution = 0.05;
  for (int case_index = 0; case_index < 3; ++case_index) {
    OccupancyMap map(config);
    if (case_index >= 1) map.setLogOdds(Index3(0, 0, 3), logOdds(0.12));
    if (case_index == 2) map.setLogOdds(Index3(0, 0, 33), logOdds(0.12));
    const IgTable t = evaluateAll(map, {Eigen::Isometry3d::Identity()}, {Eigen::Vector3d::UnitZ()},
                                  EvaluateOptions{});
    EXPECT_EQ(t.sums[0].voxels, 30u) << "case " << case_index;
    if (case_index == 0) {
      EXPECT_NEAR(value(t, Metric::Entropy), 30 * kLn2, 1e-12);
    }
  }
}

TEST(InformationGain, KernelEqualsAVoxelByVoxelSumOverOctomapKeys) {
  // Rays from voxel corners to voxel corners (5 cm), where OctoMap's walk may stop short of
  // the end key or step past its slab, against one 8^3 block around the end voxel, which is
  // measured (P = 0.45). The oracle adds the terms of every computeRayKeys voxel and then of
  // the end voxel, one by one; the kernel (every instruction set) must give the same voxel count,
  // the same end voxel terms and the same sums (up to the rounding of its closed forms).
  using kernels::VoxelTerms;
  namespace flag = kernels::voxel_flag;
  const kernels::VoxelLattice lattice(0.05);
  const double h45 = kernels::entropyNats(0.45);
  const std::vector<VoxelTerms> palette = {{kLn2, 0.5, 0.0, flag::kUnknown}, {h45, 0.55, 0.0, flag::kUnknown | flag::kMeasured}};
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> corner(-20, 20);
  int checked = 0;
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3f origin(0.05f * static_cast<float>(corner(rng)), 0.05f * static_cast<float>(corner(rng)),
                                 0.05f * static_cast<float>(corner(rng)));
    const Eigen::Vector3f end(0.05f * static_cast<float>(corner(rng)), 0.05f * static_cast<float>(corner(rng)),
                              0.05f * static_cast<float>(corner(rng)));
    kernels::RaySetup s;
    if (!kernels::setupRay(origin, end, lattice, s)) continue;
    kernels::SnapshotView view;
    for (int a = 0; a < 3; ++a) {
      view.min[a] = s.key_end[a] - (((s.key_end[a] % 8) + 8) % 8);  // the end voxel's 8-block
      view.size[a] = 8;
    }
    std::vector<kernels::SnapshotEntry> voxels(512, kernels::makeEntry(0, 1));
    voxels[view.offset(s.key_end)] = kernels::makeEntry(1, 1);
    view.voxels = voxels.data();
    view.palette = palette;

    const kernels::RaySums expected = nbv::test::sumOverOctomapKeys(origin, end, lattice, view);
    for (Isa isa : isas()) {
      kernels::RaySums got;
      kernels::walkRays(origin, std::span(&end, 1), lattice, view, isa, std::span(&got, 1));
      const std::string what = std::string(kernels::isaName(isa)) + " ray " + std::to_string(i);
      ASSERT_EQ(got.voxels, expected.voxels) << what;
      EXPECT_NEAR(got.entropy, expected.entropy, 1e-12 * expected.entropy) << what;
      EXPECT_NEAR(got.oa, expected.oa, 1e-12 * expected.oa) << what;
      EXPECT_NEAR(got.uv, expected.uv, 1e-12 * expected.uv) << what;
    }
    ++checked;
  }
  EXPECT_GT(checked, 3000);
}

/// The same sums, bit for bit, and the same counts and classes.
void expectSameBits(const kernels::RaySums& got, const kernels::RaySums& expected, const std::string& what) {
  ASSERT_EQ(got.voxels, expected.voxels) << what;
  EXPECT_EQ(got.entropy, expected.entropy) << what;
  EXPECT_EQ(got.oa, expected.oa) << what;
  EXPECT_EQ(got.uv, expected.uv) << what;
  EXPECT_EQ(got.rse, expected.rse) << what;
  EXPECT_EQ(got.pc, expected.pc) << what;
  EXPECT_EQ(got.area, expected.area) << what;
  EXPECT_EQ(got.end_occupied, expected.end_occupied) << what;
  EXPECT_EQ(got.rear_side, expected.rear_side) << what;
}

/// The rays origin -> ends in one call per instruction set: every packet walk gives the
/// scalar walk's bits.
void expectPacketsGiveScalarBits(const Eigen::Vector3f& origin, const std::vector<Eigen::Vector3f>& ends,
                                 const kernels::VoxelLattice& lattice, const kernels::SnapshotView& view,
                                 const std::string& what) {
  std::vector<kernels::RaySums> scalar(ends.size());
  kernels::walkRays(origin, ends, lattice, view, Isa::Scalar, scalar);
  for (Isa isa : isas()) {
    std::vector<kernels::RaySums> packet(ends.size());
    kernels::walkRays(origin, ends, lattice, view, isa, packet);
    for (std::size_t i = 0; i < ends.size(); ++i) {
      expectSameBits(packet[i], scalar[i], std::string(kernels::isaName(isa)) + " " + what + "ray " + std::to_string(i));
    }
  }
}

/// palette[0] unmeasured (H ln 2, keep 0.5), palette[1] measured free: the runs tests' states.
const std::vector<kernels::VoxelTerms>& unknownAndFree() {
  namespace flag = kernels::voxel_flag;
  static const std::vector<kernels::VoxelTerms> palette = {{kLn2, 0.5, 0.0, flag::kUnknown},
                                                           {kH12, 0.88, 0.0, flag::kFree | flag::kMeasured}};
  return palette;
}

/// A snapshot of `size`^3 voxels from voxel (first, first, first), without its voxels yet.
kernels::SnapshotView cube(int first, std::uint32_t size, std::span<const kernels::VoxelTerms> palette) {
  kernels::SnapshotView view;
  for (int a = 0; a < 3; ++a) {
    view.min[a] = first;
    view.size[a] = size;
  }
  view.palette = palette;
  return view;
}

TEST(InformationGain, RunsOfEmptyVoxelsAreCrossedInOneGoUpToTheEndKey) {
  // A 24^3 box of unmeasured voxels with one measured voxel at its centre, so run distances
  // reach 12: rays cross the runs in one go. Their end points lie inside the runs (the walk
  // must stop at the end key, which rounding can make it pass on rays between voxel corners)
  // or beyond the box (it must not leave the box inside a run). Every instruction set must
  // give the scalar walk's bits and the voxel-by-voxel oracle's counts and sums.
  const kernels::VoxelLattice lattice(0.05);
  constexpr int kSize = 24;
  kernels::SnapshotView view = cube(0, kSize, unknownAndFree());
  const Index3 centre(12, 12, 12);
  std::vector<kernels::SnapshotEntry> voxels(kSize * kSize * kSize);
  for (int z = 0; z < kSize; ++z) {
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        const Index3 ijk(x, y, z);
        const auto d = static_cast<unsigned>((ijk - centre).cwiseAbs().maxCoeff());
        voxels[view.offset(ijk)] = d == 0 ? kernels::makeEntry(1, 1) : kernels::makeEntry(0, d);
      }
    }
  }
  view.voxels = voxels.data();

  std::mt19937 rng(11);
  std::uniform_real_distribution<float> around(-0.4f, 1.6f), inside(0.02f, 1.18f);
  std::size_t rays = 0, long_rays = 0;
  for (int i = 0; i < 3000; ++i) {
    Eigen::Vector3f origin(around(rng), around(rng), around(rng));
    Eigen::Vector3f end(inside(rng), inside(rng), inside(rng));
    if (i % 3 == 1) end = origin + 2.0f * (end - origin);  // beyond the box, mostly
    if (i % 3 == 2) {  // voxel corners, where rounding can carry the walk past the end key
      origin = (origin / 0.05f).array().round() * 0.05f;
      end = (end / 0.05f).array().round() * 0.05f;
    }
    const kernels::RaySums expected = nbv::test::sumOverOctomapKeys(origin, end, lattice, view);
    std::vector<kernels::RaySums> got(isas().size());
    std::size_t n = 0;
    for (Isa isa : isas()) {
      kernels::walkRays(origin, std::span(&end, 1), lattice, view, isa, std::span(&got[n], 1));
      const std::string what = std::string(kernels::isaName(isa)) + " ray " + std::to_string(i);
      ASSERT_EQ(got[n].voxels, expected.voxels) << what;
      EXPECT_NEAR(got[n].entropy, expected.entropy, 1e-12 * expected.entropy) << what;
      EXPECT_NEAR(got[n].oa, expected.oa, 1e-12 * expected.oa) << what;
      EXPECT_NEAR(got[n].uv, expected.uv, 1e-12 * expected.uv) << what;
      EXPECT_NEAR(got[n].rse, expected.rse, 1e-12 * expected.rse) << what;
      EXPECT_EQ(got[n].area, expected.area) << what;
      ++n;
    }
    for (std::size_t k = 1; k < n; ++k) {  // the scalar walk's sums, exactly
      EXPECT_EQ(got[0].entropy, got[k].entropy) << "ray " << i;
      EXPECT_EQ(got[0].oa, got[k].oa) << "ray " << i;
      EXPECT_EQ(got[0].uv, got[k].uv) << "ray " << i;
      EXPECT_EQ(got[0].rse, got[k].rse) << "ray " << i;
      EXPECT_EQ(got[0].pc, got[k].pc) << "ray " << i;
    }
    ++rays;
    long_rays += expected.voxels > 30 ? 1 : 0;
  }
  EXPECT_GT(long_rays, rays / 4);  // most cross runs of many voxels

  // Many rays in one call, so that every lane of a packet walks and is refilled as its rays
  // end (1001: not a multiple of any lane width): each packet walk gives the scalar bits.
  for (const Eigen::Vector3f& origin : {Eigen::Vector3f(-0.3f, 0.2f, 0.45f), Eigen::Vector3f(0.6f, 0.6f, 0.6f)}) {
    std::vector<Eigen::Vector3f> ends;
    for (int i = 0; i < 1001; ++i) {
      Eigen::Vector3f end(inside(rng), inside(rng), inside(rng));
      if (i % 3 == 1) end = origin + 2.0f * (end - origin);
      if (i % 3 == 2) end = (end / 0.05f).array().round() * 0.05f;
      ends.push_back(end);
    }
    expectPacketsGiveScalarBits(origin, ends, lattice, view, "");
  }
}

TEST(InformationGain, PacketsEnterEveryKindOfRayAsTheScalarWalkDoes) {
  // The packet walks enter their rays a packet at a time (set-up, slab test and skip to the
  // box lane by lane), leaving to the scalar code the rays of one voxel, the rays that miss
  // the box and those the skip refuses. From origins inside the box, outside it beside each
  // face and corner, and on voxel corners in the planes of its faces, rays of every kind in
  // one call per origin: their sums must be the scalar walk's bits. The voxels are 1/16 m,
  // exact in binary, so that rays along diagonals from voxel corners cross borders of two or
  // three axes at the same time, the ties the skip must leave to the walk.
  using kernels::VoxelTerms;
  namespace flag = kernels::voxel_flag;
  const kernels::VoxelLattice lattice(0.0625);
  const std::vector<VoxelTerms> palette = {{kLn2, 0.5, 0.0, flag::kUnknown},
                                           {kH12, 0.88, 0.0, flag::kFree | flag::kMeasured},
                                           {kH97, 0.03, 0.0, flag::kOccupied | flag::kMeasured | flag::kStop}};
  kernels::SnapshotView view;
  for (int a = 0; a < 3; ++a) {
    view.min[a] = 8;  // [0.5, 1.5) m
    view.size[a] = 16;
  }
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<kernels::SnapshotEntry> voxels(16 * 16 * 16);
  for (kernels::SnapshotEntry& e : voxels) {  // run distance 1: no runs, any states
    const float u = unit(rng);
    e = kernels::makeEntry(u < 0.9f ? 0 : (u < 0.98f ? 1 : 2), 1);
  }
  view.voxels = voxels.data();
  view.palette = palette;

  std::vector<Eigen::Vector3f> origins = {{1.03f, 0.97f, 1.01f}};
  for (int a = 0; a < 3; ++a) {
    for (const bool low : {true, false}) {
      const float side = low ? 0.2f : 1.8f;
      Eigen::Vector3f o(0.97f, 1.03f, 1.01f);
      o[a] = side;
      origins.push_back(o);                                  // beside a face
      origins.push_back(Eigen::Vector3f(side, side, side));  // beside a corner
      Eigen::Vector3f corner = Eigen::Vector3f::Constant(low ? 0.5f : 1.5f);  // in two face planes
      corner[a] = low ? 0.25f : 1.75f;
      origins.push_back(corner);
    }
  }
  for (std::size_t k = 0; k < origins.size(); ++k) {
    const Eigen::Vector3f& origin = origins[k];
    std::vector<Eigen::Vector3f> ends;
    for (int i = 0; i < 601; ++i) {
      const Eigen::Vector3f target(0.4f + unit(rng), 0.4f + unit(rng), 0.4f + unit(rng));
      const Eigen::Vector3f to_corner = ((target / 0.0625f).array().round() * 0.0625f).matrix();
      switch (i % 8) {
        case 0: ends.push_back(target); break;                                         // ends near or in the box
        case 1: ends.push_back(origin + 2.0f * (target - origin)); break;              // crosses it
        case 2: ends.push_back(to_corner); break;                                      // to a voxel corner
        case 3: ends.push_back(origin + 0.004f * (target - origin).normalized()); break;  // one voxel, mostly
        case 4: ends.push_back(origin - (target - origin)); break;                    // away from the box
        case 5: ends.push_back(origin + 0.3f * (target - origin)); break;              // short of the box
        case 6: {  // along an axis or a diagonal
          Eigen::Vector3f d = Eigen::Vector3f::Zero();
          d[i % 3] = (i / 8) % 2 == 0 ? 1.0f : -1.0f;
          if ((i / 8) % 3 == 0) d = Eigen::Vector3f::Constant(d[i % 3]);
          ends.push_back(origin + 1.25f * d);
          break;
        }
        default: {  // to a voxel corner in the plane of a face of the box
          Eigen::Vector3f corner = to_corner;
          corner[i % 3] = (i / 8) % 2 == 0 ? 0.5f : 1.5f;
          ends.push_back(corner);
        }
      }
    }
    expectPacketsGiveScalarBits(origin, ends, lattice, view, "origin " + std::to_string(k) + " ");
  }
}

TEST(InformationGain, ClosedFormsOfMoreThan1022VoxelsKeepTheScalarBits) {
  // Millimetre voxels and a small box: rays cross thousands of unmeasured voxels before or
  // after the box, summed in closed form, where the visibility 2^-n is subnormal (n > 1022) or
  // zero (n > 1074). Every packet walk must give the scalar walk's bits
  // (RayAccumulator::addRepeats() takes 2^-n by std::ldexp() there).
  const kernels::VoxelLattice lattice(0.001);
  kernels::SnapshotView view = cube(2000, 16, unknownAndFree());  // [2.0, 2.016) m, measured free
  std::vector<kernels::SnapshotEntry> voxels(16 * 16 * 16, kernels::makeEntry(1, 1));
  view.voxels = voxels.data();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  // From far away (the long closed form before the box), from 1.02 m before it along x
  // (1,020 to 1,080 voxels before it: just past the normal powers of two), and from beside the
  // box to 3 m past it (the long one after it, the visibility not yet 0); 37 rays each, not a
  // multiple of 8.
  for (const Eigen::Vector3f& origin : {Eigen::Vector3f(0.1f, 0.2f, 0.15f), Eigen::Vector3f(0.9805f, 2.008f, 2.008f),
                                        Eigen::Vector3f(1.99f, 1.995f, 1.992f)}) {
    std::vector<Eigen::Vector3f> ends;
    for (int i = 0; i < 37; ++i) {
      const Eigen::Vector3f target(2.001f + 0.014f * unit(rng), 2.001f + 0.014f * unit(rng), 2.001f + 0.014f * unit(rng));
      ends.push_back(target + 3.0f * (target - origin).normalized());
    }
    std::vector<kernels::RaySums> scalar(ends.size());
    kernels::walkRays(origin, ends, lattice, view, Isa::Scalar, scalar);
    EXPECT_GT(scalar[0].voxels, 3000u);
    expectPacketsGiveScalarBits(origin, ends, lattice, view, "origin x " + std::to_string(origin.x()) + ", ");
  }
}

TEST(InformationGain, RayEndingExactlyAtMaxDepthOnAVoxelFace) {
  // From x = 0.0625 over 0.4375 m: the end point x = 0.5 is the face between voxels 3 and 4;
  // it lies in voxel 4, which closes the ray: voxels 0..4.
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(5, 5, 5), logOdds(0.3));  // a snapshot elsewhere
  EvaluateOptions options;
  options.walk.max_ray_depth = 0.4375;
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, options);
  EXPECT_EQ(t.sums[0].voxels, 5u);
}

TEST(InformationGain, RayLeavingTheSnapshotThroughItsFirstVoxel) {
  // The snapshot box starts at voxel (0, 0, 0); a ray along -x leaves it from there, where the
  // next offset is -1 (once mistaken by the packet walk for "no end voxel in the box").
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(0, 0, 0), logOdds(0.12));
  map.setLogOdds(Index3(7, 7, 7), logOdds(0.12));
  Eigen::Isometry3d T = cameraAtOrigin();
  T.translation().x() += 5 * 0.125;
  const IgTable t = evaluateAll(map, {T}, {-Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].voxels, 13u);  // voxels 5 .. -7
}

TEST(InformationGain, RayStartingOutsideTheSnapshot) {
  // The box is the 8-block of voxel (10, 0, 0); the camera voxel 0 lies outside it. Along +x:
  // voxels 0..7 outside (closed form), 8 and 9 inside and unmeasured, 10 occupied: 11 voxels.
  OccupancyMap map = tinyMap();
  map.setLogOdds(Index3(10, 0, 0), logOdds(0.97));
  const IgTable t = evaluateAll(map, {cameraAtOrigin()}, {Eigen::Vector3d::UnitX()}, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].voxels, 11u);
  EXPECT_NEAR(value(t, Metric::Entropy), 10 * kLn2 + kH97, 1e-6);
  // P_v halves over ten unknown voxels: 2 ln2 (1 - 2^-10), then 2^-10 H(0.97).
  EXPECT_NEAR(value(t, Metric::OcclusionAware), 2 * kLn2 * (1 - std::ldexp(1.0, -10)) + std::ldexp(kH97, -10), 1e-9);
  EXPECT_EQ(value(t, Metric::RearSideVoxel), 1.0);
  EXPECT_EQ(t.sums[0].area_occupied, 1u);  // unmeasured before any measured voxel: "free"
}

TEST(InformationGain, RaysThroughVoxelCorners) {
  // From a voxel corner along the diagonals: every step crosses an edge or a corner, where
  // the walk's tie-breaking decides the voxels. Fast and reference must agree voxel for voxel.
  OccupancyMap map = tinyMap();
  for (int i = 1; i < 6; ++i) {
    map.setLogOdds(Index3(i, i, i), logOdds(i % 2 == 0 ? 0.12 : 0.4));
    map.setLogOdds(Index3(i, i, 0), logOdds(0.3));
    map.setLogOdds(Index3(i, i - 1, 0), logOdds(0.45));
  }
  map.setProximity(Index3(6, 6, 6), 4);
  map.setLogOdds(Index3(7, 7, 7), logOdds(0.97));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  // at the corner (0, 0, 0) of voxels
  const std::vector<Eigen::Vector3d> directions = {
      Eigen::Vector3d(1, 1, 1).normalized(), Eigen::Vector3d(1, 1, 0).normalized(),
      Eigen::Vector3d(1, 0, 1).normalized(), Eigen::Vector3d(2, 1, 0).normalized(),
      Eigen::Vector3d(-1, -1, -1).normalized()};
  const IgTable t = evaluateAll(map, {T}, directions, EvaluateOptions{});
  EXPECT_EQ(t.sums[0].rays, 5u);
  EXPECT_GT(t.sums[0].voxels, 5u);
}

TEST(InformationGain, RandomScoreIsSeededAndUniform) {
  EXPECT_EQ(kernels::randomScore(7, 3), kernels::randomScore(7, 3));
  EXPECT_NE(kernels::randomScore(7, 3), kernels::randomScore(8, 3));
  double sum = 0.0;
  for (int i = 0; i < 10000; ++i) {
    const double r = kernels::randomScore(1, static_cast<std::uint64_t>(i));
    ASSERT_GE(r, 0.0);
    ASSERT_LT(r, 1.0);
    sum += r;
  }
  EXPECT_NEAR(sum / 10000.0, 0.5, 0.01);
}

TEST(InformationGain, MetricNamesRoundTrip) {
  for (Metric m : kernels::kAllMetrics) EXPECT_EQ(kernels::metricFromName(kernels::metricName(m)), m);
  EXPECT_FALSE(kernels::metricFromName("bogus").has_value());
}

// --- random maps: fast (both instruction sets) against the reference ----------------------

void expectSameCounts(const ViewSums& a, const ViewSums& b, const std::string& what) {
  EXPECT_EQ(a.rays, b.rays) << what;
  EXPECT_EQ(a.voxels, b.voxels) << what;
  EXPECT_EQ(a.rsv, b.rsv) << what;
  EXPECT_EQ(a.kr_voxels, b.kr_voxels) << what;
  EXPECT_EQ(a.area_occupied, b.area_occupied) << what;
  EXPECT_EQ(a.area_occplane, b.area_occplane) << what;
  EXPECT_EQ(a.area_unobserved, b.area_unobserved) << what;
  EXPECT_EQ(a.uc, b.uc) << what;
  EXPECT_EQ(a.fv, b.fv) << what;
}

void expectRelative(double a, double b, const std::string& what) {
  EXPECT_LE(std::abs(a - b), 1e-5 * std::max(std::abs(b), 1e-12)) << what << ": " << a << " vs " << b;
}

TEST(InformationGain, FastEqualsReferenceOnRandomMaps) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const test::RandomScene s = test::randomScene(seed);
    for (Visibility visibility : {Visibility::Paper, Visibility::Released}) {
      EvaluateOptions options;
      options.snapshot.visibility = visibility;
      options.walk.max_ray_depth = 0.8;
      const IgTable reference = ReferenceEvaluator(s.map).evaluate(s.views, s.directions, options);
      std::vector<IgTable> fast;
      for (Isa isa : isas()) {
        options.walk.isa = isa;
        fast.push_back(ig::evaluate(s.map, s.views, s.directions, options));
      }
      for (std::size_t v = 0; v < s.views.size(); ++v) {
        const std::string what = "seed " + std::to_string(seed) + " view " + std::to_string(v);
        for (const IgTable& t : fast) {
          expectSameCounts(t.sums[v], reference.sums[v], what);
          for (std::size_t m = 0; m < t.metrics.size(); ++m) {
            expectRelative(t.value(v, m), reference.value(v, m), what + " " + kernels::metricName(t.metrics[m]));
          }
        }
        // Every instruction set gives the same bits.
        for (std::size_t m = 0; m < fast[0].metrics.size(); ++m) EXPECT_EQ(fast.back().value(v, m), fast[0].value(v, m)) << what;
      }
      // The rays did meet every kind of voxel.
      ViewSums total;
      for (const ViewSums& v : reference.sums) total.add(v);
      EXPECT_GT(total.rsv, 0u);
      EXPECT_GT(total.area_occplane, 0u);
      EXPECT_GT(total.area_occupied, 0u);
      EXPECT_GT(total.pc, 0.0);
      EXPECT_GT(total.fv, 0u);
      EXPECT_GT(total.uc, total.fv);
    }
  }
}

// The standard workload (SEMANTICS.md "Standard workloads"): 48 views of the bunny after three scans, the released ray
// set, both visibility models; the scalar and packet walks and the OctoMap reference agree.
TEST(InformationGain, Bunny3FastEqualsReference) {
  const planner::Workload bunny3 = planner::makeWorkload("bunny-3");
  std::vector<Eigen::Isometry3d> views;
  for (const planner::View& view : bunny3.candidates) views.push_back(view.T_world_camera);
  const auto directions = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::released());
  ASSERT_EQ(directions.size(), 950u);
  const ReferenceEvaluator reference_evaluator(bunny3.map);
  for (Visibility visibility : {Visibility::Paper, Visibility::Released}) {
    EvaluateOptions options;
    options.snapshot.visibility = visibility;
    const IgTable reference = reference_evaluator.evaluate(views, directions, options);
    std::vector<IgTable> fast;
    for (Isa isa : isas()) {
      options.walk.isa = isa;
      fast.push_back(ig::evaluate(bunny3.map, views, directions, options));
    }
    ViewSums total;
    for (std::size_t v = 0; v < views.size(); ++v) {
      const std::string what = std::string(visibility == Visibility::Paper ? "paper" : "released") + " view " +
                               std::to_string(v);
      for (const IgTable& t : fast) {
        expectSameCounts(t.sums[v], reference.sums[v], what);
        for (std::size_t m = 0; m < t.metrics.size(); ++m) {
          expectRelative(t.value(v, m), reference.value(v, m), what + " " + kernels::metricName(t.metrics[m]));
        }
      }
      total.add(reference.sums[v]);
    }
    for (const IgTable& t : fast) EXPECT_EQ(t.values, fast[0].values) << "instruction sets differ";
    // The bunny is there: rays end on it, behind marks, and in every Area Factor class.
    EXPECT_GT(total.kr_voxels, 0u);
    EXPECT_GT(total.rsv, 100u);
    EXPECT_GT(total.pc, 0.0);
    EXPECT_GT(total.area_occupied, 0u);
    EXPECT_GT(total.area_occplane, 0u);
    EXPECT_GT(total.area_unobserved, 0u);
  }
}

class RealScaleWorkloads : public testing::TestWithParam<const char*> {};

TEST_P(RealScaleWorkloads, FastEqualsTheReferenceToOnePartInABillion) {
  // Maps where almost every voxel a ray crosses is measured: every walk crosses the runs of
  // identical voxels in closed form (SEMANTICS.md "Run skipping") and must give the OctoMap
  // reference's counts exactly and its values to 1e-9 relative, every instruction set the
  // same bits, on the workload's own ray length.
  const planner::Workload workload = planner::makeWorkload(GetParam());
  std::vector<Eigen::Isometry3d> views;
  const std::size_t every = workload.candidates.size() / 8;
  for (std::size_t i = 0; i < workload.candidates.size(); i += every) views.push_back(workload.candidates[i].T_world_camera);
  const auto directions = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::released());
  EvaluateOptions options;
  options.walk.max_ray_depth = workload.max_ray_depth_m;
  const IgTable reference = ReferenceEvaluator(workload.map).evaluate(views, directions, options);
  std::vector<IgTable> fast;
  for (Isa isa : isas()) {
    options.walk.isa = isa;
    fast.push_back(ig::evaluate(workload.map, views, directions, options));
  }
  for (std::size_t v = 0; v < views.size(); ++v) {
    for (const IgTable& t : fast) {
      expectSameCounts(t.sums[v], reference.sums[v], "view " + std::to_string(v));
      for (std::size_t m = 0; m < t.metrics.size(); ++m) {
        const double a = t.value(v, m), b = reference.value(v, m);
        EXPECT_LE(std::abs(a - b), 1e-9 * std::abs(b)) << "view " << v << " " << kernels::metricName(t.metrics[m]);
      }
    }
  }
  for (const IgTable& t : fast) EXPECT_EQ(t.values, fast[0].values) << "instruction sets differ";
  // Long rays through measured space: tens of voxels each, most of them measured.
  EXPECT_GT(reference.voxels, 40 * reference.rays);
}

INSTANTIATE_TEST_SUITE_P(InformationGain, RealScaleWorkloads, testing::Values("room-2cm", "building-8cm"),
                         [](const testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(InformationGain, OneAndTwoThreadsGiveIdenticalTables) {
  const test::RandomScene s = test::randomScene(4);
  EvaluateOptions options;
  options.walk.rays_per_task = 64;
  options.walk.serial = true;
  const IgTable serial = ig::evaluate(s.map, s.views, s.directions, options);
  options.walk.serial = false;
  const IgTable parallel = ig::evaluate(s.map, s.views, s.directions, options);
  EXPECT_EQ(serial.values, parallel.values);
}

TEST(InformationGain, AnEvaluatorReordersTheRaysWheneverTheirDirectionsChange) {
  // The evaluator keeps its last ray set in walk order: a set changed in place (same buffer,
  // same size, one direction different), a shorter one, and the first one again each give a
  // fresh evaluator's table; a set made invalid in place is refused again.
  const test::RandomScene s = test::randomScene(8);
  IgEvaluator kept;
  std::vector<Eigen::Vector3d> rays = s.directions;
  auto expectFresh = [&](const std::string& what) {
    const IgTable table = ig::evaluate(kept, s.map, s.views, rays);
    EXPECT_EQ(table.values, ig::evaluate(s.map, s.views, rays).values) << what;
    return table;
  };
  const IgTable first = expectFresh("first set");
  rays[17] = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const IgTable changed = expectFresh("one direction changed in place");
  EXPECT_NE(changed.values, first.values);
  rays.resize(100);
  expectFresh("fewer rays");
  rays = s.directions;
  EXPECT_EQ(expectFresh("the first set again").values, first.values);
  rays[5] = Eigen::Vector3d(0.0, 0.0, 2.0);
  EXPECT_THROW(ig::evaluate(kept, s.map, s.views, rays), InvalidArgument);
  // A refused set is kept nowhere (the ordered sets are shared in the process): the set made
  // valid again gives a fresh evaluator's table, and so does the first set.
  rays[5] = s.directions[5];
  EXPECT_EQ(expectFresh("the refused set mended").values, first.values);
  rays[5] = Eigen::Vector3d(0.0, 0.0, 2.0);
  EXPECT_THROW(ig::evaluate(s.map, s.views, rays), InvalidArgument);
  rays = s.directions;
  EXPECT_EQ(expectFresh("the first set after two refusals").values, first.values);
}

TEST(InformationGain, EvaluatorsInThreadsShareTheirOrderedRays) {
  // Evaluators of one process share the ray sets they ordered: evaluators in four threads, each
  // with its own copy of the map, going through five ray sets (more than are kept), give the
  // reference evaluator's values, and the same bits for the same set.
  const test::RandomScene s = test::randomScene(9);
  std::vector<std::vector<Eigen::Vector3d>> sets;
  for (std::size_t k = 0; k < 5; ++k) {
    std::vector<Eigen::Vector3d> rays = s.directions;
    rays.resize(rays.size() - 7 * k);
    sets.push_back(rays);
  }
  constexpr std::size_t kThreads = 4, kRounds = 6;
  std::vector<std::vector<IgTable>> tables(kThreads, std::vector<IgTable>(kRounds));
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t, map = s.map] {
      IgEvaluator evaluator;
      for (std::size_t round = 0; round < kRounds; ++round) {
        tables[t][round] = ig::evaluate(evaluator, map, s.views, sets[(t + round) % sets.size()]);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const IgTable reference = ReferenceEvaluator(s.map).evaluate(s.views, sets[k], EvaluateOptions{});
    const IgTable* first = nullptr;
    for (std::size_t t = 0; t < kThreads; ++t) {
      for (std::size_t round = 0; round < kRounds; ++round) {
        if ((t + round) % sets.size() != k) continue;
        const IgTable& table = tables[t][round];
        ASSERT_EQ(table.values.size(), reference.values.size());
        const std::string what = "set " + std::to_string(k) + ", thread " + std::to_string(t);
        for (std::size_t i = 0; i < table.values.size(); ++i) expectRelative(table.values[i], reference.values[i], what);
        if (first == nullptr) first = &table;
        EXPECT_EQ(table.values, first->values) << what;
      }
    }
  }
}

TEST(InformationGain, CoherentOrderKeepsNeighbouringPixelsTogether) {
  // The full image of the default camera, and three rays that do not look forward: the order is
  // a permutation of the rays, those three last in their given order, and eight rays in a row
  // of it (an AVX-512 packet) lie within a few pixels of each other. (The Morton cells, 1/450
  // of the image plane, are not aligned with the pixels, 1/448.1: a packet is one 4 x 2 block of
  // pixels or parts of two blocks next to each other. Cells made exactly the pixels, so that
  // every packet is one block, measured no faster on bunny-3.)
  const sensor::PinholeCamera camera;
  std::vector<Eigen::Vector3d> rays = sensor::rayDirectionsCamera(camera, sensor::PixelSampling::fromName("full"));
  const std::size_t pixels = rays.size();
  rays.push_back(Eigen::Vector3d(0.0, 0.0, -1.0));
  rays.push_back(Eigen::Vector3d(1.0, 0.0, 0.0));
  rays.push_back(Eigen::Vector3d(0.0, -0.6, -0.8));
  const std::vector<Eigen::Vector3d> ordered = ig::coherentOrder(rays);
  ASSERT_EQ(ordered.size(), rays.size());
  auto less = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::vector<Eigen::Vector3d> sorted_given = rays, sorted_ordered = ordered;
  std::sort(sorted_given.begin(), sorted_given.end(), less);
  std::sort(sorted_ordered.begin(), sorted_ordered.end(), less);
  EXPECT_TRUE(sorted_given == sorted_ordered);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(ordered[pixels + i], rays[pixels + i]);
  // Per packet, its width plus its height in pixels: 3 + 1 for a 4 x 2 block, 7 + 0 for eight
  // pixels of a row (row-major order). Measured: 46% of the packets are one block, the median
  // is 5 (one block, or parts of two next to each other), 90% of them are 9 or less.
  std::vector<double> spreads;
  for (std::size_t first = 0; first + 8 <= pixels; first += 8) {
    double u_min = 1e9, u_max = -1e9, v_min = 1e9, v_max = -1e9;
    for (std::size_t i = first; i < first + 8; ++i) {
      const double u = camera.fx * ordered[i].x() / ordered[i].z(), v = camera.fy * ordered[i].y() / ordered[i].z();
      u_min = std::min(u_min, u), u_max = std::max(u_max, u), v_min = std::min(v_min, v), v_max = std::max(v_max, v);
    }
    spreads.push_back((u_max - u_min) + (v_max - v_min));
  }
  std::sort(spreads.begin(), spreads.end());
  const double blocks = static_cast<double>(std::upper_bound(spreads.begin(), spreads.end(), 4.5) - spreads.begin());
  EXPECT_GT(blocks, 0.4 * static_cast<double>(spreads.size()));
  EXPECT_LT(spreads[spreads.size() / 2], 5.5);
  EXPECT_LT(spreads[spreads.size() * 9 / 10], 9.5);
}

/// Every metric but those that read the neighbours' classes (fv): a snapshot without frontier
/// flags, whose entries change only where voxels change.
EvaluateOptions withoutFrontier() {
  EvaluateOptions options;
  options.table.metrics.clear();
  for (const Metric m : kernels::kAllMetrics) {
    if ((kernels::metricRow(m).reads & kernels::metric_reads::kNeighbours) == 0) options.table.metrics.push_back(m);
  }
  return options;
}

TEST(InformationGain, SnapshotUpdatesOnlyChangedBlocksAndStaysExact) {
  test::RandomScene s = test::randomScene(5);
  IgEvaluator evaluator;
  const EvaluateOptions options = withoutFrontier();
  ig::evaluate(evaluator, s.map, s.views, s.directions, options);
  EXPECT_TRUE(evaluator.lastSnapshotUpdate().rebuilt);
  // Change two voxels inside the box: only their blocks are rewritten.
  s.map.setLogOdds(Index3(0, 0, 0), logOdds(0.97));
  s.map.setLogOdds(Index3(10, -3, 4), logOdds(0.12));
  const IgTable updated = ig::evaluate(evaluator, s.map, s.views, s.directions, options);
  EXPECT_FALSE(evaluator.lastSnapshotUpdate().rebuilt);
  EXPECT_EQ(evaluator.lastSnapshotUpdate().blocks, 2u);
  const IgTable fresh = ig::evaluate(s.map, s.views, s.directions, options);
  EXPECT_EQ(updated.values, fresh.values);
  // A voxel moved from one measured state to another: its block is read and its entry alone is
  // written (no cube turns empty or stops being empty); the same state again writes none.
  s.map.setLogOdds(Index3(0, 0, 0), logOdds(0.12));
  EXPECT_EQ(ig::evaluate(evaluator, s.map, s.views, s.directions, options).values,
            ig::evaluate(s.map, s.views, s.directions, options).values);
  EXPECT_EQ(evaluator.lastSnapshotUpdate().blocks, 1u);
  EXPECT_EQ(evaluator.lastSnapshotUpdate().voxels, 1u);
  s.map.setLogOdds(Index3(0, 0, 0), logOdds(0.12));
  ig::evaluate(evaluator, s.map, s.views, s.directions, options);
  EXPECT_EQ(evaluator.lastSnapshotUpdate().blocks, 1u);
  EXPECT_EQ(evaluator.lastSnapshotUpdate().voxels, 0u);
  // A change outside the box grows it around what it holds.
  s.map.setLogOdds(Index3(100, 0, 0), logOdds(0.3));
  const IgTable grown = ig::evaluate(evaluator, s.map, s.views, s.directions, options);
  EXPECT_FALSE(evaluator.lastSnapshotUpdate().rebuilt);
  EXPECT_TRUE(evaluator.lastSnapshotUpdate().grown);
  EXPECT_EQ(grown.values, ig::evaluate(s.map, s.views, s.directions, options).values);
  // Another map: rebuilt.
  const OccupancyMap copy = s.map;
  const IgTable of_copy = ig::evaluate(evaluator, copy, s.views, s.directions, options);
  EXPECT_TRUE(evaluator.lastSnapshotUpdate().rebuilt);
  EXPECT_EQ(of_copy.values, ig::evaluate(s.map, s.views, s.directions, options).values);
}

/// The run distances of a snapshot in one octant, worked out another way than the snapshot's
/// raster passes: for every voxel, the cube ahead of it grown one shell at a time while every
/// row of it along x holds the voxel's index far enough (from runs along x counted one voxel at
/// a time; outside the box every voxel has index 0).
std::vector<unsigned> bruteForceRunDistances(const kernels::SnapshotView& view, unsigned octant) {
  const int n[3] = {static_cast<int>(view.size[0]), static_cast<int>(view.size[1]), static_cast<int>(view.size[2])};
  const int s[3] = {(octant & 1) != 0 ? -1 : 1, (octant & 2) != 0 ? -1 : 1, (octant & 4) != 0 ? -1 : 1};
  const auto at = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * n[1] + y) * n[0] + x; };
  const auto inside = [&](int x, int y, int z) { return x >= 0 && y >= 0 && z >= 0 && x < n[0] && y < n[1] && z < n[2]; };
  const auto index = [&](int x, int y, int z) {
    return inside(x, y, z) ? kernels::paletteIndex(view.voxels[at(x, y, z)]) : 0u;
  };
  const unsigned cap = kernels::kMaxRunDistance;
  // Voxels of a row's first index from each voxel on along x, up to the cap.
  std::vector<unsigned> row_run(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  for (int z = 0; z < n[2]; ++z) {
    for (int y = 0; y < n[1]; ++y) {
      for (int x = 0; x < n[0]; ++x) {
        unsigned length = 0;
        while (length < cap && index(x + s[0] * static_cast<int>(length), y, z) == index(x, y, z)) ++length;
        row_run[at(x, y, z)] = length;
      }
    }
  }
  // Voxels of index c from (x, y, z) on along x, up to the cap.
  const auto run = [&](int x, int y, int z, std::uint32_t c) {
    if (!inside(x, y, z)) return c == 0 ? cap : 0u;
    return index(x, y, z) == c ? row_run[at(x, y, z)] : 0u;
  };
  std::vector<unsigned> distance(static_cast<std::size_t>(n[0]) * n[1] * n[2], 0);
  for (int z = 0; z < n[2]; ++z) {
    for (int y = 0; y < n[1]; ++y) {
      for (int x = 0; x < n[0]; ++x) {
        const std::uint32_t c = index(x, y, z);
        unsigned shortest = run(x, y, z, c);  // over the rows of the cube so far
        unsigned d = 1;
        while (d < cap) {
          for (int b = 0; b <= static_cast<int>(d); ++b) {  // the shell of rows the next cube adds
            shortest = std::min(shortest, run(x, y + s[1] * b, z + s[2] * static_cast<int>(d), c));
            shortest = std::min(shortest, run(x, y + s[1] * static_cast<int>(d), z + s[2] * b, c));
          }
          if (shortest < d + 1) break;
          ++d;
        }
        distance[at(x, y, z)] = d;
      }
    }
  }
  return distance;
}

void expectRunDistances(const kernels::SnapshotView& view, const std::string& what) {
  for (unsigned o = 0; o < kernels::kOctants; ++o) {
    const std::vector<unsigned> expected = bruteForceRunDistances(view, o);
    std::size_t wrong = 0;
    unsigned largest = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      wrong += kernels::runDistance(view.voxels[i], o) != expected[i] ? 1 : 0;
      largest = std::max(largest, expected[i]);
    }
    EXPECT_EQ(wrong, 0u) << what << ", octant " << o;
    EXPECT_EQ(largest, kernels::kMaxRunDistance) << what << ", octant " << o << ": the cap is reached somewhere";
  }
}

/// A box of `size`^3 voxels made of long runs of every state: axis-aligned boxes of random
/// states (up to half the box along each axis) laid over one another, then every voxel's run
/// distances worked out by bruteForceRunDistances().
std::vector<kernels::SnapshotEntry> runsOfStates(kernels::SnapshotView& view, int size, std::uint32_t states,
                                                 std::mt19937& rng) {
  std::vector<kernels::SnapshotEntry> voxels(static_cast<std::size_t>(size) * size * size, 0);
  std::uniform_int_distribution<int> corner(0, size - 1), extent(2, size / 2);
  std::uniform_int_distribution<std::uint32_t> state(0, states - 1);
  for (int box = 0; box < 40; ++box) {
    const Index3 lo(corner(rng), corner(rng), corner(rng));
    const Index3 hi = (lo + Index3(extent(rng), extent(rng), extent(rng))).cwiseMin(Index3::Constant(size - 1));
    const std::uint32_t k = state(rng);
    for (int z = lo.z(); z <= hi.z(); ++z) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int x = lo.x(); x <= hi.x(); ++x) voxels[view.offset(Index3(view.min[0] + x, view.min[1] + y, view.min[2] + z))] = k;
      }
    }
  }
  view.voxels = voxels.data();
  std::vector<std::vector<unsigned>> distances(kernels::kOctants);
  for (unsigned o = 0; o < kernels::kOctants; ++o) distances[o] = bruteForceRunDistances(view, o);
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    for (unsigned o = 0; o < kernels::kOctants; ++o) voxels[i] = kernels::withRunDistance(voxels[i], o, distances[o][i]);
  }
  return voxels;
}

TEST(InformationGain, RunsOfEveryStateAreCrossedInClosedFormAsTheVoxelByVoxelWalk) {
  // Long runs of measured free voxels, measured unknown ones (below and close to the stop at
  // L = 0), marked ones (two distances, one a frontier voxel), unmeasured ones and occupied
  // stops, at both visibility models' factors: every walk crosses the runs in closed form and
  // must give the voxel-by-voxel oracle's counts, classes and stop, and its sums to 1e-9
  // relative (SEMANTICS.md "Run skipping"); every packet walk the scalar walk's bits, counts
  // included.
  namespace flag = kernels::voxel_flag;
  const kernels::VoxelModel paper, released{0.8, 0.2, 60.0, kernels::Visibility::Released, false};
  for (const kernels::VoxelModel& model : {paper, released}) {
    std::vector<kernels::VoxelTerms> palette = {
        kernels::voxelTerms(model, false, 0.0f, 0),       kernels::voxelTerms(model, true, logOdds(0.12), 0),
        kernels::voxelTerms(model, true, logOdds(0.45), 0), kernels::voxelTerms(model, true, -1e-6f, 0),
        kernels::voxelTerms(model, false, 0.0f, 4),       kernels::voxelTerms(model, false, 0.0f, 9),
        kernels::voxelTerms(model, true, logOdds(0.97), 0)};
    palette[5].flags |= flag::kFrontier;
    const kernels::VoxelLattice lattice(0.05);
    constexpr int kSize = 40;
    for (unsigned seed = 1; seed <= 3; ++seed) {
      std::mt19937 rng(seed);
      kernels::SnapshotView view = cube(-20, kSize, palette);
      // Occupied stops in few boxes (the last state drawn rarely), so that rays run far.
      const std::vector<kernels::SnapshotEntry> voxels =
          runsOfStates(view, kSize, seed == 3 ? 7u : 6u, rng);
      std::uniform_real_distribution<float> around(-1.6f, 1.6f), inside(-0.98f, 0.98f);
      std::vector<Eigen::Vector3f> ends;
      const Eigen::Vector3f origin(around(rng), around(rng), inside(rng));
      for (int i = 0; i < 1500; ++i) {
        Eigen::Vector3f end(inside(rng), inside(rng), inside(rng));
        if (i % 3 == 1) end = origin + 2.0f * (end - origin);                 // beyond the box, mostly
        if (i % 3 == 2) end = (end / 0.05f).array().round() * 0.05f;          // voxel corners
        ends.push_back(end);
      }
      std::vector<kernels::RaySums> scalar(ends.size());
      std::vector<kernels::RayCounts> scalar_counts(ends.size());
      kernels::walkRays(origin, ends, lattice, view, Isa::Scalar, scalar, scalar_counts);
      std::size_t run_voxels = 0, occupied_ends = 0;
      for (std::size_t i = 0; i < ends.size(); ++i) {
        const kernels::RayResult oracle = nbv::test::resultOverOctomapKeys(origin, ends[i], lattice, view);
        const kernels::RaySums& expected = oracle.sums;
        const std::string what = "seed " + std::to_string(seed) + " ray " + std::to_string(i);
        const kernels::RaySums& got = scalar[i];
        EXPECT_EQ(scalar_counts[i].unknown, oracle.counts.unknown) << what;
        EXPECT_EQ(scalar_counts[i].frontier, oracle.counts.frontier) << what;
        ASSERT_EQ(got.voxels, expected.voxels) << what;
        EXPECT_NEAR(got.entropy, expected.entropy, 1e-9 * expected.entropy) << what;
        EXPECT_NEAR(got.oa, expected.oa, 1e-9 * expected.oa) << what;
        EXPECT_NEAR(got.uv, expected.uv, 1e-9 * expected.uv) << what;
        EXPECT_NEAR(got.rse, expected.rse, 1e-9 * expected.rse) << what;
        EXPECT_NEAR(got.pc, expected.pc, 1e-9 * expected.pc) << what;
        EXPECT_EQ(got.area, expected.area) << what;
        EXPECT_EQ(got.end_occupied, expected.end_occupied) << what;
        EXPECT_EQ(got.rear_side, expected.rear_side) << what;
        run_voxels += got.voxels;
        occupied_ends += got.end_occupied ? 1 : 0;
      }
      EXPECT_GT(run_voxels, 30 * ends.size()) << "rays cross long runs";
      if (seed == 3) {
        EXPECT_GT(occupied_ends, ends.size() / 10) << "rays stop on occupied voxels";
      }
      for (Isa isa : isas()) {
        std::vector<kernels::RaySums> packet(ends.size());
        std::vector<kernels::RayCounts> counts(ends.size());
        kernels::walkRays(origin, ends, lattice, view, isa, packet, counts);
        for (std::size_t i = 0; i < ends.size(); ++i) {
          const std::string what = std::string(kernels::isaName(isa)) + " seed " + std::to_string(seed) + " ray " + std::to_string(i);
          expectSameBits(packet[i], scalar[i], what);
          EXPECT_EQ(counts[i].unknown, scalar_counts[i].unknown) << what;
          EXPECT_EQ(counts[i].frontier, scalar_counts[i].frontier) << what;
        }
      }
    }
  }
}

TEST(HugePageAllocator, SmallLargeAndEmptyBlocksAreUsableAndLargeOnesAligned) {
  // Below kHugePageBytes: malloc's memory; from it on: 2 MiB aligned, the size rounded up.
  for (const std::size_t bytes : {std::size_t{0}, std::size_t{1}, std::size_t{4096}, kHugePageBytes - 1,
                                  kHugePageBytes, kHugePageBytes + 1, 3 * kHugePageBytes + 5}) {
    auto* block = static_cast<unsigned char*>(allocateLarge(bytes));
    ASSERT_NE(block, nullptr) << bytes;
    if (bytes >= kHugePageBytes) {
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(block) % kHugePageBytes, 0u) << bytes;
    }
    std::fill(block, block + bytes, static_cast<unsigned char>(bytes));  // every byte writable
    EXPECT_EQ(std::count(block, block + bytes, static_cast<unsigned char>(bytes)), static_cast<std::ptrdiff_t>(bytes));
    freeLarge(block, bytes);
  }
  // As a vector's allocator, growing across the threshold keeps the contents.
  std::vector<std::uint64_t, HugePageAllocator<std::uint64_t>> v;
  for (std::uint64_t i = 0; i < kHugePageBytes / 4; ++i) v.push_back(i);
  EXPECT_EQ(v.front(), 0u);
  EXPECT_EQ(v.back(), kHugePageBytes / 4 - 1);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % kHugePageBytes, 0u);
  EXPECT_THROW(HugePageAllocator<std::uint64_t>().allocate(~std::size_t{0} / 4), std::bad_alloc);
}

TEST(HugePageAllocator, FreedLargeBlocksAreKeptForTheNextOfAboutTheirSize) {
  releaseKeptLarge();  // what earlier tests of this process freed
  EXPECT_EQ(keptLargeBytes(), 0u);
  const std::size_t page = kHugePageBytes;
  void* const first = allocateLarge(3 * page + 5);
  freeLarge(first, 3 * page + 5);
  EXPECT_EQ(keptLargeBytes(), 4 * page) << "kept, its size rounded up to whole huge pages";
  // A request for more than the kept block holds, or for less than two thirds of it, gets a
  // new block; one in between gets the kept block.
  void* const larger = allocateLarge(5 * page);
  void* const smaller = allocateLarge(2 * page);
  EXPECT_NE(larger, first);
  EXPECT_NE(smaller, first);
  EXPECT_EQ(keptLargeBytes(), 4 * page);
  auto* const again = static_cast<unsigned char*>(allocateLarge(3 * page));
  EXPECT_EQ(again, first);
  EXPECT_EQ(keptLargeBytes(), 0u);
  std::fill(again, again + 3 * page, static_cast<unsigned char>(7));  // every byte asked for writable
  EXPECT_EQ(std::count(again, again + 3 * page, static_cast<unsigned char>(7)), static_cast<std::ptrdiff_t>(3 * page));
  freeLarge(again, 3 * page);
  freeLarge(larger, 5 * page);
  freeLarge(smaller, 2 * page);
  EXPECT_EQ(keptLargeBytes(), 10 * page);
  // Past kKeptLargeBytes the oldest go back first (3 pages, then 5) until the new one fits.
  const std::size_t big = kKeptLargeBytes - 4 * page;
  freeLarge(allocateLarge(big), big);
  EXPECT_EQ(keptLargeBytes(), big + 2 * page);
  // A block larger than all that may be kept is never kept.
  freeLarge(allocateLarge(kKeptLargeBytes + 1), kKeptLargeBytes + 1);
  EXPECT_EQ(keptLargeBytes(), big + 2 * page);
  releaseKeptLarge();
  EXPECT_EQ(keptLargeBytes(), 0u);
}

TEST(HugePageAllocator, ArraysABoxOutgrewAreGivenBackAndAFieldsArraysKeptWhenItGoes) {
  releaseKeptLarge();
  const std::size_t page = kHugePageBytes;
  {
    grid::LargeArray<std::uint8_t> array(3 * page);
    array.giveBack();
    EXPECT_EQ(array.size(), 0u);
    EXPECT_EQ(array.data(), nullptr);
    EXPECT_EQ(keptLargeBytes(), 0u) << "given back, not kept";
  }
  // A field of ~1 M voxels (arrays of 2 MiB and more) grows past its arrays' room: the arrays
  // it outgrew are not kept; its own are, once it goes.
  std::size_t held = 0;
  {
    ig::RunDistanceField field;
    const std::uint32_t size[3] = {100, 100, 100};
    field.reset(size);
    const std::uint32_t grown[3] = {300, 100, 100};
    field.grow(grown, Index3(100, 0, 0));
    EXPECT_EQ(keptLargeBytes(), 0u);
    held = field.bytes();
  }
  EXPECT_GE(keptLargeBytes(), held);
  EXPECT_LT(keptLargeBytes(), held + 3 * page) << "each of the three arrays rounded up to whole huge pages";
  releaseKeptLarge();
}

TEST(RunDistanceField, ABoxFromScratchHoldsOneVoxelAroundItAndABoxThatGrewRoomToGrowInPlace) {
  // Every voxel of the arrays is written when they are allocated: a box from scratch (a
  // snapshot's first build) gets the one voxel of outside on each side and no more.
  constexpr std::size_t kBytesPerVoxel = sizeof(std::uint32_t) + 1 + kernels::kOctants;  // index, cube flag, distances
  ig::RunDistanceField field;
  const std::uint32_t size[3] = {40, 24, 8};
  field.reset(size);
  EXPECT_EQ(field.bytes(), std::size_t{42} * 26 * 10 * kBytesPerVoxel);
  // Grown past that: the arrays get room around the new box ...
  const std::uint32_t grown[3] = {48, 24, 8};
  field.grow(grown, Index3(8, 0, 0));
  const std::size_t with_room = field.bytes();
  EXPECT_GT(with_room, std::size_t{50} * 26 * 10 * kBytesPerVoxel);
  // ... so that growing again by a block keeps them where they are.
  const std::uint32_t again[3] = {56, 24, 16};
  field.grow(again, Index3(0, 0, 8));
  EXPECT_EQ(field.bytes(), with_room);
}

TEST(InformationGain, SnapshotRunDistancesAreTheCubesAheadAfterRebuildAndUpdate) {
  // Clusters of measured voxels (four log-odds values) and marked voxels at both ends of a
  // 56 x 24 x 24 box, so that distances range from 1 to the cap in every octant.
  OccupancyMap map;
  std::mt19937 rng(8);
  std::uniform_int_distribution<int> near(0, 10), state(0, 5);
  const float values[4] = {logOdds(0.12), logOdds(0.3), logOdds(0.7), logOdds(0.97)};
  for (const Index3& corner : {Index3(0, 0, 0), Index3(45, 13, 13)}) {
    for (int i = 0; i < 400; ++i) {
      const Index3 ijk = corner + Index3(near(rng), near(rng), near(rng));
      const int k = state(rng);
      if (k < 4) {
        map.setLogOdds(ijk, values[k]);
      } else if (!map.isMeasured(ijk)) {
        map.setProximity(ijk, 1 + near(rng));
      }
    }
  }
  MapSnapshot snapshot;
  const kernels::VoxelModel model;
  EXPECT_TRUE(snapshot.update(map, model, std::size_t{1} << 30).rebuilt);
  const kernels::SnapshotView view = snapshot.view();
  ASSERT_EQ(std::vector<std::uint32_t>(view.size, view.size + 3), (std::vector<std::uint32_t>{56, 24, 24}));
  expectRunDistances(view, "rebuilt");
  // Voxels changed in the middle and near an end: a partial update, the same distances.
  map.setLogOdds(Index3(28, 12, 12), values[1]);
  map.setLogOdds(Index3(29, 12, 12), values[2]);
  map.setLogOdds(Index3(5, 23, 3), values[0]);
  const SnapshotUpdate update = snapshot.update(map, model, std::size_t{1} << 30);
  EXPECT_FALSE(update.rebuilt);
  EXPECT_EQ(update.blocks, 2u);
  expectRunDistances(snapshot.view(), "updated");
}

class SnapshotUpdates : public testing::TestWithParam<bool> {};

TEST_P(SnapshotUpdates, EqualASnapshotBuiltFromScratch) {
  // Rounds of changes: voxels set inside the box (measured values, marks, a measured voxel
  // over a mark) and, every third round, a voxel past one of the box's faces, so that the box
  // grows along each axis both ways. After each update every entry (the state's terms, its
  // frontier flag when the model asks for them, and all eight run distances) equals that of a
  // snapshot built from the map as it stands.
  OccupancyMap map;
  std::mt19937 rng(21);
  const float values[3] = {logOdds(0.12), logOdds(0.7), logOdds(0.97)};
  for (int i = 0; i < 300; ++i) map.setLogOdds(Index3(i % 9, (i / 9) % 9, i / 81), values[i % 3]);
  MapSnapshot updated;
  kernels::VoxelModel model;
  model.frontier = GetParam();
  EXPECT_TRUE(updated.update(map, model, std::size_t{1} << 30).rebuilt);
  Index3 lo(0, 0, 0), hi(8, 8, 8);
  bool grew = false;
  for (int round = 0; round < 24; ++round) {
    std::uniform_int_distribution<int> pick(0, 1 << 20);
    for (int i = 0; i < 40; ++i) {
      const Index3 ijk(lo.x() + pick(rng) % (hi.x() - lo.x() + 1), lo.y() + pick(rng) % (hi.y() - lo.y() + 1),
                       lo.z() + pick(rng) % (hi.z() - lo.z() + 1));
      if (i % 4 == 3 && !map.isMeasured(ijk)) {
        map.setProximity(ijk, 1 + pick(rng) % 8);
      } else {
        map.setLogOdds(ijk, values[pick(rng) % 3]);
      }
    }
    if (round % 3 == 2) {
      const int axis = (round / 3) % 3, side = (round / 9) % 2 == 0 ? 1 : -1;
      Index3 past = side > 0 ? hi : lo;
      past[axis] += side * (9 + pick(rng) % 12);
      map.setLogOdds(past, values[0]);
      lo = lo.cwiseMin(past);
      hi = hi.cwiseMax(past);
    }
    const SnapshotUpdate update = updated.update(map, model, std::size_t{1} << 30);
    EXPECT_FALSE(update.rebuilt) << "round " << round;
    grew = grew || update.grown;
    MapSnapshot fresh;
    fresh.update(map, model, std::size_t{1} << 30);
    const kernels::SnapshotView a = updated.view(), b = fresh.view();
    ASSERT_EQ(std::vector<int>(a.min, a.min + 3), std::vector<int>(b.min, b.min + 3)) << "round " << round;
    ASSERT_EQ(std::vector<std::uint32_t>(a.size, a.size + 3), std::vector<std::uint32_t>(b.size, b.size + 3));
    std::size_t wrong_distance = 0, wrong_state = 0;
    const std::size_t voxels = std::size_t{a.size[0]} * a.size[1] * a.size[2];
    for (std::size_t i = 0; i < voxels; ++i) {
      for (unsigned o = 0; o < kernels::kOctants; ++o) {
        wrong_distance += kernels::runDistance(a.voxels[i], o) != kernels::runDistance(b.voxels[i], o) ? 1 : 0;
      }
      const kernels::VoxelTerms &ta = a.palette[kernels::paletteIndex(a.voxels[i])],
                                &tb = b.palette[kernels::paletteIndex(b.voxels[i])];
      const bool same = ta.entropy == tb.entropy && ta.keep == tb.keep && ta.proximity == tb.proximity && ta.flags == tb.flags;
      wrong_state += same ? 0 : 1;
    }
    EXPECT_EQ(wrong_distance, 0u) << "round " << round;
    EXPECT_EQ(wrong_state, 0u) << "round " << round;
  }
  EXPECT_TRUE(grew);
  expectRunDistances(updated.view(), "after the rounds");
  // The frontier voxels were there to flag: free voxels next to unknown ones.
  std::size_t flagged = 0;
  const kernels::SnapshotView v = updated.view();
  for (std::size_t i = 0; i < std::size_t{v.size[0]} * v.size[1] * v.size[2]; ++i) {
    flagged += (v.palette[kernels::paletteIndex(v.voxels[i])].flags & kernels::voxel_flag::kFrontier) != 0 ? 1 : 0;
  }
  EXPECT_EQ(flagged > 100, GetParam()) << flagged << " frontier voxels";
}

INSTANTIATE_TEST_SUITE_P(InformationGain, SnapshotUpdates, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& param) { return param.param ? "frontier" : "plain"; });

TEST(InformationGain, SnapshotUpdatesAreTheSameAtAnyThreadCount) {
  // Blocks are read in tasks side by side; the states new to the palette are added in the order
  // one pass over the changed blocks meets them, so the palette and every entry are the same
  // whatever the threads. Each round sets a new log-odds value in each of 192 blocks (three in
  // some), most of them new states, spread over tasks.
  OccupancyMap map;
  for (int z = 0; z < 48; z += 2) {
    for (int y = 0; y < 64; y += 3) {
      for (int x = 0; x < 64; x += 5) map.setLogOdds(Index3(x, y, z), logOdds(0.4));
    }
  }
  const kernels::VoxelModel model;
  MapSnapshot one, two;
  tbb::task_arena arena_one(1), arena_two(2);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> voxel(0, 7), value(0, 4000);
  for (int round = 0; round < 4; ++round) {
    std::size_t blocks = 0;
    for (int bz = 0; bz < 6; ++bz) {
      for (int by = 0; by < 8; ++by) {
        for (int bx = 0; bx < 4; ++bx, ++blocks) {
          const int voxels = (bx + by + round) % 5 == 0 ? 3 : 1;
          for (int i = 0; i < voxels; ++i) {
            const Index3 ijk(8 * bx + voxel(rng), 8 * by + voxel(rng), 8 * bz + voxel(rng));
            map.setLogOdds(ijk, -1.9f + 0.001f * static_cast<float>(value(rng)));
          }
        }
      }
    }
    SnapshotUpdate a, b;
    arena_one.execute([&] { a = one.update(map, model, std::size_t{1} << 30); });
    arena_two.execute([&] { b = two.update(map, model, std::size_t{1} << 30); });
    EXPECT_EQ(a.rebuilt, round == 0);
    if (round > 0) {
      EXPECT_EQ(a.blocks, blocks) << "round " << round;
    }
    EXPECT_EQ(a.palette, b.palette) << "round " << round;
    EXPECT_EQ(a.voxels, b.voxels) << "round " << round;
    const kernels::SnapshotView va = one.view(), vb = two.view();
    ASSERT_EQ(std::vector<std::uint32_t>(va.size, va.size + 3), std::vector<std::uint32_t>(vb.size, vb.size + 3));
    const std::size_t voxels = std::size_t{va.size[0]} * va.size[1] * va.size[2];
    EXPECT_TRUE(std::equal(va.voxels, va.voxels + voxels, vb.voxels)) << "round " << round << ": entries differ";
    ASSERT_EQ(va.palette.size(), vb.palette.size());
    for (std::size_t i = 0; i < va.palette.size(); ++i) {
      EXPECT_EQ(va.palette[i].entropy, vb.palette[i].entropy) << "round " << round << ", state " << i;
    }
  }
  EXPECT_GT(one.view().palette.size(), 400u) << "the rounds added new states";
}

TEST(InformationGain, TenThousandViewsInChunksEqualViewsOneByOne) {
  // Views are evaluated in chunks (bounded memory); rows at and around the chunk edges, and the
  // last one, equal the same views evaluated alone.
  const test::RandomScene s = test::randomScene(6);
  std::vector<Eigen::Isometry3d> views;
  for (std::size_t i = 0; i < 10000; ++i) views.push_back(s.views[i % s.views.size()]);
  const std::vector<Eigen::Vector3d> rays(s.directions.begin(), s.directions.begin() + 8);
  IgEvaluator evaluator;
  const IgTable table = ig::evaluate(evaluator, s.map, views, rays);
  ASSERT_EQ(table.views(), views.size());
  for (const std::size_t v : {0u, 63u, 64u, 65u, 127u, 128u, 5003u, 9999u}) {
    const IgTable alone = ig::evaluate(evaluator, s.map, std::vector{views[v]}, rays);
    for (std::size_t m = 0; m < table.metrics.size(); ++m) {
      if (table.metrics[m] == Metric::Random) continue;  // seeded by the view's index
      EXPECT_EQ(table.value(v, m), alone.value(0, m)) << "view " << v;
    }
  }
}

TEST(InformationGain, SnapshotMemoryCapIsAClearError) {
  const test::RandomScene s = test::randomScene(7);
  EvaluateOptions options;
  options.snapshot.max_snapshot_bytes = 1000;
  try {
    ig::evaluate(s.map, s.views, s.directions, options);
    FAIL() << "no error";
  } catch (const CapacityError& e) {
    EXPECT_NE(std::string(e.what()).find("more than the limit of 1000"), std::string::npos) << e.what();
  }
}

TEST(InformationGain, BadInputsAreRefusedByName) {
  const OccupancyMap map = tinyMap();
  IgEvaluator fast;
  const std::vector<Eigen::Vector3d> dirs = {Eigen::Vector3d::UnitZ()};
  Eigen::Isometry3d nan_view = cameraAtOrigin();
  nan_view.translation().x() = std::nan("");
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{nan_view}, dirs), InvalidArgument);
  Eigen::Isometry3d scaled = cameraAtOrigin();
  scaled.linear() *= 2.0;
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{scaled}, dirs), InvalidArgument);
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{cameraAtOrigin()}, std::vector{Eigen::Vector3d(1, 1, 0)}),
               InvalidArgument);
  EvaluateOptions options;
  options.walk.max_ray_depth = 0.0;
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{cameraAtOrigin()}, dirs, options), InvalidArgument);
  options = EvaluateOptions{};
  options.table.metrics.clear();
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{cameraAtOrigin()}, dirs, options), InvalidArgument);
  // No views: an empty table, not an error. No rays: refused, by both evaluators, also after an
  // evaluation that left its rays in the evaluator.
  EXPECT_EQ(ig::evaluate(fast, map, {}, dirs).views(), 0u);
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{cameraAtOrigin()}, {}), InvalidArgument);
  EXPECT_THROW(ReferenceEvaluator(map).evaluate(std::vector{cameraAtOrigin()}, {}, EvaluateOptions{}), InvalidArgument);
  options = EvaluateOptions{};
  options.table.metrics = {Metric::Random};
  EXPECT_THROW(ig::evaluate(fast, map, std::vector{cameraAtOrigin()}, {}, options), InvalidArgument);
}

}  // namespace
}  // namespace nbv::ig
