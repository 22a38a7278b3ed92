#include "nbv/planner/experiment.hpp"

#include "nbv/errors.hpp"
#include "nbv/fork_join.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/evaluation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string_view>
#include <tuple>
#include <type_traits>

namespace nbv::planner {

namespace {

/// The columns of results.csv: the run's keys, then NBV_ITERATION_FIELDS in order.
constexpr const char* kColumns[] = {
    "model", "metric", "trial",
#define NBV_COLUMN_NAME(name, type, kind, help) #name,
    NBV_ITERATION_FIELDS(NBV_COLUMN_NAME)
#undef NBV_COLUMN_NAME
};
constexpr std::size_t kColumnCount = std::size(kColumns);
/// The columns of the first results.csv (up to gap): a file of an earlier version has these
/// and some of the later ones; the others read as their initial values.
constexpr std::size_t kFirstColumns = 3 + kFirstIterationFields;
static_assert(std::string_view(kColumns[kFirstColumns - 1]) == "gap");

/// The header of a results.csv with its first `columns` columns.
std::string headerOf(std::size_t columns) {
  std::string header;
  for (std::size_t c = 0; c < columns; ++c) {
    if (c > 0) header += ',';
    header += kColumns[c];
  }
  return header;
}

std::size_t metricRank(const std::string& name) {
  const auto metric = kernels::metricFromName(name);
  return metric ? static_cast<std::size_t>(*metric) : kernels::kMetricCount;
}

/// The shortest text that reads back as `value`.
std::string number(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof text, value);
  return error == std::errc{} ? std::string(text, end) : std::string("nan");
}

struct MeanStd {
  double mean = 0.0, stddev = 0.0;
};
MeanStd meanStd(const std::vector<double>& values) {
  MeanStd m;
  if (values.empty()) return m;
  for (double v : values) m.mean += v / static_cast<double>(values.size());
  if (values.size() > 1) {
    double sum = 0.0;
    for (double v : values) sum += (v - m.mean) * (v - m.mean);
    m.stddev = std::sqrt(sum / static_cast<double>(values.size() - 1));
  }
  return m;
}

/// "mean ± std (se s)" over the trials; one trial has no spread, so only its value.
std::string cell(const std::vector<double>& values) {
  if (values.empty()) return "-";
  const MeanStd m = meanStd(values);
  char text[64];
  if (values.size() == 1) {
    std::snprintf(text, sizeof text, "%.3f", m.mean);
  } else {
    const double standard_error = m.stddev / std::sqrt(static_cast<double>(values.size()));
    std::snprintf(text, sizeof text, "%.3f ± %.3f (se %.3f)", m.mean, m.stddev, standard_error);
  }
  return text;
}

/// A field of results.csv as a T: the whole field, a number in range (a double as to_chars
/// writes it, subnormals included). \throws InvalidArgument naming the column and the text.
template <class T>
T parsed(const std::string& text, const char* column) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || text.empty()) {
    throw InvalidArgument(std::string(column) + " '" + text + "' is not " +
                          (std::is_floating_point_v<T> ? "a number" : "a non-negative integer in range"));
  }
  return value;
}

}  // namespace

std::vector<ExperimentRun> experimentRuns(std::size_t models, const std::vector<std::string>& metrics,
                                          std::uint64_t trials, std::size_t shard, std::size_t shards) {
  if (shards == 0 || shard == 0 || shard > shards) {
    throw InvalidArgument("shard " + std::to_string(shard) + "/" + std::to_string(shards) + ": give K/N with 1 <= K <= N");
  }
  std::vector<ExperimentRun> runs;
  std::size_t index = 0;
  for (std::size_t model = 0; model < models; ++model) {
    for (const std::string& metric : metrics) {
      for (std::uint64_t trial = 0; trial < trials; ++trial, ++index) {
        if (index % shards == shard - 1) runs.push_back({model, metric, trial});
      }
    }
  }
  return runs;
}

void runExperiment(std::span<const sensor::TriangleMesh> meshes, const std::vector<View>& views,
                   const ReconstructionConfig& base, std::span<const ExperimentRun> runs, int threads,
                   const std::function<bool(std::size_t, ReconstructionResult&&)>& done,
                   const std::function<void(std::size_t, const SimulatedObject&)>& model_done,
                   const std::map<std::string, CandidateScorer>& own_planners) {
  if (threads < 0) throw InvalidArgument("threads " + std::to_string(threads) + " must be at least 1 (0: every core)");
  // Every run's configuration first, so that a bad one stops the experiment before any work.
  std::vector<ReconstructionConfig> configs;
  for (const ExperimentRun& run : runs) {
    if (run.model >= meshes.size()) {
      throw InvalidArgument("run " + std::to_string(configs.size()) + " is of model " + std::to_string(run.model) +
                            ", but the experiment has " + std::to_string(meshes.size()) + " models");
    }
    ReconstructionConfig& config = configs.emplace_back(base);
    if (const auto own = own_planners.find(run.metric); own != own_planners.end()) {
      config.planner = Planner::Custom;
      config.scorer = own->second;
    } else {
      setPlanner(config, run.metric);
    }
    config.seed = run.trial;
    config.validate();
  }
  tbb::task_arena arena(threads > 0 ? threads : tbb::info::default_concurrency());
  // A decider per thread, kept from run to run (and model to model) so that runs reuse the
  // snapshot's memory; a thread works on one run at a time (the runs are isolated below).
  tbb::enumerable_thread_specific<AnytimeDecider> deciders;
  // A run that throws, or a `done` that answers false, starts no further run; the runs in
  // flight end as they would (no cancellation reaches into them), then the first error is
  // thrown again.
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto run_one = [&](std::size_t i, const SimulatedObject& object) {
    if (stop.load()) return;
    try {
      if (!done(i, reconstruct(object, configs[i], deciders.local()))) stop = true;
    } catch (...) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      stop = true;
    }
  };
  for (std::size_t model = 0; model < meshes.size() && !stop.load(); ++model) {
    std::vector<std::size_t> mine;
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (runs[i].model == model) mine.push_back(i);
    }
    if (mine.empty()) continue;
    // The model's runs share its simulated object (scene, ground truth, scans); each run's
    // result goes to `done` by its index, so any thread count gives the same results.
    std::unique_ptr<SimulatedObject> object;
    arena.execute([&] { object = std::make_unique<SimulatedObject>(meshes[model], views, base); });
    const auto runs_of_range = [&](const tbb::blocked_range<std::size_t>& range) {
      ForkJoin::enter();
      // A thread waiting inside a run takes no other run meanwhile: runs in flight stay as
      // many as the threads, and so does their memory.
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        tbb::this_task_arena::isolate([&] { run_one(mine[k], *object); });
      }
      ForkJoin::leave();
    };
    arena.execute([&] {
      ForkJoin::fork();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mine.size(), 1), runs_of_range, tbb::simple_partitioner());
      ForkJoin::joined();
    });
    if (error) std::rethrow_exception(error);
    if (model_done && !stop.load()) model_done(model, *object);
  }
}

std::vector<ExperimentRow> experimentRows(const std::string& label, const ExperimentRun& run,
                                          const ReconstructionResult& result) {
  std::vector<ExperimentRow> rows;
  for (const IterationRecord& it : result.iterations) {
    ExperimentRow& row = rows.emplace_back();
    row.model = label;
    row.metric = run.metric;
    row.trial = run.trial;
#define NBV_ROW_FROM_RECORD(name, type, kind, help) NBV_ITERATION_IF_RECORD(kind, row.name = it.name;)
    NBV_ITERATION_FIELDS(NBV_ROW_FROM_RECORD)
#undef NBV_ROW_FROM_RECORD
    row.max_entropy_bits = result.max_entropy_bits;
    if (it.gains.empty()) row.seconds_ig = 0.0;  // no decision followed: its time is none
  }
  return rows;
}

void sortRows(std::vector<ExperimentRow>& rows) {
  std::stable_sort(rows.begin(), rows.end(), [](const ExperimentRow& a, const ExperimentRow& b) {
    return std::make_tuple(a.model, metricRank(a.metric), a.metric, a.trial, a.iteration) <
           std::make_tuple(b.model, metricRank(b.metric), b.metric, b.trial, b.iteration);
  });
}

namespace {

/// A field of results.csv: an integer as it is, a number as the shortest text that reads back
/// as it, a Gap's none (NaN) as an empty field.
std::string csvField(std::uint64_t value) { return std::to_string(value); }
std::string csvField(double value) { return std::isnan(value) ? std::string() : number(value); }

}  // namespace

std::string resultsCsvHeader() { return headerOf(kColumnCount); }

std::string resultsCsv(const std::vector<ExperimentRow>& rows) {
  std::ostringstream out;
  out << resultsCsvHeader() << '\n';
  for (const ExperimentRow& r : rows) {
    out << r.model << ',' << r.metric << ',' << r.trial;
#define NBV_CSV_FIELD(name, type, kind, help) out << ',' << csvField(r.name);
    NBV_ITERATION_FIELDS(NBV_CSV_FIELD)
#undef NBV_CSV_FIELD
    out << '\n';
  }
  return out.str();
}

std::vector<ExperimentRow> readResultsCsv(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw nbv::InvalidArgument(path.string() + ": cannot open");
  std::string line;
  std::size_t columns = kColumnCount;  // the columns this file has: all, or the first ones and some later
  const bool header = std::getline(in, line).good() || !line.empty();
  while (header && columns >= kFirstColumns && line != headerOf(columns)) --columns;
  if (!header || columns < kFirstColumns) throw nbv::InvalidArgument(path.string() + ":1: not an nbv results.csv header");
  std::vector<ExperimentRow> rows;
  std::vector<std::size_t> lines;  // each row's line number
  for (std::size_t number_of_line = 2; std::getline(in, line); ++number_of_line) {
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) f.push_back(field);
    if (!line.empty() && line.back() == ',') f.emplace_back();  // an empty last field (no gap)
    try {
      if (f.size() != columns) throw nbv::InvalidArgument("expected " + std::to_string(columns) + " fields");
      ExperimentRow r;
      r.model = f[0];
      r.metric = f[1];
      r.trial = parsed<std::uint64_t>(f[2], kColumns[2]);
      // Each field of the table in its column, if the file has it; a Gap's empty field is none.
      std::size_t column = 3;
#define NBV_CSV_READ(name, type, kind, help)                                          \
  if (column < columns && !(NBV_ITERATION_IS_GAP(kind) && f[column].empty())) { \
    r.name = parsed<type>(f[column], #name);                                          \
  }                                                                                   \
  ++column;
      NBV_ITERATION_FIELDS(NBV_CSV_READ)
#undef NBV_CSV_READ
      if (r.iteration == 0 || !(r.max_entropy_bits > 0.0)) throw InvalidArgument("bad iteration or entropy");
      rows.push_back(r);
      lines.push_back(number_of_line);
    } catch (const std::exception& e) {
      throw nbv::InvalidArgument(path.string() + ":" + std::to_string(number_of_line) + ": " + e.what());
    }
  }
  // Each run's iterations are 1, 2, ..., n, each once, in any order of lines: a curve with a
  // hole or a repeat has no area (Table 1) and would merge wrongly.
  std::map<std::tuple<std::string, std::string, std::uint64_t>, std::vector<std::pair<std::size_t, std::size_t>>> runs;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    runs[{rows[i].model, rows[i].metric, rows[i].trial}].emplace_back(rows[i].iteration, lines[i]);
  }
  for (auto& [run, iterations] : runs) {
    std::sort(iterations.begin(), iterations.end());
    for (std::size_t k = 0; k < iterations.size(); ++k) {
      if (iterations[k].first == k + 1) continue;
      const bool repeated = k > 0 && iterations[k].first == iterations[k - 1].first;
      throw nbv::InvalidArgument(path.string() + ":" + std::to_string(iterations[k].second) + ": " +
                                 std::get<0>(run) + " " + std::get<1>(run) + " trial " + std::to_string(std::get<2>(run)) +
                                 (repeated ? ": iteration " + std::to_string(iterations[k].first) + " again"
                                           : ": iteration " + std::to_string(k + 1) + " is missing"));
    }
  }
  return rows;
}

std::string table1Markdown(const std::vector<ExperimentRow>& rows) {
  // Per (model, metric): per trial, its coverage and entropy curves.
  struct Run {
    std::vector<double> coverage, entropy;
    double max_entropy = 0.0;
    std::vector<double> decision_seconds;
  };
  std::map<std::tuple<std::string, std::size_t, std::string>, std::map<std::uint64_t, Run>> runs;
  for (const ExperimentRow& r : rows) {
    Run& run = runs[{r.model, metricRank(r.metric), r.metric}][r.trial];
    if (run.coverage.size() + 1 != r.iteration) continue;  // rows arrive sorted
    run.coverage.push_back(r.coverage);
    run.entropy.push_back(r.entropy_bits);
    run.max_entropy = r.max_entropy_bits;
    if (r.seconds_ig > 0.0) run.decision_seconds.push_back(r.seconds_ig);
  }
  std::ostringstream md;
  md << "| model | metric | trials | coverage @2 | @4 | @6 | @10 | final coverage | coverage AUC | entropy AUC | "
        "s per NBV |\n"
     << "|---|---|---:|---|---|---|---|---|---|---|---:|\n";
  for (const auto& [key, trials] : runs) {
    std::vector<double> at[4], final_coverage, auc_coverage, auc_entropy, seconds;
    const unsigned marks[4] = {2, 4, 6, 10};
    for (const auto& [trial, run] : trials) {
      for (int k = 0; k < 4; ++k) {
        if (run.coverage.size() >= marks[k]) at[k].push_back(run.coverage[marks[k] - 1]);
      }
      if (!run.coverage.empty()) final_coverage.push_back(run.coverage.back());
      auc_coverage.push_back(planner::areaUnderCurve(run.coverage, 0.0, 1.0));
      auc_entropy.push_back(planner::areaUnderCurve(run.entropy, run.max_entropy, run.max_entropy));
      seconds.insert(seconds.end(), run.decision_seconds.begin(), run.decision_seconds.end());
    }
    char mean_seconds[32] = "-";  // no decision timed (rows written with --no-timings)
    if (!seconds.empty()) std::snprintf(mean_seconds, sizeof mean_seconds, "%.3f", meanStd(seconds).mean);
    md << "| " << std::get<0>(key) << " | " << std::get<2>(key) << " | " << trials.size() << " | " << cell(at[0])
       << " | " << cell(at[1]) << " | " << cell(at[2]) << " | " << cell(at[3]) << " | " << cell(final_coverage)
       << " | " << cell(auc_coverage) << " | " << cell(auc_entropy) << " | " << mean_seconds << " |\n";
  }
  md << "\nCells: mean ± standard deviation over the trials (se: the standard error of the mean, std / "
        "sqrt(trials)); one trial: its value. s per NBV: mean seconds per view decision; - where none was timed "
        "(--no-timings drops the times).\n";
  return md.str();
}

}  // namespace nbv::planner
