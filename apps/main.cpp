// csp: the Cobot Simulator Platform command line.
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"

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
