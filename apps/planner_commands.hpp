#pragma once
/// \file The planner subcommand of `nbv`: reconstruct.

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `reconstruct` to `app`.
void addPlannerCommands(CLI::App& app);

}  // namespace nbv::apps
