// AVX2 packet walk of OctoMap's DDA: four rays in the lanes of __m256d, with the same double
// comparisons and additions as traverseRayKeys() (which stays the oracle), so the same voxels.
//
// Each lane carries its voxel as a byte offset into the box (a double, exact for the box sizes
// allowed), moved by the axis stride at every step, so "reached the end voxel" is one
// comparison of offsets. That needs every voxel of the ray inside the box: along each axis the
// walk moves monotonically from the origin's voxel and overshoots the end voxel by at most one
// (rounding only, far below a voxel), so a ray whose two end voxels lie at least one voxel
// inside the box stays in it. Other rays take the scalar walk.
//
// Compiled with -mavx2 (this file only); reached through markRays() after a CPU check.
#include "dda_avx2.hpp"
#include "mark_rays_impl.hpp"

#include <immintrin.h>

namespace nbv::kernels::detail {

namespace {

/// Stores `byte` at plane[at[i]] for the four lanes of `at`. The offsets leave the register by
/// extraction, not through memory (a 16-byte store forwarded to 4-byte loads stalls on some
/// cores), and as unsigned 32-bit values, which address without a sign extension.
inline void storeAt4(std::uint8_t* plane, const __m128i& at, std::uint8_t byte) {
  const auto store = [plane, byte](int offset) {
    std::atomic_ref<std::uint8_t>(plane[static_cast<std::uint32_t>(offset)]).store(byte, std::memory_order_relaxed);
  };
  store(_mm_cvtsi128_si32(at));
  store(_mm_extract_epi32(at, 1));
  store(_mm_extract_epi32(at, 2));
  store(_mm_extract_epi32(at, 3));
}

/// Rays set up and checked ahead of the walk, each field ready to enter a lane (offsets are
/// byte offsets into the box, as doubles), in the order given.
struct Batch {
  static constexpr int kCapacity = 64;
  alignas(32) double offset[kCapacity];
  alignas(32) double end_offset[kCapacity];
  alignas(32) double t_max[3][kCapacity];
  alignas(32) double t_delta[3][kCapacity];
  alignas(32) double offset_step[3][kCapacity];  ///< step[a] * stride[a]
  alignas(32) double length[kCapacity];
  int count = 0, next = 0;
};

template <MarkSpec::Mode kMode>
class PacketWalk {
 public:
  PacketWalk(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
             const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside)
      : origins_(origins), ends_(ends), lattice_(lattice), box_(box), spec_(spec), outside_(outside),
        stride_{1.0, static_cast<double>(box.size[0]), static_cast<double>(box.size[0]) * box.size[1]} {}

  void run();

 private:
  /// Refills the batch with the next rays that visit anything in the packet. Each ray's first
  /// voxel (the origin's) is written here, and rays that may leave the box are walked here by
  /// the scalar oracle. Leaves the batch empty when no ray is left. Not inlined: it is called
  /// once per batch, and its calls must not push the packet loop's registers to memory.
  [[gnu::noinline]] void fill();
  /// Appends the rays of one setupRays4() call, lanes in `take` only.
  void append(const RaySetups4& s, const __m256d offset[2], unsigned take);

  std::span<const Eigen::Vector3f> origins_, ends_;
  const VoxelLattice& lattice_;
  const DenseBox& box_;
  const MarkSpec& spec_;
  const OutsideSink& outside_;
  const double stride_[3];
  std::size_t next_ = 0;  ///< the next ray of ends_ to set up
  Batch batch_;
};

template <MarkSpec::Mode kMode>
void PacketWalk<kMode>::fill() {
  batch_.count = batch_.next = 0;
  const __m128i zero = _mm_setzero_si128();
  while (batch_.count + 4 <= Batch::kCapacity && next_ < ends_.size()) {
    const std::size_t count = std::min<std::size_t>(4, ends_.size() - next_);
    const Eigen::Vector3f* from[4];
    const Eigen::Vector3f* to[4];
    for (std::size_t j = 0; j < 4; ++j) {
      const std::size_t i = next_ + std::min(j, count - 1);  // short groups repeat their last ray
      from[j] = &origins_[origins_.size() == 1 ? 0 : i];
      to[j] = &ends_[i];
    }
    next_ += count;
    RaySetups4 s;
    setupRays4(from, to, lattice_, s);
    // Both end voxels at least one voxel inside the box (DenseBox::holdsWithMargin), and the
    // voxels as byte offsets: (z * size_y + y) * size_x + x relative to the box's corner.
    __m128i inside = _mm_set1_epi32(-1), end_in_box = inside;
    __m256d offset[2] = {_mm256_setzero_pd(), _mm256_setzero_pd()};  // origin's, end's
    for (int a = 2; a >= 0; --a) {
      const __m128i min = _mm_set1_epi32(box_.min[a]);
      const __m128i last_inner = _mm_set1_epi32(static_cast<int>(box_.size[a]) - 2);
      const std::int32_t* keys[2] = {s.key_origin[a], s.key_end[a]};
      for (int e = 0; e < 2; ++e) {
        const __m128i v = _mm_sub_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(keys[e])), min);
        inside = _mm_and_si128(inside, _mm_andnot_si128(_mm_cmpgt_epi32(v, last_inner), _mm_cmpgt_epi32(v, zero)));
        offset[e] = _mm256_add_pd(_mm256_mul_pd(offset[e], _mm256_set1_pd(box_.size[a])), _mm256_cvtepi32_pd(v));
        if (e == 1) {  // 0 <= v <= size - 1
          end_in_box = _mm_and_si128(end_in_box, _mm_andnot_si128(_mm_cmpgt_epi32(v, _mm_add_epi32(last_inner, _mm_set1_epi32(1))),
                                                                  _mm_cmpgt_epi32(v, _mm_set1_epi32(-1))));
        }
      }
    }
    // Byte offsets as int32 (one instruction; a double to size_t conversion takes a branch).
    const __m128i at_origin = _mm256_cvttpd_epi32(offset[0]);
    const __m128i at_end = _mm256_cvttpd_epi32(offset[1]);
    const auto in_box = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(end_in_box)));
    if (spec_.end_flags != nullptr) {
      if (count == 4 && in_box == 0xFu) {
        storeAt4(spec_.end_flags, at_end, 1);
      } else {
        alignas(16) std::int32_t end[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(end), at_end);
        for (int lane = 0; lane < static_cast<int>(count); ++lane) {
          flagEnd(spec_, ((in_box >> lane) & 1u) != 0, static_cast<std::size_t>(end[lane]));
        }
      }
    }
    const unsigned rays = ((1u << count) - 1u) & ~s.same_voxel;
    const unsigned packet = rays & static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(inside)));
    if (kMode == MarkSpec::Mode::Store && packet == 0xFu) {
      storeAt4(box_.data, at_origin, spec_.value);  // the common case: four rays in packets
    } else {
      alignas(16) std::int32_t origin[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(origin), at_origin);
      for (int lane = 0; lane < static_cast<int>(count); ++lane) {
        if (((rays >> lane) & 1u) == 0) continue;
        checkStepRange(spec_, s.keyOrigin(lane), s.keyEnd(lane));
        if (((packet >> lane) & 1u) == 0) {
          markRayScalar(*from[lane], *to[lane], lattice_, box_, spec_, outside_);
        } else if constexpr (kMode == MarkSpec::Mode::Store) {
          writeByte(box_.data + static_cast<std::size_t>(origin[lane]), spec_, 0);
        }  // (MinStepIndex writes nothing for a ray's first voxel, k = 0)
      }
    }
    if (packet != 0) append(s, offset, packet);
  }
}

template <MarkSpec::Mode kMode>
void PacketWalk<kMode>::append(const RaySetups4& s, const __m256d offset[2], unsigned take) {
  __m256d step[3];
  for (int a = 0; a < 3; ++a) {
    step[a] = _mm256_mul_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(s.step[a]))),
                            _mm256_set1_pd(stride_[a]));
  }
  if (take == 0xFu && batch_.count % 4 == 0) {  // the common case: four rays, stored as vectors
    const int j = batch_.count;
    batch_.count += 4;
    _mm256_store_pd(batch_.offset + j, offset[0]);
    _mm256_store_pd(batch_.end_offset + j, offset[1]);
    for (int a = 0; a < 3; ++a) {
      _mm256_store_pd(batch_.t_max[a] + j, _mm256_load_pd(s.t_max[a]));
      _mm256_store_pd(batch_.t_delta[a] + j, _mm256_load_pd(s.t_delta[a]));
      _mm256_store_pd(batch_.offset_step[a] + j, step[a]);
    }
    _mm256_store_pd(batch_.length + j, _mm256_load_pd(s.length));
    return;
  }
  alignas(32) double at[2][4], steps[3][4];
  _mm256_store_pd(at[0], offset[0]);
  _mm256_store_pd(at[1], offset[1]);
  for (int a = 0; a < 3; ++a) _mm256_store_pd(steps[a], step[a]);
  for (int lane = 0; lane < 4; ++lane) {
    if (((take >> lane) & 1u) == 0) continue;
    const int j = batch_.count++;
    batch_.offset[j] = at[0][lane];
    batch_.end_offset[j] = at[1][lane];
    for (int a = 0; a < 3; ++a) {
      batch_.t_max[a][j] = s.t_max[a][lane];
      batch_.t_delta[a][j] = s.t_delta[a][lane];
      batch_.offset_step[a][j] = steps[a][lane];
    }
    batch_.length[j] = s.length[lane];
  }
}

template <MarkSpec::Mode kMode>
void PacketWalk<kMode>::run() {
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  const __m256d one = _mm256_set1_pd(1.0);
  std::uint8_t* const data = box_.data;
  const std::uint8_t value = spec_.value;
  __m256d offset = _mm256_setzero_pd(), end_offset = offset, tx = offset, ty = offset, tz = offset, dx = offset,
          dy = offset, dz = offset, ox = offset, oy = offset, oz = offset, length = offset, step_index = offset;
  // Puts the batch's next ray into `lane` by blending broadcast fields: the other lanes keep
  // their registers. False when no ray is left.
  auto take = [&](int lane) __attribute__((always_inline)) {
    if (batch_.next == batch_.count) fill();
    if (batch_.next == batch_.count) return false;
    const int j = batch_.next++;
    const __m256d in = laneMask(1u << lane);
    const auto put = [&](__m256d& field, const double& v) __attribute__((always_inline)) {
      field = _mm256_blendv_pd(field, _mm256_broadcast_sd(&v), in);
    };
    put(offset, batch_.offset[j]);
    put(end_offset, batch_.end_offset[j]);
    put(tx, batch_.t_max[0][j]);
    put(ty, batch_.t_max[1][j]);
    put(tz, batch_.t_max[2][j]);
    put(dx, batch_.t_delta[0][j]);
    put(dy, batch_.t_delta[1][j]);
    put(dz, batch_.t_delta[2][j]);
    put(ox, batch_.offset_step[0][j]);
    put(oy, batch_.offset_step[1][j]);
    put(oz, batch_.offset_step[2][j]);
    put(length, batch_.length[j]);
    if constexpr (kMode == MarkSpec::Mode::MinStepIndex) step_index = _mm256_andnot_pd(in, step_index);
    return true;
  };
  // Store mode writes four bytes at every step without a branch: a lane without a voxel to
  // visit (its ray ended at this step, or it has no ray) writes a byte written before with the
  // same value again, which changes nothing. Such a byte: the voxel before the step, or, for a
  // lane without a ray, `parking`, the first voxel of a ray already started.
  double parking = 0.0;
  auto park = [&](int lane) __attribute__((always_inline)) {
    const __m256d in = laneMask(1u << lane);
    offset = _mm256_blendv_pd(offset, _mm256_broadcast_sd(&parking), in);
    ox = _mm256_andnot_pd(in, ox);  // the offset stays where it is
    oy = _mm256_andnot_pd(in, oy);
    oz = _mm256_andnot_pd(in, oz);
  };
  unsigned active = 0;
  for (int lane = 0; lane < 4; ++lane) {
    if (take(lane)) {
      active |= 1u << lane;
      if (lane == 0) parking = batch_.offset[batch_.next - 1];
    } else {
      park(lane);
    }
  }

  // RayWalk::next() returning false, lane-wise: the end voxel reached, or the next border
  // beyond the length.
  auto ended = [&] {
    return _mm256_or_pd(_mm256_cmp_pd(offset, end_offset, _CMP_EQ_OQ), pastLength(tx, ty, tz, length));
  };

  while (active != 0) {
    // No function call in this loop: a call would force every ymm register (all are
    // caller-saved) to be spilled and reloaded at each step.
    unsigned finished = 0;
    if constexpr (kMode == MarkSpec::Mode::Store) {
      do {
        const __m256d before = offset;
        stepLanes(tx, ty, tz, dx, dy, dz, offset, ox, oy, oz, all);
        const __m256d done = ended();
        finished = static_cast<unsigned>(_mm256_movemask_pd(done)) & active;
        storeAt4(data, _mm256_cvttpd_epi32(_mm256_blendv_pd(offset, before, done)), value);
      } while (finished == 0);
    }
    while (finished == 0) {  // MinStepIndex
      stepLanes(tx, ty, tz, dx, dy, dz, offset, ox, oy, oz, all);

      finished = static_cast<unsigned>(_mm256_movemask_pd(ended())) & active;
      const unsigned visit = active & ~finished;
      step_index = _mm256_add_pd(step_index, one);

      // Offsets and step indices leave the vector registers by extraction (see storeAt4).
      const __m128i at = _mm256_cvttpd_epi32(offset);
      if (visit == 0xFu) {  // the common case: four voxels to write
        const __m128i k = _mm256_cvttpd_epi32(step_index);
        writeByte(data + _mm_cvtsi128_si32(at), spec_, _mm_cvtsi128_si32(k));
        writeByte(data + _mm_extract_epi32(at, 1), spec_, _mm_extract_epi32(k, 1));
        writeByte(data + _mm_extract_epi32(at, 2), spec_, _mm_extract_epi32(k, 2));
        writeByte(data + _mm_extract_epi32(at, 3), spec_, _mm_extract_epi32(k, 3));
        continue;
      }
      alignas(16) std::int32_t offsets[4], indices[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(offsets), at);
      _mm_store_si128(reinterpret_cast<__m128i*>(indices), _mm256_cvttpd_epi32(step_index));
      for (unsigned left = visit; left != 0; left &= left - 1) {
        const int lane = __builtin_ctz(left);
        writeByte(data + offsets[lane], spec_, indices[lane]);
      }
    }
    // Some rays ended: the next rays take their lanes.
    for (unsigned done = finished; done != 0; done &= done - 1) {
      const int lane = __builtin_ctz(done);
      if (!take(lane)) {
        park(lane);
        active &= ~(1u << lane);
      }
    }
  }
}

}  // namespace

void markRaysAvx2(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                  const OutsideSink& outside) {
  if (spec.mode == MarkSpec::Mode::Store) {
    PacketWalk<MarkSpec::Mode::Store>(origins, ends, lattice, box, spec, outside).run();
  } else {
    PacketWalk<MarkSpec::Mode::MinStepIndex>(origins, ends, lattice, box, spec, outside).run();
  }
}

}  // namespace nbv::kernels::detail
