#include "nbv/kernels/ig_rays.hpp"

#include "ig_rays_impl.hpp"
#include "isa_dispatch.hpp"

#include "nbv/errors.hpp"

namespace nbv::kernels {

void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out) {
  if (out.size() != ends.size()) throw InvalidArgument("walkRays: one output per ray");
  if (view.palette.empty()) throw InvalidArgument("walkRays: the snapshot has no palette");
  // The packet walks carry offsets in 32-bit lanes.
  const bool packets_fit = static_cast<double>(view.size[0]) * view.size[1] * view.size[2] < 2147483648.0;
  detail::dispatch(
      isa, packets_fit, [&] { detail::walkRaysAvx512(origin, ends, lattice, view, out); },
      [&] { detail::walkRaysAvx2(origin, ends, lattice, view, out); },
      [&] {
        for (std::size_t i = 0; i < ends.size(); ++i) out[i] = detail::walkRayScalar(origin, ends[i], lattice, view);
      });
}

}  // namespace nbv::kernels
