// The AVX-512 packet walk of markRays(): mark_rays_packet.hpp's walk over eight rays in the
// lanes of __m512d (simd_avx512.hpp). This file is compiled with -mavx2, and only the walk's
// own code, included inside the target pragma below, for AVX-512: the inline functions it
// shares with the scalar and AVX2 sources (mark_rays_impl.hpp, ray_keys.hpp, Eigen) are
// included before it and compiled as there, so whichever copy the linker keeps runs on a CPU
// without AVX-512. Reached through markRays() after a CPU check.
#include "mark_rays_impl.hpp"

#include <immintrin.h>

#include "avx512_target_begin.hpp"

#include "simd_avx512.hpp"
#include "mark_rays_packet.hpp"

namespace nbv::kernels::detail {

void markRaysAvx512(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                    const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                    const OutsideSink& outside) {
  markRaysPackets<Avx512Lanes>(origins, ends, lattice, box, spec, outside);
}

}  // namespace nbv::kernels::detail

#include "avx512_target_end.hpp"
