#include "nbv/kernels/mark_rays.hpp"

#include "mark_rays_impl.hpp"

#include "nbv/errors.hpp"

#include <string>

namespace nbv::kernels {

bool isaAvailable(Isa isa) {
  switch (isa) {
    case Isa::Scalar:
      return true;
    case Isa::Avx2:
#ifdef NBV_HAVE_AVX2
      return __builtin_cpu_supports("avx2");
#else
      return false;
#endif
    case Isa::Avx512:
#ifdef NBV_HAVE_AVX512
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
             __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
#else
      return false;
#endif
  }
  return false;
}

std::vector<Isa> availableIsas() {
  std::vector<Isa> out;
  for (Isa isa : {Isa::Scalar, Isa::Avx2, Isa::Avx512}) {
    if (isaAvailable(isa)) out.push_back(isa);
  }
  return out;
}

Isa bestIsa() { return availableIsas().back(); }

const char* isaName(Isa isa) {
  switch (isa) {
    case Isa::Avx2:
      return "avx2";
    case Isa::Avx512:
      return "avx512";
    case Isa::Scalar:
      break;
  }
  return "scalar";
}

std::optional<Isa> isaFromName(std::string_view name) {
  for (Isa isa : {Isa::Scalar, Isa::Avx2, Isa::Avx512}) {
    if (name == isaName(isa)) return isa;
  }
  return std::nullopt;
}

namespace detail {

void requireIsa(Isa isa) {
  if (isaAvailable(isa)) return;
  throw InvalidArgument(std::string("the instruction set ") + isaName(isa) +
                              " is not available: this CPU lacks it or nbv was built without it "
                              "(NBV_ENABLE_AVX2 / NBV_ENABLE_AVX512)");
}

}  // namespace detail

void markRays(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
              const OutsideSink& outside, Isa isa) {
  if (origins.size() != 1 && origins.size() != ends.size()) {
    throw InvalidArgument("markRays: give one origin, or one per ray");
  }
  detail::requireIsa(isa);
  // The packet paths carry offsets in 32-bit lanes.
  [[maybe_unused]] const bool packets_fit = box.bytes() < (std::uint64_t{1} << 31);
#ifdef NBV_HAVE_AVX512
  if (isa == Isa::Avx512 && packets_fit) {
    detail::markRaysAvx512(origins, ends, lattice, box, spec, outside);
    return;
  }
#endif
#ifdef NBV_HAVE_AVX2
  if (isa == Isa::Avx2 && packets_fit) {
    detail::markRaysAvx2(origins, ends, lattice, box, spec, outside);
    return;
  }
#endif
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
