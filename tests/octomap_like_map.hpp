#pragma once
// A liboctomap occupancy tree given an OccupancyMap's sensor model, so that the same scans give both
// the same voxels (the cross-check tests, the benchmarks against liboctomap).

#include "nbv/grid/occupancy_map.hpp"

#include <octomap/OcTree.h>

namespace nbv::test {

/// Any of liboctomap's occupancy trees (OcTree, ColorOcTree, OcTreeStamped).
inline void configureLikeMap(octomap::AbstractOccupancyOcTree& tree, const grid::OccupancyMap::Config& c) {
  tree.setProbHit(c.p_hit);
  tree.setProbMiss(c.p_miss);
  tree.setClampingThresMin(c.clamp_min);
  tree.setClampingThresMax(c.clamp_max);
}

}  // namespace nbv::test
