#include "nbv/kernels/mark_rays.hpp"

#include "isa_dispatch.hpp"
#include "mark_rays_impl.hpp"

#include "nbv/errors.hpp"

#include <string>

namespace nbv::kernels {

void markRays(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
              const OutsideSink& outside, Isa isa) {
  if (origins.size() != 1 && origins.size() != ends.size()) {
    throw InvalidArgument("markRays: give one origin, or one per ray");
  }
  // The packet paths carry offsets in 32-bit lanes.
  const bool packets_fit = box.bytes() < (std::uint64_t{1} << 31);
  detail::dispatch(
      isa, packets_fit, [&] { detail::markRaysAvx512(origins, ends, lattice, box, spec, outside); },
      [&] { detail::markRaysAvx2(origins, ends, lattice, box, spec, outside); },
      [&] {
        for (std::size_t i = 0; i < ends.size(); ++i) {
          if (spec.end_flags != nullptr) {
            std::size_t at = 0;
            const bool inside = box.locate(lattice.worldToIndex(ends[i]), at);
            detail::flagEnd(spec, inside, at);
          }
          detail::markRayScalar(origins[origins.size() == 1 ? 0 : i], ends[i], lattice, box, spec, outside);
        }
      });
}

}  // namespace nbv::kernels
