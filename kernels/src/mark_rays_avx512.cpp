// AVX-512 packet walk of OctoMap's DDA: eight rays in the lanes of __m512d, with the same
// double comparisons and additions as traverseRayKeys() (which stays the oracle), so the same
// voxels. It is mark_rays_avx2.cpp's walk at twice the width: the lane choices are mask
// registers instead of blends, and each lane's voxel is an int32 byte offset into the box
// (a lane of __m256i), moved by the stride of the axis it steps along.
//
// Rays are set up, checked to stay in the box, and grouped ahead of the walk by RayBatcher
// (mark_rays_batch.hpp), which the AVX2 walk uses too; the others take the scalar walk there.
// Rays enter the packet eight at a time, in the order given, and the packet steps until all
// eight have ended; an ended lane stays on its last voxel.
//
// This file is compiled with -mavx2, like the AVX2 walk, and only its own functions below are
// compiled for AVX-512 (avx512_target_begin.hpp): the inline functions of the headers it
// shares with the scalar and AVX2 sources (the DDA set-up, Eigen) are then compiled here
// exactly as there, so whichever copy the linker keeps runs on a CPU without AVX-512. Reached
// through markRays() after a CPU check.
#include "mark_rays_batch.hpp"

#include <immintrin.h>

#include "avx512_target_begin.hpp"

namespace nbv::kernels::detail {

namespace {

/// Stores `byte` at plane[at[i]] for the eight lanes of `at`, as unsigned 32-bit offsets. The
/// offsets leave the register through memory, one 32-byte store read back as eight 4-byte
/// loads, which beats extracting eight lanes (storeAt4() of the AVX2 walk extracts its four;
/// docs/PERFORMANCE.md has the measurements).
inline void storeAt8(std::uint8_t* plane, const __m256i& at, std::uint8_t byte) {
  alignas(32) std::uint32_t offsets[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(offsets), at);
  for (int i = 0; i < 8; ++i) std::atomic_ref<std::uint8_t>(plane[offsets[i]]).store(byte, std::memory_order_relaxed);
}

/// What a packet's eight rays keep from start to end.
struct alignas(64) PacketRays {
  __m512d dx, dy, dz;      ///< t_delta
  __m512d length;
  __m256i ox, oy, oz;      ///< offset step along each axis
  __m256i end_offset;
};

/// What a packet's rays change at every step. `ended`: the lanes whose ray has ended;
/// `last`: each lane's latest voxel, which an ended lane keeps.
struct PacketState {
  __m512d tx, ty, tz;
  __m256i offset, last;
  __mmask8 ended;
};

template <MarkSpec::Mode kMode>
class PacketWalk {
 public:
  PacketWalk(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
             const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside)
      : rays_(origins, ends, lattice, box, spec, outside), box_(box), spec_(spec) {}

  void run();

 private:
  /// Loads the next eight rays into a packet; false when no ray is left (inlined, as in the
  /// AVX2 walk, so that the packet stays in registers).
  [[gnu::always_inline]] bool load(PacketRays& rays, PacketState& state);

  RayBatcher<kMode, 8> rays_;
  const DenseBox& box_;
  const MarkSpec& spec_;
};

template <MarkSpec::Mode kMode>
inline bool PacketWalk<kMode>::load(PacketRays& rays, PacketState& state) {
  int j = 0;
  if (!rays_.next(j)) return false;
  const Batch& batch = rays_.batch();
  rays.dx = _mm512_load_pd(batch.t_delta[0] + j);
  rays.dy = _mm512_load_pd(batch.t_delta[1] + j);
  rays.dz = _mm512_load_pd(batch.t_delta[2] + j);
  rays.length = _mm512_load_pd(batch.length + j);
  // The batch's offsets are exact integers below 2^31 in doubles.
  rays.ox = _mm512_cvttpd_epi32(_mm512_load_pd(batch.offset_step[0] + j));
  rays.oy = _mm512_cvttpd_epi32(_mm512_load_pd(batch.offset_step[1] + j));
  rays.oz = _mm512_cvttpd_epi32(_mm512_load_pd(batch.offset_step[2] + j));
  rays.end_offset = _mm512_cvttpd_epi32(_mm512_load_pd(batch.end_offset + j));
  state.tx = _mm512_load_pd(batch.t_max[0] + j);
  state.ty = _mm512_load_pd(batch.t_max[1] + j);
  state.tz = _mm512_load_pd(batch.t_max[2] + j);
  state.offset = _mm512_cvttpd_epi32(_mm512_load_pd(batch.offset + j));
  state.last = state.offset;
  state.ended = 0;
  return true;
}

template <MarkSpec::Mode kMode>
void PacketWalk<kMode>::run() {
  // No function call in the step loops (every vector register is caller-saved).
  std::uint8_t* const data = box_.data;
  const std::uint8_t value = spec_.value;
  // One step of every lane: RayWalk::next() (stepLanes() of the AVX2 walk) and, in Store
  // mode, the byte of its voxel (an ended lane writes its last voxel's byte again, which
  // changes nothing). Returns the lanes that have ended.
  const auto step = [&](const PacketRays& rays, PacketState& state) __attribute__((always_inline)) {
    const __mmask8 x_before_y = _mm512_cmp_pd_mask(state.tx, state.ty, _CMP_LT_OQ);
    const __mmask8 move_x = _kand_mask8(x_before_y, _mm512_cmp_pd_mask(state.tx, state.tz, _CMP_LT_OQ));
    const __mmask8 move_y = _kandn_mask8(x_before_y, _mm512_cmp_pd_mask(state.ty, state.tz, _CMP_LT_OQ));
    const __mmask8 move_z = _knot_mask8(_kor_mask8(move_x, move_y));
    state.tx = _mm512_mask_add_pd(state.tx, move_x, state.tx, rays.dx);
    state.ty = _mm512_mask_add_pd(state.ty, move_y, state.ty, rays.dy);
    state.tz = _mm512_mask_add_pd(state.tz, move_z, state.tz, rays.dz);
    state.offset = _mm256_add_epi32(
        state.offset, _mm256_mask_blend_epi32(move_x, _mm256_mask_blend_epi32(move_y, rays.oz, rays.oy), rays.ox));
    // RayWalk::next() returning false: the end voxel reached, or the next border beyond the length.
    const __mmask8 past_length = _mm512_cmp_pd_mask(
        _mm512_min_pd(_mm512_min_pd(state.tx, state.ty), state.tz), rays.length, _CMP_GT_OQ);
    state.ended = _kor_mask8(state.ended,
                             _kor_mask8(_mm256_cmpeq_epi32_mask(state.offset, rays.end_offset), past_length));
    if constexpr (kMode == MarkSpec::Mode::Store) {
      state.last = _mm256_mask_mov_epi32(state.offset, state.ended, state.last);
      storeAt8(data, state.last, value);
    }
    return static_cast<unsigned>(state.ended);
  };
  PacketRays rays;
  PacketState packet;
  if constexpr (kMode == MarkSpec::Mode::Store) {
    while (load(rays, packet)) {
      while (step(rays, packet) != 0xFFu) {
      }
    }
  } else {
    // MinStepIndex: the lanes of a group start together, so a voxel's k is the step count.
    while (load(rays, packet)) {
      for (int k = 1;; ++k) {
        const unsigned visit = ~step(rays, packet) & 0xFFu;
        if (visit == 0) break;
        alignas(32) std::int32_t offsets[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(offsets), packet.offset);
        for (unsigned left = visit; left != 0; left &= left - 1) {
          writeByte(data + static_cast<std::uint32_t>(offsets[__builtin_ctz(left)]), spec_, k);
        }
      }
    }
  }
}

}  // namespace

void markRaysAvx512(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                    const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                    const OutsideSink& outside) {
  if (spec.mode == MarkSpec::Mode::Store) {
    PacketWalk<MarkSpec::Mode::Store>(origins, ends, lattice, box, spec, outside).run();
  } else {
    PacketWalk<MarkSpec::Mode::MinStepIndex>(origins, ends, lattice, box, spec, outside).run();
  }
}

}  // namespace nbv::kernels::detail

#include "avx512_target_end.hpp"
