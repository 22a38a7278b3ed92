#include "experiment.hpp"

#include "app_support.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

namespace nbv::apps {

namespace {

constexpr const char* kHeader =
    "model,metric,trial,iteration,view,coverage,entropy_bits,max_entropy_bits,seconds_render,"
    "seconds_integrate,seconds_ig,ties,gap,rays";
/// The header before the rays column (results of an earlier version read alike).
constexpr const char* kHeaderWithoutRays =
    "model,metric,trial,iteration,view,coverage,entropy_bits,max_entropy_bits,seconds_render,"
    "seconds_integrate,seconds_ig,ties,gap";

std::size_t metricRank(const std::string& name) {
  const auto metric = kernels::metricFromName(name);
  return metric ? static_cast<std::size_t>(*metric) : kernels::kMetricCount;
}

std::string number(double value) { return shortestNumber(value); }

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

}  // namespace

void sortRows(std::vector<ExperimentRow>& rows) {
  std::stable_sort(rows.begin(), rows.end(), [](const ExperimentRow& a, const ExperimentRow& b) {
    return std::make_tuple(a.model, metricRank(a.metric), a.metric, a.trial, a.iteration) <
           std::make_tuple(b.model, metricRank(b.metric), b.metric, b.trial, b.iteration);
  });
}

void writeResultsCsv(const std::filesystem::path& path, const std::vector<ExperimentRow>& rows) {
  std::ofstream out(path);
  if (!out) throw nbv::FileError(path, "cannot write");
  out << kHeader << '\n';
  for (const ExperimentRow& r : rows) {
    out << r.model << ',' << r.metric << ',' << r.trial << ',' << r.iteration << ',' << r.view << ','
        << number(r.coverage) << ',' << number(r.entropy_bits) << ',' << number(r.max_entropy_bits) << ','
        << number(r.seconds_render) << ',' << number(r.seconds_integrate) << ',' << number(r.seconds_ig) << ','
        << r.ties << ',' << (std::isnan(r.gap) ? std::string() : number(r.gap)) << ',' << r.rays << '\n';
  }
  if (!out.flush()) throw nbv::FileError(path, "write failed");
}

std::vector<ExperimentRow> readResultsCsv(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw nbv::InvalidArgument(path.string() + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || (line != kHeader && line != kHeaderWithoutRays)) {
    throw nbv::InvalidArgument(path.string() + ":1: not an nbv results.csv header");
  }
  const std::size_t columns = line == kHeader ? 14 : 13;
  std::vector<ExperimentRow> rows;
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
      r.trial = static_cast<unsigned>(std::stoul(f[2]));
      r.iteration = static_cast<unsigned>(std::stoul(f[3]));
      r.view = static_cast<unsigned>(std::stoul(f[4]));
      r.coverage = std::stod(f[5]);
      r.entropy_bits = std::stod(f[6]);
      r.max_entropy_bits = std::stod(f[7]);
      r.seconds_render = std::stod(f[8]);
      r.seconds_integrate = std::stod(f[9]);
      r.seconds_ig = std::stod(f[10]);
      r.ties = static_cast<std::size_t>(std::stoul(f[11]));
      r.gap = f[12].empty() ? std::numeric_limits<double>::quiet_NaN() : std::stod(f[12]);
      if (columns == 14) r.rays = std::stoull(f[13]);
      if (r.iteration == 0 || !(r.max_entropy_bits > 0.0)) throw InvalidArgument("bad iteration or entropy");
      rows.push_back(r);
    } catch (const std::exception& e) {
      throw nbv::InvalidArgument(path.string() + ":" + std::to_string(number_of_line) + ": " + e.what());
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
  std::map<std::tuple<std::string, std::size_t, std::string>, std::map<unsigned, Run>> runs;
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

}  // namespace nbv::apps
