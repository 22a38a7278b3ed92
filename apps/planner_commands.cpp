#include "planner_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"
#include "report_html.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/experiment.hpp"
#include "nbv/planner/reconstruction.hpp"

#include <CLI/CLI.hpp>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;

/// The anytime flags of reconstruct and experiment (SEMANTICS.md "Anytime decisions").
struct AnytimeFlags {
  bool on = false;
  double epsilon = 0.01;
  double delta = 0.01;
  std::optional<double> budget_ms;
};

struct ReconstructCommand {
  std::string model;
  std::string metric = "pc";
  std::string weighting = "normalized";
  std::uint64_t seed = 0;
  std::size_t iterations = 20;
  double gamma = 0.0;
  std::string rays = "released";
  std::string viewspace = "dome48";
  int threads = 0;
  std::string json;
  std::string html;
  bool no_timings = false;
  SceneFlags scene;
  AnytimeFlags anytime;
};

constexpr const char* kNoTimingsHelp =
    "Write every time as 0, so that the same inputs give byte-identical files at any thread count";

/// With --no-timings, the records keep their fields and lose their clock readings.
void dropTimings(planner::IterationRecord& r) { r.seconds_render = r.seconds_integrate = r.seconds_ig = 0.0; }

/// A number for JSON: the shortest text that reads back to it, null for NaN.
std::string number(double value) { return std::isnan(value) ? "null" : shortestNumber(value); }

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

void addAnytimeOptions(CLI::App& command, AnytimeFlags& flags) {
  command.add_flag("--anytime", flags.on, "Decide each next view from samples of the candidates' rays "
                                          "(docs/SEMANTICS.md, \"Anytime decisions\") instead of every ray");
  command.add_option("--epsilon", flags.epsilon, "With --anytime: stop once every candidate left is within this share "
                                                 "of the best")
      ->check(numberIn(0.0, 0.999999))
      ->capture_default_str();
  command.add_option("--delta", flags.delta, "With --anytime: the chance that an interval misses, at most")
      ->check(numberIn(1e-12, 0.999999))
      ->capture_default_str();
  command.add_option("--budget-ms", flags.budget_ms, "With --anytime: stop a decision after this many milliseconds")
      ->check(positiveNumber());
}

std::optional<planner::DecideOptions> anytimeOf(const AnytimeFlags& flags) {
  if (!flags.on) {
    if (flags.budget_ms) throw InvalidArgument("--budget-ms needs --anytime");
    return std::nullopt;
  }
  planner::DecideOptions options;
  options.epsilon = flags.epsilon;
  options.delta = flags.delta;
  options.max_ms = flags.budget_ms;
  return options;
}

std::string anytimeJson(const AnytimeFlags& flags) {
  if (!flags.on) return "null";
  return "{\"epsilon\": " + number(flags.epsilon) + ", \"delta\": " + number(flags.delta) +
         ", \"budget_ms\": " + (flags.budget_ms ? number(*flags.budget_ms) : std::string("null")) + "}";
}

/// The scene of a run as a JSON object: its label and every condition.
std::string sceneJson(const SceneFlags& flags) {
  const planner::SceneConditions scene = sceneOf(flags);
  std::string crop = "null";
  if (scene.crop) {
    crop = "[";
    for (int a = 0; a < 3; ++a) {
      crop += (a ? ", " : "") + number(scene.crop->min()[a]) + ", " + number(scene.crop->max()[a]);
    }
    crop += "]";
  }
  return "{\"name\": " + quoted(sceneLabel(flags)) + ", \"ground_plane\": " + (scene.ground_plane ? "true" : "false") +
         ", \"no_return\": " + quoted(scene.no_return == planner::NoReturn::Clear ? "clear" : "drop") +
         ", \"crop\": " + crop + ", \"up\": " + quoted(upOf(flags)) + ", \"visibility\": " + quoted(flags.visibility) + "}";
}

/// The run as JSON: model and viewspace named so that `nbv report` finds them from any folder
/// (standard names, or absolute paths).
void writeJson(const fs::path& path, const ReconstructCommand& c, const planner::ReconstructionResult& r) {
  std::ofstream out(path);
  if (!out) throw nbv::FileError(path, "cannot write");
  out << "{\n  \"model\": " << quoted(portableName(c.model, isStandardModel(c.model))) << ",\n  \"metric\": " << quoted(c.metric)
      << ",\n  \"seed\": " << c.seed << ",\n  \"viewspace\": " << quoted(portableName(c.viewspace, c.viewspace == "dome48"))
      << ",\n  \"weighting\": " << quoted(c.weighting) << ",\n  \"rays\": " << quoted(c.rays)
      << ",\n  \"gamma\": " << number(c.gamma) << ",\n  \"scene\": " << sceneJson(c.scene)
      << ",\n  \"anytime\": " << anytimeJson(c.anytime)
      << ",\n  \"stop\": " << quoted(planner::stopReasonName(r.stop)) << ",\n  \"iterations\": [\n";
  for (std::size_t i = 0; i < r.iterations.size(); ++i) {
    const planner::IterationRecord& it = r.iterations[i];
    out << "    {\"iteration\": " << it.iteration << ", \"view\": " << it.view << ", \"coverage\": " << number(it.coverage)
        << ", \"entropy_bits\": " << number(it.entropy_bits) << ", \"seconds_render\": " << number(it.seconds_render)
        << ", \"seconds_integrate\": " << number(it.seconds_integrate) << ", \"seconds_ig\": " << number(it.seconds_ig)
        << ", \"ties\": " << it.ties << ", \"gap\": " << number(it.gap) << ", \"rays\": " << it.rays
        << ", \"gains\": [";
    for (std::size_t v = 0; v < it.gains.size(); ++v) out << (v == 0 ? "" : ", ") << number(it.gains[v]);
    out << "]}" << (i + 1 < r.iterations.size() ? "," : "") << "\n";
  }
  out << "  ],\n  \"max_entropy_bits\": " << number(r.max_entropy_bits) << ",\n  \"auc_coverage\": "
      << number(r.auc_coverage) << ",\n  \"auc_entropy\": " << number(r.auc_entropy) << "\n}\n";
  if (!out.flush()) throw nbv::FileError(path, "write failed");
}

void runReconstruct(const ReconstructCommand& c) {
  if (!c.json.empty()) checkWritable(c.json);
  if (!c.html.empty()) {
    checkWritable(c.html);
    requireThreeJs();
  }
  planner::ReconstructionConfig config;
  config.metrics = planner::parseMetricSum(c.metric);
  config.weighting = planner::weightingFromName(c.weighting);
  config.seed = c.seed;
  config.max_iterations = c.iterations;
  config.gamma = c.gamma;
  config.rays = sensor::PixelSampling::fromName(c.rays);
  config.scene = sceneOf(c.scene);
  config.evaluation.visibility = c.scene.visibility == "released" ? grid::Visibility::Released : grid::Visibility::Paper;
  config.anytime = anytimeOf(c.anytime);
  config.validate();
  const std::vector<planner::View> views = viewspace(c.viewspace);
  const sensor::TriangleMesh mesh = placedModel(c.model, upOf(c.scene));

  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  std::printf("%s, metric %s, seed %llu, %zu views, %s rays, scene %s, %d thread%s\n", c.model.c_str(),
              c.metric.c_str(), static_cast<unsigned long long>(c.seed), views.size(), c.rays.c_str(),
              sceneLabel(c.scene).c_str(), threads, threads == 1 ? "" : "s");
  std::printf("%4s %5s %9s %13s %9s %9s %9s %5s\n", "iter", "view", "coverage", "entropy_bits", "render_s",
              "integr_s", "nbv_s", "ties");
  std::fflush(stdout);
  planner::ReconstructionResult result;
  // One object for the run and, with --html, the page's scans (each view rendered once).
  std::unique_ptr<planner::SimulatedObject> object;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    object = std::make_unique<planner::SimulatedObject>(mesh, views, config);
    result = planner::reconstruct(*object, config, [](const planner::IterationRecord& r) {
      std::printf("%4zu %5zu %9.4f %13.0f %9.3f %9.3f %9.3f %5zu\n", r.iteration, r.view, r.coverage, r.entropy_bits,
                  r.seconds_render, r.seconds_integrate, r.seconds_ig, r.ties);
      std::fflush(stdout);
      return true;
    });
  });
  double decisions = 0.0, seconds_ig = 0.0, seconds_all = 0.0;
  for (const planner::IterationRecord& r : result.iterations) {
    if (!r.gains.empty()) {
      decisions += 1.0;
      seconds_ig += r.seconds_ig;
    }
    seconds_all += r.seconds_render + r.seconds_integrate + r.seconds_ig;
  }
  std::printf("stopped: %s; coverage AUC %.4f, entropy AUC %.4f; %.3f s per NBV decision, %.2f s in all\n",
              planner::stopReasonName(result.stop), result.auc_coverage, result.auc_entropy,
              decisions > 0 ? seconds_ig / decisions : 0.0, seconds_all);
  if (c.no_timings) std::for_each(result.iterations.begin(), result.iterations.end(), dropTimings);
  if (!c.json.empty()) {
    writeAtomically(c.json, [&](const fs::path& temporary) { writeJson(temporary, c, result); });
    std::printf("wrote %s\n", c.json.c_str());
  }
  if (!c.html.empty()) {
    Report report;
    report.title = runTitle(c.model, c.metric, c.seed, sceneLabel(c.scene));
    report.views = views;
    report.runs.push_back({runLabel(c.metric, c.seed), result.iterations, result.max_entropy_bits});
    addScans(report, *object);
    writeAtomically(c.html, [&](const fs::path& temporary) { writeReportHtml(temporary, report); });
    std::printf("wrote %s\n", c.html.c_str());
  }
}

struct ExperimentCommand {
  std::string models = "bunny";
  std::string metrics = "all";
  std::string weighting = "normalized";
  unsigned trials = 20;
  std::size_t iterations = 20;
  std::string rays = "released";
  std::string viewspace = "dome48";
  int threads = 0;
  std::string shard;  // "K/N"
  std::vector<std::string> merge;
  std::string out;
  bool force = false;
  bool no_timings = false;
  SceneFlags scene;
  AnytimeFlags anytime;
};

/// "K/N" with 1 <= K <= N.
std::pair<std::size_t, std::size_t> parseShard(const std::string& text) {
  unsigned long k = 0, n = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lu/%lu%c", &k, &n, &tail) != 2 || k < 1 || k > n) {
    throw InvalidArgument("--shard '" + text + "' is not K/N with 1 <= K <= N");
  }
  return {k, n};
}

/// An experiment writes into a folder of its own: an existing one must be empty, unless
/// --force lets the run replace what it writes there.
void checkOutputFolder(const ExperimentCommand& c) {
  if (c.out.empty()) throw InvalidArgument("--out names no folder");
  std::error_code ec;
  if (!fs::exists(c.out, ec)) {
    // Made now, so that a folder that cannot be made stops the experiment before any run.
    if (!fs::create_directories(c.out, ec) && ec) throw FileError(c.out, "cannot make the --out folder: " + ec.message());
    return;
  }
  if (!fs::is_directory(c.out, ec)) throw FileError(c.out, "--out is a file, not a folder");
  if (!fs::is_empty(c.out, ec) && !c.force) {
    throw FileError(c.out, "the --out folder is not empty (give --force to write into it anyway)");
  }
  checkWritable(fs::path(c.out) / "results.csv");
}

/// The experiment's front page: Table 1 (`table1`, table.md's text, as HTML), then per model its plot and a link
/// to its report page where the run wrote one (a merge links the pages found in `out`).
void writeExperimentIndex(const fs::path& path, const fs::path& out, const std::vector<planner::ExperimentRow>& rows,
                          const std::string& table1) {
  std::ofstream html(path);
  if (!html) throw FileError(path, "cannot write");
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>nbv experiment</title>\n<style>body{font:14px "
          "sans-serif;margin:12px}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;font-size:12px}"
          "img{max-width:900px;display:block}</style></head><body>\n<h1>nbv experiment</h1>\n"
          "<p>Each model's plot, and its report page: the first trial of every metric, drawn in 3D.</p>\n";
  std::vector<std::string> labels;
  for (const planner::ExperimentRow& r : rows) {
    if (std::find(labels.begin(), labels.end(), r.model) == labels.end()) labels.push_back(r.model);
  }
  for (const std::string& label : labels) {
    html << "<h2>" << label << "</h2>\n";
    if (fs::exists(out / (label + ".html"))) html << "<p><a href=\"" << label << ".html\">" << label << ": report</a></p>\n";
    if (fs::exists(out / (label + ".png"))) html << "<img src=\"" << label << ".png\" alt=\"" << label << "\">\n";
  }
  html << "<h2>Table 1</h2>\n<table>\n";
  std::istringstream table(table1);
  for (std::string line; std::getline(table, line);) {
    if (line.rfind("|---", 0) == 0 || line.empty() || line[0] != '|') continue;
    html << "<tr>";
    std::istringstream cells(line.substr(1));
    for (std::string cell; std::getline(cells, cell, '|');) html << "<td>" << cell << "</td>";
    html << "</tr>\n";
  }
  html << "</table>\n</body></html>\n";
  if (!html.flush()) throw FileError(path, "write failed");
}

/// results.csv, table.md and the plots of `rows` in `out`.
void writeExperiment(const fs::path& out, std::vector<planner::ExperimentRow> rows) {
  planner::sortRows(rows);
  fs::create_directories(out);
  const std::string table1 = planner::table1Markdown(rows);
  const auto write_text = [](const fs::path& path, const std::string& text) {
    writeAtomically(path, [&](const fs::path& temporary) {
      std::ofstream file(temporary);
      file << text;
      if (!file.flush()) throw FileError(temporary, "write failed");
    });
  };
  write_text(out / "results.csv", planner::resultsCsv(rows));
  write_text(out / "table.md", table1);
  std::printf("wrote %s and %s (%zu rows)\n", (out / "results.csv").c_str(), (out / "table.md").c_str(), rows.size());
  // The plots, one per model label, by nbv.plots (matplotlib).
  std::fputs(runPlots({"experiment", (out / "results.csv").string(), "--out-dir", out.string()}).c_str(), stdout);
  writeAtomically(out / "index.html", [&](const fs::path& temporary) { writeExperimentIndex(temporary, out, rows, table1); });
  std::printf("wrote %s\n", (out / "index.html").c_str());
}

std::vector<planner::ExperimentRow> mergedRows(const std::vector<std::string>& folders) {
  std::vector<planner::ExperimentRow> rows;
  std::set<std::tuple<std::string, std::string, std::uint64_t, unsigned>> seen;
  for (const std::string& dir : folders) {
    for (const planner::ExperimentRow& r : planner::readResultsCsv(fs::path(dir) / "results.csv")) {
      if (!seen.insert({r.model, r.metric, r.trial, r.iteration}).second) {
        throw InvalidArgument(dir + "/results.csv: " + r.model + " " + r.metric + " trial " + std::to_string(r.trial) +
                              " iteration " + std::to_string(r.iteration) + " is also in another shard");
      }
      rows.push_back(r);
    }
  }
  return rows;
}

/// The models of --models; "all" is every standard model.
std::vector<std::string> experimentModels(const std::string& text) {
  if (text != "all") return splitList(text);
  std::vector<std::string> models;
  for (const sensor::StandardModel& model : sensor::standardModels()) models.push_back(model.name);
  return models;
}

/// The utilities of --metrics, each parsed so that a bad one stops the experiment before any
/// work; "all" is every metric alone.
std::vector<std::string> experimentMetrics(const std::string& text) {
  std::vector<std::string> metrics;
  if (text == "all") {
    for (grid::Metric m : kernels::kAllMetrics) metrics.push_back(kernels::metricName(m));
  } else {
    metrics = splitList(text);
  }
  for (const std::string& m : metrics) planner::parseMetricSum(m);
  return metrics;
}

/// "runs 3/8, ETA ..." on standard error, from any thread: one line at a time.
class RunProgress {
 public:
  explicit RunProgress(std::size_t total) : total_(total) { showProgress(0, total_, 0.0); }
  void oneDone() {
    const std::size_t finished = ++done_;
    const std::lock_guard<std::mutex> lock(mutex_);
    showProgress(finished, total_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  }

 private:
  std::size_t total_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
};

void runExperiment(const ExperimentCommand& c) {
  checkOutputFolder(c);
  if (!c.merge.empty()) {  // combine the results.csv of shards
    writeExperiment(c.out, mergedRows(c.merge));
    return;
  }
  planner::ReconstructionConfig base;
  base.max_iterations = c.iterations;
  base.rays = sensor::PixelSampling::fromName(c.rays);
  base.weighting = planner::weightingFromName(c.weighting);
  base.scene = sceneOf(c.scene);
  base.evaluation.visibility = c.scene.visibility == "released" ? grid::Visibility::Released : grid::Visibility::Paper;
  base.anytime = anytimeOf(c.anytime);
  const std::vector<planner::View> views = viewspace(c.viewspace);
  const std::vector<std::string> models = experimentModels(c.models);
  const std::vector<std::string> metrics = experimentMetrics(c.metrics);
  if (models.empty() || metrics.empty() || c.trials == 0) throw InvalidArgument("the experiment has no run");
  const auto [shard, shards] = c.shard.empty() ? std::pair<std::size_t, std::size_t>{1, 1} : parseShard(c.shard);
  const std::vector<std::string> labels = modelLabels(models);  // a mesh path by its file's stem
  const std::vector<planner::ExperimentRun> runs = planner::experimentRuns(models.size(), metrics, c.trials, shard, shards);
  requireThreeJs();  // each model's report page
  std::vector<sensor::TriangleMesh> meshes;  // loaded first: a bad file stops the experiment before any run
  for (const std::string& model : models) meshes.push_back(placedModel(model, upOf(c.scene)));
  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  std::printf("experiment: %zu runs (%zu models x %zu metrics x %u trials%s), %zu iterations, %s rays, scene %s, "
              "%d thread%s\n",
              runs.size(), models.size(), metrics.size(), c.trials, shards > 1 ? (", shard " + c.shard).c_str() : "",
              c.iterations, c.rays.c_str(), sceneLabel(c.scene).c_str(), threads, threads == 1 ? "" : "s");
  std::fflush(stdout);
  // Each run's rows land in its own slot, so any thread count writes the same rows in the
  // same order; each metric's first trial (in this shard) goes into its model's report page.
  std::vector<std::vector<planner::ExperimentRow>> rows_of_run(runs.size());
  std::vector<std::optional<planner::ReconstructionResult>> shown(runs.size());
  std::vector<std::uint64_t> first_trial(models.size(), std::numeric_limits<std::uint64_t>::max());
  for (const planner::ExperimentRun& run : runs) first_trial[run.model] = std::min(first_trial[run.model], run.trial);
  fs::create_directories(c.out);
  RunProgress progress(runs.size());
  const auto done = [&](std::size_t i, planner::ReconstructionResult&& result) {
    const planner::ExperimentRun& run = runs[i];
    if (c.no_timings) std::for_each(result.iterations.begin(), result.iterations.end(), dropTimings);
    rows_of_run[i] = planner::experimentRows(labels[run.model], run, result);
    if (run.trial == first_trial[run.model]) shown[i] = std::move(result);
    progress.oneDone();
    return true;
  };
  const auto model_done = [&](std::size_t model, const planner::SimulatedObject& object) {
    Report report;
    report.title = labels[model] + ": the first trial of each metric (" + sceneLabel(c.scene) + ", " + c.rays + " rays)";
    report.views = views;
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (runs[i].model == model && shown[i]) {
        report.runs.push_back({runLabel(runs[i].metric, first_trial[model]), shown[i]->iterations, shown[i]->max_entropy_bits});
        shown[i].reset();
      }
    }
    addScans(report, object);
    const fs::path page = fs::path(c.out) / (labels[model] + ".html");
    writeAtomically(page, [&](const fs::path& temporary) { writeReportHtml(temporary, report); });
  };
  planner::runExperiment(meshes, views, base, runs, threads, done, model_done);
  std::vector<planner::ExperimentRow> rows;
  for (const auto& run_rows : rows_of_run) rows.insert(rows.end(), run_rows.begin(), run_rows.end());
  writeExperiment(c.out, std::move(rows));
}

constexpr const char* kMetricHelp =
    "IG metric: entropy, oa, uv, rsv, rse, pc, vg, kr, random, or a weighted sum such as 0.5*pc+0.5*vg";
constexpr const char* kWeightingHelp =
    "How a weighted sum combines its metrics: normalized (each divided by its sum over the candidates, "
    "then weighted) or raw (weights on the raw values, as the released code)";

}  // namespace

void addPlannerCommands(CLI::App& app) {
  auto c = std::make_shared<ReconstructCommand>();
  CLI::App* reconstruct = app.add_subcommand(
      "reconstruct", "Reconstruct a model in simulation by next-best views (the paper's Algorithm 1).");
  reconstruct->add_option("--model", c->model, "A standard model (" + standardModelNames() + ") or a mesh file")
      ->required();
  reconstruct->add_option("--metric,--metrics", c->metric, kMetricHelp)->check(utilityText(false))->capture_default_str();
  reconstruct->add_option("--weighting", c->weighting, kWeightingHelp)
      ->check(CLI::IsMember({"normalized", "raw"}))
      ->capture_default_str();
  reconstruct->add_option("--seed", c->seed, "Seed of the start view and of `random`")->capture_default_str();
  reconstruct->add_option("--iterations", c->iterations, "Scans, the first (random) one included")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  reconstruct->add_option("--gamma", c->gamma, "Cost weight of Eq. 12, in [0, 1]")
      ->check(numberIn(0.0, 1.0))
      ->capture_default_str();
  reconstruct->add_option("--rays", c->rays, "IG ray set: released (950 rays), full (360,960) or a pixel stride")
      ->check(raySetName())
      ->capture_default_str();
  reconstruct->add_option("--viewspace", c->viewspace, "dome48 or a view file")->capture_default_str();
  reconstruct->add_option("--threads", c->threads, "Threads (default: all cores)")->check(CLI::Range(1, 1 << 20));
  reconstruct->add_option("--json", c->json, "Write the run as JSON (per iteration: view, coverage, entropy, "
                                             "times, every candidate's IG; AUCs; -: standard output)");
  reconstruct->add_option("--html", c->html, "Write the run as one self-contained HTML page (scans, candidates by "
                                             "their gain, path, curves; opens from a file:// URL)");
  reconstruct->add_flag("--no-timings", c->no_timings, kNoTimingsHelp);
  addSceneOptions(*reconstruct, c->scene, true);
  addAnytimeOptions(*reconstruct, c->anytime);
  reconstruct->callback([c] { runReconstruct(*c); });

  auto e = std::make_shared<ExperimentCommand>();
  CLI::App* experiment = app.add_subcommand(
      "experiment", "Run every (model, metric, trial) reconstruction and write results.csv, table.md and plots; "
                    "or merge the folders of shards.");
  experiment->add_option("--models", e->models, "Comma-separated models: standard names (" + standardModelNames() +
                                                  "), mesh files, or all (the 11 standard models)")
      ->capture_default_str();
  experiment->add_option("--metrics,--metric", e->metrics,
                         "all, or a comma-separated list of metrics or weighted sums (0.5*pc+0.5*vg)")
      ->check(utilityText(true))
      ->capture_default_str();
  experiment->add_option("--weighting", e->weighting, kWeightingHelp)
      ->check(CLI::IsMember({"normalized", "raw"}))
      ->capture_default_str();
  experiment->add_option("--trials", e->trials, "Trials per (model, metric); trial t uses seed t")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  experiment->add_option("--iterations", e->iterations, "Scans per run")->check(CLI::Range(1, 1 << 20))->capture_default_str();
  experiment->add_option("--rays", e->rays, "IG ray set: released, full or a pixel stride")
      ->check(raySetName())
      ->capture_default_str();
  experiment->add_option("--viewspace", e->viewspace, "dome48 or a view file")->capture_default_str();
  experiment->add_option("--threads", e->threads, "Threads of the whole experiment; runs go side by side (default: all "
                                                  "cores)")
      ->check(CLI::Range(1, 1 << 20));
  experiment->add_option("--shard", e->shard, "Run only the K-th of N disjoint slices of the runs: K/N");
  experiment->add_option("--merge", e->merge, "Combine the results of these experiment folders instead of running");
  experiment->add_option("--out", e->out, "Output folder: empty or new (files named by each model's label: a "
                                          "short name, or a mesh file's stem)")
      ->required();
  experiment->add_flag("--force", e->force, "Write into a --out folder that is not empty");
  experiment->add_flag("--no-timings", e->no_timings, kNoTimingsHelp);
  addSceneOptions(*experiment, e->scene, true);
  addAnytimeOptions(*experiment, e->anytime);
  experiment->callback([e] { runExperiment(*e); });
}

}  // namespace nbv::apps
