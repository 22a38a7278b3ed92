// The private lane code of the packet walks, at each lane width. LaneDda
// (kernels/src/dda_lanes.hpp), the DDA every packet walk runs: its set-up must give every
// field of setupRay() bit for bit (one different bit in a border time can change which voxel a
// ray through a corner takes), and its steps the voxels of traverseRayKeys(), the scalar
// oracle. The lane operations (simd_avx2.hpp, simd_avx512.hpp): each the instruction
// simd_emulated.hpp describes in plain C++, which the NBV_EMULATE_AVX512 build runs the
// 8-lane walks over on a CPU without AVX-512.
#include "lanes_check.hpp"

#include "nbv/kernels/isa.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace {

using nbv::kernels::Index3;
using nbv::kernels::Isa;
using nbv::kernels::RaySetup;
using nbv::kernels::VoxelLattice;
using nbv::test::LaneSetupRow;
using nbv::test::LaneWalks;

using Rays = std::vector<Eigen::Vector3f>;

/// A lane width this build has: its name, instruction set, width and entry points.
struct Width {
  std::string name;
  Isa isa;
  std::size_t lanes;
  std::function<std::vector<LaneSetupRow>(const Rays&, const Rays&, const VoxelLattice&)> setup;
  std::function<LaneWalks(const Rays&, const Rays&, const VoxelLattice&, int)> walk;
};

/// The lane widths this build has and this CPU runs (AVX-512 may be built and not run here).
std::vector<Width> availableWidths() {
  std::vector<Width> w = {{"avx2", Isa::Avx2, 4, nbv::test::setupInLanesAvx2, nbv::test::walkInLanesAvx2}};
#ifdef NBV_TEST_AVX512
  w.push_back({"avx512", Isa::Avx512, 8, nbv::test::setupInLanesAvx512, nbv::test::walkInLanesAvx512});
#endif
  std::erase_if(w, [](const Width& width) { return !nbv::kernels::isaAvailable(width.isa); });
  return w;
}

std::uint64_t bitsOf(double x) { return std::bit_cast<std::uint64_t>(x); }

/// Pads the rays to a multiple of 8 lanes with copies of the last one.
void pad(Rays& origins, Rays& ends) {
  while (ends.size() % 8 != 0) {
    origins.push_back(origins.back());
    ends.push_back(ends.back());
  }
}

/// Random rays: long ones, and short ones that often stay in one voxel.
void randomRays(std::uint32_t seed, Rays& origins, Rays& ends) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f), near(-0.05f, 0.05f);
  for (int i = 0; i < 4000; ++i) {
    origins.emplace_back(coord(rng), coord(rng), coord(rng));
    const Eigen::Vector3f offset = i % 3 == 0 ? Eigen::Vector3f(near(rng), near(rng), near(rng))
                                              : Eigen::Vector3f(coord(rng), coord(rng), coord(rng));
    ends.push_back(origins.back() + offset);
  }
  pad(origins, ends);
}

/// Rays along the axes, face and space diagonals, and of zero length, from a voxel corner, a
/// voxel's inside and negative coordinates.
void specialRays(Rays& origins, Rays& ends) {
  const Eigen::Vector3f corner(0.0f, 0.0f, 0.0f), inside(0.013f, -0.027f, 0.005f), negative(-0.31f, -0.02f, -1.7f);
  for (const Eigen::Vector3f& origin : {corner, inside, negative}) {
    for (int i = -2; i <= 2; ++i) {
      for (int j = -2; j <= 2; ++j) {
        for (int k = -2; k <= 2; ++k) {
          origins.push_back(origin);
          ends.push_back(origin + 0.07f * Eigen::Vector3f(static_cast<float>(i), static_cast<float>(j),
                                                          static_cast<float>(k)));
        }
      }
    }
  }
  pad(origins, ends);
}

void expectSetupRayBits(const Width& width, const Rays& origins, const Rays& ends, const VoxelLattice& lattice) {
  const std::vector<LaneSetupRow> rows = width.setup(origins, ends, lattice);
  ASSERT_EQ(rows.size(), ends.size());
  for (std::size_t i = 0; i < ends.size(); ++i) {
    SCOPED_TRACE(testing::Message() << width.name << ", ray " << i);
    RaySetup one;
    const bool visits = nbv::kernels::setupRay(origins[i], ends[i], lattice, one);
    const LaneSetupRow& lane = rows[i];
    ASSERT_EQ(!lane.same_voxel, visits);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(lane.key_origin[a], one.key_origin[a]) << "axis " << a;
      EXPECT_EQ(lane.key_end[a], one.key_end[a]) << "axis " << a;
    }
    if (!visits) continue;
    EXPECT_EQ(bitsOf(lane.length), bitsOf(one.length));
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(lane.step[a], one.step[a]) << "axis " << a;
      EXPECT_EQ(bitsOf(lane.t_max[a]), bitsOf(one.t_max[a])) << "axis " << a << ": " << lane.t_max[a] << " vs "
                                                             << one.t_max[a];
      EXPECT_EQ(bitsOf(lane.t_delta[a]), bitsOf(one.t_delta[a])) << "axis " << a;
    }
  }
}

void expectTraverseRayKeysVoxels(const Width& width, const Rays& origins, const Rays& ends,
                                 const VoxelLattice& lattice) {
  const LaneWalks walks = width.walk(origins, ends, lattice, 2000);
  ASSERT_EQ(walks.size(), ends.size());
  for (std::size_t i = 0; i < ends.size(); ++i) {
    std::vector<Index3> oracle;
    nbv::kernels::traverseRayKeys(origins[i], ends[i], lattice, [&](const Index3& ijk) { oracle.push_back(ijk); });
    ASSERT_EQ(walks[i], oracle) << width.name << ", ray " << i << " of " << ends.size();
  }
}

TEST(LaneDda, SetupGivesSetupRaysBitsAtEveryWidth) {
  if (!nbv::kernels::isaAvailable(Isa::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU";
  Rays origins, ends, special_origins, special_ends;
  randomRays(31, origins, ends);
  specialRays(special_origins, special_ends);
  for (const Width& width : availableWidths()) {
    for (double resolution : {0.01, 0.05, 0.1, 0.3}) expectSetupRayBits(width, origins, ends, VoxelLattice(resolution));
    expectSetupRayBits(width, special_origins, special_ends, VoxelLattice(0.01));
  }
}

TEST(LaneDda, StepsVisitTraverseRayKeysVoxelsAtEveryWidth) {
  if (!nbv::kernels::isaAvailable(Isa::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU";
  Rays origins, ends, special_origins, special_ends;
  randomRays(7, origins, ends);
  specialRays(special_origins, special_ends);
  for (const Width& width : availableWidths()) {
    for (double resolution : {0.05, 0.3}) {  // at most 2000 voxels per ray
      expectTraverseRayKeysVoxels(width, origins, ends, VoxelLattice(resolution));
    }
    expectTraverseRayKeysVoxels(width, special_origins, special_ends, VoxelLattice(0.01));
  }
}

/// No operation differs; else the count and the first difference.
void expectSameOperations(const std::vector<std::string>& differences) {
  EXPECT_TRUE(differences.empty()) << differences.size() << " differences, the first: "
                                   << (differences.empty() ? "" : differences.front());
}

TEST(LaneOps, Avx2OperationsAreTheEmulatedInstructions) {
  if (!nbv::kernels::isaAvailable(Isa::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU";
  expectSameOperations(nbv::test::laneOpsDifferAvx2(5, 4000));
}

TEST(LaneOps, Avx512OperationsAreTheEmulatedInstructions) {
#ifdef NBV_TEST_AVX512
  if (nbv::kernels::isaEmulated(Isa::Avx512)) GTEST_SKIP() << "this build's avx512 lanes are the emulation itself";
  if (!nbv::kernels::isaAvailable(Isa::Avx512)) GTEST_SKIP() << "no AVX-512 on this CPU";
  expectSameOperations(nbv::test::laneOpsDifferAvx512(5, 4000));
#else
  GTEST_SKIP() << "built without the AVX-512 loops";
#endif
}

}  // namespace
