// A campaign on a Slurm cluster: one job array whose task K runs `csp campaign work DIR --task K
// --tasks N` (the cases with index % N == K not yet done), and a finishing job that starts when every
// task has ended, however (sbatch --dependency=afterany): `csp campaign finish DIR` collects the table
// and report, or, when a task died and left cases undone, submits the array and itself again for
// those cases, at most `retries` times. DIR must be on a filesystem the nodes share; results are
// read from its files, not from Slurm's accounting.
#pragma once

#include <string>

#include "csp/campaign/pool.hpp"

namespace csp::campaign {

struct SlurmOptions {
  std::string partition;   // empty: the cluster's default
  std::string time;        // per task, sbatch's --time (e.g. 00:30:00); empty: the partition's default
  int array_size = 0;      // tasks; 0: one per case up to 100
  int retries = 2;         // submissions again for the cases a dead task left undone
  std::string csp;         // the csp executable the tasks run (absolute)
};

struct Submission {
  std::string array_job, finish_job;   // Slurm's job ids
  int tasks = 0;
};

// Writes DIR/slurm/job.sh and finish.sh, submits the array and the finishing job with sbatch, and
// appends a line to DIR/slurm/submissions.log. std::runtime_error with sbatch's own message when it
// cannot submit (no Slurm, controller unreachable).
Submission submit_slurm(const CampaignDir& campaign, const SlurmOptions& options);

}  // namespace csp::campaign
