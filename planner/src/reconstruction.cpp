#include "nbv/planner/reconstruction.hpp"

#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/utility.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
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

/// The candidates' gains at one iteration, one per candidate: the combined metric terms
/// (exhaustive), or an anytime decision's estimates of Eq. 12 with its choice.
struct CandidateScores {
  std::vector<double> gains;
  std::optional<std::size_t> anytime_choice;
  std::uint64_t rays = 0;
};

CandidateScores scoreCandidates(AnytimeDecider& decider, const grid::OccupancyMap& map,
                                const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Vector3d>& directions,
                                const std::vector<double>& costs, const ig::TableOptions& table_options,
                                const ReconstructionConfig& config, std::size_t iteration) {
  CandidateScores scores;
  if (config.anytime) {  // SEMANTICS.md "Anytime decisions": estimates of the utility, Eq. 12 included
    DecisionUtility utility{config.metrics, config.weighting, config.gamma, costs, table_options.random_seed};
    DecideOptions options = *config.anytime;
    options.seed = derivedSeed(config.seed, 1000 + iteration);
    decider.refresh(map, utility, config.snapshot);
    const AnytimeDecision d = decider.decide(poses, directions, utility, config.walk, options);
    for (const CandidateEstimate& e : d.candidates) scores.gains.push_back(e.estimate);
    scores.rays = d.rays_cast;
    scores.anytime_choice = d.chosen;
  } else {
    const ig::IgTable table =
        ig::evaluate(decider.evaluator(), map, poses, directions, {config.snapshot, config.walk, table_options});
    scores.gains = combinedGains(table.values, config.metrics, config.weighting);
    scores.rays = table.rays;
  }
  return scores;
}

/// The oracle's scores (SEMANTICS.md "The oracle"): each candidate's coverage gain, from its
/// scan rendered once per object and shared by every run on it. It casts no IG ray.
CandidateScores oracleScores(const SimulatedObject& object, const SurfaceCoverage& coverage,
                             const std::vector<std::size_t>& candidates) {
  CandidateScores scores;
  for (const std::size_t v : candidates) scores.gains.push_back(coverage.gainOf(object.scan(v).covered));
  return scores;
}

/// A planner of one's own: the scorer's gains for the state of the run, checked; the rays of
/// the metric values it asked for count as the decision's.
CandidateScores customScores(const ReconstructionConfig& config, AnytimeDecider& decider, DecisionState state,
                             const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Vector3d>& directions,
                             const ig::TableOptions& table_options) {
  CandidateScores scores;
  state.evaluate = [&](std::span<const ig::Metric> metrics) {
    ig::TableOptions options = table_options;
    options.metrics.assign(metrics.begin(), metrics.end());
    ig::IgTable table = ig::evaluate(decider.evaluator(), state.map, poses, directions, {config.snapshot, config.walk, options});
    scores.rays += table.rays;
    return table;
  };
  state.visible_voxels = [&](std::size_t c) {
    if (c >= poses.size()) throw InvalidArgument("visible_voxels: candidate " + std::to_string(c) + " of " + std::to_string(poses.size()));
    decider.evaluator().refresh(state.map, config.snapshot);
    scores.rays += directions.size();
    return decider.evaluator().visibleVoxels(std::span<const Eigen::Isometry3d>(&poses[c], 1), directions, config.walk);
  };
  scores.gains = config.scorer(state);
  if (scores.gains.size() != state.candidates.size()) {
    throw InvalidArgument("the planner gave " + std::to_string(scores.gains.size()) + " gains for " +
                          std::to_string(state.candidates.size()) + " candidates");
  }
  for (std::size_t c = 0; c < scores.gains.size(); ++c) {
    if (!std::isfinite(scores.gains[c])) {
      throw InvalidArgument("the planner's gain for view " + std::to_string(state.candidates[c]) + " is " +
                            numberText(scores.gains[c]) + ", not a finite number");
    }
  }
  return scores;
}

}  // namespace

const char* plannerName(Planner planner) { return planner == Planner::Oracle ? "oracle" : ""; }

void setPlanner(ReconstructionConfig& config, std::string_view text) {
  if (text == plannerName(Planner::Oracle)) {
    config.planner = Planner::Oracle;
    return;
  }
  config.metrics = parseMetricSum(text);
  config.planner = Planner::Utility;
}

const char* stopReasonName(StopReason reason) {
  switch (reason) {
    case StopReason::MaxIterations: return "max_iterations";
    case StopReason::BelowThreshold: return "g_thresh";
    case StopReason::NoViewsLeft: return "no_views_left";
    case StopReason::Caller: return "caller";
    case StopReason::TimeLimit: return "max_seconds";
  }
  return "?";
}

std::size_t startView(std::uint64_t seed, std::size_t view_count) {
  if (view_count == 0) throw InvalidArgument("startView: the viewspace holds no view");
  const double draw = kernels::randomScore(seed, 0) * static_cast<double>(view_count);  // uniform in [0, count)
  return std::min(view_count - 1, static_cast<std::size_t>(draw));
}

std::span<const ReconstructionOption> reconstructionOptions() {
#define NBV_RECONSTRUCTION_ROW(...) NBV_OPTION_ROW(ReconstructionConfig, __VA_ARGS__)
  static constexpr ReconstructionOption kOptions[] = {NBV_RECONSTRUCTION_OPTIONS(NBV_RECONSTRUCTION_ROW)};
#undef NBV_RECONSTRUCTION_ROW
  return kOptions;
}

const ReconstructionOption* reconstructionOption(std::string_view name) {
  return optionRow(reconstructionOptions(), name);
}

void ReconstructionConfig::validate() const {
  if (metrics.empty()) throw InvalidArgument("a reconstruction needs at least one metric");
  if (planner == Planner::Oracle && anytime) throw InvalidArgument("the oracle takes no anytime decision (it casts no ray)");
  if (planner == Planner::Custom && !scorer) throw InvalidArgument("a planner of one's own needs its scorer");
  if (planner == Planner::Custom && anytime) throw InvalidArgument("a planner of one's own takes no anytime decision");
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    if (!(std::isfinite(metrics[i].weight) && metrics[i].weight > 0.0)) {
      throw InvalidArgument("metric weight " + numberText(metrics[i].weight) + " must be finite and positive");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (metrics[j].metric == metrics[i].metric) {
        throw InvalidArgument(std::string("metric '") + kernels::metricName(metrics[i].metric) + "' is named twice");
      }
    }
  }
  if (max_iterations == 0) throw InvalidArgument("max_iterations must be at least 1");
  const ReconstructionConfig& c = *this;
#define NBV_RECONSTRUCTION_CHECK(...) NBV_OPTION_CHECK("reconstruction", __VA_ARGS__)
  NBV_RECONSTRUCTION_OPTIONS(NBV_RECONSTRUCTION_CHECK)
#undef NBV_RECONSTRUCTION_CHECK
  rays.validate();
  map.validate();
  if (ground_truth_points == 0) throw InvalidArgument("ground_truth_points must be at least 1");
  if (anytime) anytime->validate();
}

bool SceneConditions::operator==(const SceneConditions& other) const {
  const bool same_crop = crop.has_value() == other.crop.has_value() &&
                         (!crop || (crop->min() == other.crop->min() && crop->max() == other.crop->max()));
  return ground_plane == other.ground_plane && no_return == other.no_return && same_crop;
}

std::vector<std::string> sceneNames() { return {"bare", "released", "paper"}; }

SceneConditions sceneNamed(const std::string& name) {
  SceneConditions scene;
  if (name == "bare") return scene;
  if (name == "released") {  // the authors' example world and launch file
    scene.ground_plane = true;
    scene.crop = Eigen::AlignedBox3d(Eigen::Vector3d(-0.6, -0.6, -0.01), Eigen::Vector3d(0.6, 0.6, 0.6));
    return scene;
  }
  if (name == "paper") {  // docs/RESULTS.md: the condition nearest the paper's Table 1
    scene.ground_plane = true;
    return scene;
  }
  throw InvalidArgument("unknown scene '" + name + "' (known: bare, released, paper)");
}

std::string sceneUp(const std::string& name) {
  sceneNamed(name);  // a known name
  return name == "paper" ? "auto" : "z";
}

std::string iterationFieldNames() {
  std::string names;
#define NBV_FIELD_NAME(name, type, kind, help) NBV_ITERATION_IF_RECORD(kind, names += (names.empty() ? "" : ", ") + std::string(#name);)
  NBV_ITERATION_FIELDS(NBV_FIELD_NAME)
#undef NBV_FIELD_NAME
  return names;
}

std::string modelLabel(const std::string& given) {
  const std::string stem = std::filesystem::path(given).stem().string();
  return stem.empty() ? "model" : stem;
}

std::string sceneLabel(const std::string& preset, const SceneConditions& scene, const std::string& up) {
  const SceneConditions named = sceneNamed(preset);
  std::string label = preset;
  if (scene.ground_plane != named.ground_plane) label += scene.ground_plane ? "+ground" : "+noground";
  if (scene.no_return != named.no_return) label += scene.no_return == NoReturn::Clear ? "+clear" : "+drop";
  const bool same_crop = scene.crop.has_value() == named.crop.has_value() &&
                         (!scene.crop || (scene.crop->min() == named.crop->min() && scene.crop->max() == named.crop->max()));
  if (!same_crop) label += scene.crop ? "+crop" : "+nocrop";
  if (up != sceneUp(preset)) label += "+up=" + up;
  return label;
}

ScanPoints scanPoints(const sensor::DepthScan& scan, const Eigen::Isometry3d& T_world_camera,
                      const ReconstructionConfig& config) {
  const auto kept = [&](const Eigen::Vector3f& p) { return !config.scene.crop || config.scene.crop->contains(p.cast<double>()); };
  ScanPoints out;
  for (std::size_t i = 0; i < scan.points_world.size(); ++i) {
    if (!kept(scan.points_world[i])) continue;
    out.integrated.push_back(scan.points_world[i]);
    if (scan.surfaces[i] == sensor::Surface::Object) out.on_object.push_back(scan.points_world[i]);
  }
  if (config.scene.no_return == NoReturn::Clear) {
    // The no-return points of the scan's depth image: backProject() lists them after its hits,
    // twice the map's max_range away, as OccupancyMap::integrateDepth() places them.
    grid::DepthOptions options;
    options.no_return = NoReturn::Clear;
    options.no_return_distance_m = 2.0 * config.map.max_range;
    const std::vector<Eigen::Vector3f> points =
        grid::backProject(grid::DepthImage{scan.width, scan.height, {}, scan.depth_m}, config.camera.camera, T_world_camera, options);
    const std::size_t hits = scan.points_world.size();
    for (std::size_t i = hits; i < points.size(); ++i) {
      if (kept(points[i])) out.integrated.push_back(points[i]);
    }
  }
  return out;
}

SimulatedObject::SimulatedObject(const sensor::TriangleMesh& mesh, std::vector<View> viewspace,
                                 const ReconstructionConfig& config)
    : mesh_(mesh), viewspace_(std::move(viewspace)), config_(config), camera_(config.camera) {
  config.validate();
  if (viewspace_.empty()) throw InvalidArgument("the viewspace holds no view");
  scene_ = std::make_unique<sensor::RayScene>(mesh_, sensor::SceneOptions{config.scene.ground_plane});
  ground_truth_ = std::make_shared<const GroundTruth>(
      sensor::sampleSurface(mesh_, config.ground_truth_points, config.ground_truth_seed), config.registration_distance_m);
  rendered_ = std::vector<std::once_flag>(viewspace_.size());
  scans_.resize(viewspace_.size());
}

SimulatedObject::~SimulatedObject() = default;

bool SimulatedObject::builtFor(const ReconstructionConfig& config) const {
  const sensor::PinholeCamera& a = config.camera.camera;
  const sensor::PinholeCamera& b = config_.camera.camera;
  const bool same_camera = a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
                           a.cy == b.cy && config.camera.max_range_m == config_.camera.max_range_m &&
                           config.camera.noise.kind == config_.camera.noise.kind;
  return same_camera && config.scene == config_.scene && config.map.marksSameVoxels(config_.map) &&
         config.ground_truth_points == config_.ground_truth_points &&
         config.ground_truth_seed == config_.ground_truth_seed &&
         config.registration_distance_m == config_.registration_distance_m;
}

const SimulatedObject::Scan& SimulatedObject::scan(std::size_t view) const {
  if (view >= viewspace_.size()) throw InvalidArgument("view " + std::to_string(view) + " is outside the viewspace");
  std::call_once(rendered_[view], [&] {
    const auto start = std::chrono::steady_clock::now();
    const Eigen::Isometry3d& T_world_camera = viewspace_[view].T_world_camera;
    ScanPoints points = scanPoints(camera_.render(*scene_, T_world_camera), T_world_camera, config_);
    Scan& out = scans_[view];
    out.points_world = std::move(points.integrated);
    out.update.emplace(config_.map, out.points_world, T_world_camera.translation().cast<float>());
    out.covered = ground_truth_->coveredBy(points.on_object);
    out.seconds_render = secondsSince(start);
  });
  return scans_[view];
}

ReconstructionResult reconstruct(const sensor::TriangleMesh& mesh, const std::vector<View>& viewspace,
                                 const ReconstructionConfig& config,
                                 const std::function<bool(const IterationRecord&)>& on_iteration) {
  return reconstruct(SimulatedObject(mesh, viewspace, config), config, on_iteration);
}

ReconstructionResult reconstruct(const SimulatedObject& object, const ReconstructionConfig& config,
                                 const std::function<bool(const IterationRecord&)>& on_iteration) {
  AnytimeDecider decider;
  return reconstruct(object, config, decider, on_iteration);
}

ReconstructionResult reconstruct(const SimulatedObject& object, const ReconstructionConfig& config,
                                 AnytimeDecider& decider,
                                 const std::function<bool(const IterationRecord&)>& on_iteration) {
  const auto run_start = std::chrono::steady_clock::now();
  config.validate();
  if (!object.builtFor(config)) {
    throw InvalidArgument("reconstruct: the object was built for another camera, scene, map resolution or range, or ground truth");
  }
  const std::vector<View>& viewspace = object.viewspace();
  SurfaceCoverage coverage(object.groundTruth());
  const Eigen::Vector3d centre = sensor::meshBounds(object.mesh()).center();
  grid::OccupancyMap map(config.map);  // the decider's evaluator serves the exhaustive decisions too
  ig::TableOptions table_options;
  table_options.metrics = metricsOf(config.metrics);
  const std::vector<Eigen::Vector3d> directions = sensor::rayDirectionsCamera(config.camera.camera, config.rays);

  ReconstructionResult result;
  result.max_entropy_bits = maxMapEntropyBits(map, config.entropy_cube_m);
  std::vector<bool> visited(viewspace.size(), false);
  std::vector<std::size_t> taken;  // the views scanned, in order
  std::size_t view = startView(config.seed, viewspace.size());
  for (std::size_t iteration = 1;; ++iteration) {
    IterationRecord record;
    record.iteration = iteration;
    record.view = view;
    visited[view] = true;
    taken.push_back(view);

    const SimulatedObject::Scan& scan = object.scan(view);
    record.seconds_render = scan.seconds_render;
    auto start = std::chrono::steady_clock::now();
    map.integrate(*scan.update);
    record.seconds_integrate = secondsSince(start);
    coverage.addCovered(scan.covered);
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
    } else if (config.max_seconds && secondsSince(run_start) >= *config.max_seconds) {
      result.stop = StopReason::TimeLimit;
      stop = true;
    } else {
      start = std::chrono::steady_clock::now();
      std::vector<Eigen::Isometry3d> poses;
      for (std::size_t v : candidates) poses.push_back(viewspace[v].T_world_camera);
      table_options.random_seed = derivedSeed(config.seed, iteration);
      std::vector<double> costs(candidates.size());
      for (std::size_t c = 0; c < candidates.size(); ++c) costs[c] = travelCost(viewspace[view], viewspace[candidates[c]]);
      CandidateScores scores;
      if (config.planner == Planner::Oracle) {
        scores = oracleScores(object, coverage, candidates);
      } else if (config.planner == Planner::Custom) {
        scores = customScores(config, decider, {map, viewspace, taken, candidates, iteration, {}, {}}, poses,
                              directions, table_options);
      } else {
        scores = scoreCandidates(decider, map, poses, directions, costs, table_options, config, iteration);
      }
      const std::vector<double>& gains = scores.gains;
      record.rays = scores.rays;
      const double exhaustive_rays = static_cast<double>(candidates.size()) * static_cast<double>(directions.size());
      record.ray_share = static_cast<double>(scores.rays) / exhaustive_rays;
      record.gains.assign(viewspace.size(), std::numeric_limits<double>::quiet_NaN());
      for (std::size_t c = 0; c < candidates.size(); ++c) record.gains[candidates[c]] = gains[c];
      if (config.g_thresh && allBelow(gains, *config.g_thresh)) {  // Eq. 14
        result.stop = StopReason::BelowThreshold;
        stop = true;
      } else {
        // Exhaustive: Eq. 12 then Eq. 13. Anytime: the decision's choice, its estimates of Eq. 12.
        const std::vector<double> u = config.anytime ? gains : utilities(gains, costs, config.gamma);
        const Margin margin = decisionMargin(u);
        record.ties = margin.ties;
        record.gap = margin.gap;
        view = candidates[scores.anytime_choice ? *scores.anytime_choice : *argmaxFirst(u)];
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
