#include "csp/bridge/controllers.hpp"

#include <memory>

namespace csp::bridge {
namespace {

// Motion time, advanced by each call's period; the last command is the one at `duration`.
struct MotionClock {
  double time = 0.0;
  bool finished(rt::Duration period, double duration) {
    time += period.toSec();
    return time >= duration - 1e-9;
  }
};

}  // namespace

rt::Controller float_controller(const Vector7& damping, double duration) {
  auto clock = std::make_shared<MotionClock>();
  return [clock, damping, duration](const rt::RobotState& state, rt::Duration period) {
    const bool finished = clock->finished(period, duration);
    return rt::Command{-damping.cwiseProduct(Vector7(state.dq.data())), finished};
  };
}

rt::Controller joint_impedance_controller(const Vector7& stiffness, const Vector7& damping,
                                          const rt::RampedSineReference& trajectory, double duration) {
  struct Context {
    MotionClock clock;
    Vector7 q0;
  };
  auto context = std::make_shared<Context>();
  return [context, stiffness, damping, trajectory, duration](const rt::RobotState& state, rt::Duration period) {
    if (period.toMSec() == 0) context->q0 = Vector7(state.q_d.data());   // the first call: the start pose
    const bool finished = context->clock.finished(period, duration);
    Vector7 q_d, dq_d, ddq_d;
    trajectory.evaluate(context->q0, context->clock.time, q_d, dq_d, ddq_d);
    const Vector7 tau = stiffness.cwiseProduct(q_d - Vector7(state.q.data())) + damping.cwiseProduct(dq_d - Vector7(state.dq.data()));
    return rt::Command{tau, finished};
  };
}

Vector7 example_joint_stiffness() { return (Vector7() << 600, 600, 600, 600, 250, 150, 50).finished(); }
Vector7 example_joint_damping() { return (Vector7() << 50, 50, 50, 20, 20, 20, 10).finished(); }

rt::RampedSineReference example_excitation(double amplitude) {
  rt::RampedSineReference trajectory;
  trajectory.amplitude = Vector7::Constant(amplitude);
  trajectory.frequency_hz << 0.12, 0.17, 0.21, 0.15, 0.25, 0.19, 0.3;   // as configs/scenarios/default.yaml
  trajectory.ramp = 1.0;
  return trajectory;
}

}  // namespace csp::bridge
