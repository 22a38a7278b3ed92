#pragma once
/// \file What several subcommands of `nbv` share: where models live, how viewspaces, metrics
/// and ray sets are named, and the checks that let errors name the flag the user typed.

#include "nbv/grid/map_io.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/viewspace.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace nbv::apps {

/// Adds `--max-map-mb` to the command line, before or after the subcommand: the cap of every
/// map file a command reads (grid::MapLoadOptions::max_bytes).
void addMapLoadOption(CLI::App& app);

/// The map at `path` as the command line reads it: within `--max-map-mb`, an OctoMap file
/// with `config` (its resolution the file's), and a note on standard error of what the file
/// held that the map does not keep. \throws as grid::loadMap().
grid::OccupancyMap readMap(const std::string& path, const grid::MapConfig& config = grid::MapConfig{});

/// "dome48" or the path of a view file. \throws ViewFileError for a bad or empty file.
std::vector<planner::View> viewspace(const std::string& name);

/// The shortest text that reads back to exactly `value` ("0.38302", not "0.38302000000000003").
std::string shortestNumber(double value);

/// "[#####.....] 12/40 runs, 0:42 elapsed, ETA 1:58" on one line of the terminal (stderr);
/// `what` names the units ("runs", "frames"). When stderr is not a terminal (a log file), a
/// plain line "12/40 runs, ..." every 5 seconds, and the last one.
void showProgress(std::size_t done, std::size_t total, double elapsed_s, const char* what = "runs");

/// Items of a comma-separated list, empty items dropped.
std::vector<std::string> splitList(const std::string& text);

/// One label per model of a run, for file names and table rows: a short name stays itself, a
/// mesh path becomes its file's stem; a label taken already gets "-2", "-3", ...
std::vector<std::string> modelLabels(const std::vector<std::string>& models);

/// A CLI11 check from a function that throws on a bad value: the error then reads
/// "--flag: <what the function said>", naming the flag as the user typed it.
CLI::Validator checkedBy(const std::string& description, std::function<void(const std::string&)> check);
/// A finite number > 0.
CLI::Validator positiveNumber();
/// A finite number.
CLI::Validator finiteNumber();
/// A finite number in [low, high].
CLI::Validator numberIn(double low, double high);
/// A ray set: released, full or a stride >= 1.
CLI::Validator raySetName();
/// A visibility name (kernels::visibilityFromName(): paper or released).
CLI::Validator visibilityName();
/// A metric or a weighted sum of metrics (planner::parseMetricSum), or a comma-separated list
/// of them when `list` is true ("all" allowed there); with `planners`, "oracle" too
/// (planner::setPlanner).
CLI::Validator utilityText(bool list, bool planners);

/// The scene options of render, reconstruct and experiment (SEMANTICS.md "Scene conditions"):
/// --scene sets a preset, the other flags change it.
struct SceneFlags {
  std::string scene = "bare";
  bool ground_plane = false;
  std::string no_return;            ///< empty: the preset's
  std::vector<double> crop;         ///< X0 X1 Y0 Y1 Z0 Z1, or empty: the preset's
  bool no_crop = false;
  std::string up;                   ///< empty: the preset's (planner::sceneUp)
  std::string visibility = "paper";
};
/// Adds --scene, --ground-plane, --no-return, --crop, --no-crop, --up and (when asked)
/// --visibility to `command`.
void addSceneOptions(CLI::App& command, SceneFlags& flags, bool with_visibility);
/// The scene the flags describe.
planner::SceneConditions sceneOf(const SceneFlags& flags);
/// The up axis the flags place a model by: --up, else the preset's.
std::string upOf(const SceneFlags& flags);
/// "bare", or the preset and the changes the flags make ("bare+ground+clear").
std::string sceneLabel(const SceneFlags& flags);
/// A standard model or a mesh file, loaded and placed as SEMANTICS.md "Simulation and
/// evaluation" says, with its up axis as sensor::upAxisFor() reads `up`.
sensor::TriangleMesh placedModel(const std::string& name_or_path, const std::string& up);
/// The standard models' names, comma-separated.
std::string standardModelNames();
/// Whether `name` is a standard model's short name.
bool isStandardModel(const std::string& name);

/// How a run's JSON names a model or a viewspace so that it can be found from any folder: a
/// standard name (`standard`) stays itself, a file becomes its absolute path.
std::string portableName(const std::string& name_or_path, bool standard);
/// The file a run's JSON names (portableName()): an existing absolute path; a relative one
/// against `json_dir`, then the working folder; else the file of that name beside the JSON
/// (the run moved with its files). Empty if none exists.
std::filesystem::path findRunFile(const std::string& path, const std::filesystem::path& json_dir);

/// Runs `python3 -m nbv.plots ARGS...` (the Python package's plots) with the interpreter nbv was
/// built for (NBV_PYTHON overrides it) and the package installed or built beside this binary;
/// \returns what it printed. \throws std::runtime_error with what it printed and what to do if it
/// fails. A build without the Python package (NBV_BUILD_PYTHON=OFF) draws none and says so,
/// unless NBV_PYTHON names an interpreter (one with the package installed, say).
std::string runPlots(const std::vector<std::string>& args);

/// An option's flag: "--" and its name with dashes ("max_range": "--max-range").
std::string flagOf(std::string_view name);

/// Option values given by flag, by name (none: an optional one turned off).
using OptionFlags = std::map<std::string, std::optional<double>>;
/// Adds a flag per row of an option table (nbv/option_table.hpp) to `command`: "--" and the
/// name with dashes, a number or "none" for an optional one, each checked as it is read, its
/// help the row's after `help_prefix`; \returns them in the table's order. Instantiated for
/// planner::ReconstructionConfig and planner::DecideOptions.
template <class Config>
std::vector<CLI::Option*> addOptionFlags(CLI::App& command, std::span<const OptionRow<Config>> rows, OptionFlags& flags,
                                         const std::string& help_prefix = "");
/// Sets the options given in `config`.
template <class Config>
void applyOptionFlags(std::span<const OptionRow<Config>> rows, const OptionFlags& flags, Config& config);

/// The anytime flags of reconstruct and experiment (SEMANTICS.md "Anytime decisions").
struct AnytimeFlags {
  bool on = false;
  OptionFlags options;  ///< planner::NBV_DECIDE_OPTIONS given
};
/// Adds --anytime and a flag per row of planner::NBV_DECIDE_OPTIONS (--epsilon, ...) to `command`.
void addAnytimeOptions(CLI::App& command, AnytimeFlags& flags);
/// The anytime decisions the flags ask for; empty without --anytime.
/// \throws InvalidArgument for an option of them without --anytime.
std::optional<planner::DecideOptions> anytimeOf(const AnytimeFlags& flags);

/// The help of --no-timings and --weighting, shared by reconstruct and experiment.
inline constexpr const char* kNoTimingsHelp =
    "Write every time as 0, so that the same inputs give byte-identical files at any thread count";
inline constexpr const char* kWeightingHelp =
    "How a weighted sum combines its metrics: normalized (each divided by its sum over the candidates, "
    "then weighted) or raw (weights on the raw values, as the released code)";

/// With --no-timings, the records keep their fields and lose their clock readings.
inline void dropTimings(planner::IterationRecord& r) { r.seconds_render = r.seconds_integrate = r.seconds_ig = 0.0; }

/// The first option in `args` (argv after the subcommand) that `command` does not know, with a
/// suggestion when one of its options is spelled alike; empty if every option is known.
std::optional<std::string> unknownOption(const CLI::App& command, const std::vector<std::string>& args);

}  // namespace nbv::apps
