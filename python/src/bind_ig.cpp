// The information-gain evaluators and their table.
#include "arrays.hpp"
#include "bindings.hpp"
#include "threads.hpp"

#include "nbv/errors.hpp"
#include "nbv/ig/evaluator.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/utility.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>

namespace nbv::python {

namespace {

/// An evaluation's result: the table and the seconds the C++ evaluation took.
struct Table {
  ig::IgTable table;
  double seconds = 0.0;
};

std::vector<ig::Metric> metricsOf(const std::vector<std::string>& names) {
  if (names.size() == 1 && names[0] == "all") return {kernels::kAllMetrics.begin(), kernels::kAllMetrics.end()};
  std::vector<ig::Metric> out;
  for (const std::string& name : names) out.push_back(kernels::metricNamed(name));
  if (out.empty()) throw InvalidArgument("metrics: no metric named");
  return out;
}

/// The column of metric `name` in the table, if it has one.
std::optional<std::size_t> columnOf(const Table& t, const std::string& name) {
  const auto metric = kernels::metricFromName(name);
  if (!metric) return std::nullopt;
  const auto at = std::find(t.table.metrics.begin(), t.table.metrics.end(), *metric);
  if (at == t.table.metrics.end()) return std::nullopt;
  return static_cast<std::size_t>(at - t.table.metrics.begin());
}

}  // namespace

ig::Visibility visibilityOf(const std::string& name) { return kernels::visibilityFromName(name); }

py::dict visibleVoxelsDict(const grid::OccupancyMap& map, const std::vector<ig::VisibleVoxel>& voxels) {
  std::vector<std::int32_t> ijk;
  std::vector<Eigen::Vector3d> centres;
  std::vector<double> visible;
  std::vector<std::uint32_t> count;
  ijk.reserve(3 * voxels.size());
  centres.reserve(voxels.size());
  visible.reserve(voxels.size());
  count.reserve(voxels.size());
  for (const ig::VisibleVoxel& v : voxels) {
    ijk.insert(ijk.end(), {v.ijk.x(), v.ijk.y(), v.ijk.z()});
    centres.push_back(map.indexToWorld(v.ijk));
    visible.push_back(v.visibility);
    count.push_back(v.rays);
  }
  const auto n = static_cast<py::ssize_t>(voxels.size());
  py::dict out;
  out["index"] = ownedArray(std::move(ijk), {n, 3});
  out["centres"] = ownedRows(std::move(centres));
  out["visibility"] = ownedArray(std::move(visible), {n});
  out["rays"] = ownedArray(std::move(count), {n});
  return out;
}

/// Decider.visible_voxels().

namespace {

/// Decider.evaluate(): the table of the views' information gain.
std::shared_ptr<Table> evaluate(planner::AnytimeDecider& decider, const grid::OccupancyMap& map, const py::handle& views,
                                const py::handle& rays, const std::vector<std::string>& metrics,
                                const std::string& visibility, double max_ray_depth, std::optional<int> threads,
                                bool reference, std::uint64_t seed, const std::optional<std::string>& isa) {
  const std::vector<Eigen::Isometry3d> poses_world = poses(views, "views");
  const Rows<Eigen::Vector3d> directions = pointsDouble(rays, "rays");
  ig::EvaluateOptions options;
  options.table.metrics = metricsOf(metrics);
  options.table.random_seed = seed;
  options.snapshot.visibility = visibilityOf(visibility);
  options.walk.max_ray_depth = max_ray_depth;
  if (isa) {
    options.walk.isa = kernels::isaFromName(*isa);
    if (!options.walk.isa || !kernels::isaAvailable(*options.walk.isa)) {
      throw InvalidArgument("isa '" + *isa + "' is not available here (known: scalar, avx2, avx512)");
    }
  }
  options.validate();
  auto result = std::make_shared<Table>();
  runReleased(reference ? std::optional<int>(1) : threads, [&] {
    const auto start = std::chrono::steady_clock::now();
    result->table = reference ? ig::ReferenceEvaluator(map).evaluate(poses_world, directions.rows, options)
                              : ig::evaluate(decider.evaluator(), map, poses_world, directions.rows, options);
    result->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return 0;
  });
  return result;
}

/// The visible voxels as the dict visible_voxels() returns.
py::dict visibleVoxels(planner::AnytimeDecider& decider, const grid::OccupancyMap& map, const py::handle& view,
                       const py::handle& rays, const std::string& visibility, double max_ray_depth,
                       std::optional<int> threads) {
  const std::vector<Eigen::Isometry3d> T_world_cameras = poses(view, "view");
  const Rows<Eigen::Vector3d> directions = pointsDouble(rays, "rays");
  ig::SnapshotOptions snapshot;
  snapshot.visibility = visibilityOf(visibility);
  ig::WalkOptions walk;
  walk.max_ray_depth = max_ray_depth;
  walk.validate();
  const std::vector<ig::VisibleVoxel> voxels = runReleased(threads, [&] {
    decider.evaluator().refresh(map, snapshot);
    return decider.evaluator().visibleVoxels(T_world_cameras, directions.rows, walk);
  });
  return visibleVoxelsDict(map, voxels);
}

/// An anytime decision as the dict decide() returns.
py::dict decisionDict(const planner::AnytimeDecision& d) {
  std::vector<double> estimate, lower, upper;
  std::vector<std::uint64_t> cast;
  std::vector<std::uint8_t> exact, eliminated;
  for (const planner::CandidateEstimate& e : d.candidates) {
    estimate.push_back(e.estimate);
    lower.push_back(e.lower);
    upper.push_back(e.upper);
    cast.push_back(e.rays);
    exact.push_back(e.exact ? 1 : 0);
    eliminated.push_back(e.eliminated ? 1 : 0);
  }
  const auto n = static_cast<py::ssize_t>(d.candidates.size());
  py::dict out;
  out["chosen"] = d.chosen;
  out["end"] = planner::decisionEndName(d.end);
  out["estimate"] = ownedArray(std::move(estimate), {n});
  out["lower"] = ownedArray(std::move(lower), {n});
  out["upper"] = ownedArray(std::move(upper), {n});
  out["exact"] = py::array(ownedArray(std::move(exact), {n})).attr("astype")("bool");
  out["eliminated"] = py::array(ownedArray(std::move(eliminated), {n})).attr("astype")("bool");
  out["rays"] = ownedArray(std::move(cast), {n});
  out["rays_cast"] = d.rays_cast;
  out["rays_exhaustive"] = d.rays_exhaustive;
  out["levels"] = d.levels;
  out["seconds"] = d.seconds;
  return out;
}

/// Decider.decide().
py::dict decide(planner::AnytimeDecider& decider, const grid::OccupancyMap& map, const py::handle& views,
                const py::handle& rays, const std::string& metric, const std::string& weighting, double gamma,
                const std::optional<std::vector<double>>& costs, double epsilon, double delta,
                std::optional<std::uint64_t> max_rays, std::optional<double> budget_ms, std::uint64_t seed,
                const std::string& visibility, double max_ray_depth, std::optional<int> threads) {
  const std::vector<Eigen::Isometry3d> poses_world = poses(views, "views");
  const Rows<Eigen::Vector3d> directions = pointsDouble(rays, "rays");
  planner::DecisionUtility utility;
  utility.terms = planner::parseMetricSum(metric);
  utility.weighting = planner::weightingFromName(weighting);
  utility.gamma = gamma;
  if (costs) utility.costs = *costs;
  planner::DecideOptions options;
  options.epsilon = epsilon;
  options.delta = delta;
  options.max_rays = max_rays;
  options.max_ms = budget_ms;
  options.seed = seed;
  ig::SnapshotOptions snapshot;
  snapshot.visibility = visibilityOf(visibility);
  ig::WalkOptions walk;
  walk.max_ray_depth = max_ray_depth;
  const planner::AnytimeDecision d = runReleased(threads, [&] {
    decider.refresh(map, utility, snapshot);
    return decider.decide(poses_world, directions.rows, utility, walk, options);
  });
  return decisionDict(d);
}

constexpr const char* kTableDoc = R"doc(
The information gain of each view for each metric, with the counts behind them. It reads as a
pandas DataFrame of one column per metric: table["pc"] is a column, len(table) the number of
views, iterating gives the metric names, and numpy.asarray(table) is table.values.
)doc";
constexpr const char* kEvaluatorDoc = R"doc(
A planner's decider: the fast evaluator (docs/SEMANTICS.md, "Volumetric information"), a dense
snapshot of the map refreshed block by block and walked by SIMD ray packets on TBB threads,
with evaluate() (every metric of every view on every ray), decide() (an anytime decision,
docs/SEMANTICS.md, "Anytime decisions") and visible_voxels(). Keep one per map: the snapshot
and the ordered ray set are reused. (Named IgEvaluator before; that name still works, with a
DeprecationWarning, until the next release.) One evaluation at a time per evaluator; two
evaluators may run in two Python threads at once (the GIL is released).
)doc";
constexpr const char* kEvaluateDoc = R"doc(
The information gain of each view. map: an OccupancyMap. views: (N, 4, 4) float64
T_world_camera poses (camera -> world). rays: (R, 3) unit directions in the camera frame
(ray_set(); read in place when C-contiguous float64). metrics: short names (nbv.METRICS), as a
sequence or a comma-separated string, or "all". visibility: "paper" (Eq. 5) or "released" (the released
code's). max_ray_depth [m]. threads: TBB threads (None: every core). reference: the OctoMap
reference evaluator instead (one thread). seed: of `random`. isa: "scalar", "avx2" or "avx512"
(None: the widest available; every one gives the same bits). Raises nbv.InvalidArgument for bad
arguments, nbv.CapacityError for a map whose snapshot exceeds the memory cap.
)doc";
constexpr const char* kVisibleVoxelsDoc = R"doc(
The voxels the rays of a view reach, each ray walked exactly as evaluate() walks it (up to its
end, cut after the first occupied voxel), each voxel once: what a planner needs to compute its
own gains. view: (4, 4) float64 T_world_camera, or (N, 4, 4): the views of a path, the voxels
of all their rays together, each voxel once. rays: (R, 3) unit directions, camera frame.
visibility: "paper" (Eq. 5) or "released". max_ray_depth [m].

Returns a dict of K voxels ordered by z, then y, then x: index ((K, 3) int32 lattice indices),
centres ((K, 3) float64, world frame [m]), visibility ((K,) float64: the greatest P_v any ray
of any view reaches the voxel with, 1 at a camera's voxel), rays ((K,) uint32: how many rays
reach it). Raises nbv.InvalidArgument for a bad pose, ray or option.
)doc";
constexpr const char* kDecideDoc = R"doc(
An anytime decision (docs/SEMANTICS.md, "Anytime decisions"): the view of `views` ((N, 4, 4)
T_world_camera) with the largest utility, from nested stratified samples of the rays ((R, 3)
unit directions, camera frame), candidates eliminated when their confidence interval falls
below the best, the last ones evaluated on every ray. metric: a metric or a weighted sum
("0.5*pc+0.5*vg"); gamma and costs ((N,) metres) add Eq. 12's travel cost. epsilon: stop once
every candidate left is within this share of the best (0: the exhaustive argmax, unless an
interval failed: probability at most delta). max_rays, budget_ms: budgets. The same seed gives
the same decision at any thread count.

Returns a dict: chosen (index), end ("one_left", "epsilon", "exact" or "budget"), estimate,
lower, upper ((N,) float64: each candidate's utility and interval), exact, eliminated ((N,)
bool), rays ((N,) uint64 cast per candidate), rays_cast, rays_exhaustive, levels, seconds.
)doc";

void bindIgTable(py::module_& m) {
  py::class_<Table, std::shared_ptr<Table>>(m, "IgTable", kTableDoc)
      .def_property_readonly(
          "values",
          [](const py::object& self) {
            const Table& t = self.cast<const Table&>();
            const auto views = static_cast<py::ssize_t>(t.table.views());
            const auto metrics = static_cast<py::ssize_t>(t.table.metrics.size());
            // A view of the table's own memory: no copy; the array keeps the table alive.
            py::array_t<double> values({views, metrics}, t.table.values.data(), self);
            values.attr("setflags")(py::arg("write") = false);
            return values;
          },
          "(N, M) float64, read-only: views in the order given, metrics in the order of `metrics`. Not a copy.")
      .def_property_readonly("metrics",
                             [](const Table& t) {
                               std::vector<std::string> names;
                               for (ig::Metric metric : t.table.metrics) names.emplace_back(kernels::metricName(metric));
                               return names;
                             },
                             "The metrics' short names, one per column.")
      .def_property_readonly("rays", [](const Table& t) { return t.table.rays; }, "Rays cast, all views.")
      .def_property_readonly("voxels", [](const Table& t) { return t.table.voxels; },
                             "Voxel visits: the voxels x_0..x_n of every ray.")
      .def_property_readonly("seconds", [](const Table& t) { return t.seconds; },
                             "Seconds the C++ evaluation took (what a call costs beyond it is Python's).")
      .def(
          "__getitem__",
          [](const py::object& self, const py::object& key) -> py::object {
            const Table& t = self.cast<const Table&>();
            if (!py::isinstance<py::str>(key)) {
              // As a pandas DataFrame: columns by name; rows are table.values[i].
              throw py::key_error("the table's columns are metric names (" +
                                  std::string(py::str(self.attr("metrics"))) + "), not " + std::string(py::repr(key)) +
                                  "; a view's row is table.values[i]");
            }
            const std::string name = key.cast<std::string>();
            const std::optional<std::size_t> c = columnOf(t, name);
            if (!c) throw py::key_error("the table has no column '" + name + "'");
            const py::object values = self.attr("values");
            const py::slice all_views(0, static_cast<py::ssize_t>(t.table.views()), 1);
            return values[py::make_tuple(all_views, py::int_(*c))];
          },
          py::arg("metric"), "table['pc'] -> (N,) float64: one metric's column (a view, not a copy).")
      .def("__len__", [](const Table& t) { return t.table.views(); }, "The number of views (rows).")
      .def(
          "__iter__", [](const py::object& self) { return self.attr("metrics").attr("__iter__")(); },
          "The metric names (columns), as iterating a pandas DataFrame gives its columns.")
      .def(
          "__contains__",
          [](const Table& t, const py::object& key) {
            return py::isinstance<py::str>(key) && columnOf(t, key.cast<std::string>()).has_value();
          },
          "'pc' in table: whether the table has that metric's column.")
      .def(
          "__array__", [](const py::object& self, const py::args&) { return self.attr("values"); },
          "numpy.asarray(table) is table.values.")
      .def("__repr__", [](const Table& t) {
        return "<nbv.IgTable " + std::to_string(t.table.views()) + " views x " + std::to_string(t.table.metrics.size()) +
               " metrics, " + std::to_string(t.table.rays) + " rays>";
      });
}

}  // namespace

void bindInformationGain(py::module_& m) {
  bindIgTable(m);
  m.attr("_MAX_RAY_DEPTH") = ig::WalkOptions{}.max_ray_depth;  // the rays' default length [m]
  py::class_<planner::AnytimeDecider>(m, "Decider", kEvaluatorDoc)
      .def(py::init<>(), "Decider(): an evaluator with no snapshot yet; the first evaluation takes one.")
      .def("evaluate", &evaluate, kEvaluateDoc)
      .def("visible_voxels", &visibleVoxels, kVisibleVoxelsDoc)
      .def("decide", &decide, kDecideDoc);
}

}  // namespace nbv::python
