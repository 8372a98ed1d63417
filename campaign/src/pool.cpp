#include "csp/campaign/pool.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "csp/campaign/runner.hpp"

namespace csp::campaign {
namespace {

namespace fs = std::filesystem;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Writes `text` to a temporary file beside `path` and renames it: a reader (a resumed campaign,
// `csp campaign status`) sees the whole file or none, whatever kills this process.
void write_atomically(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp." + std::to_string(getpid());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error(temporary + ": cannot be written (" + std::strerror(errno) + ")");
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string error = std::strerror(errno);
      ::close(fd);
      throw std::runtime_error(temporary + ": cannot be written (" + error + ")");
    }
    written += static_cast<std::size_t>(n);
  }
  // On disk before the name says the case is done (a node that crashes right after).
  if (::fsync(fd) != 0 || ::close(fd) != 0 || std::rename(temporary.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot be written (" + std::strerror(errno) + ")");
}

std::string result_path(const CampaignDir& campaign, const Case& c) { return campaign.dir + "/runs/" + c.id + ".json"; }
std::string failed_path(const CampaignDir& campaign, const Case& c) { return campaign.dir + "/runs/" + c.id + ".failed"; }

// One line per case run, appended in one write (whole lines from concurrent workers and tasks).
void log_run(const CampaignDir& campaign, const Case& c, double wall_time_s) {
  char host[256] = "?";
  gethostname(host, sizeof host - 1);
  char line[512];
  const int n = std::snprintf(line, sizeof line, "%s host=%s pid=%d wall_time_s=%.3f\n", c.id.c_str(), host,
                              static_cast<int>(getpid()), wall_time_s);
  const int fd = ::open((campaign.dir + "/runs.log").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) return;   // the log is a record for people; the result is what counts
  [[maybe_unused]] const ssize_t written = ::write(fd, line, static_cast<std::size_t>(n));   // the same
  ::close(fd);
}

// The worker: one case, its result or its failure on disk, then the process's end.
[[noreturn]] void run_worker(const CampaignDir& campaign, const Case& c) {
  int status = 0;
  try {
    const Outcome outcome = run_case(campaign.campaign, c);
    write_atomically(result_path(campaign, c), outcome_json(outcome));
    log_run(campaign, c, outcome.wall_time_s);
  } catch (const std::exception& e) {
    try {
      write_atomically(failed_path(campaign, c), std::string(e.what()) + "\n");
    } catch (const std::exception&) {
    }
    status = 1;
  }
  ::_exit(status);
}

std::string describe_exit(int status) {
  if (WIFSIGNALED(status)) return std::string("the worker died of signal ") + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  return "the worker exited with status " + std::to_string(WEXITSTATUS(status));
}

}  // namespace

CampaignDir prepare_campaign(const std::string& campaign_file, const std::string& dir) {
  CampaignDir campaign;
  campaign.dir = dir;
  campaign.campaign = load_campaign(campaign_file);
  campaign.campaign.path = fs::absolute(campaign_file).lexically_normal().string();
  campaign.cases = expand_cases(campaign.campaign);
  const std::string cases = cases_json(campaign.campaign, campaign.cases);
  std::error_code error;
  fs::create_directories(dir + "/runs", error);
  if (error) throw std::runtime_error(dir + ": cannot be created (" + error.message() + ")");
  const std::string cases_path = dir + "/cases.json";
  if (fs::exists(cases_path)) {
    if (read_text(cases_path) != cases)
      throw std::runtime_error(dir + " holds another campaign's cases (" + cases_path +
                               " differs from this file's): give another --out, or remove it");
  } else {
    write_atomically(dir + "/campaign.yaml", read_text(campaign_file));
    write_atomically(cases_path, cases);
  }
  return campaign;
}

CampaignDir open_campaign(const std::string& dir) {
  CampaignDir campaign;
  campaign.dir = dir;
  read_cases_json(dir + "/cases.json", campaign.campaign, campaign.cases);
  return campaign;
}

Status campaign_status(const CampaignDir& campaign) {
  Status status;
  status.total = static_cast<int>(campaign.cases.size());
  for (const Case& c : campaign.cases) {
    if (fs::exists(result_path(campaign, c))) {
      ++status.done;
    } else if (fs::exists(failed_path(campaign, c))) {
      ++status.failed;
      std::string why = read_text(failed_path(campaign, c));
      while (!why.empty() && why.back() == '\n') why.pop_back();
      status.failures.push_back(c.id + ": " + why);
    }
  }
  return status;
}

CasesRun run_cases(const CampaignDir& campaign, int jobs, int task, int tasks, const Progress& progress) {
  if (jobs <= 0) jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<const Case*> pending;
  for (const Case& c : campaign.cases)
    if (c.index % tasks == task && !fs::exists(result_path(campaign, c))) pending.push_back(&c);

  std::map<pid_t, const Case*> running;
  std::size_t next = 0, finished = 0;
  CasesRun count;
  report(progress, "cases", 0, static_cast<double>(pending.size()));
  while (next < pending.size() || !running.empty()) {
    while (next < pending.size() && static_cast<int>(running.size()) < jobs) {
      const Case& c = *pending[next++];
      std::remove(failed_path(campaign, c).c_str());   // tried again
      std::fflush(nullptr);   // nothing buffered twice
      const pid_t pid = fork();
      if (pid < 0) throw std::runtime_error(std::string("cannot start a worker (fork: ") + std::strerror(errno) + ")");
      if (pid == 0) run_worker(campaign, c);
      running[pid] = &c;
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("waiting for the workers: ") + std::strerror(errno));
    }
    const auto worker = running.find(pid);
    if (worker == running.end()) continue;
    const Case& c = *worker->second;
    running.erase(worker);
    // A worker killed from outside (out of memory, a signal) left no result: say so.
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
      ++count.failed;
      if (!fs::exists(failed_path(campaign, c))) write_atomically(failed_path(campaign, c), describe_exit(status) + "\n");
    }
    report(progress, "cases", static_cast<double>(++finished), static_cast<double>(pending.size()));
  }
  count.ran = static_cast<int>(pending.size());
  return count;
}

}  // namespace csp::campaign
