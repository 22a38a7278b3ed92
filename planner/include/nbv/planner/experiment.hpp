#pragma once
/// \file The paper's experiment (SEMANTICS.md "Simulation and evaluation"): every (model,
/// metric, trial) reconstruction run side by side, its rows (one per run and iteration) read
/// and written as results.csv, and the paper's Table 1 made from them.

#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace nbv::planner {

/// One reconstruction of an experiment: model `model` (an index into the experiment's
/// models), utility `metric` (a metric or weighted sum, as parseMetricSum reads it), and trial
/// `trial`, which runs with seed `trial`.
struct ExperimentRun {
  std::size_t model = 0;
  std::string metric;
  std::uint64_t trial = 0;
};

/// Every (model, metric, trial) of `models` models, `metrics` and trials 0 .. trials - 1, in
/// that nesting; shard K of N (1 <= K <= N) takes every N-th run from the K-th, so the shards
/// of an experiment are disjoint and together make it whole.
std::vector<ExperimentRun> experimentRuns(std::size_t models, const std::vector<std::string>& metrics,
                                          std::uint64_t trials, std::size_t shard = 1, std::size_t shards = 1);

/// Runs `runs` side by side on `threads` threads (0: every core). The runs of a model share
/// one SimulatedObject of meshes[model] (already placed) over `views`, built from `base`; a
/// run is `base` with its metric and its trial as the seed. `done(i, result)` receives run
/// i's result from the thread that ran it, while other runs go on (so it must be safe to call
/// concurrently), and answers whether to go on: after a false, no further run starts, and
/// those in flight end and go to `done`. `model_done(model, object)` follows the runs of each
/// model that has runs, on the calling thread, unless the experiment stopped. Same inputs: the
/// same results, whatever the thread count (times aside).
/// 	hrows InvalidArgument for a bad configuration, an empty viewspace, an unknown metric or
/// a model index out of range, before any run; the first error of a run or of `done`, once
/// the runs in flight end (no further run starts).
/// A run whose metric is a key of `own_planners` runs that planner of one's own
/// (Planner::Custom); it may be called from several threads at once, one run each.
void runExperiment(std::span<const sensor::TriangleMesh> meshes, const std::vector<View>& views,
                   const ReconstructionConfig& base, std::span<const ExperimentRun> runs, int threads,
                   const std::function<bool(std::size_t run, ReconstructionResult&& result)>& done,
                   const std::function<void(std::size_t model, const SimulatedObject& object)>& model_done = {},
                   const std::map<std::string, CandidateScorer>& own_planners = {});

/// One iteration of one run of an experiment: a line of results.csv.
struct ExperimentRow {
  std::string model;         ///< the model's label
  std::string metric;
  std::uint64_t trial = 0;   ///< the run's seed
  // The columns after these, NBV_ITERATION_FIELDS in order (the run's max_entropy_bits too).
#define NBV_EXPERIMENT_ROW_MEMBER(name, type, kind, help) type name = NBV_ITERATION_INITIAL_##kind;
  NBV_ITERATION_FIELDS(NBV_EXPERIMENT_ROW_MEMBER)
#undef NBV_EXPERIMENT_ROW_MEMBER
};

/// The header line of results.csv: its columns, comma-separated (model, metric, trial, then
/// NBV_ITERATION_FIELDS in order).
std::string resultsCsvHeader();

/// The rows of `result`, run `run` of the model labelled `label`: one per iteration.
std::vector<ExperimentRow> experimentRows(const std::string& label, const ExperimentRun& run,
                                          const ReconstructionResult& result);

/// Puts rows in the canonical order: model, metric (the order of SEMANTICS.md "Volumetric
/// information"; weighted sums after, by name), trial, iteration. A whole experiment and the
/// merge of its shards then list the same rows in the same order.
void sortRows(std::vector<ExperimentRow>& rows);

/// The text of results.csv holding `rows`: a header line, then one line per row.
std::string resultsCsv(const std::vector<ExperimentRow>& rows);
/// Reads a results.csv: each run's iterations 1 to n, each once. \throws nbv::InvalidArgument
/// naming the file and line.
std::vector<ExperimentRow> readResultsCsv(const std::filesystem::path& path);

/// The paper's Table 1 of `rows` (each run's iterations 1 to n, as readResultsCsv() checks)
/// as Markdown: per model and metric, coverage at iterations 2, 4, 6 and 10, coverage AUC and
/// entropy AUC (SEMANTICS.md "Simulation and evaluation"), each as mean +- standard deviation
/// over the trials, and the mean seconds per NBV decision.
std::string table1Markdown(const std::vector<ExperimentRow>& rows);

}  // namespace nbv::planner
