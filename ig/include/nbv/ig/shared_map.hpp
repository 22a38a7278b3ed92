#pragma once
/// \file A map shared by a mapping thread and planner threads: the mapping thread integrates
/// scans, planners refresh their evaluators' snapshots from it and evaluate or decide on those
/// snapshots while the next scans come in.

#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/occupancy_map.hpp"

#include <cstdint>
#include <mutex>
#include <shared_mutex>
#include <span>

namespace nbv::ig {

using grid::DepthImage;
using grid::DepthOptions;
using grid::IntegrateOptions;
using grid::ScanStats;

/// An OccupancyMap behind a reader-writer lock. The mechanism: a writer (integrate) holds the
/// lock alone for the scan; a reader holds it shared only to copy what changed into its own
/// snapshot (IgEvaluator::refresh(), which reads the blocks the map reports changed), then
/// walks its rays on that snapshot without the lock. So a scan waits at most for a refresh,
/// an evaluation never waits for a scan once refreshed, and every evaluation sees the map as
/// it stood between two integrations, never a scan half applied.
///
/// Thread-safety: every member may be called from any thread at any time.
class SharedMap {
 public:
  explicit SharedMap(OccupancyMap map = OccupancyMap{}) : map_(std::move(map)) {}

  /// OccupancyMap::integrate() under the exclusive lock. \throws as it does.
  ScanStats integrate(std::span<const Eigen::Vector3f> points_world, const Eigen::Vector3f& origin_world,
                      const IntegrateOptions& options = IntegrateOptions{}) {
    const std::unique_lock lock(mutex_);
    return map_.integrate(points_world, origin_world, options);
  }
  /// OccupancyMap::integrateDepth() under the exclusive lock. \throws as it does.
  ScanStats integrateDepth(const DepthImage& depth, const sensor::PinholeCamera& camera,
                           const Eigen::Isometry3d& T_world_camera, const DepthOptions& depth_options = DepthOptions{},
                           const IntegrateOptions& options = IntegrateOptions{}) {
    const std::unique_lock lock(mutex_);
    return map_.integrateDepth(depth, camera, T_world_camera, depth_options, options);
  }

  /// Brings `evaluator`'s snapshot up to the map under the shared lock (IgEvaluator::refresh());
  /// then IgEvaluator::evaluate() or AnytimeDecider::decide() work on it without the lock.
  /// Returns the map's revision the snapshot now holds. \throws as IgEvaluator::refresh().
  std::uint64_t refresh(IgEvaluator& evaluator, const SnapshotOptions& options = SnapshotOptions{}) const {
    const std::shared_lock lock(mutex_);
    evaluator.refresh(map_, options);
    return map_.revision();
  }

  /// Calls `read(const OccupancyMap&)` under the shared lock and returns what it returns: the
  /// map does not change meanwhile (keep it short: integration waits).
  template <class Read>
  decltype(auto) read(Read&& read) const {
    const std::shared_lock lock(mutex_);
    return read(static_cast<const OccupancyMap&>(map_));
  }

 private:
  mutable std::shared_mutex mutex_;
  OccupancyMap map_;
};

}  // namespace nbv::ig
