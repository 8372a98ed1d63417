// The gap report: a Markdown file with SVG figures (measured vs predicted torque per joint before
// and after the selected effects, like the seed paper's Fig. 6; residual vs velocity; effect ranking).
#pragma once

#include <string>

#include "csp/gap/diagnosis.hpp"

namespace csp::gap {

// Writes report.md, torque_heldout.svg, residual_vs_velocity.svg, effect_ranking.svg into `dir`
// (created if missing); throws std::runtime_error naming what cannot be written.
void write_report(const std::string& dir, const Diagnosis& diagnosis, const std::string& command_line);

// The plain-text summary `csp gap` prints: where the gap lies, the ranking, the verdict.
std::string summary(const Diagnosis& diagnosis);

}  // namespace csp::gap
