// The nbv command: one binary, one subcommand per task.
#include "ig_commands.hpp"
#include "map_commands.hpp"
#include "planner_commands.hpp"
#include "sensor_commands.hpp"

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{"nbv: next-best-view planning with fast volumetric information gain"};
  app.require_subcommand(1);
  nbv::apps::addMapCommands(app);
  nbv::apps::addSensorCommands(app);
  nbv::apps::addIgCommands(app);
  nbv::apps::addPlannerCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "nbv: error: " << e.what() << " (see nbv --help)\n";
    return e.get_exit_code();
  } catch (const std::exception& e) {
    // Library errors already name the file or value; one line, non-zero exit.
    std::cerr << "nbv: error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
