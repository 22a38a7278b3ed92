// AVX2 packet walk of OctoMap's DDA: four rays in the lanes of __m256d, with the same double
// comparisons and additions as traverseRayKeys() (which stays the oracle), so the same voxels.
//
// Each lane carries its voxel as a byte offset into the box (a double, exact for the box sizes
// allowed), moved by the axis stride at every step, so "reached the end voxel" is one
// comparison of offsets. Rays are set up, checked to stay in the box, and grouped ahead of
// the walk by RayBatcher (mark_rays_batch.hpp); the others take the scalar walk there.
//
// Rays enter the packet four at a time, in the order given, and the packet steps until all
// four have ended; an ended lane stays on its last voxel. Neighbouring rays of a scan have
// nearly the same number of voxels, so a packet that starts four rays at once and leaves its
// loop once per four rays wastes few steps, and costs less than one that refills each lane as
// its ray ends.
//
// Compiled with -mavx2 (this file only); reached through markRays() after a CPU check.
#include "mark_rays_batch.hpp"

#include <immintrin.h>

namespace nbv::kernels::detail {

namespace {

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
      : rays_(origins, ends, lattice, box, spec, outside), box_(box), spec_(spec) {}

  void run();

 private:
  /// Loads the next group of rays into a packet; false when no ray is left. Inlined, so that
  /// the packets' registers never have their address taken (the byte stores of the walk
  /// could alias anything addressable, which would keep the packets in memory).
  [[gnu::always_inline]] bool load(PacketRays& rays, PacketState& state);

  RayBatcher<kMode, 4> rays_;
  const DenseBox& box_;
  const MarkSpec& spec_;
};

template <MarkSpec::Mode kMode>
inline bool PacketWalk<kMode>::load(PacketRays& rays, PacketState& state) {
  int j = 0;
  if (!rays_.next(j)) return false;
  const Batch& batch = rays_.batch();
  rays.dx = _mm256_load_pd(batch.t_delta[0] + j);
  rays.dy = _mm256_load_pd(batch.t_delta[1] + j);
  rays.dz = _mm256_load_pd(batch.t_delta[2] + j);
  rays.ox = _mm256_load_pd(batch.offset_step[0] + j);
  rays.oy = _mm256_load_pd(batch.offset_step[1] + j);
  rays.oz = _mm256_load_pd(batch.offset_step[2] + j);
  rays.end_offset = _mm256_load_pd(batch.end_offset + j);
  rays.length = _mm256_load_pd(batch.length + j);
  state.offset = _mm256_load_pd(batch.offset + j);
  state.tx = _mm256_load_pd(batch.t_max[0] + j);
  state.ty = _mm256_load_pd(batch.t_max[1] + j);
  state.tz = _mm256_load_pd(batch.t_max[2] + j);
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
