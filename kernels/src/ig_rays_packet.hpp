#pragma once
// Private: the packet walk of the IG rays, written once over the register types of a lane
// width S (simd_avx2.hpp: 4 rays, simd_avx512.hpp: 8 rays), in the operators of their value
// types (lane_values.hpp: a + b, a < b, m & ~n, select(m, a, b)), as the scalar walk reads. Each lane runs the DDA of
// traverseRayKeys() (LaneDda, dda_lanes.hpp, as the mark walks do) and the accumulator of
// RayAccumulator::add() with the same double operations in the same order, so every ray's
// sums equal the scalar walk's bit for bit.
//
// Rays enter a packet at a time through enterPacket() (enterSnapshot() lane by lane: the
// set-up, the slab test and the skip to the box; the closed-form run before the box follows in
// the lanes), and the packet walks until its last ray has ended, lanes whose ray ended parked:
// rays next to each other in the caller's order (IgEvaluator's Morton order of the pixels)
// cross nearly the same voxels, so the lanes take their runs in the same steps. A ray that
// stops ends in its lane. One that reaches its end voxel or leaves the box waits in a queue
// (ending_) until a packet's worth have, and they then end together in the lanes
// (the closed-form run after the box, lane by lane; a tail tailVoxels() would walk goes to
// finishWalkedTail()): ending them as they come, one or two at a time, would leave most
// lanes idle.
// Inside the box a lane carries its voxel as an offset (a double, exact for boxes below 2^31
// voxels) and, per axis, the steps left before it leaves the box. Each step loads the lanes'
// entries and their VoxelTerms rows. A lane on a voxel whose run distance in its ray's octant
// says the voxels ahead of it hold its state too crosses them as walkRayScalar() does: every
// border crossing before runEnd(), each axis's border times summed one by one as the walk sums
// them, and the voxels crossed into added in closed form (RayAccumulator::addRepeats, its
// powers by runPower()'s products), so the bits are the scalar walk's.
//
// Included by one source per lane width, after ig_rays_impl.hpp and inside that source's
// target options. The walk has internal linkage: each source has its own copy, inlined into
// its entry point, and no call goes through the shared library's symbol table.

#include "dda_lanes.hpp"
#include "ig_rays_impl.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace nbv::kernels::detail {
namespace {

template <class S, bool kCounts>
class IgPacketWalk {
  static constexpr int kLanes = S::kLanes;
  static constexpr unsigned kAllLanes = (1u << kLanes) - 1u;
  using D = LaneDoubles<S>;
  using I = LaneInts<S>;
  using M = LaneMask<S>;
  using Dda = LaneDda<S>;
  using LaneRays = typename Dda::Setup;

 public:
  /// The walk of the rays origin -> ends[i]: their sums to out[i] and, with kCounts, their
  /// counts to counts[i].
  IgPacketWalk(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends, const VoxelLattice& lattice,
               const SnapshotView& view, std::span<RaySums> out, std::span<RayCounts> counts)
      : origin_(origin), ends_(ends), lattice_(lattice), view_(view), out_(out), counts_(counts),
        stride_{1.0, static_cast<double>(view.size[0]), static_cast<double>(view.size[0]) * view.size[1]},
        key_origin_(lattice.worldToIndex(origin)) {}

  void run();

 private:
  // The column types of the lane kinds: doubles, integers, flags as 0 or -1.
  using ColumnD = double;
  using ColumnI = std::int64_t;
  using ColumnM = std::int64_t;

  // The walk's fields of a lane, one list from which the columns of Lanes, the registers, their
  // loads, the stores after a packet's steps and the copies follow (the accumulator's fields
  // are NBV_RAY_ACCUMULATOR_FIELDS):
  //   LANE(name, kind, moves): a column, and a register `name` of lane kind D, I or M;
  //   AXES(name, x, y, z, moves): a column per axis, and a register per axis;
  //   MEMORY(name), MEMORY_AXES(name): a column, or one per axis, only: read where needed.
  // `moves`: the walk changes it, so it goes back to its column after the packet's steps.
  // end_offset is NaN (equal to no offset) when the end voxel lies outside the box;
  // offset_step[a] is step[a] * stride[a]; box_left[a] the steps along axis a before the walk
  // leaves the box; run_shift the runDistanceShift() of the ray's octant; is_last is set when
  // the current voxel is the ray's end voxel; run_stop is runStop() (runs end
  // before it).
#define NBV_PACKET_WALK_FIELDS(LANE, AXES, MEMORY, MEMORY_AXES) \
  LANE(offset, D, true)                            \
  LANE(end_offset, D, false)                       \
  AXES(t_max, tx, ty, tz, true)                    \
  AXES(t_delta, dx, dy, dz, false)                 \
  AXES(offset_step, ox, oy, oz, false)             \
  AXES(box_left, left_x, left_y, left_z, true)     \
  LANE(length, D, false)                           \
  LANE(run_shift, I, false)                        \
  LANE(is_last, M, true)                           \
  MEMORY_AXES(key_end)                             \
  MEMORY(run_stop)
#define NBV_WALK_NONE(...)

  /// The lanes' state, a column per lane, spilled to memory only when a lane's ray ends (also
  /// the layout of the rays waiting to end, ending_): the walk's fields, then the accumulator's.
  struct alignas(64) Lanes {
#define NBV_WALK_COLUMN(name, kind, moves) Column##kind name[kLanes];
#define NBV_WALK_AXES(name, x, y, z, moves) double name[3][kLanes];
#define NBV_WALK_MEMORY(name) double name[kLanes];
#define NBV_WALK_MEMORY_AXES(name) double name[3][kLanes];
    NBV_PACKET_WALK_FIELDS(NBV_WALK_COLUMN, NBV_WALK_AXES, NBV_WALK_MEMORY, NBV_WALK_MEMORY_AXES)
#undef NBV_WALK_COLUMN
#undef NBV_WALK_AXES
#undef NBV_WALK_MEMORY
#undef NBV_WALK_MEMORY_AXES
#define NBV_LANE_COLUMN(name, type, initial, kind) Column##kind name[kLanes];
    NBV_RAY_ACCUMULATOR_FIELDS(NBV_LANE_COLUMN)
    NBV_RAY_COUNT_FIELDS(NBV_LANE_COLUMN)
#undef NBV_LANE_COLUMN
  };
  /// The lanes' state in registers while a packet walks: the walk's fields (by axis), the
  /// accumulator's, and what the walk derives from them.
  struct Registers {
#define NBV_WALK_REGISTER(name, kind, moves) kind name;
#define NBV_WALK_AXIS_REGISTERS(name, x, y, z, moves) D x, y, z;
    NBV_PACKET_WALK_FIELDS(NBV_WALK_REGISTER, NBV_WALK_AXIS_REGISTERS, NBV_WALK_NONE, NBV_WALK_NONE)
#undef NBV_WALK_REGISTER
#undef NBV_WALK_AXIS_REGISTERS
#define NBV_LANE_REGISTER(name, type, initial, kind) kind name;
    NBV_RAY_ACCUMULATOR_FIELDS(NBV_LANE_REGISTER)
    NBV_RAY_COUNT_FIELDS(NBV_LANE_REGISTER)
#undef NBV_LANE_REGISTER
    D inv_x, inv_y, inv_z;  ///< 1 / t_delta, for the crossing counts of runs (a parked lane's: unused)
  };

  /// What every packet step reads: the voxel flags and area classes as lanes, the terms of the
  /// empty voxel (palette[0]) that fills the world outside the box, and the closed forms'
  /// constants.
  struct Constants {
    explicit Constants(const SnapshotView& view);
    D one, zero, half, two, minus_infinity, two_52, two_52_and_1;
    I two_52_bits;               ///< n + 2^52 holds the integer n in its low bits
    I exponent_0, exponent_1;    ///< 2^-n: exponent 1023 - n; 2^-(n - 1): 1024 - n
    I unknown_bit, free_bit, stop_bit, occupied_bit, marked_bit, seen_bits, measured_bit, frontier_bit;
    I pending, area_occupied, area_occplane, area_none;
    I index_bits, distance_bits;  ///< of a SnapshotEntry
    const SnapshotEntry* voxels;
    const double* table;          ///< the palette: rows of 4 x 64 bits (VoxelTerms)
    D uniform_h, uniform_keep, uniform_proximity;
    I uniform_flags;
    M uniform_unknown, uniform_frontier;
  };

  // Column <-> register <-> scalar of each lane kind (NBV_RAY_ACCUMULATOR_FIELDS).
  static D loadD(const double* c) { return S::load(c); }
  static I loadI(const std::int64_t* c) { return S::loadI(c); }
  static M loadM(const std::int64_t* c) { return S::loadM(c); }
  static void storeD(double* c, D v) { S::store(c, v); }
  static void storeI(std::int64_t* c, I v) { S::storeI(c, v); }
  static void storeM(std::int64_t* c, M v) { S::storeM(c, v); }
  template <class T> static double toColumnD(T v) { return v; }
  template <class T> static std::int64_t toColumnI(T v) { return static_cast<std::int64_t>(v); }
  template <class T> static std::int64_t toColumnM(T v) { return v ? -1 : 0; }
  template <class T> static T fromColumnD(double v) { return v; }
  template <class T> static T fromColumnI(std::int64_t v) { return static_cast<T>(v); }
  template <class T> static T fromColumnM(std::int64_t v) { return v != 0; }
  /// A lane of each kind set to its field's initial value where `m` is set (a fresh ray).
  template <class T> static D initialWhereD(M m, D v, T initial) { return select(m, D(initial), v); }
  template <class T> static I initialWhereI(M m, I v, T initial) {
    return select(m, I(static_cast<std::int64_t>(initial)), v);
  }
  template <class T> static M initialWhereM(M m, M v, T initial) { return initial ? m | v : andNot(v, m); }

  /// Updates of the lanes' state in every lane (EveryLane) or in the lanes of a mask.
  struct EveryLane {};
  static D addIn(EveryLane, D a, D b) { return a + b; }
  static D addIn(M m, D a, D b) { return addWhere(m, a, b); }
  template <class V> static V pick(EveryLane, V updated, V) { return updated; }
  template <class V> static V pick(M m, V updated, V old) { return select(m, updated, old); }
  static M pick(M m, M updated, M old) { return (m & updated) | andNot(old, m); }
  static M within(EveryLane, M m) { return m; }
  static M within(M lanes, M m) { return lanes & m; }

  /// An end offset no walk reaches: a lane leaving the box can reach any small negative offset.
  static constexpr double kNoOffset = std::numeric_limits<double>::quiet_NaN();

  /// Enters the next kLanes rays (fewer at the end) into the lanes, which walk them together
  /// until the last one ends: neighbouring rays of the walk's order cross nearly the same
  /// voxels, so they take their runs in the same packet steps (lanes refilled one by one as
  /// each ray ends drift apart, and a run section then serves few of them). enterSnapshot()
  /// lane by lane, with its operations in its order, so the entries are its own bit for bit,
  /// and the walk's fields startAlone() would set from them (offsets, steps left in the box,
  /// runStop()...) lane by lane too. A ray the lanes cannot settle (one voxel, missing the
  /// box, refused by the skip) goes through startAlone(). Lanes without a ray are parked.
  /// Returns the lanes with a ray to walk.
  unsigned enterPacket();
  /// The ray ray_[lane] through enterSnapshot() into `lane`; a ray that never enters the box
  /// is finished and the lane parked (returns false).
  bool startAlone(int lane);
  /// mayEnter() of the lanes' rays.
  M mayEnterLanes(const D end[3]) const;
  /// skipToBox() of the rays in `lanes` (the origin outside the box): their border times,
  /// entry voxels and steps before it; returns the lanes it refuses.
  unsigned skipLanes(const LaneRays& r, unsigned lanes, D t[3], D entry[3], D& steps) const;
  // run()'s stages, always inlined into it so that the registers stay registers. (Called out
  // of line, GCC kept the walk's registers in memory.)
#define NBV_STAGE __attribute__((always_inline)) inline
  /// The lanes' state from the columns of `src` (lanes_, or the rays queued to end), and back
  /// (storeMoved(): the walk's fields that move).
  NBV_STAGE static void loadWalk(Registers& r, const Lanes& src);
  NBV_STAGE static void storeMoved(const Registers& r, Lanes& dst);
  NBV_STAGE static void loadAccumulator(Registers& r, const Lanes& src);
  NBV_STAGE static void storeAccumulator(const Registers& r, Lanes& dst);
  /// The rays enterPacket() settled start with the voxels of palette[0] before the box, as
  /// RayAccumulator::addUniform() adds them (the first visited, the others repeated).
  NBV_STAGE void startSettled(Registers& r, const Constants& c);
  /// One packet step: the current voxel's entries and terms visited, then a run of voxels of
  /// its state if the lanes are on one, then the next border crossing. Returns the lanes whose ray moved
  /// on (to its end voxel or out of the box); `stopped`: those whose ray stopped.
  NBV_STAGE unsigned step(Registers& r, const Constants& c, unsigned active, unsigned& stopped) const;
  /// RayAccumulator::add() lane-wise, in the lanes `go` (EveryLane, or a mask); returns the
  /// lanes of `go_bits` whose ray ends with this voxel (it stops the ray, or it was the end voxel).
  template <class Go>
  NBV_STAGE static unsigned visit(Registers& r, const Constants& c, D h, D keep, D proximity, I flags, Go go,
                                  unsigned go_bits);
  /// RayAccumulator::addRepeats() of palette[0] lane-wise, n (>= 0) voxels per lane, keep^n as
  /// powerOfHalf() gives it: any count (kAnyCount: the stretches before and after the box), or
  /// the short form for the counts of a run.
  template <bool kAnyCount>
  NBV_STAGE static void repeatUniform(Registers& r, const Constants& c, D n);
  /// RayAccumulator::addRepeats() of a run lane-wise, n (0 to 2^kRunPowerBits - 1) voxels per
  /// lane: of palette[0] in every lane (kUniform: keep^n from exponent bits), or of the terms of
  /// the lanes' entries `e` (keep^n by runPower()).
  template <bool kUniform>
  NBV_STAGE static void repeatRun(Registers& r, const Constants& c, D n, const SnapshotEntry (&e)[kLanes]);
  /// The sums of addRepeats() of n voxels of (h, proximity, flags) lane-wise, with keep^n,
  /// keep^(n - 1) and the geometric series' sum given.
  NBV_STAGE static void repeatWith(Registers& r, D n, D h, D proximity, I flags, M unknown, M frontier, D keep_n,
                                   D keep_n1, D decay_sum);
  /// The lanes' VoxelTerms for their entries e, unless every one is empty (palette[0]).
  NBV_STAGE static void termsOf(const Constants& c, const SnapshotEntry (&e)[kLanes], D& h, D& keep, D& proximity,
                                I& flags);
  /// RayWalk::withinLength() negated, lane-wise: the next border lies beyond the length.
  NBV_STAGE static M pastLength(const Registers& r);
  /// The run section of step(): the runners cross their runs of voxels of the state of their
  /// entries `e` (kUniform: every runner's is palette[0]); returns the lanes whose run took
  /// them past the segment.
  template <bool kUniform>
  NBV_STAGE static unsigned crossRun(Registers& r, const Constants& c, const Lanes& l, D run_steps, unsigned runners,
                                     const SnapshotEntry (&e)[kLanes]);
  /// RayWalk::next() lane-wise; returns the lanes whose walk ended without an end voxel in the
  /// box to visit next.
  NBV_STAGE static unsigned advance(Registers& r, const Constants& c, unsigned active);
  /// Ends the rays in `moving` in the lanes; returns those it ended (see its definition).
  NBV_STAGE unsigned endInLanes(Registers& r, const Constants& c, const Lanes& src, unsigned moving) const;
  /// The rays queued in ending_ end a packet at a time, in the registers.
  NBV_STAGE void endQueued(Registers& r, const Constants& c);
  /// After a step in which rays ended: spills the lanes, finishes the rays, parks their lanes
  /// and enters the next packet when this one is done. Returns the lanes with a ray to walk.
  NBV_STAGE unsigned endRays(Registers& r, const Constants& c, unsigned active, unsigned stopped, unsigned moved_on);
#undef NBV_STAGE

  /// Hands the lane's accumulator back to the scalar type.
  static RayAccumulator accumulator(const Lanes& l, int lane);
  void storeAccumulator(int lane, const RayAccumulator& acc);
  /// Parks the lane: a state that walks on without moving, to be masked out by `active`.
  void park(int lane);
  /// Ends the ray in `lane` after its walk left the box, one whose tail tailVoxels() walks voxel
  /// by voxel (finishOutside()); every other ray ends in the lanes (endInLanes()).
  void finishWalkedTail(const Lanes& l, int lane, std::size_t ray);
  /// The RaySetup of the ray in column `lane` of `l`, from its fields (t_max: the current
  /// border times).
  RaySetup setupOf(const Lanes& l, int lane) const;
  /// Moves the lane's ray, which moved on (to its end voxel or out of the box), into ending_;
  /// the rays there end together, kLanes at a time (endQueued()).
  void queueEnding(int lane);
  /// Column `from` of `src` into column `to` of `dst`: the walk's fields, or the accumulator's.
  static void copyWalk(const Lanes& src, int from, Lanes& dst, int to);
  static void copyAccumulator(const Lanes& src, int from, Lanes& dst, int to);

  const Eigen::Vector3f origin_;
  std::span<const Eigen::Vector3f> ends_;
  const VoxelLattice& lattice_;
  const SnapshotView& view_;
  std::span<RaySums> out_;
  std::span<RayCounts> counts_;
  /// Writes the sums (and with kCounts the counts) of ray `ray` from its accumulator.
  void emit(std::size_t ray, const RayAccumulator& acc) {
    out_[ray] = acc.finish();
    if constexpr (kCounts) counts_[ray] = acc.counts();
  }
  const double stride_[3];
  const Index3 key_origin_;  ///< the origin's voxel, every ray's first
  std::size_t next_ = 0;
  std::size_t ray_[kLanes] = {};  ///< each lane's ray (in a parked lane, any)
  Lanes lanes_{};
  // The lanes enterPacket() settled (their accumulators start in run()) and the voxels of
  // palette[0] each crossed before the box.
  unsigned settled_ = 0;
  alignas(64) double settled_before_[kLanes] = {};
  // Rays that moved on, waiting to end together (queueEnding()): their fields in columns.
  Lanes ending_{};
  std::size_t ending_ray_[kLanes] = {};
  int ending_count_ = 0;
};

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

#undef NBV_PACKET_WALK_FIELDS
#undef NBV_WALK_NONE
