#pragma once
// Private: what the instruction-set variants of walkRays() share. The scalar walk here is
// the oracle; the packet walk takes rays over from enterSnapshot() and hands them back to
// finishOutside().

#include "nbv/kernels/ig_rays.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace nbv::kernels::detail {

/// Manhattan distance between two voxels: a DDA walk from one to the other visits this many
/// voxels after the first (each step moves one axis by one).
inline std::uint32_t manhattan(const Index3& a, const Index3& b) {
  return static_cast<std::uint32_t>(std::abs(a.x() - b.x()) + std::abs(a.y() - b.y()) + std::abs(a.z() - b.z()));
}

/// Number of voxels from `ijk` (the walk's current voxel, visited, with its t_max state) to the
/// end of the ray, the end point's voxel included: the voxels computeRayKeys still visits plus
/// the end voxel. Usually 1 + manhattan(key_end, ijk); OctoMap's walk also stops when its
/// accumulated t_max passes the segment length, which rounding can make happen one step
/// before the end key (30 sums of 0.05 exceed 1.5), or it can step past the end key's slab.
/// Both can only happen when the last border crossings lie within rounding of the length or
/// of each other, so those rays (and only those) are walked step by step.
inline std::uint32_t tailVoxels(const RaySetup& s, const Index3& ijk, const double t_max[3]) {
  if (ijk == s.key_end) return 1;
  const std::uint32_t remaining = manhattan(s.key_end, ijk);
  // The last crossing into the end key's slab on any axis (last_in) must come clearly before
  // the segment's end and before any crossing out of the slab (first_out): with per-axis
  // errors below (remaining + 4) ulps of the values compared, the walk then takes exactly
  // `remaining` steps to the end key.
  double last_in = 0.0;
  double first_out = std::numeric_limits<double>::infinity();
  bool plain = true;
  for (int a = 0; a < 3; ++a) {
    const int delta = s.key_end[a] - ijk[a];
    if (delta == 0) {
      first_out = std::min(first_out, t_max[a]);
      continue;
    }
    if (delta * s.step[a] <= 0) plain = false;  // the walk is already past the slab
    const double in = t_max[a] + static_cast<double>(std::abs(delta) - 1) * s.t_delta[a];
    last_in = std::max(last_in, in);
    first_out = std::min(first_out, in + s.t_delta[a]);
  }
  const double slack = 1.0 + static_cast<double>(remaining + 4) * std::ldexp(1.0, -50);
  if (plain && last_in * slack < s.length && last_in * slack * slack < first_out) return 1 + remaining;
  RayWalk walk(s);
  walk.ijk = ijk;
  std::copy(t_max, t_max + 3, walk.t_max);
  std::uint32_t visited = 1;
  while (walk.next()) ++visited;
  return visited + 1;
}

/// False only if the segment origin -> end surely misses the box (a slab test against the box
/// grown by one voxel, so rounding can only say "may enter").
inline bool mayEnter(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                     const VoxelLattice& lattice, const SnapshotView& view) {
  if (view.size[0] == 0 || view.size[1] == 0 || view.size[2] == 0) return false;
  double t_in = 0.0, t_out = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = (view.min[a] - 1) * lattice.resolution();
    const double hi = (view.min[a] + static_cast<double>(view.size[a]) + 1.0) * lattice.resolution();
    const double o = origin[a], d = static_cast<double>(end[a]) - o;
    if (d == 0.0) {
      if (o < lo || o > hi) return false;
      continue;
    }
    double t0 = (lo - o) / d, t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out;
}

/// One ray, brought to its first voxel inside the snapshot.
struct RayEntry {
  RaySetup setup;
  Index3 ijk;          ///< the current voxel (inside the box unless at_end)
  double t_max[3];
  bool at_end = false; ///< the current voxel is the end point's voxel, the ray's last
  RayAccumulator acc;  ///< the voxels before the current one
};

/// Starts a ray: walks it (additions only, no look-ups) to its first voxel inside the box and
/// sums the voxels before in closed form. The walk is OctoMap's own, so the entry voxel is the
/// one OctoMap reaches even through voxel corners. Returns false if the ray never enters the
/// box; its sums are then complete in entry.acc.
inline bool enterSnapshot(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                          const VoxelLattice& lattice, const SnapshotView& view, RayEntry& entry) {
  const VoxelTerms& outside = view.palette[0];
  entry.acc = RayAccumulator{};
  RaySetup& s = entry.setup;
  if (!setupRay(origin, end, lattice, s)) {  // one voxel: the end point's
    entry.ijk = s.key_end;
    entry.at_end = true;
    if (view.contains(s.key_end)) return true;
    entry.acc.add(outside);
    return false;
  }
  if (!mayEnter(origin, end, lattice, view)) {
    entry.acc.addUniform(outside, tailVoxels(s, s.key_origin, s.t_max));
    return false;
  }
  RayWalk walk(s);
  std::uint32_t before = 0;
  entry.at_end = false;
  while (!view.contains(walk.ijk)) {
    ++before;
    if (!walk.next()) {  // the walk is over outside the box; the end voxel remains
      entry.acc.addUniform(outside, before);
      entry.ijk = s.key_end;
      entry.at_end = true;
      if (view.contains(s.key_end)) return true;
      entry.acc.add(outside);
      return false;
    }
  }
  entry.acc.addUniform(outside, before);
  entry.ijk = walk.ijk;
  std::copy(walk.t_max, walk.t_max + 3, entry.t_max);
  return true;
}

/// Ends a ray that left the box at voxel `ijk` (t_max: the walk's state there): every voxel
/// from there to the end point's, both included, is outside (the walk is monotonic per axis
/// and the box convex).
inline void finishOutside(RayAccumulator& acc, const SnapshotView& view, const RaySetup& s,
                          const Index3& ijk, const double t_max[3]) {
  acc.addUniform(view.palette[0], tailVoxels(s, ijk, t_max));
}

/// The scalar walk of one ray: the oracle of every other variant.
inline RaySums walkRayScalar(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                             const VoxelLattice& lattice, const SnapshotView& view) {
  RayEntry entry;
  if (!enterSnapshot(origin, end, lattice, view, entry)) return entry.acc.finish();
  RayAccumulator& acc = entry.acc;
  if (entry.at_end) {
    acc.add(view.terms(entry.setup.key_end));
    return acc.finish();
  }
  RayWalk walk(entry.setup);
  walk.ijk = entry.ijk;
  std::copy(entry.t_max, entry.t_max + 3, walk.t_max);
  while (true) {
    if (!view.contains(walk.ijk)) {
      finishOutside(acc, view, entry.setup, walk.ijk, walk.t_max);
      break;
    }
    const VoxelTerms& t = view.palette[paletteIndex(view.voxels[view.offset(walk.ijk)])];
    acc.add(t);
    if ((t.flags & voxel_flag::kStop) != 0) break;
    if (!walk.next()) {  // the end point's voxel closes the ray
      acc.add(view.terms(entry.setup.key_end));
      break;
    }
  }
  return acc.finish();
}

#ifdef NBV_HAVE_AVX2
/// AVX2 packet walk of four rays at a time; the box must hold fewer than 2^31 voxels.
void walkRaysAvx2(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out);
#endif

}  // namespace nbv::kernels::detail
