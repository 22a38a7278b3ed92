#pragma once
/// \file An experiment's folder as a sweep keeps it (SEMANTICS.md "Sweeps"): `sweep.json`, the
/// record of the whole sweep the folder belongs to (its models, metrics, seeds, settings,
/// shard K/N and nbv version), and `runs/<index>.json`, one file per finished run, written in
/// full and renamed into place as the run ends, so that a kill loses at most the runs in
/// flight. A resumed sweep runs only the runs without a file, and the folders of the N shards
/// of a sweep merge only when they are the whole sweep, each once.
///
/// Thread-safety: keep() may be called from several threads at once (each run its own file);
/// the rest reads and writes the folder from one thread.

#include "nbv/planner/experiment.hpp"
#include "nbv/planner/reconstruction.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace nbv::planner {

/// Everything that decides a sweep's results, and which shard of it a folder holds.
struct Sweep {
  std::vector<std::string> models;   ///< each as named: a standard name or a mesh file's absolute path
  std::vector<std::string> labels;   ///< each model's label in rows and files
  std::vector<std::string> metrics;  ///< metrics or weighted sums, as parseMetricSum() reads them
  std::vector<std::uint64_t> seeds;  ///< the trials' seeds
  std::string viewspace = "dome48";  ///< or a view file's absolute path
  std::string rays = "released";     ///< "released", "released-shipped", "full" or a pixel stride
  std::string scene = "bare";        ///< the scene's label (sceneLabel())
  std::string up = "z";              ///< the models' up axis ("z", "y" or "auto")
  /// Iterations, weighting, gamma, scene conditions, visibility and anytime options (its
  /// metrics and seed are each run's).
  ReconstructionConfig config;
  bool timings = true;               ///< false: every time written as 0 (--no-timings)
  std::size_t shard = 1, shards = 1; ///< this folder's slice K of N
  std::string version;               ///< the nbv version that ran it

  /// Every run of the whole sweep (all shards), in the order that indexes run files: model,
  /// metric, seed; ExperimentRun::trial is the seed.
  std::vector<ExperimentRun> allRuns() const;
  /// The indices (into allRuns()) of this shard's runs: every N-th from the K-th.
  std::vector<std::size_t> shardRuns() const;
  /// The first field in which `other` is another sweep than this one (shard K aside), as
  /// "metrics (pc,oa against pc)"; empty if they are the same sweep.
  std::string differenceFrom(const Sweep& other) const;
};

/// A run read back from its file.
struct KeptRun {
  std::size_t index = 0;        ///< into Sweep::allRuns()
  ExperimentRun run;            ///< its model, metric and seed
  ReconstructionResult result;  ///< every iteration's record (gains included), stop and AUCs
};

/// The folder of an experiment or of one shard of a sweep.
class ExperimentFolder {
 public:
  /// The folder `dir` for `sweep`: a new or empty folder gets `sweep.json` and `runs/`; a folder
  /// with a `sweep.json` of the same sweep and shard is continued (its kept runs stay) when
  /// `resume` is true; `force` (without `resume`) starts afresh in any folder, its kept runs
  /// dropped. \throws FileError naming the folder if it cannot be made or written, holds other
  /// files, or holds another sweep (naming what differs), or the same one without `resume`
  /// (saying how many runs are kept and how to resume).
  ExperimentFolder(const std::filesystem::path& dir, const Sweep& sweep, bool resume, bool force = false);

  /// The sweep recorded in `dir`/sweep.json. \throws FileError naming the file and what is wrong.
  static Sweep readSweep(const std::filesystem::path& dir);
  /// Whether `dir` holds a sweep record.
  static bool hasSweep(const std::filesystem::path& dir);

  const std::filesystem::path& dir() const { return dir_; }
  const Sweep& sweep() const { return sweep_; }

  /// The runs kept so far, by index. \throws FileError naming a run file that cannot be read.
  std::map<std::size_t, KeptRun> kept() const;
  /// Keeps a finished run: its file is written in full, flushed to disk and renamed into place.
  /// \throws FileError if it cannot be written.
  void keep(std::size_t index, const ReconstructionResult& result) const;

 private:
  std::filesystem::path dir_;
  Sweep sweep_;
};

/// The runs of `folders` (the shards of one sweep), checked to be that whole sweep: every
/// folder records the same sweep (else the folder and the field that differs are named), each
/// shard K of N comes once (a repeated one is named with both folders), none is missing and
/// each holds all its runs (else the missing shards, or the folder and its missing runs, are
/// named), unless `allow_partial`; then `missing` lists what is not there.
struct MergedSweep {
  Sweep sweep;                        ///< the sweep, shard 1/1
  std::map<std::size_t, KeptRun> runs;
  std::vector<std::string> missing;   ///< with allow_partial: "shard 2/3", "shard1: 4 runs", ...
};
MergedSweep mergeShards(const std::vector<std::filesystem::path>& folders, bool allow_partial);

}  // namespace nbv::planner
