#pragma once
/// \file Marking every voxel of many rays from one origin in a dense byte box: the hot loop
/// of map integration, with a scalar path (the oracle) and AVX2 and AVX-512 packet paths.

#include "nbv/kernels/isa.hpp"
#include "nbv/kernels/ray_keys.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace nbv::kernels {

/// A box of voxels, one byte each, x fastest: voxel (i, j, k) at
/// (i - min[0]) + size[0] * ((j - min[1]) + size[1] * (k - min[2])). Does not own `data`.
/// Boxes made by DenseBox::around() are aligned to 8 voxels, so each x-row of an OpenVDB
/// leaf is 8 consecutive bytes.
struct DenseBox {
  int min[3] = {0, 0, 0};                ///< first voxel index per axis
  std::uint32_t size[3] = {0, 0, 0};     ///< voxels per axis
  std::uint8_t* data = nullptr;          ///< size[0] * size[1] * size[2] bytes

  /// The 8-aligned box holding [lo, hi] (inclusive); `data` left empty.
  static DenseBox around(const Index3& lo, const Index3& hi) {
    DenseBox box;
    for (int a = 0; a < 3; ++a) {
      box.min[a] = lo[a] & ~7;
      box.size[a] = static_cast<std::uint32_t>((hi[a] | 7) - box.min[a] + 1);
    }
    return box;
  }
  /// Bytes the box needs; saturates rather than wrapping for boxes near the index range.
  std::uint64_t bytes() const {
    const double b = static_cast<double>(size[0]) * size[1] * size[2];
    return b >= 1e18 ? ~std::uint64_t{0} : static_cast<std::uint64_t>(b);
  }
  /// Byte offset of voxel `ijk`, or false if it lies outside the box.
  bool locate(const Index3& ijk, std::size_t& at) const {
    const auto x = static_cast<std::uint32_t>(ijk.x() - min[0]);
    const auto y = static_cast<std::uint32_t>(ijk.y() - min[1]);
    const auto z = static_cast<std::uint32_t>(ijk.z() - min[2]);
    if (x >= size[0] || y >= size[1] || z >= size[2]) return false;
    at = (std::size_t{z} * size[1] + y) * size[0] + x;
    return true;
  }
  /// True if `ijk` lies inside the box and at least one voxel away from its faces.
  bool holdsWithMargin(const Index3& ijk) const {
    for (int a = 0; a < 3; ++a) {
      const auto v = static_cast<std::int64_t>(ijk[a]) - min[a];
      if (v < 1 || v + 1 >= static_cast<std::int64_t>(size[a])) return false;
    }
    return true;
  }
};

/// What markRays() writes at the voxels of a ray.
struct MarkSpec {
  enum class Mode {
    Store,         ///< write `value` at every voxel
    MinStepIndex,  ///< at the k-th voxel (k = 0: the origin's, skipped) keep min(byte, k),
                   ///< a zero byte meaning "none yet"; rays must cross at most 253 voxels
  };
  Mode mode = Mode::Store;
  std::uint8_t value = 1;  ///< the byte of Mode::Store
  /// If set: a plane of bytes in the box's layout, where the end voxel of every ray (the
  /// voxel of its end point, which the walk itself leaves out) is set to 1. Every end voxel
  /// must then lie in the box.
  std::uint8_t* end_flags = nullptr;
};

/// Receives a voxel outside the box and the byte that was meant for it (rare: the box
/// normally holds every voxel).
using OutsideSink = std::function<void(const Index3&, std::uint8_t)>;

/// Walks every ray origin -> ends[i] as traverseRayKeys() does and writes each voxel's byte
/// per `spec` (relaxed atomic byte operations), or passes it to `outside` if the box does not
/// hold it. `origins` holds one origin shared by all rays, or one per ray. Every instruction
/// set writes the same bytes. Thread-safe: concurrent calls may share a box (`outside` must
/// then be thread-safe). All points must satisfy lattice.inRange().
/// \throws InvalidArgument if `isa` is not available here, the spans do not match, a
/// MinStepIndex ray is too long for byte distances, or an end voxel to flag is outside the box.
void markRays(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
              const OutsideSink& outside, Isa isa);

}  // namespace nbv::kernels
