#pragma once
/// \file The NBV loop of the paper's Algorithm 1 in simulation (SEMANTICS.md "The planner", "Simulation and evaluation"): render, integrate,
/// evaluate the candidates, choose, repeat.

#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/option_table.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/surface_sampling.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace nbv::planner {

/// What a no-return pixel (one that sees nothing within range) adds to the map.
using grid::NoReturn;
using grid::noReturnFromName;

/// The scene around the object (SEMANTICS.md "Scene conditions"); each off by default.
struct SceneConditions {
  bool ground_plane = false;          ///< the plane z = 0 in the scene; its hits never cover the object
  NoReturn no_return = NoReturn::Drop;
  /// Points outside this world box [m] are dropped before integration and coverage.
  std::optional<Eigen::AlignedBox3d> crop;

  bool operator==(const SceneConditions& other) const;
};

/// The named presets: "bare" (nothing added), "released" (the released example world: ground
/// plane and the launch file's crop box x, y in [-0.6, 0.6], z in [-0.01, 0.6]), "paper" (the
/// conditions docs/RESULTS.md finds closest to the paper's figures: the ground plane, with the
/// models upright on it as sceneUp() says).
/// \throws InvalidArgument naming the known presets for another name.
SceneConditions sceneNamed(const std::string& name);
/// The up axis by which a preset places a named model, as sensor::upAxisFor() reads it:
/// "auto" (a standard model upright) for "paper", "z" (as stored) for the others. The planner
/// takes a mesh as placed; the command line and Python place named models by it.
/// \throws InvalidArgument as sceneNamed().
std::string sceneUp(const std::string& name);
/// The preset names, in the order above.
std::vector<std::string> sceneNames();
/// A scene's label: the preset's name, then each way `scene` and `up` differ from it, as
/// "+ground" / "+noground", "+clear" / "+drop", "+crop" / "+nocrop" and "+up=AXIS"
/// ("paper+clear", "bare+ground+crop"). \throws InvalidArgument as sceneNamed().
std::string sceneLabel(const std::string& preset, const SceneConditions& scene, const std::string& up);
/// The names of an iteration's fields in a run's record (NBV_ITERATION_FIELDS, the run's own
/// aside), comma-separated in the table's order: what help texts list.
std::string iterationFieldNames();
/// A model's label in results (rows, file names, plots) for the model as given: a standard
/// name stays itself, a mesh file's path becomes its file's stem ("/data/ring.obj": "ring"),
/// an empty stem "model". The command line and Python label alike through it.
std::string modelLabel(const std::string& given);

/// The options of a reconstruction a user sets by name, each declared once as a row of an
/// option table (nbv/option_table.hpp): X(name, type, member, unit, check, rule, help), its
/// default the member's. A row is a flag of `nbv reconstruct` and `nbv experiment` ("--" and
/// the name with dashes; "none" for an optional one), a keyword of Python's reconstruct() and
/// experiment(), a key of a run's JSON and Python dict and of an experiment's sweep.json, a
/// line of their help, and a check of ReconstructionConfig::validate(). A new option is a row
/// at the end (an experiment folder written before it reads its default), its use and its test.
#define NBV_RECONSTRUCTION_OPTIONS(X)                                                                            \
  X(gamma, double, gamma, "", v >= 0.0 && v <= 1.0, "must be in [0, 1]",                                          \
    "cost weight of Eq. 12: the travel distance against the gain")                                               \
  X(g_thresh, std::optional<double>, g_thresh, "", !v || std::isfinite(*v), "must be finite",                     \
    "Eq. 14: stop once every candidate's gain is below this (none: off)")                                        \
  X(max_ray_depth, double, walk.max_ray_depth, "m", std::isfinite(v) && v > 0.0, "must be finite and > 0",        \
    "an IG ray that meets nothing ends here")                                                                    \
  X(max_seconds, std::optional<double>, max_seconds, "s", !v || (std::isfinite(*v) && *v > 0.0),                   \
    "must be finite and > 0",                                                                                    \
    "stop the run after the first scan that ends this long after the run began (none: no limit; a run it stops " \
    "depends on the machine)")

/// What scores the candidates of a decision.
enum class Planner {
  Utility,  ///< the volumetric IG of the metrics (Eq. 1-12)
  /// The ground-truth oracle (SEMANTICS.md "The oracle"): each candidate's gain is the surface
  /// coverage its scan would add; the ceiling of every greedy planner.
  Oracle,
  /// A planner of one's own (ReconstructionConfig::scorer): a gain per candidate from the
  /// state of the run (SEMANTICS.md "Planners of one's own").
  Custom,
};

/// What a planner of one's own is given at a decision: the state of the run. Valid during the
/// call only.
struct DecisionState {
  const grid::OccupancyMap& map;        ///< the run's map after the latest scan
  const std::vector<View>& viewspace;   ///< every view of the run
  std::vector<std::size_t> taken;       ///< the views scanned so far, in order
  std::vector<std::size_t> candidates;  ///< the open views, ascending: the gains' order
  std::size_t iteration = 0;            ///< scans so far
  /// The candidates' values of `metrics` on the run's rays, as the built-in metrics compute
  /// them (the run's evaluator, snapshot and walk options): a table of candidates x metrics.
  /// Its rays count as the decision's.
  std::function<ig::IgTable(std::span<const ig::Metric> metrics)> evaluate;
  /// The voxels the run's rays reach from candidate `candidates[c]` (IgEvaluator::visibleVoxels()
  /// on the run's snapshot): what a formulation of one's own sums.
  std::function<std::vector<ig::VisibleVoxel>(std::size_t c)> visible_voxels;
};
/// A planner of one's own: a gain per candidate of `state.candidates`, in order; the run chooses
/// by Eq. 12 and 13 as for any gain. It may throw: the run stops and the error reaches the caller.
using CandidateScorer = std::function<std::vector<double>(const DecisionState& state)>;

/// Options of a reconstruction. Defaults: SEMANTICS.md "The planner", "Simulation and evaluation" (Proximity Count, 20 scans, gamma 0).
struct ReconstructionConfig {
  Planner planner = Planner::Utility;
  CandidateScorer scorer;  ///< the planner of Planner::Custom
  /// The gain G_v of a view under Planner::Utility: its metrics combined by `weighting` (one
  /// metric: its value).
  std::vector<MetricWeight> metrics{MetricWeight{}};
  Weighting weighting = Weighting::Normalized;
  std::uint64_t seed = 0;               ///< start view and `random`
  std::size_t max_iterations = 20;      ///< scans, the first (random) one included
  double gamma = 0.0;                   ///< Eq. 12 cost weight, in [0, 1]
  std::optional<double> g_thresh;       ///< Eq. 14: stop when every gain is below; empty: off
  /// Stop after the first scan that ends at least this many seconds [s] after the run began;
  /// empty: no limit.
  std::optional<double> max_seconds;
  sensor::PixelSampling rays = sensor::PixelSampling::released();  ///< IG ray set
  ig::SnapshotOptions snapshot;         ///< visibility and the snapshot's cap (the metrics' reads are added)
  ig::WalkOptions walk;                 ///< ray depth, threads, instruction set
  grid::MapConfig map;                  ///< SEMANTICS.md "The map"
  sensor::DepthCameraConfig camera;     ///< SEMANTICS.md "Simulation and evaluation": the ideal camera
  SceneConditions scene;                ///< SEMANTICS.md "Scene conditions"
  /// Decide each next view by an anytime decision (SEMANTICS.md "Anytime decisions") instead
  /// of evaluating every candidate on every ray; empty: exhaustive.
  std::optional<DecideOptions> anytime;
  std::size_t ground_truth_points = sensor::kDefaultGroundTruthPoints;
  std::uint64_t ground_truth_seed = 0;  ///< the same surface points for every run of a model
  double registration_distance_m = 0.005;  ///< Eq. 15's d_reg
  double entropy_cube_m = 1.28;            ///< Eq. 16's cube

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
};

/// A row of NBV_RECONSTRUCTION_OPTIONS as data (nbv/option_table.hpp).
using ReconstructionOption = OptionRow<ReconstructionConfig>;
/// The name of a planner that is not an IG utility ("oracle"), as `--metric` and Python's
/// metric= take it, or empty for Planner::Utility.
const char* plannerName(Planner planner);
/// Sets `config`'s planner from what `--metric` or Python's metric= gives: "oracle", or a
/// metric or weighted sum of metrics (parseMetricSum(), then Planner::Utility).
/// \throws InvalidArgument as parseMetricSum() for anything else.
void setPlanner(ReconstructionConfig& config, std::string_view text);
/// The rows of NBV_RECONSTRUCTION_OPTIONS, in its order.
std::span<const ReconstructionOption> reconstructionOptions();
/// The row named `name`, or null.
const ReconstructionOption* reconstructionOption(std::string_view name);

/// The fields of a run's record per iteration, each declared once: X(name, type, kind, help).
/// A row is an IterationRecord member (kind Run aside), a column of results.csv (in this order,
/// after model, metric and trial), a key of an iteration in the run files (`nbv reconstruct
/// --json`, an experiment's runs/) and in Python's iteration dicts, and a line of their help.
/// Kinds: Count (an integer), Number, Time (seconds; 0 under --no-timings), Gap (a number or
/// none: NaN, which JSON writes null and results.csv leaves empty), Run (the run's value,
/// ReconstructionResult's member, repeated on each row of results.csv only). A new field is a
/// row at the end, and the line of reconstruct() that sets it.
#define NBV_ITERATION_FIELDS(X)                                                                             \
  X(iteration, std::size_t, Count, "1-based: the number of scans so far")                                  \
  X(view, std::size_t, Count, "the view scanned: its index in the viewspace")                              \
  X(coverage, double, Number, "surface coverage after this scan (Eq. 15)")                                 \
  X(entropy_bits, double, Number, "map entropy after this scan [bits] (Eq. 16)")                           \
  X(max_entropy_bits, double, Run, "the entropy of the empty map's cube [bits]")                           \
  X(seconds_render, double, Time, "rendering the scan and marking its rays (a shared scan: the first time)") \
  X(seconds_integrate, double, Time, "applying the marked scan to the run's map")                          \
  X(seconds_ig, double, Time, "the NBV decision after this scan (in results.csv 0 where none followed)")    \
  X(ties, std::size_t, Count, "candidates sharing the best utility exactly (0: no decision followed)")     \
  X(gap, double, Gap, "best utility minus the second best (0 on a tie; NaN: one candidate, no decision)") \
  X(rays, std::uint64_t, Count, "rays cast for the decision")                                             \
  X(ray_share, double, Number, "the decision's rays over an exhaustive evaluation's (1 unless anytime)")

/// The fields of the table's first version (iteration to gap): a file written before a later
/// field was added lacks it, and it reads as its initial value.
inline constexpr std::size_t kFirstIterationFields = 10;

/// A field's initial value by its kind: NaN for a Gap (none), else 0.
#define NBV_ITERATION_INITIAL_Count 0
#define NBV_ITERATION_INITIAL_Number 0.0
#define NBV_ITERATION_INITIAL_Time 0.0
#define NBV_ITERATION_INITIAL_Run 0.0
#define NBV_ITERATION_INITIAL_Gap std::numeric_limits<double>::quiet_NaN()
/// Whether a field of kind `kind` is a Gap (its none is NaN: JSON null, an empty CSV field).
#define NBV_ITERATION_IS_GAP(kind) (std::string_view(#kind) == "Gap")
/// The code after `kind` for a field that IterationRecord holds, nothing for one of the run
/// (kind Run): the writers and readers of iterations skip those.
#define NBV_ITERATION_IF_RECORD(kind, ...) NBV_ITERATION_IF_RECORD_##kind(__VA_ARGS__)
#define NBV_ITERATION_IF_RECORD_Count(...) __VA_ARGS__
#define NBV_ITERATION_IF_RECORD_Number(...) __VA_ARGS__
#define NBV_ITERATION_IF_RECORD_Time(...) __VA_ARGS__
#define NBV_ITERATION_IF_RECORD_Gap(...) __VA_ARGS__
#define NBV_ITERATION_IF_RECORD_Run(...)

/// What one iteration did: iteration k scanned `view`; `gains` are the candidates' IG computed
/// afterwards to choose the view of iteration k + 1 (NaN for visited views; empty when no
/// choice followed). With an anytime decision the gains are its estimates of each candidate's
/// utility (Eq. 12; with gamma 0 the gain), exact for the candidates it evaluated on every ray.
/// The decision's margin (ties, gap): SEMANTICS.md "The planner".
struct IterationRecord {
#define NBV_ITERATION_MEMBER(name, type, kind, help) \
  NBV_ITERATION_IF_RECORD(kind, type name = NBV_ITERATION_INITIAL_##kind;)
  NBV_ITERATION_FIELDS(NBV_ITERATION_MEMBER)
#undef NBV_ITERATION_MEMBER
  std::vector<double> gains;
};

/// Why a reconstruction stopped.
enum class StopReason {
  MaxIterations,   ///< the scan budget
  BelowThreshold,  ///< Eq. 14
  NoViewsLeft,     ///< every view visited
  Caller,          ///< the caller's on_iteration returned false
  TimeLimit,       ///< max_seconds passed
};
const char* stopReasonName(StopReason reason);

struct ReconstructionResult {
  std::vector<IterationRecord> iterations;
  StopReason stop = StopReason::MaxIterations;
  double max_entropy_bits = 0.0;  ///< the entropy of the empty map's cube
  double auc_coverage = 0.0;      ///< SEMANTICS.md "Simulation and evaluation", over iterations 0..N
  double auc_entropy = 0.0;       ///< SEMANTICS.md "Simulation and evaluation", over iterations 0..N
};

/// What a rendered scan gives a run under `config`'s scene: the points to integrate (every hit
/// inside the crop box, and the no-return points under "clear") and the object hits among them,
/// the only points that cover the object (SEMANTICS.md "Scene conditions").
struct ScanPoints {
  std::vector<Eigen::Vector3f> integrated;
  std::vector<Eigen::Vector3f> on_object;
};
ScanPoints scanPoints(const sensor::DepthScan& scan, const Eigen::Isometry3d& T_world_camera,
                      const ReconstructionConfig& config);

/// The simulated object of a reconstruction: the placed mesh in its scene, the ground truth of
/// Eq. 15, and each view's scan, rendered on first use and then shared: what is the same for
/// every run on the object (every trial, metric and seed) is built once. Thread-safe.
class SimulatedObject {
 public:
  /// One view's scan, as a run uses it.
  struct Scan {
    std::vector<Eigen::Vector3f> points_world;  ///< to integrate: hits and no-return points, cropped
    /// The same points' rays marked once for the config's map: what a run integrates.
    std::optional<grid::ScanUpdate> update;
    std::vector<std::uint32_t> covered;         ///< ground-truth points its object hits cover
    double seconds_render = 0.0;                ///< rendering and preparing it (coverage, rays marked), once
  };

  /// Builds the scene and the ground truth of `mesh` (already placed) for `viewspace`, from the
  /// camera, scene, map range and ground-truth settings of `config`.
  /// \throws InvalidArgument for bad settings or an empty viewspace.
  SimulatedObject(const sensor::TriangleMesh& mesh, std::vector<View> viewspace, const ReconstructionConfig& config);
  ~SimulatedObject();

  const std::vector<View>& viewspace() const { return viewspace_; }
  const sensor::TriangleMesh& mesh() const { return mesh_; }
  const std::shared_ptr<const GroundTruth>& groundTruth() const { return ground_truth_; }
  /// The scan of view `view`, rendered on the first call. \throws InvalidArgument for a view
  /// outside the viewspace.
  const Scan& scan(std::size_t view) const;
  /// True if `config` asks for the object this one was built as (camera, scene, map range and
  /// ground truth alike).
  bool builtFor(const ReconstructionConfig& config) const;

 private:
  sensor::TriangleMesh mesh_;
  std::vector<View> viewspace_;
  ReconstructionConfig config_;
  std::unique_ptr<sensor::RayScene> scene_;
  sensor::DepthCamera camera_;
  std::shared_ptr<const GroundTruth> ground_truth_;
  mutable std::vector<std::once_flag> rendered_;
  mutable std::vector<Scan> scans_;
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

/// reconstruct() on an object built once for many runs: the same result as the call above
/// with the object's mesh and viewspace. Runs may share the object concurrently.
/// \throws InvalidArgument if the object was not built for `config` (SimulatedObject::builtFor).
ReconstructionResult reconstruct(const SimulatedObject& object, const ReconstructionConfig& config,
                                 const std::function<bool(const IterationRecord&)>& on_iteration = {});

/// reconstruct() deciding with `decider`: the same result as the calls above. Runs one after
/// another on one decider reuse its memory (the snapshot's arrays, the ray sample) instead of
/// allocating and clearing it again; the decider serves one run at a time.
/// \throws as the call above.
ReconstructionResult reconstruct(const SimulatedObject& object, const ReconstructionConfig& config,
                                 AnytimeDecider& decider,
                                 const std::function<bool(const IterationRecord&)>& on_iteration = {});

}  // namespace nbv::planner
