// The csp subcommands. Each add_* registers its options on `app` and returns the function that
// runs it; the function returns the process exit code and throws on bad input.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace csp::cli {

using Command = std::function<int()>;

Command add_model_command(CLI::App& app);
Command add_workspace_command(CLI::App& app);

}  // namespace csp::cli
