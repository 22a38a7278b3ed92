#include "nbv/planner/utility.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace nbv::planner {

double travelCost(const View& from, const View& to) {
  return (to.T_world_camera.translation() - from.T_world_camera.translation()).norm();
}

std::vector<double> utilities(std::span<const double> gains, std::span<const double> costs, double gamma) {
  if (gains.size() != costs.size()) throw std::invalid_argument("utilities: one cost per gain");
  if (!(gamma >= 0.0 && gamma <= 1.0)) {
    throw std::invalid_argument("gamma " + std::to_string(gamma) + " must lie in [0, 1]");
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

bool allBelow(std::span<const double> gains, double g_thresh) {
  for (double g : gains) {
    if (!(g < g_thresh)) return false;
  }
  return true;
}

}  // namespace nbv::planner
