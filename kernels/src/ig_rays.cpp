#include "nbv/kernels/ig_rays.hpp"

#include "ig_rays_impl.hpp"
#include "isa_dispatch.hpp"

#include "nbv/errors.hpp"

namespace nbv::kernels {

void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out) {
  walkRays(origin, ends, lattice, view, isa, out, std::span<RayCounts>{});
}

void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out, std::span<RayCounts> counts) {
  if (out.size() != ends.size()) throw InvalidArgument("walkRays: one output per ray");
  if (!counts.empty() && counts.size() != ends.size()) throw InvalidArgument("walkRays: counts of none or of every ray");
  if (view.palette.empty()) throw InvalidArgument("walkRays: the snapshot has no palette");
  // The packet walks carry offsets in 32-bit lanes.
  const bool packets_fit = static_cast<double>(view.size[0]) * view.size[1] * view.size[2] < 2147483648.0;
  detail::dispatch(
      isa, packets_fit, [&] { detail::walkRaysAvx512(origin, ends, lattice, view, out, counts); },
      [&] { detail::walkRaysAvx2(origin, ends, lattice, view, out, counts); },
      [&] {
        for (std::size_t i = 0; i < ends.size(); ++i) {
          const RayAccumulator acc = detail::walkRayScalar(origin, ends[i], lattice, view);
          out[i] = acc.finish();
          if (!counts.empty()) counts[i] = acc.counts();
        }
      });
}

}  // namespace nbv::kernels
