// LaneDda and the lane operations over the four lanes of simd_avx2.hpp, for test_lanes.cpp.
// Compiled with -mavx2.
#include "simd_avx2.hpp"
#include "lane_ops_check_impl.hpp"
#include "lanes_check_impl.hpp"

namespace nbv::test {

std::vector<LaneSetupRow> setupInLanesAvx2(const std::vector<Eigen::Vector3f>& origins,
                                           const std::vector<Eigen::Vector3f>& ends,
                                           const kernels::VoxelLattice& lattice) {
  return setupInLanes<kernels::detail::Avx2Lanes>(origins, ends, lattice);
}

LaneWalks walkInLanesAvx2(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                          const kernels::VoxelLattice& lattice, int max_steps) {
  return walkInLanes<kernels::detail::Avx2Lanes>(origins, ends, lattice, max_steps);
}

std::vector<std::string> laneOpsDifferAvx2(std::uint32_t seed, int rounds) {
  return LaneOpsCheck<kernels::detail::Avx2Lanes, OutsideLanes::SignOfZeroFree>(seed).run(rounds);
}

}  // namespace nbv::test
