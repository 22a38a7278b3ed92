#pragma once
/// \file What several subcommands of `nbv` share: where models live, how viewspaces and
/// metrics are named.

#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/viewspace.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace nbv::apps {

/// Where `make models` puts the meshes; the environment variable NBV_MODELS_DIR overrides it.
std::filesystem::path modelsDir();

/// The metric of a SPEC short name. \throws grid::InvalidArgument naming the unknown name.
kernels::Metric metricNamed(const std::string& name);

/// "dome48" or the path of a view file (SPEC §4 format). \throws planner::ViewFileError for a
/// bad or empty file.
std::vector<planner::View> viewspace(const std::string& name);

}  // namespace nbv::apps
