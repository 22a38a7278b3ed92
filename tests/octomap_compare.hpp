#pragma once
// Comparison of an OccupancyMap with a liboctomap OcTree, voxel by voxel.

#include "nbv/grid/occupancy_map.hpp"
#include "octomap_like_map.hpp"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <map>
#include <tuple>

namespace nbv::test {

/// Every voxel of `tree` (pruned leaves expanded) keyed by nbv index.
inline std::map<std::tuple<int, int, int>, float> treeVoxels(const octomap::OcTree& tree) {
  std::map<std::tuple<int, int, int>, float> voxels;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey base = it.getIndexKey();
    const int side = 1 << (16 - static_cast<int>(it.getDepth()));
    for (int dx = 0; dx < side; ++dx)
      for (int dy = 0; dy < side; ++dy)
        for (int dz = 0; dz < side; ++dz)
          voxels[{base[0] - 32768 + dx, base[1] - 32768 + dy, base[2] - 32768 + dz}] = it->getLogOdds();
  }
  return voxels;
}

/// Same set of measured voxels, and |log-odds difference| < tolerance at every one.
inline void expectMapEqualsTree(const grid::OccupancyMap& map, const octomap::OcTree& tree,
                                double tolerance) {
  const auto expected = treeVoxels(tree);
  const auto actual = map.measuredVoxels();
  ASSERT_EQ(actual.size(), expected.size()) << "measured voxel count differs from OctoMap";
  ASSERT_GT(actual.size(), 0u);
  for (const auto& voxel : actual) {
    const auto it = expected.find({voxel.ijk.x(), voxel.ijk.y(), voxel.ijk.z()});
    ASSERT_NE(it, expected.end()) << "voxel " << voxel.ijk.transpose() << " not in OctoMap";
    ASSERT_NEAR(voxel.log_odds, it->second, tolerance) << "voxel " << voxel.ijk.transpose();
  }
}

}  // namespace nbv::test
