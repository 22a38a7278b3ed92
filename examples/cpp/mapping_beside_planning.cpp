// The loop a robot with a depth camera runs: a mapping thread integrates each depth frame as
// it arrives, and a planner thread, after each frame, decides the next best view from the map
// as it stands. The frames come from a TUM RGB-D style folder (depth.txt, groundtruth.txt,
// 16-bit PNGs; `nbv render --tum-out DIR` writes one), replayed at the pace of their timestamps.
//
//   mapping_beside_planning TUM_DIR [--fast] [--depth-scale S] [--camera W H FX FY CX CY]
//
// The two threads share a ig::SharedMap: integrating holds its lock alone for one frame, a
// planner holds it shared only while its evaluator copies what changed (refresh), then decides
// on its own snapshot while the next frame is integrated. A planner slower than the camera
// skips frames (it always decides on the newest map); it never sees half a frame.
#include "nbv/errors.hpp"
#include "nbv/ig/shared_map.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_io.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Arguments {
  std::string folder;
  bool fast = false;
  double depth_scale = 5000.0;
  nbv::sensor::PinholeCamera camera;  // the simulated camera's defaults (752 x 480)
};

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto number = [&](const char* what) {
      if (i + 1 >= argc) throw nbv::InvalidArgument(std::string(what) + " needs a value");
      char* end = nullptr;
      const double value = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0') throw nbv::InvalidArgument(std::string(what) + ": '" + argv[i] + "' is not a number");
      return value;
    };
    if (arg == "--fast") {
      a.fast = true;
    } else if (arg == "--depth-scale") {
      a.depth_scale = number("--depth-scale");
    } else if (arg == "--camera") {
      a.camera.width = static_cast<int>(number("--camera W"));
      a.camera.height = static_cast<int>(number("--camera H"));
      a.camera.fx = number("--camera FX");
      a.camera.fy = number("--camera FY");
      a.camera.cx = number("--camera CX");
      a.camera.cy = number("--camera CY");
    } else if (a.folder.empty() && arg.rfind("--", 0) != 0) {
      a.folder = arg;
    } else {
      throw nbv::InvalidArgument("unknown argument '" + arg + "'");
    }
  }
  if (a.folder.empty()) throw nbv::InvalidArgument("give a TUM RGB-D folder (nbv render --tum-out DIR writes one)");
  a.camera.validate();
  return a;
}

/// What the mapping thread tells the planner: frames integrated so far, and whether it is done.
struct Progress {
  std::mutex mutex;
  std::condition_variable changed;
  std::size_t frames = 0;
  bool done = false;
  std::exception_ptr error;
};

void mapFrames(const Arguments& a, const std::vector<nbv::sensor::TumFrame>& frames, nbv::ig::SharedMap& map,
               Progress& progress) {
  try {
    nbv::grid::DepthOptions depth_options;
    depth_options.scale = a.depth_scale;
    const Clock::time_point start = Clock::now();
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (!a.fast) {  // a camera delivers frame i at its timestamp
        const double due_s = frames[i].timestamp - frames[0].timestamp;
        std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(due_s)));
      }
      const nbv::sensor::DepthPng png = nbv::sensor::readDepthPng16(frames[i].depth_file);
      const nbv::grid::DepthImage depth{png.width, png.height, png.values, {}};
      // Under the progress lock too, so that a planner's refresh (also under it) sees exactly
      // the frames it counts; without the counting, SharedMap's own lock would do.
      const std::lock_guard lock(progress.mutex);
      map.integrateDepth(depth, a.camera, frames[i].T_world_camera, depth_options);
      progress.frames = i + 1;
      progress.changed.notify_one();
    }
  } catch (...) {
    const std::lock_guard lock(progress.mutex);
    progress.error = std::current_exception();
  }
  const std::lock_guard lock(progress.mutex);
  progress.done = true;
  progress.changed.notify_one();
}

/// After each new frame (the newest, when several came meanwhile): refresh the evaluator from
/// the shared map, then decide among the dome's 48 views by Proximity Count on the released
/// rays, with anytime sampling (docs/SEMANTICS.md, "Anytime decisions").
void planAfterFrames(const nbv::ig::SharedMap& map, std::size_t frame_count, Progress& progress) {
  std::vector<Eigen::Isometry3d> candidates;
  for (const nbv::planner::View& view : nbv::planner::dome48()) candidates.push_back(view.T_world_camera);
  const std::vector<Eigen::Vector3d> rays =
      nbv::sensor::rayDirectionsCamera(nbv::sensor::PinholeCamera{}, nbv::sensor::PixelSampling::released());
  nbv::planner::AnytimeDecider decider;
  const nbv::planner::DecisionUtility utility;  // Proximity Count
  const nbv::ig::SnapshotOptions snapshot = nbv::ig::snapshotFor(utility.metrics());  // what pc reads
  std::size_t decided = 0;
  double total_ms = 0.0;
  std::size_t decisions = 0;
  while (true) {
    std::size_t frames = 0;
    Clock::time_point start;
    {
      std::unique_lock lock(progress.mutex);
      progress.changed.wait(lock, [&] { return progress.frames > decided || progress.done; });
      if (progress.frames == decided) break;  // done, and the last frame decided on
      frames = progress.frames;
      start = Clock::now();
      map.refresh(decider.evaluator(), snapshot);  // the map after exactly `frames` frames
    }
    const double refresh_ms = msSince(start);
    const nbv::planner::AnytimeDecision d = decider.decide(candidates, rays, utility);
    const double ms = msSince(start);
    total_ms += ms;
    ++decisions;
    std::printf("after frame %3zu/%zu: next view %2zu (pc %.0f), decided in %6.1f ms (refresh %5.1f ms)%s\n", frames,
                frame_count, d.chosen, d.candidates[d.chosen].estimate, ms, refresh_ms,
                frames > decided + 1 ? "  [skipped frames the planner was too slow for]" : "");
    decided = frames;
  }
  std::printf("%zu decisions, %.1f ms each on average\n", decisions, decisions > 0 ? total_ms / decisions : 0.0);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Arguments a = parse(argc, argv);
    const std::vector<nbv::sensor::TumFrame> frames = nbv::sensor::readTumSequence(a.folder);
    std::printf("%zu depth frames from %s, %s\n", frames.size(), a.folder.c_str(),
                a.fast ? "as fast as they integrate" : "at the pace of their timestamps");
    nbv::ig::SharedMap map;
    Progress progress;
    std::thread mapping([&] { mapFrames(a, frames, map, progress); });
    try {
      planAfterFrames(map, frames.size(), progress);
    } catch (...) {
      mapping.join();  // the sequence runs out; a thread must not outlive its std::thread
      throw;
    }
    mapping.join();
    if (progress.error) std::rethrow_exception(progress.error);
    map.read([](const nbv::grid::OccupancyMap& m) {
      std::printf("map: %zu voxels measured, %zu occupied (P > 0.8), %zu free (P < 0.2)\n", m.measuredCount(),
                  m.occupiedCount(), m.freeCount());
      return 0;
    });
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mapping_beside_planning: %s\n", e.what());
    return 1;
  }
}
