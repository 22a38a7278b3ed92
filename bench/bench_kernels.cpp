// markRays on the rays of the integration workload (a full 752 x 480 ideal scan of a sphere of
// radius 0.25 m from 0.6 m, 1 cm voxels): the scalar walk (the oracle) against the AVX2 and
// AVX-512 packet walks, side by side, in voxel visits per second.
#include "nbv/kernels/mark_rays.hpp"

#include "scenes.hpp"

#include <benchmark/benchmark.h>

namespace {

struct Workload {
  std::vector<Eigen::Vector3f> ends;
  Eigen::Vector3f origin;
  nbv::kernels::VoxelLattice lattice{0.01};
  nbv::kernels::DenseBox box;
  std::vector<std::uint8_t> bytes;
  double visits = 0;  // voxels per pass, counted with the scalar walk

  Workload() {
    const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
    const Eigen::Vector3d position(0.6, 0.0, 0.25);
    ends = nbv::test::idealScan(sphere, nbv::test::lookAt(position, sphere.centre));
    origin = position.cast<float>();
    Eigen::Vector3f lo = origin, hi = origin;
    for (const auto& e : ends) {
      lo = lo.cwiseMin(e);
      hi = hi.cwiseMax(e);
    }
    box = nbv::kernels::DenseBox::around(lattice.worldToIndex(lo) - nbv::kernels::Index3::Ones(),
                                         lattice.worldToIndex(hi) + nbv::kernels::Index3::Ones());
    bytes.assign(box.bytes(), 0);
    box.data = bytes.data();
    for (const auto& e : ends) nbv::kernels::traverseRayKeys(origin, e, lattice, [&](const auto&) { ++visits; });
  }
};

const Workload& workload() {
  static const Workload w;
  return w;
}

void BM_MarkRays(benchmark::State& state) {
  const auto isa = static_cast<nbv::kernels::Isa>(state.range(0));
  if (!nbv::kernels::isaAvailable(isa)) {
    state.SkipWithError("this instruction set is not available here");
    return;
  }
  const Workload& w = workload();
  const nbv::kernels::MarkSpec spec{nbv::kernels::MarkSpec::Mode::Store, 1};
  const nbv::kernels::OutsideSink ignore = [](const nbv::kernels::Index3&, std::uint8_t) {};
  for (auto _ : state) {
    nbv::kernels::markRays(std::span(&w.origin, 1), w.ends, w.lattice, w.box, spec, ignore, isa);
    benchmark::ClobberMemory();
  }
  state.SetLabel(nbv::kernels::isaName(isa));
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(w.ends.size()),
                                                benchmark::Counter::kIsIterationInvariantRate);
  state.counters["visits/s"] = benchmark::Counter(w.visits, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["ns/visit"] = benchmark::Counter(w.visits, benchmark::Counter::kIsIterationInvariantRate |
                                                                benchmark::Counter::kInvert);
}
BENCHMARK(BM_MarkRays)
    ->ArgName("isa")
    ->Arg(static_cast<int>(nbv::kernels::Isa::Scalar))
    ->Arg(static_cast<int>(nbv::kernels::Isa::Avx2))
    ->Arg(static_cast<int>(nbv::kernels::Isa::Avx512))
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
