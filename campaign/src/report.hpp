// The campaign's report (table.hpp): summary.md and the figures, from the collected rows.
#pragma once

#include <vector>

#include "csp/campaign/pool.hpp"
#include "csp/campaign/runner.hpp"

namespace csp::campaign {

struct Row {
  const Case* c;
  Outcome outcome;
};

// Writes DIR/report/summary.md and its SVG figures (created; old figures replaced).
void write_report(const CampaignDir& campaign, const std::vector<Row>& rows, int missing);

}  // namespace csp::campaign
