#pragma once
/// \file Choosing the next view (paper Sec. 3, SPEC §4): cost, utility (Eq. 12), argmax
/// (Eq. 13) and the termination test (Eq. 14).

#include "nbv/planner/viewspace.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace nbv::planner {

/// Cost of moving the sensor from `from` to `to`: the Euclidean distance of their positions [m].
double travelCost(const View& from, const View& to);

/// Eq. 12 for every candidate: U_v = (1 - gamma) G_v / sum G - gamma C_v / sum C. A term whose
/// total is 0 contributes 0 (no information, or no cost, anywhere).
/// \throws std::invalid_argument if the spans differ in size or gamma is outside [0, 1].
std::vector<double> utilities(std::span<const double> gains, std::span<const double> costs, double gamma);

/// Eq. 13: the index of the largest value, the first one on ties; empty when there is none.
/// NaN values are never chosen.
std::optional<std::size_t> argmaxFirst(std::span<const double> values);

/// Eq. 14: true if every gain is below `g_thresh` (also when there is no gain at all).
bool allBelow(std::span<const double> gains, double g_thresh);

}  // namespace nbv::planner
