#include "planner_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/grid/errors.hpp"
#include "nbv/planner/reconstruction.hpp"

#include <CLI/CLI.hpp>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;

struct ReconstructCommand {
  std::string model;
  std::string metric = "pc";
  std::uint64_t seed = 0;
  std::size_t iterations = 20;
  double gamma = 0.0;
  std::string rays = "released";
  std::string viewspace = "dome48";
  int threads = 0;
  std::string json;
};

/// "pc", or a weighted sum such as "0.5*pc+0.5*vg".
std::vector<planner::MetricWeight> parseMetricSum(const std::string& text) {
  std::vector<planner::MetricWeight> terms;
  std::stringstream list(text);
  std::string term;
  while (std::getline(list, term, '+')) {
    planner::MetricWeight w;
    std::string name = term;
    if (const auto star = term.find('*'); star != std::string::npos) {
      std::size_t used = 0;
      try {
        w.weight = std::stod(term.substr(0, star), &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != star || !std::isfinite(w.weight)) {
        throw grid::InvalidArgument("--metric: bad weight in '" + term + "'");
      }
      name = term.substr(star + 1);
    }
    w.metric = metricNamed(name);
    terms.push_back(w);
  }
  if (terms.empty()) throw grid::InvalidArgument("--metric names no metric");
  return terms;
}

std::string number(double value) {
  if (std::isnan(value)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

void writeJson(const fs::path& path, const ReconstructCommand& c, const planner::ReconstructionResult& r) {
  std::ofstream out(path);
  if (!out) throw grid::InvalidArgument(path.string() + ": cannot write");
  out << "{\n  \"model\": " << quoted(c.model) << ",\n  \"metric\": " << quoted(c.metric)
      << ",\n  \"seed\": " << c.seed << ",\n  \"viewspace\": " << quoted(c.viewspace)
      << ",\n  \"rays\": " << quoted(c.rays) << ",\n  \"gamma\": " << number(c.gamma)
      << ",\n  \"stop\": " << quoted(planner::stopReasonName(r.stop)) << ",\n  \"iterations\": [\n";
  for (std::size_t i = 0; i < r.iterations.size(); ++i) {
    const planner::IterationRecord& it = r.iterations[i];
    out << "    {\"iteration\": " << it.iteration << ", \"view\": " << it.view << ", \"coverage\": " << number(it.coverage)
        << ", \"entropy_bits\": " << number(it.entropy_bits) << ", \"seconds_render\": " << number(it.seconds_render)
        << ", \"seconds_integrate\": " << number(it.seconds_integrate) << ", \"seconds_ig\": " << number(it.seconds_ig)
        << ", \"gains\": [";
    for (std::size_t v = 0; v < it.gains.size(); ++v) out << (v == 0 ? "" : ", ") << number(it.gains[v]);
    out << "]}" << (i + 1 < r.iterations.size() ? "," : "") << "\n";
  }
  out << "  ],\n  \"max_entropy_bits\": " << number(r.max_entropy_bits) << ",\n  \"auc_coverage\": "
      << number(r.auc_coverage) << ",\n  \"auc_entropy\": " << number(r.auc_entropy) << "\n}\n";
  if (!out.flush()) throw grid::InvalidArgument(path.string() + ": write failed");
}

void runReconstruct(const ReconstructCommand& c) {
  planner::ReconstructionConfig config;
  config.metrics = parseMetricSum(c.metric);
  config.seed = c.seed;
  config.max_iterations = c.iterations;
  config.gamma = c.gamma;
  config.rays = sensor::PixelSampling::fromName(c.rays);
  config.validate();
  const std::vector<planner::View> views = viewspace(c.viewspace);
  sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel(c.model, modelsDir()));
  sensor::normalizeMesh(mesh);  // SPEC §5

  const int threads = c.threads > 0 ? c.threads : tbb::info::default_concurrency();
  std::printf("%s, metric %s, seed %llu, %zu views, %s rays, %d thread%s\n", c.model.c_str(), c.metric.c_str(),
              static_cast<unsigned long long>(c.seed), views.size(), c.rays.c_str(), threads, threads == 1 ? "" : "s");
  std::printf("%4s %5s %9s %13s %9s %9s %9s\n", "iter", "view", "coverage", "entropy_bits", "render_s",
              "integr_s", "nbv_s");
  std::fflush(stdout);
  planner::ReconstructionResult result;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    result = planner::reconstruct(mesh, views, config, [](const planner::IterationRecord& r) {
      std::printf("%4zu %5zu %9.4f %13.0f %9.3f %9.3f %9.3f\n", r.iteration, r.view, r.coverage, r.entropy_bits,
                  r.seconds_render, r.seconds_integrate, r.seconds_ig);
      std::fflush(stdout);
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
  if (!c.json.empty()) {
    writeAtomically(c.json, [&](const fs::path& temporary) { writeJson(temporary, c, result); });
    std::printf("wrote %s\n", c.json.c_str());
  }
}

}  // namespace

void addPlannerCommands(CLI::App& app) {
  auto c = std::make_shared<ReconstructCommand>();
  CLI::App* reconstruct = app.add_subcommand(
      "reconstruct", "Reconstruct a model in simulation by next-best views (the paper's Algorithm 1).");
  reconstruct->add_option("--model", c->model, "bunny, armadillo, dragon, dino, head, or a mesh file")->required();
  reconstruct->add_option("--metric", c->metric, "IG metric: entropy, oa, uv, rsv, rse, pc, vg, kr, random, "
                                                 "or a weighted sum such as 0.5*pc+0.5*vg")
      ->capture_default_str();
  reconstruct->add_option("--seed", c->seed, "Seed of the start view and of `random`")->capture_default_str();
  reconstruct->add_option("--iterations", c->iterations, "Scans, the first (random) one included")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  reconstruct->add_option("--gamma", c->gamma, "Cost weight of Eq. 12, in [0, 1]")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  reconstruct->add_option("--rays", c->rays, "IG ray set: released (950 rays), full (360,960) or a pixel stride")
      ->capture_default_str();
  reconstruct->add_option("--viewspace", c->viewspace, "dome48 or a view file")->capture_default_str();
  reconstruct->add_option("--threads", c->threads, "Threads (default: all cores)")->check(CLI::PositiveNumber);
  reconstruct->add_option("--json", c->json, "Write the run as JSON (per iteration: view, coverage, entropy, "
                                             "times, every candidate's IG; AUCs)");
  reconstruct->callback([c] { runReconstruct(*c); });
}

}  // namespace nbv::apps
