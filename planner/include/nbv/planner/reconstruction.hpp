#pragma once
/// \file The NBV loop of the paper's Algorithm 1 in simulation (SEMANTICS.md "The planner", "Simulation and evaluation"): render, integrate,
/// evaluate the candidates, choose, repeat.

#include "nbv/grid/information_gain.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/surface_sampling.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace nbv::planner {

/// Options of a reconstruction. Defaults: SEMANTICS.md "The planner", "Simulation and evaluation" (Proximity Count, 20 scans, gamma 0).
struct ReconstructionConfig {
  /// The gain G_v of a view: its metrics combined by `weighting` (one metric: its value).
  std::vector<MetricWeight> metrics{MetricWeight{}};
  Weighting weighting = Weighting::Normalized;
  std::uint64_t seed = 0;               ///< start view and `random`
  std::size_t max_iterations = 20;      ///< scans, the first (random) one included
  double gamma = 0.0;                   ///< Eq. 12 cost weight, in [0, 1]
  std::optional<double> g_thresh;       ///< Eq. 14: stop when every gain is below; empty: off
  sensor::PixelSampling rays = sensor::PixelSampling::released();  ///< IG ray set
  grid::EvaluateOptions evaluation;     ///< ray depth, visibility, thresholds, threads (metrics ignored)
  grid::MapConfig map;                  ///< SEMANTICS.md "The map"
  sensor::DepthCameraConfig camera;     ///< SEMANTICS.md "Simulation and evaluation": the ideal camera
  std::size_t ground_truth_points = sensor::kDefaultGroundTruthPoints;
  std::uint64_t ground_truth_seed = 0;  ///< the same surface points for every run of a model
  double registration_distance_m = 0.005;  ///< Eq. 15's d_reg
  double entropy_cube_m = 1.28;            ///< Eq. 16's cube

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// What one iteration did: iteration k scanned `view`; `gains` are the candidates' IG computed
/// afterwards to choose the view of iteration k + 1 (NaN for visited views; empty when no
/// choice followed).
struct IterationRecord {
  std::size_t iteration = 0;  ///< 1-based: the number of scans so far
  std::size_t view = 0;       ///< index in the viewspace
  double coverage = 0.0;      ///< Eq. 15 after this scan
  double entropy_bits = 0.0;  ///< Eq. 16 after this scan
  std::vector<double> gains;
  double seconds_render = 0.0;
  double seconds_integrate = 0.0;
  double seconds_ig = 0.0;    ///< evaluating every candidate (the NBV decision)
};

/// Why a reconstruction stopped.
enum class StopReason {
  MaxIterations,   ///< the scan budget
  BelowThreshold,  ///< Eq. 14
  NoViewsLeft,     ///< every view visited
  Caller,          ///< the caller's on_iteration returned false
};
const char* stopReasonName(StopReason reason);

struct ReconstructionResult {
  std::vector<IterationRecord> iterations;
  StopReason stop = StopReason::MaxIterations;
  double max_entropy_bits = 0.0;  ///< the entropy of the empty map's cube
  double auc_coverage = 0.0;      ///< SEMANTICS.md "Simulation and evaluation", over iterations 0..N
  double auc_entropy = 0.0;       ///< SEMANTICS.md "Simulation and evaluation", over iterations 0..N
};

/// The first view of a run with `seed` over `view_count` views (SEMANTICS.md "The planner":
/// drawn uniformly with the run's seed). \throws InvalidArgument if view_count is 0.
std::size_t startView(std::uint64_t seed, std::size_t view_count);

/// Reconstructs `mesh` (already placed in the world, e.g. by sensor::normalizeMesh) by the
/// paper's Algorithm 1 over `viewspace`: the first view is drawn from the seed; then each
/// iteration renders the view with the ideal camera, integrates the scan, and, unless the
/// run ends, evaluates every candidate not visited yet and moves to the one with the largest
/// utility (Eq. 12-13). Calls `on_iteration` after each iteration; the run stops there if it
/// returns false. Same inputs and seed: the same result, whatever the thread count (times
/// aside).
/// \throws InvalidArgument for a bad configuration or an empty viewspace.
ReconstructionResult reconstruct(const sensor::TriangleMesh& mesh, const std::vector<View>& viewspace,
                                 const ReconstructionConfig& config,
                                 const std::function<bool(const IterationRecord&)>& on_iteration = {});

}  // namespace nbv::planner
