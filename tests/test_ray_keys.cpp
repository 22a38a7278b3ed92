// The voxel sequence of a ray equals OctoMap's computeRayKeys, key for key (SPEC §1).
#include "nbv/kernels/ray_keys.hpp"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>
#include <vector>

namespace {

using nbv::kernels::Index3;
using nbv::kernels::VoxelLattice;

std::vector<Index3> ourKeys(const Eigen::Vector3f& a, const Eigen::Vector3f& b, double res) {
  std::vector<Index3> keys;
  nbv::kernels::traverseRayKeys(a, b, VoxelLattice(res), [&](const Index3& k) { keys.push_back(k); });
  return keys;
}

std::vector<Index3> octomapKeys(const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                octomap::OcTree& tree) {
  octomap::KeyRay ray;
  EXPECT_TRUE(tree.computeRayKeys(octomap::point3d(a.x(), a.y(), a.z()),
                                  octomap::point3d(b.x(), b.y(), b.z()), ray));
  std::vector<Index3> keys;
  for (const auto& k : ray) keys.emplace_back(k[0] - 32768, k[1] - 32768, k[2] - 32768);
  return keys;
}

void expectSameKeys(const Eigen::Vector3f& a, const Eigen::Vector3f& b, double res) {
  octomap::OcTree tree(res);
  const auto ours = ourKeys(a, b, res);
  const auto theirs = octomapKeys(a, b, tree);
  ASSERT_EQ(ours.size(), theirs.size()) << "ray " << a.transpose() << " -> " << b.transpose();
  for (std::size_t i = 0; i < ours.size(); ++i) {
    ASSERT_EQ(ours[i], theirs[i]) << "voxel " << i << " of ray " << a.transpose() << " -> "
                                  << b.transpose();
  }
}

TEST(RayKeys, ThreeVoxelsAlongX) {
  // From the centre of voxel 0 to the centre of voxel 3: voxels 0, 1, 2 (end excluded).
  const auto keys = ourKeys({0.005f, 0.005f, 0.005f}, {0.035f, 0.005f, 0.005f}, 0.01);
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[0], Index3(0, 0, 0));
  EXPECT_EQ(keys[1], Index3(1, 0, 0));
  EXPECT_EQ(keys[2], Index3(2, 0, 0));
}

TEST(RayKeys, SameVoxelGivesNothing) {
  EXPECT_TRUE(ourKeys({0.001f, 0.002f, 0.003f}, {0.009f, 0.008f, 0.007f}, 0.01).empty());
}

TEST(RayKeys, NegativeCoordinatesFloorDown) {
  const VoxelLattice lattice(0.01);
  EXPECT_EQ(lattice.worldToIndex(Eigen::Vector3f(-0.001f, 0.0f, 0.019f)), Index3(-1, 0, 1));
  EXPECT_DOUBLE_EQ(lattice.indexToWorld(-1), -0.005);
}

TEST(RayKeys, RandomRaysMatchOctomap) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-1.0f, 1.0f);
  for (int i = 0; i < 20000; ++i) {
    expectSameKeys({coord(rng), coord(rng), coord(rng)}, {coord(rng), coord(rng), coord(rng)}, 0.01);
  }
}

TEST(RayKeys, AxisRaysAndCornersMatchOctomap) {
  const double res = 0.01;
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> rays = {
      {{0.005f, 0.005f, 0.005f}, {0.505f, 0.005f, 0.005f}},    // along +x through centres
      {{0.005f, 0.005f, 0.005f}, {0.005f, -0.505f, 0.005f}},   // along -y
      {{0.005f, 0.005f, 0.005f}, {0.005f, 0.005f, 0.305f}},    // along +z
      {{0.0f, 0.0f, 0.0f}, {0.3f, 0.0f, 0.0f}},                // along an edge of voxels
      {{0.0f, 0.0f, 0.0f}, {0.3f, 0.3f, 0.3f}},                // through voxel corners
      {{0.0f, 0.0f, 0.0f}, {-0.2f, 0.2f, 0.0f}},               // face diagonal, corners
      {{0.01f, 0.02f, 0.03f}, {0.21f, 0.22f, 0.23f}},          // corners, offset
      {{-0.1f, -0.1f, -0.1f}, {0.1f, 0.1f, 0.1f}},             // crosses the origin corner
  };
  // Many rays from a voxel corner to other corners of the lattice.
  for (int i = -6; i <= 6; ++i) {
    for (int j = -6; j <= 6; ++j) {
      rays.push_back({{0.0f, 0.0f, 0.0f}, {0.05f * static_cast<float>(i), 0.05f * static_cast<float>(j), 0.1f}});
    }
  }
  for (const auto& [a, b] : rays) expectSameKeys(a, b, res);
}

TEST(RayKeys, OtherResolutionsMatchOctomap) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  for (double res : {0.05, 0.1, 0.0234, 0.2}) {
    for (int i = 0; i < 2000; ++i) {
      expectSameKeys({coord(rng), coord(rng), coord(rng)}, {coord(rng), coord(rng), coord(rng)}, res);
    }
  }
}

}  // namespace
