#pragma once
/// \file The IG ray walk over a dense snapshot of the map (SPEC §2-3): every metric of every
/// ray in one traversal, with a scalar path (the oracle) and AVX2 and AVX-512 packet paths.

#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/kernels/ray_keys.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

namespace nbv::kernels {

/// A snapshot entry: the voxel's palette index in the low 24 bits, and in the high 8 bits
/// its run distance d: the Chebyshev distance, in voxels, to the nearest voxel with another
/// palette index (outside the box everything is palette[0]), capped at kMaxRunDistance. A DDA
/// walk from the voxel meets only voxels of its palette index in its next d - 1 steps.
using SnapshotEntry = std::uint32_t;
inline constexpr unsigned kMaxRunDistance = 64;
inline constexpr std::uint32_t kMaxPaletteSize = 1u << 24;
inline constexpr std::uint32_t paletteIndex(SnapshotEntry entry) { return entry & (kMaxPaletteSize - 1); }
inline constexpr unsigned runDistance(SnapshotEntry entry) { return entry >> 24; }
inline constexpr SnapshotEntry makeEntry(std::uint32_t palette_index, unsigned run_distance) {
  return palette_index | (static_cast<std::uint32_t>(run_distance) << 24);
}

/// A box of the map, one SnapshotEntry per voxel, x fastest (DenseBox's layout). Everything
/// outside the box is unmeasured and unmarked and reads as palette[0]. Does not own its data.
struct SnapshotView {
  int min[3] = {0, 0, 0};             ///< first voxel index per axis
  std::uint32_t size[3] = {0, 0, 0};  ///< voxels per axis (0: an empty box)
  const SnapshotEntry* voxels = nullptr;  ///< one per voxel
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
