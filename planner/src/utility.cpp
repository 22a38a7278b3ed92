#include "nbv/planner/utility.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>
#include <string>

namespace nbv::planner {

Weighting weightingFromName(std::string_view name) {
  if (name == "normalized") return Weighting::Normalized;
  if (name == "raw") return Weighting::Raw;
  throw InvalidArgument("weighting '" + std::string(name) + "' is not 'normalized' or 'raw'");
}

const char* weightingName(Weighting weighting) {
  return weighting == Weighting::Raw ? "raw" : "normalized";
}

namespace {

/// A weight as written in a term; empty if the text is not a number.
std::optional<double> parseWeight(std::string_view text) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace

std::vector<kernels::Metric> metricsOf(std::span<const MetricWeight> terms) {
  std::vector<kernels::Metric> metrics;
  for (const MetricWeight& term : terms) metrics.push_back(term.metric);
  return metrics;
}

std::vector<MetricWeight> parseMetricSum(std::string_view text) {
  std::string compact;  // spaces carry no meaning
  std::copy_if(text.begin(), text.end(), std::back_inserter(compact), [](char c) { return c != ' ' && c != '\t'; });
  if (compact.empty()) throw InvalidArgument("the utility names no metric");
  std::vector<MetricWeight> terms;
  for (std::size_t start = 0;;) {
    const std::size_t plus = std::min(compact.find('+', start), compact.size());
    const std::string term = compact.substr(start, plus - start);
    if (term.empty()) throw InvalidArgument("utility '" + std::string(text) + "' has an empty term (a '+' too many)");
    // "w*name" or "name*w": the side that is a metric name is the metric.
    std::string name = term;
    std::optional<double> weight = 1.0;
    if (const std::size_t star = term.find('*'); star != std::string::npos) {
      const std::string left = term.substr(0, star), right = term.substr(star + 1);
      const bool metric_left = kernels::metricFromName(left).has_value();
      name = metric_left ? left : right;
      weight = parseWeight(metric_left ? right : left);
      if (!weight) throw InvalidArgument("utility term '" + term + "': '" + (metric_left ? right : left) + "' is not a number");
    }
    const auto metric = kernels::metricFromName(name);
    if (!metric) {
      throw InvalidArgument("utility term '" + term + "': unknown metric '" + name + "' (known: " + kernels::metricNames() + ")");
    }
    if (!(std::isfinite(*weight) && *weight > 0.0)) {
      throw InvalidArgument("utility term '" + term + "': the weight must be finite and positive");
    }
    if (std::any_of(terms.begin(), terms.end(), [&](const MetricWeight& t) { return t.metric == *metric; })) {
      throw InvalidArgument("utility '" + std::string(text) + "' names '" + name + "' twice");
    }
    terms.push_back({*metric, *weight});
    if (plus == compact.size()) break;
    start = plus + 1;
  }
  return terms;
}

std::vector<double> combinedGains(std::span<const double> values, std::span<const MetricWeight> terms,
                                  Weighting weighting) {
  if (terms.empty() || values.size() % terms.size() != 0) {
    throw InvalidArgument("combinedGains: " + std::to_string(values.size()) + " values are not rows of " +
                          std::to_string(terms.size()) + " terms");
  }
  const std::size_t candidates = values.size() / terms.size();
  const bool normalize = weighting == Weighting::Normalized && terms.size() > 1;
  std::vector<double> totals(terms.size(), 1.0);  // the divisor of each column
  for (std::size_t t = 0; normalize && t < terms.size(); ++t) {
    totals[t] = 0.0;
    for (std::size_t c = 0; c < candidates; ++c) totals[t] += values[c * terms.size() + t];
  }
  std::vector<double> gains(candidates, 0.0);
  for (std::size_t c = 0; c < candidates; ++c) {
    for (std::size_t t = 0; t < terms.size(); ++t) {
      const double value = values[c * terms.size() + t];
      if (!normalize) {
        gains[c] += terms[t].weight * value;
      } else if (totals[t] != 0.0) {
        gains[c] += terms[t].weight * (value / totals[t]);
      }
    }
  }
  return gains;
}

double travelCost(const View& from, const View& to) {
  return (to.T_world_camera.translation() - from.T_world_camera.translation()).norm();
}

std::vector<double> utilities(std::span<const double> gains, std::span<const double> costs, double gamma) {
  if (gains.size() != costs.size()) throw InvalidArgument("utilities: one cost per gain");
  if (!(gamma >= 0.0 && gamma <= 1.0)) {
    throw InvalidArgument("gamma " + std::to_string(gamma) + " must lie in [0, 1]");
  }
  const double gain_total = std::accumulate(gains.begin(), gains.end(), 0.0);
  const double cost_total = std::accumulate(costs.begin(), costs.end(), 0.0);
  std::vector<double> u(gains.size());
  for (std::size_t v = 0; v < gains.size(); ++v) {  // Eq. 12
    const double gain_term = gain_total != 0.0 ? gains[v] / gain_total : 0.0;
    const double cost_term = cost_total != 0.0 ? costs[v] / cost_total : 0.0;
    u[v] = (1.0 - gamma) * gain_term - gamma * cost_term;
  }
  return u;
}

std::optional<std::size_t> argmaxFirst(std::span<const double> values) {
  std::optional<std::size_t> best;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (std::isnan(values[i])) continue;
    if (!best || values[i] > values[*best]) best = i;  // strictly greater: the first wins ties
  }
  return best;
}

Margin decisionMargin(std::span<const double> values) {
  Margin margin;
  double best = -std::numeric_limits<double>::infinity(), second = best;
  std::size_t count = 0;
  for (const double v : values) {
    if (std::isnan(v)) continue;
    ++count;
    if (v > best) {
      second = best;
      best = v;
      margin.ties = 1;
    } else if (v == best) {
      ++margin.ties;
      second = v;
    } else if (v > second) {
      second = v;
    }
  }
  if (count >= 2) margin.gap = best - second;
  return margin;
}

bool allBelow(std::span<const double> gains, double g_thresh) {
  for (double g : gains) {
    if (!(g < g_thresh)) return false;
  }
  return true;
}

}  // namespace nbv::planner
