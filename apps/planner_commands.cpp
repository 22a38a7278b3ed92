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

struct ReconstructCommand {
  std::string model;
  std::string metric = "pc";
  std::string weighting = "normalized";
  std::uint64_t seed = 0;
  std::size_t iterations = 20;
  OptionFlags options;  // gamma and the others of planner::NBV_RECONSTRUCTION_OPTIONS
  std::string rays = "released";
  std::string viewspace = "dome48";
  int threads = 0;
  std::string json;
  std::string html;
  bool no_timings = false;
  SceneFlags scene;
  AnytimeFlags anytime;
};

/// A number for JSON: the shortest text that reads back to it, null for NaN.
std::string number(double value) { return std::isnan(value) ? "null" : shortestNumber(value); }
/// A field of an iteration in the run's JSON: an integer as it is, a number as number() writes it.
std::string jsonValue(std::uint64_t value) { return std::to_string(value); }
std::string jsonValue(double value) { return number(value); }

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

/// A number or none as JSON.
std::string optionJson(const std::optional<double>& value) { return value ? number(*value) : std::string("null"); }

/// The anytime decisions of a run as JSON: null, or an object of planner::NBV_DECIDE_OPTIONS.
std::string anytimeJson(const std::optional<planner::DecideOptions>& anytime) {
  if (!anytime) return "null";
  std::string out;
  for (const planner::DecideOption& option : planner::decideOptions()) {
    out += (out.empty() ? "{" : ", ") + quoted(option.name) + ": " + optionJson(option.get(*anytime));
  }
  return out + "}";
}

/// The run's options (planner::NBV_RECONSTRUCTION_OPTIONS) as JSON fields, each after ",\n  ".
std::string optionsJson(const planner::ReconstructionConfig& config) {
  std::string out;
  for (const planner::ReconstructionOption& option : planner::reconstructionOptions()) {
    out += ",\n  " + quoted(option.name) + ": " + optionJson(option.get(config));
  }
  return out;
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
void writeJson(const fs::path& path, const ReconstructCommand& c, const planner::ReconstructionConfig& config,
               const planner::ReconstructionResult& r) {
  std::ofstream out(path);
  if (!out) throw nbv::FileError(path, "cannot write");
  out << "{\n  \"model\": " << quoted(portableName(c.model, isStandardModel(c.model))) << ",\n  \"metric\": " << quoted(c.metric)
      << ",\n  \"seed\": " << c.seed << ",\n  \"viewspace\": " << quoted(portableName(c.viewspace, c.viewspace == "dome48"))
      << ",\n  \"weighting\": " << quoted(c.weighting) << ",\n  \"rays\": " << quoted(c.rays)
      << optionsJson(config) << ",\n  \"scene\": " << sceneJson(c.scene)
      << ",\n  \"anytime\": " << anytimeJson(config.anytime)
      << ",\n  \"stop\": " << quoted(planner::stopReasonName(r.stop)) << ",\n  \"iterations\": [\n";
  for (std::size_t i = 0; i < r.iterations.size(); ++i) {
    const planner::IterationRecord& it = r.iterations[i];
    out << "    {";
#define NBV_JSON_FIELD(name, type, kind, help) \
  NBV_ITERATION_IF_RECORD(kind, out << "\"" #name "\": " << jsonValue(it.name) << ", ";)
    NBV_ITERATION_FIELDS(NBV_JSON_FIELD)
#undef NBV_JSON_FIELD
    out << "\"gains\": [";
    for (std::size_t v = 0; v < it.gains.size(); ++v) out << (v == 0 ? "" : ", ") << number(it.gains[v]);
    out << "]}" << (i + 1 < r.iterations.size() ? "," : "") << "\n";
  }
  out << "  ],\n  \"max_entropy_bits\": " << number(r.max_entropy_bits) << ",\n  \"auc_coverage\": "
      << number(r.auc_coverage) << ",\n  \"auc_entropy\": " << number(r.auc_entropy) << "\n}\n";
  if (!out.flush()) throw nbv::FileError(path, "write failed");
}

/// A value of an iteration's record as `nbv reconstruct` prints it: a count as an integer, a
/// time (kind Time) in seconds to the millisecond, another number to 7 significant digits,
/// none (NaN) as "-".
std::string cellText(std::uint64_t value, std::string_view) { return std::to_string(value); }
std::string cellText(double value, std::string_view kind) {
  if (std::isnan(value)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, kind == "Time" ? "%.3f" : "%.7g", value);
  return text;
}

/// A line of the table `nbv reconstruct` prints as it runs: a column per field of an
/// iteration's record (planner::NBV_ITERATION_FIELDS, the run's own aside), its name as the
/// header (`record` null), each value right-aligned under it.
std::string iterationLine(const planner::IterationRecord* record) {
  std::string line;
  auto column = [&line](std::string_view name, const std::string& value) {
    const std::size_t width = std::max<std::size_t>(name.size(), 8);
    line += (line.empty() ? "" : " ") + std::string(width - std::min(width, value.size()), ' ') + value;
  };
#define NBV_PRINTED_FIELD(name, type, kind, help) \
  NBV_ITERATION_IF_RECORD(kind, column(#name, record ? cellText(record->name, #kind) : std::string(#name));)
  NBV_ITERATION_FIELDS(NBV_PRINTED_FIELD)
#undef NBV_PRINTED_FIELD
  return line;
}

void runReconstruct(const ReconstructCommand& c) {
  if (!c.json.empty()) checkWritable(c.json);
  if (!c.html.empty()) {
    checkWritable(c.html);
    requireThreeJs();
  }
  planner::ReconstructionConfig config;
  planner::setPlanner(config, c.metric);
  config.weighting = planner::weightingFromName(c.weighting);
  config.seed = c.seed;
  config.max_iterations = c.iterations;
  applyOptionFlags(planner::reconstructionOptions(), c.options, config);
  config.rays = sensor::PixelSampling::fromName(c.rays);
  config.scene = sceneOf(c.scene);
  config.snapshot.visibility = kernels::visibilityFromName(c.scene.visibility);
  config.anytime = anytimeOf(c.anytime);
  config.validate();
  const std::vector<planner::View> views = viewspace(c.viewspace);
  const sensor::TriangleMesh mesh = placedModel(c.model, upOf(c.scene));

  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  std::printf("%s, metric %s, seed %llu, %zu views, %s rays, scene %s, %d thread%s\n", c.model.c_str(),
              c.metric.c_str(), static_cast<unsigned long long>(c.seed), views.size(), c.rays.c_str(),
              sceneLabel(c.scene).c_str(), threads, threads == 1 ? "" : "s");
  std::printf("%s\n", iterationLine(nullptr).c_str());
  std::fflush(stdout);
  planner::ReconstructionResult result;
  // One object for the run and, with --html, the page's scans (each view rendered once).
  std::unique_ptr<planner::SimulatedObject> object;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    object = std::make_unique<planner::SimulatedObject>(mesh, views, config);
    result = planner::reconstruct(*object, config, [](const planner::IterationRecord& r) {
      std::printf("%s\n", iterationLine(&r).c_str());
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
    writeAtomically(c.json, [&](const fs::path& temporary) { writeJson(temporary, c, config, result); });
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

/// The help of --metric: the table's short names.
std::string metricHelp() {
  return "IG metric: " + kernels::metricNames() +
         ", or a weighted sum such as 0.5*pc+0.5*vg; or oracle, the ground-truth ceiling (docs/SEMANTICS.md, \"The oracle\")";
}
}  // namespace

void addPlannerCommands(CLI::App& app) {
  auto c = std::make_shared<ReconstructCommand>();
  CLI::App* reconstruct = app.add_subcommand(
      "reconstruct", "Reconstruct a model in simulation by next-best views (the paper's Algorithm 1).");
  reconstruct->add_option("--model", c->model, "A standard model (" + standardModelNames() + ") or a mesh file")
      ->required();
  reconstruct->add_option("--metric,--metrics", c->metric, metricHelp())->check(utilityText(false, true))->capture_default_str();
  reconstruct->add_option("--weighting", c->weighting, kWeightingHelp)
      ->check(CLI::IsMember({"normalized", "raw"}))
      ->capture_default_str();
  reconstruct->add_option("--seed", c->seed, "Seed of the start view and of `random`")->capture_default_str();
  reconstruct->add_option("--iterations", c->iterations, "Scans, the first (random) one included")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  addOptionFlags(*reconstruct, planner::reconstructionOptions(), c->options);
  reconstruct->add_option("--rays", c->rays, std::string("IG ray set: ") + sensor::PixelSampling::kNamesHelp)
      ->check(raySetName())
      ->capture_default_str();
  reconstruct->add_option("--viewspace", c->viewspace, "dome48 or a view file")->capture_default_str();
  reconstruct->add_option("--threads", c->threads, "Threads (default: all cores)")->check(CLI::Range(1, 1 << 20));
  reconstruct->add_option("--json", c->json, "Write the run as JSON (per iteration: " + planner::iterationFieldNames() +
                                                 " and every candidate's IG as gains; AUCs; -: standard output)");
  reconstruct->add_option("--html", c->html, "Write the run as one self-contained HTML page (scans, candidates by "
                                             "their gain, path, curves; opens from a file:// URL)");
  reconstruct->add_flag("--no-timings", c->no_timings, kNoTimingsHelp);
  addSceneOptions(*reconstruct, c->scene, true);
  addAnytimeOptions(*reconstruct, c->anytime);
  reconstruct->callback([c] { runReconstruct(*c); });
}

}  // namespace nbv::apps
