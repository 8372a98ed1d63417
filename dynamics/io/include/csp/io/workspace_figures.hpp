// The reachable-workspace figures of `csp workspace` (the seed paper's Fig. 3): side and top
// density maps of the sampled positions with the shoulder, the sampled maximum and Franka's
// datasheet reach drawn in.
#pragma once

#include <string>

#include "csp/dynamics/workspace.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp {

// Franka's datasheet "maximum reach" of the Panda/FR3 arm [m]; it is the flange's.
constexpr double kFrankaDatasheetReach = 0.855;

struct WorkspaceFigures {
  HeatMapFigure side;   // signed horizontal radius vs z (WorkspaceResult::side)
  HeatMapFigure top;    // x vs y (WorkspaceResult::top)
};

// The figures of a sample_workspace(model, options) result. `robot` names the robot in the
// titles; `end_effector` names the end effector whose positions were sampled, empty when they
// are the flange's (then the flange statistics are drawn, else the end effector's).
WorkspaceFigures workspace_figures(const WorkspaceResult& result, const WorkspaceOptions& options,
                                   const std::string& robot, const std::string& end_effector);

}  // namespace csp
