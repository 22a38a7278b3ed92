#pragma once
// Private: OctoMap's DDA (setupRay() and RayWalk::next() of ray_keys.hpp) in the lanes of a
// register type S (simd_avx2.hpp: 4 lanes, simd_avx512.hpp: 8 lanes), written in the
// operators of their value types (lane_values.hpp). Every lane performs the
// scalar walk's single and double precision operations in the same order, so it has the
// scalar walk's bits and visits its voxels. The packet walks of markRays()
// (mark_rays_packet.hpp) and of the IG rays (ig_rays_packet.hpp) set up and step their rays
// with it. Included inside the target options of the source that instantiates it.

#include "lane_values.hpp"

#include "nbv/kernels/ray_keys.hpp"

#include <limits>

namespace nbv::kernels::detail {

template <class S>
struct LaneDda {
  using D = LaneDoubles<S>;
  using M = LaneMask<S>;
  using F = typename S::F;

  /// RaySetup of each lane's ray, integers (keys, steps) as doubles.
  struct Setup {
    D key_origin[3], key_end[3], step[3], t_max[3], t_delta[3], length;
  };

  /// setupRay() of the lanes' rays origin -> end. Returns the lanes whose points lie in one
  /// voxel (setupRay() returns false); their other fields are meaningless. Every point must
  /// satisfy lattice.inRange().
  [[gnu::always_inline]] static M setup(const F origin[3], const F end[3], const VoxelLattice& lattice, Setup& s) {
    const double resolution = lattice.resolution();
    const D inverse(lattice.inverseResolution());
    const D zero = S::zero();
    M same_voxel = zero == zero;
    D from[3];
    F dir[3];
    for (int a = 0; a < 3; ++a) {
      // VoxelLattice::worldToIndex(): floor(1 / resolution * coordinate), in double precision.
      from[a] = S::toDouble(origin[a]);
      s.key_origin[a] = floor(inverse * from[a]);
      s.key_end[a] = floor(inverse * D(S::toDouble(end[a])));
      same_voxel = same_voxel & (s.key_end[a] == s.key_origin[a]);
      dir[a] = S::subF(end[a], origin[a]);
    }
    // octomapNorm(): single-precision squares summed x, y, z in order, a double square root,
    // the length rounded to single precision; the direction divided by it in single precision.
    const F norm_sq = S::addF(S::addF(S::mulF(dir[0], dir[0]), S::mulF(dir[1], dir[1])), S::mulF(dir[2], dir[2]));
    const F length = S::toSingle(S::sqrt(S::toDouble(norm_sq)));
    s.length = S::toDouble(length);
    const D no_step(std::numeric_limits<double>::max());
    const D half_voxel(static_cast<float>(resolution * 0.5));
    const D minus_half_voxel(static_cast<float>(-resolution * 0.5));
    for (int a = 0; a < 3; ++a) {
      const D d = S::toDouble(S::divF(dir[a], length));
      const M forward = d > zero, backward = d < zero;
      s.step[a] = select(forward, D(1.0), select(backward, D(-1.0), zero));
      // indexToWorld(key_origin) + float(step * resolution * 0.5): the first border ahead.
      const D centre = (s.key_origin[a] + D(0.5)) * D(resolution);
      const D border = centre + select(forward, half_voxel, minus_half_voxel);
      const M moves = forward | backward;
      s.t_max[a] = select(moves, (border - from[a]) / d, no_step);
      s.t_delta[a] = select(moves, D(resolution) / abs(d), no_step);
    }
    return same_voxel;
  }

  /// The axes the lanes moved along in one step(): a lane moved along z where x_or_y is clear.
  struct Moves {
    M x, y, x_or_y;
  };

  /// RayWalk::next()'s move in each lane: the axis of the nearest border, chosen as OctoMap
  /// chooses it, then its border time advanced by t_delta (d*) and the lane's voxel offset by
  /// the axis's offset step (o*). A masked add leaves the other lanes' values unchanged. The
  /// border times are D or S's own lanes (V); the offsets are D or S's offset lanes (S::O),
  /// whose add() and select() S overloads.
  template <class V, class O>
  [[gnu::always_inline]] static Moves step(V& tx, V& ty, V& tz, D dx, D dy, D dz, O& offset, O ox, O oy, O oz) {
    const D x = tx, y = ty, z = tz;
    const M x_before_y = x < y;
    Moves move;
    move.x = x_before_y & (x < z);
    move.y = andNot(y < z, x_before_y);
    move.x_or_y = move.x | move.y;
    tx = addWhere(move.x, x, dx);
    ty = addWhere(move.y, y, dy);
    tz = addUnless(move.x_or_y, z, dz);
    offset = S::add(offset, S::select(move.x, ox, S::select(move.y, oy, oz)));
    return move;
  }

  /// RayWalk::withinLength() negated, lane-wise: the next border lies beyond the length.
  [[gnu::always_inline]] static M pastLength(D tx, D ty, D tz, D length) {
    return min(min(tx, ty), tz) > length;
  }
};

}  // namespace nbv::kernels::detail
