#pragma once
// Private, part of ig_rays_packet.hpp (included there after ig_packet_step.hpp): how rays end
// in the lanes (endInLanes(), endQueued(), endRays()), and the entry point walkPackets().

namespace nbv::kernels::detail {
namespace {

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::endInLanes(Registers& r, const Constants& c, const Lanes& src, unsigned moving) const {
  // The rays in `moving` moved on without stopping; they end in the lanes (their fields in the
  // registers, their end keys in src), as RayWalk::next() and finishOutside() end them: the end
  // voxel next (reached, or rounding carried the walk past the segment); or, having left the
  // box, the voxels still ahead (tailVoxels()) of palette[0] and the end voxel if the box holds
  // it. A tail that tailVoxels() would walk voxel by voxel is left to finishWalkedTail().
  const M lanes = M::of(moving);
  const M end_next = lanes & (~(min(min(r.left_x, r.left_y), r.left_z) < c.zero) | pastLength(r));
  const M leaving = andNot(lanes, end_next);
  const M end_inside = r.end_offset == r.end_offset;  // (kNoOffset is NaN)
  // tailVoxels() at the voxel outside, found from the steps left in the box per axis.
  const D t[3] = {r.tx, r.ty, r.tz}, delta[3] = {r.dx, r.dy, r.dz}, left[3] = {r.left_x, r.left_y, r.left_z},
          offset_steps[3] = {r.ox, r.oy, r.oz};
  D remaining = c.zero, last_in = c.zero, first_out(std::numeric_limits<double>::infinity());
  M at_end_key = c.zero == c.zero, plain = at_end_key;
  for (int a = 0; a < 3; ++a) {
    const M forward = offset_steps[a] > c.zero, backward = offset_steps[a] < c.zero;
    const D last(view_.min[a] + static_cast<double>(view_.size[a]) - 1.0);
    const D ijk = select(forward, last - left[a], select(backward, D(view_.min[a]) + left[a], D(key_origin_[a])));
    const D to_end = loadD(src.key_end[a]) - ijk;
    const M here = to_end == c.zero;
    at_end_key = at_end_key & here;
    const D crossings = abs(to_end);
    remaining += crossings;
    const D step = select(forward, c.one, select(backward, D(-1.0), c.zero));
    plain = andNot(plain, ~here & (to_end * step <= c.zero));
    const D in = t[a] + (crossings - c.one) * delta[a];
    last_in = select(~here & (last_in < in), in, last_in);  // std::max
    const D out = select(here, t[a], in + delta[a]);
    first_out = select(out < first_out, out, first_out);  // std::min
  }
  const D slack = c.one + (remaining + D(4.0)) * D(0x1p-50);
  const D slacked = last_in * slack;
  const M tail_plain = plain & ((slacked < r.length) & (slacked * slack < first_out));
  const M tail = leaving & (at_end_key | tail_plain);
  const D tail_voxels = c.one + select(at_end_key, c.zero, remaining);  // the end voxel included
  // The voxels of palette[0]: all of them, or all but the end voxel when the box holds it.
  const D uniform = zeroUnless(tail, tail_voxels - zeroUnless(end_inside, c.one));
  const M first = tail & (uniform > c.zero);
  visit(r, c, c.uniform_h, c.uniform_keep, c.uniform_proximity, c.uniform_flags, first, 0u);
  repeatUniform<true>(r, c, uniform - zeroUnless(first, c.one));
  // The end voxel: its terms when the box holds it, else palette[0]'s.
  const M end_voxel = end_next | (tail & end_inside);
  D h = c.uniform_h, keep = c.uniform_keep, proximity = c.uniform_proximity;
  I flags = c.uniform_flags;
  if (const M load = end_voxel & end_inside; load.bits() != 0) {
    alignas(64) SnapshotEntry e[kLanes];
    S::loadEntries(c.voxels, select(load, r.end_offset, c.zero), e);
    termsOf(c, e, h, keep, proximity, flags);
  }
  const M outside_end = andNot(end_voxel, end_inside);
  visit(r, c, select(outside_end, c.uniform_h, h), select(outside_end, c.uniform_keep, keep),
        select(outside_end, c.uniform_proximity, proximity), select(outside_end, c.uniform_flags, flags), end_voxel,
        0u);
  return (end_next | tail).bits();
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::endQueued(Registers& r, const Constants& c) {
  // The queued rays' fields become the registers' lanes (the lanes' own state is spilled to
  // lanes_ by then, and reloaded after); their sums go to out_.
  Lanes& q = ending_;
  loadWalk(r, q);
  loadAccumulator(r, q);
  const unsigned ended = endInLanes(r, c, q, (1u << ending_count_) - 1u);
  storeAccumulator(r, q);
  for (int k = 0; k < ending_count_; ++k) {
    if ((ended >> k) & 1u) {
      emit(ending_ray_[k], accumulator(q, k));
    } else {
      finishWalkedTail(q, k, ending_ray_[k]);
    }
  }
  ending_count_ = 0;
}

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::endRays(Registers& r, const Constants& c, unsigned active, unsigned stopped,
                                  unsigned moved_on) {
  Lanes& l = lanes_;
  storeMoved(r, l);
  storeAccumulator(r, l);
  for (unsigned done = stopped | moved_on; done != 0; done &= done - 1) {
    const int lane = __builtin_ctz(done);
    if ((stopped >> lane) & 1u) {
      emit(ray_[lane], accumulator(lanes_, lane));
    } else {
      queueEnding(lane);
      if (ending_count_ == kLanes) endQueued(r, c);
    }
    park(lane);
    active &= ~(1u << lane);
  }
  while (active == 0 && next_ < ends_.size()) active = enterPacket();
  if (active == 0 && ending_count_ > 0) endQueued(r, c);
  return active;
}

/// The packet walk over the lanes S, with the counts if `counts` is not empty (a walk of its
/// own: one without them pays nothing for them).
template <class S>
void walkPackets(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends, const VoxelLattice& lattice,
                 const SnapshotView& view, std::span<RaySums> out, std::span<RayCounts> counts) {
  if (!counts.empty()) {
    IgPacketWalk<S, true>(origin, ends, lattice, view, out, counts).run();
  } else {
    IgPacketWalk<S, false>(origin, ends, lattice, view, out, counts).run();
  }
}

}  // namespace
}  // namespace nbv::kernels::detail
