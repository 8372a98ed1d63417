// The csp subcommands. Each add_* registers its options on `app` and returns the function that
// runs it; the function returns the process exit code and throws on bad input.
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_options.hpp"

namespace csp::cli {

using Command = std::function<int()>;

Command add_model_command(CLI::App& app);
Command add_workspace_command(CLI::App& app);
Command add_demo_command(CLI::App& app);
Command add_emulate_command(CLI::App& app);
Command add_serve_command(CLI::App& app);
Command add_replay_command(CLI::App& app);
Command add_log_command(CLI::App& app);
Command add_gap_command(CLI::App& app);
Command add_can_command(CLI::App& app);
Command add_fci_command(CLI::App& app);
Command add_plan_command(CLI::App& app);
Command add_view_command(CLI::App& app);
Command add_campaign_command(CLI::App& app);

// The most samples `csp workspace` and `csp demo` take: a billion take about 7 minutes (400 ns
// each) and make --points a 60 GB file; the reach statistics and density maps settle long before
// (the default is a million).
inline constexpr long long kMaxWorkspaceSamples = 1'000'000'000;

struct WorkspaceArguments {
  ModelArguments model;
  long long samples = 1'000'000;
  long long seed = 1;
  std::string out = "workspace_out";
  std::string points;
  int grid = 200;
  bool progress = false;
};
int run_workspace(const WorkspaceArguments& args);

}  // namespace csp::cli
