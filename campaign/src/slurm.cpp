#include "csp/campaign/slurm.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
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

}  // namespace

std::string submit_slurm(const CampaignDir& campaign, const SlurmOptions& options) {
  const int cases = static_cast<int>(campaign.cases.size());
  const int tasks = options.array_size > 0 ? std::min(options.array_size, cases) : std::min(cases, 100);
  const std::string dir = std::filesystem::absolute(campaign.dir).lexically_normal().string();
  std::filesystem::create_directories(dir + "/slurm");
  // Each task runs its slice of the cases not yet done: a resubmission runs only what is missing.
  const std::string script = dir + "/slurm/job.sh";
  write_text_file(script, "#!/bin/sh\n# csp campaign: one task of the job array (docs/campaign.md)\nexec " +
                              shell_word(options.csp) + " campaign work " + shell_word(dir) +
                              " --task \"$SLURM_ARRAY_TASK_ID\" --tasks " + std::to_string(tasks) + "\n");
  std::filesystem::permissions(script, std::filesystem::perms::owner_exec, std::filesystem::perm_options::add);

  std::vector<std::string> argv{"sbatch", "--parsable", "--job-name=csp-campaign", format("--array=0-%d", tasks - 1),
                                "--output=" + dir + "/slurm/task_%a.out", "--chdir=" + dir};
  if (!options.partition.empty()) argv.push_back("--partition=" + options.partition);
  if (!options.time.empty()) argv.push_back("--time=" + options.time);
  argv.push_back(script);
  const ProgramResult result = run_program(argv);
  if (result.status == 127) throw std::runtime_error("sbatch not found: Slurm's client commands (slurm-client) are not installed here");
  if (result.status != 0)
    throw std::runtime_error("sbatch could not submit the job array (exit status " + std::to_string(result.status) + "): " + result.output);
  // --parsable: "jobid" or "jobid;cluster".
  const std::string job = result.output.substr(0, result.output.find(';'));
  write_text_file(dir + "/slurm/job_id", job + "\n");
  return job;
}

}  // namespace csp::campaign
