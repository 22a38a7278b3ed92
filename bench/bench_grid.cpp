// Integration of one full ideal scan (SPEC §2 camera, 752 x 480) of a sphere of radius
// 0.25 m seen from 0.6 m: nbv at 1 and 2 threads against liboctomap's insertPointCloud, in
// one binary so that the ratio is measured side by side.
#include "nbv/grid/occupancy_map.hpp"

#include "scenes.hpp"

#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>
#include <tbb/task_arena.h>

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

void BM_NbvIntegrate(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const bool with_marks = state.range(1) != 0;
  nbv::grid::OccupancyMap::Config config;
  if (!with_marks) config.proximity_range = 0.0;
  tbb::task_arena arena(threads);
  for (auto _ : state) {
    nbv::grid::OccupancyMap map(config);
    arena.execute([&] { map.integrate(scan().points, scan().origin); });
    benchmark::DoNotOptimize(map.measuredCount());
  }
  setCounters(state);
}
BENCHMARK(BM_NbvIntegrate)
    ->ArgNames({"threads", "proximity_marks"})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_OctomapInsertPointCloud(benchmark::State& state) {
  octomap::Pointcloud cloud;
  for (const auto& p : scan().points) cloud.push_back(p.x(), p.y(), p.z());
  const octomap::point3d origin(scan().origin.x(), scan().origin.y(), scan().origin.z());
  for (auto _ : state) {
    octomap::OcTree tree(0.01);
    tree.setClampingThresMin(0.12);
    tree.setClampingThresMax(0.97);
    tree.insertPointCloud(cloud, origin, 1.5, false, false);
    benchmark::DoNotOptimize(tree.size());
  }
  setCounters(state);
}
BENCHMARK(BM_OctomapInsertPointCloud)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
