#pragma once
// Private: what the instruction-set variants of walkRays() share. The scalar walk here is
// the oracle; the packet walk takes rays over from enterSnapshot() and hands them back to
// finishOutside().

#include "nbv/kernels/ig_rays.hpp"

#include <algorithm>
#include <cstdlib>

namespace nbv::kernels::detail {

/// Manhattan distance between two voxels: a DDA walk from one to the other visits this many
/// voxels after the first (each step moves one axis by one).
inline std::uint32_t manhattan(const Index3& a, const Index3& b) {
  return static_cast<std::uint32_t>(std::abs(a.x() - b.x()) + std::abs(a.y() - b.y()) + std::abs(a.z() - b.z()));
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
    entry.acc.addUniform(outside, 1 + manhattan(s.key_end, s.key_origin));
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

/// Ends a ray that left the box at voxel `ijk`: every voxel from there to the end point's,
/// both included, is outside (the walk is monotonic per axis and the box convex).
inline void finishOutside(RayAccumulator& acc, const SnapshotView& view, const Index3& ijk,
                          const Index3& key_end) {
  acc.addUniform(view.palette[0], 1 + manhattan(key_end, ijk));
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
      finishOutside(acc, view, walk.ijk, entry.setup.key_end);
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
