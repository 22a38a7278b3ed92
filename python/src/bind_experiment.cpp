// The paper's experiment: many reconstructions side by side, its Table 1 and results.csv.
#include "arrays.hpp"
#include "bindings.hpp"
#include "runs.hpp"
#include "threads.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/experiment.hpp"
#include "nbv/planner/experiment_folder.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>
#include <type_traits>

namespace nbv::python {

namespace {

/// The most trials of an experiment, as `nbv experiment --trials` takes.
constexpr std::uint64_t kMaxTrials = std::uint64_t{1} << 20;

std::vector<std::string> commaList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) items.push_back(item);
  if (!text.empty() && text.back() == ',') items.emplace_back();
  return items;
}

/// results.csv holds a label or a metric as a field of its own: no comma, quote or line break.
void requireCsvField(const std::string& text, const std::string& where) {
  if (text.empty() || text.find_first_of(",\"\n\r") != std::string::npos) {
    throw InvalidArgument(where + " = '" + text + "' is empty or holds a comma, a quote or a line break, which "
                                  "results.csv cannot hold");
  }
}

/// One model of experiment()'s models: a name or a path (a str or an os.PathLike), or an
/// nbv.Mesh. \throws InvalidArgument naming `where` for anything else.
ModelGiven modelGiven(const py::handle& model, const std::string& where) {
  if (py::isinstance<Mesh>(model)) return model.cast<std::shared_ptr<Mesh>>();
  if (py::isinstance<py::str>(model) || py::hasattr(model, "__fspath__")) {
    const py::object path = py::module_::import("os").attr("fspath")(model);
    if (py::isinstance<py::str>(path)) return path.cast<std::string>();
  }
  throw InvalidArgument(where + " = " + shortRepr(model) + " is not a model name, a mesh file or an nbv.Mesh");
}

/// The models of experiment(): their labels (as reconstruct() names a model, or a dict's keys)
/// and meshes, each label once.
struct Models {
  std::vector<std::string> labels;
  std::vector<std::string> records;  ///< what a sweep record names: a standard name, an absolute path, "mesh"
  std::vector<sensor::TriangleMesh> meshes;
};

Models modelsOf(const py::handle& models, const std::string& up) {
  std::vector<std::tuple<std::string, std::string, py::object>> given;  // (where, label or "", model)
  if (py::isinstance<py::str>(models)) {
    const std::string text = models.cast<std::string>();
    std::vector<std::string> names;
    if (text == "all") {
      for (const sensor::StandardModel& model : sensor::standardModels()) names.push_back(model.name);
    } else {
      names = commaList(text);
    }
    for (const std::string& name : names) given.emplace_back("experiment: models '" + name + "'", "", py::str(name));
  } else if (py::isinstance<py::dict>(models)) {
    for (const auto& [key, value] : models.cast<py::dict>()) {
      const auto label = optionValue<std::string>(key, "experiment: a key of models");
      given.emplace_back("experiment: models['" + label + "']", label, py::reinterpret_borrow<py::object>(value));
    }
  } else if (py::isinstance<Mesh>(models) || py::hasattr(models, "__fspath__")) {
    given.emplace_back("experiment: models", "", py::reinterpret_borrow<py::object>(models));
  } else if (py::isinstance<py::sequence>(models)) {
    const auto items = models.cast<py::sequence>();
    for (std::size_t i = 0; i < items.size(); ++i) {
      given.emplace_back("experiment: models[" + std::to_string(i) + "]", "", py::object(items[i]));
    }
  } else {
    throw InvalidArgument("experiment: models = " + shortRepr(models) +
                          " is not a model name, a mesh file, an nbv.Mesh, \"all\", or a sequence or dict of them");
  }
  if (given.empty()) throw InvalidArgument("experiment: models holds no model");
  Models out;
  for (const auto& [where, label, model] : given) {
    const ModelArg chosen = modelOf(modelGiven(model, where), up);
    const std::shared_ptr<Mesh>& mesh = chosen.mesh;
    const std::string named = label.empty() ? planner::modelLabel(chosen.given) : label;
    requireCsvField(named, where + "'s label");
    for (std::size_t k = 0; k < out.labels.size(); ++k) {
      if (out.labels[k] == named) {
        throw InvalidArgument(where + " is labelled '" + named + "', as an earlier model is (an nbv.Mesh is labelled " +
                              "\"mesh\"): give models as a dict {label: model}");
      }
    }
    out.labels.push_back(named);
    out.records.push_back(chosen.record);
    out.meshes.push_back(mesh->mesh());
  }
  return out;
}

/// The metrics of experiment(): "all" (each metric alone), a comma-separated str, or a sequence
/// of str and callables; each a metric, a weighted sum or "oracle", parsed here so that a bad
/// one stops before any run, or a planner of one's own, labelled by its __name__ and put in
/// `own` (borrowed: experiment()'s arguments hold it).
std::vector<std::string> metricsOf(const py::handle& metrics, std::map<std::string, planner::CandidateScorer>& own) {
  std::vector<std::string> list;
  if (!py::isinstance<py::str>(metrics) && py::isinstance<py::sequence>(metrics)) {
    for (const py::handle item : metrics) {
      if (!PyCallable_Check(item.ptr())) continue;
      const std::string label =
          py::hasattr(item, "__name__") ? py::str(item.attr("__name__")).cast<std::string>() : std::string("custom");
      if (own.count(label) != 0) throw InvalidArgument("experiment: metric '" + label + "' is given twice");
      own[label] = pythonScorer(item.ptr());
    }
  }
  if (!own.empty()) {
    for (const py::handle item : metrics) {
      list.push_back(PyCallable_Check(item.ptr()) ? py::str(item.attr("__name__")).cast<std::string>()
                                                  : optionValue<std::string>(item, "experiment: metrics"));
    }
  } else if (py::isinstance<py::str>(metrics)) {
    const std::string text = metrics.cast<std::string>();
    if (text == "all") {
      for (ig::Metric m : kernels::kAllMetrics) list.push_back(kernels::metricName(m));
    } else {
      list = commaList(text);
    }
  } else {
    list = optionValue<std::vector<std::string>>(metrics, "experiment: metrics");
  }
  if (list.empty()) throw InvalidArgument("experiment: metrics holds no metric");
  std::set<std::string> seen;
  for (const std::string& metric : list) {
    requireCsvField(metric, "experiment: metric");
    planner::ReconstructionConfig checked;
    if (own.count(metric) == 0) planner::setPlanner(checked, metric);
    if (!seen.insert(metric).second) throw InvalidArgument("experiment: metric '" + metric + "' is given twice");
  }
  return list;
}

/// The seeds of experiment()'s trials: a count t (seeds 0 .. t - 1, as `nbv experiment --trials`)
/// or a sequence of distinct seeds (to add trials to an experiment, or to repeat some).
std::vector<std::uint64_t> seedsOf(const py::handle& trials) {
  std::vector<std::uint64_t> seeds;
  if (py::isinstance<py::sequence>(trials) && !py::isinstance<py::str>(trials)) {
    seeds = optionValue<std::vector<std::uint64_t>>(trials, "experiment: trials");
    if (seeds.empty() || seeds.size() > kMaxTrials) {
      throw InvalidArgument("experiment: trials holds " + std::to_string(seeds.size()) + " seeds, not 1 to " +
                            std::to_string(kMaxTrials));
    }
    if (std::set<std::uint64_t>(seeds.begin(), seeds.end()).size() != seeds.size()) {
      throw InvalidArgument("experiment: trials names a seed twice");
    }
    return seeds;
  }
  const auto count = optionValue<std::uint64_t>(trials, "experiment: trials");
  if (count < 1 || count > kMaxTrials) {
    throw InvalidArgument("experiment: trials = " + std::to_string(count) + " is not in [1, " +
                          std::to_string(kMaxTrials) + "]");
  }
  for (std::uint64_t seed = 0; seed < count; ++seed) seeds.push_back(seed);
  return seeds;
}

/// `dict[key]`, or an error naming `where` and the key.
py::object field(const py::dict& dict, const char* key, const std::string& where) {
  if (!dict.contains(key)) throw InvalidArgument(where + " has no '" + key + "' (not a run of reconstruct() or experiment())");
  return dict[key];
}

/// A field of an iteration's dict as a T, named `where` in errors; with `gap`, None is none (NaN).
template <class T>
T dictField(const py::handle& value, const std::string& where, bool gap) {
  if constexpr (std::is_floating_point_v<T>) {
    if (gap) return optionValue<std::optional<T>>(value, where).value_or(std::numeric_limits<T>::quiet_NaN());
  }
  return optionValue<T>(value, where);
}

/// The rows of results.csv of `runs` (run dicts of reconstruct(), experiment() or load_run()),
/// in the canonical order. \throws InvalidArgument naming the run and field at fault.
std::vector<planner::ExperimentRow> rowsOfRuns(const py::handle& runs, const std::string& owner) {
  if (py::isinstance<py::dict>(runs) || py::isinstance<py::str>(runs) || !py::isinstance<py::sequence>(runs)) {
    throw InvalidArgument(owner + ": runs = " + shortRepr(runs) + " is not a sequence of runs (the dicts reconstruct() "
                                  "and experiment() return)");
  }
  std::vector<planner::ExperimentRow> rows;
  std::set<std::tuple<std::string, std::string, std::uint64_t>> seen;
  const auto list = runs.cast<py::sequence>();
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = owner + ": runs[" + std::to_string(i) + "]";
    const py::object item = list[i];
    if (!py::isinstance<py::dict>(item)) {
      throw InvalidArgument(where + " is a " + std::string(py::str(py::type::of(item).attr("__name__"))) +
                            ", not the dict of a run");
    }
    const auto run = item.cast<py::dict>();
    const auto at = [&](const char* key) { return where + "['" + key + "']"; };
    planner::ExperimentRow run_row;  // the run's keys and max_entropy_bits, each iteration's row starts from it
    run_row.model = optionValue<std::string>(field(run, "model", where), at("model"));
    run_row.metric = optionValue<std::string>(field(run, "metric", where), at("metric"));
    run_row.trial = optionValue<std::uint64_t>(field(run, "seed", where), at("seed"));
    run_row.max_entropy_bits = optionValue<double>(field(run, "max_entropy_bits", where), at("max_entropy_bits"));
    requireCsvField(run_row.model, at("model"));
    requireCsvField(run_row.metric, at("metric"));
    if (!(run_row.max_entropy_bits > 0.0) || !std::isfinite(run_row.max_entropy_bits)) {
      throw InvalidArgument(at("max_entropy_bits") + " = " + std::to_string(run_row.max_entropy_bits) +
                            " is not a positive number");
    }
    if (!seen.insert({run_row.model, run_row.metric, run_row.trial}).second) {
      throw InvalidArgument(where + " repeats model '" + run_row.model + "', metric '" + run_row.metric + "' and seed " +
                            std::to_string(run_row.trial) + " of an earlier run");
    }
    const py::object iterations = field(run, "iterations", where);
    if (!py::isinstance<py::sequence>(iterations) || py::isinstance<py::str>(iterations)) {
      throw InvalidArgument(at("iterations") + " = " + shortRepr(iterations) + " is not a sequence of iterations");
    }
    const auto records = iterations.cast<py::sequence>();
    for (std::size_t j = 0; j < records.size(); ++j) {
      const std::string it_where = at("iterations") + "[" + std::to_string(j) + "]";
      const py::object it_item = records[j];
      if (!py::isinstance<py::dict>(it_item)) throw InvalidArgument(it_where + " is not the dict of an iteration");
      const auto it = it_item.cast<py::dict>();
      const auto value = [&](const char* key) { return field(it, key, it_where); };
      const auto name = [&](const char* key) { return it_where + "['" + key + "']"; };
      // Every field of the record (a Gap's None is none, NaN, as JSON writes it); a field added
      // after the first version may be missing (a run of an earlier version's file).
      std::size_t index = 0;
      planner::ExperimentRow row = run_row;
#define NBV_ROW_FROM_DICT(field, type, kind, help)                                                       \
  if (index++ < planner::kFirstIterationFields || it.contains(#field)) {                                 \
    NBV_ITERATION_IF_RECORD(kind, row.field = dictField<type>(value(#field), name(#field), NBV_ITERATION_IS_GAP(kind));) \
  }
      NBV_ITERATION_FIELDS(NBV_ROW_FROM_DICT)
#undef NBV_ROW_FROM_DICT
      if (row.iteration != j + 1) {
        throw InvalidArgument(name("iteration") + " = " + std::to_string(row.iteration) + ", not " + std::to_string(j + 1));
      }
      // A decision followed where the iteration scored the candidates: then its time counts.
      if (py::len(value("gains")) == 0) row.seconds_ig = 0.0;
      rows.push_back(row);
    }
  }
  planner::sortRows(rows);
  return rows;
}

/// The shard of experiment(): None (the whole sweep), "K/N" or (K, N) with 1 <= K <= N.
std::pair<std::size_t, std::size_t> shardOf(const py::handle& shard) {
  if (shard.is_none()) return {1, 1};
  std::size_t k = 0, n = 0;
  if (py::isinstance<py::str>(shard)) {
    char tail = 0;
    if (std::sscanf(shard.cast<std::string>().c_str(), "%zu/%zu%c", &k, &n, &tail) != 2) k = 0;
  } else {
    const auto pair = optionValue<std::vector<std::uint64_t>>(shard, "experiment: shard");
    if (pair.size() == 2) std::tie(k, n) = std::pair<std::size_t, std::size_t>(pair[0], pair[1]);
  }
  if (k < 1 || k > n) throw InvalidArgument("experiment: shard = " + shortRepr(shard) + " is not \"K/N\" or (K, N) with 1 <= K <= N");
  return {k, n};
}

/// The sweep experiment() runs: the record a folder keeps (planner/experiment_folder.hpp).
planner::Sweep sweepOf(const Models& models, std::vector<std::string> metrics, std::vector<std::uint64_t> seeds,
                       const RunSettings& settings, const py::handle& shard) {
  planner::Sweep s;
  s.models = models.records;
  s.labels = models.labels;
  s.metrics = std::move(metrics);
  s.seeds = std::move(seeds);
  s.viewspace = settings.viewspace;
  s.rays = settings.rays;
  s.scene = planner::sceneLabel(settings.preset, settings.config.scene, settings.up);
  s.up = settings.up;
  s.config = settings.config;
  s.timings = !settings.no_timings;
  std::tie(s.shard, s.shards) = shardOf(shard);
  s.version = NBV_VERSION;
  return s;
}

/// `text` written beside `path` and renamed into place.
void writeText(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path temporary = path.string() + ".part";
  {
    std::ofstream file(temporary);
    file << text;
    if (!file.flush()) throw FileError(path, "cannot write");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw FileError(path, "cannot write: " + ec.message());
}

}  // namespace

namespace {

constexpr const char* kExperimentDoc = R"doc(
The paper's experiment, as `nbv experiment`: every (model, metric, trial) reconstruction, run
side by side on the threads (a model's runs share its scene, ground truth and scans). Each run
is the dict reconstruct(model, metric, seed, iterations, rays, viewspace, **options) returns,
with the same numbers (times aside), listed by model, metric and seed in the order given.

models: a standard name, a mesh path, an nbv.Mesh, "all" (the 11 standard models), a
comma-separated str, a sequence of these, or a dict {label: model}; a run's "model" is its
label, as the command line labels it: a standard name, a mesh file's stem ("ring" for
"/data/ring.obj"), "mesh" for an nbv.Mesh, or the dict's key. metrics: "all"
(every metric alone), a comma-separated str or a sequence of metrics and weighted sums
("0.5*pc+0.5*vg"), "oracle" among them too, and callables: planners of one's own (as
reconstruct()'s metric=callable; labelled by their __name__; called from one run at a time per
thread, with the GIL). trials: a count t (seeds 0 .. t - 1, as the command line's trials) or a
sequence of distinct seeds (range(20, 40) adds twenty trials to an experiment of twenty).
options: those of reconstruct(); threads (None: every core) are the experiment's, shared by
its runs.

callback(run) gets each run as it ends (in the order they end) and may return False: then no
further run starts, and the runs that ended are returned. An error in a run or in the
callback, or Ctrl-C, starts no further run and is raised once the runs in flight end.
table1() and save_experiment() make the paper's Table 1 and results.csv of the runs.

out: a folder that keeps the sweep as `nbv experiment --out` does (sweep.json, and each run in
runs/ as it ends, on disk before the next starts): called again with the same sweep, it runs
only the runs the folder lacks and returns them all, the same as one uninterrupted call; a
folder of another sweep raises nbv.FileError naming what differs. Once every run is there it
gets results.csv and table.md; `nbv experiment --merge` takes it as it takes a shard's.
shard: "K/N" or (K, N), only the K-th of N disjoint slices of the runs, as --shard.
)doc";
constexpr const char* kTable1Doc = R"doc(
The paper's Table 1 of `runs` (the dicts of experiment(), reconstruct() or load_run(), each
(model, metric, seed) once) as Markdown, as `nbv experiment` writes table.md: per model and
metric, the coverage after 2, 4, 6 and 10 scans, the final coverage, coverage AUC and entropy
AUC as mean ± standard deviation over the seeds, and the mean seconds per decision.
)doc";

}  // namespace

void bindExperiment(py::module_& m) {
  m.def(
      "experiment",
      [](const py::handle& models_arg, const py::handle& metrics_arg, const py::handle& trials_arg,
         std::size_t iterations, const RaysGiven& rays, const py::handle& viewspace,
         const std::optional<py::function>& callback, const std::optional<std::filesystem::path>& out,
         const py::handle& shard, const py::dict& options) {
        const RunSettings settings = runSettings(iterations, rays, viewspace, options);
        checkThreads(settings.threads);  // before the models load
        const Models models = modelsOf(models_arg, settings.up);
        std::map<std::string, planner::CandidateScorer> own;  // planners of one's own, by label
        const planner::Sweep sweep = sweepOf(models, metricsOf(metrics_arg, own), seedsOf(trials_arg), settings, shard);
        // With a folder: the runs it keeps count as run, each new one is kept as it ends.
        std::optional<planner::ExperimentFolder> folder;
        std::map<std::size_t, planner::KeptRun> kept;
        if (out) {
          folder.emplace(*out, sweep, true);
          kept = folder->kept();
        }
        const std::vector<planner::ExperimentRun> all = sweep.allRuns();
        std::vector<std::size_t> todo;  // indices into `all`
        for (const std::size_t i : sweep.shardRuns()) {
          if (kept.count(i) == 0) todo.push_back(i);
        }
        std::vector<planner::ExperimentRun> runs;
        for (const std::size_t i : todo) runs.push_back(all[i]);
        // Each finished run becomes its dict at once (the callback sees it), in its slot: any
        // thread count returns the same list.
        std::map<std::size_t, py::object> finished;
        for (auto& [index, run] : kept) {
          finished[index] = runDict(models.labels[run.run.model], settings.up, run.run.metric, run.run.trial, settings,
                                    run.result);
        }
        const auto done = [&](std::size_t i, planner::ReconstructionResult&& result) {
          if (folder) {
            if (settings.no_timings) {
              for (planner::IterationRecord& r : result.iterations) r.seconds_render = r.seconds_integrate = r.seconds_ig = 0.0;
            }
            folder->keep(todo[i], result);  // on disk before it counts
          }
          py::gil_scoped_acquire locked;
          const planner::ExperimentRun& run = runs[i];
          py::dict dict = runDict(models.labels[run.model], settings.up, run.metric, run.trial, settings, result);
          finished[todo[i]] = dict;
          if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C, seen from the main thread
          if (!callback) return true;
          const py::object answer = (*callback)(dict);
          return answer.is_none() || optionValue<bool>(answer, "experiment: the callback's answer");
        };
        const int threads = settings.threads.value_or(0);  // 0: every core
        runReleased(std::nullopt, [&] {
          planner::runExperiment(models.meshes, settings.views, settings.config, runs, threads, done, {}, own);
        });
        py::list list;
        for (const auto& [index, run] : finished) list.append(run);
        if (folder && finished.size() == sweep.shardRuns().size()) {
          const std::vector<planner::ExperimentRow> rows = rowsOfRuns(list, "experiment");
          writeText(folder->dir() / "results.csv", planner::resultsCsv(rows));
          writeText(folder->dir() / "table.md", planner::table1Markdown(rows));
        }
        return list;
      },
      kExperimentDoc);

  m.def(
      "table1",
      [](const py::handle& runs) { return planner::table1Markdown(rowsOfRuns(runs, "table1")); }, kTable1Doc);

  m.def(
      "_results_csv", [](const py::handle& runs) { return planner::resultsCsv(rowsOfRuns(runs, "save_experiment")); },
      "The text of results.csv of `runs`, as `nbv experiment` writes it (save_experiment()).");
}

}  // namespace nbv::python
