#pragma once
// Private, for the -mavx2 sources only: one step of OctoMap's DDA in four lanes.

#include <immintrin.h>

namespace nbv::kernels::detail {

/// The axes four lanes move along at one step; each mask is all ones or all zeros per lane.
struct LaneMoves {
  __m256d x, y, z;
};

/// One step of RayWalk::next() in each lane: the axis of the nearest border, chosen as OctoMap
/// chooses it, then its border time and the lane's offset advanced. Adding +0.0 leaves a value
/// unchanged, so the masked adds equal OctoMap's conditional add. `o*`: offset change per
/// step along each axis; `all`: every bit set.
inline LaneMoves stepLanes(__m256d& tx, __m256d& ty, __m256d& tz, const __m256d& dx, const __m256d& dy,
                           const __m256d& dz, __m256d& offset, const __m256d& ox, const __m256d& oy,
                           const __m256d& oz, const __m256d& all) {
  const __m256d x_before_y = _mm256_cmp_pd(tx, ty, _CMP_LT_OQ);
  LaneMoves move;
  move.x = _mm256_and_pd(x_before_y, _mm256_cmp_pd(tx, tz, _CMP_LT_OQ));
  move.y = _mm256_andnot_pd(x_before_y, _mm256_cmp_pd(ty, tz, _CMP_LT_OQ));
  move.z = _mm256_andnot_pd(_mm256_or_pd(move.x, move.y), all);
  tx = _mm256_add_pd(tx, _mm256_and_pd(move.x, dx));
  ty = _mm256_add_pd(ty, _mm256_and_pd(move.y, dy));
  tz = _mm256_add_pd(tz, _mm256_and_pd(move.z, dz));
  offset = _mm256_add_pd(offset, _mm256_or_pd(_mm256_or_pd(_mm256_and_pd(move.x, ox), _mm256_and_pd(move.y, oy)),
                                              _mm256_and_pd(move.z, oz)));
  return move;
}

}  // namespace nbv::kernels::detail
