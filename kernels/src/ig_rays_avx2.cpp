// AVX2 packet walk of the IG rays: four rays in the lanes of __m256d, each lane running the
// DDA of traverseRayKeys() and the accumulator of RayAccumulator::add() with the same double
// operations in the same order, so every ray's sums equal the scalar walk's bit for bit.
//
// Rays enter through enterSnapshot() (the closed-form run before the box) and leave through
// the scalar code below when they stop, reach their end voxel, or leave the box (the closed-
// form run after it). Inside the box a lane carries its voxel as an offset (a double, exact
// for boxes below 2^31 voxels) and, per axis, the steps left before it leaves the box. Each
// step loads the four voxels' entries and their VoxelTerms rows. A lane on an empty voxel
// (palette[0]) whose run distance says the voxels around it are empty too crosses them as
// walkRayScalar() does: every border crossing before runEnd(), each axis's border times
// summed one by one as the walk sums them, and the voxels crossed into added in closed form
// (RayAccumulator::addRepeats), so the bits are the scalar walk's.
//
// Compiled with -mavx2 (this file only); reached through walkRays() after a CPU check.
#include "dda_avx2.hpp"
#include "ig_rays_impl.hpp"

#include <immintrin.h>

#include <cstring>
#include <limits>

namespace nbv::kernels::detail {

namespace {

/// Per-lane state, spilled to memory only when a lane's ray ends.
struct alignas(32) Lanes {
  // The walk.
  double offset[4];
  double end_offset[4];       ///< NaN (equal to no offset) when the end voxel lies outside the box
  double t_max[3][4];
  double t_delta[3][4];
  double offset_step[3][4];   ///< step[a] * stride[a]
  double box_left[3][4];      ///< steps along each axis before the walk leaves the box
  double length[4];
  double run_stop[4];         ///< runStop(): runs of empty voxels end before it
  double is_last[4];          ///< all bits set: the current voxel is the ray's end voxel
  // The accumulator (RayAccumulator's fields).
  double visibility[4], entropy[4], oa[4], uv[4], pc[4], run[4], run_before[4], last_term[4], voxels[4];
  std::int64_t last_flags[4], previous_flags[4], seen_measured[4], previous_free[4], area[4];
};

/// An end offset no walk reaches: a lane leaving the box can reach any small negative offset.
constexpr double kNoOffset = std::numeric_limits<double>::quiet_NaN();

/// A double whose 64 bits are all set (a lane mask).
double maskBits(bool on) {
  std::int64_t bits = on ? -1 : 0;
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}

class PacketWalk {
 public:
  PacketWalk(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
             const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out)
      : origin_(origin), ends_(ends), lattice_(lattice), view_(view), out_(out),
        stride_{1.0, static_cast<double>(view.size[0]), static_cast<double>(view.size[0]) * view.size[1]} {}

  void run();

 private:
  /// Loads the next ray that enters the box into `lane`, finishing the others on the way;
  /// parks the lane (a state that never moves or ends) and returns false when none is left.
  bool start(int lane);
  /// Hands the lane's accumulator back to the scalar type.
  RayAccumulator accumulator(int lane) const;
  void storeAccumulator(int lane, const RayAccumulator& acc);
  void park(int lane);
  /// Ends the ray in `lane` after its walk stopped, reached its end, or left the box.
  void finish(int lane, bool stopped);

  const Eigen::Vector3f origin_;
  std::span<const Eigen::Vector3f> ends_;
  const VoxelLattice& lattice_;
  const SnapshotView& view_;
  std::span<RaySums> out_;
  const double stride_[3];
  std::size_t next_ = 0;
  std::size_t ray_[4] = {};
  RaySetup setup_[4];  ///< each lane's ray
  Lanes lanes_{};
};

RayAccumulator PacketWalk::accumulator(int lane) const {
  const Lanes& l = lanes_;
  RayAccumulator acc;
  acc.visibility = l.visibility[lane];
  acc.entropy = l.entropy[lane];
  acc.oa = l.oa[lane];
  acc.uv = l.uv[lane];
  acc.pc = l.pc[lane];
  acc.run = l.run[lane];
  acc.run_before = l.run_before[lane];
  acc.last_term = l.last_term[lane];
  acc.voxels = l.voxels[lane];
  acc.last_flags = static_cast<std::uint64_t>(l.last_flags[lane]);
  acc.previous_flags = static_cast<std::uint64_t>(l.previous_flags[lane]);
  acc.seen_measured = l.seen_measured[lane] != 0;
  acc.previous_free = l.previous_free[lane] != 0;
  acc.area = static_cast<AreaClass>(l.area[lane]);
  return acc;
}

void PacketWalk::storeAccumulator(int lane, const RayAccumulator& acc) {
  Lanes& l = lanes_;
  l.visibility[lane] = acc.visibility;
  l.entropy[lane] = acc.entropy;
  l.oa[lane] = acc.oa;
  l.uv[lane] = acc.uv;
  l.pc[lane] = acc.pc;
  l.run[lane] = acc.run;
  l.run_before[lane] = acc.run_before;
  l.last_term[lane] = acc.last_term;
  l.voxels[lane] = acc.voxels;
  l.last_flags[lane] = static_cast<std::int64_t>(acc.last_flags);
  l.previous_flags[lane] = static_cast<std::int64_t>(acc.previous_flags);
  l.seen_measured[lane] = acc.seen_measured ? -1 : 0;
  l.previous_free[lane] = acc.previous_free ? -1 : 0;
  l.area[lane] = static_cast<std::int64_t>(acc.area);
}

void PacketWalk::park(int lane) {
  Lanes& l = lanes_;
  l.offset[lane] = 0.0;
  l.end_offset[lane] = kNoOffset;
  for (int a = 0; a < 3; ++a) {
    l.t_max[a][lane] = 0.0;
    l.t_delta[a][lane] = 0.0;
    l.offset_step[a][lane] = 0.0;
    l.box_left[a][lane] = std::numeric_limits<double>::infinity();
  }
  l.length[lane] = std::numeric_limits<double>::infinity();
  l.run_stop[lane] = -std::numeric_limits<double>::infinity();
  l.is_last[lane] = maskBits(false);
  storeAccumulator(lane, RayAccumulator{});
}

bool PacketWalk::start(int lane) {
  RayEntry entry;
  while (next_ < ends_.size()) {
    const std::size_t i = next_++;
    if (!enterSnapshot(origin_, ends_[i], lattice_, view_, entry)) {
      out_[i] = entry.acc.finish();
      continue;
    }
    const RaySetup& s = entry.setup;
    Lanes& l = lanes_;
    ray_[lane] = i;
    setup_[lane] = s;
    l.offset[lane] = static_cast<double>(view_.offset(entry.ijk));
    l.end_offset[lane] = view_.contains(s.key_end) ? static_cast<double>(view_.offset(s.key_end)) : kNoOffset;
    for (int a = 0; a < 3; ++a) {
      l.t_max[a][lane] = entry.t_max[a];
      l.t_delta[a][lane] = s.t_delta[a];
      l.offset_step[a][lane] = s.step[a] * stride_[a];
      l.box_left[a][lane] = boxLeft(view_, s, entry.ijk, a);
    }
    l.length[lane] = s.length;
    l.run_stop[lane] = runStop(s);
    l.is_last[lane] = maskBits(entry.at_end);
    storeAccumulator(lane, entry.acc);
    return true;
  }
  park(lane);
  return false;
}

void PacketWalk::finish(int lane, bool stopped) {
  RayAccumulator acc = accumulator(lane);
  const Lanes& l = lanes_;
  if (!stopped) {
    // As RayWalk::next(): the end voxel first (reached, or rounding carried the walk past the
    // segment), else the walk left the box.
    const double t_min = std::min(std::min(l.t_max[0][lane], l.t_max[1][lane]), l.t_max[2][lane]);
    const bool left_box = l.box_left[0][lane] < 0.0 || l.box_left[1][lane] < 0.0 || l.box_left[2][lane] < 0.0;
    if (!left_box || t_min > l.length[lane]) {
      acc.add(view_.terms(setup_[lane].key_end));
    } else {
      // The voxel before the exit step lay inside the box: decode it, then take the step.
      int axis = 0;
      while (l.box_left[axis][lane] >= 0.0) ++axis;
      auto inside = static_cast<std::size_t>(l.offset[lane] - l.offset_step[axis][lane]);
      Index3 ijk;
      ijk.x() = view_.min[0] + static_cast<int>(inside % view_.size[0]);
      inside /= view_.size[0];
      ijk.y() = view_.min[1] + static_cast<int>(inside % view_.size[1]);
      ijk.z() = view_.min[2] + static_cast<int>(inside / view_.size[1]);
      ijk[axis] += setup_[lane].step[axis];
      const double t_max[3] = {l.t_max[0][lane], l.t_max[1][lane], l.t_max[2][lane]};
      finishOutside(acc, view_, setup_[lane], ijk, t_max);
    }
  }
  out_[ray_[lane]] = acc.finish();
}

void PacketWalk::run() {
  unsigned active = 0;
  for (int lane = 0; lane < 4; ++lane) {
    if (start(lane)) active |= 1u << lane;
  }
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d zero = _mm256_setzero_pd();
  const __m256i unknown_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kUnknown));
  const __m256i free_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kFree));
  const __m256i stop_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kStop));
  const __m256i occupied_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kOccupied));
  const __m256i marked_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kMarked));
  const __m256i seen_bits =
      _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kMeasured | voxel_flag::kMarked));
  const __m256i measured_bit = _mm256_set1_epi64x(static_cast<std::int64_t>(voxel_flag::kMeasured));
  const __m256i zero_i = _mm256_setzero_si256();
  const __m256i pending = _mm256_set1_epi64x(static_cast<std::int64_t>(AreaClass::Pending));
  const __m256i area_occupied = _mm256_set1_epi64x(static_cast<std::int64_t>(AreaClass::Occupied));
  const __m256i area_occplane = _mm256_set1_epi64x(static_cast<std::int64_t>(AreaClass::Occplane));
  const __m256i area_none = _mm256_set1_epi64x(static_cast<std::int64_t>(AreaClass::None));
  constexpr SnapshotEntry index_bits = kMaxPaletteSize - 1;
  const SnapshotEntry* voxels = view_.voxels;
  const double* table = &view_.palette[0].entropy;  // rows of 4 x 64 bits
  static_assert(sizeof(VoxelTerms) == 4 * sizeof(double));
  // Most voxels a ray crosses in the box are empty (unmeasured and unmarked): palette[0].
  const __m256d uniform_h = _mm256_set1_pd(view_.palette[0].entropy);
  const __m256d uniform_keep = _mm256_set1_pd(view_.palette[0].keep);
  const __m256d uniform_proximity = _mm256_set1_pd(view_.palette[0].proximity);
  const __m256i uniform_flags = _mm256_set1_epi64x(static_cast<std::int64_t>(view_.palette[0].flags));

  // Runs of empty voxels (walkRayScalar's), and the constants of their closed form.
  const unsigned runs_allowed = crossesEmptyRuns(view_) ? 0xFu : 0u;
  const __m256d half = _mm256_set1_pd(0.5);
  const __m256d minus_infinity = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
  const __m256d two_52 = _mm256_set1_pd(0x1p52);  // n + 2^52 holds the integer n in its low bits
  const __m256i two_52_bits = _mm256_castpd_si256(two_52);
  const __m256i exponent_0 = _mm256_set1_epi64x(1023);  // 2^-n: exponent 1023 - n
  const __m256i exponent_1 = _mm256_set1_epi64x(1024);  // 2^-(n - 1)
  const __m256d uniform_unknown = _mm256_castsi256_pd(
      _mm256_cmpeq_epi64(_mm256_and_si256(uniform_flags, unknown_bit), unknown_bit));

  Lanes& l = lanes_;
  while (active != 0) {
    __m256d offset = _mm256_load_pd(l.offset);
    const __m256d end_offset = _mm256_load_pd(l.end_offset);
    __m256d tx = _mm256_load_pd(l.t_max[0]), ty = _mm256_load_pd(l.t_max[1]), tz = _mm256_load_pd(l.t_max[2]);
    const __m256d dx = _mm256_load_pd(l.t_delta[0]), dy = _mm256_load_pd(l.t_delta[1]),
                  dz = _mm256_load_pd(l.t_delta[2]);
    const __m256d ox = _mm256_load_pd(l.offset_step[0]), oy = _mm256_load_pd(l.offset_step[1]),
                  oz = _mm256_load_pd(l.offset_step[2]);
    __m256d left_x = _mm256_load_pd(l.box_left[0]), left_y = _mm256_load_pd(l.box_left[1]),
            left_z = _mm256_load_pd(l.box_left[2]);
    const __m256d length = _mm256_load_pd(l.length);
    __m256d is_last = _mm256_load_pd(l.is_last);
    __m256d visibility = _mm256_load_pd(l.visibility), entropy = _mm256_load_pd(l.entropy),
            oa = _mm256_load_pd(l.oa), uv = _mm256_load_pd(l.uv), pc = _mm256_load_pd(l.pc),
            run = _mm256_load_pd(l.run), run_before = _mm256_load_pd(l.run_before),
            last_term = _mm256_load_pd(l.last_term), count = _mm256_load_pd(l.voxels);
    auto load_i = [](const std::int64_t* p) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(p)); };
    __m256i last_flags = load_i(l.last_flags), previous_flags = load_i(l.previous_flags),
            seen_measured = load_i(l.seen_measured), previous_free = load_i(l.previous_free),
            area = load_i(l.area);

    unsigned stopped = 0, moved_on = 0;

    // RayAccumulator::add() lane-wise; returns the lanes whose ray ends with this voxel (it
    // stops the ray, or it was the end voxel).
    auto visit = [&](const __m256d& h, const __m256d& keep, const __m256d& proximity, const __m256i& flags) {
      auto has = [&](const __m256i& bit) { return _mm256_cmpeq_epi64(_mm256_and_si256(flags, bit), bit); };
      const __m256d term = _mm256_mul_pd(visibility, h);
      const __m256d unknown = _mm256_castsi256_pd(has(unknown_bit));
      entropy = _mm256_add_pd(entropy, h);
      oa = _mm256_add_pd(oa, term);                            // Eq. 6
      uv = _mm256_add_pd(uv, _mm256_and_pd(unknown, term));    // Eq. 8
      run_before = run;
      run = _mm256_and_pd(unknown, _mm256_add_pd(run, term));  // Eq. 10's run
      last_term = term;
      pc = _mm256_add_pd(pc, proximity);                       // Eq. 11
      // Eqs. 17-20: a pending ray is classified by a marked or an occupied voxel.
      const __m256i is_pending = _mm256_cmpeq_epi64(area, pending);
      const __m256i after_free =
          _mm256_and_si256(previous_free, _mm256_castpd_si256(_mm256_cmp_pd(count, zero, _CMP_GT_OQ)));
      __m256i classified = _mm256_blendv_epi8(pending, _mm256_blendv_epi8(area_none, area_occupied, after_free),
                                              has(occupied_bit));
      classified = _mm256_blendv_epi8(classified, area_occplane, has(marked_bit));
      area = _mm256_blendv_epi8(area, classified, is_pending);
      seen_measured = _mm256_or_si256(seen_measured, has(measured_bit));
      const __m256i unseen = _mm256_cmpeq_epi64(_mm256_and_si256(flags, seen_bits), zero_i);
      previous_free = _mm256_or_si256(has(free_bit), _mm256_andnot_si256(seen_measured, unseen));
      previous_flags = last_flags;
      last_flags = flags;
      count = _mm256_add_pd(count, one);
      visibility = _mm256_mul_pd(visibility, keep);            // Eq. 5
      return static_cast<unsigned>(_mm256_movemask_pd(_mm256_or_pd(_mm256_castsi256_pd(has(stop_bit)), is_last))) &
             active;
    };
    // RayWalk::withinLength() negated, lane-wise: the next border lies beyond the length.
    auto past_length = [&] { return pastLength(tx, ty, tz, length); };
    // RayWalk::next() lane-wise; returns the lanes whose walk ended without an end voxel in
    // the box to visit next (they finish in scalar code).
    auto advance = [&] {
      const LaneMoves move = stepLanes(tx, ty, tz, dx, dy, dz, offset, ox, oy, oz);
      left_x = _mm256_sub_pd(left_x, _mm256_and_pd(move.x, one));
      left_y = _mm256_sub_pd(left_y, _mm256_and_pd(move.y, one));
      left_z = _mm256_sub_pd(left_z, _mm256_andnot_pd(move.x_or_y, one));
      const __m256d past = past_length();
      const __m256d outside = _mm256_cmp_pd(_mm256_min_pd(_mm256_min_pd(left_x, left_y), left_z), zero, _CMP_LT_OQ);
      // (An offset outside the box may alias one inside: only a lane inside has reached.)
      const __m256d reached = _mm256_andnot_pd(outside, _mm256_cmp_pd(offset, end_offset, _CMP_EQ_OQ));
      is_last = reached;
      return static_cast<unsigned>(_mm256_movemask_pd(_mm256_andnot_pd(reached, _mm256_or_pd(past, outside)))) &
             active;
    };

    while ((stopped | moved_on) == 0) {
      // --- the current voxel: its entry, then (unless all four are empty) its terms --------
      // Scalar loads and a 4 x 4 transpose (gathers were no faster on the cores measured).
      alignas(16) std::int32_t at[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(at), _mm256_cvttpd_epi32(offset));
      const SnapshotEntry e0 = voxels[at[0]], e1 = voxels[at[1]], e2 = voxels[at[2]], e3 = voxels[at[3]];
      __m256d h = uniform_h, keep = uniform_keep, proximity = uniform_proximity;
      __m256i flags = uniform_flags;
      if (((e0 | e1 | e2 | e3) & index_bits) != 0) {
        const __m256d r0 = _mm256_loadu_pd(table + 4 * paletteIndex(e0));
        const __m256d r1 = _mm256_loadu_pd(table + 4 * paletteIndex(e1));
        const __m256d r2 = _mm256_loadu_pd(table + 4 * paletteIndex(e2));
        const __m256d r3 = _mm256_loadu_pd(table + 4 * paletteIndex(e3));
        const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
        const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
        h = _mm256_permute2f128_pd(t0, t2, 0x20);
        proximity = _mm256_permute2f128_pd(t0, t2, 0x31);
        keep = _mm256_permute2f128_pd(t1, t3, 0x20);
        flags = _mm256_castpd_si256(_mm256_permute2f128_pd(t1, t3, 0x31));
      }
      stopped = visit(h, keep, proximity, flags);

      // --- a run of empty voxels (walkRayScalar's, lane by lane): every crossing before
      // runEnd(), each axis on its own, then the voxels crossed into in closed form ---------
      const __m128i entries = _mm_set_epi32(static_cast<int>(e3), static_cast<int>(e2), static_cast<int>(e1),
                                            static_cast<int>(e0));
      const __m128i run_steps_i = _mm_sub_epi32(_mm_srli_epi32(entries, 24), _mm_set1_epi32(1));
      const __m128i empty_run =  // palette[0] with a run distance of 2 or more
          _mm_and_si128(_mm_cmpeq_epi32(_mm_and_si128(entries, _mm_set1_epi32(index_bits)), _mm_setzero_si128()),
                        _mm_cmpgt_epi32(run_steps_i, _mm_setzero_si128()));
      const unsigned runners =
          static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(empty_run))) & active & ~stopped & runs_allowed;
      unsigned run_over = 0;
      if (runners != 0) {
        const __m256d run_steps = _mm256_cvtepi32_pd(run_steps_i);
        __m256d t_end = _mm256_load_pd(l.run_stop);
        t_end = _mm256_min_pd(
            _mm256_add_pd(tx, _mm256_mul_pd(_mm256_sub_pd(_mm256_min_pd(run_steps, left_x), half), dx)), t_end);
        t_end = _mm256_min_pd(
            _mm256_add_pd(ty, _mm256_mul_pd(_mm256_sub_pd(_mm256_min_pd(run_steps, left_y), half), dy)), t_end);
        t_end = _mm256_min_pd(
            _mm256_add_pd(tz, _mm256_mul_pd(_mm256_sub_pd(_mm256_min_pd(run_steps, left_z), half), dz)), t_end);
        t_end = _mm256_blendv_pd(minus_infinity, t_end, laneMask(runners));
        // Each axis's border times as one chain of sums; t_max keeps the first one not before
        // t_end (the walk's state after the run), the counts the crossings before it.
        __m256d nx = tx, ny = ty, nz = tz, cx = zero, cy = zero, cz = zero;
        while (true) {
          const __m256d mx = _mm256_cmp_pd(nx, t_end, _CMP_LT_OQ), my = _mm256_cmp_pd(ny, t_end, _CMP_LT_OQ),
                        mz = _mm256_cmp_pd(nz, t_end, _CMP_LT_OQ);
          if (_mm256_movemask_pd(_mm256_or_pd(_mm256_or_pd(mx, my), mz)) == 0) break;
          nx = _mm256_add_pd(nx, dx);
          ny = _mm256_add_pd(ny, dy);
          nz = _mm256_add_pd(nz, dz);
          tx = _mm256_blendv_pd(tx, nx, mx);
          ty = _mm256_blendv_pd(ty, ny, my);
          tz = _mm256_blendv_pd(tz, nz, mz);
          cx = _mm256_add_pd(cx, _mm256_and_pd(mx, one));
          cy = _mm256_add_pd(cy, _mm256_and_pd(my, one));
          cz = _mm256_add_pd(cz, _mm256_and_pd(mz, one));
        }
        offset = _mm256_add_pd(offset, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(cx, ox), _mm256_mul_pd(cy, oy)),
                                                     _mm256_mul_pd(cz, oz)));
        left_x = _mm256_sub_pd(left_x, cx);
        left_y = _mm256_sub_pd(left_y, cy);
        left_z = _mm256_sub_pd(left_z, cz);
        const __m256d crossed = _mm256_add_pd(_mm256_add_pd(cx, cy), cz);
        // As the walk's length test: a lane past the segment after its last crossing ends
        // before the voxel it crossed into; its end voxel follows in finish().
        const __m256d over = _mm256_and_pd(_mm256_cmp_pd(crossed, zero, _CMP_GT_OQ), past_length());
        run_over = static_cast<unsigned>(_mm256_movemask_pd(over));
        const __m256d n = _mm256_sub_pd(crossed, _mm256_and_pd(over, one));
        // RayAccumulator::addRepeats() for keep = 0.5: keep^n and keep^(n - 1) exactly.
        const __m256i n_bits = _mm256_sub_epi64(_mm256_castpd_si256(_mm256_add_pd(n, two_52)), two_52_bits);
        const __m256d keep_n = _mm256_castsi256_pd(_mm256_slli_epi64(_mm256_sub_epi64(exponent_0, n_bits), 52));
        const __m256d keep_n1 = _mm256_castsi256_pd(_mm256_slli_epi64(_mm256_sub_epi64(exponent_1, n_bits), 52));
        const __m256d repeated = _mm256_cmp_pd(n, zero, _CMP_GT_OQ);
        const __m256d decay_sum = _mm256_div_pd(_mm256_sub_pd(one, keep_n), _mm256_sub_pd(one, uniform_keep));
        const __m256d terms = _mm256_mul_pd(_mm256_mul_pd(visibility, uniform_h), decay_sum);
        entropy = _mm256_add_pd(entropy, _mm256_mul_pd(n, uniform_h));
        oa = _mm256_add_pd(oa, terms);
        uv = _mm256_add_pd(uv, _mm256_and_pd(uniform_unknown, terms));
        const __m256d run_last = _mm256_mul_pd(_mm256_mul_pd(visibility, keep_n1), uniform_h);
        const __m256d run_sum = _mm256_and_pd(uniform_unknown, _mm256_add_pd(run, terms));
        last_term = _mm256_blendv_pd(last_term, run_last, repeated);
        run = _mm256_blendv_pd(run, run_sum, repeated);
        run_before = _mm256_blendv_pd(run_before, _mm256_and_pd(uniform_unknown, _mm256_sub_pd(run_sum, run_last)),
                                      repeated);
        pc = _mm256_add_pd(pc, _mm256_mul_pd(n, uniform_proximity));
        previous_flags = _mm256_blendv_epi8(previous_flags, uniform_flags, _mm256_castpd_si256(repeated));
        count = _mm256_add_pd(count, n);
        visibility = _mm256_mul_pd(visibility, keep_n);
      }
      moved_on = (advance() | run_over) & ~stopped;
    }

    // Some rays ended: spill the state, finish them, start new rays in their lanes, reload.
    _mm256_store_pd(l.offset, offset);
    _mm256_store_pd(l.t_max[0], tx);
    _mm256_store_pd(l.t_max[1], ty);
    _mm256_store_pd(l.t_max[2], tz);
    _mm256_store_pd(l.box_left[0], left_x);
    _mm256_store_pd(l.box_left[1], left_y);
    _mm256_store_pd(l.box_left[2], left_z);
    _mm256_store_pd(l.is_last, is_last);
    _mm256_store_pd(l.visibility, visibility);
    _mm256_store_pd(l.entropy, entropy);
    _mm256_store_pd(l.oa, oa);
    _mm256_store_pd(l.uv, uv);
    _mm256_store_pd(l.pc, pc);
    _mm256_store_pd(l.run, run);
    _mm256_store_pd(l.run_before, run_before);
    _mm256_store_pd(l.last_term, last_term);
    _mm256_store_pd(l.voxels, count);
    auto store_i = [](std::int64_t* p, const __m256i& v) { _mm256_store_si256(reinterpret_cast<__m256i*>(p), v); };
    store_i(l.last_flags, last_flags);
    store_i(l.previous_flags, previous_flags);
    store_i(l.seen_measured, seen_measured);
    store_i(l.previous_free, previous_free);
    store_i(l.area, area);
    for (unsigned done = stopped | moved_on; done != 0; done &= done - 1) {
      const int lane = __builtin_ctz(done);
      finish(lane, (stopped >> lane) & 1u);
      if (!start(lane)) active &= ~(1u << lane);
    }
  }
}

}  // namespace

void walkRaysAvx2(const Eigen::Vector3f& origin, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const SnapshotView& view, std::span<RaySums> out) {
  PacketWalk(origin, ends, lattice, view, out).run();
}

}  // namespace nbv::kernels::detail
