// Hand-computed cases of SEMANTICS.md "The map": misses, hits, clamps, max range, proximity marks.
#include "nbv/errors.hpp"
#include "nbv/grid/occupancy_map.hpp"

#include "scenes.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <bit>
#include <random>

namespace {

using nbv::grid::Index3;
using nbv::grid::OccupancyMap;

// log(p / (1 - p)) worked out by hand: ln(0.4/0.6), ln(0.7/0.3), ln(0.12/0.88), ln(0.97/0.03).
constexpr double kMiss = -0.4054651081;
constexpr double kHit = 0.8472978604;
constexpr double kClampMin = -1.9924301646;
constexpr double kClampMax = 3.4760986898;

const Eigen::Vector3f kOrigin(0.005f, 0.005f, 0.005f);  // centre of voxel (0, 0, 0)

Eigen::Vector3f onXAxis(int voxel) { return {0.01f * static_cast<float>(voxel) + 0.005f, 0.005f, 0.005f}; }

TEST(OccupancyMap, DefaultsAreSpecSection1) {
  const OccupancyMap::Config c;
  EXPECT_EQ(c.resolution, 0.01);
  EXPECT_EQ(c.p_hit, 0.7);
  EXPECT_EQ(c.p_miss, 0.4);
  EXPECT_EQ(c.clamp_min, 0.12);
  EXPECT_EQ(c.clamp_max, 0.97);
  EXPECT_EQ(c.max_range, 1.5);
  EXPECT_EQ(c.proximity_range, 0.3);
}

TEST(OccupancyMap, UnmeasuredVoxelReadsThePrior) {
  const OccupancyMap map;
  EXPECT_FALSE(map.isMeasured(Index3(3, 4, 5)));
  EXPECT_EQ(map.logOdds(Index3(3, 4, 5)), 0.0f);
  EXPECT_EQ(map.probability(Index3(3, 4, 5)), 0.5);
  EXPECT_EQ(map.measuredCount(), 0u);
  EXPECT_FALSE(map.measuredBoundsIndex().has_value());
}

TEST(OccupancyMap, OneRayThroughThreeVoxels) {
  OccupancyMap map;
  const auto stats = map.integrate({onXAxis(3)}, kOrigin);
  EXPECT_EQ(stats.hits, 1u);
  EXPECT_EQ(stats.voxels_missed, 3u);
  EXPECT_EQ(stats.voxels_hit, 1u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(map.logOdds(Index3(i, 0, 0)), kMiss, 1e-6) << i;
    EXPECT_NEAR(map.probability(Index3(i, 0, 0)), 0.4, 1e-7);
  }
  EXPECT_NEAR(map.logOdds(Index3(3, 0, 0)), kHit, 1e-6);
  EXPECT_NEAR(map.probability(Index3(3, 0, 0)), 0.7, 1e-7);
  EXPECT_FALSE(map.isMeasured(Index3(4, 0, 0)));
  EXPECT_EQ(map.measuredCount(), 4u);
  const auto bounds = map.measuredBoundsIndex();
  ASSERT_TRUE(bounds.has_value());
  EXPECT_EQ(bounds->min(), Index3(0, 0, 0));
  EXPECT_EQ(bounds->max(), Index3(3, 0, 0));
  // Queries by world point agree with queries by index.
  EXPECT_EQ(map.logOdds(Eigen::Vector3d(0.031, 0.001, 0.009)), map.logOdds(Index3(3, 0, 0)));
}

TEST(OccupancyMap, VoxelHitAndCrossedInOneScanGetsOnlyTheHit) {
  OccupancyMap map;
  // The ray to voxel 5 crosses voxel 3, which the other point hits.
  map.integrate({onXAxis(3), onXAxis(5)}, kOrigin);
  EXPECT_NEAR(map.logOdds(Index3(3, 0, 0)), kHit, 1e-6);
  EXPECT_NEAR(map.logOdds(Index3(4, 0, 0)), kMiss, 1e-6);
  EXPECT_NEAR(map.logOdds(Index3(5, 0, 0)), kHit, 1e-6);
}

TEST(OccupancyMap, EachVoxelUpdatedOncePerScan) {
  OccupancyMap map;
  // Twenty points in voxel 3 and twenty rays through voxels 0..2: one update each.
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 20; ++i) points.push_back(onXAxis(3) + Eigen::Vector3f(0.0002f * static_cast<float>(i), 0.0f, 0.0f));
  map.integrate(points, kOrigin);
  EXPECT_NEAR(map.logOdds(Index3(1, 0, 0)), kMiss, 1e-6);
  EXPECT_NEAR(map.logOdds(Index3(3, 0, 0)), kHit, 1e-6);
}

TEST(OccupancyMap, LogOddsClampAtBothEnds) {
  OccupancyMap map;
  for (int scan = 1; scan <= 6; ++scan) {
    map.integrate({onXAxis(3)}, kOrigin);
    const double hits = std::min(scan * kHit, kClampMax);
    const double misses = std::max(scan * kMiss, kClampMin);
    EXPECT_NEAR(map.logOdds(Index3(3, 0, 0)), hits, 1e-5) << scan;
    EXPECT_NEAR(map.logOdds(Index3(1, 0, 0)), misses, 1e-5) << scan;
  }
  EXPECT_NEAR(map.probability(Index3(3, 0, 0)), 0.97, 1e-6);
  EXPECT_NEAR(map.probability(Index3(1, 0, 0)), 0.12, 1e-6);
  EXPECT_EQ(map.occupiedCount(), 1u);
  EXPECT_EQ(map.freeCount(), 3u);
}

TEST(OccupancyMap, PointBeyondMaxRangeClearsUpToMaxRangeWithoutHit) {
  OccupancyMap::Config config;
  config.max_range = 0.1;
  OccupancyMap map(config);
  const auto stats = map.integrate({onXAxis(30)}, kOrigin);
  EXPECT_EQ(stats.beyond_range, 1u);
  EXPECT_EQ(stats.hits, 0u);
  // Free space to origin + 0.1 m = x 0.105 (voxel 10, excluded as the segment's end voxel).
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(map.logOdds(Index3(i, 0, 0)), kMiss, 1e-6) << i;
  EXPECT_FALSE(map.isMeasured(Index3(10, 0, 0)));
  EXPECT_FALSE(map.isMeasured(Index3(30, 0, 0)));
  EXPECT_EQ(map.markedCount(), 0u);  // no hit, no marks
}

TEST(OccupancyMap, ProximityMarksBehindTheHit) {
  OccupancyMap map;
  map.integrate({onXAxis(10)}, kOrigin);
  // Ray continued from the hit point for 0.3 m: voxels 11..39 behind the hit voxel 10 get
  // d = 1..29; voxel 40 holds the end point and is excluded, as in every ray of the map.
  EXPECT_FALSE(map.proximity(Index3(10, 0, 0)).has_value());  // measured: never marked
  for (int k = 1; k <= 29; ++k) {
    const auto d = map.proximity(Index3(10 + k, 0, 0));
    ASSERT_TRUE(d.has_value()) << k;
    EXPECT_EQ(*d, k);
    EXPECT_FALSE(map.isMeasured(Index3(10 + k, 0, 0)));  // a marked voxel stays unmeasured
    EXPECT_EQ(map.probability(Index3(10 + k, 0, 0)), 0.5);
  }
  EXPECT_FALSE(map.proximity(Index3(40, 0, 0)).has_value());
  EXPECT_EQ(map.markedCount(), 29u);

  // A later scan hits voxel 12: voxel 11 becomes measured (mark gone), voxel 13 keeps the
  // smaller distance 1 instead of 3.
  map.integrate({onXAxis(12)}, kOrigin);
  EXPECT_FALSE(map.proximity(Index3(11, 0, 0)).has_value());
  EXPECT_FALSE(map.proximity(Index3(12, 0, 0)).has_value());
  EXPECT_EQ(map.proximity(Index3(13, 0, 0)), 1);
  EXPECT_EQ(map.proximity(Index3(20, 0, 0)), 8);
  EXPECT_EQ(map.proximity(Index3(39, 0, 0)), 27);
  EXPECT_EQ(map.proximity(Index3(41, 0, 0)), 29);
}

TEST(OccupancyMap, ProximityDistancesBeyondAByteAreKept) {
  // 3 m behind a hit at 1 cm: the distances reach 299, beyond a byte (and the scan's dense
  // scratch, which holds bytes: the sparse path marks them).
  OccupancyMap::Config config;
  config.proximity_range = 3.0;
  OccupancyMap map(config);
  map.integrate({onXAxis(10)}, kOrigin);
  EXPECT_EQ(map.markedCount(), 299u);
  EXPECT_EQ(map.proximity(Index3(11, 0, 0)), 1);
  EXPECT_EQ(map.proximity(Index3(266, 0, 0)), 256);
  EXPECT_EQ(map.proximity(Index3(309, 0, 0)), 299);
}

TEST(OccupancyMap, ProximityDistanceIsSixteenBits) {
  OccupancyMap map;
  map.setProximity(Index3(-1, 2, 3), OccupancyMap::Config::kMaxProximityDistance);
  EXPECT_EQ(map.proximity(Index3(-1, 2, 3)), 65535);
  try {
    map.setProximity(Index3(-1, 2, 3), 65536);
    FAIL();
  } catch (const nbv::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("65536"), std::string::npos) << e.what();
  }
  EXPECT_THROW(map.setProximity(Index3(0, 0, 0), 0), nbv::InvalidArgument);
  EXPECT_EQ(map.proximity(Index3(-1, 2, 3)), 65535);  // a refused mark changes nothing
  EXPECT_EQ(map.markedCount(), 1u);
}

TEST(OccupancyMap, AMapAroundTheOriginTakesSmallNodes) {
  // One voxel and one mark in each octant around the origin: each lies in its own 8^3 leaf
  // under two levels of 8^3 nodes, about 20 KB an octant for both grids (OpenVDB's standard
  // trees put a node of 32^3 children, 270 KB, above each leaf, in each grid: 4.9 MB).
  OccupancyMap map;
  for (int octant = 0; octant < 8; ++octant) {
    const Index3 ijk((octant & 1) != 0 ? -1 : 0, (octant & 2) != 0 ? -1 : 0, (octant & 4) != 0 ? -1 : 0);
    map.setLogOdds(ijk, 0.5f);
    map.setProximity(ijk + Index3(0, 0, (octant & 4) != 0 ? -1 : 1), 1);
  }
  EXPECT_EQ(map.measuredCount(), 8u);
  EXPECT_EQ(map.markedCount(), 8u);
  EXPECT_LT(map.memoryBytes(), std::size_t{256} * 1024);
}

TEST(OccupancyMap, ProximityRangeZeroDisablesMarks) {
  OccupancyMap::Config config;
  config.proximity_range = 0.0;
  OccupancyMap map(config);
  map.integrate({onXAxis(10)}, kOrigin);
  EXPECT_EQ(map.markedCount(), 0u);
}

TEST(OccupancyMap, NonFinitePointsAreSkipped) {
  OccupancyMap map;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const auto stats = map.integrate({{nan, 0.f, 0.f}, onXAxis(3), {0.f, inf, 0.f}, {1e30f, 0.f, 0.f}}, kOrigin);
  EXPECT_EQ(stats.skipped_points, 3u);
  EXPECT_EQ(stats.hits, 1u);
  EXPECT_EQ(map.measuredCount(), 4u);
}

TEST(OccupancyMap, PointsAtTheEdgeOfTheIndexRangeAreSkippedExactlyWhenOutOfRange) {
  // Points a few ulps around the largest coordinate the lattice accepts (about 2^30 voxels),
  // on every axis and both signs; beyond max_range, so each kept one clears a short ray.
  for (double resolution : {0.01, 0.05, 1.0 / 3.0}) {
    OccupancyMap::Config config;
    config.resolution = resolution;
    config.max_range = 0.5;
    const nbv::kernels::VoxelLattice lattice(resolution);
    auto coordinate = static_cast<float>(static_cast<double>(nbv::kernels::kMaxVoxelIndex) * resolution);
    for (int k = 0; k < 4; ++k) coordinate = std::nextafter(coordinate, 0.0f);
    std::vector<Eigen::Vector3f> points;
    std::size_t out_of_range = 0;
    for (int k = 0; k < 8; ++k, coordinate = std::nextafter(coordinate, 1e30f)) {
      for (int a = 0; a < 3; ++a) {
        for (float sign : {1.0f, -1.0f}) {
          points.push_back(Eigen::Vector3f::Unit(a) * (sign * coordinate));
          out_of_range += !lattice.inRange(points.back());
        }
      }
    }
    ASSERT_GT(out_of_range, 0u);
    ASSERT_LT(out_of_range, points.size());
    OccupancyMap map(config);
    const nbv::grid::ScanStats stats = map.integrate(points, Eigen::Vector3f::Zero());
    EXPECT_EQ(stats.skipped_points, out_of_range) << "resolution " << resolution;
    EXPECT_EQ(stats.beyond_range, points.size() - out_of_range);
  }
}

TEST(OccupancyMap, NonFiniteOriginThrows) {
  OccupancyMap map;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(map.integrate({onXAxis(3)}, {nan, 0.f, 0.f}), nbv::InvalidArgument);
  EXPECT_THROW(map.integrate({onXAxis(3)}, {0.f, std::numeric_limits<float>::infinity(), 0.f}),
               nbv::InvalidArgument);
  EXPECT_EQ(map.measuredCount(), 0u);
}

TEST(OccupancyMap, EmptyScanChangesNothing) {
  OccupancyMap map;
  const auto stats = map.integrate(std::vector<Eigen::Vector3f>{}, kOrigin);
  EXPECT_EQ(stats.points, 0u);
  EXPECT_EQ(map.measuredCount(), 0u);
}

TEST(OccupancyMap, InvalidConfigurationThrowsNamingTheValue) {
  for (auto mutate : {+[](OccupancyMap::Config& c) { c.resolution = 0.0; },
                      +[](OccupancyMap::Config& c) { c.resolution = -0.01; },
                      +[](OccupancyMap::Config& c) { c.max_range = 0.0; },
                      +[](OccupancyMap::Config& c) { c.p_hit = 0.4; },
                      +[](OccupancyMap::Config& c) { c.clamp_min = std::nan(""); },
                      +[](OccupancyMap::Config& c) { c.proximity_range = -1.0; },
                      +[](OccupancyMap::Config& c) { c.proximity_range = 200.01; }}) {
    OccupancyMap::Config config;
    mutate(config);
    EXPECT_THROW(OccupancyMap{config}, nbv::InvalidArgument);
  }
  try {
    OccupancyMap::Config config;
    config.resolution = -0.5;
    OccupancyMap map(config);
    FAIL();
  } catch (const nbv::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("resolution = -0.5"), std::string::npos) << e.what();
  }
  OccupancyMap::Config longest;
  longest.proximity_range = 200.0;  // 20,000 voxels of 1 cm: the longest a 16-bit mark allows
  EXPECT_NO_THROW(OccupancyMap{longest});
}

TEST(OccupancyMap, EveryConfigurationFieldIsARowThatValidationNamesWithItsRule) {
  const auto fields = nbv::grid::mapConfigFields();
  ASSERT_EQ(fields.size(), 10u);
  EXPECT_EQ(nbv::grid::mapConfigFieldNames(),
            "resolution, p_hit, p_miss, clamp_min, clamp_max, max_range, proximity_range, occupied_threshold, "
            "free_threshold, min_range");
  const OccupancyMap::Config defaults;
  for (const nbv::grid::MapConfigField& field : fields) {
    SCOPED_TRACE(field.name);
    EXPECT_EQ(defaults.*field.member, field.default_value);
    EXPECT_EQ(nbv::grid::mapConfigField(field.name), &field);
    // NaN fails every field's check, and the error names the field, the value and the rule.
    OccupancyMap::Config config;
    config.*field.member = std::nan("");
    try {
      config.validate();
      ADD_FAILURE() << "NaN accepted";
    } catch (const nbv::InvalidArgument& e) {
      EXPECT_EQ(std::string(e.what()), "invalid map configuration: " + std::string(field.name) + " = nan (" + field.rule + ")");
    }
  }
  EXPECT_EQ(nbv::grid::mapConfigField("p_hitt"), nullptr);
  // The checks that read another field.
  OccupancyMap::Config config;
  config.min_range = config.max_range;
  EXPECT_THROW(config.validate(), nbv::InvalidArgument);
  config = {};
  config.free_threshold = 0.9;
  EXPECT_THROW(config.validate(), nbv::InvalidArgument);
}

void expectBitIdentical(const OccupancyMap& a, const OccupancyMap& b) {
  const auto va = a.measuredVoxels();
  const auto vb = b.measuredVoxels();
  ASSERT_EQ(va.size(), vb.size());
  ASSERT_GT(va.size(), 1000u);
  for (std::size_t i = 0; i < va.size(); ++i) {
    ASSERT_EQ(va[i].ijk, vb[i].ijk);
    ASSERT_EQ(std::bit_cast<std::uint32_t>(va[i].log_odds), std::bit_cast<std::uint32_t>(vb[i].log_odds));
  }
  const auto ma = a.proximityMarks();
  const auto mb = b.proximityMarks();
  ASSERT_EQ(ma.size(), mb.size());
  ASSERT_GT(ma.size(), 1000u);
  for (std::size_t i = 0; i < ma.size(); ++i) {
    ASSERT_EQ(ma[i].ijk, mb[i].ijk);
    ASSERT_EQ(ma[i].distance, mb[i].distance);
  }
}

TEST(OccupancyMap, SerialParallelEveryIsaDenseAndSparsePathsAreBitIdentical) {
  const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  nbv::grid::IntegrateOptions serial;
  serial.serial = true;
  nbv::grid::IntegrateOptions parallel;
  parallel.grain_size = 64;  // many tasks
  nbv::grid::IntegrateOptions sparse = parallel;
  sparse.max_scratch_bytes = 0;  // forces the sparse OpenVDB voxel sets
  // The others take the best instruction set here; each available one gets a map too.
  std::vector<nbv::grid::IntegrateOptions> per_isa;
  for (nbv::kernels::Isa isa : nbv::kernels::availableIsas()) {
    per_isa.push_back(parallel);
    per_isa.back().isa = isa;
  }
  OccupancyMap map_serial, map_parallel, map_sparse;
  std::vector<OccupancyMap> map_isa(per_isa.size());
  for (const Eigen::Vector3d& position : {Eigen::Vector3d(0.6, 0.0, 0.15), Eigen::Vector3d(0.0, -0.6, 0.4),
                                          Eigen::Vector3d(-0.4, 0.3, 0.7)}) {
    const auto T = nbv::test::lookAt(position, {0.0, 0.0, 0.25});
    auto points = nbv::test::idealScan(sphere, T, 3);
    points.emplace_back(5.0f, 0.1f, 0.2f);  // beyond max range
    const Eigen::Vector3f origin = position.cast<float>();
    map_serial.integrate(points, origin, serial);
    map_parallel.integrate(points, origin, parallel);
    map_sparse.integrate(points, origin, sparse);
    for (std::size_t i = 0; i < per_isa.size(); ++i) map_isa[i].integrate(points, origin, per_isa[i]);
  }
  expectBitIdentical(map_serial, map_parallel);
  for (const OccupancyMap& map : map_isa) expectBitIdentical(map_serial, map);
  expectBitIdentical(map_serial, map_sparse);
}

void expectSameStats(const nbv::grid::ScanStats& a, const nbv::grid::ScanStats& b) {
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.skipped_points, b.skipped_points);
  EXPECT_EQ(a.hits, b.hits);
  EXPECT_EQ(a.beyond_range, b.beyond_range);
  EXPECT_EQ(a.voxels_hit, b.voxels_hit);
  EXPECT_EQ(a.voxels_missed, b.voxels_missed);
  EXPECT_EQ(a.voxels_marked, b.voxels_marked);
}

TEST(OccupancyMap, ScanUpdatesMarkedOnceLeaveEveryMapAsItsPointsDo) {
  // Three scans marked once each (dense and sparse sets), applied to maps that see them in
  // different orders: each map equals the one integrate() of the points gives in that order,
  // with the same stats, and the update's voxel count is the scan's updated voxels.
  const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  struct Scan {
    std::vector<Eigen::Vector3f> points;
    Eigen::Vector3f origin;
  };
  std::vector<Scan> scans;
  for (const Eigen::Vector3d& position : {Eigen::Vector3d(0.6, 0.0, 0.15), Eigen::Vector3d(0.0, -0.6, 0.4),
                                          Eigen::Vector3d(-0.4, 0.3, 0.7)}) {
    const auto T = nbv::test::lookAt(position, {0.0, 0.0, 0.25});
    scans.push_back({nbv::test::idealScan(sphere, T, 3), position.cast<float>()});
    scans.back().points.emplace_back(5.0f, 0.1f, 0.2f);                                    // beyond max range
    scans.back().points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);  // skipped
  }
  nbv::grid::IntegrateOptions sparse;
  sparse.max_scratch_bytes = 0;
  std::vector<nbv::grid::ScanUpdate> dense_updates, sparse_updates;
  for (const Scan& scan : scans) {
    dense_updates.emplace_back(nbv::grid::MapConfig{}, scan.points, scan.origin);
    sparse_updates.emplace_back(nbv::grid::MapConfig{}, scan.points, scan.origin, sparse);
    EXPECT_EQ(dense_updates.back().voxelCount(), sparse_updates.back().voxelCount());
    EXPECT_EQ(dense_updates.back().points().skipped_points, 1u);
    EXPECT_EQ(dense_updates.back().points().beyond_range, 1u);
  }
  for (const std::array<int, 3>& order : {std::array{0, 1, 2}, std::array{2, 0, 1}, std::array{1, 2, 0}}) {
    OccupancyMap from_points, from_dense, from_sparse;
    for (int s : order) {
      const nbv::grid::ScanStats expected = from_points.integrate(scans[s].points, scans[s].origin);
      EXPECT_EQ(dense_updates[s].voxelCount(), expected.voxels_hit + expected.voxels_missed);
      expectSameStats(from_dense.integrate(dense_updates[s]), expected);
      expectSameStats(from_sparse.integrate(sparse_updates[s]), expected);
    }
    expectBitIdentical(from_points, from_dense);
    expectBitIdentical(from_points, from_sparse);
  }
}

TEST(OccupancyMap, ScanUpdateOfAnotherConfigurationIsRefused) {
  const nbv::grid::ScanUpdate update(nbv::grid::MapConfig{}, std::vector<Eigen::Vector3f>{onXAxis(3)}, kOrigin);
  for (const auto& change : std::vector<std::function<void(nbv::grid::MapConfig&)>>{
           [](auto& c) { c.resolution = 0.02; }, [](auto& c) { c.max_range = 2.0; },
           [](auto& c) { c.proximity_range = 0.1; }}) {
    nbv::grid::MapConfig config;
    change(config);
    OccupancyMap map(config);
    EXPECT_THROW(map.integrate(update), nbv::InvalidArgument);
    EXPECT_EQ(map.measuredCount(), 0u);
  }
  nbv::grid::MapConfig other_sensor_model;  // the probabilities are the map's own, not the scan's
  other_sensor_model.p_hit = 0.9;
  OccupancyMap map(other_sensor_model);
  map.integrate(update);
  EXPECT_FLOAT_EQ(map.logOdds(Index3(3, 0, 0)), OccupancyMap::logOddsOf(0.9));
  EXPECT_THROW(nbv::grid::ScanUpdate(nbv::grid::MapConfig{}, std::vector<Eigen::Vector3f>{onXAxis(3)},
                                     Eigen::Vector3f(std::numeric_limits<float>::infinity(), 0.0f, 0.0f)),
               nbv::InvalidArgument);
}

TEST(OccupancyMap, VoxelCapRefusesAScanAndLeavesTheMapAsItWas) {
  const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  const auto T = nbv::test::lookAt({0.6, 0.0, 0.15}, {0.0, 0.0, 0.25});
  const auto points = nbv::test::idealScan(sphere, T, 4);
  const Eigen::Vector3f origin = T.translation().cast<float>();
  OccupancyMap reference;
  reference.integrate(points, origin);
  const std::size_t voxels = reference.measuredCount();
  ASSERT_GT(voxels, 1000u);
  for (const std::size_t scratch_bytes : {std::size_t{1} << 27, std::size_t{0}}) {  // dense and sparse sets
    nbv::grid::IntegrateOptions capped;
    capped.max_scratch_bytes = scratch_bytes;
    capped.max_measured_voxels = voxels - 1;
    OccupancyMap map;
    EXPECT_THROW(map.integrate(points, origin, capped), nbv::CapacityError);
    EXPECT_EQ(map.measuredCount(), 0u);
    // Exactly at the cap it fits; the same scan again adds no voxel, so it fits too.
    capped.max_measured_voxels = voxels;
    map.integrate(points, origin, capped);
    map.integrate(points, origin, capped);
    EXPECT_EQ(map.measuredCount(), voxels);
    // A scan from elsewhere would add voxels: refused, and the map keeps its log-odds.
    const auto T2 = nbv::test::lookAt({0.0, -0.6, 0.4}, {0.0, 0.0, 0.25});
    const auto before = map.measuredVoxels();
    EXPECT_THROW(map.integrate(nbv::test::idealScan(sphere, T2, 4), T2.translation().cast<float>(), capped),
                 nbv::CapacityError);
    const auto after = map.measuredVoxels();
    ASSERT_EQ(before.size(), after.size());
    for (std::size_t i = 0; i < before.size(); ++i) ASSERT_EQ(before[i].log_odds, after[i].log_odds);
  }
}

TEST(OccupancyMap, CopyMeasuredLogOddsFillsTheBoxAndLeavesTheRest) {
  // Measured voxels inside and outside a box that crosses block borders (blocks of 8^3): those
  // inside land at ((i - i0) * nj + (j - j0)) * nk + (k - k0); the unmeasured keep their value.
  OccupancyMap map;
  const std::vector<std::pair<Index3, float>> set = {{Index3(-3, 2, 5), 0.5f},  {Index3(4, 7, 9), -1.25f},
                                                     {Index3(4, 8, 9), 2.0f},   {Index3(-4, 2, 5), 3.0f},
                                                     {Index3(9, 20, -2), 1.0f}, {Index3(0, 0, 0), -0.75f}};
  for (const auto& [ijk, value] : set) map.setLogOdds(ijk, value);
  const Eigen::AlignedBox3i box(Index3(-3, 0, 0), Index3(4, 7, 9));  // 8 x 8 x 10
  std::vector<float> dense(8 * 8 * 10, 42.0f);
  map.copyMeasuredLogOdds(box, dense);
  std::vector<float> expected(dense.size(), 42.0f);
  for (const auto& [ijk, value] : set) {
    if (!box.contains(ijk)) continue;
    const Index3 r = ijk - box.min();
    expected[(static_cast<std::size_t>(r.x()) * 8 + static_cast<std::size_t>(r.y())) * 10 + static_cast<std::size_t>(r.z())] = value;
  }
  EXPECT_EQ(dense, expected);
  EXPECT_EQ(std::count(dense.begin(), dense.end(), 42.0f), 8 * 8 * 10 - 3);
  std::vector<float> short_by_one(8 * 8 * 10 - 1);
  EXPECT_THROW(map.copyMeasuredLogOdds(box, short_by_one), nbv::InvalidArgument);
}

TEST(OccupancyMap, CopyIsDeep) {
  OccupancyMap a;
  a.integrate({onXAxis(3)}, kOrigin);
  OccupancyMap b = a;
  b.integrate({onXAxis(3)}, kOrigin);
  EXPECT_NEAR(a.logOdds(Index3(3, 0, 0)), kHit, 1e-6);
  EXPECT_NEAR(b.logOdds(Index3(3, 0, 0)), 2 * kHit, 1e-5);
}

}  // namespace
