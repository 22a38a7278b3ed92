#include "nbv/planner/reconstruction.hpp"

#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/utility.hpp"

#include "nbv/errors.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace nbv::planner {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A seed for one purpose of a run (start view, ground truth, random metric per iteration).
std::uint64_t derivedSeed(std::uint64_t seed, std::uint64_t purpose) {
  return static_cast<std::uint64_t>(kernels::randomScore(seed, purpose) * 0x1.0p53);
}

}  // namespace

const char* stopReasonName(StopReason reason) {
  switch (reason) {
    case StopReason::MaxIterations: return "max_iterations";
    case StopReason::BelowThreshold: return "g_thresh";
    case StopReason::NoViewsLeft: return "no_views_left";
    case StopReason::Caller: return "caller";
  }
  return "?";
}

std::size_t startView(std::uint64_t seed, std::size_t view_count) {
  if (view_count == 0) throw InvalidArgument("startView: the viewspace holds no view");
  const double draw = kernels::randomScore(seed, 0) * static_cast<double>(view_count);  // uniform in [0, count)
  return std::min(view_count - 1, static_cast<std::size_t>(draw));
}

void ReconstructionConfig::validate() const {
  if (metrics.empty()) throw InvalidArgument("a reconstruction needs at least one metric");
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    if (!(std::isfinite(metrics[i].weight) && metrics[i].weight > 0.0)) {
      throw InvalidArgument("metric weight " + std::to_string(metrics[i].weight) + " must be finite and positive");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (metrics[j].metric == metrics[i].metric) {
        throw InvalidArgument(std::string("metric '") + kernels::metricName(metrics[i].metric) + "' is named twice");
      }
    }
  }
  if (max_iterations == 0) throw InvalidArgument("max_iterations must be at least 1");
  if (!(gamma >= 0.0 && gamma <= 1.0)) throw InvalidArgument("gamma " + std::to_string(gamma) + " must lie in [0, 1]");
  if (g_thresh && !std::isfinite(*g_thresh)) throw InvalidArgument("g_thresh must be finite");
  rays.validate();
  map.validate();
  if (ground_truth_points == 0) throw InvalidArgument("ground_truth_points must be at least 1");
}

ReconstructionResult reconstruct(const sensor::TriangleMesh& mesh, const std::vector<View>& viewspace,
                                 const ReconstructionConfig& config,
                                 const std::function<bool(const IterationRecord&)>& on_iteration) {
  config.validate();
  if (viewspace.empty()) throw InvalidArgument("the viewspace holds no view");
  const sensor::RayScene scene(mesh);
  const sensor::DepthCamera camera(config.camera);
  SurfaceCoverage coverage(sensor::sampleSurface(mesh, config.ground_truth_points, config.ground_truth_seed),
                           config.registration_distance_m);
  const Eigen::Vector3d centre = sensor::meshBounds(mesh).center();
  grid::OccupancyMap map(config.map);
  grid::IgEvaluator evaluator;
  grid::EvaluateOptions evaluation = config.evaluation;
  evaluation.metrics.clear();
  for (const MetricWeight& m : config.metrics) evaluation.metrics.push_back(m.metric);
  const std::vector<Eigen::Vector3d> directions = sensor::rayDirectionsCamera(config.camera.camera, config.rays);

  ReconstructionResult result;
  result.max_entropy_bits = maxMapEntropyBits(map, config.entropy_cube_m);
  std::vector<bool> visited(viewspace.size(), false);
  std::size_t view = startView(config.seed, viewspace.size());
  for (std::size_t iteration = 1;; ++iteration) {
    IterationRecord record;
    record.iteration = iteration;
    record.view = view;
    visited[view] = true;
    const Eigen::Isometry3d& T_world_camera = viewspace[view].T_world_camera;

    auto start = std::chrono::steady_clock::now();
    const sensor::DepthScan scan = camera.render(scene, T_world_camera);
    record.seconds_render = secondsSince(start);
    start = std::chrono::steady_clock::now();
    map.integrate(scan.points_world, T_world_camera.translation().cast<float>());
    record.seconds_integrate = secondsSince(start);
    coverage.addScan(scan.points_world);
    record.coverage = coverage.coverage();
    record.entropy_bits = mapEntropyBits(map, centre, config.entropy_cube_m);

    // Termination (SEMANTICS.md "The planner"): the scan budget, no views left, or Eq. 14 below.
    std::vector<std::size_t> candidates;
    for (std::size_t v = 0; v < viewspace.size(); ++v) {
      if (!visited[v]) candidates.push_back(v);
    }
    bool stop = false;
    if (iteration >= config.max_iterations) {
      result.stop = StopReason::MaxIterations;
      stop = true;
    } else if (candidates.empty()) {
      result.stop = StopReason::NoViewsLeft;
      stop = true;
    } else {
      start = std::chrono::steady_clock::now();
      std::vector<Eigen::Isometry3d> poses;
      for (std::size_t v : candidates) poses.push_back(viewspace[v].T_world_camera);
      evaluation.random_seed = derivedSeed(config.seed, iteration);
      const grid::IgTable table = evaluator.evaluate(map, poses, directions, evaluation);
      const std::vector<double> gains = combinedGains(table.values, config.metrics, config.weighting);
      std::vector<double> costs(candidates.size());
      for (std::size_t c = 0; c < candidates.size(); ++c) costs[c] = travelCost(viewspace[view], viewspace[candidates[c]]);
      record.gains.assign(viewspace.size(), std::numeric_limits<double>::quiet_NaN());
      for (std::size_t c = 0; c < candidates.size(); ++c) record.gains[candidates[c]] = gains[c];
      if (config.g_thresh && allBelow(gains, *config.g_thresh)) {  // Eq. 14
        result.stop = StopReason::BelowThreshold;
        stop = true;
      } else {
        view = candidates[*argmaxFirst(utilities(gains, costs, config.gamma))];  // Eqs. 12-13
      }
      record.seconds_ig = secondsSince(start);
    }
    result.iterations.push_back(record);
    if (on_iteration && !on_iteration(result.iterations.back()) && !stop) {
      result.stop = StopReason::Caller;
      stop = true;
    }
    if (stop) break;
  }

  std::vector<double> coverages, entropies;
  for (const IterationRecord& r : result.iterations) {
    coverages.push_back(r.coverage);
    entropies.push_back(r.entropy_bits);
  }
  result.auc_coverage = areaUnderCurve(coverages, 0.0, 1.0);
  result.auc_entropy = areaUnderCurve(entropies, result.max_entropy_bits, result.max_entropy_bits);
  return result;
}

}  // namespace nbv::planner
