#pragma once
/// \file `nbv experiment`: a sweep of (model, metric, trial) reconstructions, or a slice of it,
/// kept run by run in its folder (planner/experiment_folder.hpp), resumed, and merged from its
/// shards into results.csv, table.md, the plots and the report pages.

#include <CLI/App.hpp>

#include <stdexcept>

namespace nbv::apps {

/// Thrown when Ctrl-C or SIGTERM stopped an experiment after its runs in flight were kept;
/// what() says how many and how to resume. The command then exits with 130.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Adds `experiment` to `app`.
void addExperimentCommand(CLI::App& app);

}  // namespace nbv::apps
