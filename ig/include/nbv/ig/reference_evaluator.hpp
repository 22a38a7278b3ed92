#pragma once
/// \file The OctoMap reference evaluator: the oracle and the baseline of IgEvaluator.

#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/occupancy_map.hpp"

#include <memory>

namespace nbv::ig {

/// IG the way the paper's released code computes it: an octomap::OcTree holding the map,
/// OctoMap's own computeRayKeys per ray and OcTree::search per voxel, one ray at a time in
/// double precision, with the proximity marks in a hash map beside the tree (OctoMap has no
/// place for them). Nothing in it is tuned or slowed; it shares the per-voxel and per-ray
/// definitions (kernels/information_gain.hpp) with the fast evaluator and nothing else.
/// Thread-safe for concurrent evaluate() calls; runs on the calling thread only.
class ReferenceEvaluator {
 public:
  /// Copies `map` into an OcTree and a mark table.
  /// \throws InvalidArgument if the map extends beyond OctoMap's 16-bit keys.
  explicit ReferenceEvaluator(const OccupancyMap& map);
  ~ReferenceEvaluator();
  ReferenceEvaluator(const ReferenceEvaluator&) = delete;
  ReferenceEvaluator& operator=(const ReferenceEvaluator&) = delete;

  /// As IgEvaluator::evaluate() (options.serial, rays_per_task, isa and the snapshot limit do
  /// not apply). \throws InvalidArgument for bad options, views or directions, or a ray that
  /// leaves OctoMap's key range.
  IgTable evaluate(std::span<const Eigen::Isometry3d> T_world_cameras,
                   std::span<const Eigen::Vector3d> directions_camera,
                   const EvaluateOptions& options = EvaluateOptions{}) const;

 private:
  struct Octree;
  OccupancyMap empty_like_;  ///< the map's configuration and lattice, for validation
  std::unique_ptr<Octree> octree_;
};

}  // namespace nbv::ig
