#include "nbv/kernels/ig_rays.hpp"

#include "ig_rays_impl.hpp"

#include <stdexcept>

namespace nbv::kernels {

void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out) {
  if (out.size() != ends.size()) throw std::invalid_argument("walkRays: one output per ray");
  if (view.palette.empty()) throw std::invalid_argument("walkRays: the snapshot has no palette");
  if (isa == Isa::Avx2) {
#ifdef NBV_HAVE_AVX2
    if (!__builtin_cpu_supports("avx2")) throw std::invalid_argument("this CPU has no AVX2");
    if (static_cast<double>(view.size[0]) * view.size[1] * view.size[2] < 2147483648.0) {
      detail::walkRaysAvx2(origin, ends, lattice, view, out);
      return;
    }
#else
    throw std::invalid_argument("nbv was built without AVX2 (NBV_ENABLE_AVX2=OFF)");
#endif
  }
  for (std::size_t i = 0; i < ends.size(); ++i) out[i] = detail::walkRayScalar(origin, ends[i], lattice, view);
}

}  // namespace nbv::kernels
