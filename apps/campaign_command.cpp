// csp campaign: many runs of a scenario over swept parameters, seeds and faults (docs/campaign.md),
// on this machine's cores or as a Slurm job array; resumable; one table and a report.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "progress.hpp"
#include "csp/campaign/slurm.hpp"
#include "csp/campaign/table.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp::cli {
namespace {

struct CampaignArguments {
  std::string file, out, dir;
  int jobs = 0;
  bool progress = false;
  bool slurm = false;
  campaign::SlurmOptions slurm_options;
  bool retries_given = false;
  int task = 0, tasks = 1;
};

// The csp executable itself, for the Slurm tasks to run.
std::string this_executable() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find this csp executable (/proc/self/exe): " + error.message());
  return self.string();
}

int print_collected(const campaign::CampaignDir& dir) {
  const campaign::Collected collected = campaign::collect_results(dir);
  std::printf("  results: %s/results.csv (%d rows, %d failed runs%s), report: %s/report/summary.md\n", dir.dir.c_str(),
              collected.rows, collected.failed, collected.missing ? format(", %d cases missing", collected.missing).c_str() : "",
              dir.dir.c_str());
  return collected.missing ? 1 : 0;
}

int print_status(const campaign::CampaignDir& dir) {
  const campaign::Status status = campaign::campaign_status(dir);
  std::printf("csp campaign: %s: %d of %d cases done, %d failed (see below), %d to run\n", dir.dir.c_str(), status.done,
              status.total, status.failed, status.total - status.done - status.failed);
  for (const std::string& failure : status.failures) std::printf("  failed %s\n", failure.c_str());
  std::ifstream submissions(dir.dir + "/slurm/submissions.log");
  std::string line, last;
  int count = 0;
  for (; std::getline(submissions, line); ++count) last = line;
  if (count)
    std::printf("  Slurm: %d submission%s, the last: %s (task logs %s/slurm/task_*.out, finish_*.out)\n", count,
                count == 1 ? "" : "s", last.c_str(), dir.dir.c_str());
  return status.done == status.total ? 0 : 1;
}

// The Slurm job after the array (campaign/slurm.hpp): cases a dead task left undone are submitted
// again while retries are left; else the table and report from what is done.
int finish_slurm_campaign(const CampaignArguments& args) {
  const campaign::CampaignDir dir = campaign::open_campaign(args.dir);
  const campaign::Status status = campaign::campaign_status(dir);
  const int undone = status.total - status.done;
  if (undone > 0 && args.slurm_options.retries > 0) {
    campaign::SlurmOptions options = args.slurm_options;
    options.retries -= 1;
    options.csp = this_executable();
    const campaign::Submission submission = campaign::submit_slurm(dir, options);
    std::printf("csp campaign finish: %s: %d of %d cases not done after the job array: submitted them again (array %s, %d tasks; "
                "%d retries left)\n",
                dir.dir.c_str(), undone, status.total, submission.array_job.c_str(), submission.tasks, options.retries);
    return 0;
  }
  // The table first: its last line says it is written (what scripts wait for).
  const int collected = print_collected(dir);
  std::printf("csp campaign finish: %s: %d of %d cases done%s\n", dir.dir.c_str(), status.done, status.total,
              undone ? ", no retries left (the same csp campaign --slurm again submits the rest)" : "");
  return collected;
}

int run_campaign(const CampaignArguments& args) {
  if (args.file.empty()) throw UsageError("expected a campaign file (csp campaign FILE --out DIR), or status, work, collect");
  if (args.out.empty()) throw UsageError("--out: expected the campaign's folder");
  const campaign::SlurmOptions& slurm = args.slurm_options;
  if (!args.slurm && (!slurm.partition.empty() || !slurm.time.empty() || slurm.array_size > 0 || args.retries_given))
    throw UsageError("--partition, --time, --array-size and --retries are options of --slurm");
  const campaign::CampaignDir dir = campaign::prepare_campaign(args.file, args.out);
  const campaign::Status before = campaign::campaign_status(dir);
  std::printf("csp campaign: %s: %zu cases, %d already done\n", args.file.c_str(), dir.cases.size(), before.done);
  if (args.slurm) {
    campaign::SlurmOptions options = args.slurm_options;
    options.csp = this_executable();
    const campaign::Submission submission = campaign::submit_slurm(dir, options);
    std::printf("  submitted Slurm job array %s (%d tasks) and job %s, which writes the table when the array ends (or submits\n"
                "  what a dead task left undone again, at most %d times): `csp campaign status %s` for progress\n",
                submission.array_job.c_str(), submission.tasks, submission.finish_job.c_str(), options.retries, args.out.c_str());
    return 0;
  }
  ProgressMeter progress("csp campaign", args.progress);
  const campaign::CasesRun run = campaign::run_cases(dir, args.jobs, 0, 1, progress.callback());
  progress.finish(format("ran %d cases, %d failed", run.ran, run.failed));
  const campaign::Status after = campaign::campaign_status(dir);
  for (const std::string& failure : after.failures) std::printf("  failed %s\n", failure.c_str());
  return print_collected(dir);
}

}  // namespace

Command add_campaign_command(CLI::App& app) {
  auto args = std::make_shared<CampaignArguments>();
  CLI::App* cmd = app.add_subcommand("campaign", "Run a scenario over swept parameters, seeds and faults, locally or on Slurm (docs/campaign.md)");
  cmd->add_option("file", args->file, "The campaign file (YAML)");
  cmd->add_option("--out", args->out, "The campaign's folder: results, report, what a resumed run skips");
  cmd->add_option("--jobs", args->jobs, "Cases run at once (default: every core)")->check(CLI::Range(1, 4096));
  cmd->add_flag("--slurm", args->slurm, "Submit the cases as a Slurm job array (sbatch) instead of running them here");
  cmd->add_option("--partition", args->slurm_options.partition, "--slurm: the partition");
  cmd->add_option("--time", args->slurm_options.time, "--slurm: each task's time limit (sbatch --time, e.g. 00:30:00)");
  cmd->add_option("--array-size", args->slurm_options.array_size, "--slurm: the tasks (default: one per case, at most 100)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option_function<int>(
         "--retries",
         [args](int retries) {
           args->slurm_options.retries = retries;
           args->retries_given = true;
         },
         "--slurm: submissions again of the cases dead tasks left undone (default 2)")
      ->check(CLI::Range(0, 100));
  add_progress_flag(*cmd, args->progress);

  CLI::App* status = cmd->add_subcommand("status", "How many of a campaign's cases are done, failed, left");
  status->add_option("dir", args->dir, "The campaign's folder")->required();
  CLI::App* collect = cmd->add_subcommand("collect", "Build results.csv and the report from the cases done");
  collect->add_option("dir", args->dir, "The campaign's folder")->required();
  CLI::App* work = cmd->add_subcommand("work", "Run one slice of a prepared campaign (what each Slurm task runs)");
  work->add_option("dir", args->dir, "The campaign's folder")->required();
  work->add_option("--task", args->task, "This task's index")->required()->check(CLI::NonNegativeNumber);
  work->add_option("--tasks", args->tasks, "The number of tasks")->required()->check(CLI::PositiveNumber);
  work->add_option("--jobs", args->jobs, "Cases run at once (default 1)")->check(CLI::Range(1, 4096));
  CLI::App* finish = cmd->add_subcommand("finish", "After a Slurm job array: the table, or what dead tasks left undone submitted again");
  finish->add_option("dir", args->dir, "The campaign's folder")->required();
  finish->add_option("--retries", args->slurm_options.retries, "Submissions again left")->required()->check(CLI::Range(0, 100));
  finish->add_option("--array-size", args->slurm_options.array_size, "The tasks of a new array")->check(CLI::Range(1, 100000));
  finish->add_option("--partition", args->slurm_options.partition, "The partition of a new array");
  finish->add_option("--time", args->slurm_options.time, "Each task's time limit in a new array");

  return [args, status, collect, work, finish] {
    if (finish->parsed()) return finish_slurm_campaign(*args);
    if (status->parsed()) return print_status(campaign::open_campaign(args->dir));
    if (collect->parsed()) return print_collected(campaign::open_campaign(args->dir));
    if (work->parsed()) {
      if (args->task >= args->tasks) throw UsageError("--task: expected a number below --tasks");
      const campaign::CampaignDir dir = campaign::open_campaign(args->dir);
      const campaign::CasesRun run = campaign::run_cases(dir, args->jobs > 0 ? args->jobs : 1, args->task, args->tasks, {});
      std::printf("csp campaign work: task %d of %d ran %d cases, %d failed\n", args->task, args->tasks, run.ran, run.failed);
      return run.failed ? 1 : 0;
    }
    return run_campaign(*args);
  };
}

}  // namespace csp::cli
