#pragma once
// Private, part of ig_rays_packet.hpp: the packet walk of the IG rays (its lanes' state and
// its stages declared; their definitions in ig_packet_enter.hpp, ig_packet_step.hpp and
// ig_packet_end.hpp), written once over the register types of a lane
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
// ig_rays_packet.hpp is included by one source per lane width, after ig_rays_impl.hpp and
// inside that source's target options. The walk has internal linkage: each source has its own copy, inlined into
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

}  // namespace
}  // namespace nbv::kernels::detail
