#include "nbv/kernels/mark_rays.hpp"

#include "mark_rays_impl.hpp"

#include <stdexcept>

namespace nbv::kernels {

Isa bestIsa() {
#ifdef NBV_HAVE_AVX2
  if (__builtin_cpu_supports("avx2")) return Isa::Avx2;
#endif
  return Isa::Scalar;
}

const char* isaName(Isa isa) { return isa == Isa::Avx2 ? "avx2" : "scalar"; }

void markRays(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
              const OutsideSink& outside, Isa isa) {
  if (origins.size() != 1 && origins.size() != ends.size()) {
    throw std::invalid_argument("markRays: give one origin, or one per ray");
  }
  if (isa == Isa::Avx2) {
#ifdef NBV_HAVE_AVX2
    if (!__builtin_cpu_supports("avx2")) throw std::invalid_argument("this CPU has no AVX2");
    // The packet path converts offsets to 32-bit lanes.
    if (box.bytes() < (std::uint64_t{1} << 31)) {
      detail::markRaysAvx2(origins, ends, lattice, box, spec, outside);
      return;
    }
#else
    throw std::invalid_argument("nbv was built without AVX2 (NBV_ENABLE_AVX2=OFF)");
#endif
  }
  for (std::size_t i = 0; i < ends.size(); ++i) {
    if (spec.end_flags != nullptr) {
      std::size_t at = 0;
      const bool inside = box.locate(lattice.worldToIndex(ends[i]), at);
      detail::flagEnd(spec, inside, at);
    }
    detail::markRayScalar(origins[origins.size() == 1 ? 0 : i], ends[i], lattice, box, spec, outside);
  }
}

}  // namespace nbv::kernels
