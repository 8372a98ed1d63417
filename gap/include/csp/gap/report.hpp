// The gap report: a Markdown file with SVG figures (measured vs predicted torque per joint before
// and after the selected effects, like the seed paper's Fig. 6; residual vs velocity; effect ranking).
#pragma once

#include <string>

#include "csp/gap/diagnosis.hpp"

namespace csp::gap {

// Writes report.md, torque_heldout.svg, residual_vs_velocity.svg, effect_ranking.svg into `dir`
// (created if missing); throws std::runtime_error naming what cannot be written.
void write_report(const std::string& dir, const Diagnosis& diagnosis, const std::string& command_line);

// One paragraph a user can act on: how big the gap is, what the causes remove, how what is left
// splits into noise, the model's input and the rest, the strongest structure left in the measured
// torque (joint, kind, band, size against the noise floor) with what to add or check, and the fits
// that are not physical. It leads the summary and the report.
std::string finding(const Diagnosis& diagnosis);

// The plain-text summary `csp gap` prints: where the gap lies, the ranking, the verdict.
std::string summary(const Diagnosis& diagnosis);

}  // namespace csp::gap
