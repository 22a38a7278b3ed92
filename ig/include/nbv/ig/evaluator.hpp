#pragma once
/// \file Information gain of candidate views (SEMANTICS.md "Views and rays", "Volumetric information"): the fast evaluator over a snapshot of
/// the map, and the options, ray sets and result table it shares with the OctoMap reference
/// evaluator (reference_evaluator.hpp).

#include "nbv/ig/map_snapshot.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/mark_rays.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace nbv::ig {

using grid::Index3;
using grid::MapConfig;
using grid::VoxelLattice;
using grid::MeasuredVoxel;
using grid::ProximityMark;
using grid::OccupancyMap;
using kernels::Metric;
using kernels::Visibility;

/// What a snapshot of the map is built under, beside the map's own thresholds (MapConfig).
/// Defaults: SEMANTICS.md "Volumetric information".
struct SnapshotOptions {
  Visibility visibility = Visibility::Paper;
  /// Flag the frontier voxels (SEMANTICS.md "Volumetric information"), which the metrics that
  /// read neighbours (fv) need; a snapshot without them (snapshotFor() of metrics that do not
  /// read neighbours) skips the neighbour pass of every refresh.
  bool frontier = true;
  std::size_t max_snapshot_bytes = std::size_t{1} << 31;  ///< refuse larger snapshots

  /// The per-voxel model of these options and the map's configuration (the voxel classes'
  /// thresholds are the map's: MapConfig::occupied_threshold, free_threshold).
  kernels::VoxelModel voxelModel(const MapConfig& map) const;
};

/// How the rays are cast and walked. Defaults: SEMANTICS.md "Views and rays".
struct WalkOptions {
  double max_ray_depth = 1.5;           ///< [m] a ray that meets nothing ends here
  bool serial = false;                  ///< run on the calling thread only
  /// Rays per task (a view's rays are summed task by task in order). Results are identical
  /// for any thread count; this fixes their rounding, so keep it fixed when comparing runs.
  std::size_t rays_per_task = 4096;
  std::optional<kernels::Isa> isa;      ///< instruction set; empty: the best available

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// What an IG table holds.
struct TableOptions {
  std::vector<Metric> metrics{kernels::kAllMetrics.begin(), kernels::kAllMetrics.end()};
  std::uint64_t random_seed = 0;        ///< seed of Metric::Random

  /// Throws InvalidArgument if no metric is requested.
  void validate() const;
};

/// The options of one evaluation of a map: its snapshot, its walk and its table.
struct EvaluateOptions {
  SnapshotOptions snapshot;
  WalkOptions walk;
  TableOptions table;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
  /// `snapshot`, with the frontier flags if a metric of `table` reads neighbours.
  SnapshotOptions snapshotOptions() const;
};

/// `options` with the frontier flags exactly if one of `metrics` reads neighbours (fv): the
/// snapshot an evaluation of `metrics` needs, and no more.
SnapshotOptions snapshotFor(std::span<const Metric> metrics, SnapshotOptions options = SnapshotOptions{});

/// Whether an evaluation of `metrics` casts rays: Metric::Random alone needs no ray, nor a snapshot.
bool castsRays(std::span<const Metric> metrics);

/// Values [view][metric] in the order of TableOptions::metrics, with the sums behind them.
struct IgTable {
  std::vector<Metric> metrics;
  std::vector<double> values;             ///< row-major, views x metrics
  std::vector<kernels::ViewSums> sums;    ///< per view
  std::uint64_t rays = 0;                 ///< rays cast, all views
  std::uint64_t voxels = 0;               ///< voxels on those rays (x_0..x_n each)

  std::size_t views() const { return sums.size(); }
  /// The value of view `view` in column `metric_column` (the order of `metrics`).
  /// \throws InvalidArgument naming the view or column outside the table.
  double value(std::size_t view, std::size_t metric_column) const;
  /// The value of view `view` for `metric`. \throws InvalidArgument for a view outside the
  /// table or a metric it does not hold.
  double value(std::size_t view, Metric metric) const;
};

/// The end point, at `depth_m` along the unit camera-frame direction, of a ray of the view
/// `T_world_camera`, and its origin, in the single precision of OctoMap's points.
struct IgRay {
  Eigen::Vector3f origin;
  Eigen::Vector3f end;
};
IgRay igRay(const Eigen::Isometry3d& T_world_camera, const Eigen::Vector3d& direction_camera,
            double depth_m);

/// A voxel that rays of a view or of a path of views reach (IgEvaluator::visibleVoxels()).
struct VisibleVoxel {
  Index3 ijk;                ///< the voxel's index in the map's lattice
  double visibility = 0.0;   ///< the greatest P_v (Eq. 5) it is reached with by any of the rays
  std::uint32_t rays = 0;    ///< how many of the rays reach it
};

/// Throws InvalidArgument naming the first view that is not a finite rigid pose inside the
/// map's index range, or the first direction that is not finite and unit length, or if there
/// is no direction.
void validateViews(const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                   std::span<const Eigen::Vector3d> directions_camera, double max_ray_depth);

/// The order in which IgEvaluator walks the rays `directions_camera` (camera frame): Morton
/// order of their pixels in the normalised image plane, so that rays next to each other in it
/// cross nearly the same voxels (the packet walks rely on it: neighbouring rays walk together).
/// Rays that do not look forward (z <= 0) come last, in their given order. Thread-safe.
std::vector<Eigen::Vector3d> coherentOrder(std::span<const Eigen::Vector3d> directions_camera);

/// coherentOrder() as a permutation: the index in `directions_camera` of each ray of the order.
std::vector<std::uint32_t> coherentPermutation(std::span<const Eigen::Vector3d> directions_camera);

/// Fills the table's values from its sums (Metric::Random from the seed).
void fillValues(IgTable& table, std::uint64_t random_seed);

/// The fast evaluator: keeps a MapSnapshot of the last map it saw and refreshes only what
/// changed, then walks the rays in SIMD packets with TBB over views and blocks of rays.
/// refresh() is the only call that reads a map; the others work on the snapshot as it is, so a
/// planner beside a mapping thread holds the map's lock for the refresh only (SharedMap).
/// Not thread-safe (one call at a time per evaluator); results are bit-identical for any thread
/// count. Memory: the snapshot, two copies of the ray directions (as given and in walk order),
/// and per-chunk sums of 64 views; no view's rays are held beyond the block being walked.
class IgEvaluator {
 public:
  /// Brings the snapshot up to `map` under `options`, reading only what changed since the last
  /// refresh. \throws CapacityError for a map whose snapshot needs more than
  /// `options.max_snapshot_bytes` or holds more than 2^24 distinct voxel states.
  const SnapshotUpdate& refresh(const OccupancyMap& map, const SnapshotOptions& options = SnapshotOptions{});

  /// IG of each view in `T_world_cameras` (camera to world) on the snapshot, casting the rays of
  /// `directions_camera` (unit, camera frame; see sensor::pixelRays).
  /// \throws InvalidArgument for bad options, views or directions, no direction at all, no
  /// refresh before, or a metric that reads what the snapshot was refreshed without (fv).
  IgTable evaluate(std::span<const Eigen::Isometry3d> T_world_cameras, std::span<const Eigen::Vector3d> directions_camera,
                   const TableOptions& table = TableOptions{}, const WalkOptions& walk = WalkOptions{});

  /// The sums of chosen rays of each view (and their counts, if one of `metrics` reads them):
  /// for view v, the rays directions_camera[i] for i in chosen[v], each walked with the snapshot
  /// and packets evaluate() uses, so that a ray's sums are the bits evaluate() adds for it;
  /// out[v][k] is the ray chosen[v][k]. Anytime decisions walk their samples this way.
  /// \throws as evaluate(); InvalidArgument for a ray index outside the directions or a list
  /// count that is not the view count.
  void walkChosen(std::span<const Eigen::Isometry3d> T_world_cameras, std::span<const Eigen::Vector3d> directions_camera,
                  std::span<const std::vector<std::uint32_t>> chosen, std::span<const Metric> metrics,
                  const WalkOptions& walk, std::vector<std::vector<kernels::RayResult>>& out);

  /// The voxels the rays `directions_camera` of the views `T_world_cameras` reach together (one
  /// view, or a path of views): each ray's x_0..x_n exactly as evaluate() walks them (OctoMap's
  /// ray keys, the end voxel, cut after the first occupied voxel), each voxel once with the
  /// greatest visibility P_v any ray reaches it with (Eq. 5, under the snapshot's visibility; 1
  /// at the camera's voxel) and the count of rays that reach it. Voxels outside the map's
  /// measured box are included (unknown, P_o = 0.5). Ordered by z, then y, then x; no view, no
  /// voxel. A planner computes its own gains from it, e.g. over a path of views with each voxel
  /// counted once. \throws as evaluate().
  std::vector<VisibleVoxel> visibleVoxels(std::span<const Eigen::Isometry3d> T_world_cameras,
                                          std::span<const Eigen::Vector3d> directions_camera,
                                          const WalkOptions& walk = WalkOptions{});

  /// What the last refresh() did to the snapshot.
  const SnapshotUpdate& lastSnapshotUpdate() const { return last_update_; }

 private:
  /// A ray set validated and in the walk's order (rays close in it cross the same voxels).
  struct CoherentRays;
  /// `directions_camera` validated and in the walk's order. Kept until the directions change,
  /// and shared with the other evaluators of the process (the last four ray sets): a planner
  /// scores every decision with one ray set, and checking and ordering the 360,960 rays of the
  /// full set costs about what walking them from one view does (a new evaluator per
  /// reconstruction would pay it each time), while comparing them with kept ones costs far less.
  const std::vector<Eigen::Vector3d>& coherentRays(std::span<const Eigen::Vector3d> directions_camera);

  /// What every walk checks first (the options, a refresh that flagged what `metrics` read, the
  /// views' poses), and the directions in walk order. \throws as evaluate().
  const std::vector<Eigen::Vector3d>& checkedRays(std::span<const Eigen::Isometry3d> T_world_cameras,
                                                  std::span<const Eigen::Vector3d> directions_camera,
                                                  std::span<const Metric> metrics, const WalkOptions& walk);

  /// What the last refresh() read besides the snapshot: the map's lattice and voxel model.
  struct Refreshed {
    VoxelLattice lattice;
    kernels::VoxelModel model;
  };
  MapSnapshot snapshot_;
  SnapshotUpdate last_update_;
  std::optional<Refreshed> refreshed_;
  std::shared_ptr<const CoherentRays> rays_;  ///< the ray set of the last evaluation
};

/// IG of each view of `T_world_cameras` on `map` through `evaluator`: its refresh (which reads
/// only what changed since the last one, so a planner that decides again and again keeps the
/// evaluator) and its evaluation on the snapshot. Metric::Random alone needs no snapshot: the
/// views and rays are checked and the evaluator is left as it is.
/// \throws as IgEvaluator::refresh() and evaluate().
IgTable evaluate(IgEvaluator& evaluator, const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                 std::span<const Eigen::Vector3d> directions_camera, const EvaluateOptions& options = EvaluateOptions{});

/// The same through a new evaluator: one evaluation in one call.
IgTable evaluate(const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                 std::span<const Eigen::Vector3d> directions_camera, const EvaluateOptions& options = EvaluateOptions{});

}  // namespace nbv::ig
