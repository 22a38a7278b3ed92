#pragma once
/// \file
/// The voxel lattice and the voxel sequence of a ray, exactly as OctoMap 1.9 computes them.
///
/// SEMANTICS.md "The map": a ray's voxels are those of OctoMap's computeRayKeys.
/// Integration, proximity marks and the IG kernels all walk rays through this one header
/// (the packet traversals of mark_rays.hpp start every ray as setupRay() below does).
/// The arithmetic mirrors OcTreeBaseImpl::computeRayKeys operation by operation (single
/// precision points, double precision tMax/tDelta, the same tie-breaking), so that rays through
/// voxel corners or along faces pick the same voxels as OctoMap. Keep floating-point
/// contraction off where this is compiled (the project builds in ISO mode for that).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace nbv::kernels {

/// Integer voxel index (i, j, k); voxel (i, j, k) spans [i, i+1) * resolution along x, etc.
using Index3 = Eigen::Vector3i;

/// Largest |index| a voxel may have. Points farther out are refused (treated like non-finite
/// points); at 1 cm this is about 10,000 km.
inline constexpr std::int64_t kMaxVoxelIndex = std::int64_t{1} << 30;

/// The voxel lattice: centres at (k + 0.5) * resolution, as OctoMap's keys (minus its 2^15
/// offset). Thread-safe (immutable). OccupancyMap checks the resolution.
class VoxelLattice {
 public:
  /// \param resolution voxel edge length [m], > 0 (not checked here; OccupancyMap checks it).
  explicit VoxelLattice(double resolution)
      : resolution_(resolution), inv_resolution_(1.0 / resolution) {}

  double resolution() const { return resolution_; }
  /// 1 / resolution, the factor worldToIndex() multiplies by.
  double inverseResolution() const { return inv_resolution_; }

  /// Index of the voxel holding world coordinate `coord_m` (OctoMap's coordToKey): the floor of
  /// coord_m / resolution, as truncation stepped down below a negative fraction (exact within
  /// the index range, and without a libm call on a baseline x86-64 build). `coord_m` in range.
  int worldToIndex(double coord_m) const {
    const double scaled = inv_resolution_ * coord_m;
    const int truncated = static_cast<int>(scaled);
    return truncated - (scaled < static_cast<double>(truncated) ? 1 : 0);
  }
  Index3 worldToIndex(const Eigen::Vector3f& p_world) const {
    return {worldToIndex(double{p_world.x()}), worldToIndex(double{p_world.y()}),
            worldToIndex(double{p_world.z()})};
  }
  Index3 worldToIndex(const Eigen::Vector3d& p_world) const {
    return {worldToIndex(p_world.x()), worldToIndex(p_world.y()), worldToIndex(p_world.z())};
  }

  /// True when every coordinate is finite and its voxel index is within +-kMaxVoxelIndex.
  template <class Vec>
  bool inRange(const Vec& p_world) const {
    bool in = true;
    for (int a = 0; a < 3; ++a) {  // false for NaN and infinities too
      in &= std::fabs(inv_resolution_ * static_cast<double>(p_world[a])) < static_cast<double>(kMaxVoxelIndex);
    }
    return in;
  }

  /// World coordinate of the centre of voxel `index` along one axis (OctoMap's keyToCoord).
  double indexToWorld(int index) const { return (static_cast<double>(index) + 0.5) * resolution_; }
  Eigen::Vector3d indexToWorld(const Index3& ijk) const {
    return {indexToWorld(ijk.x()), indexToWorld(ijk.y()), indexToWorld(ijk.z())};
  }

 private:
  double resolution_;
  double inv_resolution_;
};

/// Length of a single-precision vector as octomath::Vector3::norm computes it (float squares
/// and sum, double square root).
inline double octomapNorm(const Eigen::Vector3f& v) {
  const float norm_sq = v.x() * v.x() + v.y() * v.y() + v.z() * v.z();
  return std::sqrt(static_cast<double>(norm_sq));
}

/// `v` divided by its length, as octomath::Vector3::normalized (a zero vector stays zero).
inline Eigen::Vector3f octomapNormalized(const Eigen::Vector3f& v) {
  const double length = octomapNorm(v);
  if (!(length > 0.0)) return v;
  const auto length_f = static_cast<float>(length);
  return {v.x() / length_f, v.y() / length_f, v.z() / length_f};
}

/// OctoMap's initialisation phase of one ray, origin to end (Amanatides & Woo).
struct RaySetup {
  Index3 key_origin;
  Index3 key_end;
  int step[3];       ///< -1, 0 or +1 per axis
  double t_max[3];   ///< ray length at which the next voxel border is crossed, per axis
  double t_delta[3]; ///< ray length between two borders, per axis
  double length;     ///< segment length, in OctoMap's single precision
};

/// Fills `setup` for the ray origin -> end exactly as OctoMap's computeRayKeys does; false
/// if both points lie in one voxel (the ray visits nothing). Both points must satisfy
/// lattice.inRange(). Thread-safe.
inline bool setupRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                     const VoxelLattice& lattice, RaySetup& setup) {
  setup.key_origin = lattice.worldToIndex(origin);
  setup.key_end = lattice.worldToIndex(end);
  if (setup.key_origin == setup.key_end) return false;

  // In OctoMap's precision: float direction and length, double borders and times.
  Eigen::Vector3f direction(end.x() - origin.x(), end.y() - origin.y(), end.z() - origin.z());
  const auto length = static_cast<float>(octomapNorm(direction));
  direction = Eigen::Vector3f(direction.x() / length, direction.y() / length,
                              direction.z() / length);
  setup.length = static_cast<double>(length);
  const double resolution = lattice.resolution();
  for (int a = 0; a < 3; ++a) {
    const float dir = direction[a];
    setup.step[a] = dir > 0.0f ? 1 : (dir < 0.0f ? -1 : 0);
    if (setup.step[a] != 0) {
      double voxel_border = lattice.indexToWorld(setup.key_origin[a]);
      voxel_border += static_cast<float>(setup.step[a] * resolution * 0.5);
      setup.t_max[a] = (voxel_border - static_cast<double>(origin[a])) / static_cast<double>(dir);
      setup.t_delta[a] = resolution / static_cast<double>(std::fabs(dir));
    } else {
      setup.t_max[a] = std::numeric_limits<double>::max();
      setup.t_delta[a] = std::numeric_limits<double>::max();
    }
  }
  return true;
}

/// The incremental phase of OctoMap's walk, one voxel per next(): the same comparisons and
/// additions as computeRayKeys, the axis chosen without branches. Starts at the origin's
/// voxel of a RaySetup.
struct RayWalk {
  Index3 ijk;        ///< the current voxel
  double t_max[3];   ///< as RaySetup, advanced
  const RaySetup* setup;

  explicit RayWalk(const RaySetup& s)
      : ijk(s.key_origin), t_max{s.t_max[0], s.t_max[1], s.t_max[2]}, setup(&s) {}

  /// Moves to the next voxel; false when the walk is over: the next voxel would be the end
  /// point's (excluded by computeRayKeys), or rounding carried the walk past the segment's
  /// length without meeting it (OctoMap stops there too).
  bool next() {
    const RaySetup& s = *setup;
    const bool x_before_y = t_max[0] < t_max[1];
    const bool move_x = x_before_y && t_max[0] < t_max[2];
    const bool move_y = !x_before_y && t_max[1] < t_max[2];
    const bool move_z = !move_x && !move_y;
    ijk.x() += move_x ? s.step[0] : 0;
    ijk.y() += move_y ? s.step[1] : 0;
    ijk.z() += move_z ? s.step[2] : 0;
    t_max[0] = move_x ? t_max[0] + s.t_delta[0] : t_max[0];
    t_max[1] = move_y ? t_max[1] + s.t_delta[1] : t_max[1];
    t_max[2] = move_z ? t_max[2] + s.t_delta[2] : t_max[2];
    if (ijk == s.key_end) return false;
    return withinLength();
  }

  /// False once the next border lies beyond the segment's length (OctoMap's length stop).
  bool withinLength() const {
    return std::min(std::min(t_max[0], t_max[1]), t_max[2]) <= setup->length;
  }
};

/// Calls `visit(const Index3&)` for each voxel of OctoMap's computeRayKeys(origin, end): the
/// origin's voxel first, every voxel the segment crosses, the end point's voxel excluded
/// (nothing at all when both lie in one voxel). Both points must satisfy lattice.inRange().
/// Thread-safe; allocates nothing. This scalar walk is the oracle of the packet traversal.
template <class Visit>
void traverseRayKeys(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                     const VoxelLattice& lattice, Visit&& visit) {
  RaySetup s;
  if (!setupRay(origin, end, lattice, s)) return;
  RayWalk walk(s);
  do {
    visit(static_cast<const Index3&>(walk.ijk));
  } while (walk.next());
}

}  // namespace nbv::kernels
