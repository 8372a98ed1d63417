// A campaign on a Slurm cluster: one job array whose task K runs `csp campaign work DIR --task K
// --tasks N` (the cases with index % N == K not yet done). DIR must be on a filesystem the nodes
// share; results are read from its files, not from Slurm's accounting.
#pragma once

#include <string>

#include "csp/campaign/pool.hpp"

namespace csp::campaign {

struct SlurmOptions {
  std::string partition;   // empty: the cluster's default
  std::string time;        // per task, sbatch's --time (e.g. 00:30:00); empty: the partition's default
  int array_size = 0;      // tasks; 0: one per case up to 100
  std::string csp;         // the csp executable the tasks run (absolute)
};

// Writes DIR/slurm/job.sh and submits it with sbatch; returns the job id. std::runtime_error with
// sbatch's own message when it cannot submit (no Slurm, controller unreachable).
std::string submit_slurm(const CampaignDir& campaign, const SlurmOptions& options);

}  // namespace csp::campaign
