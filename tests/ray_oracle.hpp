#pragma once
// The oracle of the IG ray kernel, for the tests and fuzz_ig_rays: a ray's sums added voxel
// by voxel over OctoMap's keys (traverseRayKeys), then the end point's voxel, cut after the
// first voxel with kStop (SEMANTICS.md "Views and rays", "Volumetric information"). No closed forms and no skips, unlike kernels::walkRays.

#include "nbv/kernels/ig_rays.hpp"

namespace nbv::test {

inline kernels::RayResult resultOverOctomapKeys(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                                                const kernels::VoxelLattice& lattice,
                                                const kernels::SnapshotView& view) {
  kernels::RayAccumulator sums;
  bool stopped = false;
  kernels::traverseRayKeys(origin, end, lattice, [&](const kernels::Index3& ijk) {
    if (stopped) return;
    const kernels::VoxelTerms& t = view.terms(ijk);
    sums.add(t);
    stopped = (t.flags & kernels::voxel_flag::kStop) != 0;
  });
  if (!stopped) sums.add(view.terms(lattice.worldToIndex(end)));
  return {sums.finish(), sums.counts()};
}

/// The sums of resultOverOctomapKeys().
inline kernels::RaySums sumOverOctomapKeys(const Eigen::Vector3f& origin, const Eigen::Vector3f& end,
                                           const kernels::VoxelLattice& lattice, const kernels::SnapshotView& view) {
  return resultOverOctomapKeys(origin, end, lattice, view).sums;
}

}  // namespace nbv::test
