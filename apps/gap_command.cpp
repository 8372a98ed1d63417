// csp gap: diagnose the sim-to-real gap of a joint log (docs/gap.md): where the simulator model
// misses, which unmodelled effect is responsible, how far the held-out gap shrinks once it is added.
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/gap/report.hpp"

namespace csp::cli {
namespace {

struct GapArguments {
  ModelArguments model;
  std::string log, heldout, json, report;
  std::string channel = "CSP_STATE";
  double train_fraction = 0.5;
  double sample_period = gap::FilterOptions{}.sample_period;
  unsigned seed = 1;
};

// A CSV joint log, or the robot states of an LCM log: told apart by content, not by name.
JointLog read_log(const std::string& path, const std::string& channel) {
  return bridge::is_lcm_log(path) ? bridge::read_joint_log_lcm(path, channel) : read_joint_log_csv(path);
}

int run_gap(const GapArguments& args, const std::string& command_line) {
  if (!(args.train_fraction > 0.0 && args.train_fraction < 1.0))
    throw UsageError("--train-fraction: expected a number between 0 and 1");
  if (!(args.sample_period > 0.0 && args.sample_period <= 0.02))
    throw UsageError("--sample-period: expected a period in (0, 0.02] s");
  const Model model = args.model.build();
  gap::DiagnosisOptions options;
  options.train_fraction = args.train_fraction;
  options.filter.sample_period = args.sample_period;
  options.seed = args.seed;
  const JointLog log = read_log(args.log, args.channel);
  const auto start = std::chrono::steady_clock::now();
  const gap::Diagnosis diagnosis = args.heldout.empty()
                                       ? gap::diagnose(model, log, options)
                                       : gap::diagnose(model, log, read_log(args.heldout, args.channel), options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::cout << "csp gap: " << args.log
            << (args.heldout.empty() ? " (first " + std::to_string(static_cast<int>(100 * args.train_fraction)) +
                                           " % training, the rest held out)"
                                     : ", held out: " + args.heldout)
            << "\n"
            << gap::summary(diagnosis) << "diagnosis time: " << seconds << " s\n";
  if (!args.json.empty()) {
    std::ofstream out(args.json);
    out << gap::to_json(diagnosis).dump(2) << '\n';
    if (!out) throw std::runtime_error("cannot write " + args.json);
    std::cout << "json: " << args.json << '\n';
  }
  if (!args.report.empty()) {
    gap::write_report(args.report, diagnosis, command_line);
    std::cout << "report: " << args.report << "/report.md\n";
  }
  return 0;
}

}  // namespace

Command add_gap_command(CLI::App& app) {
  auto args = std::make_shared<GapArguments>();
  CLI::App* command = app.add_subcommand(
      "gap",
      "Diagnose the sim-to-real gap of a joint log: where the model misses, which unmodelled effect causes it, "
      "how far the held-out gap shrinks once it is added");
  command
      ->add_option("--log", args->log,
                   "Joint log: CSV (t, q1..q7, dq1..dq7, tau_J1..tau_J7, ...; docs/joint-log.md) or an LCM log")
      ->required();
  command->add_option("--log-heldout", args->heldout,
                      "A second log (another trajectory) to judge the fits on; without it the log is split in time");
  command->add_option("--channel", args->channel, "Channel of the robot states in an LCM log")->capture_default_str();
  args->model.add_to(*command);
  command
      ->add_option("--train-fraction", args->train_fraction,
                   "Fraction of --log used for training without --log-heldout")
      ->capture_default_str();
  command->add_option("--sample-period", args->sample_period, "Period of the filtered samples used for fitting [s]")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Seed of the random regressors of the significance test")
      ->capture_default_str();
  command->add_option("--json", args->json, "Write the diagnosis as JSON (docs/gap.md: the output contract)");
  command->add_option("--report", args->report, "Write report.md and SVG figures into this directory");
  return [args, command] {
    std::string line = "csp gap";
    for (const CLI::Option* option : command->get_options())
      if (option->count() > 0 && !option->get_name().empty() && option->get_name() != "--help")
        line += " " + option->get_name() + " " + option->as<std::string>();
    return run_gap(*args, line);
  };
}

}  // namespace csp::cli
