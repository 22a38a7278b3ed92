#pragma once
/// \file The IG ray walk over a dense snapshot of the map (SPEC §2-3): every metric of every
/// ray in one traversal, with a scalar path (the oracle) and an AVX2 packet path.

#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/kernels/ray_keys.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

namespace nbv::kernels {

/// Entries stored after the last voxel of a snapshot, so that a packet walk may read 4 bytes
/// at any voxel.
inline constexpr std::size_t kSnapshotPadding = 2;

/// Unmeasured, unmarked voxels inside a snapshot (palette[0]) carry instead of 0 their
/// Chebyshev distance d, in voxels, to the nearest other voxel, capped at this: a DDA walk
/// from such a voxel meets only palette[0] voxels in its next d - 1 steps.
inline constexpr unsigned kMaxUniformDistance = 32;
/// Entries at or above this are palette[0] voxels: the entry is 65536 - d.
inline constexpr std::uint16_t kFirstUniformEntry = 0x10000 - kMaxUniformDistance;
/// The entry of a palette[0] voxel at distance d (1 <= d <= kMaxUniformDistance).
inline constexpr std::uint16_t uniformEntry(unsigned d) { return static_cast<std::uint16_t>(0x10000 - d); }
/// The distance of an entry: 0 for other voxels.
inline constexpr unsigned uniformDistance(std::uint16_t entry) {
  return entry >= kFirstUniformEntry ? 0x10000u - entry : 0u;
}
/// The palette index of an entry.
inline constexpr std::uint16_t paletteIndex(std::uint16_t entry) {
  return entry >= kFirstUniformEntry ? 0 : entry;
}

/// A box of the map, one entry per voxel, x fastest (DenseBox's layout): a palette index, or
/// for an unmeasured, unmarked voxel a uniformEntry(). Everything outside the box is
/// unmeasured and unmarked and reads as palette[0]. Does not own its data.
struct SnapshotView {
  int min[3] = {0, 0, 0};             ///< first voxel index per axis
  std::uint32_t size[3] = {0, 0, 0};  ///< voxels per axis (0: an empty box)
  const std::uint16_t* voxels = nullptr;  ///< size product + kSnapshotPadding entries
  std::span<const VoxelTerms> palette;    ///< palette[0]: the unmeasured, unmarked voxel

  bool contains(const Index3& ijk) const {
    return static_cast<std::uint32_t>(ijk.x() - min[0]) < size[0] &&
           static_cast<std::uint32_t>(ijk.y() - min[1]) < size[1] &&
           static_cast<std::uint32_t>(ijk.z() - min[2]) < size[2];
  }
  /// Offset of a voxel the box contains.
  std::size_t offset(const Index3& ijk) const {
    return (static_cast<std::size_t>(ijk.z() - min[2]) * size[1] + static_cast<std::size_t>(ijk.y() - min[1])) *
               size[0] + static_cast<std::size_t>(ijk.x() - min[0]);
  }
  /// The terms of any voxel.
  const VoxelTerms& terms(const Index3& ijk) const {
    return contains(ijk) ? palette[paletteIndex(voxels[offset(ijk)])] : palette[0];
  }
};

/// Walks the rays origin -> ends[i] and writes each ray's sums to out[i] (SPEC §2-3).
///
/// A ray's voxels are OctoMap's computeRayKeys(origin, end) followed by the end point's voxel,
/// cut after the first voxel with the kStop flag. `ends[i]` is the point at max_ray_depth.
/// Runs of voxels outside the snapshot (before the ray enters it and after it leaves) are
/// summed in closed form. Every instruction set gives bit-identical sums. All points must
/// satisfy lattice.inRange(); `view.palette` must hold every index the box uses.
/// Thread-safe (reads `view` only). \throws std::invalid_argument if `isa` is not available
/// or the spans do not match.
void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out);

}  // namespace nbv::kernels
