#pragma once
// Private, part of ig_rays_packet.hpp (included there after ig_packet_enter.hpp): the packet
// steps in the registers: run(), the loads and stores of the lanes' state, a voxel's visit,
// the runs crossed in closed form (repeatUniform(), repeatRun(), crossRun()) and the next
// border crossing (advance()).

namespace nbv::kernels::detail {
namespace {

template <class S, bool kCounts>
IgPacketWalk<S, kCounts>::Constants::Constants(const SnapshotView& view)
    : one(D(1.0)), zero(S::zero()), half(D(0.5)), two(D(2.0)),
      minus_infinity(D(-std::numeric_limits<double>::infinity())), two_52(D(0x1p52)),
      two_52_and_1(D(0x1p52 + 1.0)), two_52_bits(bitsOf(two_52)), exponent_0(I(1023)),
      exponent_1(I(1024)), unknown_bit(I(static_cast<std::int64_t>(voxel_flag::kUnknown))),
      free_bit(I(static_cast<std::int64_t>(voxel_flag::kFree))),
      stop_bit(I(static_cast<std::int64_t>(voxel_flag::kStop))),
      occupied_bit(I(static_cast<std::int64_t>(voxel_flag::kOccupied))),
      marked_bit(I(static_cast<std::int64_t>(voxel_flag::kMarked))),
      seen_bits(I(static_cast<std::int64_t>(voxel_flag::kMeasured | voxel_flag::kMarked))),
      measured_bit(I(static_cast<std::int64_t>(voxel_flag::kMeasured))),
      frontier_bit(I(static_cast<std::int64_t>(voxel_flag::kFrontier))),
      pending(I(static_cast<std::int64_t>(AreaClass::Pending))),
      area_occupied(I(static_cast<std::int64_t>(AreaClass::Occupied))),
      area_occplane(I(static_cast<std::int64_t>(AreaClass::Occplane))),
      area_none(I(static_cast<std::int64_t>(AreaClass::None))),
      index_bits(I(static_cast<std::int64_t>(kMaxPaletteSize - 1))),
      distance_bits(I(static_cast<std::int64_t>(kMaxRunDistance))), voxels(view.voxels),
      table(&view.palette[0].entropy), uniform_h(D(view.palette[0].entropy)),
      uniform_keep(D(view.palette[0].keep)), uniform_proximity(D(view.palette[0].proximity)),
      uniform_flags(I(static_cast<std::int64_t>(view.palette[0].flags))),
      uniform_unknown(has(uniform_flags, unknown_bit)), uniform_frontier(has(uniform_flags, frontier_bit)) {
  static_assert(sizeof(VoxelTerms) == 4 * sizeof(double));
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::run() {
  unsigned active = 0;
  while (active == 0 && next_ < ends_.size()) active = enterPacket();
  const Constants c(view_);
  while (active != 0) {
    Registers r;
    loadWalk(r, lanes_);
    loadAccumulator(r, lanes_);
    r.inv_x = c.one / r.dx;
    r.inv_y = c.one / r.dy;
    r.inv_z = c.one / r.dz;
    if (settled_ != 0) startSettled(r, c);
    unsigned stopped = 0, moved_on = 0;
    while ((stopped | moved_on) == 0) moved_on = step(r, c, active, stopped);
    active = endRays(r, c, active, stopped, moved_on);
  }
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::loadWalk(Registers& r, const Lanes& src) {
#define NBV_LOAD_LANE(name, kind, moves) r.name = load##kind(src.name);
#define NBV_LOAD_AXES(name, x, y, z, moves) \
  r.x = S::load(src.name[0]);               \
  r.y = S::load(src.name[1]);               \
  r.z = S::load(src.name[2]);
  NBV_PACKET_WALK_FIELDS(NBV_LOAD_LANE, NBV_LOAD_AXES, NBV_WALK_NONE, NBV_WALK_NONE)
#undef NBV_LOAD_LANE
#undef NBV_LOAD_AXES
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::storeMoved(const Registers& r, Lanes& dst) {
#define NBV_STORE_LANE(name, kind, moves) \
  if constexpr (moves) store##kind(dst.name, r.name);
#define NBV_STORE_AXES(name, x, y, z, moves) \
  if constexpr (moves) {                     \
    S::store(dst.name[0], r.x);              \
    S::store(dst.name[1], r.y);              \
    S::store(dst.name[2], r.z);              \
  }
  NBV_PACKET_WALK_FIELDS(NBV_STORE_LANE, NBV_STORE_AXES, NBV_WALK_NONE, NBV_WALK_NONE)
#undef NBV_STORE_LANE
#undef NBV_STORE_AXES
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::loadAccumulator(Registers& r, const Lanes& src) {
#define NBV_LOAD_COLUMN(name, type, initial, kind) r.name = load##kind(src.name);
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_LOAD_COLUMN)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_LOAD_COLUMN)
  }
#undef NBV_LOAD_COLUMN
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::storeAccumulator(const Registers& r, Lanes& dst) {
#define NBV_STORE_COLUMN(name, type, initial, kind) store##kind(dst.name, r.name);
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_STORE_COLUMN)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_STORE_COLUMN)
  }
#undef NBV_STORE_COLUMN
}

template <class S, bool kCounts>
template <class Go>
unsigned IgPacketWalk<S, kCounts>::visit(Registers& r, const Constants& c, D h, D keep, D proximity, I flags, Go go,
                                unsigned go_bits) {
  const D term = r.visibility * h;
  const M unknown = has(flags, c.unknown_bit);
  r.entropy = addIn(go, r.entropy, h);
  r.oa = addIn(go, r.oa, term);                                     // Eq. 6
  r.uv = addWhere(within(go, unknown), r.uv, term);                 // Eq. 8
  if constexpr (kCounts) {
    r.unknown = addWhere(within(go, unknown), r.unknown, c.one);                       // uc
    r.frontier = addWhere(within(go, has(flags, c.frontier_bit)), r.frontier, c.one);  // fv
  }
  r.run_before = pick(go, r.run, r.run_before);
  r.run = pick(go, addOrZero(unknown, r.run, term), r.run);         // Eq. 10's run
  r.last_term = pick(go, term, r.last_term);
  r.pc = addIn(go, r.pc, proximity);                                // Eq. 11
  // Eqs. 17-20: a pending ray is classified by a marked or an occupied voxel.
  const M is_pending = within(go, r.area == c.pending);
  const M after_free = r.previous_free & (r.voxels > c.zero);
  I classified = select(has(flags, c.occupied_bit), select(after_free, c.area_occupied, c.area_none), c.pending);
  classified = select(has(flags, c.marked_bit), c.area_occplane, classified);
  r.area = select(is_pending, classified, r.area);
  r.seen_measured = r.seen_measured | within(go, has(flags, c.measured_bit));
  r.previous_free = pick(go, has(flags, c.free_bit) | andNot(hasNone(flags, c.seen_bits), r.seen_measured),
                         r.previous_free);
  r.previous_flags = pick(go, r.last_flags, r.previous_flags);
  r.last_flags = pick(go, flags, r.last_flags);
  r.voxels = addIn(go, r.voxels, c.one);
  r.visibility = pick(go, r.visibility * keep, r.visibility);  // Eq. 5
  return (has(flags, c.stop_bit) | r.is_last).bits() & go_bits;
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::repeatWith(Registers& r, D n, D h, D proximity, I flags, M unknown, M frontier, D keep_n,
                                          D keep_n1, D decay_sum) {
  const M repeated = n > D(0.0);
  const D terms = (r.visibility * h) * decay_sum;
  r.entropy += n * h;
  r.oa += terms;
  r.uv = addWhere(unknown, r.uv, terms);
  if constexpr (kCounts) {
    r.unknown = addWhere(unknown, r.unknown, n);
    r.frontier = addWhere(frontier, r.frontier, n);
  }
  const D run_last = (r.visibility * keep_n1) * h;
  const D run_sum = addOrZero(unknown, r.run, terms);
  r.last_term = select(repeated, run_last, r.last_term);
  r.run = select(repeated, run_sum, r.run);
  r.run_before = select(repeated, zeroUnless(unknown, run_sum - run_last), r.run_before);
  r.pc += n * proximity;
  r.previous_flags = select(repeated, flags, r.previous_flags);
  r.voxels += n;
  r.visibility *= keep_n;
}

template <class S, bool kCounts>
template <bool kAnyCount>
void IgPacketWalk<S, kCounts>::repeatUniform(Registers& r, const Constants& c, D n) {
  // n = 0 changes nothing. keep = 0.5: keep^n and keep^(n - 1) exactly, from exponent bits, as
  // powerOfHalf() gives them (and runPower(), which multiplies powers of two exactly). Runs (at
  // most 30 crossings per axis) take the short form; the closed forms before and after the box
  // take kAnyCount: there 2^-n may be subnormal or 0 (powerOfHalf()'s std::ldexp()), the
  // product of two normal powers 2^-floor(n/2) 2^-(n - floor(n/2)), correctly rounded once.
  D keep_n, keep_n1;
  if constexpr (kAnyCount) {
    const D capped = min(n, D(2000.0));  // (powerOfHalf()'s cap: 0 either way)
    const D low = floor(capped * c.half);
    const I low_bits = bitsOf(low + c.two_52) - c.two_52_bits;
    const I high_bits = bitsOf((capped - low) + c.two_52) - c.two_52_bits;
    const D low_power = fromBits(shiftLeft<52>(c.exponent_0 - low_bits));
    keep_n = low_power * fromBits(shiftLeft<52>(c.exponent_0 - high_bits));
    keep_n1 = low_power * fromBits(shiftLeft<52>(c.exponent_1 - high_bits));
  } else {
    const I n_bits = bitsOf(n + c.two_52) - c.two_52_bits;
    keep_n = fromBits(shiftLeft<52>(c.exponent_0 - n_bits));
    keep_n1 = fromBits(shiftLeft<52>(c.exponent_1 - n_bits));
  }
  // (1 - keep^n) / (1 - keep) with keep = 0.5: a division by 0.5, exactly a product by 2.
  repeatWith(r, n, c.uniform_h, c.uniform_proximity, c.uniform_flags, c.uniform_unknown, c.uniform_frontier, keep_n,
             keep_n1, (c.one - keep_n) * c.two);
}

template <class S, bool kCounts>
template <bool kUniform>
void IgPacketWalk<S, kCounts>::repeatRun(Registers& r, const Constants& c, D n, const SnapshotEntry (&e)[kLanes]) {
  if constexpr (kUniform) {
    repeatUniform<false>(r, c, n);
  } else {
    // The lanes' terms again (not kept in registers through the step), then runPower() of n
    // and of n - 1 (0 where n is 0: unused there), lane by lane.
    D h, keep, proximity;
    I flags;
    termsOf(c, e, h, keep, proximity, flags);
    const I n_bits = bitsOf(n + c.two_52) - c.two_52_bits;
    const I n1_bits = bitsOf(max(n - c.one, c.zero) + c.two_52) - c.two_52_bits;
    D square = keep, keep_n = c.one, keep_n1 = c.one;
    for (unsigned k = 0; k < kRunPowerBits; ++k) {
      const I bit(static_cast<std::int64_t>(1) << k);
      keep_n = select(has(n_bits, bit), keep_n * square, keep_n);
      keep_n1 = select(has(n1_bits, bit), keep_n1 * square, keep_n1);
      square = square * square;
    }
    const D decay_sum = select(keep == c.one, n, (c.one - keep_n) / (c.one - keep));
    repeatWith(r, n, h, proximity, flags, has(flags, c.unknown_bit), has(flags, c.frontier_bit), keep_n, keep_n1,
               decay_sum);
  }
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::termsOf(const Constants& c, const SnapshotEntry (&e)[kLanes], D& h, D& keep, D& proximity,
                              I& flags) {
  h = c.uniform_h;
  keep = c.uniform_keep;
  proximity = c.uniform_proximity;
  flags = c.uniform_flags;
  SnapshotEntry any = 0;
  for (int i = 0; i < kLanes; ++i) any |= e[i];
  if ((any & (kMaxPaletteSize - 1)) != 0) {
    const double* row[kLanes];
    for (int i = 0; i < kLanes; ++i) row[i] = c.table + 4 * paletteIndex(e[i]);
    typename S::D columns[4];
    S::transposeRows(row, columns);  // VoxelTerms: entropy, keep, proximity, flags
    h = columns[0];
    keep = columns[1];
    proximity = columns[2];
    flags = S::bitsOf(columns[3]);
  }
}

template <class S, bool kCounts>
typename IgPacketWalk<S, kCounts>::M IgPacketWalk<S, kCounts>::pastLength(const Registers& r) {
  return Dda::pastLength(r.tx, r.ty, r.tz, r.length);
}

template <class S, bool kCounts>
void IgPacketWalk<S, kCounts>::startSettled(Registers& r, const Constants& c) {
  const M settled = M::of(settled_);
#define NBV_INITIAL_LANES(name, type, initial, kind) r.name = initialWhere##kind(settled, r.name, initial);
  NBV_RAY_ACCUMULATOR_FIELDS(NBV_INITIAL_LANES)
  if constexpr (kCounts) {
    NBV_RAY_COUNT_FIELDS(NBV_INITIAL_LANES)
  }
#undef NBV_INITIAL_LANES
  const D before = zeroUnless(settled, loadD(settled_before_));
  const M first = settled & (before > c.zero);
  visit(r, c, c.uniform_h, c.uniform_keep, c.uniform_proximity, c.uniform_flags, first, 0u);
  repeatUniform<true>(r, c, before - zeroUnless(first, c.one));
  settled_ = 0;
}

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::step(Registers& r, const Constants& c, unsigned active, unsigned& stopped) const {
  // The current voxel: its entry, then (unless all lanes are empty) its terms.
  alignas(64) SnapshotEntry e[kLanes];
  const I entries = S::loadEntries(c.voxels, r.offset, e);
  D h, keep, proximity;
  I flags;
  termsOf(c, e, h, keep, proximity, flags);
  stopped = visit(r, c, h, keep, proximity, flags, EveryLane{}, active);

  // A run of voxels of the lane's state: a run distance of 2 or more in the lane's octant (the
  // distance less one as a double: 2^52 + d holds d in its low bits).
  const I distance = (entries >> r.run_shift) & c.distance_bits;
  const D run_steps = fromBits(distance | c.two_52_bits) - c.two_52_and_1;
  const unsigned runners = (run_steps > c.zero).bits() & active & ~stopped;
  unsigned run_over = 0;
  if (runners != 0) [[likely]] {  // (a layout hint: a quarter of the steps run)
    // Runs of unmeasured voxels (most of an object's box) by their constants; runs of other
    // states (most of a room's or a building's) by their terms.
    if ((hasNone(entries, c.index_bits).bits() & runners) == runners) [[likely]] {
      run_over = crossRun<true>(r, c, lanes_, run_steps, runners, e);
    } else [[unlikely]] {
      run_over = crossRun<false>(r, c, lanes_, run_steps, runners, e);
    }
  }
  return (advance(r, c, active) | run_over) & ~stopped;
}

template <class S, bool kCounts>
template <bool kUniform>
unsigned IgPacketWalk<S, kCounts>::crossRun(Registers& r, const Constants& c, const Lanes& l, D run_steps, unsigned runners,
                                            const SnapshotEntry (&e)[kLanes]) {
  // walkRayScalar's run, lane by lane: every border crossing before runEnd(), each axis on its
  // own, then the voxels crossed into in closed form.
  D t_end = loadD(l.run_stop);
  t_end = min(r.tx + (min(run_steps, r.left_x) - c.half) * r.dx, t_end);
  t_end = min(r.ty + (min(run_steps, r.left_y) - c.half) * r.dy, t_end);
  t_end = min(r.tz + (min(run_steps, r.left_z) - c.half) * r.dz, t_end);
  t_end = select(M::of(runners), t_end, c.minus_infinity);
  // A run whose first crossing is not before t_end changes nothing (at the box's faces and
  // before the end key's slab). Four lanes test whether every runner's is; eight rarely skip.
  if (kLanes > 4 || (min(min(r.tx, r.ty), r.tz) < t_end).bits() != 0) {
    // Each axis's border times as one chain of sums; t_max keeps the first one not before
    // t_end (the walk's state after the run). The chains run on past t_end, unused:
    // S::kRunBlock sums per axis without a branch, then one test whether any lane has
    // crossings left (its exit is the one mispredicted branch of a run).
    const D start_x = r.tx, start_y = r.ty, start_z = r.tz;
    D nx = r.tx, ny = r.ty, nz = r.tz;
    do {
#pragma GCC unroll 8
      for (int k = 0; k < S::kRunBlock; ++k) {
        const M mx = nx < t_end, my = ny < t_end, mz = nz < t_end;
        nx += r.dx;
        ny += r.dy;
        nz += r.dz;
        r.tx = select(mx, nx, r.tx);
        r.ty = select(my, ny, r.ty);
        r.tz = select(mz, nz, r.tz);
      }
    } while (((r.tx < t_end) | (r.ty < t_end) | (r.tz < t_end)).bits() != 0);
    // The crossings taken, from the border times: t_max moved by count sums of t_delta, each
    // rounded by at most half an ulp of t_max, so (t_after - t_before) / t_delta lies within
    // 1e-9 of the count (at most 30 crossings per axis, t_max / t_delta below 2^17:
    // 30 * 2^-52 * 2^17 < 1e-9).
    const D cx = zeroUnless(start_x < r.tx, round((r.tx - start_x) * r.inv_x));
    const D cy = zeroUnless(start_y < r.ty, round((r.ty - start_y) * r.inv_y));
    const D cz = zeroUnless(start_z < r.tz, round((r.tz - start_z) * r.inv_z));
    r.offset += (cx * r.ox + cy * r.oy) + cz * r.oz;
    r.left_x -= cx;
    r.left_y -= cy;
    r.left_z -= cz;
    const D crossed = (cx + cy) + cz;
    // As the walk's length test: a lane past the segment after its last crossing ends before
    // the voxel it crossed into; its end voxel follows at the end of the walk.
    const M over = (crossed > c.zero) & pastLength(r);
    repeatRun<kUniform>(r, c, crossed - zeroUnless(over, c.one), e);
    return over.bits();
  }
  return 0;
}

template <class S, bool kCounts>
unsigned IgPacketWalk<S, kCounts>::advance(Registers& r, const Constants& c, unsigned active) {
  // One DDA step (border time and offset), then the steps left in the box along its axis.
  const typename Dda::Moves move = Dda::step(r.tx, r.ty, r.tz, r.dx, r.dy, r.dz, r.offset, r.ox, r.oy, r.oz);
  r.left_x = subWhere(move.x, r.left_x, c.one);
  r.left_y = subWhere(move.y, r.left_y, c.one);
  r.left_z = subUnless(move.x_or_y, r.left_z, c.one);
  const M past = pastLength(r);
  const M outside = min(min(r.left_x, r.left_y), r.left_z) < c.zero;
  // (An offset outside the box may alias one inside: only a lane inside has reached.)
  const M reached = andNot(r.offset == r.end_offset, outside);
  r.is_last = reached;
  return andNot(past | outside, reached).bits() & active;
}

}  // namespace
}  // namespace nbv::kernels::detail
