#include "ig_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/information_gain.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/grid/reference_evaluator.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <CLI/CLI.hpp>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
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
  std::size_t max_snapshot_mb = grid::EvaluateOptions{}.max_snapshot_bytes >> 20;
  std::string csv;
};

/// "all" or a comma-separated list of short names.
std::vector<grid::Metric> parseMetrics(const std::string& text) {
  if (text == "all") return {kernels::kAllMetrics.begin(), kernels::kAllMetrics.end()};
  std::vector<grid::Metric> metrics;
  std::stringstream list(text);
  std::string name;
  while (std::getline(list, name, ',')) {
    metrics.push_back(metricNamed(name));
  }
  if (metrics.empty()) throw nbv::InvalidArgument("'" + text + "' names no metric");
  return metrics;
}

/// One row per view: its index, then one column per metric, at full double precision.
void writeCsv(const fs::path& path, const grid::IgTable& table) {
  std::ofstream out(path);
  if (!out) throw nbv::FileError(path, "cannot write");
  out << "view";
  for (grid::Metric metric : table.metrics) out << ',' << kernels::metricName(metric);
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

/// PC and VG read proximity marks, which .ot and .bt files do not carry: say so once.
void warnIfNoMarks(const EvaluateCommand& c, const grid::EvaluateOptions& options) {
  const grid::MapFormat format = grid::mapFormatFromPath(c.map);
  const bool reads_marks = std::any_of(options.metrics.begin(), options.metrics.end(), [](grid::Metric m) {
    return m == grid::Metric::ProximityCount || m == grid::Metric::AreaFactor;
  });
  if (format != grid::MapFormat::Vdb && reads_marks) {
    std::fprintf(stderr,
                 "nbv: warning: %s has no proximity marks (OctoMap files do not carry them), so pc is 0 for every "
                 "view and vg finds no occplane ray; integrate the scans into a .vdb map (nbv integrate --map "
                 "MAP.vdb) to get them\n",
                 c.map.c_str());
  }
}

void runEvaluate(const EvaluateCommand& c) {
  checkWritable(c.csv);
  grid::EvaluateOptions options;
  options.metrics = parseMetrics(c.metrics);
  options.visibility = c.visibility == "released" ? grid::Visibility::Released : grid::Visibility::Paper;
  options.max_ray_depth = c.max_ray_depth;
  options.max_snapshot_bytes = c.max_snapshot_mb << 20;
  options.random_seed = c.seed;
  if (c.isa != "auto") {
    options.isa = kernels::isaFromName(c.isa);
    if (!kernels::isaAvailable(*options.isa)) {
      throw nbv::InvalidArgument("--isa " + c.isa + ": not available here (this CPU lacks it, or nbv was built without it)");
    }
  }
  options.validate();
  const sensor::PinholeCamera camera;
  const std::vector<Eigen::Vector3d> directions =
      sensor::rayDirectionsCamera(camera, sensor::PixelSampling::fromName(c.rays));
  std::vector<Eigen::Isometry3d> poses;
  for (const planner::View& view : viewspace(c.views)) poses.push_back(view.T_world_camera);
  const grid::OccupancyMap map = grid::loadMap(c.map);
  warnIfNoMarks(c, options);

  const int threads = c.reference ? 1 : (c.threads > 0 ? c.threads : tbb::info::default_concurrency());
  const auto start = std::chrono::steady_clock::now();
  grid::IgTable table;
  if (c.reference) {
    table = grid::ReferenceEvaluator(map).evaluate(poses, directions, options);
  } else {
    tbb::task_arena arena(threads);
    arena.execute([&] { table = grid::IgEvaluator().evaluate(map, poses, directions, options); });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  writeAtomically(c.csv, [&](const fs::path& temporary) { writeCsv(temporary, table); });
  std::printf("%s: %zu views x %zu rays, %zu metrics, %s, %d thread%s: %.3f s (%.1f views/s, %.2f M rays/s, "
              "%.1f M voxels/s)\nwrote %s\n",
              c.map.c_str(), poses.size(), directions.size(), options.metrics.size(),
              c.reference ? "OctoMap reference" : kernels::isaName(options.isa.value_or(kernels::bestIsa())),
              threads, threads == 1 ? "" : "s", seconds, static_cast<double>(poses.size()) / seconds,
              static_cast<double>(table.rays) / seconds * 1e-6, static_cast<double>(table.voxels) / seconds * 1e-6,
              c.csv.c_str());
}

struct WorkloadCommand {
  std::string name;
  std::string map;
  std::string views;
};

void runWorkload(const WorkloadCommand& c) {
  const grid::MapFormat format = grid::mapFormatFromPath(c.map);  // refuse a bad extension first
  checkWritable(c.map);
  if (!c.views.empty()) checkWritable(c.views);
  const planner::Workload workload = planner::makeWorkload(c.name, modelsDir());
  writeAtomically(c.map, [&](const fs::path& temporary) { grid::saveMap(workload.map, temporary, format); });
  std::printf("%s: %zu measured voxels, %zu marked; wrote %s\n", c.name.c_str(), workload.map.measuredCount(),
              workload.map.markedCount(), c.map.c_str());
  if (!c.views.empty()) {
    writeAtomically(c.views, [&](const fs::path& temporary) { planner::saveViews(temporary, workload.candidates); });
    std::printf("wrote %zu candidate views to %s\n", workload.candidates.size(), c.views.c_str());
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
  evaluate->add_option("--metrics,--metric", c->metrics, "all, or a comma-separated list of: entropy, oa, uv, rsv, "
                                                         "rse, pc, vg, kr, random")
      ->check(checkedBy("", [](const std::string& text) { parseMetrics(text); }))
      ->capture_default_str();
  evaluate->add_option("--rays", c->rays, "Ray set: released (950 rays), full (360,960) or a pixel stride")
      ->check(raySetName())
      ->capture_default_str();
  evaluate->add_option("--threads", c->threads, "Threads (default: all cores)")->check(CLI::Range(1, 1 << 20));
  evaluate->add_flag("--reference", c->reference, "Use the OctoMap reference evaluator (one thread)");
  evaluate->add_option("--visibility", c->visibility, "paper (Eq. 5) or released (the released code's P_o)")
      ->check(CLI::IsMember({"paper", "released"}))
      ->capture_default_str();
  evaluate->add_option("--isa", c->isa, "Instruction set of the fast evaluator")
      ->check(CLI::IsMember({"auto", "avx512", "avx2", "scalar"}))
      ->capture_default_str();
  evaluate->add_option("--max-ray-depth", c->max_ray_depth, "Ray length [m]")->check(positiveNumber())->capture_default_str();
  evaluate->add_option("--seed", c->seed, "Seed of the random metric")->capture_default_str();
  evaluate->add_option("--max-snapshot-mb", c->max_snapshot_mb, "Refuse a map whose IG snapshot needs more memory [MiB]")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 30))
      ->capture_default_str();
  evaluate->add_option("--csv", c->csv, "Output CSV: view, then one column per metric")->required();
  evaluate->callback([c] { runEvaluate(*c); });

  auto w = std::make_shared<WorkloadCommand>();
  CLI::App* workload = app.add_subcommand("workload", "Build a standard workload (its map and views; docs/SEMANTICS.md, \"Standard workloads\").");
  workload->add_option("--name", w->name, "Workload: bunny-3")->required()->check(CLI::IsMember({"bunny-3"}));
  workload->add_option("--map", w->map, "Output map (.vdb, .ot or .bt)")->required();
  workload->add_option("--views", w->views, "Output view file of the candidates (optional)");
  workload->callback([w] { runWorkload(*w); });
}

}  // namespace nbv::apps
