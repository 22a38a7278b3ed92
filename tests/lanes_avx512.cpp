// LaneDda and the lane operations over the eight lanes of simd_avx512.hpp, for test_lanes.cpp.
// Compiled with -mavx2, its own functions for AVX-512 (avx512_target_begin.hpp, after every
// shared header).
#include "lanes_check.hpp"

#include <immintrin.h>

#include "avx512_target_begin.hpp"

#include "simd_avx512.hpp"
#include "lane_ops_check_impl.hpp"
#include "lanes_check_impl.hpp"

namespace nbv::test {

std::vector<LaneSetupRow> setupInLanesAvx512(const std::vector<Eigen::Vector3f>& origins,
                                             const std::vector<Eigen::Vector3f>& ends,
                                             const kernels::VoxelLattice& lattice) {
  return setupInLanes<kernels::detail::Avx512Lanes>(origins, ends, lattice);
}

LaneWalks walkInLanesAvx512(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                            const kernels::VoxelLattice& lattice, int max_steps) {
  return walkInLanes<kernels::detail::Avx512Lanes>(origins, ends, lattice, max_steps);
}

std::vector<std::string> laneOpsDifferAvx512(std::uint32_t seed, int rounds) {
  return LaneOpsCheck<kernels::detail::Avx512Lanes, OutsideLanes::Exact>(seed).run(rounds);
}

}  // namespace nbv::test

#include "avx512_target_end.hpp"
