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
  std::size_t next = 0;
  // Starts the next ray that visits anything in `lane` (its first voxel, the origin's, is
  // written here); rays that may leave the box are walked here by the scalar oracle.
  // False when no ray is left.
  auto start = [&](int lane) {
    RaySetup s;
    while (next < ends.size()) {
      const std::size_t i = next++;
      const Eigen::Vector3f& origin = origins[origins.size() == 1 ? 0 : i];
      if (!setupRay(origin, ends[i], lattice, s)) continue;
      checkStepRange(spec, s);
      if (!box.holdsWithMargin(s.key_origin) || !box.holdsWithMargin(s.key_end)) {
        markRayScalar(origin, ends[i], lattice, box, spec, outside);
        continue;
      }
      writeVoxel(box, spec, outside, s.key_origin, 0);
      std::size_t at_origin = 0, at_end = 0;
      box.locate(s.key_origin, at_origin);
      box.locate(s.key_end, at_end);
      lanes.offset[lane] = static_cast<double>(at_origin);
      lanes.end_offset[lane] = static_cast<double>(at_end);
      for (int a = 0; a < 3; ++a) {
        lanes.t_max[a][lane] = s.t_max[a];
        lanes.t_delta[a][lane] = s.t_delta[a];
        lanes.offset_step[a][lane] = s.step[a] * stride[a];
      }
      lanes.length[lane] = s.length;
      lanes.step_index[lane] = 0.0;
      return true;
    }
    return false;
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
