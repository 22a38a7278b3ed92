// The ideal depth camera (Embree): full 752 x 480 renders of the normalised bunny from the 48
// views of the dome, at 1 and 2 threads, in rays per second; and reading the bunny's OFF file
// (2.6 MB, 75,408 triangles). Needs `make models`.
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

namespace {

struct Bunny {
  nbv::sensor::TriangleMesh mesh;
  std::unique_ptr<nbv::sensor::RayScene> scene;
  Bunny() {
    mesh = nbv::sensor::loadMesh(nbv::sensor::resolveModel("bunny"));
    nbv::sensor::normalizeMesh(mesh);
    scene = std::make_unique<nbv::sensor::RayScene>(mesh);
  }
};

void BM_RenderDome48(benchmark::State& state) {
  static const Bunny bunny;
  const auto views = nbv::planner::dome48();
  const nbv::sensor::DepthCamera camera;
  tbb::task_arena arena(static_cast<int>(state.range(0)));
  std::size_t points = 0;
  for (auto _ : state) {
    points = 0;
    arena.execute([&] {
      for (const auto& view : views) points += camera.render(*bunny.scene, view.T_world_camera).points_world.size();
    });
  }
  const double rays = 48.0 * camera.config().camera.width * camera.config().camera.height;
  state.counters["rays/s"] = benchmark::Counter(rays, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["views/s"] = benchmark::Counter(48.0, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["hits/view"] = static_cast<double>(points) / 48.0;
}
BENCHMARK(BM_RenderDome48)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LoadBunnyOff(benchmark::State& state) {
  const auto path = nbv::sensor::resolveModel("bunny");
  std::size_t triangles = 0;
  for (auto _ : state) triangles = nbv::sensor::loadMesh(path).triangles.size();
  state.counters["triangles/s"] =
      benchmark::Counter(static_cast<double>(triangles), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LoadBunnyOff)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
