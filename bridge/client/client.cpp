#include "csp/bridge/client.hpp"

#include "csp/bridge/lcm_url.hpp"

#include <poll.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>

namespace csp::bridge {
namespace {

using Clock = std::chrono::steady_clock;

// An Eigen vector or matrix into a message array, column-major.
template <typename Derived, std::size_t N>
void copy_to(const Eigen::MatrixBase<Derived>& from, double (&to)[N]) {
  static_assert(Derived::SizeAtCompileTime == static_cast<int>(N));
  const typename Derived::PlainObject values = from;
  std::copy(values.data(), values.data() + N, to);
}

}  // namespace

Client::Client(const std::string& lcm_url, const std::string& channel_prefix, double timeout)
    : channels_(channel_prefix), lcm_(checked_lcm_url(lcm_url)), timeout_(timeout) {
  if (!lcm_.good()) throw ClientError("cannot open LCM at `" + lcm_url + "`");
  // Function-pointer subscriptions: GCC 12's UBSan misreports LCM's member-function-pointer call.
  lcm_.subscribeFunction<robot_state_t, Client*>(
      channels_.state,
      [](const lcm::ReceiveBuffer* buffer, const std::string& channel, const robot_state_t* message, Client* client) {
        client->on_state(buffer, channel, message);
      },
      this);
  lcm_.subscribeFunction<config_reply_t, Client*>(
      channels_.config_reply,
      [](const lcm::ReceiveBuffer* buffer, const std::string& channel, const config_reply_t* message, Client* client) {
        client->on_reply(buffer, channel, message);
      },
      this);
}

void Client::on_state(const lcm::ReceiveBuffer*, const std::string&, const robot_state_t* message) {
  if (!latest_ || message->message_id >= latest_->message_id) latest_ = *message;
}

void Client::on_reply(const lcm::ReceiveBuffer*, const std::string&, const config_reply_t* message) { reply_ = *message; }

const robot_state_t& Client::wait_state_after(int64_t message_id) {
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_));
  while (!latest_ || latest_->message_id <= message_id) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", timeout_);
      throw ClientError("no new robot state on " + channels_.state + " for " + seconds + " s (is csp serve running?)");
    }
    lcm_.handleTimeout(static_cast<int>(left));
  }
  // A slow controller answers the newest state, as libfranka does.
  pollfd fd{lcm_.getFileno(), POLLIN, 0};
  while (poll(&fd, 1, 0) > 0) lcm_.handle();
  return *latest_;
}

rt::RobotState Client::read_once() { return from_message(wait_state_after(latest_ ? latest_->message_id : -1)); }

void Client::request(int8_t kind, const char* what, const std::function<void(config_request_t&)>& fill) {
  config_request_t request{};
  request.utime = now_utime();
  request.request_id = next_request_id_++;
  request.request = kind;
  fill(request);
  reply_.reset();
  lcm_.publish(channels_.config, &request);
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_));
  while (!reply_ || reply_->request_id != request.request_id) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) throw ClientError(std::string(what) + ": no reply on " + channels_.config_reply + " (is csp serve running?)");
    lcm_.handleTimeout(static_cast<int>(left));
  }
  if (!reply_->ok) throw ClientError(std::string(what) + " refused: " + reply_->error);
}

void Client::set_collision_behavior(const rt::CollisionBehavior& b) {
  request(config_request_t::SET_COLLISION_BEHAVIOR, "setCollisionBehavior", [&](config_request_t& r) {
    copy_to(b.lower_torque_acceleration, r.lower_torque_thresholds_acceleration);
    copy_to(b.upper_torque_acceleration, r.upper_torque_thresholds_acceleration);
    copy_to(b.lower_torque_nominal, r.lower_torque_thresholds_nominal);
    copy_to(b.upper_torque_nominal, r.upper_torque_thresholds_nominal);
    copy_to(b.lower_force_acceleration, r.lower_force_thresholds_acceleration);
    copy_to(b.upper_force_acceleration, r.upper_force_thresholds_acceleration);
    copy_to(b.lower_force_nominal, r.lower_force_thresholds_nominal);
    copy_to(b.upper_force_nominal, r.upper_force_thresholds_nominal);
  });
}

void Client::set_joint_impedance(const Vector7& K_theta) {
  request(config_request_t::SET_JOINT_IMPEDANCE, "setJointImpedance", [&](config_request_t& r) { copy_to(K_theta, r.K_theta); });
}

void Client::set_load(const RigidBodyInertia& load) {
  request(config_request_t::SET_LOAD, "setLoad", [&](config_request_t& r) {
    r.load_mass = load.mass;
    copy_to(load.com, r.F_x_Cload);
    copy_to(load.inertia, r.load_inertia);
  });
}

void Client::set_EE(const Transform& NE_T_EE) {
  request(config_request_t::SET_EE, "setEE", [&](config_request_t& r) { copy_to(NE_T_EE.matrix(), r.NE_T_EE); });
}

void Client::set_K(const Transform& EE_T_K) {
  request(config_request_t::SET_K, "setK", [&](config_request_t& r) { copy_to(EE_T_K.matrix(), r.EE_T_K); });
}

void Client::automatic_error_recovery() {
  request(config_request_t::AUTOMATIC_ERROR_RECOVERY, "automaticErrorRecovery", [](config_request_t&) {});
}

SessionResult Client::control(rt::ControlMode mode, const rt::Controller& controller) {
  if (!latest_) wait_state_after(-1);   // the robot is there
  request(config_request_t::START_MOTION, "start of the control session",
          [&](config_request_t& r) { r.control_mode = control_mode_code(mode); });

  // The first command answers the newest state with period 0, as in libfranka.
  SessionResult result;
  robot_state_t state = *latest_;
  rt::Duration period(0);
  while (true) {
    result.state = from_message(state);
    const rt::Command command = controller(result.state, period);
    const std::vector<uint8_t> bytes = encode_command(mode, state.message_id, command, now_utime());
    lcm_.publish(channels_.command, bytes.data(), static_cast<unsigned>(bytes.size()));
    ++result.commands;
    const robot_state_t& next = wait_state_after(state.message_id);
    period = rt::Duration(static_cast<uint64_t>(next.message_id - state.message_id));
    state = next;
    if (command.motion_finished || state.robot_mode != robot_state_t::MODE_MOVE) break;
  }
  result.state = from_message(state);
  result.reflex = state.robot_mode == robot_state_t::MODE_REFLEX;
  return result;
}

}  // namespace csp::bridge
