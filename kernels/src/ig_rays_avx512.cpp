// The AVX-512 packet walk of the IG rays: ig_rays_packet.hpp's walk over eight rays in the
// lanes of __m512d (simd_avx512.hpp). As in mark_rays_avx512.cpp, this file is compiled with
// -mavx2 and only the walk's own code, included inside the target pragma below, for AVX-512;
// the inline functions it shares with the other sources (ig_rays_impl.hpp, Eigen) are
// included before it and compiled as there. Reached through walkRays() after a CPU check.
#include "ig_rays_impl.hpp"

#include <immintrin.h>

#include "avx512_target_begin.hpp"

#include "simd_avx512.hpp"
#include "ig_rays_packet.hpp"

namespace nbv::kernels::detail {

void walkRaysAvx512(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                    const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out,
                    std::span<RayCounts> counts) {
  walkPackets<Avx512Lanes>(origin, ends, lattice, view, out, counts);
}

}  // namespace nbv::kernels::detail

#include "avx512_target_end.hpp"
