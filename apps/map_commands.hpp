#pragma once
/// \file The map subcommands of `nbv`: integrate, convert, info.

#include <CLI/App.hpp>

namespace nbv::apps {

/// Adds `integrate`, `convert` and `info` to `app`.
void addMapCommands(CLI::App& app);

}  // namespace nbv::apps
