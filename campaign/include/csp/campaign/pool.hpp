// A campaign's folder and its runs on this machine: one forked worker per case, at most `jobs` at a
// time; each writes runs/<id>.json atomically (a temporary file renamed), so that a killed
// campaign loses no finished case and a rerun skips every id already done.
//
//   DIR/campaign.yaml   the campaign file as given     DIR/runs/<id>.json    one finished case
//   DIR/cases.json      the campaign and its cases     DIR/runs/<id>.failed  a case whose worker died
//   DIR/runs.log        one line per case run (id, host, pid, seconds)
#pragma once

#include <string>
#include <vector>

#include "csp/campaign/cases.hpp"
#include "csp/dynamics/progress.hpp"

namespace csp::campaign {

struct CampaignDir {
  std::string dir;
  Campaign campaign;
  std::vector<Case> cases;
};

// Writes campaign.yaml and cases.json into `dir` (created); a folder that holds another campaign's
// cases is refused (std::runtime_error), the same one is resumed.
CampaignDir prepare_campaign(const std::string& campaign_file, const std::string& dir);
// A prepared folder (cases.json); std::runtime_error when there is none.
CampaignDir open_campaign(const std::string& dir);

struct Status {
  int total = 0, done = 0, failed = 0;   // failed: a worker died (a marker, no result)
  std::vector<std::string> failures;     // "<id>: why", of the failed markers
};
Status campaign_status(const CampaignDir& campaign);

// Runs the cases not yet done whose index i has i % tasks == task (all of them: task 0 of 1), at
// most `jobs` at a time (0: one per core). Progress counts finished cases.
struct CasesRun {
  int ran = 0, failed = 0;   // failed: its worker threw or died (runs/<id>.failed says why)
};
CasesRun run_cases(const CampaignDir& campaign, int jobs, int task, int tasks, const Progress& progress);

}  // namespace csp::campaign
