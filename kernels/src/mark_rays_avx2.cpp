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
// Rays enter the packet four at a time, in the order given, and the packet steps until all
// four have ended; an ended lane stays on its last voxel. Neighbouring rays of a scan have
// nearly the same number of voxels (the integration benchmark's groups take 0.5% more steps
// than their rays have voxels), and a packet that starts four rays at once and leaves its loop
// once per four rays costs less than one that refills each lane as its ray ends.
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

/// Rays set up and checked ahead of the walk, in groups of four that enter a packet together
/// (offsets are byte offsets into the box, as doubles). A lane of a group without a ray is
/// parked: it sits on the first voxel of a ray of its group (written before the group is
/// walked), with no offset step and that voxel as its end, so it ends at its first step.
struct Batch {
  static constexpr int kCapacity = 64;  ///< rays, a multiple of 4
  alignas(32) double offset[kCapacity];
  alignas(32) double end_offset[kCapacity];
  alignas(32) double t_max[3][kCapacity];
  alignas(32) double t_delta[3][kCapacity];
  alignas(32) double offset_step[3][kCapacity];  ///< step[a] * stride[a]
  alignas(32) double length[kCapacity];
  int count = 0, next = 0;  ///< multiples of 4
};

/// What a packet's four rays keep from start to end.
struct alignas(32) PacketRays {
  __m256d dx, dy, dz;  ///< t_delta
  __m256d ox, oy, oz;  ///< offset_step
  __m256d end_offset, length;
};

/// What a packet's rays change at every step. `ended`: the lanes whose ray has ended (all
/// bits set); `last`: each lane's latest voxel, which an ended lane keeps.
struct PacketState {
  __m256d offset, tx, ty, tz, ended, last;
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
  /// Appends the rays of one setupRays4() call as a group, lanes in `take` only (not none).
  void append(const RaySetups4& s, const __m256d offset[2], unsigned take);
  /// Loads the batch's next group into a packet; false when no ray is left. Inlined, so that
  /// the packets' registers never have their address taken (the byte stores of the walk
  /// could alias anything addressable, which would keep the packets in memory).
  [[gnu::always_inline]] bool load(PacketRays& rays, PacketState& state);

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
  while (batch_.count < Batch::kCapacity && next_ < ends_.size()) {
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
  const int j = batch_.count;
  batch_.count += 4;
  const __m256d in = laneMask(take);
  __m256d origin = offset[0], end = offset[1];
  if (take != 0xFu) {
    alignas(32) double at[4];
    _mm256_store_pd(at, origin);
    const __m256d parking = _mm256_set1_pd(at[__builtin_ctz(take)]);
    origin = _mm256_blendv_pd(parking, origin, in);
    end = _mm256_blendv_pd(parking, end, in);
  }
  _mm256_store_pd(batch_.offset + j, origin);
  _mm256_store_pd(batch_.end_offset + j, end);
  for (int a = 0; a < 3; ++a) {
    const __m256d step = _mm256_mul_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(s.step[a]))),
                                       _mm256_set1_pd(stride_[a]));
    _mm256_store_pd(batch_.t_max[a] + j, _mm256_load_pd(s.t_max[a]));
    _mm256_store_pd(batch_.t_delta[a] + j, _mm256_load_pd(s.t_delta[a]));
    _mm256_store_pd(batch_.offset_step[a] + j, _mm256_and_pd(in, step));
  }
  _mm256_store_pd(batch_.length + j, _mm256_load_pd(s.length));
}

template <MarkSpec::Mode kMode>
inline bool PacketWalk<kMode>::load(PacketRays& rays, PacketState& state) {
  if (batch_.next == batch_.count) fill();
  if (batch_.next == batch_.count) return false;
  const int j = batch_.next;
  batch_.next += 4;
  rays.dx = _mm256_load_pd(batch_.t_delta[0] + j);
  rays.dy = _mm256_load_pd(batch_.t_delta[1] + j);
  rays.dz = _mm256_load_pd(batch_.t_delta[2] + j);
  rays.ox = _mm256_load_pd(batch_.offset_step[0] + j);
  rays.oy = _mm256_load_pd(batch_.offset_step[1] + j);
  rays.oz = _mm256_load_pd(batch_.offset_step[2] + j);
  rays.end_offset = _mm256_load_pd(batch_.end_offset + j);
  rays.length = _mm256_load_pd(batch_.length + j);
  state.offset = _mm256_load_pd(batch_.offset + j);
  state.tx = _mm256_load_pd(batch_.t_max[0] + j);
  state.ty = _mm256_load_pd(batch_.t_max[1] + j);
  state.tz = _mm256_load_pd(batch_.t_max[2] + j);
  state.ended = _mm256_setzero_pd();
  state.last = state.offset;
  return true;
}

template <MarkSpec::Mode kMode>
void PacketWalk<kMode>::run() {
  // No function call in the step loops: a call would force every ymm register (all are
  // caller-saved) to be spilled and reloaded at each step.
  std::uint8_t* const data = box_.data;
  const std::uint8_t value = spec_.value;
  // One step of every lane: RayWalk::next() and, in Store mode, the byte of its voxel (an
  // ended lane writes its last voxel's byte again, which changes nothing). Returns the lanes
  // that have ended, as a movemask.
  const auto step = [&](const PacketRays& rays, PacketState& state) __attribute__((always_inline)) {
    stepLanes(state.tx, state.ty, state.tz, rays.dx, rays.dy, rays.dz, state.offset, rays.ox, rays.oy, rays.oz);
    // RayWalk::next() returning false: the end voxel reached, or the next border beyond the length.
    const __m256d done = _mm256_or_pd(_mm256_cmp_pd(state.offset, rays.end_offset, _CMP_EQ_OQ),
                                      pastLength(state.tx, state.ty, state.tz, rays.length));
    state.ended = _mm256_or_pd(state.ended, done);
    if constexpr (kMode == MarkSpec::Mode::Store) {
      state.last = _mm256_blendv_pd(state.offset, state.last, state.ended);
      storeAt4(data, _mm256_cvttpd_epi32(state.last), value);
    }
    return static_cast<unsigned>(_mm256_movemask_pd(state.ended));
  };
  PacketRays rays;
  PacketState packet;
  if constexpr (kMode == MarkSpec::Mode::Store) {
    while (load(rays, packet)) {
      while (step(rays, packet) != 0xFu) {
      }
    }
  } else {
    // MinStepIndex: the lanes of a group start together, so a voxel's k is the step count.
    const auto at_offset = [data](std::int32_t at) { return data + static_cast<std::uint32_t>(at); };
    while (load(rays, packet)) {
      for (int k = 1;; ++k) {
        const unsigned visit = ~step(rays, packet) & 0xFu;
        if (visit == 0) break;
        const __m128i at = _mm256_cvttpd_epi32(packet.offset);
        if (visit == 0xFu) {  // the common case: four voxels to write
          writeByte(at_offset(_mm_cvtsi128_si32(at)), spec_, k);
          writeByte(at_offset(_mm_extract_epi32(at, 1)), spec_, k);
          writeByte(at_offset(_mm_extract_epi32(at, 2)), spec_, k);
          writeByte(at_offset(_mm_extract_epi32(at, 3)), spec_, k);
          continue;
        }
        alignas(16) std::int32_t offsets[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(offsets), at);
        for (unsigned left = visit; left != 0; left &= left - 1) {
          writeByte(at_offset(offsets[__builtin_ctz(left)]), spec_, k);
        }
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
