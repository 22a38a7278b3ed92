#include "ig_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <CLI/CLI.hpp>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;

struct EvaluateCommand {
  std::string map;
  std::string views = "dome48";
  std::string metrics = "all";
  std::string rays = "released";
  int threads = 0;  // 0: all
  bool reference = false;
  std::string visibility = "paper";
  std::string isa = "auto";
  double max_ray_depth = 1.5;
  std::uint64_t seed = 0;
  std::size_t max_snapshot_mb = ig::SnapshotOptions{}.max_snapshot_bytes >> 20;
  std::string csv;
};

/// "all" or a comma-separated list of short names.
std::vector<ig::Metric> parseMetrics(const std::string& text) {
  if (text == "all") return {kernels::kAllMetrics.begin(), kernels::kAllMetrics.end()};
  std::vector<ig::Metric> metrics;
  std::stringstream list(text);
  std::string name;
  while (std::getline(list, name, ',')) {
    metrics.push_back(kernels::metricNamed(name));
  }
  if (metrics.empty()) throw nbv::InvalidArgument("'" + text + "' names no metric");
  return metrics;
}

/// One row per view: its index, then one column per metric, at full double precision.
void writeCsv(const fs::path& path, const ig::IgTable& table) {
  std::ofstream out(path);
  if (!out) throw nbv::FileError(path, "cannot write");
  out << "view";
  for (ig::Metric metric : table.metrics) out << ',' << kernels::metricName(metric);
  out << '\n';
  char number[32];
  for (std::size_t v = 0; v < table.views(); ++v) {
    out << v;
    for (std::size_t m = 0; m < table.metrics.size(); ++m) {
      std::snprintf(number, sizeof number, "%.17g", table.value(v, m));
      out << ',' << number;
    }
    out << '\n';
  }
  if (!out.flush()) throw nbv::FileError(path, "write failed");
}

/// The metrics that read proximity marks (pc, vg: the table's kMarks), which .ot and .bt
/// files do not carry: say so once.
void warnIfNoMarks(const EvaluateCommand& c, const ig::TableOptions& options) {
  if (grid::mapFormatFromPath(c.map) == grid::MapFormat::Vdb) return;
  std::string readers;
  for (const ig::Metric m : options.metrics) {
    if ((kernels::metricRow(m).reads & kernels::metric_reads::kMarks) != 0) {
      readers += (readers.empty() ? "" : ", ") + std::string(kernels::metricName(m));
    }
  }
  if (!readers.empty()) {
    std::fprintf(stderr,
                 "nbv: warning: %s has no proximity marks (OctoMap files do not carry them), which %s read: pc is 0 "
                 "for every view and vg finds no occplane ray; integrate the scans into a .vdb map (nbv integrate "
                 "--map MAP.vdb) to get them\n",
                 c.map.c_str(), readers.c_str());
  }
}

void runEvaluate(const EvaluateCommand& c) {
  checkWritable(c.csv);
  ig::EvaluateOptions options;
  options.table.metrics = parseMetrics(c.metrics);
  options.table.random_seed = c.seed;
  options.snapshot.visibility = kernels::visibilityFromName(c.visibility);
  options.snapshot.max_snapshot_bytes = c.max_snapshot_mb << 20;
  options.walk.max_ray_depth = c.max_ray_depth;
  if (c.isa != "auto") {
    options.walk.isa = kernels::isaFromName(c.isa);
    if (!kernels::isaAvailable(*options.walk.isa)) {
      throw nbv::InvalidArgument("--isa " + c.isa + ": not available here (this CPU lacks it, or nbv was built without it)");
    }
  }
  options.validate();
  const sensor::PinholeCamera camera;
  const std::vector<Eigen::Vector3d> directions =
      sensor::rayDirectionsCamera(camera, sensor::PixelSampling::fromName(c.rays));
  std::vector<Eigen::Isometry3d> poses;
  for (const planner::View& view : viewspace(c.views)) poses.push_back(view.T_world_camera);
  const grid::OccupancyMap map = readMap(c.map);
  warnIfNoMarks(c, options.table);

  const int threads = c.reference ? 1 : (c.threads > 0 ? c.threads : tbb::info::default_concurrency());
  const auto start = std::chrono::steady_clock::now();
  ig::IgTable table;
  if (c.reference) {
    table = ig::ReferenceEvaluator(map).evaluate(poses, directions, options);
  } else {
    tbb::task_arena arena(threads);
    arena.execute([&] { table = ig::evaluate(map, poses, directions, options); });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  writeAtomically(c.csv, [&](const fs::path& temporary) { writeCsv(temporary, table); });
  std::printf("%s: %zu views x %zu rays, %zu metrics, %s, %d thread%s: %.3f s (%.1f views/s, %.2f M rays/s, "
              "%.1f M voxels/s)\nwrote %s\n",
              c.map.c_str(), poses.size(), directions.size(), options.table.metrics.size(),
              c.reference ? "OctoMap reference" : kernels::isaName(options.walk.isa.value_or(kernels::bestIsa())),
              threads, threads == 1 ? "" : "s", seconds, static_cast<double>(poses.size()) / seconds,
              static_cast<double>(table.rays) / seconds * 1e-6, static_cast<double>(table.voxels) / seconds * 1e-6,
              c.csv.c_str());
}

struct DecideCommand {
  std::string map;
  std::string views = "dome48";
  std::string metric = "pc";
  std::string weighting = "normalized";
  std::string rays = "full";
  OptionFlags options;  // epsilon and the others of planner::NBV_DECIDE_OPTIONS
  std::optional<std::uint64_t> max_rays;
  std::uint64_t seed = 0;
  int threads = 0;
  std::string visibility = "paper";
  bool check = false;
  std::string json;
};

void writeDecisionJson(const fs::path& path, const DecideCommand& c, const planner::DecideOptions& options,
                       const planner::AnytimeDecision& d, const std::optional<ig::IgTable>& exhaustive) {
  std::ofstream out(path);
  if (!out) throw FileError(path, "cannot write");
  auto num = [](double v) { return std::isfinite(v) ? shortestNumber(v) : std::string("null"); };
  out << "{\n  \"map\": \"" << c.map << "\",\n  \"metric\": \"" << c.metric << "\",\n  \"rays\": \"" << c.rays << "\"";
  for (const planner::DecideOption& option : planner::decideOptions()) {
    const std::optional<double> value = option.get(options);
    out << ",\n  \"" << option.name << "\": " << (value ? num(*value) : std::string("null"));
  }
  out << ",\n  \"seed\": " << c.seed
      << ",\n  \"chosen\": " << d.chosen << ",\n  \"end\": \"" << planner::decisionEndName(d.end)
      << "\",\n  \"rays_cast\": " << d.rays_cast << ",\n  \"rays_exhaustive\": " << d.rays_exhaustive
      << ",\n  \"levels\": " << d.levels << ",\n  \"seconds\": " << num(d.seconds) << ",\n  \"candidates\": [\n";
  for (std::size_t v = 0; v < d.candidates.size(); ++v) {
    const planner::CandidateEstimate& e = d.candidates[v];
    out << "    {\"view\": " << v << ", \"estimate\": " << num(e.estimate) << ", \"lower\": " << num(e.lower)
        << ", \"upper\": " << num(e.upper) << ", \"exact\": " << (e.exact ? "true" : "false")
        << ", \"eliminated\": " << (e.eliminated ? "true" : "false") << ", \"rays\": " << e.rays;
    if (exhaustive) out << ", \"exhaustive\": " << num(exhaustive->value(v, 0));
    out << "}" << (v + 1 < d.candidates.size() ? "," : "") << "\n";
  }
  out << "  ]\n}\n";
  if (!out.flush()) throw FileError(path, "write failed");
}

void runDecide(const DecideCommand& c) {
  if (!c.json.empty()) checkWritable(c.json);
  planner::DecisionUtility utility;
  utility.terms = planner::parseMetricSum(c.metric);
  utility.weighting = planner::weightingFromName(c.weighting);
  planner::DecideOptions options;
  applyOptionFlags(planner::decideOptions(), c.options, options);
  options.max_rays = c.max_rays;
  options.seed = c.seed;
  options.validate();
  ig::SnapshotOptions snapshot;
  snapshot.visibility = kernels::visibilityFromName(c.visibility);
  const std::vector<Eigen::Vector3d> directions =
      sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::fromName(c.rays));
  std::vector<Eigen::Isometry3d> poses;
  for (const planner::View& view : viewspace(c.views)) poses.push_back(view.T_world_camera);
  const grid::OccupancyMap map = readMap(c.map);
  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  planner::AnytimeDecider decider;
  ig::IgEvaluator& evaluator = decider.evaluator();
  planner::AnytimeDecision d;
  arena.execute([&] {
    decider.refresh(map, utility, snapshot);
    d = decider.decide(poses, directions, utility, ig::WalkOptions{}, options);
  });
  const planner::CandidateEstimate& best = d.candidates[d.chosen];
  std::printf("%s: %zu candidates x %zu rays, metric %s, epsilon %g, delta %g, %d thread%s\n", c.map.c_str(), poses.size(),
              directions.size(), c.metric.c_str(), options.epsilon, options.delta, threads, threads == 1 ? "" : "s");
  std::printf("chosen view %zu: %.10g in [%.10g, %.10g]%s; ended: %s after %zu level%s, %.3f s\n", d.chosen, best.estimate,
              best.lower, best.upper, best.exact ? " (exact)" : "", planner::decisionEndName(d.end), d.levels,
              d.levels == 1 ? "" : "s", d.seconds);
  std::printf("rays cast: %llu of %llu (%.2f%% of the exhaustive count)\n", static_cast<unsigned long long>(d.rays_cast),
              static_cast<unsigned long long>(d.rays_exhaustive),
              100.0 * static_cast<double>(d.rays_cast) / static_cast<double>(d.rays_exhaustive));
  std::optional<ig::IgTable> exhaustive;
  if (c.check) {  // every candidate on every ray, the utility as the planner computes it
    const auto check_start = std::chrono::steady_clock::now();
    ig::IgTable table;  // on the decision's snapshot, which holds what the utility's metrics read
    arena.execute([&] { table = evaluator.evaluate(poses, directions, {utility.metrics(), utility.random_seed}); });
    const double check_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - check_start).count();
    table.metrics = {table.metrics.front()};
    table.values = planner::combinedGains(table.values, utility.terms, utility.weighting);
    const std::size_t exact_best = *planner::argmaxFirst(table.values);
    const double ratio = table.values[d.chosen] / table.values[exact_best];
    std::printf("exhaustive: view %zu (%.10g) in %.3f s; chosen/best %.6f, same view: %s, within epsilon: %s\n", exact_best,
                table.values[exact_best], check_s, ratio, exact_best == d.chosen ? "yes" : "no",
                ratio >= 1.0 - options.epsilon ? "yes" : "no");
    exhaustive = std::move(table);
  }
  if (!c.json.empty()) {
    writeAtomically(c.json, [&](const fs::path& temporary) { writeDecisionJson(temporary, c, options, d, exhaustive); });
    std::printf("wrote %s\n", c.json.c_str());
  }
}

struct WorkloadCommand {
  std::string name;
  std::string map;
  std::string views;
  std::uint64_t seed = planner::kDefaultWorkloadSeed;
};

void runWorkload(const WorkloadCommand& c) {
  const grid::MapFormat format = grid::mapFormatFromPath(c.map);  // refuse a bad extension first
  checkWritable(c.map);
  if (!c.views.empty()) checkWritable(c.views);
  const planner::Workload workload = planner::makeWorkload(c.name, sensor::modelSearchPath(), c.seed);
  writeAtomically(c.map, [&](const fs::path& temporary) { grid::saveMap(workload.map, temporary, format); });
  std::printf("%s: %zu measured voxels, %zu marked; wrote %s\n", c.name.c_str(), workload.map.measuredCount(),
              workload.map.markedCount(), c.map.c_str());
  if (!c.views.empty()) {
    writeAtomically(c.views, [&](const fs::path& temporary) { planner::saveViews(temporary, workload.candidates); });
    std::printf("wrote %zu candidate views to %s (evaluate them with --max-ray-depth %g)\n", workload.candidates.size(),
                c.views.c_str(), workload.max_ray_depth_m);
  }
}

}  // namespace

void addIgCommands(CLI::App& app) {
  auto c = std::make_shared<EvaluateCommand>();
  CLI::App* evaluate = app.add_subcommand(
      "evaluate", "Score candidate views by information gain (docs/SEMANTICS.md, \"Volumetric information\") and write one CSV "
      "row per view.");
  evaluate->add_option("--map", c->map, "Map to evaluate (.vdb, .ot or .bt)")->required();
  evaluate->add_option("--views", c->views, "dome48 or a view file (N, then N lines x y z qx qy qz qw)")
      ->capture_default_str();
  evaluate->add_option("--metrics,--metric", c->metrics, "all, or a comma-separated list of: " + kernels::metricNames())
      ->check(checkedBy("", [](const std::string& text) { parseMetrics(text); }))
      ->capture_default_str();
  evaluate->add_option("--rays", c->rays, std::string("Ray set: ") + sensor::PixelSampling::kNamesHelp)
      ->check(raySetName())
      ->capture_default_str();
  evaluate->add_option("--threads", c->threads, "Threads (default: all cores)")->check(CLI::Range(1, 1 << 20));
  evaluate->add_flag("--reference", c->reference, "Use the OctoMap reference evaluator (one thread)");
  evaluate->add_option("--visibility", c->visibility, "paper (Eq. 5) or released (the released code's P_o)")
      ->check(visibilityName())
      ->capture_default_str();
  evaluate->add_option("--isa", c->isa, "Instruction set of the fast evaluator")
      ->check(CLI::IsMember({"auto", "avx512", "avx2", "scalar"}))
      ->capture_default_str();
  evaluate->add_option("--max-ray-depth", c->max_ray_depth, "Ray length [m]")->check(positiveNumber())->capture_default_str();
  evaluate->add_option("--seed", c->seed, "Seed of the random metric")->capture_default_str();
  evaluate->add_option("--max-snapshot-mb", c->max_snapshot_mb, "Refuse a map whose IG snapshot needs more memory [MiB]")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 30))
      ->capture_default_str();
  evaluate->add_option("--csv", c->csv, "Output CSV: view, then one column per metric (-: standard output)")->required();
  evaluate->callback([c] { runEvaluate(*c); });

  auto d = std::make_shared<DecideCommand>();
  CLI::App* decide = app.add_subcommand(
      "decide", "Choose the next best view from samples of each candidate's rays (docs/SEMANTICS.md, \"Anytime "
                "decisions\"): as the exhaustive argmax, at a fraction of the rays.");
  decide->add_option("--map", d->map, "Map (.vdb, .ot or .bt)")->required();
  decide->add_option("--views", d->views, "Candidates: dome48 or a view file")->capture_default_str();
  decide->add_option("--metric,--metrics", d->metric, "A metric or a weighted sum (0.5*pc+0.5*vg)")
      ->check(utilityText(false, false))
      ->capture_default_str();
  decide->add_option("--weighting", d->weighting, "normalized or raw (see nbv reconstruct --help)")
      ->check(CLI::IsMember({"normalized", "raw"}))
      ->capture_default_str();
  decide->add_option("--rays", d->rays, std::string("Ray set: ") + sensor::PixelSampling::kNamesHelp)
      ->check(raySetName())
      ->capture_default_str();
  addOptionFlags(*decide, planner::decideOptions(), d->options);
  decide->add_option("--max-rays", d->max_rays, "Stop after casting this many rays")->check(CLI::Range(std::uint64_t{1}, ~std::uint64_t{0}));
  decide->add_option("--seed", d->seed, "Seed of the samples")->capture_default_str();
  decide->add_option("--threads", d->threads, "Threads (default: all cores)")->check(CLI::Range(1, 1 << 20));
  decide->add_option("--visibility", d->visibility, "paper (Eq. 5) or released")
      ->check(visibilityName())
      ->capture_default_str();
  decide->add_flag("--check", d->check, "Also evaluate every candidate on every ray and compare");
  decide->add_option("--json", d->json, "Write the decision as JSON (every candidate's estimate and interval; -: standard output)");
  decide->callback([d] { runDecide(*d); });

  auto w = std::make_shared<WorkloadCommand>();
  std::string workloads_help;
  for (const planner::WorkloadRow& row : planner::kWorkloadTable) {
    workloads_help += "\n  " + std::string(row.name) + ": " + std::string(row.description);
  }
  CLI::App* workload = app.add_subcommand(
      "workload", "Build a standard workload (its map and views; docs/SEMANTICS.md, \"Standard workloads\" and \"Real-scale "
                  "workloads\").");
  workload->add_option("--name", w->name, "Workload:" + workloads_help)->required()->check(CLI::IsMember(planner::workloadNames()));
  workload->add_option("--seed", w->seed, "Seed of the scene and the scans (the standard workload: the default)")
      ->capture_default_str();
  workload->add_option("--map", w->map, "Output map (.vdb, .ot or .bt)")->required();
  workload->add_option("--views", w->views, "Output view file of the candidates (optional)");
  workload->callback([w] { runWorkload(*w); });
}

}  // namespace nbv::apps
