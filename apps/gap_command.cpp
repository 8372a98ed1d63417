// csp gap: diagnose the sim-to-real gap of a joint log (docs/gap.md): where the simulator model
// misses, which unmodelled effect is responsible, how far the held-out gap shrinks once it is added.
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/gap/idle.hpp"
#include "csp/gap/report.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/run/session_log.hpp"

namespace csp::cli {
namespace {

struct GapArguments {
  ModelArguments model;
  std::string log, heldout, json, report;
  std::string channel = "CSP_STATE";
  double train_fraction = 0.5;
  double sample_period = gap::FilterOptions{}.sample_period;
  unsigned seed = 1;
  bool keep_idle = false;
  bool progress = false;
  bool robot_given = false, ee_given = false;   // on the command line (else a session log's recorded ones)
};

// The simulator model. For the log of a CSP session (an LCM log with the robot's scenario record)
// the robot file and end effector are the ones the robot ran with, unless given on the command line.
// What was used goes to `notes` (lines said once the diagnosis is made: an error stays one line).
Model build_model(const GapArguments& args, std::vector<std::string>& notes) {
  const run::SessionRobot robot = run::session_robot(
      args.log, args.channel, {args.model.robot, args.model.end_effector, args.robot_given, args.ee_given});
  if (!robot.used.empty()) notes.push_back("csp gap: " + args.log + ": " + robot.used);
  for (const std::string& note : robot.notes) notes.push_back("csp gap: " + args.log + ": " + note);
  ModelArguments model = args.model;
  model.robot = robot.robot_file;
  model.end_effector = robot.end_effector;
  try {
    return model.build();
  } catch (const ConfigError& e) {
    if (!robot.robot_file_recorded) throw;
    throw ConfigError("the robot file recorded in " + args.log + " (" + robot.recorded->recorded_path + ") cannot be used: " +
                      e.what() + "; give --robot");
  }
}

// A CSV joint log, or the robot states of an LCM log: told apart by content, not by name. Its idle
// stretches are left out (and said so in `notes`) unless --keep-idle.
JointLog read_log(const std::string& path, const GapArguments& args, const gap::FilterOptions& filter,
                  std::vector<std::string>& notes) {
  const JointLog log = run::read_joint_log(path, args.channel);
  if (args.keep_idle) return log;
  gap::IdleTrim trim = gap::leave_out_idle(log, filter);
  if (trim.stretches > 0) {
    const gap::IdleOptions idle;
    std::ostringstream note;
    note << "csp gap: " << path << ": left out " << std::fixed << std::setprecision(2) << trim.seconds_left_out
         << std::defaultfloat << " s of idle in " << trim.stretches << (trim.stretches == 1 ? " stretch" : " stretches")
         << " (every joint slower than " << idle.velocity << " rad/s for " << idle.min_duration
         << " s or more; --keep-idle keeps them)";
    notes.push_back(note.str());
  }
  return std::move(trim.log);
}

int run_gap(const GapArguments& args, const std::string& command_line) {
  if (!(args.train_fraction > 0.0 && args.train_fraction < 1.0))
    throw UsageError("--train-fraction: expected a number between 0 and 1");
  if (!(args.sample_period > 0.0 && args.sample_period <= 0.02))
    throw UsageError("--sample-period: expected a period in (0, 0.02] s");
  // The outputs before the diagnosis (minutes on a long log): a bad path fails at once.
  Outputs()
      .file("--json", args.json)
      .directory("--report", args.report,
                 {"report.md", "unexplained.svg", "torque_heldout.svg", "residual_vs_velocity.svg", "effect_ranking.svg"})
      .input("--log", args.log)
      .input("--log-heldout", args.heldout)
      .input("--robot", args.robot_given ? args.model.robot : "")
      .check();
  std::vector<std::string> notes;
  const Model model = build_model(args, notes);
  gap::DiagnosisOptions options;
  options.train_fraction = args.train_fraction;
  options.filter.sample_period = args.sample_period;
  options.seed = args.seed;
  const JointLog log = read_log(args.log, args, options.filter, notes);
  ProgressMeter progress("csp gap", args.progress);
  options.progress = progress.callback();
  const auto start = std::chrono::steady_clock::now();
  const gap::Diagnosis diagnosis = args.heldout.empty()
                                       ? gap::diagnose(model, log, options)
                                       : gap::diagnose(model, log, read_log(args.heldout, args, options.filter, notes), options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string causes;
  for (const std::string& cause : diagnosis.causes) causes += (causes.empty() ? "" : ", ") + cause;
  for (const std::string& note : notes) std::cerr << note << "\n";
  progress.finish("verdict: " + (causes.empty() ? std::string("no library effect") : causes) +
                  format("; %.1f %% of the held-out gap unexplained", 100.0 * diagnosis.unexplained_fraction));
  const double idle_share = gap::idle_fraction(diagnosis.heldout.samples);
  if (idle_share > 0.5)
    std::cerr << "csp gap: warning: the arm is at rest in " << std::lround(100.0 * idle_share)
              << " % of the held-out part: the verdict judges standing still more than motion (give a log with more motion, or "
                 "--log-heldout)\n";

  std::cout << "csp gap: " << args.log
            << (args.heldout.empty() ? " (first " + std::to_string(static_cast<int>(100 * args.train_fraction)) +
                                           " % training, the rest held out)"
                                     : ", held out: " + args.heldout)
            << "\n"
            << gap::summary(diagnosis) << "diagnosis time: " << seconds << " s\n";
  if (!args.json.empty()) {
    std::ofstream out(args.json);
    out << gap::to_json(diagnosis).dump(2) << '\n';
    out.close();   // (a write error may show only when the last bytes go out)
    if (!out) throw std::runtime_error(args.json + ": cannot write the diagnosis (" + std::strerror(errno) + ")");
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
  add_progress_flag(*command, args->progress);
  command->add_flag("--keep-idle", args->keep_idle,
                    "Keep the idle stretches (every joint slower than 0.01 rad/s for 0.5 s or more), which are left out by default");
  command->add_option("--json", args->json, "Write the diagnosis as JSON (docs/gap.md: the output contract)");
  command->add_option("--report", args->report, "Write report.md and SVG figures into this directory");
  return [args, command] {
    args->robot_given = command->get_option("--robot")->count() > 0;
    args->ee_given = command->get_option("--ee")->count() > 0;
    std::string line = "csp gap";
    for (const CLI::Option* option : command->get_options())
      if (option->count() > 0 && !option->get_name().empty() && option->get_name() != "--help")
        line += " " + option->get_name() + " " + option->as<std::string>();
    return run_gap(*args, line);
  };
}

}  // namespace csp::cli
