#pragma once
// Private: OctoMap's DDA (setupRay() and RayWalk::next() of ray_keys.hpp) in the lanes of a
// register type S (simd_avx2.hpp: 4 lanes, simd_avx512.hpp: 8 lanes). Every lane performs the
// scalar walk's single and double precision operations in the same order, so it has the
// scalar walk's bits and visits its voxels. The packet walks of markRays()
// (mark_rays_packet.hpp) and of the IG rays (ig_rays_packet.hpp) set up and step their rays
// with it. Included inside the target options of the source that instantiates it.

#include "nbv/kernels/ray_keys.hpp"

#include <limits>

namespace nbv::kernels::detail {

template <class S>
struct LaneDda {
  using D = typename S::D;
  using M = typename S::M;

  /// RaySetup of each lane's ray, integers (keys, steps) as doubles.
  struct Setup {
    D key_origin[3], key_end[3], step[3], t_max[3], t_delta[3], length;
  };

  using F = typename S::F;

  /// setupRay() of the lanes' rays origin -> end. Returns the lanes whose points lie in one
  /// voxel (setupRay() returns false); their other fields are meaningless. Every point must
  /// satisfy lattice.inRange().
  [[gnu::always_inline]] static M setup(const F origin[3], const F end[3], const VoxelLattice& lattice, Setup& s) {
    const double resolution = lattice.resolution();
    const D inverse = S::set1(lattice.inverseResolution());
    const D zero = S::zero();
    M same_voxel = S::eq(zero, zero);
    D from[3];
    F dir[3];
    for (int a = 0; a < 3; ++a) {
      // VoxelLattice::worldToIndex(): floor(1 / resolution * coordinate), in double precision.
      from[a] = S::toDouble(origin[a]);
      s.key_origin[a] = S::floor(S::mul(inverse, from[a]));
      s.key_end[a] = S::floor(S::mul(inverse, S::toDouble(end[a])));
      same_voxel = S::both(same_voxel, S::eq(s.key_end[a], s.key_origin[a]));
      dir[a] = S::subF(end[a], origin[a]);
    }
    // octomapNorm(): single-precision squares summed x, y, z in order, a double square root,
    // the length rounded to single precision; the direction divided by it in single precision.
    const F norm_sq = S::addF(S::addF(S::mulF(dir[0], dir[0]), S::mulF(dir[1], dir[1])), S::mulF(dir[2], dir[2]));
    const F length = S::toSingle(S::sqrt(S::toDouble(norm_sq)));
    s.length = S::toDouble(length);
    const D no_step = S::set1(std::numeric_limits<double>::max());
    const D half_voxel = S::set1(static_cast<float>(resolution * 0.5));
    const D minus_half_voxel = S::set1(static_cast<float>(-resolution * 0.5));
    for (int a = 0; a < 3; ++a) {
      const D d = S::toDouble(S::divF(dir[a], length));
      const M forward = S::gt(d, zero), backward = S::lt(d, zero);
      s.step[a] = S::select(forward, S::set1(1.0), S::select(backward, S::set1(-1.0), zero));
      // indexToWorld(key_origin) + float(step * resolution * 0.5): the first border ahead.
      const D centre = S::mul(S::add(s.key_origin[a], S::set1(0.5)), S::set1(resolution));
      const D border = S::add(centre, S::select(forward, half_voxel, minus_half_voxel));
      const M moves = S::either(forward, backward);
      s.t_max[a] = S::select(moves, S::div(S::sub(border, from[a]), d), no_step);
      s.t_delta[a] = S::select(moves, S::div(S::set1(resolution), S::abs(d)), no_step);
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
  /// offsets are doubles (D) or S's offset lanes (S::O), whose add() and select() S overloads.
  template <class O>
  [[gnu::always_inline]] static Moves step(D& tx, D& ty, D& tz, D dx, D dy, D dz, O& offset, O ox, O oy, O oz) {
    const M x_before_y = S::lt(tx, ty);
    Moves move;
    move.x = S::both(x_before_y, S::lt(tx, tz));
    move.y = S::butNot(x_before_y, S::lt(ty, tz));
    move.x_or_y = S::either(move.x, move.y);
    tx = S::addWhere(move.x, tx, dx);
    ty = S::addWhere(move.y, ty, dy);
    tz = S::addUnless(move.x_or_y, tz, dz);
    offset = S::add(offset, S::select(move.x, ox, S::select(move.y, oy, oz)));
    return move;
  }

  /// RayWalk::withinLength() negated, lane-wise: the next border lies beyond the length.
  [[gnu::always_inline]] static M pastLength(D tx, D ty, D tz, D length) {
    return S::gt(S::min(S::min(tx, ty), tz), length);
  }
};

}  // namespace nbv::kernels::detail
