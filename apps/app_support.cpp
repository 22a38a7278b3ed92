#include "app_support.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace nbv::apps {

namespace fs = std::filesystem;

namespace {
/// `--max-map-mb`, as set for this run.
std::size_t max_map_mb = grid::MapLoadOptions{}.max_bytes >> 20;
}  // namespace

void addMapLoadOption(CLI::App& app) {
  app.add_option("--max-map-mb", max_map_mb,
                 "Refuse a map file whose map would take more memory than this [MiB] (a few bytes of a pruned OctoMap "
                 "tree can describe billions of voxels); may follow the subcommand")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 30))
      ->capture_default_str();
  app.fallthrough();
}

grid::OccupancyMap readMap(const std::string& path, const grid::MapConfig& config) {
  grid::MapLoadOptions options;
  options.config = config;
  options.max_bytes = max_map_mb << 20;
  grid::MapLoadReport report;
  grid::OccupancyMap map = grid::loadMap(path, options, &report);
  if (!report.dropped.empty()) {
    std::cerr << "nbv: note: " << path << " (an OctoMap " << report.tree_type << ") holds " << report.dropped
              << ", which a map does not keep\n";
  }
  return map;
}

std::vector<planner::View> viewspace(const std::string& name) {
  if (name == "dome48") return planner::dome48();
  std::vector<planner::View> views = planner::loadViews(name);
  if (views.empty()) throw ViewFileError(name, "the viewspace holds no view");
  return views;
}

std::string shortestNumber(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof text, value);
  return error == std::errc{} ? std::string(text, end) : std::string("nan");
}

void showProgress(std::size_t done, std::size_t total, double elapsed_s, const char* what) {
  constexpr int kWidth = 30;
  constexpr double kLogEvery_s = 5.0;
  const int filled = total == 0 ? kWidth : static_cast<int>(kWidth * done / total);
  const double eta = done == 0 ? 0.0 : elapsed_s / static_cast<double>(done) * static_cast<double>(total - done);
  auto clock = [](double s) {
    char text[48];
    const auto t = static_cast<long>(s + 0.5);
    std::snprintf(text, sizeof text, "%ld:%02ld", t / 60, t % 60);
    return std::string(text);
  };
  const std::string eta_text = done == 0 ? "?" : clock(eta);
  if (::isatty(STDERR_FILENO) == 0) {
    // A log file, not a terminal: a line every few seconds and the last, no carriage returns.
    static double last_line_s = 0.0;
    if (done == 0) last_line_s = 0.0;  // a new count
    if (done != total && elapsed_s - last_line_s < kLogEvery_s) return;
    last_line_s = elapsed_s;
    std::fprintf(stderr, "%zu/%zu %s, %s elapsed, ETA %s\n", done, total, what, clock(elapsed_s).c_str(), eta_text.c_str());
    std::fflush(stderr);
    return;
  }
  std::fprintf(stderr, "\r[%s%s] %zu/%zu %s, %s elapsed, ETA %s ", std::string(filled, '#').c_str(),
               std::string(kWidth - filled, '.').c_str(), done, total, what, clock(elapsed_s).c_str(), eta_text.c_str());
  if (done == total) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

std::vector<std::string> modelLabels(const std::vector<std::string>& models) {
  std::vector<std::string> labels;
  std::set<std::string> taken;
  for (const std::string& model : models) {
    const std::string first = planner::modelLabel(model);
    std::string label = first;
    for (int n = 2; taken.count(label) != 0; ++n) label = first + "-" + std::to_string(n);
    taken.insert(label);
    labels.push_back(label);
  }
  return labels;
}

CLI::Validator checkedBy(const std::string& description, std::function<void(const std::string&)> check) {
  return CLI::Validator(
      [check = std::move(check)](std::string& value) -> std::string {
        try {
          check(value);
        } catch (const std::exception& e) {
          return e.what();
        }
        return {};
      },
      description);
}

namespace {

/// The whole text as a number, or an error naming it.
double parseNumber(const std::string& text) {
  double value = 0.0;
  const char* first = text.data();
  if (!text.empty() && text[0] == '+') ++first;
  const auto [end, error] = std::from_chars(first, text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size()) throw InvalidArgument("'" + text + "' is not a number");
  return value;
}

}  // namespace

CLI::Validator positiveNumber() {
  return checkedBy("", [](const std::string& text) {
    const double value = parseNumber(text);
    if (!(std::isfinite(value) && value > 0.0)) throw InvalidArgument(text + " is not a finite number > 0");
  });
}

CLI::Validator finiteNumber() {
  return checkedBy("", [](const std::string& text) {
    if (!std::isfinite(parseNumber(text))) throw InvalidArgument(text + " is not a finite number");
  });
}

CLI::Validator numberIn(double low, double high) {
  std::ostringstream range;
  range << "[" << low << ", " << high << "]";
  return checkedBy("", [low, high, range = range.str()](const std::string& text) {
    const double value = parseNumber(text);
    if (!(value >= low && value <= high)) throw InvalidArgument(text + " is not in " + range);
  });
}

CLI::Validator raySetName() {
  return checkedBy("", [](const std::string& text) { sensor::PixelSampling::fromName(text); });
}

CLI::Validator visibilityName() {
  return checkedBy("", [](const std::string& text) { kernels::visibilityFromName(text); });
}

CLI::Validator utilityText(bool list, bool planners) {
  return checkedBy("", [list, planners](const std::string& text) {
    auto check = [planners](const std::string& item) {
      planner::ReconstructionConfig config;
      if (planners) {
        planner::setPlanner(config, item);
      } else {
        planner::parseMetricSum(item);
      }
    };
    if (!list) {
      check(text);
      return;
    }
    if (text == "all") return;
    const std::vector<std::string> items = splitList(text);
    if (items.empty()) throw InvalidArgument("'" + text + "' names no metric");
    for (const std::string& item : items) check(item);
  });
}

std::string flagOf(std::string_view name) {
  std::string flag = "--" + std::string(name);
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

namespace {

/// An option's value as a flag gives it: a number, or "none" for an optional one.
template <class Config>
std::optional<double> optionValue(const OptionRow<Config>& option, const std::string& text) {
  if (option.optional && text == "none") return std::nullopt;
  return parseNumber(text);
}

}  // namespace

template <class Config>
std::vector<CLI::Option*> addOptionFlags(CLI::App& command, std::span<const OptionRow<Config>> rows, OptionFlags& flags,
                                         const std::string& help_prefix) {
  const Config defaults;
  std::vector<CLI::Option*> added;
  for (const OptionRow<Config>& option : rows) {
    const std::optional<double> initial = option.get(defaults);
    std::string help = std::string(option.help) + (*option.unit ? std::string(" [") + option.unit + "]" : "") + "; " +
                       option.rule + " (default " + (initial ? numberText(*initial) : "none") + ")";
    if (help_prefix.empty()) help[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(help[0])));
    const std::string name = option.name;
    added.push_back(command
                        .add_option_function<std::string>(
                            flagOf(name),
                            [&flags, &option, name](const std::string& text) { flags[name] = optionValue(option, text); },
                            help_prefix + help)
                        ->type_name(option.optional ? "NUMBER|none" : "NUMBER")
                        ->check(checkedBy("", [&option](const std::string& text) {
                          Config config;
                          option.set(config, optionValue(option, text));
                          try {
                            config.validate();  // the defaults and this option: only its check can fail
                          } catch (const InvalidArgument&) {
                            throw InvalidArgument(text + " " + option.rule);
                          }
                        })));
  }
  return added;
}

template <class Config>
void applyOptionFlags(std::span<const OptionRow<Config>> rows, const OptionFlags& flags, Config& config) {
  for (const auto& [name, value] : flags) optionRow(rows, name)->set(config, value);
}

template std::vector<CLI::Option*> addOptionFlags(CLI::App&, std::span<const OptionRow<planner::ReconstructionConfig>>,
                                                  OptionFlags&, const std::string&);
template std::vector<CLI::Option*> addOptionFlags(CLI::App&, std::span<const OptionRow<planner::DecideOptions>>,
                                                  OptionFlags&, const std::string&);
template void applyOptionFlags(std::span<const OptionRow<planner::ReconstructionConfig>>, const OptionFlags&,
                               planner::ReconstructionConfig&);
template void applyOptionFlags(std::span<const OptionRow<planner::DecideOptions>>, const OptionFlags&,
                               planner::DecideOptions&);

void addAnytimeOptions(CLI::App& command, AnytimeFlags& flags) {
  command.add_flag("--anytime", flags.on, "Decide each next view from samples of the candidates' rays "
                                          "(docs/SEMANTICS.md, \"Anytime decisions\") instead of every ray");
  addOptionFlags(command, planner::decideOptions(), flags.options, "With --anytime: ");
}

std::optional<planner::DecideOptions> anytimeOf(const AnytimeFlags& flags) {
  if (!flags.on) {
    if (!flags.options.empty()) throw InvalidArgument(flagOf(flags.options.begin()->first) + " needs --anytime");
    return std::nullopt;
  }
  planner::DecideOptions options;
  applyOptionFlags(planner::decideOptions(), flags.options, options);
  return options;
}

void addSceneOptions(CLI::App& command, SceneFlags& flags, bool with_visibility) {
  command.add_option("--scene", flags.scene, "Scene preset: bare (the object alone), released (ground plane and the "
                                             "released launch file's crop box), paper (docs/RESULTS.md's choice)")
      ->check(CLI::IsMember(planner::sceneNames()))
      ->capture_default_str();
  command.add_flag("--ground-plane", flags.ground_plane,
                   "Add the plane z = 0 to the scene: its hits are integrated and never cover the object");
  command.add_option("--no-return", flags.no_return,
                     "What a pixel that sees nothing adds: drop (nothing) or clear (free space up to max range); "
                     "default: the preset's")
      ->check(CLI::IsMember({"drop", "clear"}));
  command.add_option("--crop", flags.crop, "Drop points outside this world box before integration: X0 X1 Y0 Y1 Z0 Z1 [m]")
      ->expected(6)
      ->check(finiteNumber());
  command.add_flag("--no-crop", flags.no_crop, "No crop box, whatever the preset says");
  command.add_option("--up", flags.up, "The mesh file's up axis: z (as stored), y (turned +90 degrees about x), or "
                                       "auto (a standard model upright, as docs/SEMANTICS.md lists; a file as stored); "
                                       "default: the preset's (auto for paper, else z)")
      ->check(CLI::IsMember({"z", "y", "auto"}));
  if (with_visibility) {
    command.add_option("--visibility", flags.visibility, "paper (Eq. 5) or released (the released code's P_o)")
        ->check(visibilityName())
        ->capture_default_str();
  }
}

planner::SceneConditions sceneOf(const SceneFlags& flags) {
  planner::SceneConditions scene = planner::sceneNamed(flags.scene);
  if (flags.ground_plane) scene.ground_plane = true;
  if (!flags.no_return.empty()) scene.no_return = planner::noReturnFromName(flags.no_return);
  if (flags.no_crop) scene.crop.reset();
  if (!flags.crop.empty()) {
    const Eigen::Vector3d lo(flags.crop[0], flags.crop[2], flags.crop[4]), hi(flags.crop[1], flags.crop[3], flags.crop[5]);
    if (!(lo.array() < hi.array()).all()) throw InvalidArgument("--crop: each minimum must be below its maximum (X0 X1 Y0 Y1 Z0 Z1)");
    scene.crop = Eigen::AlignedBox3d(lo, hi);
  }
  return scene;
}

std::string upOf(const SceneFlags& flags) { return flags.up.empty() ? planner::sceneUp(flags.scene) : flags.up; }

std::string sceneLabel(const SceneFlags& flags) { return planner::sceneLabel(flags.scene, sceneOf(flags), upOf(flags)); }

sensor::TriangleMesh placedModel(const std::string& name_or_path, const std::string& up) {
  sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel(name_or_path));
  sensor::normalizeMesh(mesh, {sensor::upAxisFor(name_or_path, up)});  // SEMANTICS.md "Simulation and evaluation"
  return mesh;
}

std::string standardModelNames() {
  std::string names;
  for (const sensor::StandardModel& model : sensor::standardModels()) names += (names.empty() ? "" : ", ") + model.name;
  return names;
}

bool isStandardModel(const std::string& name) {
  const auto& models = sensor::standardModels();
  return std::any_of(models.begin(), models.end(), [&](const sensor::StandardModel& m) { return m.name == name; });
}

std::string portableName(const std::string& name_or_path, bool standard) {
  return standard ? name_or_path : fs::absolute(name_or_path).lexically_normal().string();
}

fs::path findRunFile(const std::string& path, const fs::path& json_dir) {
  const fs::path given(path);
  std::vector<fs::path> candidates = {given.is_absolute() ? given : json_dir / given};
  if (given.is_relative()) candidates.push_back(given);
  candidates.push_back(json_dir / given.filename());
  for (const fs::path& candidate : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  return {};
}

namespace {

std::string shellQuoted(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

/// The folder that holds this binary's Python package (nbv/plots.py): installed beside it, or
/// in the build tree; empty if neither (the interpreter may still have nbv, pip-installed).
fs::path pythonPackageBeside() {
  std::error_code ec;
  const fs::path binary = fs::canonical("/proc/self/exe", ec);
  if (ec) return {};
  for (const char* relative : {NBV_PYTHON_FROM_BIN, NBV_PYTHON_FROM_BUILD}) {
    const fs::path dir = (binary.parent_path() / relative).lexically_normal();
    if (fs::is_regular_file(dir / "nbv" / "plots.py", ec)) return dir;
  }
  return {};
}

}  // namespace

std::string runPlots(const std::vector<std::string>& args) {
  const char* chosen = std::getenv("NBV_PYTHON");
  const bool interpreter_named = chosen != nullptr && *chosen != '\0';
  if (NBV_WITH_PYTHON_PACKAGE == 0 && !interpreter_named) {
    std::string command = "python3 -m nbv.plots";
    for (const std::string& arg : args) command += " " + shellQuoted(arg);
    std::fprintf(stderr,
                 "nbv: note: no plots: this nbv was built without its Python package (NBV_BUILD_PYTHON=OFF); `%s` "
                 "draws them where the package is installed (NBV_PYTHON names an interpreter that has it)\n",
                 command.c_str());
    return {};
  }
  const std::string python = interpreter_named ? chosen : NBV_PYTHON;
  std::string command;
  if (const fs::path package = pythonPackageBeside(); !package.empty()) {
    const char* path = std::getenv("PYTHONPATH");
    command = "PYTHONPATH=" + shellQuoted(package.string() + (path != nullptr && *path != '\0' ? ":" + std::string(path) : "")) + " ";
  }
  command += shellQuoted(python) + " -m nbv.plots";
  for (const std::string& arg : args) command += " " + shellQuoted(arg);
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen((command + " 2>&1").c_str(), "r"), &::pclose);
  if (!pipe) throw std::runtime_error("cannot run `" + command + "`");
  std::string output;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe.get())) > 0;) output.append(buffer, n);
  const int status = ::pclose(pipe.release());
  if (status != 0) {
    while (!output.empty() && output.back() == '\n') output.pop_back();
    throw std::runtime_error("the plots failed: `" + command + "` exited with status " +
                             std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : status) + ":\n" + output +
                             "\n(the plots need the nbv Python package and matplotlib in " + python +
                             "; NBV_PYTHON names another interpreter)");
  }
  return output;
}

namespace {

/// Edit distance of two short strings (insertions, deletions, substitutions).
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// A negative number or a weighted term ("-1*pc"): a value, not an option.
bool looksLikeValue(const std::string& text) {
  return text.size() > 1 && text[0] == '-' && (std::isdigit(static_cast<unsigned char>(text[1])) != 0 || text[1] == '.');
}

}  // namespace

std::optional<std::string> unknownOption(const CLI::App& command, const std::vector<std::string>& args) {
  for (const std::string& arg : args) {
    if (arg.size() < 2 || arg[0] != '-' || arg == "--" || looksLikeValue(arg)) continue;
    const std::string name = arg.substr(0, arg.find('='));  // --flag=value
    const CLI::App* parent = command.get_parent();
    if (command.get_option_no_throw(name) != nullptr || (parent != nullptr && parent->get_option_no_throw(name) != nullptr) ||
        name == "--help" || name == "-h") {
      continue;
    }
    std::string message = "unknown option '" + name + "' for 'nbv " + command.get_name() + "'";
    std::string closest;
    std::size_t best = 3;  // suggest only spellings within two edits
    for (const CLI::Option* option : command.get_options()) {
      for (const std::string& long_name : option->get_lnames()) {
        const std::size_t d = editDistance(name, "--" + long_name);
        if (d < best) {
          best = d;
          closest = "--" + long_name;
        }
      }
    }
    // Outputs are named by what they hold (--csv, --ply, --html): for a generic output
    // option, list this command's instead of a spelling.
    const bool generic_output = name == "--out" || name == "--output" || name == "-o";
    std::string outputs;
    if (generic_output) {
      for (const CLI::Option* option : command.get_options()) {
        const std::string& what = option->get_description();
        if (what.starts_with("Output") || what.starts_with("Write the")) {
          outputs += (outputs.empty() ? "" : ", ") + option->get_name();
        }
      }
    }
    if (!outputs.empty()) {
      message += " (its outputs: " + outputs + ")";
    } else if (!closest.empty() && !generic_output) {
      message += " (did you mean " + closest + "?)";
    }
    return message;
  }
  return std::nullopt;
}

}  // namespace nbv::apps
