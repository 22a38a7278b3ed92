#pragma once
// Private: the instruction-set variants behind markRays().

#include "nbv/kernels/mark_rays.hpp"

namespace nbv::kernels::detail {

#ifdef NBV_HAVE_AVX2
/// AVX2 packet walk of four rays at a time; box.bytes() must be below 2^31.
void markRaysAvx2(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const DenseBox& box, std::uint8_t value,
                  const OutsideSink& outside);
#endif

}  // namespace nbv::kernels::detail
