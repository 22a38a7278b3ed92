#pragma once
// Private to the tests: the private lane code of the kernels at one lane width, its results in
// plain types. LaneDda (kernels/src/dda_lanes.hpp) run over whole rays, for comparison with
// setupRay() and traverseRayKeys() (lanes_check_impl.hpp), and the lane operations against
// their plain C++ emulation (lane_ops_check_impl.hpp). lanes_avx2.cpp and lanes_avx512.cpp
// instantiate them.

#include "nbv/kernels/ray_keys.hpp"

// Every standard header of lanes_check_impl.hpp, lane_ops_check_impl.hpp and
// simd_emulated.hpp, here so that lanes_avx512.cpp parses them before its AVX-512 region: a
// standard template defined inside it (std::mt19937's members, say) would be compiled for
// AVX-512, and the linker may keep that copy for every caller in the test binary.
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace nbv::test {

/// One lane of LaneDda::setup(), integers as doubles.
struct LaneSetupRow {
  bool same_voxel = false;
  double key_origin[3] = {}, key_end[3] = {}, step[3] = {}, t_max[3] = {}, t_delta[3] = {}, length = 0.0;
};

/// The voxels LaneDda visits for each ray (the origin's first; none when both points share a
/// voxel), stepping the rays a packet at a time. A walk longer than `max_steps` stops there.
using LaneWalks = std::vector<std::vector<kernels::Index3>>;

/// For the lane widths of simd_avx2.hpp and simd_avx512.hpp (call where isaAvailable()).
std::vector<LaneSetupRow> setupInLanesAvx2(const std::vector<Eigen::Vector3f>& origins,
                                           const std::vector<Eigen::Vector3f>& ends,
                                           const kernels::VoxelLattice& lattice);
LaneWalks walkInLanesAvx2(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                          const kernels::VoxelLattice& lattice, int max_steps);
std::vector<LaneSetupRow> setupInLanesAvx512(const std::vector<Eigen::Vector3f>& origins,
                                             const std::vector<Eigen::Vector3f>& ends,
                                             const kernels::VoxelLattice& lattice);
LaneWalks walkInLanesAvx512(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                            const kernels::VoxelLattice& lattice, int max_steps);

/// Every operation of simd_avx2.hpp (simd_avx512.hpp) against simd_emulated.hpp's lanes of
/// its width, over `rounds` random draws from `seed`: one line per operation and lane that
/// differs (call where isaAvailable()).
std::vector<std::string> laneOpsDifferAvx2(std::uint32_t seed, int rounds);
std::vector<std::string> laneOpsDifferAvx512(std::uint32_t seed, int rounds);

}  // namespace nbv::test
