#pragma once
/// \file The sensor subcommands of `nbv`: render, viewspace.

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `render` and `viewspace` to `app`.
void addSensorCommands(CLI::App& app);

}  // namespace nbv::apps
