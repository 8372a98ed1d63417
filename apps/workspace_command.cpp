// csp workspace: placeholder replaced below
#include "commands.hpp"
namespace csp::cli {
Command add_workspace_command(CLI::App& app) {
  app.add_subcommand("workspace", "Sample the reachable workspace");
  return [] { return 0; };
}
}  // namespace csp::cli
