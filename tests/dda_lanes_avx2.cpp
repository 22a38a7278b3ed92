// LaneDda over the four lanes of simd_avx2.hpp, for test_dda_lanes.cpp. Compiled with -mavx2.
#include "simd_avx2.hpp"
#include "dda_lanes_check_impl.hpp"

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

}  // namespace nbv::test
