// flowplan: generate datasets, train, evaluate, export and plan with
// flow-matching planners. Adds the subcommands (experiment/commands.h),
// parses, runs the chosen one, and reports any error in one line.

#include <CLI/CLI.hpp>
#include <c10/util/Exception.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/logging.h"
#include "experiment/commands.h"
#include "sim/mujoco_util.h"

namespace {

// The first word on the command line that is neither an option nor one of
// `commands`: what the user meant as the command ("" if there is none).
std::string UnknownCommand(const std::vector<std::string>& commands, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--log-level") {
      ++i;  // its value
      continue;
    }
    if (arg.empty() || arg[0] == '-') continue;
    return std::find(commands.begin(), commands.end(), arg) == commands.end() ? arg : "";
  }
  return "";
}

int Main(int argc, char** argv) {
  flowplan::SetUpLogging("info");  // the line format, also for errors found while parsing
  CLI::App app{"flowplan: flow-matching trajectory planners that stitch, from data to TorchScript"};
  app.require_subcommand(1);
  app.fallthrough();  // --log-level also after the subcommand
  app.option_defaults()->always_capture_default();
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "debug, info, warn, error or off");
  const std::vector<flowplan::experiment::Command> commands = flowplan::experiment::AddCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line and status 1, like every other error (CLI11's own would add a
    // second line and exit with its internal code).
    std::vector<std::string> names;
    for (const auto& command : commands) names.push_back(command.app->get_name());
    const std::string unknown = app.get_subcommands().empty() ? UnknownCommand(names, argc, argv) : "";
    if (!unknown.empty()) {
      spdlog::error("unknown command \"{}\" (commands: {})", unknown, fmt::join(names, ", "));
    } else {
      spdlog::error("{} (see flowplan --help)", e.what());
    }
    return 1;
  }
  flowplan::SetUpLogging(log_level);
  flowplan::InstallInterruptHandler();
  flowplan::sim::InstallMujocoHandlers();
  for (const auto& command : commands) {
    if (command.app->parsed()) command.run();
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const flowplan::Error& e) {
    spdlog::error("{}", e.what());
  } catch (const c10::Error& e) {
    spdlog::error("LibTorch: {}", flowplan::FirstLine(e.what_without_backtrace()));
  } catch (const flowplan::InternalError& e) {
    spdlog::critical("{} (this is a bug in flowplan)", e.what());
  } catch (const std::exception& e) {
    spdlog::error("{}", flowplan::FirstLine(e.what()));
  }
  return 1;
}
