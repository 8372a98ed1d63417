// csp log export / import: LCM logs <-> CSV joint logs (docs/joint-log.md).
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/bridge/csv_convert.hpp"

namespace csp::cli {
namespace {

struct LogArguments {
  std::string input, out;
  std::string channel = "CSP_STATE";
  bool progress = false;
};

}  // namespace

Command add_log_command(CLI::App& app) {
  auto args = std::make_shared<LogArguments>();
  CLI::App* cmd = app.add_subcommand("log", "Convert LCM logs to and from CSV joint logs (docs/joint-log.md)");
  cmd->require_subcommand(1);
  CLI::App* to_csv = cmd->add_subcommand("export", "Write the robot states of an LCM log as CSV");
  to_csv->add_option("log", args->input, "LCM log file")->required();
  CLI::App* from_csv = cmd->add_subcommand("import", "Turn a CSV joint log (t, q, dq, tau_J and any optional groups) into an LCM log");
  from_csv->add_option("csv", args->input, "CSV file")->required();
  for (CLI::App* sub : {to_csv, from_csv}) {
    sub->add_option("--out", args->out, "Output file")->required();
    sub->add_option("--channel", args->channel, "Channel of the robot states")->capture_default_str();
    add_progress_flag(*sub, args->progress);
  }
  return [args, to_csv] {
    // Opening the output truncates it: writing over the input would destroy what is being read.
    Outputs().file("--out", args->out).input(to_csv->parsed() ? "the LCM log" : "the CSV file", args->input).check();
    if (to_csv->parsed()) {
      ProgressMeter progress("csp log export", args->progress);
      const bridge::ExportReport r = bridge::export_csv(args->input, args->out, args->channel, progress.callback());
      if (r.rows == 0) {
        std::error_code error;
        std::filesystem::remove(args->out, error);   // a header alone is no joint log
        std::string why = r.refused.empty() ? "" : "; " + r.refused;
        if (!r.damage.empty()) why += "; " + r.damage;
        throw std::runtime_error(args->input + ": no robot_state_t on channel " + args->channel + why);
      }
      progress.finish(std::to_string(r.rows) + " rows");
      std::printf("csp log export: %llu rows to %s (%llu repeated states skipped, %llu undecodable events)\n",
                  static_cast<unsigned long long>(r.rows), args->out.c_str(), static_cast<unsigned long long>(r.repeated),
                  static_cast<unsigned long long>(r.rejected));
      if (!r.missing.empty()) std::fprintf(stderr, "csp log export: %s: not in the recording: %s\n", args->input.c_str(), r.missing.c_str());
      // What was not exported, as csp replay and csp gap refuse it (one reader rule: read_state_event).
      std::string left_out = r.damage;
      if (!r.refused.empty())
        left_out += (left_out.empty() ? "" : "; ") + r.refused +
                    (r.rejected > 1 ? " (and " + std::to_string(r.rejected - 1) + " more)" : "");
      if (left_out.empty()) return 0;
      std::fprintf(stderr, "csp log export: %s: only the readable states were exported\n", left_out.c_str());
      return 1;
    }
    const uint64_t rows = bridge::import_csv(args->input, args->out, args->channel);
    std::printf("csp log import: %llu states to %s\n", static_cast<unsigned long long>(rows), args->out.c_str());
    return 0;
  };
}

}  // namespace csp::cli
