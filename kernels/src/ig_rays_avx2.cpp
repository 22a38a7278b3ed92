// The AVX2 packet walk of the IG rays: ig_rays_packet.hpp's walk over four rays in the lanes
// of __m256d (simd_avx2.hpp). Compiled with -mavx2 (this file only); reached through
// walkRays() after a CPU check.
#include "ig_rays_impl.hpp"
#include "simd_avx2.hpp"
#include "ig_rays_packet.hpp"

namespace nbv::kernels::detail {

void walkRaysAvx2(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out,
                  std::span<RayCounts> counts) {
  walkPackets<Avx2Lanes>(origin, ends, lattice, view, out, counts);
}

}  // namespace nbv::kernels::detail
