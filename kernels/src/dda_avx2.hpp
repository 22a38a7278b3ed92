#pragma once
// Private, for the -mavx2 sources only: one step of OctoMap's DDA in four lanes.

#include "nbv/kernels/ray_keys.hpp"

#include <immintrin.h>

#include <cstdint>
#include <limits>

namespace nbv::kernels::detail {

/// The axes four lanes move along at one step; each mask is all ones or all zeros per lane.
/// A lane moves along z where `x_or_y` is clear.
struct LaneMoves {
  __m256d x, y, x_or_y;
};

/// One step of RayWalk::next() in each lane: the axis of the nearest border, chosen as OctoMap
/// chooses it, then its border time and the lane's offset advanced. Adding +0.0 leaves a value
/// unchanged, so the masked adds equal OctoMap's conditional add. `o*`: offset change per
/// step along each axis.
inline LaneMoves stepLanes(__m256d& tx, __m256d& ty, __m256d& tz, const __m256d& dx, const __m256d& dy,
                           const __m256d& dz, __m256d& offset, const __m256d& ox, const __m256d& oy,
                           const __m256d& oz) {
  const __m256d x_before_y = _mm256_cmp_pd(tx, ty, _CMP_LT_OQ);
  LaneMoves move;
  move.x = _mm256_and_pd(x_before_y, _mm256_cmp_pd(tx, tz, _CMP_LT_OQ));
  move.y = _mm256_andnot_pd(x_before_y, _mm256_cmp_pd(ty, tz, _CMP_LT_OQ));
  move.x_or_y = _mm256_or_pd(move.x, move.y);
  tx = _mm256_add_pd(tx, _mm256_and_pd(move.x, dx));
  ty = _mm256_add_pd(ty, _mm256_and_pd(move.y, dy));
  tz = _mm256_add_pd(tz, _mm256_andnot_pd(move.x_or_y, dz));
  offset = _mm256_add_pd(offset, _mm256_blendv_pd(_mm256_blendv_pd(oz, oy, move.y), ox, move.x));
  return move;
}

/// RayWalk::withinLength() negated, lane-wise: the next border lies beyond the length.
inline __m256d pastLength(const __m256d& tx, const __m256d& ty, const __m256d& tz, const __m256d& length) {
  return _mm256_cmp_pd(_mm256_min_pd(_mm256_min_pd(tx, ty), tz), length, _CMP_GT_OQ);
}

/// Lane masks (all bits set or clear per lane) of the low four bits of `lanes`.
inline __m256d laneMask(unsigned lanes) {
  const __m256i bits = _mm256_set_epi64x(8, 4, 2, 1);
  const __m256i set = _mm256_and_si256(_mm256_set1_epi64x(static_cast<std::int64_t>(lanes)), bits);
  return _mm256_castsi256_pd(_mm256_cmpeq_epi64(set, bits));
}

/// setupRay() of four rays, lane i from origin[i] to end[i], in the lanes of each field.
struct RaySetups4 {
  alignas(32) double t_max[3][4];
  alignas(32) double t_delta[3][4];
  alignas(32) double length[4];
  alignas(16) std::int32_t key_origin[3][4];
  alignas(16) std::int32_t key_end[3][4];
  alignas(16) std::int32_t step[3][4];
  unsigned same_voxel;  ///< bit i: lane i's points share a voxel (setupRay() is false)

  Index3 keyOrigin(int lane) const { return {key_origin[0][lane], key_origin[1][lane], key_origin[2][lane]}; }
  Index3 keyEnd(int lane) const { return {key_end[0][lane], key_end[1][lane], key_end[2][lane]}; }
};

/// setupRay() for four rays at once: the same single and double precision operations in the
/// same order (no contraction: this header is compiled with -mavx2 only), so every field of a
/// lane has the bits setupRay() gives, and the divisions and square roots of four rays cost
/// about what one ray's do. A lane's fields are meaningless when its same_voxel bit is set.
/// Every point must satisfy lattice.inRange().
inline void setupRays4(const Eigen::Vector3f* const origin[4], const Eigen::Vector3f* const end[4],
                       const VoxelLattice& lattice, RaySetups4& out) {
  const __m256d inverse = _mm256_set1_pd(lattice.inverseResolution());
  const __m256d resolution = _mm256_set1_pd(lattice.resolution());
  const __m256d half = _mm256_set1_pd(0.5);
  __m128 from[3], to[3], direction[3];
  __m128i same = _mm_set1_epi32(-1);
  for (int a = 0; a < 3; ++a) {
    from[a] = _mm_setr_ps((*origin[0])[a], (*origin[1])[a], (*origin[2])[a], (*origin[3])[a]);
    to[a] = _mm_setr_ps((*end[0])[a], (*end[1])[a], (*end[2])[a], (*end[3])[a]);
    // VoxelLattice::worldToIndex: floor(inverse * double(coordinate)), then to int.
    const __m128i key_origin =
        _mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_mul_pd(inverse, _mm256_cvtps_pd(from[a]))));
    const __m128i key_end = _mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_mul_pd(inverse, _mm256_cvtps_pd(to[a]))));
    _mm_store_si128(reinterpret_cast<__m128i*>(out.key_origin[a]), key_origin);
    _mm_store_si128(reinterpret_cast<__m128i*>(out.key_end[a]), key_end);
    same = _mm_and_si128(same, _mm_cmpeq_epi32(key_origin, key_end));
    direction[a] = _mm_sub_ps(to[a], from[a]);
  }
  out.same_voxel = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(same)));

  // octomapNorm: float squares summed x, y, z in order, double square root, back to float.
  const __m128 norm_sq = _mm_add_ps(_mm_add_ps(_mm_mul_ps(direction[0], direction[0]),
                                               _mm_mul_ps(direction[1], direction[1])),
                                    _mm_mul_ps(direction[2], direction[2]));
  const __m128 length = _mm256_cvtpd_ps(_mm256_sqrt_pd(_mm256_cvtps_pd(norm_sq)));
  _mm256_store_pd(out.length, _mm256_cvtps_pd(length));
  const __m128 zero = _mm_setzero_ps();
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m256d none = _mm256_set1_pd(std::numeric_limits<double>::max());
  for (int a = 0; a < 3; ++a) {
    const __m128 dir = _mm_div_ps(direction[a], length);
    // -1, 0 or +1: the masks are all ones (-1) where true.
    const __m128i step = _mm_sub_epi32(_mm_castps_si128(_mm_cmplt_ps(dir, zero)),
                                       _mm_castps_si128(_mm_cmpgt_ps(dir, zero)));
    _mm_store_si128(reinterpret_cast<__m128i*>(out.step[a]), step);
    const __m256d step_d = _mm256_cvtepi32_pd(step);
    // indexToWorld(key) + float(step * resolution * 0.5), then (border - origin) / dir.
    __m256d border = _mm256_mul_pd(
        _mm256_add_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(out.key_origin[a]))), half),
        resolution);
    border = _mm256_add_pd(border, _mm256_cvtps_pd(_mm256_cvtpd_ps(_mm256_mul_pd(_mm256_mul_pd(step_d, resolution), half))));
    const __m256d dir_d = _mm256_cvtps_pd(dir);
    const __m256d t_max = _mm256_div_pd(_mm256_sub_pd(border, _mm256_cvtps_pd(from[a])), dir_d);
    const __m256d t_delta = _mm256_div_pd(resolution, _mm256_cvtps_pd(_mm_andnot_ps(sign, dir)));
    const __m256d still = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpeq_epi32(step, _mm_setzero_si128())));
    _mm256_store_pd(out.t_max[a], _mm256_blendv_pd(t_max, none, still));
    _mm256_store_pd(out.t_delta[a], _mm256_blendv_pd(t_delta, none, still));
  }
}

}  // namespace nbv::kernels::detail
