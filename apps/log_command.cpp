// csp log export / import: LCM logs <-> CSV joint logs (docs/joint-log.md); a session log as MCAP
// for Foxglove and Rerun (docs/mcap.md).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/run/mcap_export.hpp"
#include "csp/run/session_log.hpp"

namespace csp::cli {
namespace {

struct LogArguments {
  std::string input, out;
  std::string channel = "CSP_STATE";
  std::string format = "csv";
  std::string robot = ModelArguments{}.robot, end_effector = "none", scene;
  bool robot_given = false, ee_given = false;
  bool progress = false;
};

// `csp log export --format mcap`: the session's rows with the robot it recorded (or the one given)
// for /tf, and the scene given or its recorded scenario's for /scene.
int export_mcap(const LogArguments& args) {
  const run::SessionRobot robot =
      run::session_robot(args.input, args.channel, {args.robot, args.end_effector, args.robot_given, args.ee_given, true});
  if (!robot.used.empty()) std::cerr << "csp log export: " << args.input << ": " << robot.used << "\n";
  for (const std::string& note : robot.notes) std::cerr << "csp log export: " << args.input << ": " << note << "\n";
  const JointLog log = run::read_joint_log(args.input, args.channel);
  // The scene: the one given, else the recorded scenario's where its file is still there (a scenario
  // record holds the scenario's text, not its scene's). A recorded scene's tool is the robot's end effector.
  std::shared_ptr<const Scene> scene;
  if (!args.scene.empty()) {
    scene = std::make_shared<Scene>(load_scene(args.scene));
  } else if (robot.recorded && robot.record.text.find("scene:") != std::string::npos) {
    try {
      scene = rt::load_scenario(robot.recorded_scenario).emulator.scene;
    } catch (const std::exception& e) {
      std::cerr << "csp log export: " << args.input << ": no /scene (nor its tool): the recorded scenario cannot be loaded (give --scene): "
                << e.what() << "\n";
    }
  }
  const run::McapSession session = run::mcap_session(robot, scene);
  const run::McapExportReport r = run::write_session_mcap(args.out, log, session);
  std::printf("csp log export: %llu rows to %s (/joint_states, /tf%s, /errors: %llu messages)\n",
              static_cast<unsigned long long>(r.rows), args.out.c_str(),
              scene ? (", /scene: " + std::to_string(r.obstacles) + " obstacles").c_str() : "",
              static_cast<unsigned long long>(r.error_messages));
  return 0;
}

}  // namespace

Command add_log_command(CLI::App& app) {
  auto args = std::make_shared<LogArguments>();
  CLI::App* cmd = app.add_subcommand("log", "Convert LCM logs to and from CSV joint logs (docs/joint-log.md)");
  cmd->require_subcommand(1);
  CLI::App* to_csv = cmd->add_subcommand(
      "export", "Write the robot states of an LCM log as CSV, or a session log (LCM or CSV) as MCAP for Foxglove and Rerun (docs/mcap.md)");
  to_csv->add_option("log", args->input, "LCM log file (csv); LCM log, CSV joint log or MCAP file (mcap)")->required();
  to_csv->add_option("--format", args->format, "csv: the joint log; mcap: /joint_states, /tf, /scene, /errors as JSON")
      ->check(CLI::IsMember({"csv", "mcap"}))
      ->capture_default_str();
  to_csv->add_option("--robot", args->robot, "mcap: robot file for /tf (default: the one the log recorded, else panda)");
  to_csv->add_option("--ee", args->end_effector, "mcap: end effector of the robot file (default: the recorded one, else none)");
  to_csv->add_option("--scene", args->scene, "mcap: scene file for /scene (default: the recorded scenario's scene, if any)");
  CLI::App* from_csv = cmd->add_subcommand("import", "Turn a CSV joint log (t, q, dq, tau_J and any optional groups) into an LCM log");
  from_csv->add_option("csv", args->input, "CSV file")->required();
  for (CLI::App* sub : {to_csv, from_csv}) {
    sub->add_option("--out", args->out, "Output file")->required();
    sub->add_option("--channel", args->channel, "Channel of the robot states")->capture_default_str();
    add_progress_flag(*sub, args->progress);
  }
  return [args, to_csv] {
    // Opening the output truncates it: writing over the input would destroy what is being read.
    Outputs().file("--out", args->out).input(to_csv->parsed() ? "the log" : "the CSV file", args->input).check();
    args->robot_given = to_csv->count("--robot") > 0;
    args->ee_given = to_csv->count("--ee") > 0;
    if (args->format != "mcap" && (args->robot_given || args->ee_given || !args->scene.empty()))
      throw UsageError("--robot, --ee and --scene: only with --format mcap");
    if (to_csv->parsed() && args->format == "mcap") return export_mcap(*args);
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
