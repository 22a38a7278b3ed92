// markRays on the rays of the integration workload (a full 752 x 480 ideal scan of a sphere of
// radius 0.25 m from 0.6 m, 1 cm voxels): the scalar walk (the oracle) against the AVX2 and
// AVX-512 packet walks, side by side, in voxel visits per second. BM_MarkRays: the rays from
// the camera to the hits (Store mode, as the occupancy update); BM_MarkProximity: the rays
// from the hits 0.3 m on (MinStepIndex, as the proximity marks).
#include "nbv/kernels/mark_rays.hpp"

#include "scenes.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace {

/// Rays origins[i] -> ends[i] (one origin for all, or one each) and a box that holds them.
struct Rays {
  std::vector<Eigen::Vector3f> origins, ends;
  nbv::kernels::VoxelLattice lattice{0.01};
  nbv::kernels::DenseBox box;  ///< without data: each benchmark has its own bytes
  double visits = 0;  // voxels per pass, counted with the scalar walk

  void makeBox() {
    Eigen::Vector3f lo = origins[0], hi = origins[0];
    for (const auto& points : {origins, ends}) {
      for (const auto& p : points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
    box = nbv::kernels::DenseBox::around(lattice.worldToIndex(lo) - nbv::kernels::Index3::Ones(),
                                         lattice.worldToIndex(hi) + nbv::kernels::Index3::Ones());
    for (std::size_t i = 0; i < ends.size(); ++i) {
      nbv::kernels::traverseRayKeys(origins[origins.size() == 1 ? 0 : i], ends[i], lattice,
                                    [&](const auto&) { ++visits; });
    }
  }
};

/// The camera's rays to the hits of the sphere scan.
const Rays& scanRays() {
  static const Rays rays = [] {
    Rays r;
    const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
    const Eigen::Vector3d position(0.6, 0.0, 0.25);
    r.ends = nbv::test::idealScan(sphere, nbv::test::lookAt(position, sphere.centre));
    r.origins = {position.cast<float>()};
    r.makeBox();
    return r;
  }();
  return rays;
}

/// The same rays continued 0.3 m beyond their hits (the proximity marks of SEMANTICS.md "The map").
const Rays& proximityRays() {
  static const Rays rays = [] {
    Rays r;
    const Rays& scan = scanRays();
    for (const auto& hit : scan.ends) {
      r.origins.push_back(hit);
      r.ends.push_back(hit + 0.3f * (hit - scan.origins[0]).normalized());
    }
    r.makeBox();
    return r;
  }();
  return rays;
}

void setCounters(benchmark::State& state, const Rays& w, nbv::kernels::Isa isa) {
  state.SetLabel(nbv::kernels::isaName(isa));
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(w.ends.size()),
                                                benchmark::Counter::kIsIterationInvariantRate);
  state.counters["visits/s"] = benchmark::Counter(w.visits, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["ns/visit"] = benchmark::Counter(w.visits, benchmark::Counter::kIsIterationInvariantRate |
                                                                benchmark::Counter::kInvert);
}

/// markRays() over `w` with the instruction set of the row; `fresh` clears the box before
/// each pass, as a scan's new scratch is (MinStepIndex keeps minima, so the bytes matter).
void markRows(benchmark::State& state, const Rays& w, const nbv::kernels::MarkSpec& spec, bool fresh) {
  const auto isa = static_cast<nbv::kernels::Isa>(state.range(0));
  if (!nbv::kernels::isaAvailable(isa)) {
    state.SkipWithError("this instruction set is not available here");
    return;
  }
  const nbv::kernels::OutsideSink ignore = [](const nbv::kernels::Index3&, std::uint8_t) {};
  std::vector<std::uint8_t> bytes(w.box.bytes());
  nbv::kernels::DenseBox box = w.box;
  box.data = bytes.data();
  for (auto _ : state) {
    if (fresh) std::fill(bytes.begin(), bytes.end(), std::uint8_t{0});
    nbv::kernels::markRays(w.origins, w.ends, w.lattice, box, spec, ignore, isa);
    benchmark::ClobberMemory();
  }
  setCounters(state, w, isa);
}

void BM_MarkRays(benchmark::State& state) {
  markRows(state, scanRays(), {nbv::kernels::MarkSpec::Mode::Store, 1}, false);
}

void BM_MarkProximity(benchmark::State& state) {
  markRows(state, proximityRays(), {nbv::kernels::MarkSpec::Mode::MinStepIndex, 0}, true);
}

/// One row per instruction set (skipped where it is not available).
void everyIsa(benchmark::internal::Benchmark* b) {
  b->ArgName("isa");
  for (auto isa : {nbv::kernels::Isa::Scalar, nbv::kernels::Isa::Avx2, nbv::kernels::Isa::Avx512}) {
    b->Arg(static_cast<int>(isa));
  }
}
BENCHMARK(BM_MarkRays)->Apply(everyIsa)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MarkProximity)->Apply(everyIsa)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
