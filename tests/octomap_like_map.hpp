#pragma once
// A liboctomap OcTree given an OccupancyMap's sensor model, so that the same scans give both
// the same voxels (the cross-check tests, the benchmarks against liboctomap).

#include "nbv/grid/occupancy_map.hpp"

#include <octomap/OcTree.h>

namespace nbv::test {

inline void configureLikeMap(octomap::OcTree& tree, const grid::OccupancyMap::Config& c) {
  tree.setProbHit(c.p_hit);
  tree.setProbMiss(c.p_miss);
  tree.setClampingThresMin(c.clamp_min);
  tree.setClampingThresMax(c.clamp_max);
}

}  // namespace nbv::test
