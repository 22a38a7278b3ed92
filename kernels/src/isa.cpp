#include "nbv/kernels/isa.hpp"

#include "isa_dispatch.hpp"

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
#if defined(NBV_EMULATE_AVX512)
      return __builtin_cpu_supports("avx2");  // plain C++ lanes, compiled with -mavx2
#elif defined(NBV_HAVE_AVX512)
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

bool isaEmulated([[maybe_unused]] Isa isa) {
#ifdef NBV_EMULATE_AVX512
  return isa == Isa::Avx512;
#else
  return false;
#endif
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

}  // namespace nbv::kernels
