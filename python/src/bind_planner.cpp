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
#include <limits>

namespace nbv::python {

namespace {

py::dict recordDict(const planner::IterationRecord& r) {
  py::dict d;
  d["iteration"] = r.iteration;
  d["view"] = r.view;
  d["coverage"] = r.coverage;
  d["entropy_bits"] = r.entropy_bits;
  d["seconds_render"] = r.seconds_render;
  d["seconds_integrate"] = r.seconds_integrate;
  d["seconds_ig"] = r.seconds_ig;
  d["ties"] = r.ties;
  d["gap"] = r.gap;
  d["rays"] = r.rays;
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

/// Applies the keyword options of reconstruct(), refusing unknown ones by name.
void applyOptions(const std::string& owner, planner::ReconstructionConfig& config, std::optional<int>& threads,
                  bool& no_timings, const py::kwargs& options) {
  const KeywordOptions option{owner};
  for (const auto& [key, value] : options) {
    const std::string k = py::str(key);
    if (k == "gamma") {
      config.gamma = option.as<double>(value, k);
    } else if (k == "weighting") {
      config.weighting = planner::weightingFromName(option.as<std::string>(value, k));
    } else if (k == "threads") {
      if (!value.is_none()) threads = option.as<int>(value, k);
    } else if (k == "visibility") {
      config.snapshot.visibility = visibilityOf(option.as<std::string>(value, k));
    } else if (k == "max_ray_depth") {
      config.walk.max_ray_depth = option.as<double>(value, k);
    } else if (k == "g_thresh") {
      if (!value.is_none()) config.g_thresh = option.as<double>(value, k);
    } else if (k == "no_timings") {
      no_timings = option.as<bool>(value, k);
    } else if (k == "scene") {
      const planner::SceneConditions preset = planner::sceneNamed(option.as<std::string>(value, k));
      // A preset sets the base; ground_plane, no_return and crop change it, in any order.
      if (!options.contains("ground_plane")) config.scene.ground_plane = preset.ground_plane;
      if (!options.contains("no_return")) config.scene.no_return = preset.no_return;
      if (!options.contains("crop")) config.scene.crop = preset.crop;
    } else if (k == "ground_plane") {
      config.scene.ground_plane = option.as<bool>(value, k);
    } else if (k == "no_return") {
      config.scene.no_return = planner::noReturnFromName(option.as<std::string>(value, k));
    } else if (k == "crop") {
      if (value.is_none()) {
        config.scene.crop.reset();
      } else {
        const auto c = option.as<std::vector<double>>(value, k);
        if (c.size() != 6) throw InvalidArgument("crop: give (x0, x1, y0, y1, z0, z1) or None");
        const Eigen::Vector3d lo(c[0], c[2], c[4]), hi(c[1], c[3], c[5]);
        if (!(lo.array() < hi.array()).all()) throw InvalidArgument("crop: each minimum must be below its maximum");
        config.scene.crop = Eigen::AlignedBox3d(lo, hi);
      }
    } else if (k == "anytime") {
      const bool anytime = option.as<bool>(value, k);
      if (anytime && !config.anytime) config.anytime = planner::DecideOptions{};
      if (!anytime) config.anytime.reset();
    } else if (k == "epsilon" || k == "delta" || k == "budget_ms") {
      continue;  // read with "anytime", below
    } else if (k != "up") {
      option.refuse(k, "gamma, weighting, threads, visibility, max_ray_depth, g_thresh, no_timings, scene, "
                       "ground_plane, no_return, crop, up, anytime, epsilon, delta, budget_ms");
    }
  }
  for (const char* k : {"epsilon", "delta", "budget_ms"}) {
    if (!options.contains(k)) continue;
    if (!config.anytime) throw InvalidArgument(std::string(k) + " needs anytime=True");
    const py::object value = options[k];
    if (std::string(k) == "epsilon") config.anytime->epsilon = option.as<double>(value, k);
    if (std::string(k) == "delta") config.anytime->delta = option.as<double>(value, k);
    if (std::string(k) == "budget_ms" && !value.is_none()) config.anytime->max_ms = option.as<double>(value, k);
  }
}

}  // namespace

RunSettings runSettings(const std::string& owner, const py::handle& iterations, const py::handle& rays,
                        const py::handle& viewspace, const py::kwargs& options) {
  RunSettings s;
  s.config.max_iterations = KeywordOptions{owner}.as<std::size_t>(iterations, "iterations");
  s.rays = py::str(rays);  // "released", "full" or a stride
  s.config.rays = sensor::PixelSampling::fromName(s.rays);
  applyOptions(owner, s.config, s.threads, s.no_timings, options);
  std::tie(s.views, s.viewspace) = viewspaceOf(viewspace);
  // The up axis: up=..., else the scene preset's (planner::sceneUp; "bare", the default, keeps z).
  s.preset = options.contains("scene") ? options["scene"].cast<std::string>() : "bare";
  s.up = options.contains("up") ? optionValue<std::string>(options["up"], owner + ": up") : planner::sceneUp(s.preset);
  return s;
}

ModelArg modelOf(const py::handle& model, const std::string& up, const std::string& where) {
  std::shared_ptr<Mesh> mesh = meshOf(model, up, where);
  if (const std::optional<std::string> name = modelNameOrPath(model)) return {*name, mesh->source(), up, mesh};
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
  out["gamma"] = config.gamma;
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
  scene["visibility"] = config.snapshot.visibility == ig::Visibility::Released ? "released" : "paper";
  out["scene"] = scene;
  if (config.anytime) {
    py::dict anytime;
    anytime["epsilon"] = config.anytime->epsilon;
    anytime["delta"] = config.anytime->delta;
    anytime["budget_ms"] = config.anytime->max_ms ? py::cast(*config.anytime->max_ms) : py::none();
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
reconstruct(model, metric="pc", seed=0, iterations=20, rays="released", viewspace=None,
            callback=None, **options) -> dict

The paper's Algorithm 1 in simulation, as `nbv reconstruct`: start at a view drawn with the
seed, scan it with the ideal camera, integrate, score the views not visited yet, move to the
best, until `iterations` scans. model: a standard name or a mesh path (placed as load_mesh()
places it), or a Mesh (used as given, world frame). metric: a short name or a weighted sum
("0.5*pc+0.5*vg"). rays: "released", "released-shipped", "full" or a pixel
stride. viewspace: None or "dome48", a
view file's path, or (N, 4, 4) T_world_camera poses. callback(record) runs after each scan with
that iteration's dict and may return False to stop the run. options: gamma (0), weighting
("normalized" or "raw"), threads (None: every core), visibility ("paper"), max_ray_depth (1.5),
g_thresh (None), no_timings (False: times as measured), and the scene (docs/SEMANTICS.md, "Scene
conditions"): scene ("bare", "released" or "paper": a preset), ground_plane (bool), no_return
("drop" or "clear"), crop ((x0, x1, y0, y1, z0, z1) [m] or None), up ("z", "y" or "auto", for a
model named by name or path; default: the preset's, "auto" for "paper", else "z"), and anytime decisions (docs/SEMANTICS.md, "Anytime decisions"):
anytime (False), epsilon (0.01), delta (0.01), budget_ms (None).

Returns the fields of `nbv reconstruct --json`, in its order: model, metric, seed, viewspace,
weighting, rays, gamma, scene (name: the preset and what differs from it, then each condition),
anytime (None or epsilon, delta, budget_ms), stop, iterations (per scan: iteration, view,
coverage, entropy_bits, seconds_render, seconds_integrate, seconds_ig, ties, gap (the
decision's margin), rays, and gains: a (V,) float64 array of every candidate's gain, NaN for
visited views, empty after the last scan), max_entropy_bits, auc_coverage, auc_entropy.
save_run() writes it as that file.
)doc";
constexpr const char* kStartViewDoc = R"doc(
start_view(seed, view_count) -> int

The first view of a reconstruction with `seed` over `view_count` candidates: the draw
reconstruct() and `nbv reconstruct` make (docs/SEMANTICS.md, "The planner").
)doc";
constexpr const char* kSurfaceCoverageClassDoc = R"doc(
Eq. 15 scan by scan: the ground truth in a KD-tree, each scan marking the points it covers, as
reconstruct() scores its runs.
)doc";
constexpr const char* kSurfaceCoverageDoc = R"doc(
SurfaceCoverage(ground_truth, d_reg=0.005)

ground_truth: (N, 3) floating, world frame [m] (sample_surface()). d_reg: registration distance [m].
)doc";
constexpr const char* kAddScanDoc = R"doc(
add_scan(observed)

Marks the ground-truth points within d_reg of any point of one scan ((K, 3) floating, world
frame [m]).
)doc";
constexpr const char* kSurfaceCoverageDoc2 = R"doc(
surface_coverage(ground_truth, observed, d_reg=0.005) -> float

Eq. 15: the fraction of ground-truth points ((N, 3) floating, world frame [m]; sample_surface())
that have an observed point ((K, 3), all scans so far) within d_reg [m].
)doc";
constexpr const char* kMapEntropyBitsDoc = R"doc(
map_entropy_bits(map, centre, edge=1.28) -> float

Eq. 16: the sum of voxel entropies in bits over the cube of `edge` [m] centred on `centre`
((3,), world frame [m]); an unmeasured voxel counts 1 bit (docs/SEMANTICS.md, "Simulation and
evaluation").
)doc";

}  // namespace

namespace {

void bindReconstructionAndCoverage(py::module_& m) {
  m.def(
      "reconstruct",
      [](const py::object& model, const py::object& metric_arg, const py::object& seed_arg,
         const py::object& iterations, const py::object& rays, const py::object& viewspace, const py::object& callback,
         const py::kwargs& options) {
        const KeywordOptions option{"reconstruct"};
        const auto metric = option.as<std::string>(metric_arg, "metric");
        const auto seed = option.as<std::uint64_t>(seed_arg, "seed");
        const RunSettings settings = runSettings("reconstruct", iterations, rays, viewspace, options);
        planner::ReconstructionConfig config = settings.config;
        config.metrics = planner::parseMetricSum(metric);
        config.seed = seed;
        config.validate();
        const ModelArg chosen = modelOf(model, settings.up, "reconstruct: model");
        const std::shared_ptr<Mesh>& mesh = chosen.mesh;
        bool callback_failed = false;
        std::function<bool(const planner::IterationRecord&)> on_iteration;
        if (!callback.is_none()) {
          on_iteration = [&](const planner::IterationRecord& r) {
            py::gil_scoped_acquire locked;
            try {
              const py::object answer = callback(recordDict(r));
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
      py::arg("model"), py::arg("metric") = "pc", py::arg("seed") = 0, py::arg("iterations") = 20,
      py::arg("rays") = "released", py::arg("viewspace") = py::none(), py::arg("callback") = py::none(), kReconstructDoc);

  m.def(
      "start_view",
      [](const py::object& seed, const py::object& view_count) {
        const KeywordOptions option{"start_view"};
        return planner::startView(option.as<std::uint64_t>(seed, "seed"),
                                  option.as<std::size_t>(view_count, "view_count"));
      },
      py::arg("seed"), py::arg("view_count"), kStartViewDoc);

  py::class_<planner::SurfaceCoverage>(m, "SurfaceCoverage", kSurfaceCoverageClassDoc)
      .def(py::init([](const py::object& ground_truth, const py::object& d_reg) {
             const Rows<Eigen::Vector3f> truth = pointsFloat(ground_truth, "ground_truth");
             return planner::SurfaceCoverage({truth.rows.begin(), truth.rows.end()},
                                             optionValue<double>(d_reg, "SurfaceCoverage: d_reg"));
           }),
           py::arg("ground_truth"), py::arg("d_reg") = 0.005, kSurfaceCoverageDoc)
      .def(
          "add_scan",
          [](planner::SurfaceCoverage& coverage, const py::object& observed) {
            const Rows<Eigen::Vector3f> points = pointsFloat(observed, "observed");
            py::gil_scoped_release unlocked;
            coverage.addScan(points.rows);
          },
          py::arg("observed"), kAddScanDoc)
      .def_property_readonly("coverage", &planner::SurfaceCoverage::coverage, "Covered fraction in [0, 1].");
}

void bindScores(py::module_& m) {

  m.def(
      "surface_coverage",
      [](const py::object& ground_truth, const py::object& observed, const py::object& d_reg) {
        const Rows<Eigen::Vector3f> truth = pointsFloat(ground_truth, "ground_truth");
        const Rows<Eigen::Vector3f> seen = pointsFloat(observed, "observed");
        planner::SurfaceCoverage coverage({truth.rows.begin(), truth.rows.end()},
                                          optionValue<double>(d_reg, "surface_coverage: d_reg"));
        coverage.addScan(seen.rows);
        return coverage.coverage();
      },
      py::arg("ground_truth"), py::arg("observed"), py::arg("d_reg") = 0.005, kSurfaceCoverageDoc2);

  m.def(
      "map_entropy_bits",
      [](const py::object& map, const py::object& centre, const py::object& edge) {
        return planner::mapEntropyBits(mapOf(map, "map_entropy_bits"), vector3(centre, "centre"),
                                       optionValue<double>(edge, "map_entropy_bits: edge"));
      },
      py::arg("map"), py::arg("centre"), py::arg("edge") = 1.28, kMapEntropyBitsDoc);
}

}  // namespace

void bindPlanner(py::module_& m) {
  bindReconstructionAndCoverage(m);
  bindScores(m);
}

}  // namespace nbv::python
