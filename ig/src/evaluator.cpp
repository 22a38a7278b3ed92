#include "nbv/ig/evaluator.hpp"

#include "nbv/fork_join.hpp"
#include "reached_voxels.hpp"
#include "recently_built.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/ig_rays.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace nbv::ig {

void WalkOptions::validate() const {
  if (!(max_ray_depth > 0.0) || !std::isfinite(max_ray_depth)) {
    throw InvalidArgument("max_ray_depth " + numberText(max_ray_depth) + " must be a positive number of metres");
  }
  if (rays_per_task == 0) throw InvalidArgument("rays_per_task must be at least 1");
}

void TableOptions::validate() const {
  if (metrics.empty()) throw InvalidArgument("no metric requested");
}

void EvaluateOptions::validate() const {
  table.validate();
  walk.validate();
}

SnapshotOptions snapshotFor(std::span<const Metric> metrics, SnapshotOptions options) {
  options.frontier = kernels::readsAny(metrics, kernels::metric_reads::kNeighbours);  // fv
  return options;
}

bool castsRays(std::span<const Metric> metrics) {
  return std::any_of(metrics.begin(), metrics.end(), [](Metric m) { return m != Metric::Random; });
}

SnapshotOptions EvaluateOptions::snapshotOptions() const { return snapshotFor(table.metrics, snapshot); }

kernels::VoxelModel SnapshotOptions::voxelModel(const MapConfig& map) const {
  kernels::VoxelModel model;
  model.occupied_threshold = map.occupied_threshold;
  model.free_threshold = map.free_threshold;
  model.proximity_max = 2.0 * map.proximity_range / map.resolution;  // M of Eq. 11
  model.visibility = visibility;
  model.frontier = frontier;
  return model;
}

double IgTable::value(std::size_t view, std::size_t metric_column) const {
  if (view >= views()) {
    throw InvalidArgument("IgTable::value: view " + std::to_string(view) + " is outside the table's " +
                          std::to_string(views()) + " views");
  }
  if (metric_column >= metrics.size()) {
    throw InvalidArgument("IgTable::value: column " + std::to_string(metric_column) + " is outside the table's " +
                          std::to_string(metrics.size()) + " metrics");
  }
  return values[view * metrics.size() + metric_column];
}

double IgTable::value(std::size_t view, Metric metric) const {
  const auto column = std::find(metrics.begin(), metrics.end(), metric);
  if (column == metrics.end()) {
    throw InvalidArgument(std::string("IgTable::value: the table holds no '") + kernels::metricName(metric) + "' column");
  }
  return value(view, static_cast<std::size_t>(column - metrics.begin()));
}

IgRay igRay(const Eigen::Isometry3d& T_world_camera, const Eigen::Vector3d& direction_camera,
            double depth_m) {
  const Eigen::Vector3d end = T_world_camera.translation() + T_world_camera.linear() * (direction_camera * depth_m);
  return {T_world_camera.translation().cast<float>(), end.cast<float>()};
}

namespace {

/// visibleVoxels() cuts a call's rays into about this many tasks per thread, for balance...
constexpr std::size_t kTasksPerThread = 4;
/// ...but no task of fewer rays than this: neighbouring rays share voxels, and a thread's
/// gathering adds a ray's visits cheaply only where its recent voxels are met again.
constexpr std::size_t kMinRaysPerBlock = 128;

void validateDirections(std::span<const Eigen::Vector3d> directions_camera) {
  // Zero rays would score every view 0 for every metric: a caller's mistake, not an answer.
  if (directions_camera.empty()) throw InvalidArgument("no ray direction given: the ray set is empty");
  for (std::size_t i = 0; i < directions_camera.size(); ++i) {
    const Eigen::Vector3d& d = directions_camera[i];
    if (!d.allFinite() || std::abs(d.norm() - 1.0) > 1e-6) {
      throw InvalidArgument("ray direction " + std::to_string(i) + " is not a finite unit vector");
    }
  }
}

void validatePoses(const VoxelLattice& lattice, std::span<const Eigen::Isometry3d> T_world_cameras,
                   double max_ray_depth) {
  for (std::size_t i = 0; i < T_world_cameras.size(); ++i) {
    const Eigen::Isometry3d& T = T_world_cameras[i];
    const Eigen::Matrix3d R = T.linear();
    const bool rigid = T.matrix().allFinite() &&
                       (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
                       R.determinant() > 0.0;
    if (!rigid) throw InvalidArgument("view " + std::to_string(i) + " is not a finite rigid pose");
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(max_ray_depth + lattice.resolution());
    if (!lattice.inRange(T.translation() + reach) || !lattice.inRange(T.translation() - reach)) {
      throw InvalidArgument("view " + std::to_string(i) + " lies outside the map's index range");
    }
  }
}

}  // namespace

void validateViews(const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                   std::span<const Eigen::Vector3d> directions_camera, double max_ray_depth) {
  validateDirections(directions_camera);
  validatePoses(map.lattice(), T_world_cameras, max_ray_depth);
}

void fillValues(IgTable& table, std::uint64_t random_seed) {
  table.values.assign(table.views() * table.metrics.size(), 0.0);
  table.rays = table.voxels = 0;
  for (std::size_t v = 0; v < table.views(); ++v) {
    for (std::size_t m = 0; m < table.metrics.size(); ++m) {
      table.values[v * table.metrics.size() + m] =
          table.metrics[m] == Metric::Random ? kernels::randomScore(random_seed, v)
                                             : kernels::metricValue(table.sums[v], table.metrics[m]);
    }
    table.rays += table.sums[v].rays;
    table.voxels += table.sums[v].voxels;
  }
}

namespace {

/// Interleaves the low 21 bits of x and y (Morton order).
std::uint64_t interleave(std::uint64_t x, std::uint64_t y) {
  auto spread = [](std::uint64_t v) {
    v &= 0x1FFFFF;
    v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
    v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
    v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
    v = (v | (v << 2)) & 0x3333333333333333ull;
    v = (v | (v << 1)) & 0x5555555555555555ull;
    return v;
  };
  return spread(x) | (spread(y) << 1);
}

}  // namespace

// Cells of about one pixel of a typical depth camera. Rays close in this order cross the same
// voxels, so the snapshot stays in cache, and the rays of a packet form a 2 x 2 (four lanes) or
// 4 x 2 (eight) block that walks together; in row-major order a row of rays fans through more
// voxels than the cache holds (docs/PERFORMANCE.md, "Tried and dropped").
std::vector<std::uint32_t> coherentPermutation(std::span<const Eigen::Vector3d> directions) {
  constexpr double kCell = 1.0 / 450.0;  // a pixel at a focal length of ~450 pixels
  constexpr double kOffset = 1 << 20;
  std::vector<std::pair<std::uint64_t, std::size_t>> keys(directions.size());
  for (std::size_t i = 0; i < directions.size(); ++i) {
    const Eigen::Vector3d& d = directions[i];
    std::uint64_t key = ~std::uint64_t{0};  // rays that do not look forward last, in order
    if (d.z() > 1e-9) {
      const double u = std::clamp(d.x() / d.z() / kCell + kOffset, 0.0, 2.0 * kOffset - 1.0);
      const double v = std::clamp(d.y() / d.z() / kCell + kOffset, 0.0, 2.0 * kOffset - 1.0);
      key = interleave(static_cast<std::uint64_t>(u), static_cast<std::uint64_t>(v));
    }
    keys[i] = {key, i};
  }
  std::stable_sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::uint32_t> order(directions.size());
  for (std::size_t i = 0; i < keys.size(); ++i) order[i] = static_cast<std::uint32_t>(keys[i].second);
  return order;
}

std::vector<Eigen::Vector3d> coherentOrder(std::span<const Eigen::Vector3d> directions) {
  std::vector<Eigen::Vector3d> ordered;
  ordered.reserve(directions.size());
  for (const std::uint32_t i : coherentPermutation(directions)) ordered.push_back(directions[i]);
  return ordered;
}

struct IgEvaluator::CoherentRays {
  std::vector<Eigen::Vector3d> given;    ///< the directions as given
  std::vector<Eigen::Vector3d> ordered;  ///< the same in coherent order
  std::vector<std::uint32_t> rank;       ///< each given ray's place in `ordered`

  /// \throws InvalidArgument for no direction or one that is not a finite unit vector.
  explicit CoherentRays(std::span<const Eigen::Vector3d> directions)
      : given((validateDirections(directions), std::vector<Eigen::Vector3d>(directions.begin(), directions.end()))) {
    const std::vector<std::uint32_t> order = coherentPermutation(directions);
    ordered.resize(order.size());
    rank.resize(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      ordered[k] = directions[order[k]];
      rank[order[k]] = static_cast<std::uint32_t>(k);
    }
  }
  /// Compared as bytes (the same bits give the same rays): several times faster than comparing
  /// the 360,960 vectors of the full set element by element.
  bool isOf(std::span<const Eigen::Vector3d> directions) const {
    return !directions.empty() && directions.size() == given.size() &&
           std::memcmp(directions.data(), given.data(), directions.size_bytes()) == 0;
  }
};

const std::vector<Eigen::Vector3d>& IgEvaluator::coherentRays(std::span<const Eigen::Vector3d> directions_camera) {
  if (!rays_ || !rays_->isOf(directions_camera)) {
    static detail::RecentlyBuilt<CoherentRays, 4> kept;
    rays_ = kept.get([&](const CoherentRays& r) { return r.isOf(directions_camera); },
                     [&] { return std::make_shared<const CoherentRays>(directions_camera); });
  }
  return rays_->ordered;
}

const SnapshotUpdate& IgEvaluator::refresh(const OccupancyMap& map, const SnapshotOptions& options) {
  refreshed_.reset();
  last_update_ = snapshot_.update(map, options.voxelModel(map.config()), options.max_snapshot_bytes);
  refreshed_ = Refreshed{map.lattice(), options.voxelModel(map.config())};
  return last_update_;
}

const std::vector<Eigen::Vector3d>& IgEvaluator::checkedRays(std::span<const Eigen::Isometry3d> T_world_cameras,
                                                            std::span<const Eigen::Vector3d> directions_camera,
                                                            std::span<const Metric> metrics, const WalkOptions& walk) {
  walk.validate();
  if (!refreshed_) throw InvalidArgument("the evaluator holds no snapshot: refresh() it from a map first");
  if (kernels::readsAny(metrics, kernels::metric_reads::kNeighbours) && !refreshed_->model.frontier) {
    throw InvalidArgument("the evaluator's snapshot was refreshed without the frontier voxels fv reads: refresh() "
                          "again with SnapshotOptions::frontier set");
  }
  const std::vector<Eigen::Vector3d>& directions = coherentRays(directions_camera);
  validatePoses(refreshed_->lattice, T_world_cameras, walk.max_ray_depth);
  return directions;
}

IgTable IgEvaluator::evaluate(std::span<const Eigen::Isometry3d> T_world_cameras,
                              std::span<const Eigen::Vector3d> directions_camera, const TableOptions& options,
                              const WalkOptions& walk) {
  options.validate();
  const std::vector<Eigen::Vector3d>& directions = checkedRays(T_world_cameras, directions_camera, options.metrics, walk);
  const VoxelLattice& lattice = refreshed_->lattice;
  const kernels::SnapshotView view = snapshot_.view();
  const kernels::Isa isa = walk.isa.value_or(kernels::bestIsa());
  const bool counts = kernels::readsAny(options.metrics, kernels::metric_reads::kCounts);

  const std::size_t rays = directions.size();
  // Metric::Random alone casts no ray: its table has no sums.
  const std::size_t blocks = castsRays(options.metrics) ? (rays + walk.rays_per_task - 1) / walk.rays_per_task : 0;

  // One task per (view, block of rays); each block's sums land in a fixed slot and a view adds
  // its slots in order, so the thread count never changes a result. Views go in chunks, so
  // that memory stays bounded however many views there are.
  constexpr std::size_t kViewsPerChunk = 64;
  std::vector<kernels::ViewSums> partial;
  struct Scratch {
    std::vector<Eigen::Vector3f> ends;
    std::vector<kernels::RaySums> sums;
    std::vector<kernels::RayCounts> counts;  ///< empty unless a metric reads counts
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  IgTable table;
  table.metrics = options.metrics;
  table.sums.resize(T_world_cameras.size());
  for (std::size_t first_view = 0; first_view < T_world_cameras.size() && blocks > 0; first_view += kViewsPerChunk) {
    const std::size_t views = std::min(kViewsPerChunk, T_world_cameras.size() - first_view);
    partial.assign(views * blocks, kernels::ViewSums{});
    auto run_task = [&](std::size_t task) {
      const std::size_t first_ray = (task % blocks) * walk.rays_per_task;
      const std::size_t count = std::min(walk.rays_per_task, rays - first_ray);
      Scratch& s = scratch.local();
      s.ends.resize(count);
      s.sums.resize(count);
      s.counts.resize(counts ? count : 0);
      const Eigen::Isometry3d& T = T_world_cameras[first_view + task / blocks];
      for (std::size_t i = 0; i < count; ++i) {
        s.ends[i] = igRay(T, directions[first_ray + i], walk.max_ray_depth).end;
      }
      kernels::walkRays(T.translation().cast<float>(), s.ends, lattice, view, isa, s.sums, s.counts);
      for (std::size_t i = 0; i < count; ++i) partial[task].add(s.sums[i], counts ? s.counts[i] : kernels::RayCounts{});
    };
    if (walk.serial) {
      for (std::size_t task = 0; task < partial.size(); ++task) run_task(task);
    } else {
      ForkJoin::parallelFor(partial.size(), run_task);
    }
    for (std::size_t v = 0; v < views; ++v) {
      for (std::size_t b = 0; b < blocks; ++b) table.sums[first_view + v].add(partial[v * blocks + b]);
    }
  }
  fillValues(table, options.random_seed);
  return table;
}

void IgEvaluator::walkChosen(std::span<const Eigen::Isometry3d> T_world_cameras,
                             std::span<const Eigen::Vector3d> directions_camera,
                             std::span<const std::vector<std::uint32_t>> chosen, std::span<const Metric> metrics,
                             const WalkOptions& options, std::vector<std::vector<kernels::RayResult>>& out) {
  const std::vector<Eigen::Vector3d>& ordered = checkedRays(T_world_cameras, directions_camera, metrics, options);
  if (chosen.size() != T_world_cameras.size()) {
    throw InvalidArgument("walkChosen: " + std::to_string(chosen.size()) + " ray lists for " +
                          std::to_string(T_world_cameras.size()) + " views");
  }
  const VoxelLattice& lattice = refreshed_->lattice;
  const kernels::SnapshotView view = snapshot_.view();
  const kernels::Isa isa = options.isa.value_or(kernels::bestIsa());
  const bool counts = kernels::readsAny(metrics, kernels::metric_reads::kCounts);
  // Each view's rays in the walk's order (neighbours walk together in a packet), blocks of
  // rays_per_task of them one task each; a ray's sums go back to its place in chosen[v].
  std::vector<std::vector<std::uint32_t>> walk(chosen.size());
  struct Task {
    std::size_t view, first, count;
  };
  std::vector<Task> tasks;
  out.assign(chosen.size(), {});
  for (std::size_t v = 0; v < chosen.size(); ++v) {
    if (v > 0 && chosen[v] == chosen[v - 1]) {  // the same rays as the view before (every view of an anytime level)
      walk[v] = walk[v - 1];
    } else {
      walk[v].resize(chosen[v].size());
      for (std::size_t k = 0; k < chosen[v].size(); ++k) {
        if (chosen[v][k] >= directions_camera.size()) {
          throw InvalidArgument("walkChosen: ray " + std::to_string(chosen[v][k]) + " of view " + std::to_string(v) +
                                " is outside the " + std::to_string(directions_camera.size()) + " directions");
        }
        walk[v][k] = static_cast<std::uint32_t>(k);
      }
      std::sort(walk[v].begin(), walk[v].end(),
                [&](std::uint32_t a, std::uint32_t b) { return rays_->rank[chosen[v][a]] < rays_->rank[chosen[v][b]]; });
    }
    out[v].resize(chosen[v].size());
    for (std::size_t first = 0; first < chosen[v].size(); first += options.rays_per_task) {
      tasks.push_back({v, first, std::min(options.rays_per_task, chosen[v].size() - first)});
    }
  }
  struct Scratch {
    std::vector<Eigen::Vector3f> ends;
    std::vector<kernels::RaySums> sums;
    std::vector<kernels::RayCounts> counts;  ///< empty unless a metric reads counts
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  auto run_task = [&](std::size_t t) {
    const Task& task = tasks[t];
    Scratch& s = scratch.local();
    s.ends.resize(task.count);
    s.sums.resize(task.count);
    s.counts.resize(counts ? task.count : 0);
    const Eigen::Isometry3d& T = T_world_cameras[task.view];
    for (std::size_t i = 0; i < task.count; ++i) {
      const std::uint32_t ray = chosen[task.view][walk[task.view][task.first + i]];
      s.ends[i] = igRay(T, ordered[rays_->rank[ray]], options.max_ray_depth).end;
    }
    kernels::walkRays(T.translation().cast<float>(), s.ends, lattice, view, isa, s.sums, s.counts);
    for (std::size_t i = 0; i < task.count; ++i) {
      out[task.view][walk[task.view][task.first + i]] = {s.sums[i], counts ? s.counts[i] : kernels::RayCounts{}};
    }
  };
  if (options.serial) {
    for (std::size_t t = 0; t < tasks.size(); ++t) run_task(t);
  } else {
    ForkJoin::parallelFor(tasks.size(), run_task);
  }
}

std::vector<VisibleVoxel> IgEvaluator::visibleVoxels(std::span<const Eigen::Isometry3d> T_world_cameras,
                                                     std::span<const Eigen::Vector3d> directions_camera,
                                                     const WalkOptions& options) {
  const std::vector<Eigen::Vector3d>& directions = checkedRays(T_world_cameras, directions_camera, {}, options);
  if (T_world_cameras.empty()) return {};
  const VoxelLattice& lattice = refreshed_->lattice;
  const kernels::SnapshotView view = snapshot_.view();

  // A ray crosses at least one voxel per voxel edge of its length: room for that many per ray.
  const double steps_per_ray = std::ceil(options.max_ray_depth / lattice.resolution()) + 2.0;
  const std::size_t room = static_cast<std::size_t>(std::min(
      static_cast<double>(detail::ReachedVoxels::kFoldAt), steps_per_ray * static_cast<double>(directions.size())));
  tbb::enumerable_thread_specific<detail::ReachedVoxels> reached([room] { return detail::ReachedVoxels(room); });
  // One ray's voxels, x_0..x_n as walkRays() takes them: P_v(x_0) = 1 and P_v(x_{i+1}) =
  // P_v(x_i) * keep(x_i) (Eq. 5), the walk cut after the first voxel with kStop.
  const auto walk_ray = [&](const Eigen::Isometry3d& T_world_camera, const Eigen::Vector3d& direction,
                            detail::ReachedVoxels& out) {
    const Eigen::Vector3f origin = T_world_camera.translation().cast<float>();
    const Eigen::Vector3f end = igRay(T_world_camera, direction, options.max_ray_depth).end;
    double visibility = 1.0;
    const auto visit = [&](const Index3& ijk) {
      out.add(ijk, visibility);
      const kernels::VoxelTerms& terms = view.terms(ijk);
      visibility *= terms.keep;
      return (terms.flags & kernels::voxel_flag::kStop) == 0;
    };
    kernels::RaySetup setup;
    if (kernels::setupRay(origin, end, lattice, setup)) {
      kernels::RayWalk walk(setup);
      do {
        if (!visit(walk.ijk)) return;
      } while (walk.next());
    }
    visit(lattice.worldToIndex(end));
  };
  // One task per (view, block of rays). A voxel's visibility and ray count do not depend on
  // which task met it, so blocks may be cut finer than rays_per_task: into enough tasks for
  // every thread when a call has few views (one view's released rays are a single block).
  const std::size_t threads = options.serial ? 1 : static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  const std::size_t blocks_wanted =
      threads == 1 ? 1 : (kTasksPerThread * threads + T_world_cameras.size() - 1) / T_world_cameras.size();
  const std::size_t block_rays = std::min(
      options.rays_per_task,
      std::max(kMinRaysPerBlock, (directions.size() + blocks_wanted - 1) / blocks_wanted));
  const std::size_t blocks = (directions.size() + block_rays - 1) / block_rays;
  const std::size_t tasks = T_world_cameras.size() * blocks;
  const auto run_task = [&](std::size_t t) {
    detail::ReachedVoxels& mine = reached.local();
    const Eigen::Isometry3d& T_world_camera = T_world_cameras[t / blocks];
    const std::size_t first = (t % blocks) * block_rays;
    const std::size_t last = std::min(directions.size(), first + block_rays);
    for (std::size_t i = first; i < last; ++i) walk_ray(T_world_camera, directions[i], mine);
  };
  if (options.serial) {
    for (std::size_t t = 0; t < tasks; ++t) run_task(t);
  } else {
    ForkJoin::parallelFor(tasks, run_task);
  }
  // Each thread's voxels settled (sorted, each once) side by side, then merged: the result is
  // the voxels of every ray, whichever thread met them (a view and a ray: one part at least).
  std::vector<detail::ReachedVoxels*> parts;
  for (detail::ReachedVoxels& part : reached) parts.push_back(&part);
  const auto settle = [&](std::size_t i) { parts[i]->settle(); };
  if (options.serial || parts.size() == 1) {
    for (std::size_t i = 0; i < parts.size(); ++i) settle(i);
  } else {
    ForkJoin::parallelFor(parts.size(), settle);
  }
  for (std::size_t i = 1; i < parts.size(); ++i) parts[0]->merge(*parts[i]);
  return parts[0]->take();
}

IgTable evaluate(IgEvaluator& evaluator, const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                 std::span<const Eigen::Vector3d> directions_camera, const EvaluateOptions& options) {
  options.validate();
  if (!castsRays(options.table.metrics)) {  // no snapshot to build: only the checks
    validateViews(map, T_world_cameras, directions_camera, options.walk.max_ray_depth);
    IgTable table;
    table.metrics = options.table.metrics;
    table.sums.resize(T_world_cameras.size());
    fillValues(table, options.table.random_seed);
    return table;
  }
  evaluator.refresh(map, options.snapshotOptions());
  return evaluator.evaluate(T_world_cameras, directions_camera, options.table, options.walk);
}

IgTable evaluate(const OccupancyMap& map, std::span<const Eigen::Isometry3d> T_world_cameras,
                 std::span<const Eigen::Vector3d> directions_camera, const EvaluateOptions& options) {
  IgEvaluator evaluator;
  return evaluate(evaluator, map, T_world_cameras, directions_camera, options);
}

}  // namespace nbv::ig
