// The voxel sequence of a ray equals OctoMap's computeRayKeys, key for key (SEMANTICS.md "The map").
#include "nbv/kernels/ray_keys.hpp"

#include "../kernels/src/ig_rays_impl.hpp"  // white box: skipToBox

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

// White box (kernels/src/ig_rays_impl.hpp): the IG walk skips a ray's steps before the
// snapshot box with per-axis sums; where it does, the voxel, the border times and the step
// count must equal the walk's, bit for bit. Origins on voxel corners and axis or diagonal
// directions make the ties it must leave to the walk.
TEST(RayKeys, SkippingToTheSnapshotBoxEqualsWalkingThere) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> corner(-40, 40), box_min(-8, 4), box_size(1, 12), kind(0, 3);
  int skipped = 0, walked = 0;  // rays that reach the box from outside, skipped or walked
  for (const double res : {0.05, 0.01, 0.125}) {
    const VoxelLattice lattice(res);
    for (int i = 0; i < 20000; ++i) {
      nbv::kernels::SnapshotView view;
      for (int a = 0; a < 3; ++a) {
        view.min[a] = box_min(rng);
        view.size[a] = static_cast<std::uint32_t>(box_size(rng));
      }
      Eigen::Vector3f origin(static_cast<float>(corner(rng)), static_cast<float>(corner(rng)),
                             static_cast<float>(corner(rng)));
      origin *= static_cast<float>(res);
      if (kind(rng) != 0) origin += Eigen::Vector3f(unit(rng), unit(rng), unit(rng)) * static_cast<float>(res);
      // Mostly towards a point of the box, so that most rays reach it.
      Eigen::Vector3f direction(unit(rng), unit(rng), unit(rng));
      for (int a = 0; a < 3; ++a) {
        direction[a] += static_cast<float>((view.min[a] + 0.5 * view.size[a]) * res) - origin[a];
      }
      switch (kind(rng)) {
        case 0: direction = Eigen::Vector3f::Unit(i % 3) * (i % 2 == 0 ? 1.0f : -1.0f); break;
        case 1: direction = Eigen::Vector3f(1.0f, i % 2 == 0 ? 1.0f : -1.0f, 1.0f); break;
        default: break;
      }
      if (direction.norm() < 1e-3f) continue;
      const Eigen::Vector3f end = origin + direction.normalized() * static_cast<float>(res * (5 + i % 120));
      nbv::kernels::RaySetup s;
      if (!nbv::kernels::setupRay(origin, end, lattice, s)) continue;
      Index3 ijk;
      double t_max[3];
      std::uint32_t steps = 0;
      if (!nbv::kernels::detail::skipToBox(s, view, ijk, t_max, steps)) {
        nbv::kernels::RayWalk walk(s);
        bool reaches = !view.contains(walk.ijk);
        while (reaches && !view.contains(walk.ijk)) reaches = walk.next();
        walked += reaches ? 1 : 0;  // a ray that reaches the box from outside, walked
        continue;
      }
      ++skipped;
      nbv::kernels::RayWalk walk(s);
      std::uint32_t before = 0;
      while (!view.contains(walk.ijk)) {
        ++before;
        ASSERT_TRUE(walk.next()) << "the walk ends before the box; ray " << origin.transpose() << " -> " << end.transpose();
      }
      ASSERT_EQ(walk.ijk, ijk) << "ray " << origin.transpose() << " -> " << end.transpose();
      ASSERT_EQ(before, steps);
      for (int a = 0; a < 3; ++a) ASSERT_EQ(walk.t_max[a], t_max[a]);
    }
  }
  // The walk of fuzz_integrate_evaluate's ray (5 cm, from the corner (0, 0, 0) along +z over
  // 1.5 m) stops on the step into voxel 29, its sums having passed the length: with the box
  // starting there, the walk never enters it, so the skip must not either.
  const VoxelLattice lattice(0.05);
  nbv::kernels::RaySetup s;
  ASSERT_TRUE(nbv::kernels::setupRay(Eigen::Vector3f::Zero(), Eigen::Vector3f(0.0f, 0.0f, 1.5f), lattice, s));
  nbv::kernels::SnapshotView view;
  view.min[2] = 29;
  view.size[0] = view.size[1] = view.size[2] = 4;
  Index3 ijk;
  double t_max[3];
  std::uint32_t steps = 0;
  EXPECT_FALSE(nbv::kernels::detail::skipToBox(s, view, ijk, t_max, steps));
  view.min[2] = 28;  // one voxel earlier the walk does enter, after 28 steps
  ASSERT_TRUE(nbv::kernels::detail::skipToBox(s, view, ijk, t_max, steps));
  EXPECT_EQ(ijk, Index3(0, 0, 28));
  EXPECT_EQ(steps, 28u);

  EXPECT_GT(skipped, 2000);  // of the rays that reach the box from outside, nearly all
  EXPECT_GT(walked, 0);      // and ties that are left to the walk
}
