#pragma once
// An evaluator used as a planner uses it: refresh() from the map, then the walk on the snapshot
// (ig::evaluate(evaluator, map, ...) does so for tables).

#include "nbv/ig/evaluator.hpp"

#include <span>
#include <vector>

namespace nbv::test {

/// `evaluator` refreshed from `map`, then the voxels the rays of the views reach.
inline std::vector<ig::VisibleVoxel> visibleVoxelsOn(ig::IgEvaluator& evaluator, const grid::OccupancyMap& map,
                                                     std::span<const Eigen::Isometry3d> T_world_cameras,
                                                     std::span<const Eigen::Vector3d> directions_camera,
                                                     const ig::EvaluateOptions& options = ig::EvaluateOptions{}) {
  evaluator.refresh(map, options.snapshotOptions());
  return evaluator.visibleVoxels(T_world_cameras, directions_camera, options.walk);
}

/// The same for one view.
inline std::vector<ig::VisibleVoxel> visibleVoxelsOn(ig::IgEvaluator& evaluator, const grid::OccupancyMap& map,
                                                     const Eigen::Isometry3d& T_world_camera,
                                                     std::span<const Eigen::Vector3d> directions_camera,
                                                     const ig::EvaluateOptions& options = ig::EvaluateOptions{}) {
  return visibleVoxelsOn(evaluator, map, std::span<const Eigen::Isometry3d>(&T_world_camera, 1), directions_camera, options);
}

}  // namespace nbv::test
