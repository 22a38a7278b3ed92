#include "experiment_command.hpp"

#include "app_support.hpp"
#include "output_file.hpp"
#include "report_html.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/experiment.hpp"
#include "nbv/planner/experiment_folder.hpp"

#include <CLI/CLI.hpp>
#include <tbb/info.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;
using planner::ExperimentFolder;
using planner::KeptRun;
using planner::Sweep;

struct ExperimentCommand {
  std::string models = "bunny";
  std::string metrics = "all";
  std::string weighting = "normalized";
  unsigned trials = 20;
  std::size_t iterations = 20;
  OptionFlags options;  // gamma and the others of planner::NBV_RECONSTRUCTION_OPTIONS
  std::string rays = "released";
  std::string viewspace = "dome48";
  int threads = 0;
  std::string shard;  // "K/N"
  std::vector<std::string> merge;
  std::string out;
  bool force = false;
  bool resume = false;
  bool allow_partial = false;
  bool no_timings = false;
  SceneFlags scene;
  AnytimeFlags anytime;
  /// The options that define a sweep (a merge refuses them; a resume checks them).
  std::vector<const CLI::Option*> sweep_options;
};

/// Whether the user gave any option that defines the sweep; the first one, if so.
const CLI::Option* givenSweepOption(const ExperimentCommand& c) {
  for (const CLI::Option* option : c.sweep_options) {
    if (option->count() > 0) return option;
  }
  return nullptr;
}

/// "K/N" with 1 <= K <= N.
std::pair<std::size_t, std::size_t> parseShard(const std::string& text) {
  unsigned long k = 0, n = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lu/%lu%c", &k, &n, &tail) != 2 || k < 1 || k > n) {
    throw InvalidArgument("--shard '" + text + "' is not K/N with 1 <= K <= N");
  }
  return {k, n};
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
    for (ig::Metric m : kernels::kAllMetrics) metrics.push_back(kernels::metricName(m));
  } else {
    metrics = splitList(text);
  }
  for (const std::string& m : metrics) {
    planner::ReconstructionConfig checked;
    planner::setPlanner(checked, m);
  }
  return metrics;
}

/// The sweep the command line describes.
Sweep sweepOf(const ExperimentCommand& c) {
  Sweep s;
  const std::vector<std::string> models = experimentModels(c.models);
  for (const std::string& model : models) s.models.push_back(portableName(model, isStandardModel(model)));
  s.labels = modelLabels(models);  // a mesh path by its file's stem
  s.metrics = experimentMetrics(c.metrics);
  for (std::uint64_t t = 0; t < c.trials; ++t) s.seeds.push_back(t);
  if (s.models.empty() || s.metrics.empty() || s.seeds.empty()) throw InvalidArgument("the experiment has no run");
  s.viewspace = portableName(c.viewspace, c.viewspace == "dome48");
  s.rays = c.rays;
  s.scene = sceneLabel(c.scene);
  s.up = upOf(c.scene);
  planner::ReconstructionConfig& base = s.config;
  base.max_iterations = c.iterations;
  base.rays = sensor::PixelSampling::fromName(c.rays);
  base.weighting = planner::weightingFromName(c.weighting);
  base.scene = sceneOf(c.scene);
  base.snapshot.visibility = kernels::visibilityFromName(c.scene.visibility);
  base.anytime = anytimeOf(c.anytime);
  applyOptionFlags(planner::reconstructionOptions(), c.options, base);
  s.timings = !c.no_timings;
  std::tie(s.shard, s.shards) = c.shard.empty() ? std::pair<std::size_t, std::size_t>{1, 1} : parseShard(c.shard);
  s.version = NBV_VERSION;
  return s;
}

/// Ctrl-C or a job's end (SIGINT, SIGTERM): no further run starts, the runs in flight end and
/// are kept. A second signal stops at once.
std::atomic<bool> interrupted{false};
extern "C" void onInterrupt(int) {
  interrupted = true;
  static const char kNote[] = "\nnbv: interrupted: the runs in flight end and are kept (again: stop at once)\n";
  [[maybe_unused]] const auto ignored = ::write(STDERR_FILENO, kNote, sizeof kNote - 1);
  ::signal(SIGINT, SIG_DFL);
  ::signal(SIGTERM, SIG_DFL);
}

/// Catches SIGINT and SIGTERM for its lifetime.
class InterruptGuard {
 public:
  InterruptGuard() {
    interrupted = false;
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    ::sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, &old_int_);
    ::sigaction(SIGTERM, &action, &old_term_);
  }
  ~InterruptGuard() {
    ::sigaction(SIGINT, &old_int_, nullptr);
    ::sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

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

/// The experiment's front page: Table 1 (`table1`, table.md's text, as HTML), then per model
/// its plot and a link to its report page.
void writeExperimentIndex(const fs::path& path, const fs::path& out, const std::vector<std::string>& labels,
                          const std::string& table1) {
  std::ofstream html(path);
  if (!html) throw FileError(path, "cannot write");
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>nbv experiment</title>\n<style>body{font:14px "
          "sans-serif;margin:12px}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;font-size:12px}"
          "img{max-width:900px;display:block}</style></head><body>\n<h1>nbv experiment</h1>\n"
          "<p>Each model's plot, and its report page: the first trial of every metric, drawn in 3D.</p>\n";
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

/// The report page of model `model`: the first trial of each of its metrics among `runs`,
/// their scans added by `add_scans(report)`.
template <class AddScans>
void writeModelPage(const fs::path& out, const Sweep& sweep, std::size_t model, const std::map<std::size_t, KeptRun>& runs,
                    const std::vector<planner::View>& views, AddScans add_scans) {
  Report report;
  report.title = sweep.labels[model] + ": the first trial of each metric (" + sweep.scene + ", " + sweep.rays + " rays)";
  report.views = views;
  for (const std::string& metric : sweep.metrics) {
    const KeptRun* first = nullptr;  // the smallest seed of this model and metric
    for (const auto& [index, kept] : runs) {
      if (kept.run.model == model && kept.run.metric == metric && (first == nullptr || kept.run.trial < first->run.trial)) {
        first = &kept;
      }
    }
    if (first != nullptr) {
      report.runs.push_back({runLabel(metric, first->run.trial), first->result.iterations, first->result.max_entropy_bits});
    }
  }
  if (report.runs.empty()) return;
  add_scans(report);
  writeAtomically(out / (sweep.labels[model] + ".html"), [&](const fs::path& temporary) { writeReportHtml(temporary, report); });
}

/// Writes, for every model of `sweep` with runs in `runs` and no page in `out` yet, its report
/// page (the scans rendered again); a model that cannot be loaded here gets no page and a note.
void writeMissingPages(const fs::path& out, const Sweep& sweep, const std::map<std::size_t, KeptRun>& runs) {
  for (std::size_t model = 0; model < sweep.models.size(); ++model) {
    std::error_code ec;
    if (fs::exists(out / (sweep.labels[model] + ".html"), ec)) continue;
    if (std::none_of(runs.begin(), runs.end(), [&](const auto& r) { return r.second.run.model == model; })) continue;
    try {
      const std::vector<planner::View> views = viewspace(sweep.viewspace);
      const sensor::TriangleMesh mesh = placedModel(sweep.models[model], sweep.up);
      writeModelPage(out, sweep, model, runs, views, [&](Report& report) { addScans(report, mesh, sweep.config); });
    } catch (const FileError& e) {
      std::fprintf(stderr, "nbv: note: no report page for %s: %s\n", sweep.labels[model].c_str(), e.what());
    }
  }
}

/// results.csv, table.md (with `note` under it), and for a whole sweep the plots, the report
/// pages still missing and index.html, of the runs `runs` of `sweep`, in `out`. A shard's folder
/// is a piece of its sweep: its plots and pages come with the merge.
void writeExperiment(const fs::path& out, const Sweep& sweep, const std::map<std::size_t, KeptRun>& runs,
                     const std::string& note = "") {
  std::vector<planner::ExperimentRow> rows;
  for (const auto& [index, kept] : runs) {
    const std::vector<planner::ExperimentRow> its = planner::experimentRows(sweep.labels[kept.run.model], kept.run, kept.result);
    rows.insert(rows.end(), its.begin(), its.end());
  }
  planner::sortRows(rows);
  const std::string table1 = planner::table1Markdown(rows) + note;
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
  if (sweep.shards > 1) {
    std::printf("shard %zu/%zu: `nbv experiment --merge` of the %zu shards draws the plots and report pages\n", sweep.shard,
                sweep.shards, sweep.shards);
    return;
  }
  writeMissingPages(out, sweep, runs);
  // The plots, one per model label, by nbv.plots (matplotlib).
  std::fputs(runPlots({"experiment", (out / "results.csv").string(), "--out-dir", out.string()}).c_str(), stdout);
  writeAtomically(out / "index.html", [&](const fs::path& temporary) { writeExperimentIndex(temporary, out, sweep.labels, table1); });
  std::printf("wrote %s\n", (out / "index.html").c_str());
}

/// `--merge`: the shards' runs, checked to be their whole sweep, written as one experiment.
void mergeExperiment(const ExperimentCommand& c) {
  if (const CLI::Option* given = givenSweepOption(c)) {
    throw InvalidArgument(given->get_name() + " has no effect with --merge: each shard's sweep.json says what it ran");
  }
  if (c.resume) throw InvalidArgument("--resume has no effect with --merge (resume a shard's own folder)");
  std::vector<fs::path> folders(c.merge.begin(), c.merge.end());
  for (const fs::path& folder : folders) {
    std::error_code ec;
    if (fs::equivalent(folder, c.out, ec)) throw InvalidArgument("--out " + c.out + " is one of the --merge folders");
  }
  const planner::MergedSweep merged = planner::mergeShards(folders, c.allow_partial);
  std::string note;
  if (!merged.missing.empty()) {
    note = "\nPartial: merged with --allow-partial; missing: ";
    for (std::size_t i = 0; i < merged.missing.size(); ++i) note += (i ? "; " : "") + merged.missing[i];
    note += ".\n";
    std::fprintf(stderr, "nbv: note: a partial sweep (%zu of %zu runs): %s", merged.runs.size(),
                 merged.sweep.allRuns().size(), note.substr(1).c_str());
  }
  // The merged folder holds the whole sweep again (so it merges and resumes as any experiment).
  const ExperimentFolder folder(c.out, merged.sweep, false, c.force);
  for (const auto& [index, kept] : merged.runs) folder.keep(index, kept.result);
  writeExperiment(c.out, merged.sweep, merged.runs, note);
}

/// Runs the runs of the folder's shard that it does not hold yet; \returns the runs it holds.
std::map<std::size_t, KeptRun> runMissing(const ExperimentFolder& folder, int threads) {
  const Sweep& sweep = folder.sweep();
  std::map<std::size_t, KeptRun> kept = folder.kept();
  const std::vector<planner::ExperimentRun> all = sweep.allRuns();
  std::vector<std::size_t> todo;  // indices into `all`
  for (const std::size_t i : sweep.shardRuns()) {
    if (kept.count(i) == 0) todo.push_back(i);
  }
  std::vector<planner::ExperimentRun> runs;
  for (const std::size_t i : todo) runs.push_back(all[i]);
  std::vector<sensor::TriangleMesh> meshes;  // loaded first: a bad file stops the experiment before any run
  for (const std::string& model : sweep.models) meshes.push_back(placedModel(model, sweep.up));
  const std::vector<planner::View> views = viewspace(sweep.viewspace);
  std::printf("experiment: %zu runs (%zu models x %zu metrics x %zu trials%s), %zu kept, %zu to run; %zu iterations, "
              "%s rays, scene %s, %d thread%s\n",
              all.size(), sweep.models.size(), sweep.metrics.size(), sweep.seeds.size(),
              sweep.shards > 1 ? (", shard " + std::to_string(sweep.shard) + "/" + std::to_string(sweep.shards)).c_str() : "",
              kept.size(), todo.size(), sweep.config.max_iterations, sweep.rays.c_str(), sweep.scene.c_str(), threads,
              threads == 1 ? "" : "s");
  std::fflush(stdout);
  std::mutex kept_mutex;
  RunProgress progress(todo.size());
  const InterruptGuard guard;
  const auto done = [&](std::size_t i, planner::ReconstructionResult&& result) {
    if (!sweep.timings) std::for_each(result.iterations.begin(), result.iterations.end(), dropTimings);
    folder.keep(todo[i], result);  // on disk before it counts
    {
      const std::lock_guard<std::mutex> lock(kept_mutex);
      kept[todo[i]] = KeptRun{todo[i], runs[i], std::move(result)};
    }
    progress.oneDone();
    return !interrupted.load();
  };
  const auto model_done = [&](std::size_t model, const planner::SimulatedObject& object) {
    if (sweep.shards > 1) return;  // a shard's pages come with the merge
    writeModelPage(folder.dir(), sweep, model, kept, views, [&](Report& report) { addScans(report, object); });
  };
  planner::runExperiment(meshes, views, sweep.config, runs, threads, done, model_done);
  if (interrupted.load()) {
    const std::size_t mine = sweep.shardRuns().size();
    throw Interrupted("interrupted: " + std::to_string(kept.size()) + " of " + std::to_string(mine) + " runs kept in " +
                      folder.dir().string() + "; `nbv experiment --resume --out " + folder.dir().string() +
                      "` runs the " + std::to_string(mine - kept.size()) + " left");
  }
  return kept;
}

void runExperiment(const ExperimentCommand& c) {
  if (c.out.empty()) throw InvalidArgument("--out names no folder");
  if (!c.merge.empty()) {
    mergeExperiment(c);
    return;
  }
  if (c.allow_partial) throw InvalidArgument("--allow-partial is an option of --merge");
  requireThreeJs();  // each model's report page
  // --resume without the sweep's options takes them from the folder's record.
  const bool recorded = c.resume && ExperimentFolder::hasSweep(c.out) && givenSweepOption(c) == nullptr;
  const Sweep sweep = recorded ? ExperimentFolder::readSweep(c.out) : sweepOf(c);
  const ExperimentFolder folder(c.out, sweep, c.resume, c.force);
  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  const std::map<std::size_t, KeptRun> kept = runMissing(folder, threads);
  writeExperiment(c.out, sweep, kept);
}

}  // namespace

void addExperimentCommand(CLI::App& app) {
  auto e = std::make_shared<ExperimentCommand>();
  CLI::App* experiment = app.add_subcommand(
      "experiment", "Run every (model, metric, trial) reconstruction of a sweep (or a shard of it), keeping each run as it "
                    "ends, and write results.csv, table.md, plots and report pages; resume an interrupted sweep; or "
                    "merge the folders of a sweep's shards.");
  auto& sweep = e->sweep_options;
  sweep.push_back(experiment->add_option("--models", e->models, "Comma-separated models: standard names (" +
                                                                    standardModelNames() +
                                                                    "), mesh files, or all (the 11 standard models)")
                      ->capture_default_str());
  sweep.push_back(experiment->add_option("--metrics,--metric", e->metrics,
                                         "all, or a comma-separated list of metrics or weighted sums (0.5*pc+0.5*vg)")
                      ->check(utilityText(true, true))
                      ->capture_default_str());
  sweep.push_back(experiment->add_option("--weighting", e->weighting, kWeightingHelp)
                      ->check(CLI::IsMember({"normalized", "raw"}))
                      ->capture_default_str());
  sweep.push_back(experiment->add_option("--trials", e->trials, "Trials per (model, metric); trial t uses seed t")
                      ->check(CLI::Range(1, 1 << 20))
                      ->capture_default_str());
  sweep.push_back(
      experiment->add_option("--iterations", e->iterations, "Scans per run")->check(CLI::Range(1, 1 << 20))->capture_default_str());
  sweep.push_back(experiment->add_option("--rays", e->rays, std::string("IG ray set: ") + sensor::PixelSampling::kNamesHelp)
                      ->check(raySetName())
                      ->capture_default_str());
  sweep.push_back(experiment->add_option("--viewspace", e->viewspace, "dome48 or a view file")->capture_default_str());
  sweep.push_back(experiment->add_option("--shard", e->shard, "Run only the K-th of N disjoint slices of the runs: K/N"));
  sweep.push_back(experiment->add_flag("--no-timings", e->no_timings, kNoTimingsHelp));
  for (CLI::Option* option : addOptionFlags(*experiment, planner::reconstructionOptions(), e->options)) sweep.push_back(option);
  const std::size_t before = experiment->get_options().size();
  addSceneOptions(*experiment, e->scene, true);
  addAnytimeOptions(*experiment, e->anytime);
  const std::vector<CLI::Option*> added = experiment->get_options();
  sweep.insert(sweep.end(), added.begin() + static_cast<std::ptrdiff_t>(before), added.end());
  experiment->add_option("--threads", e->threads, "Threads of the whole experiment; runs go side by side (default: all "
                                                  "cores)")
      ->check(CLI::Range(1, 1 << 20));
  experiment->add_option("--merge", e->merge, "Combine the folders of a sweep's shards (each once, all of them) instead "
                                              "of running");
  experiment->add_flag("--allow-partial", e->allow_partial, "With --merge: merge shards that are not the whole sweep (the "
                                                            "table then says what is missing)");
  experiment->add_flag("--resume", e->resume, "Finish the sweep of the --out folder: run only the runs it does not hold "
                                              "(its sweep.json gives the options; given ones must match it); a new "
                                              "folder starts the sweep");
  experiment->add_option("--out", e->out, "Output folder: new, empty, or one of this sweep with --resume (files named "
                                          "by each model's label: a short name, or a mesh file's stem); its results.csv "
                                          "has a line per run and iteration, with the columns " +
                                              planner::resultsCsvHeader())
      ->required();
  experiment->add_flag("--force", e->force, "Write into a --out folder that is not empty, starting afresh");
  experiment->callback([e] { runExperiment(*e); });
}

}  // namespace nbv::apps
