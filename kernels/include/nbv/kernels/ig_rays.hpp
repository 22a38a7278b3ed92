#pragma once
/// \file The IG ray walk over a dense snapshot of the map (SEMANTICS.md "Views and rays", "Volumetric information"): every metric of every
/// ray in one traversal, with a scalar path (the oracle) and AVX2 and AVX-512 packet paths.

#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/isa.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/kernels/ray_keys.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

namespace nbv::kernels {

/// A snapshot entry: the voxel's palette index in the low 24 bits, then, 5 bits each, its run
/// distance in each of the eight octants. Octant o is the direction of a walk whose steps are
/// negative along x if bit 0 of o is set (else positive or zero), along y if bit 1 is, along z
/// if bit 2 is (octantOf()). The run distance d of voxel v in octant o is the largest d up to
/// kMaxRunDistance such that every voxel v + (a sx, b sy, c sz), 0 <= a, b, c < d (s the
/// octant's signs, +1 for "positive or zero") has v's palette index; outside the box every
/// voxel has index 0 (SEMANTICS.md "Run skipping"). A DDA walk from v in octant o therefore
/// meets only voxels of v's state as long as it has taken fewer than d crossings along every
/// axis, and crosses them in closed form. (A walk has no reason to look back: its voxels only
/// ever move forward along each axis.) A walk stops at a voxel that stops rays before reading
/// its run distance.
using SnapshotEntry = std::uint64_t;
inline constexpr unsigned kOctants = 8;
inline constexpr unsigned kRunDistanceBits = 5;
inline constexpr unsigned kMaxRunDistance = (1u << kRunDistanceBits) - 1;  // 31
inline constexpr std::uint32_t kMaxPaletteSize = 1u << 24;
inline constexpr unsigned kFirstRunDistanceBit = 24;
static_assert(kFirstRunDistanceBit + kOctants * kRunDistanceBits <= 64);

/// The octant of a walk with these steps (-1, 0 or +1 per axis).
inline constexpr unsigned octantOf(const int step[3]) {
  return (step[0] < 0 ? 1u : 0u) | (step[1] < 0 ? 2u : 0u) | (step[2] < 0 ? 4u : 0u);
}
/// Where octant o's run distance lies in an entry.
inline constexpr unsigned runDistanceShift(unsigned octant) { return kFirstRunDistanceBit + kRunDistanceBits * octant; }
inline constexpr std::uint32_t paletteIndex(SnapshotEntry entry) {
  return static_cast<std::uint32_t>(entry) & (kMaxPaletteSize - 1);
}
inline constexpr unsigned runDistance(SnapshotEntry entry, unsigned octant) {
  return static_cast<unsigned>(entry >> runDistanceShift(octant)) & kMaxRunDistance;
}
/// `entry` with run distance `run_distance` (at most kMaxRunDistance) in `octant`, whose field
/// must be 0 so far: runDistance()'s inverse.
inline constexpr SnapshotEntry withRunDistance(SnapshotEntry entry, unsigned octant, unsigned run_distance) {
  return entry | SnapshotEntry{run_distance} << runDistanceShift(octant);
}
/// An entry with the same run distance (at most kMaxRunDistance) in every octant.
inline constexpr SnapshotEntry makeEntry(std::uint32_t palette_index, unsigned run_distance) {
  SnapshotEntry entry = palette_index;
  for (unsigned o = 0; o < kOctants; ++o) entry = withRunDistance(entry, o, run_distance);
  return entry;
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

/// Walks the rays origin -> ends[i] and writes each ray's sums to out[i] (SEMANTICS.md "Views and rays", "Volumetric information").
///
/// A ray's voxels are OctoMap's computeRayKeys(origin, end) followed by the end point's voxel,
/// cut after the first voxel with the kStop flag. `ends[i]` is the point at max_ray_depth.
/// Runs of identical voxels (SnapshotEntry), and the voxels outside the snapshot (before the ray
/// enters it and after it leaves), are summed in closed form. Every instruction set gives bit-identical sums. All points must
/// satisfy lattice.inRange(); `view.palette` must hold every index the box uses.
/// Thread-safe (reads `view` only). \throws InvalidArgument if `isa` is not available, the
/// spans do not match or the snapshot has no palette.
void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out);

/// walkRays() that also writes each ray's counts (RayCounts, what the counting formulations
/// read) to counts[i], unless `counts` is empty: only a walk asked for them pays for them.
/// \throws as walkRays(); InvalidArgument if `counts` is neither empty nor one per ray.
void walkRays(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
              const VoxelLattice& lattice, const SnapshotView& view, Isa isa,
              std::span<RaySums> out, std::span<RayCounts> counts);

}  // namespace nbv::kernels
