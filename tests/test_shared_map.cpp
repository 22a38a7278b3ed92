// A planner beside a mapping thread (ig::SharedMap): one thread integrates scans while
// another refreshes, evaluates and decides, for many rounds; every table and decision is that
// of some map state between two integrations. Run under ThreadSanitizer by `make tsan`.
#include "nbv/ig/shared_map.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include "scenes.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace nbv {
namespace {

struct Scene {
  std::vector<std::vector<Eigen::Vector3f>> scans;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Isometry3d> candidates;
  std::vector<Eigen::Vector3d> rays = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, sensor::PixelSampling{24, 1.0});
};

Scene scene() {
  Scene s;
  const sensor::RayScene mesh(test::sphereMesh({0.0f, 0.0f, 0.2f}, 0.2f, 24));
  sensor::DepthCameraConfig config;
  config.camera = {188, 120, 112.0, 112.0, 94.0, 60.0};  // a small camera: quick scans
  const sensor::DepthCamera camera(config);
  const std::vector<planner::View> dome = planner::dome48();
  for (const int v : {0, 7, 18, 25, 33, 40}) {
    s.scans.push_back(camera.render(mesh, dome[static_cast<std::size_t>(v)].T_world_camera).points_world);
    s.poses.push_back(dome[static_cast<std::size_t>(v)].T_world_camera);
  }
  for (const planner::View& v : dome) s.candidates.push_back(v.T_world_camera);
  return s;
}

TEST(SharedMapThreads, EveryEvaluationIsOfAMapStateBetweenTwoIntegrations) {
  const Scene s = scene();
  ig::EvaluateOptions options;
  options.table.metrics = {ig::Metric::OcclusionAware, ig::Metric::ProximityCount, ig::Metric::AverageEntropy};
  // The tables of every state: after 0, 1, ..., all scans, each by a fresh evaluator.
  std::vector<std::vector<double>> states;
  std::vector<std::size_t> best_pc;
  {
    grid::OccupancyMap map;
    for (std::size_t k = 0; k <= s.scans.size(); ++k) {
      if (k > 0) map.integrate(s.scans[k - 1], s.poses[k - 1].translation().cast<float>());
      const ig::IgTable table = ig::evaluate(map, s.candidates, s.rays, options);
      states.push_back(table.values);
      std::vector<double> pc;
      for (std::size_t v = 0; v < table.views(); ++v) pc.push_back(table.value(v, 1));
      best_pc.push_back(*planner::argmaxFirst(pc));
    }
  }
  for (int round = 0; round < 4; ++round) {
    ig::SharedMap shared;
    std::atomic<bool> done{false};
    std::thread mapping([&] {
      for (std::size_t k = 0; k < s.scans.size(); ++k) shared.integrate(s.scans[k], s.poses[k].translation().cast<float>());
      done = true;
    });
    ig::IgEvaluator evaluator;
    planner::AnytimeDecider decider;
    planner::DecisionUtility pc;
    planner::DecideOptions exact;
    exact.epsilon = 0.0;
    exact.delta = 1e-9;
    std::size_t evaluations = 0;
    while (true) {
      const bool last = done.load();
      shared.refresh(evaluator, options.snapshotOptions());
      const ig::IgTable table = evaluator.evaluate(s.candidates, s.rays, options.table, options.walk);
      const auto state = std::find(states.begin(), states.end(), table.values);
      ASSERT_NE(state, states.end()) << "round " << round << ": a table of no map state (a torn read)";
      shared.refresh(decider.evaluator(), ig::snapshotFor(pc.metrics()));
      const planner::AnytimeDecision d = decider.decide(s.candidates, s.rays, pc, ig::WalkOptions{}, exact);
      EXPECT_NE(std::find(best_pc.begin(), best_pc.end(), d.chosen), best_pc.end()) << "a decision of no map state";
      ++evaluations;
      if (last) {
        EXPECT_EQ(table.values, states.back()) << "after the last scan: the last state";
        break;
      }
    }
    mapping.join();
    EXPECT_GE(evaluations, 2u);
  }
}

}  // namespace
}  // namespace nbv
