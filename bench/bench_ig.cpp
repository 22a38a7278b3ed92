// Information gain on the standard workload bunny-3 (SEMANTICS.md "Standard workloads"): the fast evaluator at 1 and 2
// threads and the OctoMap reference evaluator at 1 thread, in one run, with views/s, rays/s,
// voxel visits/s and seconds per voxel visit. Needs `make models`. The fast rows name their
// instruction set; all metrics at once at 1 thread run with every one this CPU has.
//
// `workload/NAME/...`: the same side by side on bunny-3 and the real-scale workloads
// (SEMANTICS.md "Real-scale workloads": room-2cm, building-8cm, building-5cm), the paper's nine
// metrics on the workload's ray length: the first call of a new evaluator (its refresh apart),
// the released rays on every candidate and the full set on every k-th, fast (every ISA at 1
// thread, the best at 2) and the reference.
//
// Ray sets: `released` (950 rays per view, all 48 views) and `full` (360,960 rays per view).
// The reference takes ~6 s per full view, so the full-set comparison uses every 8th view
// (6 views) for both evaluators; the fast evaluator also runs all 48 full views.
// `along_scans/NAME`: a planner beside a mapping thread along room-2cm's and building-8cm's scans.
// Besides: the snapshot's rebuild, a decision right after each scan of a reconstruction, and
// IgEvaluator::visibleVoxels (released rays from 48 views, one by one and as one path; the full
// set from 6).
#include "nbv/ig/evaluator.hpp"
#include "nbv/ig/map_snapshot.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/ig/shared_map.hpp"
#include "nbv/planner/anytime.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using nbv::ig::Metric;

struct Bunny3 {
  nbv::planner::Workload workload = nbv::planner::makeWorkload("bunny-3");
  std::vector<Eigen::Isometry3d> all_views, every_8th_view;
  std::unique_ptr<nbv::ig::ReferenceEvaluator> reference;
  Bunny3() {
    for (std::size_t i = 0; i < workload.candidates.size(); ++i) {
      all_views.push_back(workload.candidates[i].T_world_camera);
      if (i % 8 == 0) every_8th_view.push_back(workload.candidates[i].T_world_camera);
    }
    reference = std::make_unique<nbv::ig::ReferenceEvaluator>(workload.map);
  }
};

const Bunny3& bunny3() {
  static const Bunny3 instance;
  return instance;
}

/// A standard workload of SEMANTICS.md "Real-scale workloads" (or bunny-3), built once when a
/// row first needs it: its candidates, every k-th of them for the full ray set (the
/// reference's full views take seconds each), and the reference evaluator on its map.
struct WorkloadData {
  nbv::planner::Workload workload;
  std::vector<Eigen::Isometry3d> all_views, full_views;
  std::unique_ptr<nbv::ig::ReferenceEvaluator> reference;
  WorkloadData(const std::string& name, std::size_t full_every) : workload(nbv::planner::makeWorkload(name)) {
    for (std::size_t i = 0; i < workload.candidates.size(); ++i) {
      all_views.push_back(workload.candidates[i].T_world_camera);
      if (i % full_every == 0) full_views.push_back(workload.candidates[i].T_world_camera);
    }
    reference = std::make_unique<nbv::ig::ReferenceEvaluator>(workload.map);
  }
};

/// The workloads of the side-by-side rows: name and the step between full-set views.
const std::vector<std::pair<std::string, std::size_t>> kWorkloadRows = {
    {"bunny-3", 8}, {"room-2cm", 12}, {"building-8cm", 49}, {"building-5cm", 49}};

const WorkloadData& workloadData(const std::string& name) {
  static std::map<std::string, std::unique_ptr<WorkloadData>> built;
  auto& data = built[name];
  if (!data) {
    for (const auto& [row, every] : kWorkloadRows) {
      if (row == name) data = std::make_unique<WorkloadData>(name, every);
    }
  }
  return *data;
}

/// The paper's nine metrics, as the workload rows score them: the metric table's rows up to
/// `random` (the counting formulations follow it).
const std::vector<Metric> kPaperMetrics(nbv::kernels::kAllMetrics.begin(),
                                        std::find(nbv::kernels::kAllMetrics.begin(), nbv::kernels::kAllMetrics.end(),
                                                  Metric::Random) + 1);

std::vector<Eigen::Vector3d> raySet(const std::string& name) {
  return nbv::sensor::rayDirectionsCamera(nbv::sensor::PinholeCamera{}, nbv::sensor::PixelSampling::fromName(name));
}

void setCounters(benchmark::State& state, const nbv::ig::IgTable& table, std::size_t views) {
  using benchmark::Counter;
  state.counters["views/s"] = Counter(static_cast<double>(views), Counter::kIsIterationInvariantRate);
  state.counters["rays/s"] = Counter(static_cast<double>(table.rays), Counter::kIsIterationInvariantRate);
  state.counters["visits/s"] = Counter(static_cast<double>(table.voxels), Counter::kIsIterationInvariantRate);
  state.counters["s/visit"] =
      Counter(static_cast<double>(table.voxels), Counter::kIsIterationInvariantRate | Counter::kInvert);
}

/// Times the fast evaluator on `views` of `map`, `threads` in a task arena. The snapshot is
/// built and the rays ordered before timing, by an evaluation of no view (a planner keeps its
/// evaluator: it refreshes only what changed in the map, and orders its ray set once); each
/// iteration then decides again: a refresh (nothing changed), then the walk.
nbv::ig::IgTable timeFast(benchmark::State& state, const nbv::grid::OccupancyMap& map,
                          std::span<const Eigen::Isometry3d> views, const std::vector<Eigen::Vector3d>& directions,
                          const std::vector<Metric>& metrics, const nbv::ig::WalkOptions& walk, int threads) {
  const nbv::ig::TableOptions options{metrics};
  const nbv::ig::SnapshotOptions snapshot = nbv::ig::snapshotFor(metrics);
  nbv::ig::IgEvaluator evaluator;
  tbb::task_arena arena(threads);
  nbv::ig::IgTable table;
  arena.execute([&] {
    evaluator.refresh(map, snapshot);
    table = evaluator.evaluate({}, directions, options, walk);
  });
  for (auto _ : state) {
    arena.execute([&] {
      evaluator.refresh(map, snapshot);
      table = evaluator.evaluate(views, directions, options, walk);
    });
  }
  return table;
}

/// The fast evaluator on bunny-3 with instruction set `isa`.
void fast(benchmark::State& state, std::string rays, bool all_views, std::vector<Metric> metrics, int threads,
          nbv::kernels::Isa isa) {
  const Bunny3& b = bunny3();
  const auto& views = all_views ? b.all_views : b.every_8th_view;
  nbv::ig::WalkOptions walk;
  walk.isa = isa;
  setCounters(state, timeFast(state, b.workload.map, views, raySet(rays), metrics, walk, threads), views.size());
}

/// The fast evaluator on a workload's views (all, or the full set's), on the workload's ray length.
void fastOn(benchmark::State& state, std::string name, std::string rays, int threads, nbv::kernels::Isa isa) {
  const WorkloadData& w = workloadData(name);
  const auto& views = rays == "full" ? w.full_views : w.all_views;
  nbv::ig::WalkOptions walk;
  walk.isa = isa;
  walk.max_ray_depth = w.workload.max_ray_depth_m;
  setCounters(state, timeFast(state, w.workload.map, views, raySet(rays), kPaperMetrics, walk, threads), views.size());
  state.counters["s/view"] = benchmark::Counter(static_cast<double>(views.size()),
                                                benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// The OctoMap reference evaluator on the same views and rays.
void referenceOn(benchmark::State& state, std::string name, std::string rays) {
  const WorkloadData& w = workloadData(name);
  const auto& views = rays == "full" ? w.full_views : w.all_views;
  const auto directions = raySet(rays);
  nbv::ig::EvaluateOptions options;
  options.table.metrics = kPaperMetrics;
  options.walk.max_ray_depth = w.workload.max_ray_depth_m;
  nbv::ig::IgTable table;
  for (auto _ : state) table = w.reference->evaluate(views, directions, options);
  setCounters(state, table, views.size());
  state.counters["s/view"] = benchmark::Counter(static_cast<double>(views.size()),
                                                benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// A first evaluation: a new evaluator refreshes its snapshot from the workload's map and
/// scores every candidate on the released rays, `threads` in a task arena; counters give the
/// refresh's and the walk's share and the refresh per million measured voxels. (In a new
/// process the first call also pays the page faults of memory this one may reuse: the command
/// line's figure is in docs/PERFORMANCE.md.)
void firstCall(benchmark::State& state, std::string name, int threads) {
  const WorkloadData& w = workloadData(name);
  const auto directions = raySet("released");
  const nbv::ig::TableOptions options{kPaperMetrics};
  nbv::ig::WalkOptions walk;
  walk.max_ray_depth = w.workload.max_ray_depth_m;
  tbb::task_arena arena(threads);
  double refresh_s = 0.0, evaluate_s = 0.0, calls = 0.0;
  std::size_t snapshot_bytes = 0;
  for (auto _ : state) {
    arena.execute([&] {
      nbv::ig::IgEvaluator evaluator;
      const auto start = std::chrono::steady_clock::now();
      snapshot_bytes = evaluator.refresh(w.workload.map, nbv::ig::snapshotFor(kPaperMetrics)).bytes;
      const auto refreshed = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(evaluator.evaluate(w.all_views, directions, options, walk));
      refresh_s += std::chrono::duration<double>(refreshed - start).count();
      evaluate_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - refreshed).count();
      calls += 1.0;
    });
  }
  const double measured_millions = static_cast<double>(w.workload.map.measuredCount()) * 1e-6;
  state.counters["refresh_ms"] = 1e3 * refresh_s / calls;
  state.counters["evaluate_ms"] = 1e3 * evaluate_s / calls;
  state.counters["refresh_ms/Mvoxel"] = 1e3 * refresh_s / calls / measured_millions;
  state.counters["snapshot_MB"] = static_cast<double>(snapshot_bytes) * 1e-6;
  state.counters["map_MB"] = static_cast<double>(w.workload.map.memoryBytes()) * 1e-6;
}

void reference(benchmark::State& state, std::string rays, bool all_views, std::vector<Metric> metrics) {
  const Bunny3& b = bunny3();
  const auto& views = all_views ? b.all_views : b.every_8th_view;
  const auto directions = raySet(rays);
  nbv::ig::EvaluateOptions options;
  options.table.metrics = metrics;
  nbv::ig::IgTable table;
  for (auto _ : state) table = b.reference->evaluate(views, directions, options);
  setCounters(state, table, views.size());
}

/// The fast evaluator's snapshot of bunny-3 built from scratch: the palette, the dense box and
/// its run distances (a planner refreshes most of the box after each scan).
void snapshotRebuild(benchmark::State& state) {
  const Bunny3& b = bunny3();
  const nbv::kernels::VoxelModel model;
  std::size_t voxels = 0;
  for (auto _ : state) {
    nbv::ig::MapSnapshot snapshot;
    snapshot.update(b.workload.map, model, std::size_t{1} << 31);
    const nbv::kernels::SnapshotView view = snapshot.view();
    voxels = std::size_t{view.size[0]} * view.size[1] * view.size[2];
    benchmark::DoNotOptimize(view.voxels);
  }
  state.counters["voxels"] = static_cast<double>(voxels);
  state.counters["voxels/s"] =
      benchmark::Counter(static_cast<double>(voxels), benchmark::Counter::kIsIterationInvariantRate);
}

/// IgEvaluator::visibleVoxels on bunny-3 (a planner scoring a path of views with each voxel
/// counted once): the released rays from each of the 48 views, or the full set from every 8th,
/// one call per view, or the 48 views as one path in one call; `threads` in a task arena;
/// counters give the seconds per view and per ray visit.
void visibleVoxels(benchmark::State& state, std::string rays, bool all_views, bool path, int threads) {
  const Bunny3& b = bunny3();
  const auto& views = all_views ? b.all_views : b.every_8th_view;
  const auto directions = raySet(rays);
  nbv::ig::IgEvaluator evaluator;
  tbb::task_arena arena(threads);
  arena.execute([&] { evaluator.refresh(b.workload.map); });
  std::size_t visits = 0, voxels = 0;
  const auto count = [&](const std::vector<nbv::ig::VisibleVoxel>& reached) {
    voxels += reached.size();
    for (const nbv::ig::VisibleVoxel& v : reached) visits += v.rays;
  };
  for (auto _ : state) {
    visits = voxels = 0;
    arena.execute([&] {
      if (path) {
        count(evaluator.visibleVoxels(views, directions));
      } else {
        for (const Eigen::Isometry3d& view : views) count(evaluator.visibleVoxels(std::span(&view, 1), directions));
      }
    });
  }
  using benchmark::Counter;
  const auto per = Counter::kIsIterationInvariantRate | Counter::kInvert;
  state.counters["s/view"] = Counter(static_cast<double>(views.size()), per);
  state.counters["s/visit"] = Counter(static_cast<double>(visits), per);
  state.counters["voxels/call"] = static_cast<double>(voxels) / (path ? 1.0 : static_cast<double>(views.size()));
}

/// A decision right after a scan, along a reconstruction: the bunny scanned from the views a
/// Proximity Count run of seed 0 visits (20 scans); after each scan, the released-ray (or
/// full-ray) decision over the views not yet visited, at 2 threads. Only the decisions are
/// timed (the evaluator refreshes its snapshot from the scan, then walks); counters give the
/// seconds per decision and the share of it spent refreshing.
void decisionAfterScan(benchmark::State& state, std::string rays_name, bool anytime) {
  static const auto run = [] {
    nbv::sensor::TriangleMesh mesh = nbv::sensor::loadMesh(nbv::sensor::resolveModel("bunny"));
    nbv::sensor::normalizeMesh(mesh);
    nbv::planner::ReconstructionConfig config;
    auto object = std::make_shared<nbv::planner::SimulatedObject>(mesh, nbv::planner::dome48(), config);
    std::vector<std::size_t> path;
    for (const auto& it : nbv::planner::reconstruct(*object, config).iterations) path.push_back(it.view);
    return std::make_pair(object, path);
  }();
  const auto& [object, path] = run;
  const std::vector<Eigen::Vector3d> rays = raySet(rays_name);
  const nbv::planner::DecisionUtility pc;  // Proximity Count
  const nbv::ig::TableOptions options{pc.metrics()};
  tbb::task_arena arena(2);
  double decisions = 0.0, refresh_s = 0.0;
  for (auto _ : state) {
    nbv::grid::OccupancyMap map;
    nbv::planner::AnytimeDecider decider;
    std::vector<bool> visited(object->viewspace().size(), false);
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
      state.PauseTiming();
      visited[path[i]] = true;
      map.integrate(object->scan(path[i]).points_world, object->viewspace()[path[i]].T_world_camera.translation().cast<float>());
      std::vector<Eigen::Isometry3d> candidates;
      for (std::size_t v = 0; v < visited.size(); ++v) {
        if (!visited[v]) candidates.push_back(object->viewspace()[v].T_world_camera);
      }
      state.ResumeTiming();
      arena.execute([&] {
        const auto start = std::chrono::steady_clock::now();
        decider.refresh(map, pc);
        refresh_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (anytime) {
          benchmark::DoNotOptimize(decider.decide(candidates, rays, pc));
        } else {
          benchmark::DoNotOptimize(decider.evaluator().evaluate(candidates, rays, options));
        }
      });
      decisions += 1.0;
    }
  }
  using benchmark::Counter;
  state.counters["s/decision"] = Counter(decisions, Counter::kIsRate | Counter::kInvert);
  state.counters["refresh_s/decision"] = Counter(refresh_s / decisions);
}

/// A planner beside a mapping thread along a workload's scans (SEMANTICS.md "Real-scale
/// workloads"): the scans go one by one into a SharedMap (untimed), and after each the planner
/// refreshes its snapshot from it and decides among the workload's candidates on the released
/// rays, 2 threads: an anytime decision by Proximity Count, or (exhaustive) a table of oa and
/// pc. Counters: the first decision (refresh included), the later ones' mean, and the refresh's
/// mean share of those.
void alongScans(benchmark::State& state, std::string name, bool anytime) {
  const WorkloadData& w = workloadData(name);
  static std::map<std::string, std::vector<nbv::planner::WorkloadScan>> replayed;
  std::vector<nbv::planner::WorkloadScan>& scans = replayed[name];
  const nbv::planner::WorkloadRow& row = nbv::planner::workloadRow(name);
  if (scans.empty()) {
    row.scans(nbv::sensor::modelSearchPath(), nbv::planner::kDefaultWorkloadSeed,
              [&](const nbv::planner::WorkloadScan& scan) { scans.push_back(scan); });
  }
  const auto rays = raySet("released");
  const nbv::planner::DecisionUtility pc;
  const nbv::ig::TableOptions two_metrics{{Metric::OcclusionAware, Metric::ProximityCount}};
  nbv::ig::WalkOptions walk;
  walk.max_ray_depth = w.workload.max_ray_depth_m;
  tbb::task_arena arena(2);
  double first_s = 0.0, later_s = 0.0, later_refresh_s = 0.0, runs = 0.0, later = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    nbv::ig::SharedMap map{nbv::grid::OccupancyMap(row.config)};
    nbv::planner::AnytimeDecider decider;
    state.ResumeTiming();
    for (std::size_t i = 0; i < scans.size(); ++i) {
      state.PauseTiming();
      map.integrate(scans[i].points_world, scans[i].origin_world);
      state.ResumeTiming();
      const auto start = std::chrono::steady_clock::now();
      double refresh_s = 0.0;
      arena.execute([&] {
        map.refresh(decider.evaluator(), nbv::ig::snapshotFor(anytime ? pc.metrics() : two_metrics.metrics));
        refresh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (anytime) {
          benchmark::DoNotOptimize(decider.decide(w.all_views, rays, pc, walk));
        } else {
          benchmark::DoNotOptimize(decider.evaluator().evaluate(w.all_views, rays, two_metrics, walk));
        }
      });
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (i == 0) {
        first_s += s;
      } else {
        later_s += s;
        later_refresh_s += refresh_s;
        later += 1.0;
      }
    }
    runs += 1.0;
  }
  state.counters["first_ms"] = 1e3 * first_s / runs;
  state.counters["later_ms"] = 1e3 * later_s / later;
  state.counters["later_refresh_ms"] = 1e3 * later_refresh_s / later;
  state.counters["scans"] = static_cast<double>(scans.size());
}

/// The rows of the workloads side by side: per workload the first call (1 and 2 threads), the
/// released rays on every candidate and the full set on every k-th (fast with every ISA at 1
/// thread, the best at 2; the reference), the paper's nine metrics.
void registerWorkloads() {
  const nbv::kernels::Isa best = nbv::kernels::bestIsa();
  for (const auto& [name, every] : kWorkloadRows) {
    const std::string prefix = "workload/" + name;
    for (int threads : {1, 2}) {
      benchmark::RegisterBenchmark((prefix + "/first_call/threads:" + std::to_string(threads)).c_str(),
                                   [=](benchmark::State& s) { firstCall(s, name, threads); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(3);
    }
    for (const char* rays : {"released", "full"}) {
      const std::string row = prefix + "/" + rays;
      for (nbv::kernels::Isa isa : nbv::kernels::availableIsas()) {
        for (int threads : {1, 2}) {
          if (threads == 2 && isa != best) continue;
          benchmark::RegisterBenchmark(
              (row + "/fast/" + nbv::kernels::isaName(isa) + "/threads:" + std::to_string(threads)).c_str(),
              [=](benchmark::State& s) { fastOn(s, name, rays, threads, isa); })
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
        }
      }
      benchmark::RegisterBenchmark((row + "/reference").c_str(), [=](benchmark::State& s) { referenceOn(s, name, rays); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(1);
    }
  }
}

void registerAll() {
  registerWorkloads();
  for (const char* name : {"room-2cm", "building-8cm"}) {
    for (const bool anytime : {false, true}) {
      benchmark::RegisterBenchmark((std::string("along_scans/") + name + (anytime ? "/anytime" : "/exhaustive")).c_str(),
                                   [=](benchmark::State& st) { alongScans(st, name, anytime); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(1);
    }
  }
  benchmark::RegisterBenchmark("snapshot/rebuild", snapshotRebuild)->Unit(benchmark::kMillisecond)->UseRealTime();
  for (int threads : {1, 2}) {
    const std::string suffix = "/threads:" + std::to_string(threads);
    const auto add_visible = [&](const std::string& name, const char* rays, bool all_views, bool path) {
      return benchmark::RegisterBenchmark(("visible_voxels/" + name + suffix).c_str(),
                                          [=](benchmark::State& s) { visibleVoxels(s, rays, all_views, path, threads); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    };
    add_visible("released/48views", "released", true, false);
    add_visible("released/48views_as_a_path", "released", true, true);
    add_visible("full/6views", "full", false, false)->Iterations(1);
  }
  for (const char* rays : {"released", "full"}) {
    for (const bool anytime : {false, true}) {
      const std::string name = std::string("decision_after_scan/") + rays + (anytime ? "/anytime" : "/exhaustive");
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) { decisionAfterScan(s, rays, anytime); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(std::string(rays) == "full" && !anytime ? 1 : 3);
    }
  }
  const std::vector<Metric> all(nbv::kernels::kAllMetrics.begin(), nbv::kernels::kAllMetrics.end());
  auto add = [](const std::string& name, auto function) {
    return benchmark::RegisterBenchmark(name.c_str(), function)->Unit(benchmark::kMillisecond)->UseRealTime();
  };
  const nbv::kernels::Isa best = nbv::kernels::bestIsa();
  const auto fast_name = [](const std::string& prefix, nbv::kernels::Isa isa, int threads) {
    return prefix + "/fast/" + nbv::kernels::isaName(isa) + "/threads:" + std::to_string(threads);
  };
  // released: 48 views, every metric alone and all at once; all at once with every ISA.
  for (const auto& [label, metrics] : [&] {
         std::vector<std::pair<std::string, std::vector<Metric>>> sets{{"all", all}};
         for (Metric m : all) sets.push_back({nbv::kernels::metricName(m), {m}});
         return sets;
       }()) {
    const std::string prefix = "released/48views/" + label;
    if (label == "all") {
      for (nbv::kernels::Isa isa : nbv::kernels::availableIsas()) {
        if (isa != best) add(fast_name(prefix, isa, 1), [=](benchmark::State& s) { fast(s, "released", true, metrics, 1, isa); });
      }
    }
    for (int threads : {1, 2}) {
      add(fast_name(prefix, best, threads), [=](benchmark::State& s) { fast(s, "released", true, metrics, threads, best); });
    }
    add(prefix + "/reference", [=](benchmark::State& s) { reference(s, "released", true, metrics); });
  }
  // full: all metrics at once; the reference on 6 views, the fast evaluator on those (with
  // every ISA at 1 thread) and on 48.
  for (nbv::kernels::Isa isa : nbv::kernels::availableIsas()) {
    if (isa != best) {
      add(fast_name("full/6views/all", isa, 1), [=](benchmark::State& s) { fast(s, "full", false, all, 1, isa); })
          ->MinTime(2.0);
    }
  }
  for (int threads : {1, 2}) {
    add(fast_name("full/6views/all", best, threads), [=](benchmark::State& s) { fast(s, "full", false, all, threads, best); })
        ->MinTime(2.0);
    add(fast_name("full/48views/all", best, threads), [=](benchmark::State& s) { fast(s, "full", true, all, threads, best); })
        ->Iterations(2);
  }
  add("full/6views/all/reference", [=](benchmark::State& s) { reference(s, "full", false, all); })->Iterations(1);
  // full, each metric alone, 6 views, 1 thread.
  for (Metric m : all) {
    add(fast_name(std::string("full/6views/") + nbv::kernels::metricName(m), best, 1),
        [=](benchmark::State& s) { fast(s, "full", false, {m}, 1, best); })->Iterations(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  registerAll();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
