#include "nbv/kernels/mark_rays.hpp"

#include "mark_rays_impl.hpp"

#include <atomic>
#include <stdexcept>

namespace nbv::kernels {

Isa bestIsa() {
#ifdef NBV_HAVE_AVX2
  if (__builtin_cpu_supports("avx2")) return Isa::Avx2;
#endif
  return Isa::Scalar;
}

const char* isaName(Isa isa) { return isa == Isa::Avx2 ? "avx2" : "scalar"; }

void markRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const DenseBox& box, std::uint8_t value,
              const OutsideSink& outside, Isa isa) {
  if (isa == Isa::Avx2) {
#ifdef NBV_HAVE_AVX2
    if (!__builtin_cpu_supports("avx2")) throw std::invalid_argument("this CPU has no AVX2");
    // The packet path converts offsets to 32-bit lanes.
    if (box.bytes() < (std::uint64_t{1} << 31)) {
      detail::markRaysAvx2(origin, ends, lattice, box, value, outside);
      return;
    }
#else
    throw std::invalid_argument("nbv was built without AVX2 (NBV_ENABLE_AVX2=OFF)");
#endif
  }
  for (const Eigen::Vector3f& end : ends) {
    traverseRayKeys(origin, end, lattice, [&](const Index3& ijk) {
      std::size_t at;
      if (box.locate(ijk, at)) {
        std::atomic_ref<std::uint8_t>(box.data[at]).store(value, std::memory_order_relaxed);
      } else {
        outside(ijk);
      }
    });
  }
}

}  // namespace nbv::kernels
