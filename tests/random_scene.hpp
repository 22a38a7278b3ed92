#pragma once
// A random map of the tests (the IG evaluators against each other, anytime decisions against
// the exhaustive argmax): random voxel states and marks in a 0.4 m cube, views in and around it.

#include "nbv/grid/occupancy_map.hpp"

#include <Eigen/Geometry>

#include <random>
#include <vector>

namespace nbv::test {

/// A random map of 1 cm voxels in a 0.4 m cube with random states, marks among the
/// unmeasured, and views around it (some inside the cube, some outside the snapshot).
struct RandomScene {
  grid::OccupancyMap map;
  std::vector<Eigen::Isometry3d> views;
  std::vector<Eigen::Vector3d> directions;
};

inline RandomScene randomScene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coord(-20, 19);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  RandomScene s{grid::OccupancyMap(grid::MapConfig{}), {}, {}};
  auto logOdds = [](double p) { return grid::OccupancyMap::logOddsOf(p); };
  const float levels[] = {logOdds(0.12), logOdds(0.3), logOdds(0.45), logOdds(0.55), logOdds(0.7), logOdds(0.97),
                          logOdds(0.4), logOdds(0.85)};
  for (int i = 0; i < 6000; ++i) {
    const grid::Index3 ijk(coord(rng), coord(rng), coord(rng));
    // Mostly free or unknown so that rays travel: 1 in 8 stops a ray.
    const int level = unit(rng) < 0.85 ? (unit(rng) < 0.5 ? 0 : (unit(rng) < 0.5 ? 1 : 2)) : 3 + static_cast<int>(unit(rng) * 5) % 5;
    s.map.setLogOdds(ijk, levels[level]);
  }
  for (int i = 0; i < 3000; ++i) {
    const grid::Index3 ijk(coord(rng), coord(rng), coord(rng));
    if (!s.map.isMeasured(ijk)) s.map.setProximity(ijk, 1 + static_cast<int>(unit(rng) * 59));
  }
  for (int v = 0; v < 6; ++v) {
    // Half the views inside the cube, half outside it, looking at random points.
    const double r = v % 2 == 0 ? 0.1 : 0.6;
    Eigen::Vector3d p(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    p = p.normalized() * r;
    const Eigen::Vector3d z = (Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.2 - p).normalized();
    const Eigen::Vector3d x = z.unitOrthogonal();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() << x, z.cross(x), z;
    T.translation() = p;
    s.views.push_back(T);
  }
  for (int i = 0; i < 400; ++i) {
    s.directions.push_back(Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, 1.0).normalized());
  }
  // Edge directions: along the camera axes and diagonals through voxel corners.
  s.directions.push_back(Eigen::Vector3d::UnitZ());
  s.directions.push_back(Eigen::Vector3d(1, 1, 1).normalized());
  s.directions.push_back(Eigen::Vector3d(-1, 1, 1).normalized());
  return s;
}

}  // namespace nbv::test
