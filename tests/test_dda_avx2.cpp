// setupRays4() sets up four rays with AVX2 and must give every field of setupRay(), bit for
// bit: the packet walks start from it, and one different bit in a border time can change
// which voxel a ray through a corner takes.
#include "dda_avx2.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <random>
#include <vector>

namespace {

using nbv::kernels::Index3;
using nbv::kernels::RaySetup;
using nbv::kernels::VoxelLattice;
using nbv::kernels::detail::RaySetups4;

/// Sets up rays 4 at a time and compares each lane with setupRay().
void expectSameAsSetupRay(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                          const VoxelLattice& lattice) {
  ASSERT_EQ(origins.size(), ends.size());
  ASSERT_EQ(ends.size() % 4, 0u);
  for (std::size_t first = 0; first < ends.size(); first += 4) {
    const Eigen::Vector3f* from[4];
    const Eigen::Vector3f* to[4];
    for (std::size_t j = 0; j < 4; ++j) {
      from[j] = &origins[first + j];
      to[j] = &ends[first + j];
    }
    RaySetups4 four;
    nbv::kernels::detail::setupRays4(from, to, lattice, four);
    for (int j = 0; j < 4; ++j) {
      SCOPED_TRACE(testing::Message() << "ray " << first + static_cast<std::size_t>(j));
      RaySetup one;
      const bool visits = nbv::kernels::setupRay(*from[j], *to[j], lattice, one);
      EXPECT_EQ(((four.same_voxel >> j) & 1u) == 0, visits);
      EXPECT_EQ(four.keyOrigin(j), one.key_origin);
      EXPECT_EQ(four.keyEnd(j), one.key_end);
      if (!visits) continue;
      EXPECT_EQ(std::bit_cast<std::uint64_t>(four.length[j]), std::bit_cast<std::uint64_t>(one.length));
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(four.step[a][j], one.step[a]) << "axis " << a;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(four.t_max[a][j]), std::bit_cast<std::uint64_t>(one.t_max[a]))
            << "axis " << a << ": " << four.t_max[a][j] << " vs " << one.t_max[a];
        EXPECT_EQ(std::bit_cast<std::uint64_t>(four.t_delta[a][j]), std::bit_cast<std::uint64_t>(one.t_delta[a]))
            << "axis " << a;
      }
    }
  }
}

bool haveAvx2() { return __builtin_cpu_supports("avx2"); }

TEST(SetupRays4, RandomRaysGiveSetupRaysBits) {
  if (!haveAvx2()) GTEST_SKIP() << "no AVX2 on this CPU";
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f), near(-0.05f, 0.05f);
  for (double resolution : {0.01, 0.05, 0.1, 0.3}) {
    std::vector<Eigen::Vector3f> origins, ends;
    for (int i = 0; i < 4000; ++i) {
      origins.emplace_back(coord(rng), coord(rng), coord(rng));
      // Long and short rays, the short ones often within one voxel.
      const Eigen::Vector3f offset = i % 3 == 0 ? Eigen::Vector3f(near(rng), near(rng), near(rng))
                                                : Eigen::Vector3f(coord(rng), coord(rng), coord(rng));
      ends.push_back(origins.back() + offset);
    }
    expectSameAsSetupRay(origins, ends, VoxelLattice(resolution));
  }
}

TEST(SetupRays4, AxesCornersZeroComponentsAndNegativeCoordinates) {
  if (!haveAvx2()) GTEST_SKIP() << "no AVX2 on this CPU";
  std::vector<Eigen::Vector3f> origins, ends;
  const Eigen::Vector3f corner(0.0f, 0.0f, 0.0f), inside(0.013f, -0.027f, 0.005f), negative(-0.31f, -0.02f, -1.7f);
  for (const Eigen::Vector3f& origin : {corner, inside, negative}) {
    for (int i = -2; i <= 2; ++i) {
      for (int j = -2; j <= 2; ++j) {
        for (int k = -2; k <= 2; ++k) {  // along axes, face and space diagonals, and itself
          origins.push_back(origin);
          ends.push_back(origin + 0.07f * Eigen::Vector3f(static_cast<float>(i), static_cast<float>(j),
                                                          static_cast<float>(k)));
        }
      }
    }
  }
  while (ends.size() % 4 != 0) {
    origins.push_back(corner);
    ends.emplace_back(0.0f, 0.0f, -0.3f);
  }
  expectSameAsSetupRay(origins, ends, VoxelLattice(0.01));
}

}  // namespace
