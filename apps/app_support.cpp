#include "app_support.hpp"

#include "nbv/grid/errors.hpp"

#include <cstdlib>

namespace nbv::apps {

std::filesystem::path modelsDir() {
  if (const char* dir = std::getenv("NBV_MODELS_DIR")) return dir;
  return NBV_DEFAULT_MODELS_DIR;
}

kernels::Metric metricNamed(const std::string& name) {
  const auto metric = kernels::metricFromName(name);
  if (!metric) {
    throw grid::InvalidArgument("unknown metric '" + name + "' (known: entropy, oa, uv, rsv, rse, pc, vg, kr, random)");
  }
  return *metric;
}

std::vector<planner::View> viewspace(const std::string& name) {
  if (name == "dome48") return planner::dome48();
  std::vector<planner::View> views = planner::loadViews(name);
  if (views.empty()) throw planner::ViewFileError(name, "the viewspace holds no view");
  return views;
}

}  // namespace nbv::apps
