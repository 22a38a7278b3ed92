// Small random scans (bytes -> sensor origins and points) integrated serially and in parallel,
// then one view evaluated by the fast and the reference evaluator. Invariants: the two maps are
// identical, counts add up, probabilities lie in [0, 1], fast == reference.
#include "fuzz_input_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/kernels/information_gain.hpp"

#include <cmath>
#include <vector>

namespace {

/// Byte b as a coordinate in [-0.5, 0.5) m.
float coordinate(std::uint8_t b) { return (static_cast<float>(b) - 128.0f) / 256.0f; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using nbv::fuzz::check;
  nbv::grid::MapConfig config;
  config.resolution = 0.05;
  nbv::grid::OccupancyMap serial(config), parallel(config);
  nbv::grid::IntegrateOptions one_thread;
  one_thread.serial = true;
  nbv::grid::IntegrateOptions many;
  many.grain_size = 2;
  // Scans: 3 bytes of origin, 1 byte n, then n points of 3 bytes; a view from the last 3 bytes.
  std::size_t at = 0;
  while (at + 4 <= size) {
    const Eigen::Vector3f origin(coordinate(data[at]), coordinate(data[at + 1]), coordinate(data[at + 2]));
    const std::size_t n = std::min<std::size_t>(data[at + 3] % 64, (size - at - 4) / 3);
    at += 4;
    std::vector<Eigen::Vector3f> points;
    for (std::size_t i = 0; i < n; ++i, at += 3) {
      points.emplace_back(coordinate(data[at]) * 4.0f, coordinate(data[at + 1]) * 4.0f, coordinate(data[at + 2]) * 4.0f);
    }
    const nbv::grid::ScanStats a = serial.integrate(points, origin, one_thread);
    const nbv::grid::ScanStats b = parallel.integrate(points, origin, many);
    check(a.voxels_hit == b.voxels_hit && a.voxels_missed == b.voxels_missed, "serial == parallel stats");
  }
  const auto voxels = serial.measuredVoxels();
  const auto others = parallel.measuredVoxels();
  check(voxels.size() == others.size(), "serial == parallel voxel count");
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    check(voxels[i].ijk == others[i].ijk && voxels[i].log_odds == others[i].log_odds, "serial == parallel voxels");
    const double p = serial.probability(voxels[i].ijk);
    check(p >= 0.0 && p <= 1.0, "probabilities in [0, 1]");
  }
  check(serial.occupiedCount() + serial.freeCount() <= serial.measuredCount(), "counts add up");

  Eigen::Isometry3d view = Eigen::Isometry3d::Identity();
  if (size >= 3) view.translation() = Eigen::Vector3d(coordinate(data[size - 3]), coordinate(data[size - 2]), -0.8);
  std::vector<Eigen::Vector3d> rays;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) rays.push_back(Eigen::Vector3d(0.1 * i, 0.1 * j, 1.0).normalized());
  }
  const std::vector<Eigen::Isometry3d> views{view};
  const nbv::ig::IgTable fast = nbv::ig::evaluate(serial, views, rays);
  const nbv::ig::IgTable reference = nbv::ig::ReferenceEvaluator(serial).evaluate(views, rays);
  for (std::size_t m = 0; m < fast.metrics.size(); ++m) {
    const double f = fast.value(0, m), r = reference.value(0, m);
    if (!(std::abs(f - r) <= 1e-5 * std::abs(r) + 1e-9)) {
      std::fprintf(stderr, "%s: fast %.17g, reference %.17g\n", nbv::kernels::metricName(fast.metrics[m]), f, r);
      check(false, "fast == reference");
    }
  }
  return 0;
}
