#include "app_support.hpp"

#include <cstdlib>

namespace nbv::apps {

std::filesystem::path modelsDir() {
  if (const char* dir = std::getenv("NBV_MODELS_DIR")) return dir;
  return NBV_DEFAULT_MODELS_DIR;
}

std::vector<planner::View> viewspace(const std::string& name) {
  if (name == "dome48") return planner::dome48();
  return planner::loadViews(name);
}

}  // namespace nbv::apps
