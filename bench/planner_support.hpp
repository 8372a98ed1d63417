// Bench helpers shared by the planner benchmarks: a shipped scene and the robot carrying its tool.
#pragma once

#include <string>
#include <vector>

#include "csp/io/robot_config.hpp"
#include "csp/io/scene.hpp"

namespace csp::bench {

inline const std::vector<std::string> kShippedScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};

inline Scene shipped_scene(int index) {
  return load_scene(std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + kShippedScenes[index] + ".yaml");
}

// The Panda with the scene's tool as its end effector.
inline Model panda_with_tool(const Scene& scene) {
  return Model(with_tool(
      model_parameters(load_robot_config(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"), {}), scene.tool));
}

}  // namespace csp::bench
