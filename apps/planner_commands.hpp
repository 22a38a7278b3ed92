#pragma once
/// \file The planner subcommands of `nbv`: reconstruct, experiment.

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `reconstruct` and `experiment` to `app`.
void addPlannerCommands(CLI::App& app);

}  // namespace nbv::apps
