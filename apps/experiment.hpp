#pragma once
/// \file The data of `nbv experiment`: one row per (run, iteration), read and written as CSV,
/// and the paper's Table 1 made from them.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace nbv::apps {

/// One iteration of one run of an experiment.
struct ExperimentRow {
  std::string model;
  std::string metric;
  unsigned trial = 0;        ///< the run's seed
  unsigned iteration = 0;    ///< 1-based
  unsigned view = 0;
  double coverage = 0.0;
  double entropy_bits = 0.0;
  double max_entropy_bits = 0.0;
  double seconds_render = 0.0;
  double seconds_integrate = 0.0;
  double seconds_ig = 0.0;   ///< 0 where no decision followed (the last iteration)
  std::size_t ties = 0;      ///< candidates sharing the best utility; 0 where no decision followed
  double gap = std::numeric_limits<double>::quiet_NaN();  ///< best minus second utility (NaN: none)
  std::uint64_t rays = 0;    ///< rays cast for the decision (0 where none followed)
};

/// Puts rows in the canonical order: model, metric (the order of SEMANTICS.md "Volumetric information"), trial, iteration. A whole
/// experiment and the merge of its shards then list the same rows in the same order.
void sortRows(std::vector<ExperimentRow>& rows);

/// Writes `rows` as results.csv (a header line, then one line per row).
void writeResultsCsv(const std::filesystem::path& path, const std::vector<ExperimentRow>& rows);
/// Reads a results.csv. \throws nbv::InvalidArgument naming the file and line.
std::vector<ExperimentRow> readResultsCsv(const std::filesystem::path& path);

/// The paper's Table 1 as Markdown: per model and metric, coverage at iterations 2, 4, 6 and
/// 10, coverage AUC and entropy AUC (SEMANTICS.md "Simulation and evaluation"), each as mean +- standard deviation over the
/// trials, and the mean seconds per NBV decision.
std::string table1Markdown(const std::vector<ExperimentRow>& rows);

}  // namespace nbv::apps
