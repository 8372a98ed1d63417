// The controller side of `csp serve`, shaped like libfranka's franka::Robot: configuration calls
// between motions and control(mode, callback), which starts a control session and calls the
// callback once per received state until it returns motion_finished or the robot ends the
// session (reflex). Each command echoes the message_id of the state it answers.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "csp/bridge/messages.hpp"

namespace csp::bridge {

// No robot on the bus, or a request refused (the message names which and why).
class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SessionResult {
  rt::RobotState state;           // the last state received (Idle after motion_finished, Reflex after a reflex)
  uint64_t commands = 0;          // commands sent
  bool reflex = false;
};

class Client {
 public:
  explicit Client(const std::string& lcm_url = kDefaultLcmUrl, const std::string& channel_prefix = "",
                  double timeout = 2.0);

  // The newest state, waiting for one newer than any seen so far; throws after the timeout.
  rt::RobotState read_once();

  void set_collision_behavior(const rt::CollisionBehavior& behavior);
  void set_joint_impedance(const Vector7& K_theta);
  void set_load(const RigidBodyInertia& load);
  void set_EE(const Transform& NE_T_EE);
  void set_K(const Transform& EE_T_K);
  void automatic_error_recovery();

  SessionResult control(rt::ControlMode mode, const rt::Controller& controller);

 private:
  void on_state(const lcm::ReceiveBuffer* buffer, const std::string& channel, const robot_state_t* message);
  void on_reply(const lcm::ReceiveBuffer* buffer, const std::string& channel, const config_reply_t* message);
  // Handles messages until a state newer than `message_id` arrived, then takes every pending one.
  const robot_state_t& wait_state_after(int64_t message_id);
  // Sends a request of `kind` (config_request_t's constants) with the fields `fill` sets, and
  // waits for its reply; throws ClientError naming `what` if it is refused or unanswered.
  void request(int8_t kind, const char* what, const std::function<void(config_request_t&)>& fill);

  Channels channels_;
  lcm::LCM lcm_;
  double timeout_;
  std::optional<robot_state_t> latest_;
  std::optional<config_reply_t> reply_;
  int64_t next_request_id_ = 1;
};

}  // namespace csp::bridge
