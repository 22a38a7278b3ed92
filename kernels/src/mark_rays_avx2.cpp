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

/// Per-lane ray state, spilled to memory only when a lane's ray ends.
struct alignas(32) Lanes {
  double offset[4] = {};
  double end_offset[4] = {};
  double t_max[3][4] = {};
  double t_delta[3][4] = {};
  double offset_step[3][4] = {};  ///< step[a] * stride[a]
  double length[4] = {};
  double step_index[4] = {};      ///< k of the lane's current voxel (MinStepIndex)
};

template <MarkSpec::Mode kMode>
void walk(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
          const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
          const OutsideSink& outside) {
  const double stride[3] = {1.0, static_cast<double>(box.size[0]),
                            static_cast<double>(box.size[0]) * box.size[1]};
  Lanes lanes;
  // Rays set up four at a time (setupRays4), waiting in `ready` for a free lane.
  RaySetups4 ready;
  int ready_lane[4];
  int ready_count = 0, ready_next = 0;
  std::size_t next = 0;
  // Sets up the next four rays; the origin's voxel of each is written here, and rays that may
  // leave the box are walked here by the scalar oracle. False when no ray is left.
  auto prepare = [&] {
    if (next >= ends.size()) return false;
    const std::size_t count = std::min<std::size_t>(4, ends.size() - next);
    const Eigen::Vector3f* from[4];
    const Eigen::Vector3f* to[4];
    for (std::size_t j = 0; j < 4; ++j) {
      const std::size_t i = next + std::min(j, count - 1);  // short batches repeat their last ray
      from[j] = &origins[origins.size() == 1 ? 0 : i];
      to[j] = &ends[i];
    }
    next += count;
    setupRays4(from, to, lattice, ready);
    ready_count = ready_next = 0;
    for (int j = 0; j < static_cast<int>(count); ++j) {
      if ((ready.same_voxel >> j) & 1u) continue;
      const Index3 key_origin = ready.keyOrigin(j), key_end = ready.keyEnd(j);
      checkStepRange(spec, key_origin, key_end);
      if (!box.holdsWithMargin(key_origin) || !box.holdsWithMargin(key_end)) {
        markRayScalar(*from[j], *to[j], lattice, box, spec, outside);
        continue;
      }
      writeVoxel(box, spec, outside, key_origin, 0);
      ready_lane[ready_count++] = j;
    }
    return true;
  };
  // Starts the next ray that visits anything in `lane`. False when no ray is left.
  auto start = [&](int lane) {
    while (ready_next == ready_count) {
      if (!prepare()) return false;
    }
    const int j = ready_lane[ready_next++];
    std::size_t at_origin = 0, at_end = 0;
    box.locate(ready.keyOrigin(j), at_origin);
    box.locate(ready.keyEnd(j), at_end);
    lanes.offset[lane] = static_cast<double>(at_origin);
    lanes.end_offset[lane] = static_cast<double>(at_end);
    for (int a = 0; a < 3; ++a) {
      lanes.t_max[a][lane] = ready.t_max[a][j];
      lanes.t_delta[a][lane] = ready.t_delta[a][j];
      lanes.offset_step[a][lane] = ready.step[a][j] * stride[a];
    }
    lanes.length[lane] = ready.length[j];
    lanes.step_index[lane] = 0.0;
    return true;
  };
  unsigned active = 0;
  for (int lane = 0; lane < 4; ++lane) {
    if (start(lane)) active |= 1u << lane;
  }

  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  const __m256d one = _mm256_set1_pd(1.0);
  std::uint8_t* const data = box.data;
  const std::uint8_t value = spec.value;
  while (active != 0) {
    __m256d offset = _mm256_load_pd(lanes.offset);
    const __m256d end_offset = _mm256_load_pd(lanes.end_offset);
    __m256d tx = _mm256_load_pd(lanes.t_max[0]), ty = _mm256_load_pd(lanes.t_max[1]),
            tz = _mm256_load_pd(lanes.t_max[2]);
    const __m256d dx = _mm256_load_pd(lanes.t_delta[0]), dy = _mm256_load_pd(lanes.t_delta[1]),
                  dz = _mm256_load_pd(lanes.t_delta[2]);
    const __m256d ox = _mm256_load_pd(lanes.offset_step[0]), oy = _mm256_load_pd(lanes.offset_step[1]),
                  oz = _mm256_load_pd(lanes.offset_step[2]);
    const __m256d length = _mm256_load_pd(lanes.length);
    __m256d step_index = _mm256_load_pd(lanes.step_index);

    // No function call in this loop: a call would force every ymm register (all are
    // caller-saved) to be spilled and reloaded at each step.
    unsigned finished = 0;
    while (finished == 0) {
      stepLanes(tx, ty, tz, dx, dy, dz, offset, ox, oy, oz, all);

      const __m256d at_end = _mm256_cmp_pd(offset, end_offset, _CMP_EQ_OQ);
      const __m256d past = _mm256_cmp_pd(_mm256_min_pd(_mm256_min_pd(tx, ty), tz), length, _CMP_GT_OQ);
      finished = static_cast<unsigned>(_mm256_movemask_pd(_mm256_or_pd(at_end, past))) & active;
      const unsigned visit = active & ~finished;

      if constexpr (kMode == MarkSpec::Mode::MinStepIndex) step_index = _mm256_add_pd(step_index, one);

      // Offsets (and step indices) leave the vector registers by extraction, not through
      // memory: forwarding a 16-byte store to 4-byte loads stalls on some cores.
      const __m128i at = _mm256_cvttpd_epi32(offset);
      if (visit == 0xFu) {  // the common case: four voxels to write
        if constexpr (kMode == MarkSpec::Mode::Store) {
          std::atomic_ref<std::uint8_t>(data[_mm_cvtsi128_si32(at)]).store(value, std::memory_order_relaxed);
          std::atomic_ref<std::uint8_t>(data[_mm_extract_epi32(at, 1)]).store(value, std::memory_order_relaxed);
          std::atomic_ref<std::uint8_t>(data[_mm_extract_epi32(at, 2)]).store(value, std::memory_order_relaxed);
          std::atomic_ref<std::uint8_t>(data[_mm_extract_epi32(at, 3)]).store(value, std::memory_order_relaxed);
        } else {
          const __m128i k = _mm256_cvttpd_epi32(step_index);
          writeByte(data + _mm_cvtsi128_si32(at), spec, _mm_cvtsi128_si32(k));
          writeByte(data + _mm_extract_epi32(at, 1), spec, _mm_extract_epi32(k, 1));
          writeByte(data + _mm_extract_epi32(at, 2), spec, _mm_extract_epi32(k, 2));
          writeByte(data + _mm_extract_epi32(at, 3), spec, _mm_extract_epi32(k, 3));
        }
        continue;
      }
      alignas(16) std::int32_t offsets[4], indices[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(offsets), at);
      _mm_store_si128(reinterpret_cast<__m128i*>(indices), _mm256_cvttpd_epi32(step_index));
      for (unsigned left = visit; left != 0; left &= left - 1) {
        const int lane = __builtin_ctz(left);
        writeByte(data + offsets[lane], spec, indices[lane]);
      }
    }

    // Some rays ended: spill the state, start new rays in their lanes, reload.
    _mm256_store_pd(lanes.offset, offset);
    _mm256_store_pd(lanes.t_max[0], tx);
    _mm256_store_pd(lanes.t_max[1], ty);
    _mm256_store_pd(lanes.t_max[2], tz);
    _mm256_store_pd(lanes.step_index, step_index);
    for (unsigned done = finished; done != 0; done &= done - 1) {
      const int lane = __builtin_ctz(done);
      if (!start(lane)) active &= ~(1u << lane);
    }
  }
}

}  // namespace

void markRaysAvx2(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                  const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                  const OutsideSink& outside) {
  if (spec.mode == MarkSpec::Mode::Store) {
    walk<MarkSpec::Mode::Store>(origins, ends, lattice, box, spec, outside);
  } else {
    walk<MarkSpec::Mode::MinStepIndex>(origins, ends, lattice, box, spec, outside);
  }
}

}  // namespace nbv::kernels::detail
