// csp: the Cobot Simulator Platform command line.
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"

namespace {

// An empty value never means "the default" (`--inertia ''` would silently pick the file's
// default set): the first option given an empty string, in any parsed (sub)command.
const CLI::Option* option_with_empty_value(const CLI::App& command) {
  for (const CLI::Option* option : command.get_options())
    for (const std::string& value : option->results())
      if (value.empty()) return option;
  for (const CLI::App* sub : command.get_subcommands())
    if (const CLI::Option* option = option_with_empty_value(*sub)) return option;
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace csp::cli;
  CLI::App app{"CSP, the Cobot Simulator Platform: Franka Panda / FR3 dynamics and emulation"};
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, Command>> commands;
  auto add = [&](Command (*adder)(CLI::App&)) {
    Command run = adder(app);
    commands.emplace_back(app.get_subcommands({}).back(), std::move(run));
  };
  add(add_model_command);
  add(add_workspace_command);
  add(add_demo_command);
  add(add_emulate_command);
  add(add_serve_command);
  add(add_replay_command);
  add(add_log_command);
  add(add_gap_command);
  add(add_can_command);

  // CLI11 would report an unknown command as a missing one; name it instead.
  std::string known;
  bool is_known = false;
  for (const auto& [command, run] : commands) {
    known += (known.empty() ? "" : ", ") + command->get_name();
    is_known = is_known || (argc > 1 && command->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !is_known) {
    std::cerr << "csp: unknown command `" << argv[1] << "` (commands: " << known << ")\n";
    return 2;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);   // --help on a subcommand, --version
    std::cerr << "csp: " << e.what() << " (see csp --help)\n";
    return 2;
  }
  if (const CLI::Option* empty = option_with_empty_value(app)) {
    std::cerr << "csp: " << empty->get_name() << ": expected a value, got an empty string (see csp --help)\n";
    return 2;
  }

  for (const auto& [command, run] : commands) {
    if (!command->parsed()) continue;
    try {
      return run();
    } catch (const std::exception& e) {   // UsageError, ConfigError, invalid_argument, I/O errors
      std::cerr << "csp " << command->get_name() << ": " << e.what() << '\n';
    }
    return 2;
  }
  return 2;
}
