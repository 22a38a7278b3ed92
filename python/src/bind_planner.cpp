// Reconstructions and their scores.
#include "arrays.hpp"
#include "bindings.hpp"
#include "runs.hpp"
#include "threads.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/reconstruction.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <sstream>
#include <limits>
#include <string>
#include <string_view>

namespace nbv::python {

namespace {

py::dict recordDict(const planner::IterationRecord& r) {
  py::dict d;
#define NBV_DICT_FIELD(name, type, kind, help) NBV_ITERATION_IF_RECORD(kind, d[#name] = r.name;)
  NBV_ITERATION_FIELDS(NBV_DICT_FIELD)
#undef NBV_DICT_FIELD
  std::vector<double> gains = r.gains;
  d["gains"] = ownedArray(std::move(gains), {static_cast<py::ssize_t>(r.gains.size())});
  return d;
}

/// The viewspace argument: None (dome48), "dome48", a view file's path, or (N, 4, 4) poses.
std::pair<std::vector<planner::View>, std::string> viewspaceOf(const py::handle& viewspace) {
  if (viewspace.is_none()) return {planner::dome48(), "dome48"};
  if (py::isinstance<py::str>(viewspace)) {
    const std::string name = viewspace.cast<std::string>();
    if (name == "dome48") return {planner::dome48(), name};
    std::vector<planner::View> views = planner::loadViews(name);
    if (views.empty()) throw ViewFileError(name, "the viewspace holds no view");
    return {std::move(views), std::filesystem::absolute(name).lexically_normal().string()};
  }
  return {viewsOf(viewspace, "viewspace"), "array"};
}

/// The crop box of (x0, x1, y0, y1, z0, z1), or none.
std::optional<Eigen::AlignedBox3d> cropOf(const std::optional<std::vector<double>>& c) {
  if (!c) return std::nullopt;
  if (c->size() != 6) throw InvalidArgument("crop: give (x0, x1, y0, y1, z0, z1) or None");
  const Eigen::Vector3d lo((*c)[0], (*c)[2], (*c)[4]), hi((*c)[1], (*c)[3], (*c)[5]);
  if (!(lo.array() < hi.array()).all()) throw InvalidArgument("crop: each minimum must be below its maximum");
  return Eigen::AlignedBox3d(lo, hi);
}

/// Applies the keyword options of reconstruct(), each already of its type (the Python layer
/// takes only these names and converts each value).
void applyOptions(planner::ReconstructionConfig& config, std::optional<int>& threads, bool& no_timings,
                  const py::dict& options) {
  for (const auto& [key, value] : options) {
    const std::string k = py::str(key);
    if (const planner::ReconstructionOption* option = planner::reconstructionOption(k)) {
      option->set(config, value.cast<std::optional<double>>());
    } else if (k == "weighting") {
      config.weighting = planner::weightingFromName(value.cast<std::string>());
    } else if (k == "threads") {
      threads = value.cast<std::optional<int>>();
    } else if (k == "visibility") {
      config.snapshot.visibility = visibilityOf(value.cast<std::string>());
    } else if (k == "no_timings") {
      no_timings = value.cast<bool>();
    } else if (k == "scene") {
      const planner::SceneConditions preset = planner::sceneNamed(value.cast<std::string>());
      // A preset sets the base; ground_plane, no_return and crop change it, in any order.
      if (!options.contains("ground_plane")) config.scene.ground_plane = preset.ground_plane;
      if (!options.contains("no_return")) config.scene.no_return = preset.no_return;
      if (!options.contains("crop")) config.scene.crop = preset.crop;
    } else if (k == "ground_plane") {
      config.scene.ground_plane = value.cast<bool>();
    } else if (k == "no_return") {
      config.scene.no_return = planner::noReturnFromName(value.cast<std::string>());
    } else if (k == "crop") {
      config.scene.crop = cropOf(value.cast<std::optional<std::vector<double>>>());
    } else if (k == "anytime") {
      const bool anytime = value.cast<bool>();
      if (anytime && !config.anytime) config.anytime = planner::DecideOptions{};
      if (!anytime) config.anytime.reset();
    } else if (planner::decideOption(k) == nullptr && k != "up") {  // anytime decisions' options: below
      throw InvalidArgument("reconstruct: unknown option '" + k + "'");
    }
  }
  for (const planner::DecideOption& option : planner::decideOptions()) {
    if (!options.contains(option.name)) continue;
    if (!config.anytime) throw InvalidArgument(std::string(option.name) + " needs anytime=True");
    option.set(*config.anytime, options[option.name].cast<std::optional<double>>());
  }
}

/// The state of a decision as a planner of one's own sees it: a dict of the map (a copy),
/// viewspace ((V, 4, 4) poses), taken (the views scanned, in order), candidates ((C,) int64,
/// the order of the gains it returns), iteration, metric_values(metrics="pc") -> (C, k)
/// float64, the candidates' values of the built-in metrics on the run's rays, and
/// visible_voxels(c), the voxels the run's rays reach from candidate c (as
/// Decider.visible_voxels). The two functions work during the call only (`alive`).
py::dict stateDict(const planner::DecisionState& state, const std::shared_ptr<bool>& alive) {
  py::dict d;
  d["map"] = py::cast(grid::OccupancyMap(state.map));
  d["viewspace"] = posesArray(state.viewspace);
  d["taken"] = py::cast(state.taken);
  std::vector<std::int64_t> candidates(state.candidates.begin(), state.candidates.end());
  d["candidates"] = ownedArray(std::move(candidates), {static_cast<py::ssize_t>(state.candidates.size())});
  d["iteration"] = state.iteration;
  d["metric_values"] = py::cpp_function(
      [&state, alive](const py::object& metrics) {
        if (!*alive) throw InvalidArgument("metric_values: the decision it belongs to is over");
        std::vector<std::string> names;
        if (py::isinstance<py::str>(metrics)) {
          std::stringstream text(metrics.cast<std::string>());
          for (std::string name; std::getline(text, name, ',');) {
            name.erase(0, name.find_first_not_of(' '));
            name.erase(name.find_last_not_of(' ') + 1);
            names.push_back(name);
          }
        } else {
          names = metrics.cast<std::vector<std::string>>();
        }
        std::vector<ig::Metric> chosen;
        for (const std::string& name : names) chosen.push_back(kernels::metricNamed(name));
        if (chosen.empty()) throw InvalidArgument("metric_values: no metric named");
        ig::IgTable table;
        {
          py::gil_scoped_release unlocked;
          table = state.evaluate(chosen);
        }
        std::vector<double> values = table.values;
        return ownedArray(std::move(values), {static_cast<py::ssize_t>(state.candidates.size()),
                                              static_cast<py::ssize_t>(chosen.size())});
      },
      py::arg("metrics") = "pc");
  d["visible_voxels"] = py::cpp_function(
      [&state, alive](std::size_t c) {
        if (!*alive) throw InvalidArgument("visible_voxels: the decision it belongs to is over");
        std::vector<ig::VisibleVoxel> voxels;
        {
          py::gil_scoped_release unlocked;
          voxels = state.visible_voxels(c);
        }
        return visibleVoxelsDict(state.map, voxels);
      },
      py::arg("c"));
  return d;
}

}  // namespace

planner::CandidateScorer pythonScorer(PyObject* planner) {
  return [planner](const planner::DecisionState& state) {
    py::gil_scoped_acquire locked;
    const auto alive = std::make_shared<bool>(true);
    struct Expire {  // the state's functions end with the call, whatever it raised
      std::shared_ptr<bool> alive;
      ~Expire() { *alive = false; }
    } expire{alive};
    // A Python error leaves as py::error_already_set: it ends the run (and an experiment's
    // further runs), and the caller's binding raises it again.
    const py::object answer = py::reinterpret_borrow<py::object>(planner)(stateDict(state, alive));
    try {
      return answer.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
      throw InvalidArgument("the planner's answer is not a sequence of numbers, one per candidate");
    }
  };
}

RunSettings runSettings(std::size_t iterations, const RaysGiven& rays, const py::handle& viewspace,
                        const py::dict& options) {
  RunSettings s;
  s.config.max_iterations = iterations;
  s.rays = std::holds_alternative<int>(rays) ? std::to_string(std::get<int>(rays)) : std::get<std::string>(rays);
  s.config.rays = sensor::PixelSampling::fromName(s.rays);
  applyOptions(s.config, s.threads, s.no_timings, options);
  std::tie(s.views, s.viewspace) = viewspaceOf(viewspace);
  // The up axis: up=..., else the scene preset's (planner::sceneUp; "bare", the default, keeps z).
  s.preset = options.contains("scene") ? options["scene"].cast<std::string>() : "bare";
  s.up = options.contains("up") ? options["up"].cast<std::string>() : planner::sceneUp(s.preset);
  return s;
}

ModelArg modelOf(const ModelGiven& model, const std::string& up) {
  std::shared_ptr<Mesh> mesh = meshOf(model, up);
  if (const std::string* name = std::get_if<std::string>(&model)) return {*name, mesh->source(), up, mesh};
  if (mesh->source().empty()) return {"mesh", "mesh", up, mesh};
  return {"mesh", mesh->source(), mesh->up(), mesh};
}

py::dict runDict(const std::string& model, const std::string& up, const std::string& metric, std::uint64_t seed,
                 const RunSettings& settings, planner::ReconstructionResult& result) {
  const planner::ReconstructionConfig& config = settings.config;
  py::list records;
  for (planner::IterationRecord& r : result.iterations) {
    if (settings.no_timings) r.seconds_render = r.seconds_integrate = r.seconds_ig = 0.0;
    records.append(recordDict(r));
  }
  py::dict out;
  out["model"] = model;
  out["metric"] = metric;
  out["seed"] = seed;
  out["viewspace"] = settings.viewspace;
  out["weighting"] = planner::weightingName(config.weighting);
  out["rays"] = settings.rays;
  for (const planner::ReconstructionOption& option : planner::reconstructionOptions()) {
    const std::optional<double> value = option.get(config);
    out[option.name] = value ? py::cast(*value) : py::none();
  }
  py::dict scene;
  scene["name"] = planner::sceneLabel(settings.preset, config.scene, up);
  scene["ground_plane"] = config.scene.ground_plane;
  scene["no_return"] = config.scene.no_return == planner::NoReturn::Clear ? "clear" : "drop";
  if (config.scene.crop) {
    const Eigen::AlignedBox3d& b = *config.scene.crop;
    scene["crop"] = py::make_tuple(b.min().x(), b.max().x(), b.min().y(), b.max().y(), b.min().z(), b.max().z());
  } else {
    scene["crop"] = py::none();
  }
  scene["up"] = up;
  scene["visibility"] = kernels::visibilityName(config.snapshot.visibility);
  out["scene"] = scene;
  if (config.anytime) {
    py::dict anytime;
    for (const planner::DecideOption& option : planner::decideOptions()) {
      const std::optional<double> value = option.get(*config.anytime);
      anytime[option.name] = value ? py::cast(*value) : py::none();
    }
    out["anytime"] = anytime;
  } else {
    out["anytime"] = py::none();
  }
  out["stop"] = planner::stopReasonName(result.stop);
  out["iterations"] = records;
  out["max_entropy_bits"] = result.max_entropy_bits;
  out["auc_coverage"] = result.auc_coverage;
  out["auc_entropy"] = result.auc_entropy;
  if (settings.viewspace == "array") {  // the poses themselves, so that a report can draw them
    py::list views;
    for (const planner::View& v : settings.views) {
      const Eigen::Vector3d p = v.T_world_camera.translation();
      const Eigen::Quaterniond q = planner::canonicalQuaternion(v);
      views.append(py::make_tuple(p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()));
    }
    out["views"] = views;
  }
  return out;
}

namespace {

constexpr const char* kReconstructDoc = R"doc(
The paper's Algorithm 1 in simulation, as `nbv reconstruct`: start at a view drawn with the
seed, scan it with the ideal camera, integrate, score the views not visited yet, move to the
best, until `iterations` scans. model: a standard name or a mesh path (placed as load_mesh()
places it), or a Mesh (used as given, world frame). metric: a short name or a weighted sum
("0.5*pc+0.5*vg"), or "oracle" (the ground-truth ceiling, docs/SEMANTICS.md "The oracle"). rays: "released", "released-shipped", "full" or a pixel
stride. viewspace: None or "dome48", a
view file's path, or (N, 4, 4) T_world_camera poses. callback(record) runs after each scan with
that iteration's dict and may return False to stop the run. options: the run's
RECONSTRUCTION_OPTIONS
weighting ("normalized" or "raw"), threads (None: every core), visibility ("paper"),
no_timings (False: times as measured), and the scene (docs/SEMANTICS.md, "Scene
conditions"): scene ("bare", "released" or "paper": a preset), ground_plane (bool), no_return
("drop" or "clear"), crop ((x0, x1, y0, y1, z0, z1) [m] or None), up ("z", "y" or "auto", for a
model named by name or path; default: the preset's, "auto" for "paper", else "z"), and anytime
decisions (docs/SEMANTICS.md, "Anytime decisions"): anytime (False), and with anytime=True
DECIDE_OPTIONS

Returns the fields of `nbv reconstruct --json`, in its order: model, metric, seed, viewspace,
weighting, rays, OPTION_NAMES, scene (name: the preset and what differs from it, then each condition),
anytime (None or DECIDE_NAMES), stop, iterations, max_entropy_bits, auc_coverage,
auc_entropy. iterations holds a dict per scan:
ITERATION_FIELDS
    gains: a (V,) float64 array of every candidate's gain, NaN for visited views, empty after
        the last scan
save_run() writes it as that file.
)doc";

/// The rows of an option table as a docstring lists them, a line each: "    gamma = 0: cost
/// weight of Eq. 12...; must be in [0, 1]".
template <class Config>
std::string optionLines(std::span<const OptionRow<Config>> rows) {
  const Config defaults;
  std::string lines;
  for (const OptionRow<Config>& option : rows) {
    const std::optional<double> initial = option.get(defaults);
    const std::string unit = *option.unit ? std::string(" [") + option.unit + "]" : "";
    lines += "    " + std::string(option.name) + unit + " = " + (initial ? numberText(*initial) : "None") + ": " +
             option.help + "; " + option.rule + "\n";
  }
  return lines;
}

/// The rows' names, comma-separated.
template <class Config>
std::string optionNames(std::span<const OptionRow<Config>> rows) {
  std::string names;
  for (const OptionRow<Config>& option : rows) names += (names.empty() ? "" : ", ") + std::string(option.name);
  return names;
}

/// An option table as Python reads it: name -> (optional, default or None).
template <class Config>
py::dict optionDefaults(std::span<const OptionRow<Config>> rows) {
  const Config defaults;
  py::dict table;
  for (const OptionRow<Config>& option : rows) {
    const std::optional<double> initial = option.get(defaults);
    table[option.name] = py::make_tuple(option.optional, initial ? py::cast(*initial) : py::none());
  }
  return table;
}

/// kReconstructDoc with the iteration record's fields, a line each with what it holds, in the
/// table's order (NBV_ITERATION_FIELDS; the run's own aside).
const std::string& reconstructDoc() {
  static const std::string doc = [] {
    std::string fields;
#define NBV_FIELD_HELP(name, type, kind, help) \
  NBV_ITERATION_IF_RECORD(kind, fields += std::string(fields.empty() ? "" : "\n") + "    " #name ": " + help;)
    NBV_ITERATION_FIELDS(NBV_FIELD_HELP)
#undef NBV_FIELD_HELP
    std::string text = kReconstructDoc;
    auto fill = [&text](std::string_view key, const std::string& value) { text.replace(text.find(key), key.size(), value); };
    fill("ITERATION_FIELDS", fields);
    fill("RECONSTRUCTION_OPTIONS\n", optionLines(planner::reconstructionOptions()));
    fill("OPTION_NAMES", optionNames(planner::reconstructionOptions()));
    fill("DECIDE_OPTIONS\n", optionLines(planner::decideOptions()));
    fill("DECIDE_NAMES", optionNames(planner::decideOptions()));
    return text;
  }();
  return doc;
}
constexpr const char* kStartViewDoc = R"doc(
The first view of a reconstruction with `seed` over `view_count` candidates: the draw
reconstruct() and `nbv reconstruct` make (docs/SEMANTICS.md, "The planner").
)doc";
constexpr const char* kSurfaceCoverageClassDoc = R"doc(
Eq. 15 scan by scan: the ground truth in a KD-tree, each scan marking the points it covers, as
reconstruct() scores its runs.
)doc";
constexpr const char* kSurfaceCoverageDoc = R"doc(
ground_truth: (N, 3) floating, world frame [m] (sample_surface()). d_reg: registration distance [m].
)doc";
constexpr const char* kAddScanDoc = R"doc(
Marks the ground-truth points within d_reg of any point of one scan ((K, 3) floating, world
frame [m]).
)doc";
constexpr const char* kSurfaceCoverageDoc2 = R"doc(
Eq. 15: the fraction of ground-truth points ((N, 3) floating, world frame [m]; sample_surface())
that have an observed point ((K, 3), all scans so far) within d_reg [m].
)doc";
constexpr const char* kMapEntropyBitsDoc = R"doc(
Eq. 16: the sum of voxel entropies in bits over the cube of `edge` [m] centred on `centre`
((3,), world frame [m]); an unmeasured voxel counts 1 bit (docs/SEMANTICS.md, "Simulation and
evaluation").
)doc";

}  // namespace

namespace {

void bindReconstructionAndCoverage(py::module_& m) {
  m.def(
      "reconstruct",
      [](const ModelGiven& model, const py::object& planner, std::uint64_t seed, std::size_t iterations,
         const RaysGiven& rays, const py::handle& viewspace, const std::optional<py::function>& callback,
         const py::dict& options) {
        const RunSettings settings = runSettings(iterations, rays, viewspace, options);
        planner::ReconstructionConfig config = settings.config;
        std::string metric;  // the run's label
        if (PyCallable_Check(planner.ptr())) {
          config.planner = planner::Planner::Custom;
          config.scorer = pythonScorer(planner.ptr());
          metric = py::hasattr(planner, "__name__") ? py::str(planner.attr("__name__")).cast<std::string>() : "custom";
        } else {
          metric = planner.cast<std::string>();
          planner::setPlanner(config, metric);
        }
        config.seed = seed;
        config.validate();
        const ModelArg chosen = modelOf(model, settings.up);
        const std::shared_ptr<Mesh>& mesh = chosen.mesh;
        bool callback_failed = false;
        std::function<bool(const planner::IterationRecord&)> on_iteration;
        if (callback) {
          on_iteration = [&](const planner::IterationRecord& r) {
            py::gil_scoped_acquire locked;
            try {
              const py::object answer = (*callback)(recordDict(r));
              return answer.is_none() || optionValue<bool>(answer, "reconstruct: the callback's answer");
            } catch (py::error_already_set& e) {
              e.restore();  // raised again once the run has returned
              callback_failed = true;
              return false;
            }
          };
        }
        planner::ReconstructionResult result = runReleased(
            settings.threads, [&] { return planner::reconstruct(mesh->mesh(), settings.views, config, on_iteration); });
        if (callback_failed) throw py::error_already_set();
        return runDict(chosen.record, chosen.up, metric, seed, settings, result);
      },
      reconstructDoc().c_str());

  m.def(
      "start_view",
      [](std::uint64_t seed, std::size_t view_count) { return planner::startView(seed, view_count); }, kStartViewDoc);

  py::class_<planner::SurfaceCoverage>(m, "SurfaceCoverage", kSurfaceCoverageClassDoc)
      .def(py::init([](const py::handle& ground_truth, double d_reg) {
             const Rows<Eigen::Vector3f> truth = pointsFloat(ground_truth, "ground_truth");
             return planner::SurfaceCoverage({truth.rows.begin(), truth.rows.end()}, d_reg);
           }),
           kSurfaceCoverageDoc)
      .def(
          "add_scan",
          [](planner::SurfaceCoverage& coverage, const py::handle& observed) {
            const Rows<Eigen::Vector3f> points = pointsFloat(observed, "observed");
            py::gil_scoped_release unlocked;
            coverage.addScan(points.rows);
          },
          kAddScanDoc)
      .def_property_readonly("coverage", &planner::SurfaceCoverage::coverage, "Covered fraction in [0, 1].");
}

void bindScores(py::module_& m) {

  m.def(
      "surface_coverage",
      [](const py::handle& ground_truth, const py::handle& observed, double d_reg) {
        const Rows<Eigen::Vector3f> truth = pointsFloat(ground_truth, "ground_truth");
        const Rows<Eigen::Vector3f> seen = pointsFloat(observed, "observed");
        planner::SurfaceCoverage coverage({truth.rows.begin(), truth.rows.end()}, d_reg);
        coverage.addScan(seen.rows);
        return coverage.coverage();
      },
      kSurfaceCoverageDoc2);

  m.def(
      "map_entropy_bits",
      [](const grid::OccupancyMap& map, const py::handle& centre, double edge) {
        return planner::mapEntropyBits(map, vector3(centre, "centre"), edge);
      },
      kMapEntropyBitsDoc);
}

}  // namespace

void bindPlanner(py::module_& m) {
  // The iteration record's fields, as the table declares them (nbv/__init__.py reads them).
  py::list fields;
#define NBV_FIELD_TUPLE(name, type, kind, help) \
  NBV_ITERATION_IF_RECORD(kind, fields.append(py::make_tuple(#name, #kind, help));)
  NBV_ITERATION_FIELDS(NBV_FIELD_TUPLE)
#undef NBV_FIELD_TUPLE
  m.attr("_ITERATION_FIELDS") = py::tuple(fields);
  // The option tables of a reconstruction and of its anytime decisions: name -> (optional, default).
  m.attr("_RECONSTRUCTION_OPTIONS") = optionDefaults(planner::reconstructionOptions());
  m.attr("_DECIDE_OPTIONS") = optionDefaults(planner::decideOptions());
  bindReconstructionAndCoverage(m);
  bindScores(m);
}

}  // namespace nbv::python
