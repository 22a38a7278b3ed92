#pragma once
/// \file The IG subcommands of `nbv`: evaluate, workload.

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `evaluate` and `workload` to `app`.
void addIgCommands(CLI::App& app);

}  // namespace nbv::apps
