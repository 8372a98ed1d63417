// The campaign's results: DIR/results.csv (one row per case, sorted by id: id, seed, the axes'
// parameters, then reflex, failed, the metrics, the reflex and failure texts, csp gap's verdict when
// asked, and last the columns that are not deterministic: the controller's time, the wall time) and
// DIR/report/ (summary.md and SVG figures: failure rate against each axis, the region where the
// controller holds over the first two axes, the worst runs).
#pragma once

#include <string>

#include "csp/campaign/pool.hpp"

namespace csp::campaign {

struct Collected {
  int rows = 0, failed = 0, missing = 0;
};

// Reads runs/*.json and writes results.csv and the report. Missing cases are left out (counted).
Collected collect_results(const CampaignDir& campaign);

}  // namespace csp::campaign
