#include "bench_model.hpp"

#include <random>
#include <string>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/robot_config.hpp"

namespace csp::bench {

const Model& model() {
  static const Model instance = [] {
    ModelOptions options;
    options.inertia = "gaz2019";
    options.end_effector = "hand";
    return Model(model_parameters(load_robot_config(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"), options));
  }();
  return instance;
}

const States& states() {
  static const States instance = [] {
    States s;
    std::mt19937_64 engine(20240917);
    auto uniform = [&engine](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); };
    const JointLimits& limits = model().parameters().joint_limits;
    Data data;
    for (std::size_t k = 0; k < kNumStates; ++k) {
      Vector7 q, dq, ddq, tau;
      for (int i = 0; i < kNumJoints; ++i) {
        q[i] = uniform(limits.q_min[i], limits.q_max[i]);
        dq[i] = uniform(-2.5, 2.5);
        ddq[i] = uniform(-10.0, 10.0);
      }
      rnea(model(), data, q, dq, ddq, tau);
      s.q.push_back(q);
      s.dq.push_back(dq);
      s.ddq.push_back(ddq);
      s.tau.push_back(tau);
    }
    return s;
  }();
  return instance;
}

}  // namespace csp::bench
