// The same scans in liboctomap's OcTree::insertPointCloud and in OccupancyMap give the same
// measured voxels with equal log-odds (SEMANTICS.md "The map").
#include "nbv/grid/occupancy_map.hpp"

#include "octomap_compare.hpp"
#include "scenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using nbv::grid::OccupancyMap;
using nbv::test::Box;
using nbv::test::Sphere;
using Points = std::vector<Eigen::Vector3f>;

struct Scan {
  Points points;
  Eigen::Vector3f origin;
};

void crossCheck(const std::vector<Scan>& scans, const OccupancyMap::Config& config = {},
                nbv::grid::IntegrateOptions options = {}) {
  OccupancyMap map(config);
  octomap::OcTree tree(config.resolution);
  nbv::test::configureLikeMap(tree, config);
  for (const Scan& scan : scans) {
    map.integrate(scan.points, scan.origin, options);
    octomap::Pointcloud cloud;
    for (const auto& p : scan.points) {
      if (p.allFinite()) cloud.push_back(p.x(), p.y(), p.z());
    }
    tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x(), scan.origin.y(), scan.origin.z()),
                          config.max_range, /*lazy_eval=*/false, options.discretize);
  }
  nbv::test::expectMapEqualsTree(map, tree, 1e-6);
}

Scan sphereScan(const Sphere& sphere, const Eigen::Vector3d& position, int stride) {
  const auto T = nbv::test::lookAt(position, sphere.centre);
  return {nbv::test::idealScan(sphere, T, stride), position.cast<float>()};
}

TEST(OctomapCrossCheck, SphereFromSeveralOrigins) {
  const Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  std::vector<Scan> scans;
  for (const Eigen::Vector3d& position :
       {Eigen::Vector3d(0.6, 0.0, 0.15), Eigen::Vector3d(0.0, 0.6, 0.35), Eigen::Vector3d(-0.42, -0.1, 0.77),
        Eigen::Vector3d(0.3, -0.5, 0.05), Eigen::Vector3d(0.6, 0.0, 0.15)}) {
    scans.push_back(sphereScan(sphere, position, 4));
  }
  crossCheck(scans);
}

TEST(OctomapCrossCheck, DiscretizeIsOneRayPerEndVoxel) {
  // insertPointCloud(..., discretize = true): the points reduced to their voxels' centres,
  // through the dense and the sorted reduction, on a sphere, random points (many beyond max
  // range) and a coarse lattice.
  nbv::grid::IntegrateOptions discretize;
  discretize.discretize = true;
  nbv::grid::IntegrateOptions sorted = discretize;
  sorted.max_scratch_bytes = 0;
  const Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  const std::vector<Scan> spheres = {sphereScan(sphere, {0.6, 0.0, 0.15}, 1), sphereScan(sphere, {0.0, 0.6, 0.35}, 2),
                                     sphereScan(sphere, {-0.42, -0.1, 0.77}, 1)};
  crossCheck(spheres, {}, discretize);
  crossCheck(spheres, {}, sorted);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> coord(-2.5f, 2.5f);
  Scan random{{}, {0.1f, -0.05f, 0.2f}};
  for (int i = 0; i < 6000; ++i) random.points.emplace_back(coord(rng), coord(rng), coord(rng));
  random.points.emplace_back(std::nanf(""), 0.0f, 0.0f);
  crossCheck({random, random}, {}, discretize);
  OccupancyMap::Config coarse;
  coarse.resolution = 0.05;
  coarse.max_range = 0.7;
  crossCheck({random}, coarse, discretize);
  crossCheck({random}, coarse, sorted);
  // Fewer rays than points: one per distinct voxel.
  OccupancyMap map;
  const auto stats = map.integrate(spheres[0].points, spheres[0].origin, discretize);
  EXPECT_EQ(stats.points, spheres[0].points.size());
  EXPECT_LT(stats.hits * 5, stats.points);
}

TEST(OctomapCrossCheck, BoxFromSeveralOrigins) {
  const Box box{{-0.1, -0.15, 0.0}, {0.12, 0.1, 0.3}};
  std::vector<Scan> scans;
  for (const Eigen::Vector3d& position :
       {Eigen::Vector3d(0.6, 0.0, 0.15), Eigen::Vector3d(0.0, 0.6, 0.15), Eigen::Vector3d(0.4, 0.4, 0.7)}) {
    const auto T = nbv::test::lookAt(position, {0.0, 0.0, 0.15});
    scans.push_back({nbv::test::idealScan(box, T, 4), position.cast<float>()});
  }
  crossCheck(scans);
}

TEST(OctomapCrossCheck, SphereThroughTheSparsePath) {
  const Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  nbv::grid::IntegrateOptions sparse;
  sparse.max_scratch_bytes = 0;
  crossCheck({sphereScan(sphere, {0.6, 0.0, 0.15}, 4), sphereScan(sphere, {0.0, 0.6, 0.35}, 4)}, {}, sparse);
}

TEST(OctomapCrossCheck, RandomPointsIncludingBeyondMaxRange) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coord(-2.5f, 2.5f);  // many beyond 1.5 m
  std::vector<Scan> scans;
  for (int s = 0; s < 4; ++s) {
    Scan scan{{}, {coord(rng) * 0.2f, coord(rng) * 0.2f, coord(rng) * 0.2f}};
    for (int i = 0; i < 3000; ++i) scan.points.emplace_back(coord(rng), coord(rng), coord(rng));
    scans.push_back(scan);
  }
  crossCheck(scans);
}

TEST(OctomapCrossCheck, ShortMaxRangeAndCoarseResolution) {
  OccupancyMap::Config config;
  config.resolution = 0.05;
  config.max_range = 0.5;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coord(-1.0f, 1.0f);
  Scan scan{{}, {0.01f, -0.02f, 0.03f}};
  for (int i = 0; i < 5000; ++i) scan.points.emplace_back(coord(rng), coord(rng), coord(rng));
  crossCheck({scan, scan}, config);
}

TEST(OctomapCrossCheck, PointsWithinAFewUlpsOfMaxRange) {
  // Hit or ray end at max_range: decided by |p - origin| <= max_range in OctoMap's precision.
  std::mt19937 rng(13);
  std::normal_distribution<float> gauss;
  const Eigen::Vector3f origin(0.013f, -0.021f, 0.05f);
  for (double max_range : {1.5, 0.37, 2.0, 0.3, 0.31}) {
    OccupancyMap::Config config;
    config.max_range = max_range;
    Scan scan{{}, origin};
    for (int i = 0; i < 400; ++i) {
      const Eigen::Vector3f direction = Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng)).normalized();
      float r = static_cast<float>(max_range);
      for (int k = 0; k < 3; ++k) r = std::nextafter(r, 0.0f);
      for (int k = -3; k <= 3; ++k, r = std::nextafter(r, 10.0f)) scan.points.push_back(origin + direction * r);
    }
    // From (0, 0, 0): r along an axis plus a small b along the next one, so that the squared
    // lengths r * r + b * b sweep every float near max_range^2, the boundary value included
    // (a hit; rounding max_range^2 to float is not always that value).
    Scan axes{{}, Eigen::Vector3f::Zero()};
    float r = static_cast<float>(max_range);
    for (int k = 0; k < 3; ++k) r = std::nextafter(r, 0.0f);
    for (int k = -3; k <= 3; ++k, r = std::nextafter(r, 10.0f)) {
      for (int a = 0; a < 3; ++a) {
        for (int j = 0; j < 24; ++j) {
          const Eigen::Vector3f side = Eigen::Vector3f::Unit((a + 1) % 3) * (2e-5f * static_cast<float>(j));
          axes.points.push_back(Eigen::Vector3f::Unit(a) * r + side);
          axes.points.push_back(-Eigen::Vector3f::Unit(a) * r - side);
        }
      }
    }
    crossCheck({scan, axes}, config);
  }
}

TEST(OctomapCrossCheck, ManyPointsInOneVoxel) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> jitter(0.0f, 0.0099f);
  Scan scan{{}, {0.0f, 0.0f, 0.0f}};
  for (int i = 0; i < 500; ++i) scan.points.emplace_back(0.30f + jitter(rng), 0.20f + jitter(rng), 0.10f + jitter(rng));
  crossCheck({scan, scan, scan});
}

TEST(OctomapCrossCheck, RaysAlongAxesAndThroughVoxelCorners) {
  Scan axes{{}, {0.005f, 0.005f, 0.005f}};
  for (int d = 1; d <= 40; ++d) {
    const float t = 0.01f * static_cast<float>(d) + 0.005f;
    axes.points.emplace_back(t, 0.005f, 0.005f);
    axes.points.emplace_back(0.005f, -t, 0.005f);
    axes.points.emplace_back(0.005f, 0.005f, t);
  }
  Scan corners{{}, {0.0f, 0.0f, 0.0f}};  // origin on a voxel corner
  for (int i = -8; i <= 8; ++i) {
    for (int j = -8; j <= 8; ++j) {
      corners.points.emplace_back(0.02f * static_cast<float>(i), 0.02f * static_cast<float>(j), 0.3f);
      corners.points.emplace_back(0.3f, 0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j));
    }
  }
  crossCheck({axes, corners});
}

TEST(OctomapCrossCheck, OriginInsideTheObject) {
  const Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  // From inside the sphere every ray hits its inner surface.
  crossCheck({sphereScan(sphere, {0.05, 0.02, 0.2}, 5), sphereScan(sphere, {0.6, 0.0, 0.15}, 5),
              sphereScan(sphere, {-0.1, 0.0, 0.3}, 5)});
}

}  // namespace
