// Bench helpers shared by the planner benchmarks: a shipped scene and the robot carrying its tool.
#pragma once

#include <string>
#include <vector>

#include "csp/io/robot_config.hpp"
#include "csp/planners/scene.hpp"

namespace csp::bench {

inline const std::vector<std::string> kShippedScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};

inline planners::Scene shipped_scene(int index) {
  return planners::load_scene(std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + kShippedScenes[index] + ".yaml");
}

// The Panda with the scene's tool as its end effector.
inline Model panda_with_tool(const planners::Scene& scene) {
  return Model(planners::with_tool(
      model_parameters(load_robot_config(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"), {}), scene.tool));
}

}  // namespace csp::bench
