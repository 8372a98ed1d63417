// csp: the Cobot Simulator Platform command line.
#include <charconv>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"
#include "csp/io/joint_log.hpp"   // quote_input

namespace {

// Values CLI11 would take silently: an empty string (`--inertia ''` would pick the file's default
// set) and a whole number beyond 64 bits (CLI11 clamps it to INT64_MAX). Returns the first such
// option of any parsed (sub)command with what was expected, or nothing.
std::optional<std::string> option_problem(const CLI::App& command) {
  for (const CLI::Option* option : command.get_options())
    for (const std::string& value : option->results()) {
      if (value.empty()) return option->get_name() + ": expected a value, got an empty string";
      const bool whole = value.find_first_not_of("+-0123456789") == std::string::npos && value.find_first_of("0123456789") != std::string::npos;
      long long parsed = 0;
      const char* begin = value.data() + (value[0] == '+' ? 1 : 0);
      if (whole && std::from_chars(begin, value.data() + value.size(), parsed).ec == std::errc::result_out_of_range)
        return option->get_name() + ": " + csp::quote_input(value) + " is out of range (expected a whole number of at most 64 bits)";
    }
  for (const CLI::App* sub : command.get_subcommands())
    if (std::optional<std::string> problem = option_problem(*sub)) return problem;
  return std::nullopt;
}

// A message as printed: one line of bounded length, whatever input it quotes (CLI11 quotes a
// value it cannot convert whole; each reader shortens what it quotes with csp::quote_input, this
// is the net under them all).
std::string bounded(const std::string& message) {
  constexpr std::size_t kMaxBytes = 2000;
  std::string line = message.size() <= kMaxBytes ? message : message.substr(0, kMaxBytes) + "... (" + std::to_string(message.size()) + " bytes)";
  for (char& c : line)
    if (c == '\n' || c == '\r') c = ' ';
  return line;
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
  // One add(add_<name>_command); per command this build has (apps/CMakeLists.txt, CSP_COMMANDS).
#include "command_registrations.inc"

  // CLI11 would report an unknown command as a missing one; name it instead.
  std::string known;
  bool is_known = false;
  for (const auto& [command, run] : commands) {
    known += (known.empty() ? "" : ", ") + command->get_name();
    is_known = is_known || (argc > 1 && command->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !is_known) {
    std::cerr << "csp: unknown command " << csp::quote_input(argv[1]) << " (commands: " << known << ")\n";
    if (CSP_MISSING_COMMANDS[0] != '\0')
      std::cerr << "csp: not built in: " CSP_MISSING_COMMANDS " (CSP_COMMANDS; every command: "
                   "cmake -B build -U CSP_COMMANDS && cmake --build build --target csp)\n";
    return 2;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);   // --help on a subcommand, --version
    std::cerr << "csp: " << bounded(e.what()) << " (see csp --help)\n";
    return 2;
  }
  if (const std::optional<std::string> problem = option_problem(app)) {
    std::cerr << "csp: " << *problem << " (see csp --help)\n";
    return 2;
  }

  for (const auto& [command, run] : commands) {
    if (!command->parsed()) continue;
    set_command_name(command->get_name());
    try {
      return run();
    } catch (const std::exception& e) {   // UsageError, ConfigError, invalid_argument, I/O errors
      std::cerr << "csp " << command->get_name() << ": " << bounded(e.what()) << '\n';
    }
    return 2;
  }
  return 2;
}
