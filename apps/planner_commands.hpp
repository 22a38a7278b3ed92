#pragma once
/// \file The planner subcommands of `nbv`: reconstruct (here) and experiment (experiment_command.hpp).

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `reconstruct` to `app`.
void addPlannerCommands(CLI::App& app);

}  // namespace nbv::apps
