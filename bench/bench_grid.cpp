// Integration of one full ideal scan (the camera of SEMANTICS.md "Views and rays", 752 x 480) of a sphere of radius
// 0.25 m seen from 0.6 m: nbv at 1 and 2 threads, with each instruction set of its ray walk,
// against liboctomap's insertPointCloud, in one binary so that the ratio is measured side by
// side. Then depth frames as a camera delivers them (752 x 480, 16-bit) integrated through
// integrateDepth() against the same points integrated as a cloud, and frames as a public RGB-D
// dataset ships them (640 x 480, noisy, holey, 2-3 m away) at 1 and 2 threads.
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"

#include "dataset_like.hpp"
#include "octomap_like_map.hpp"
#include "scenes.hpp"

#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace {

struct SphereScan {
  std::vector<Eigen::Vector3f> points;
  Eigen::Vector3f origin;
  SphereScan() {
    const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
    const Eigen::Vector3d position(0.6, 0.0, 0.25);
    points = nbv::test::idealScan(sphere, nbv::test::lookAt(position, sphere.centre));
    origin = position.cast<float>();
  }
};

const SphereScan& scan() {
  static const SphereScan s;
  return s;
}

void setCounters(benchmark::State& state) {
  state.counters["points"] = static_cast<double>(scan().points.size());
  state.counters["points/s"] = benchmark::Counter(
      static_cast<double>(scan().points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

/// An nbv row's arguments (isa, threads, proximity_marks, discretize) as integration options, a map
/// configuration and a task arena; empty after skipping a row whose instruction set is not
/// available here.
struct NbvRow {
  nbv::grid::IntegrateOptions options;
  nbv::grid::OccupancyMap::Config config;
  std::optional<tbb::task_arena> arena;

  explicit NbvRow(benchmark::State& state) {
    options.isa = static_cast<nbv::kernels::Isa>(state.range(0));
    if (!nbv::kernels::isaAvailable(*options.isa)) {
      state.SkipWithError("this instruction set is not available here");
      return;
    }
    if (state.range(2) == 0) config.proximity_range = 0.0;
    options.discretize = state.range(3) == 1;
    arena.emplace(static_cast<int>(state.range(1)));
    state.SetLabel(std::string(nbv::kernels::isaName(*options.isa)) + (options.discretize ? ", discretize" : ""));
  }
  void integrate(nbv::grid::OccupancyMap& map) {
    arena->execute([&] { map.integrate(scan().points, scan().origin, options); });
  }
};

void BM_NbvIntegrate(benchmark::State& state) {
  NbvRow row(state);
  if (!row.arena) return;
  for (auto _ : state) {
    nbv::grid::OccupancyMap map(row.config);
    row.integrate(map);
    benchmark::DoNotOptimize(map.measuredCount());
  }
  setCounters(state);
}
// isa: 0 scalar, 1 AVX2, 2 AVX-512 (nbv::kernels::Isa).
BENCHMARK(BM_NbvIntegrate)
    ->ArgNames({"isa", "threads", "proximity_marks", "discretize"})
    ->Args({0, 1, 0, 0})
    ->ArgsProduct({{1, 2}, {1, 2}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The same scan integrated again and again into one map, as a planner integrates its scans
/// into the map it keeps (after the first, the voxels exist and the updates are clamped).
void BM_NbvIntegrateIntoOneMap(benchmark::State& state) {
  NbvRow row(state);
  if (!row.arena) return;
  nbv::grid::OccupancyMap map(row.config);
  row.integrate(map);
  for (auto _ : state) row.integrate(map);
  benchmark::DoNotOptimize(map.measuredCount());
  setCounters(state);
}
BENCHMARK(BM_NbvIntegrateIntoOneMap)
    ->ArgNames({"isa", "threads", "proximity_marks", "discretize"})
    ->ArgsProduct({{2}, {1, 2}, {0, 1}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_OctomapInsertPointCloud(benchmark::State& state) {
  octomap::Pointcloud cloud;
  for (const auto& p : scan().points) cloud.push_back(p.x(), p.y(), p.z());
  const octomap::point3d origin(scan().origin.x(), scan().origin.y(), scan().origin.z());
  for (auto _ : state) {
    octomap::OcTree tree(0.01);
    nbv::test::configureLikeMap(tree, nbv::grid::MapConfig{});
    tree.insertPointCloud(cloud, origin, 1.5, false, state.range(0) == 1);
    benchmark::DoNotOptimize(tree.size());
  }
  state.SetLabel(state.range(0) == 1 ? "discretize" : "default");
  setCounters(state);
}
BENCHMARK(BM_OctomapInsertPointCloud)->ArgName("discretize")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The dome's 48 views of the normalised bunny as 16-bit depth frames (5000 per metre, 0 where
/// nothing was hit), and the cloud each frame back-projects to.
struct BunnyFrames {
  nbv::sensor::PinholeCamera camera;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<std::vector<std::uint16_t>> raw;
  std::vector<std::vector<Eigen::Vector3f>> clouds;
  BunnyFrames() {
    nbv::sensor::TriangleMesh mesh = nbv::sensor::loadMesh(nbv::sensor::resolveModel("bunny"));
    nbv::sensor::normalizeMesh(mesh);
    const nbv::sensor::RayScene scene(mesh);
    const nbv::sensor::DepthCamera depth_camera;
    camera = depth_camera.config().camera;
    for (const nbv::planner::View& view : nbv::planner::dome48()) {
      const nbv::sensor::DepthScan scan = depth_camera.render(scene, view.T_world_camera);
      std::vector<std::uint16_t> frame(scan.depth_m.size());
      for (std::size_t i = 0; i < frame.size(); ++i) {
        frame[i] = static_cast<std::uint16_t>(std::lround(static_cast<double>(scan.depth_m[i]) * 5000.0));
      }
      const nbv::grid::DepthImage image{scan.width, scan.height, frame, {}};
      clouds.push_back(nbv::grid::backProject(image, camera, view.T_world_camera, nbv::grid::DepthOptions{}));
      raw.push_back(std::move(frame));
      poses.push_back(view.T_world_camera);
    }
  }
};

/// One frame after another of the dome, around and around, into one map (as a robot's mapping
/// thread integrates), at the default thread count: argument 0 through integrateDepth() (the
/// back-projection included), 1 the same points as a cloud.
void BM_DepthFrames(benchmark::State& state) {
  static const BunnyFrames frames;
  const bool as_cloud = state.range(0) == 1;
  state.SetLabel(as_cloud ? "cloud" : "depth");
  nbv::grid::OccupancyMap map;
  std::size_t i = 0, points = 0;
  for (auto _ : state) {
    const std::size_t v = i++ % frames.poses.size();
    if (as_cloud) {
      map.integrate(frames.clouds[v], frames.poses[v].translation().cast<float>());
    } else {
      const nbv::grid::DepthImage image{frames.camera.width, frames.camera.height, frames.raw[v], {}};
      map.integrateDepth(image, frames.camera, frames.poses[v]);
    }
    points += frames.clouds[v].size();
  }
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(i), benchmark::Counter::kIsRate);
  state.counters["points/frame"] = static_cast<double>(points) / static_cast<double>(std::max<std::size_t>(i, 1));
}
BENCHMARK(BM_DepthFrames)->ArgName("as_cloud")->Arg(0)->Arg(1)->Iterations(96)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Memory after the dome's 48 views of the bunny (BunnyFrames' clouds), nbv with and without
/// proximity marks against liboctomap's memoryUsage(), in bytes per measured voxel (the same
/// voxels in both maps). One iteration: a size, not a time.
void BM_MemoryAfterDome(benchmark::State& state) {
  static const BunnyFrames frames;
  const int kind = static_cast<int>(state.range(0));  // 0 nbv without marks, 1 nbv with marks, 2 liboctomap
  std::size_t bytes = 0, voxels = 0;
  for (auto _ : state) {
    if (kind == 2) {
      octomap::OcTree tree(0.01);
      nbv::test::configureLikeMap(tree, nbv::grid::MapConfig{});
      for (std::size_t v = 0; v < frames.poses.size(); ++v) {
        octomap::Pointcloud cloud;
        for (const auto& p : frames.clouds[v]) cloud.push_back(p.x(), p.y(), p.z());
        const Eigen::Vector3d o = frames.poses[v].translation();
        tree.insertPointCloud(cloud, octomap::point3d(static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z())), 1.5,
                              false, false);
      }
      bytes = tree.memoryUsage();
      voxels = 0;
      for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) voxels += std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
    } else {
      nbv::grid::OccupancyMap::Config config;
      if (kind == 0) config.proximity_range = 0.0;
      nbv::grid::OccupancyMap map(config);
      for (std::size_t v = 0; v < frames.poses.size(); ++v) map.integrate(frames.clouds[v], frames.poses[v].translation().cast<float>());
      bytes = map.memoryBytes();
      voxels = map.measuredCount();
    }
  }
  state.SetLabel(kind == 2 ? "liboctomap" : kind == 1 ? "nbv, marks" : "nbv, no marks");
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["voxels"] = static_cast<double>(voxels);
  state.counters["B/voxel"] = static_cast<double>(bytes) / static_cast<double>(std::max<std::size_t>(voxels, 1));
}
BENCHMARK(BM_MemoryAfterDome)->ArgName("map")->Arg(0)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Frames as a public RGB-D dataset ships them (tests/dataset_like.hpp: 640 x 480, ICL-NUIM's
/// intrinsics with fy < 0, noise, holes, a scene 2-3 m away), through integrateDepth() into one
/// map of 1 cm voxels and a 3 m range, at 1 and 2 threads.
void BM_DatasetFrames(benchmark::State& state) {
  static const nbv::test::DatasetLikeSequence sequence(12);
  const nbv::sensor::PinholeCamera camera = nbv::test::DatasetLikeSequence::camera();
  nbv::grid::OccupancyMap::Config config;
  config.max_range = 3.0;
  nbv::grid::OccupancyMap map(config);
  tbb::task_arena arena(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t f = i++ % sequence.depth.size();
    const nbv::grid::DepthImage image{camera.width, camera.height, sequence.depth[f], {}};
    arena.execute([&] { map.integrateDepth(image, camera, sequence.T_world_camera[f]); });
  }
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(i), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DatasetFrames)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(24)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
