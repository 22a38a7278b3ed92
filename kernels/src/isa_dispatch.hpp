#pragma once
// Private: the one choice of a ray loop by instruction set, shared by markRays() and walkRays().

#include "nbv/kernels/isa.hpp"

namespace nbv::kernels::detail {

/// Throws InvalidArgument unless isaAvailable(isa).
void requireIsa(Isa isa);

/// Runs the loop of `isa`: `packets8()` (AVX-512) or `packets4()` (AVX2) when this build has it
/// and the packets fit (their offsets are 32-bit lanes), else `scalar()`; returns what it
/// returns. A build without a packet loop never calls (nor emits) its lambda.
/// \throws InvalidArgument unless isaAvailable(isa).
template <class Packets8, class Packets4, class Scalar>
decltype(auto) dispatch(Isa isa, [[maybe_unused]] bool packets_fit, [[maybe_unused]] Packets8&& packets8,
                        [[maybe_unused]] Packets4&& packets4, Scalar&& scalar) {
  requireIsa(isa);
#ifdef NBV_HAVE_AVX512
  if (isa == Isa::Avx512 && packets_fit) return packets8();
#endif
#ifdef NBV_HAVE_AVX2
  if (isa == Isa::Avx2 && packets_fit) return packets4();
#endif
  return scalar();
}

}  // namespace nbv::kernels::detail
