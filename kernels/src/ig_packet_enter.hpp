#pragma once
// Private, part of ig_rays_packet.hpp (included there after ig_packet_walk.hpp): how rays enter
// the lanes (enterPacket(), startAlone(), the skip to the box), how a lane is parked, and how a
// lane's state moves between the lanes, the queue of rays to end and the scalar accumulator.

namespace nbv::kernels::detail {
namespace {

template <class S, bool kCounts>
RayAccumulator IgPacketWalk<S, kCounts>::accumulator(const Lanes& l, int lane) {
  RayAccumulator acc;
#define NBV_FROM_COLUMN(name, type, initial, kind) acc.name = fromColumn##kind<type>(l.name[lane]);
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_FROM_COLUMN)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_FROM_COLUMN)
  }
#undef NBV_FROM_COLUMN
  return acc;
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::storeAccumulator(int lane, const RayAccumulator& acc) {
#define NBV_TO_COLUMN(name, type, initial, kind) lanes_.name[lane] = toColumn##kind(acc.name);
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_TO_COLUMN)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_TO_COLUMN)
  }
#undef NBV_TO_COLUMN
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::park(int lane) {
  // What a lane outside `active` still does is masked out of every result, so its state only
  // has to stay harmless: its offset fixed inside the box (the entry loads), its visibility far
  // from subnormal numbers; nothing else needs resetting.
  Lanes& l = lanes_;
  l.offset[lane] = 0.0;
  for (int a = 0; a < 3; ++a) l.offset_step[a][lane] = 0.0;
  l.visibility[lane] = 1.0;
}

template <class S, bool kCounts>
typename IgPacketWalk<S, kCounts>::M IgPacketWalk<S, kCounts>::mayEnterLanes(const D end[3]) const {
  const D zero = S::zero();
  if (view_.size[0] == 0 || view_.size[1] == 0 || view_.size[2] == 0) return zero < zero;
  M may_enter = zero == zero;
  D t_in = zero, t_out(1.0);
  for (int a = 0; a < 3; ++a) {
    const double resolution = lattice_.resolution();
    const double lo = (view_.min[a] - 1) * resolution;
    const double hi = (view_.min[a] + static_cast<double>(view_.size[a]) + 1.0) * resolution;
    const double o = origin_[a];
    const D d = end[a] - D(o);
    const M flat = d == zero;  // the axis is skipped, or rules the ray out
    if (o < lo || o > hi) may_enter = andNot(may_enter, flat);
    const D inv_d = D(1.0) / d;
    const D t0 = D(lo - o) * inv_d, t1 = D(hi - o) * inv_d;
    const M swap = t0 > t1;
    const D near = select(swap, t1, t0), far = select(swap, t0, t1);
    t_in = select(flat, t_in, select(t_in < near, near, t_in));     // std::max(t_in, near)
    t_out = select(flat, t_out, select(far < t_out, far, t_out));  // std::min(t_out, far)
  }
  return may_enter & (t_in <= t_out);
}

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::skipLanes(const LaneRays& r, unsigned lanes, D t[3], D entry[3], D& steps) const {
  const D zero = S::zero(), one(1.0);
  // The crossings each axis needs before its index lies in the box: the origin is shared, so
  // they are too; a lane moving away from the box along such an axis is refused.
  unsigned refused = 0;
  int enter[3];
  for (int a = 0; a < 3; ++a) {
    const int lo = view_.min[a], hi = view_.min[a] + static_cast<int>(view_.size[a]) - 1;
    const int o = key_origin_[a];
    enter[a] = o < lo ? lo - o : (o > hi ? o - hi : 0);
    if (o < lo) refused |= ~(r.step[a] > zero).bits();
    if (o > hi) refused |= ~(r.step[a] < zero).bits();
  }
  // The time of each axis's entering crossing; the latest one is the entry step.
  D taken[3] = {zero, zero, zero};
  D t_entry(-1.0), last_axis(-1.0);
  M tie = zero < zero;
  for (int a = 0; a < 3; ++a) {
    t[a] = r.t_max[a];
    if (enter[a] == 0) continue;
    for (int k = 0; k < enter[a] - 1; ++k) t[a] += r.t_delta[a];
    taken[a] = D(enter[a] - 1);
    tie = tie | (t[a] == t_entry);
    const M later = t[a] > t_entry;
    t_entry = select(later, t[a], t_entry);
    last_axis = select(later, D(a), last_axis);
  }
  refused |= (tie | ~(t_entry <= r.length)).bits();
  const M skip = M::of(lanes & ~refused);
  // Every crossing before t_entry is taken (the entering one of the last axis included); an
  // axis the ray does not move along has t = DBL_MAX and takes none.
  tie = zero < zero;
  for (int a = 0; a < 3; ++a) {
    // As a run's chain in run(): the sums run on unused past t_entry, S::kRunBlock between two
    // tests, so that no compare waits on the last sum.
    const D t_stop = select(skip, t_entry, D(-std::numeric_limits<double>::infinity()));
    if ((t[a] < t_stop).bits() != 0) {
      D sum = t[a];
      do {
#pragma GCC unroll 8
        for (int k = 0; k < S::kRunBlock; ++k) {
          const M more = sum < t_stop;
          sum += r.t_delta[a];
          t[a] = select(more, sum, t[a]);
          taken[a] = addWhere(more, taken[a], one);
        }
      } while ((t[a] < t_stop).bits() != 0);
    }
    const M last = skip & (last_axis == D(a));
    t[a] = addWhere(last, t[a], r.t_delta[a]);
    taken[a] = addWhere(last, taken[a], one);
    tie = tie | andNot(t[a] == t_entry, last);
  }
  // Refused too: a tie with the entry step, an axis that left the box first, the end key on
  // the way, a length stop at the entry step.
  M bad = tie;
  M on_the_way = zero == zero;
  for (int a = 0; a < 3; ++a) {
    const D lo(view_.min[a]), hi(view_.min[a] + static_cast<double>(view_.size[a]) - 1.0);
    const D o(key_origin_[a]);
    entry[a] = o + r.step[a] * taken[a];
    bad = bad | ((entry[a] < lo) | (entry[a] > hi));
    on_the_way = on_the_way & ((min(o, entry[a]) <= r.key_end[a]) & (r.key_end[a] <= max(o, entry[a])));
  }
  bad = bad | (on_the_way | ~(min(min(t[0], t[1]), t[2]) <= r.length));
  steps = (taken[0] + taken[1]) + taken[2];
  return (refused | bad.bits()) & lanes;
}

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::enterPacket() {
  const int n = static_cast<int>(std::min<std::size_t>(kLanes, ends_.size() - next_));
  alignas(64) float end_lanes[3][kLanes];  // unused lanes repeat the last ray (and are parked)
  for (int i = 0; i < kLanes; ++i) {
    ray_[i] = next_ + static_cast<std::size_t>(std::min(i, n - 1));
    for (int a = 0; a < 3; ++a) end_lanes[a][i] = ends_[ray_[i]][a];
  }
  next_ += static_cast<std::size_t>(n);
  const typename S::F end_single[3] = {S::loadF(end_lanes[0]), S::loadF(end_lanes[1]), S::loadF(end_lanes[2])};
  const D end[3] = {S::toDouble(end_single[0]), S::toDouble(end_single[1]), S::toDouble(end_single[2])};

  // enterSnapshot(), lane by lane; the rays it leaves to the scalar code (alone) are few.
  LaneRays r;
  const unsigned lanes = (1u << n) - 1u;
  const typename S::F origin[3] = {S::set1F(origin_[0]), S::set1F(origin_[1]), S::set1F(origin_[2])};
  unsigned alone = Dda::setup(origin, end_single, lattice_, r).bits() & lanes;  // one voxel: the end point's
  D t[3] = {r.t_max[0], r.t_max[1], r.t_max[2]};
  D entry[3] = {D(key_origin_[0]), D(key_origin_[1]), D(key_origin_[2])};
  D before = S::zero();
  if (!view_.contains(key_origin_)) {  // else every ray starts in the box
    alone |= ~mayEnterLanes(end).bits() & lanes;
    if ((lanes & ~alone) != 0) alone |= skipLanes(r, lanes & ~alone, t, entry, before);
  }

  // The walk's fields of the settled rays, as startAlone() sets them from enterSnapshot()'s
  // entry (view_.offset(), boxLeft(), runStop(), runDistanceShift()), lane by lane.
  Lanes& f = lanes_;
  const D zero = S::zero(), one(1.0), nan(kNoOffset);
  const D infinity(std::numeric_limits<double>::infinity());
  D offset = zero, end_offset = zero, enters_end(-std::numeric_limits<double>::infinity()), octant = zero;
  M end_inside = zero == zero;
  for (int a = 0; a < 3; ++a) {
    const D lo(view_.min[a]), hi(view_.min[a] + static_cast<double>(view_.size[a]) - 1.0);
    const D stride(stride_[a]);
    offset += (entry[a] - lo) * stride;
    end_offset += (r.key_end[a] - lo) * stride;
    end_inside = end_inside & ((lo <= r.key_end[a]) & (r.key_end[a] <= hi));
    const M forward = r.step[a] > zero, backward = r.step[a] < zero;
    S::store(f.t_max[a], t[a]);
    S::store(f.t_delta[a], r.t_delta[a]);
    S::store(f.offset_step[a], r.step[a] * stride);
    S::store(f.box_left[a], select(forward, hi - entry[a], select(backward, entry[a] - lo, infinity)));
    S::store(f.key_end[a], r.key_end[a]);
    // runStop(): std::max(enters_end, ...) over the axes whose end key lies ahead.
    const D crossings = (r.key_end[a] - D(key_origin_[a])) * r.step[a];
    const D enters = r.t_max[a] + (crossings - D(1.5)) * r.t_delta[a];
    enters_end = select((one <= crossings) & (enters_end < enters), enters, enters_end);
    octant += zeroUnless(backward, D(1 << a));
  }
  S::store(f.offset, offset);
  S::store(f.end_offset, select(end_inside, end_offset, nan));
  S::store(f.length, r.length);
  S::store(f.run_stop, select(enters_end < r.length, enters_end, r.length));  // std::min(length, ...)
  alignas(64) double octants[kLanes];
  S::store(octants, octant);
  S::store(settled_before_, before);
  unsigned active = 0;
  settled_ = 0;
  for (int i = 0; i < kLanes; ++i) {
    if (i >= n) {
      park(i);
      continue;
    }
    if ((alone >> i) & 1u) {
      if (startAlone(i)) active |= 1u << i;
      continue;
    }
    f.run_shift[i] = runDistanceShift(static_cast<unsigned>(octants[i]));
    f.is_last[i] = 0;
    settled_ |= 1u << i;
    active |= 1u << i;
  }
  return active;
}

template <class S, bool kCounts>
bool IgPacketWalk<S, kCounts>::startAlone(int lane) {
  RayEntry entry;
  const std::size_t i = ray_[lane];
  if (!enterSnapshot(origin_, ends_[i], lattice_, view_, entry)) {
    emit(i, entry.acc);
    park(lane);
    return false;
  }
  // Its fields as enterPacket() sets them lane by lane.
  const RaySetup& s = entry.setup;
  Lanes& l = lanes_;
  l.offset[lane] = static_cast<double>(view_.offset(entry.ijk));
  l.end_offset[lane] = view_.contains(s.key_end) ? static_cast<double>(view_.offset(s.key_end)) : kNoOffset;
  for (int a = 0; a < 3; ++a) {
    l.t_max[a][lane] = entry.t_max[a];
    l.t_delta[a][lane] = s.t_delta[a];
    l.offset_step[a][lane] = s.step[a] * stride_[a];
    l.box_left[a][lane] = boxLeft(view_, s, entry.ijk, a);
    l.key_end[a][lane] = s.key_end[a];
  }
  l.length[lane] = s.length;
  l.run_stop[lane] = runStop(s);
  l.run_shift[lane] = runDistanceShift(octantOf(s.step));
  l.is_last[lane] = entry.at_end ? -1 : 0;
  storeAccumulator(lane, entry.acc);
  return true;
}

template <class S, bool kCounts>
RaySetup IgPacketWalk<S, kCounts>::setupOf(const Lanes& l, int lane) const {
  RaySetup s;
  s.key_origin = key_origin_;
  for (int a = 0; a < 3; ++a) {
    s.key_end[a] = static_cast<int>(l.key_end[a][lane]);
    s.step[a] = l.offset_step[a][lane] > 0.0 ? 1 : (l.offset_step[a][lane] < 0.0 ? -1 : 0);
    s.t_max[a] = l.t_max[a][lane];
    s.t_delta[a] = l.t_delta[a][lane];
  }
  s.length = l.length[lane];
  return s;
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::finishWalkedTail(const Lanes& l, int lane, std::size_t ray) {
  RayAccumulator acc = accumulator(l, lane);
  // The voxel outside, from the steps left in the box per axis (-1 along the exit axis; an
  // axis the ray does not move along keeps the origin's index).
  const RaySetup s = setupOf(l, lane);
  Index3 ijk;
  for (int a = 0; a < 3; ++a) {
    if (s.step[a] == 0) {
      ijk[a] = s.key_origin[a];  // (its steps left are infinite)
      continue;
    }
    const auto left = static_cast<int>(l.box_left[a][lane]);
    ijk[a] = s.step[a] > 0 ? view_.min[a] + static_cast<int>(view_.size[a]) - 1 - left : view_.min[a] + left;
  }
  const double t_max[3] = {l.t_max[0][lane], l.t_max[1][lane], l.t_max[2][lane]};
  finishOutside(acc, view_, s, ijk, t_max);
  emit(ray, acc);
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::queueEnding(int lane) {
  const int k = ending_count_++;
  ending_ray_[k] = ray_[lane];
  copyWalk(lanes_, lane, ending_, k);
  copyAccumulator(lanes_, lane, ending_, k);
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::copyWalk(const Lanes& src, int from, Lanes& dst, int to) {
#define NBV_COPY_COLUMN(name, ...) dst.name[to] = src.name[from];
#define NBV_COPY_COLUMNS(name, ...) \
  for (int a = 0; a < 3; ++a) dst.name[a][to] = src.name[a][from];
  NBV_PACKET_WALK_FIELDS(NBV_COPY_COLUMN, NBV_COPY_COLUMNS, NBV_COPY_COLUMN, NBV_COPY_COLUMNS)
#undef NBV_COPY_COLUMN
#undef NBV_COPY_COLUMNS
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::copyAccumulator(const Lanes& src, int from, Lanes& dst, int to) {
#define NBV_COPY_COLUMN(name, type, initial, kind) dst.name[to] = src.name[from];
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_COPY_COLUMN)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_COPY_COLUMN)
  }
#undef NBV_COPY_COLUMN
}

}  // namespace
}  // namespace nbv::kernels::detail
