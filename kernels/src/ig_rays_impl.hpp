#pragma once
// Private: what the instruction-set variants of walkRays() share. The scalar walk here is
// the oracle; the packet walk takes rays over from enterSnapshot() and hands them back to
// finishOutside().

#include "nbv/kernels/ig_rays.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>

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
    const double inv_d = 1.0 / d;  // one division, not two: the grown box absorbs the rounding
    double t0 = (lo - o) * inv_d, t1 = (hi - o) * inv_d;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out;
}

/// The walk of a ray that starts outside the box, skipped to its first voxel inside: on each
/// axis the border times are the same sums the walk forms (t_max += t_delta, one at a time), so
/// the state found equals the walk's bit for bit, without its per-step choice of axis. The walk
/// takes the crossings in order of time; it has entered the box once every axis has, at the
/// latest of the axes' entering crossings (t_entry), and has then taken exactly the crossings
/// before t_entry. Returns false (the caller walks) where the walk's own tie-breaking, length
/// stop or end key could decide otherwise: crossings equal to t_entry, a length stop on the way
/// or at the entry step, the end key on the way, an axis leaving the box before t_entry, the
/// origin inside the box.
/// `steps`: voxels before the entry voxel (the origin's included).
inline bool skipToBox(const RaySetup& s, const SnapshotView& view, Index3& ijk, double t_max[3],
                      std::uint32_t& steps) {
  int lo[3], hi[3];  // the box's first and last index per axis
  int enter[3];      // crossings along each axis before its index lies in the box
  bool outside = false;
  for (int a = 0; a < 3; ++a) {
    lo[a] = view.min[a];
    hi[a] = view.min[a] + static_cast<int>(view.size[a]) - 1;
    const int o = s.key_origin[a];
    if (o >= lo[a] && o <= hi[a]) {
      enter[a] = 0;
    } else if (s.step[a] > 0 && o < lo[a]) {
      enter[a] = lo[a] - o;
    } else if (s.step[a] < 0 && o > hi[a]) {
      enter[a] = o - hi[a];
    } else {
      return false;  // never enters along this axis
    }
    outside = outside || enter[a] > 0;
  }
  if (!outside) return false;
  // The time of each axis's entering crossing; the latest one is the entry step.
  double t[3] = {s.t_max[0], s.t_max[1], s.t_max[2]};
  int taken[3] = {0, 0, 0};
  double t_entry = -1.0;
  int last_axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (enter[a] == 0) continue;
    for (; taken[a] < enter[a] - 1; ++taken[a]) t[a] = t[a] + s.t_delta[a];
    if (t[a] == t_entry) return false;
    if (t[a] > t_entry) {
      t_entry = t[a];
      last_axis = a;
    }
  }
  if (!(t_entry <= s.length)) return false;  // the walk would stop before the box
  // Every crossing before t_entry is taken (the entering one of the last axis included).
  for (int a = 0; a < 3; ++a) {
    if (s.step[a] == 0) continue;
    while (t[a] < t_entry) {
      t[a] = t[a] + s.t_delta[a];
      ++taken[a];
    }
    if (a == last_axis) {
      t[a] = t[a] + s.t_delta[a];
      ++taken[a];
    } else if (t[a] == t_entry) {
      return false;  // a tie with the entry step: the walk's order decides
    }
  }
  Index3 entry;
  for (int a = 0; a < 3; ++a) {
    entry[a] = s.key_origin[a] + s.step[a] * taken[a];
    if (entry[a] < lo[a] || entry[a] > hi[a]) return false;  // left the box along this axis first
  }
  // The end key must not lie on the way (the walk stops there): the way stays in the
  // bounding box of origin and entry voxel.
  bool on_the_way = true;
  for (int a = 0; a < 3; ++a) {
    const int first = std::min(s.key_origin[a], entry[a]), last = std::max(s.key_origin[a], entry[a]);
    on_the_way = on_the_way && s.key_end[a] >= first && s.key_end[a] <= last;
  }
  if (on_the_way) return false;
  // The entry step itself must pass the walk's length test, or the walk ends there.
  if (!(std::min(std::min(t[0], t[1]), t[2]) <= s.length)) return false;
  ijk = entry;
  std::copy(t, t + 3, t_max);
  steps = static_cast<std::uint32_t>(taken[0] + taken[1] + taken[2]);
  return true;
}

/// The crossings along axis `a` the walk at `ijk` can still take inside the box. The packet
/// entry (enterPacket() in ig_rays_packet.hpp) repeats this and runStop() lane by lane.
inline double boxLeft(const SnapshotView& view, const RaySetup& s, const Index3& ijk, int a) {
  const int last = view.min[a] + static_cast<int>(view.size[a]) - 1;
  return s.step[a] > 0   ? static_cast<double>(last - ijk[a])
         : s.step[a] < 0 ? static_cast<double>(ijk[a] - view.min[a])
                         : std::numeric_limits<double>::infinity();
}

/// A time before which the walk surely neither reaches the end key nor passes the segment's
/// length: the length, or, if earlier, half a t_delta before the crossing on which the last
/// axis enters the end key's slab (the E-th crossing of an axis comes at t_max + (E - 1) t_delta,
/// up to rounding far below half a t_delta). Repeated lane by lane by enterPacket().
inline double runStop(const RaySetup& s) {
  double enters_end = -std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const int crossings = (s.key_end[a] - s.key_origin[a]) * s.step[a];
    if (crossings >= 1) {
      enters_end = std::max(enters_end, s.t_max[a] + (static_cast<double>(crossings) - 1.5) * s.t_delta[a]);
    }
  }
  return std::min(s.length, enters_end);
}

/// Where a run of identical voxels ends for the walk at a voxel whose run distance in the walk's
/// octant is `run_steps` + 1: the walk may take every crossing before the returned time and
/// stay inside the run's cube ahead of it (at most run_steps crossings per axis), inside the
/// box (at most box_left[a] crossings per axis) and before run_stop. The threshold lies half
/// a t_delta between two crossings of the limiting axis, far from rounding. Taking every
/// crossing before a time, on each axis separately, is a prefix of the walk's own order
/// whatever its tie-breaking. The packet walk computes the same operations lane by lane (its
/// _mm256_min_pd(x, t) is std::min(t, x), equal values included).
inline double runEnd(const double t_max[3], const double t_delta[3], const double box_left[3], double run_steps,
                     double run_stop) {
  double t = run_stop;
  for (int a = 0; a < 3; ++a) t = std::min(t, t_max[a] + (std::min(run_steps, box_left[a]) - 0.5) * t_delta[a]);
  return t;
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
/// box; its sums are then complete in entry.acc. The packet walks repeat setupRay(),
/// mayEnter() and skipToBox() lane by lane (enterPacket() in ig_rays_packet.hpp): a change to
/// their operations is a change to both.
inline bool enterSnapshot(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                          const VoxelLattice& lattice, const SnapshotView& view, RayEntry& entry) {
  const VoxelTerms& outside = view.palette[0];
  new (&entry.acc) RayAccumulator;  // in place: a temporary and its copy cost a store-forwarding stall per ray
  RaySetup& s = entry.setup;
  if (!setupRay(origin, end, lattice, s)) {  // one voxel: the end point's
    entry.ijk = s.key_end;
    entry.at_end = true;
    if (view.contains(s.key_end)) return true;
    entry.acc.add(outside);
    return false;
  }
  // A ray from a voxel of the box enters it (the slab test's divisions are then not needed).
  if (!view.contains(s.key_origin) && !mayEnter(origin, end, lattice, view)) {
    entry.acc.addUniform(outside, tailVoxels(s, s.key_origin, s.t_max));
    return false;
  }
  entry.at_end = false;
  std::uint32_t before = 0;
  if (skipToBox(s, view, entry.ijk, entry.t_max, before)) {
    entry.acc.addUniform(outside, before);
    return true;
  }
  RayWalk walk(s);
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
/// the walk still visits is outside (the walk is monotonic per axis and the box convex). The
/// end point's voxel closes the ray with its own terms: rounding can carry the walk past the
/// end key's slab and out of the box while the end key lies inside it. The packet walks repeat
/// this and tailVoxels()'s closed-form case lane by lane (IgPacketWalk::endInLanes()): a
/// change to either is a change to both.
inline void finishOutside(RayAccumulator& acc, const SnapshotView& view, const RaySetup& s,
                          const Index3& ijk, const double t_max[3]) {
  const std::uint32_t voxels = tailVoxels(s, ijk, t_max);  // the end voxel included
  if (view.contains(s.key_end)) {
    acc.addUniform(view.palette[0], voxels - 1);
    acc.add(view.terms(s.key_end));
  } else {
    acc.addUniform(view.palette[0], voxels);
  }
}

/// The scalar walk of one ray, its accumulator after the end voxel: the oracle of every other
/// variant.
inline RayAccumulator walkRayScalar(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                             const VoxelLattice& lattice, const SnapshotView& view) {
  RayEntry entry;
  if (!enterSnapshot(origin, end, lattice, view, entry)) return entry.acc;
  RayAccumulator& acc = entry.acc;
  if (entry.at_end) {
    acc.add(view.terms(entry.setup.key_end));
    return acc;
  }
  const RaySetup& s = entry.setup;
  const double run_stop = runStop(s);
  const unsigned octant = octantOf(s.step);
  RayWalk walk(s);
  walk.ijk = entry.ijk;
  std::copy(entry.t_max, entry.t_max + 3, walk.t_max);
  while (true) {
    if (!view.contains(walk.ijk)) {
      finishOutside(acc, view, s, walk.ijk, walk.t_max);
      break;
    }
    const SnapshotEntry e = view.voxels[view.offset(walk.ijk)];
    const VoxelTerms& t = view.palette[paletteIndex(e)];
    acc.add(t);
    if ((t.flags & voxel_flag::kStop) != 0) break;
    if (runDistance(e, octant) >= 2) {
      // A run of voxels of this one state (SnapshotEntry): every crossing before runEnd(),
      // axis by axis, and the voxels crossed into in closed form (the sums of SEMANTICS.md
      // "Run skipping").
      const double box_left[3] = {boxLeft(view, s, walk.ijk, 0), boxLeft(view, s, walk.ijk, 1),
                                  boxLeft(view, s, walk.ijk, 2)};
      const double t_end = runEnd(walk.t_max, s.t_delta, box_left, runDistance(e, octant) - 1.0, run_stop);
      std::uint32_t crossed = 0;
      for (int a = 0; a < 3; ++a) {
        for (; walk.t_max[a] < t_end; ++crossed) {
          walk.t_max[a] = walk.t_max[a] + s.t_delta[a];
          walk.ijk[a] += s.step[a];
        }
      }
      if (crossed > 0 && !walk.withinLength()) {
        acc.addRepeats(t, crossed - 1);  // the walk is over before the last voxel crossed into
        acc.add(view.terms(s.key_end));
        break;
      }
      acc.addRepeats(t, crossed);
    }
    if (!walk.next()) {  // the end point's voxel closes the ray
      acc.add(view.terms(s.key_end));
      break;
    }
  }
  return acc;
}

/// AVX2 packet walk of four rays at a time; the box must hold fewer than 2^31 voxels.
void walkRaysAvx2(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out,
                  std::span<RayCounts> counts);
/// AVX-512 packet walk of eight rays at a time; the box must hold fewer than 2^31 voxels.
void walkRaysAvx512(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                    const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out,
                  std::span<RayCounts> counts);

}  // namespace nbv::kernels::detail
