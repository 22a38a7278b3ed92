// The nbv command: one binary, one subcommand per task.
#include "app_support.hpp"
#include "experiment_command.hpp"
#include "export_ply.hpp"
#include "ig_commands.hpp"
#include "map_commands.hpp"
#include "planner_commands.hpp"
#include "report_html.hpp"
#include "sensor_commands.hpp"

#include "output_file.hpp"

#include "nbv/kernels/mark_rays.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace {

std::string versionText() {
  const nbv::kernels::Isa best = nbv::kernels::bestIsa();
  std::string text = std::string("nbv ") + NBV_VERSION + "\nray walks: " + nbv::kernels::isaName(best) +
                     " (the widest instruction set of avx512, avx2 and scalar that this CPU and build support)";
  if (nbv::kernels::isaEmulated(best)) {
    text += "\nthis build emulates avx512 in plain C++ (NBV_EMULATE_AVX512): for checks only, slow";
  }
  return text;
}

const CLI::App* findSubcommand(const CLI::App& app, const std::string& name) {
  const auto found = app.get_subcommands([&](const CLI::App* sub) { return sub->get_name() == name; });
  return found.empty() ? nullptr : found.front();
}

/// The subcommands' names, for the error of an unknown one.
std::string subcommandNames(const CLI::App& app) {
  std::string names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return names;
}

int fail(const std::string& message) {
  std::cerr << "nbv: error: " << message << '\n';
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // Named "nbv" so that a usage line reads "nbv evaluate [OPTIONS]" whatever path ran it.
  CLI::App app{"nbv: next-best-view planning with fast volumetric information gain", "nbv"};
  app.require_subcommand(1);
  app.set_version_flag("--version", versionText(), "Print the version and the instruction set the ray walks use");
  nbv::apps::addMapLoadOption(app);
  nbv::apps::addMapCommands(app);
  nbv::apps::addSensorCommands(app);
  nbv::apps::addIgCommands(app);
  nbv::apps::addPlannerCommands(app);
  nbv::apps::addExperimentCommand(app);
  nbv::apps::addExportCommand(app);
  nbv::apps::addReportCommand(app);

  const std::vector<std::string> args(argv + 1, argv + argc);
  const CLI::App* command = nullptr;
  if (!args.empty() && !args[0].empty() && args[0][0] != '-') {
    command = findSubcommand(app, args[0]);
    if (command == nullptr) {
      return fail("unknown subcommand '" + args[0] + "' (known: " + subcommandNames(app) + "; see nbv --help)");
    }
  }
  try {
    // "-" names standard output as an output: the file goes there, the command's report to
    // standard error. One file at most, or they would run together.
    const auto to_standard_output = std::count(args.begin(), args.end(), nbv::apps::kStandardOutput);
    if (to_standard_output > 1) {
      return fail("'-' (standard output) is given " + std::to_string(to_standard_output) +
                  " times: at most one output may go to standard output");
    }
    if (to_standard_output == 1) nbv::apps::reserveStandardOutput();
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // An unknown flag explains the other errors (a misspelt --map is also a missing --map).
    if (command != nullptr) {
      const auto unknown = nbv::apps::unknownOption(*command, {args.begin() + 1, args.end()});
      if (unknown) return fail(*unknown + " (see nbv " + command->get_name() + " --help)");
    }
    std::cerr << "nbv: error: " << e.what() << " (see nbv " << (command != nullptr ? command->get_name() + " " : "")
              << "--help)\n";
    return e.get_exit_code();
  } catch (const nbv::apps::Interrupted& e) {
    std::cerr << "nbv: " << e.what() << '\n';
    return 130;  // as a shell reports a command that SIGINT ended
  } catch (const std::filesystem::filesystem_error& e) {
    // The standard library's "filesystem error: cannot ...: reason [path]", said as nbv says it.
    std::string what = e.what();
    const std::string prefix = "filesystem error: ";
    if (what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());
    what = what.substr(0, what.find(" ["));
    return fail(e.path1().string() + ": " + what);
  } catch (const std::exception& e) {
    // Library errors already name the file or value; one line, non-zero exit.
    return fail(e.what());
  }
  return 0;
}
