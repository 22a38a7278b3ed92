#pragma once
/// \file Choosing the next view (paper Sec. 3, SEMANTICS.md "The planner"): cost, utility (Eq. 12), argmax
/// (Eq. 13) and the termination test (Eq. 14).
///
/// Thread-safety: the functions share no state and may run in several threads at once.

#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/viewspace.hpp"

#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace nbv::planner {

/// One term of the information gain a planner maximises: weight x metric.
struct MetricWeight {
  kernels::Metric metric = kernels::Metric::ProximityCount;
  double weight = 1.0;
};

/// The metrics of `terms`, in order.
std::vector<kernels::Metric> metricsOf(std::span<const MetricWeight> terms);

/// How the terms of a weighted sum of metrics are combined into one gain.
enum class Weighting {
  /// Each metric divided by its sum over the candidates, then weighted: the weights compare
  /// metrics of different scales (pc counts hundreds of thousands, vg lies in [0, 2]). The
  /// default.
  Normalized,
  /// The weights multiply the raw values, as the released code does.
  Raw,
};

/// "normalized" or "raw". \throws InvalidArgument for another name.
Weighting weightingFromName(std::string_view name);
const char* weightingName(Weighting weighting);

/// Parses a utility written as metric names with optional weights joined by `+`: "pc",
/// "0.5*pc+0.5*vg", "pc*0.5 + vg" (spaces are ignored). \throws InvalidArgument naming the
/// term for an unknown metric, a weight that is not a finite positive number, an empty term
/// (a leading, trailing or doubled `+`) or a metric named twice.
std::vector<MetricWeight> parseMetricSum(std::string_view text);

/// The gain of each candidate. `values` holds one row per candidate and one column per term,
/// row-major, column t the value of terms[t].metric. One term: weight x value. Several, with
/// Normalized weighting: sum over t of weight_t x value_t / (sum of column t over the
/// candidates), a column summing to 0 adding 0; with Raw: sum of weight_t x value_t.
/// \throws InvalidArgument if `values` is not a whole number of rows of terms.size().
std::vector<double> combinedGains(std::span<const double> values, std::span<const MetricWeight> terms,
                                  Weighting weighting);

/// Cost of moving the sensor from `from` to `to`: the Euclidean distance of their positions [m].
double travelCost(const View& from, const View& to);

/// Eq. 12 for every candidate: U_v = (1 - gamma) G_v / sum G - gamma C_v / sum C. A term whose
/// total is 0 contributes 0 (no information, or no cost, anywhere).
/// \throws InvalidArgument if the spans differ in size or gamma is outside [0, 1].
std::vector<double> utilities(std::span<const double> gains, std::span<const double> costs, double gamma);

/// Eq. 13: the index of the largest value, the first one on ties; empty when there is none.
/// NaN values are never chosen.
std::optional<std::size_t> argmaxFirst(std::span<const double> values);

/// How clearly an argmax was decided: how many values equal the largest exactly, and the
/// largest minus the second largest (0 on a tie; NaN with fewer than two values). NaN values
/// take no part.
struct Margin {
  std::size_t ties = 0;
  double gap = std::numeric_limits<double>::quiet_NaN();
};
Margin decisionMargin(std::span<const double> values);

/// Eq. 14: true if every gain is below `g_thresh` (also when there is no gain at all).
bool allBelow(std::span<const double> gains, double g_thresh);

}  // namespace nbv::planner
