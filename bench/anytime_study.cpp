// Anytime decisions against exhaustive ones, side by side on the same maps (docs/performance-log.md,
// "Anytime decisions"):
//
//   nbv_anytime_study decisions [--models bunny,...] [--iterations N] [--seeds S] [--rays full]
//                               [--utilities pc,vg,...] [--epsilon 0.01]
//       Along reconstructions (the exhaustive argmax drives them, so both decide on the same
//       maps) and on bunny-3: per model and utility, the seconds per decision of each, the rays
//       the anytime decision casts as a share of the exhaustive count, how often its view is
//       within epsilon of the exact best, how often it is the same view, and the share of the
//       candidates whose exact utility is within epsilon of the best (near ties: to tell them
//       apart, an estimate needs a precision of that order).
//   nbv_anytime_study scaling [--counts 48,500,5000] [--rays full]
//       On bunny-3, Fibonacci spheres of growing size: seconds per decision of each.
//
// Each method has its own evaluator, so each pays its own snapshot refreshes; the anytime
// decider keeps its sample tree across decisions as a planner does. Times are wall seconds at
// the default TBB concurrency (all cores).
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/workloads.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace nbv;

double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Tally {
  std::size_t decisions = 0, within = 0, same = 0;
  double exhaustive_s = 0.0, anytime_s = 0.0, ray_share = 0.0, near_ties = 0.0;
  void print(const std::string& label) const {
    const double n = static_cast<double>(decisions);
    std::printf("| %s | %zu | %.4f | %.4f | %.1fx | %.3f%% | %.3f | %.3f | %.3f |\n", label.c_str(), decisions,
                exhaustive_s / n, anytime_s / n, exhaustive_s / anytime_s, 100.0 * ray_share / n,
                static_cast<double>(within) / n, static_cast<double>(same) / n, near_ties / n);
    std::fflush(stdout);
  }
  void add(const Tally& t) {
    decisions += t.decisions;
    within += t.within;
    same += t.same;
    exhaustive_s += t.exhaustive_s;
    anytime_s += t.anytime_s;
    ray_share += t.ray_share;
    near_ties += t.near_ties;
  }
};

/// The decisions' epsilon (--epsilon; DecideOptions' default 0.01).
double g_epsilon = planner::DecideOptions{}.epsilon;

/// One decision both ways on `map` over `candidates`; adds to `tally`; the exhaustive argmax.
std::size_t decideBoth(ig::IgEvaluator& exhaustive, planner::AnytimeDecider& anytime, const grid::OccupancyMap& map,
                       const std::vector<Eigen::Isometry3d>& candidates, const std::vector<Eigen::Vector3d>& rays,
                       const std::string& utility_text, std::uint64_t seed, Tally& tally) {
  planner::DecisionUtility utility;
  utility.terms = planner::parseMetricSum(utility_text);
  auto start = std::chrono::steady_clock::now();
  exhaustive.refresh(map, ig::snapshotFor(utility.metrics()));
  const ig::IgTable table = exhaustive.evaluate(candidates, rays, {utility.metrics()});
  const std::vector<double> gains = planner::combinedGains(table.values, utility.terms, utility.weighting);
  const std::size_t best = *planner::argmaxFirst(gains);
  tally.exhaustive_s += seconds(start);
  planner::DecideOptions options;  // delta 0.01
  options.epsilon = g_epsilon;
  options.seed = seed;
  start = std::chrono::steady_clock::now();
  anytime.refresh(map, utility);
  const planner::AnytimeDecision d = anytime.decide(candidates, rays, utility, ig::WalkOptions{}, options);
  tally.anytime_s += seconds(start);
  ++tally.decisions;
  tally.ray_share += static_cast<double>(d.rays_cast) / static_cast<double>(d.rays_exhaustive);
  tally.within += gains[d.chosen] >= (1.0 - options.epsilon) * gains[best] ? 1 : 0;
  tally.same += d.chosen == best ? 1 : 0;
  const auto near = std::count_if(gains.begin(), gains.end(), [&](double g) { return g >= (1.0 - options.epsilon) * gains[best]; });
  tally.near_ties += static_cast<double>(near) / static_cast<double>(gains.size());
  return best;
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) items.push_back(item);
  return items;
}

std::string option(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 2; i + 1 < argc; ++i) {
    if (argv[i] == name) return argv[i + 1];
  }
  return fallback;
}

void runDecisions(int argc, char** argv) {
  const std::vector<std::string> models = split(option(argc, argv, "--models", "bunny,armadillo,dragon,dino,head"));
  const std::size_t iterations = std::stoul(option(argc, argv, "--iterations", "10"));
  const std::size_t seeds = std::stoul(option(argc, argv, "--seeds", "2"));
  const auto rays = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::fromName(option(argc, argv, "--rays", "full")));
  const std::vector<std::string> utilities = split(option(argc, argv, "--utilities", "pc,vg,oa,kr,0.5*pc+0.5*vg"));
  g_epsilon = std::stod(option(argc, argv, "--epsilon", std::to_string(g_epsilon)));
  std::printf("| map | decisions | exhaustive s | anytime s | speed-up | rays cast | within epsilon | same view | "
              "candidates within epsilon |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  // bunny-3: the standard workload, every utility, several sample seeds, warm evaluators.
  {
    const planner::Workload w = planner::makeWorkload("bunny-3");
    std::vector<Eigen::Isometry3d> candidates;
    for (const planner::View& v : w.candidates) candidates.push_back(v.T_world_camera);
    for (const std::string& utility : utilities) {
      ig::IgEvaluator exhaustive;
      planner::AnytimeDecider anytime;
      Tally warm_up, tally;
      decideBoth(exhaustive, anytime, w.map, candidates, rays, utility, 1000, warm_up);
      for (std::uint64_t seed = 0; seed < 5; ++seed) decideBoth(exhaustive, anytime, w.map, candidates, rays, utility, seed, tally);
      tally.print("bunny-3, " + utility);
    }
  }
  // Along reconstructions: the exhaustive argmax chooses each next view.
  std::map<std::string, Tally> by_utility;
  for (const std::string& model : models) {
    sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel(model));
    sensor::normalizeMesh(mesh);
    const planner::ReconstructionConfig config;
    const planner::SimulatedObject object(mesh, planner::dome48(), config);
    for (const std::string& utility : utilities) {
      Tally tally;
      for (std::uint64_t seed = 0; seed < seeds; ++seed) {
        grid::OccupancyMap map(config.map);
        ig::IgEvaluator exhaustive;
        planner::AnytimeDecider anytime;
        std::vector<bool> visited(object.viewspace().size(), false);
        std::size_t view = planner::startView(seed, visited.size());
        for (std::size_t it = 1; it < iterations; ++it) {
          visited[view] = true;
          map.integrate(object.scan(view).points_world, object.viewspace()[view].T_world_camera.translation().cast<float>());
          std::vector<Eigen::Isometry3d> candidates;
          std::vector<std::size_t> index;
          for (std::size_t v = 0; v < visited.size(); ++v) {
            if (visited[v]) continue;
            candidates.push_back(object.viewspace()[v].T_world_camera);
            index.push_back(v);
          }
          view = index[decideBoth(exhaustive, anytime, map, candidates, rays, utility, 17 * seed + it, tally)];
        }
      }
      tally.print(model + ", " + utility);
      by_utility[utility].add(tally);
    }
  }
  for (const std::string& utility : utilities) by_utility[utility].print("all models, " + utility);
}

void runScaling(int argc, char** argv) {
  const planner::Workload w = planner::makeWorkload("bunny-3");
  const auto rays = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling::fromName(option(argc, argv, "--rays", "full")));
  std::printf("| candidates | utility | exhaustive s | anytime s | speed-up | rays cast | same view |\n|---:|---|---:|---:|---:|---:|---:|\n");
  for (const std::string& count : split(option(argc, argv, "--counts", "48,500,5000"))) {
    const auto views = planner::fibonacciSphere(std::stoul(count), 0.6, Eigen::Vector3d(0.0, 0.0, 0.25));
    std::vector<Eigen::Isometry3d> candidates;
    for (const planner::View& v : views) candidates.push_back(v.T_world_camera);
    for (const std::string& utility : {std::string("pc"), std::string("kr")}) {
      ig::IgEvaluator exhaustive;
      planner::AnytimeDecider anytime;
      Tally warm_up, tally;
      decideBoth(exhaustive, anytime, w.map, {candidates.begin(), candidates.begin() + 1}, rays, utility, 1, warm_up);
      decideBoth(exhaustive, anytime, w.map, candidates, rays, utility, 0, tally);
      std::printf("| %s | %s | %.3f | %.3f | %.1fx | %.3f%% | %s |\n", count.c_str(), utility.c_str(), tally.exhaustive_s,
                  tally.anytime_s, tally.exhaustive_s / tally.anytime_s, 100.0 * tally.ray_share,
                  tally.same == 1 ? "yes" : "no");
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "decisions") {
      runDecisions(argc, argv);
    } else if (mode == "scaling") {
      runScaling(argc, argv);
    } else {
      std::fprintf(stderr, "usage: nbv_anytime_study decisions|scaling [options] (see the file's head)\n");
      return 2;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "nbv_anytime_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
