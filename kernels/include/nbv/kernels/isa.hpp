#pragma once
/// \file The instruction sets of the ray loops (markRays(), walkRays()), chosen at run time.

#include <optional>
#include <string_view>
#include <vector>

namespace nbv::kernels {

/// Instruction sets of the ray loops. Every one gives the same results bit for bit.
enum class Isa {
  Scalar,  ///< the oracle: one ray at a time, always built
  Avx2,    ///< packets of 4 rays (NBV_ENABLE_AVX2)
  Avx512,  ///< packets of 8 rays (AVX-512 F/VL/DQ/BW, NBV_ENABLE_AVX512)
};

/// True when this build has the instruction set's loops and this CPU runs them. Thread-safe.
bool isaAvailable(Isa isa);
/// True when this build runs the instruction set's loops over plain C++ lanes in its place
/// (NBV_EMULATE_AVX512: the AVX-512 walks checked on a CPU without AVX-512). Same results, far
/// slower. Thread-safe.
bool isaEmulated(Isa isa);
/// The widest available instruction set. Thread-safe.
Isa bestIsa();
/// Every available instruction set, Isa::Scalar first. Thread-safe.
std::vector<Isa> availableIsas();
/// "scalar", "avx2" or "avx512".
const char* isaName(Isa isa);
/// The instruction set of a name isaName() gives; empty if there is none.
std::optional<Isa> isaFromName(std::string_view name);

}  // namespace nbv::kernels
