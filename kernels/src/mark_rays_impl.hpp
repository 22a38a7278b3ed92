#pragma once
// Private: what the instruction-set variants of markRays() share.

#include "nbv/kernels/mark_rays.hpp"

#include "nbv/errors.hpp"

#include <atomic>
#include <cstdlib>

namespace nbv::kernels::detail {

/// Stores `value` at `byte`, relaxed: concurrent markRays() calls may share a box.
inline void storeByte(std::uint8_t* byte, std::uint8_t value) {
  std::atomic_ref<std::uint8_t>(*byte).store(value, std::memory_order_relaxed);
}

/// MinStepIndex's write: lowers the byte to `d` unless it holds a nonzero value <= d (0: none
/// yet), atomically, so concurrent walks keep the least.
inline void lowerByte(std::uint8_t* byte, std::uint8_t d) {
  std::atomic_ref<std::uint8_t> slot(*byte);
  std::uint8_t current = slot.load(std::memory_order_relaxed);
  while ((current == 0 || d < current) &&
         !slot.compare_exchange_weak(current, d, std::memory_order_relaxed)) {
  }
}

/// Writes one voxel's byte per `spec`; `step_index` is the voxel's k along its ray.
inline void writeByte(std::uint8_t* byte, const MarkSpec& spec, int step_index) {
  if (spec.mode == MarkSpec::Mode::Store) {
    storeByte(byte, spec.value);
  } else {
    lowerByte(byte, static_cast<std::uint8_t>(step_index));
  }
}

/// Writes the byte of the k-th voxel `ijk` of a ray, or hands it to `outside`.
inline void writeVoxel(const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside,
                       const Index3& ijk, int step_index) {
  if (spec.mode == MarkSpec::Mode::MinStepIndex && step_index == 0) return;
  std::size_t at;
  if (box.locate(ijk, at)) {
    writeByte(box.data + at, spec, step_index);
  } else {
    outside(ijk, spec.mode == MarkSpec::Mode::Store ? spec.value : static_cast<std::uint8_t>(step_index));
  }
}

/// Throws unless a MinStepIndex ray fits byte distances: the walk visits at most the
/// Manhattan distance of its end voxels plus one (rounding) voxels after its first.
inline void checkStepRange(const MarkSpec& spec, const Index3& key_origin, const Index3& key_end) {
  if (spec.mode != MarkSpec::Mode::MinStepIndex) return;
  const int manhattan = std::abs(key_end.x() - key_origin.x()) + std::abs(key_end.y() - key_origin.y()) +
                        std::abs(key_end.z() - key_origin.z());
  if (manhattan + 1 > 253) {
    throw InvalidArgument("markRays: a ray crosses more than 253 voxels, too many for byte distances");
  }
}

/// Sets the end flag of the voxel at `at` (spec.end_flags set), or throws if `inside` is false.
inline void flagEnd(const MarkSpec& spec, bool inside, std::size_t at) {
  if (!inside) throw InvalidArgument("markRays: an end voxel to flag is outside the box");
  storeByte(spec.end_flags + at, 1);
}

/// The scalar walk of one ray: the oracle of every other variant.
inline void markRayScalar(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                          const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                          const OutsideSink& outside) {
  if (spec.mode == MarkSpec::Mode::MinStepIndex) {  // byte distances: check the ray's length
    RaySetup s;
    if (setupRay(origin, end, lattice, s)) checkStepRange(spec, s.key_origin, s.key_end);
  }
  int k = 0;
  traverseRayKeys(origin, end, lattice,
                  [&](const Index3& ijk) { writeVoxel(box, spec, outside, ijk, k++); });
}

/// AVX2 packet walk of four rays at a time; box.bytes() must be below 2^31.
void markRaysAvx2(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                  const OutsideSink& outside);
/// AVX-512 packet walk of eight rays at a time; box.bytes() must be below 2^31.
void markRaysAvx512(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                    const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                    const OutsideSink& outside);

}  // namespace nbv::kernels::detail
