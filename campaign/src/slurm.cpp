#include "csp/campaign/slurm.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "csp/io/svg_plot.hpp"

namespace csp::campaign {
namespace {

// A word for sh: single-quoted, its own quotes escaped.
std::string shell_word(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

struct ProgramResult {
  int status = -1;      // the exit status; 127: not found
  std::string output;   // stdout and stderr
};

// Runs `argv` (found on PATH) and waits for it.
ProgramResult run_program(const std::vector<std::string>& argv) {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    dup2(pipe_fds[1], STDOUT_FILENO);
    dup2(pipe_fds[1], STDERR_FILENO);
    close(pipe_fds[0]);
    close(pipe_fds[1]);
    std::vector<char*> args;
    for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(pipe_fds[1]);
  ProgramResult result;
  char buffer[4096];
  for (ssize_t n; (n = read(pipe_fds[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    result.output.append(buffer, static_cast<std::size_t>(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  while (!result.output.empty() && (result.output.back() == '\n' || result.output.back() == ' ')) result.output.pop_back();
  return result;
}

// One line more in a log of this campaign's folder.
void append_text_file(const std::string& path, const std::string& line) {
  std::ofstream out(path, std::ios::app);
  if (!(out << line) || !out.flush()) throw std::runtime_error(path + ": cannot be written");
}

// An executable sh script that runs csp with `arguments` (shell words already).
void write_script(const std::string& path, const std::string& comment, const std::string& csp, const std::string& arguments) {
  write_text_file(path, "#!/bin/sh\n# " + comment + " (docs/campaign.md)\nexec " + shell_word(csp) + " campaign " + arguments + "\n");
  std::filesystem::permissions(path, std::filesystem::perms::owner_exec, std::filesystem::perm_options::add);
}

// sbatch `what` with `options`' partition and time; returns the job id.
std::string sbatch(std::vector<std::string> argv, const SlurmOptions& options, const std::string& script, const std::string& what) {
  argv.insert(argv.begin(), {"sbatch", "--parsable"});
  if (!options.partition.empty()) argv.push_back("--partition=" + options.partition);
  if (!options.time.empty()) argv.push_back("--time=" + options.time);
  argv.push_back(script);
  const ProgramResult result = run_program(argv);
  if (result.status == 127) throw std::runtime_error("sbatch not found: Slurm's client commands (slurm-client) are not installed here");
  if (result.status != 0)
    throw std::runtime_error("sbatch could not submit " + what + " (exit status " + std::to_string(result.status) + "): " + result.output);
  return result.output.substr(0, result.output.find(';'));   // --parsable: "jobid" or "jobid;cluster"
}

}  // namespace

Submission submit_slurm(const CampaignDir& campaign, const SlurmOptions& options) {
  const int cases = static_cast<int>(campaign.cases.size());
  Submission submission;
  submission.tasks = options.array_size > 0 ? std::min(options.array_size, cases) : std::min(cases, 100);
  const std::string dir = std::filesystem::absolute(campaign.dir).lexically_normal().string();
  const std::string slurm = dir + "/slurm";
  std::filesystem::create_directories(slurm);
  // Each task runs its slice of the cases not yet done: a resubmission runs only what is missing.
  const std::string tasks = std::to_string(submission.tasks);
  write_script(slurm + "/job.sh", "csp campaign: one task of the job array", options.csp,
               "work " + shell_word(dir) + " --task \"$SLURM_ARRAY_TASK_ID\" --tasks " + tasks);
  submission.array_job = sbatch({"--job-name=csp-campaign", "--array=0-" + std::to_string(submission.tasks - 1),
                                 "--output=" + slurm + "/task_%a.out", "--chdir=" + dir},
                                options, slurm + "/job.sh", "the job array");

  // The finishing job: once every task has ended (done, failed, cancelled, out of time).
  std::string finish = "finish " + shell_word(dir) + " --retries " + std::to_string(options.retries) + " --array-size " + tasks;
  if (!options.partition.empty()) finish += " --partition " + shell_word(options.partition);
  if (!options.time.empty()) finish += " --time " + shell_word(options.time);
  write_script(slurm + "/finish.sh", "csp campaign: after the job array, collect or submit what is missing again", options.csp,
               finish);
  try {
    submission.finish_job = sbatch({"--job-name=csp-campaign-finish", "--dependency=afterany:" + submission.array_job,
                                    "--output=" + slurm + "/finish_%j.out", "--chdir=" + dir},
                                   options, slurm + "/finish.sh", "the job that finishes the array");
  } catch (const std::runtime_error&) {
    run_program({"scancel", submission.array_job});   // no array left running without its finish
    throw;
  }
  append_text_file(slurm + "/submissions.log", format("array %s (%d tasks), finish %s, retries left %d\n", submission.array_job.c_str(),
                                                       submission.tasks, submission.finish_job.c_str(), options.retries));
  return submission;
}

}  // namespace csp::campaign
