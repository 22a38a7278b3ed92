// The AVX2 packet walk of markRays(): mark_rays_packet.hpp's walk over four rays in the lanes
// of __m256d (simd_avx2.hpp). Compiled with -mavx2 (this file only); reached through
// markRays() after a CPU check.
#include "mark_rays_impl.hpp"
#include "simd_avx2.hpp"
#include "mark_rays_packet.hpp"

namespace nbv::kernels::detail {

void markRaysAvx2(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                  const OutsideSink& outside) {
  markRaysPackets<Avx2Lanes>(origins, ends, lattice, box, spec, outside);
}

}  // namespace nbv::kernels::detail
