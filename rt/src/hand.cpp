#include "csp/rt/hand.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "csp/io/yaml_field.hpp"

namespace csp::rt {

namespace {

constexpr double kGravity = 9.81;   // [m/s^2]

// A number as a message shows it (shortest form).
std::string show(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

void require_finite(double value, const char* name) {
  if (!std::isfinite(value)) throw CommandRefused(std::string(name) + " is " + show(value) + ", not a finite number");
}

// value in [low, high], or CommandRefused naming it and the range.
void require_range(double value, double low, double high, const char* name, const char* unit, const char* why) {
  require_finite(value, name);
  if (value < low || value > high)
    throw CommandRefused(std::string(name) + " " + show(value) + " " + unit + " is outside " + show(low) + ".." +
                         show(high) + " " + unit + " (" + why + ")");
}

uint16_t whole_degrees(double celsius) { return static_cast<uint16_t>(std::clamp(std::lround(celsius), 0L, 65535L)); }

// The device sends its state as the next message once the state period is over.
template <typename State>
void publish_when_due(State now, State& published, double& next_state_in, double state_period) {
  if (next_state_in > 0.0) return;
  now.message_id = published.message_id + 1;
  published = now;
  next_state_in = state_period;
}

RigidBodyInertia point_mass(double mass, const Vector3& where) { return {mass, where, Matrix3::Zero()}; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// CommandAnswers

uint64_t CommandAnswers::issue() {
  if (of(current_) == CommandStatus::kRunning) set(current_, CommandStatus::kAborted);
  ++current_;
  set(current_, CommandStatus::kRunning);
  return current_;
}

CommandStatus CommandAnswers::of(uint64_t id) const {
  const Entry& entry = ring_[id % ring_.size()];
  // Older than the ring remembers: it was answered long ago, and a newer command has run since.
  return entry.id == id ? entry.status : CommandStatus::kAborted;
}

// ---------------------------------------------------------------------------------------------
// Hand

Hand::Hand(const HandSettings& settings)
    : settings_(settings),
      width_(std::clamp(settings.initial_width, 0.0, settings.max_width)),
      max_width_(settings.homed ? settings.max_width : 0.0),
      temperature_(settings.ambient_temperature),
      object_(settings.object),
      next_state_in_(settings.state_period) {
  published_ = state();
}

uint64_t Hand::homing() { return issue({Kind::kHoming}); }

uint64_t Hand::move(double width, double speed) {
  require_range(width, 0.0, max_width_, "width", "m", "the opening homing measured");
  require_range(speed, 0.0, settings_.max_speed, "speed", "m/s", "the Franka Hand's speed range");
  if (speed == 0.0) throw CommandRefused("speed 0 m/s: the fingers would never arrive");
  return issue({Kind::kMove, width, speed});
}

uint64_t Hand::grasp(double width, double speed, double force, double epsilon_inner, double epsilon_outer) {
  require_range(width, 0.0, max_width_, "width", "m", "the opening homing measured");
  require_range(speed, 0.0, settings_.max_speed, "speed", "m/s", "the Franka Hand's speed range");
  if (speed == 0.0) throw CommandRefused("speed 0 m/s: the fingers would never arrive");
  require_range(force, 0.0, settings_.max_force, "force", "N", "the Franka Hand's maximum grasping force");
  require_finite(epsilon_inner, "epsilon_inner");
  require_finite(epsilon_outer, "epsilon_outer");
  if (epsilon_inner < 0.0 || epsilon_outer < 0.0)
    throw CommandRefused("epsilon_inner " + show(epsilon_inner) + " m and epsilon_outer " + show(epsilon_outer) +
                         " m must not be negative");
  return issue({Kind::kGrasp, width, speed, force, epsilon_inner, epsilon_outer});
}

uint64_t Hand::stop() { return issue({Kind::kStop}); }

uint64_t Hand::issue(const Command& command) {
  // The hand takes one command at a time: a new one aborts the one running, whose motion halts.
  const uint64_t id = answers_.issue();
  moving_ = false;
  command_ = command;
  pending_ = true;
  reaction_left_ = settings_.reaction_time;
  return id;
}

void Hand::start() {
  pending_ = false;
  if (command_.kind == Kind::kGrasp && holding_) {
    answers_.answer(CommandStatus::kUnsuccessful);   // already holding: libfranka issue #108
    return;
  }
  holding_ = false;   // every other command releases the grip
  switch (command_.kind) {
    case Kind::kStop:
      answers_.answer(CommandStatus::kSuccess);
      return;
    case Kind::kHoming:
      homing_leg_ = 1;
      target_ = 0.0;
      speed_ = settings_.homing_speed;
      break;
    case Kind::kMove:
      target_ = command_.width;
      speed_ = command_.speed;
      break;
    case Kind::kGrasp:
      // Close until contact, or open to the end when the object is wider than the opening.
      target_ = command_.width <= width_ ? 0.0 : max_width_;
      speed_ = command_.speed;
      break;
  }
  moving_ = true;
  if (heading_to() == width_) arrive();
}

// The scenario places the object after homing (as a user does), so homing finds the fingers free.
bool Hand::object_between() const { return object_ && object_->width <= width_ && command_.kind != Kind::kHoming; }

bool Hand::object_in_fingers() const { return object_ && object_->width == width_; }

double Hand::heading_to() const {
  // Closing fingers meet an object standing between them; opening ones never do.
  if (target_ < width_ && object_between()) return std::max(target_, object_->width);
  return target_;
}

void Hand::arrive() {
  moving_ = false;
  const bool blocked = target_ != width_;   // stopped by the object before the target
  switch (command_.kind) {
    case Kind::kHoming:
      if (homing_leg_ == 1) {
        homing_leg_ = 2;
        target_ = settings_.max_width;
        moving_ = true;
      } else {
        max_width_ = settings_.max_width;
        answers_.answer(CommandStatus::kSuccess);
      }
      return;
    case Kind::kMove:
      answers_.answer(blocked ? CommandStatus::kUnsuccessful : CommandStatus::kSuccess);
      return;
    case Kind::kGrasp: {
      band_low_ = command_.width - command_.epsilon_inner;
      band_high_ = command_.width + command_.epsilon_outer;
      const bool in_band = band_low_ < width_ && width_ < band_high_;
      answers_.answer(in_band ? CommandStatus::kSuccess : CommandStatus::kUnsuccessful);
      if (!in_band) return;
      holding_ = true;
      force_ = command_.force;
      // Two pads press with force F each: friction carries up to 2 mu F. A heavier object slides
      // out and the fingers, still pressing, close on nothing.
      if (object_in_fingers() && 2.0 * object_->friction * force_ < object_->mass * kGravity) {
        object_.reset();
        target_ = 0.0;
        moving_ = true;
      }
      return;
    }
    case Kind::kStop:
      return;
  }
}

void Hand::step(double dt) {
  while (dt > 0.0) {
    // The next event cuts the step.
    double segment = std::min(dt, next_state_in_);
    if (pending_) segment = std::min(segment, reaction_left_);
    const double stop_at = heading_to();
    const double distance = std::abs(stop_at - width_);
    if (moving_) segment = std::min(segment, distance / speed_);

    // Motion at constant speed; heating by the motor current, a first-order lag towards the
    // temperature the present force sustains (rise proportional to force squared).
    const bool arrives = moving_ && segment >= distance / speed_;
    if (moving_) width_ = arrives ? stop_at : width_ + std::copysign(speed_ * segment, stop_at - width_);
    const double load = force() / settings_.max_continuous_force;
    const double sustained = settings_.ambient_temperature + settings_.temperature_rise_at_continuous_force * load * load;
    temperature_ = sustained + (temperature_ - sustained) * std::exp(-segment / settings_.thermal_time_constant);

    time_ += segment;
    dt -= segment;
    next_state_in_ -= segment;
    if (pending_) {
      reaction_left_ -= segment;
      if (reaction_left_ <= 0.0) start();
    }
    if (arrives) arrive();
    publish_when_due(state(), published_, next_state_in_, settings_.state_period);
  }
}

HandState Hand::state() const {
  HandState s;
  s.width = width_;
  s.max_width = max_width_;
  s.is_grasped = holding_ && band_low_ < width_ && width_ < band_high_;
  s.temperature = whole_degrees(temperature_);
  s.message_id = published_.message_id;
  return s;
}

RigidBodyInertia Hand::carried_object() const {
  if (!(holding_ && object_in_fingers())) return {};
  return point_mass(object_->mass, settings_.grasp_point);
}

// ---------------------------------------------------------------------------------------------
// VacuumPump

namespace {
constexpr double kMaxSetpoint = 100.0;   // x 10 mbar: a vacuum cannot exceed ambient pressure (~1013 mbar)
}

VacuumPump::VacuumPump(const VacuumSettings& settings)
    : settings_(settings), part_on_cup_(settings.part.has_value()), next_state_in_(settings.state_period) {
  published_ = state();
}

uint64_t VacuumPump::vacuum(unsigned setpoint, double timeout, VacuumProfile profile) {
  if (setpoint == 0 || setpoint > kMaxSetpoint)
    throw CommandRefused("vacuum setpoint " + std::to_string(setpoint) +
                         " (x 10 mbar) is outside 1..100 (a vacuum cannot exceed ambient pressure)");
  profile_ = profile;
  return issue(Kind::kVacuum, 10.0 * setpoint, timeout);
}

uint64_t VacuumPump::drop_off(double timeout) { return issue(Kind::kDropOff, 0.0, timeout); }

uint64_t VacuumPump::stop() { return issue(Kind::kStop, 0.0, 0.0); }

uint64_t VacuumPump::issue(Kind kind, double setpoint, double timeout) {
  if (kind != Kind::kStop && !(std::isfinite(timeout) && timeout > 0.0))
    throw CommandRefused("timeout " + show(timeout * 1e3) + " ms: a positive time is needed");
  const uint64_t id = answers_.issue();
  kind_ = kind;
  pending_ = true;
  running_ = false;
  reaction_left_ = settings_.reaction_time;
  timeout_left_ = timeout;
  pending_setpoint_ = setpoint;
  return id;
}

void VacuumPump::start() {
  pending_ = false;
  running_ = true;
  switch (kind_) {
    case Kind::kVacuum:
      pump_ = Pump::kSuction;
      setpoint_ = pending_setpoint_;
      part_detached_ = false;
      break;
    case Kind::kDropOff: pump_ = Pump::kBlowOff; break;
    case Kind::kStop:
      pump_ = Pump::kOff;
      answers_.answer(CommandStatus::kSuccess);
      running_ = false;
      return;
  }
  check_answer();
}

double VacuumPump::heading_to() const {
  if (pump_ != Pump::kSuction) return 0.0;
  return std::min(setpoint_, part_on_cup_ ? settings_.max_vacuum : settings_.open_vacuum);
}

double VacuumPump::time_constant() const {
  switch (pump_) {
    case Pump::kSuction: return settings_.evacuation_time_constant;
    case Pump::kBlowOff: return settings_.release_time_constant;
    case Pump::kOff: break;
  }
  // Pump off: a sealed part holds the vacuum and lets it leak slowly; an open cup loses it at once.
  return part_on_cup_ ? settings_.leak_time_constant : settings_.release_time_constant;
}

bool VacuumPump::in_control_range() const {
  // The pump regulates at the setpoint, or at the most it reaches on a part if that is less.
  return pump_ == Pump::kSuction &&
         vacuum_ >= std::min(setpoint_, settings_.max_vacuum) - settings_.control_hysteresis;
}

void VacuumPump::check_answer() {
  if (!running_) return;
  if (kind_ == Kind::kVacuum && in_control_range()) {
    answers_.answer(CommandStatus::kSuccess);
    running_ = false;
  } else if (kind_ == Kind::kDropOff && !part_present_) {
    answers_.answer(CommandStatus::kSuccess);
    running_ = false;
  } else if (timeout_left_ <= 0.0) {
    answers_.answer(CommandStatus::kUnsuccessful);
    running_ = false;
  }
}

void VacuumPump::step(double dt) {
  while (dt > 0.0) {
    double segment = std::min(dt, next_state_in_);
    if (pending_) segment = std::min(segment, reaction_left_);
    if (running_) segment = std::min(segment, timeout_left_);

    const double target = heading_to();
    vacuum_ = target + (vacuum_ - target) * std::exp(-segment / time_constant());
    // Part present above H2, absent again below H2 - h2 (the pump's hysteresis).
    const bool was_present = part_present_;
    if (vacuum_ > settings_.part_present_threshold) part_present_ = true;
    if (vacuum_ < settings_.part_present_threshold - settings_.part_present_hysteresis) part_present_ = false;
    if (was_present && !part_present_ && pump_ == Pump::kBlowOff) {
      part_detached_ = true;
      part_on_cup_ = false;   // blown off: the part has left the cup
    }

    dt -= segment;
    next_state_in_ -= segment;
    if (running_) timeout_left_ -= segment;
    if (pending_) {
      reaction_left_ -= segment;
      if (reaction_left_ <= 0.0) start();
    }
    check_answer();
    publish_when_due(state(), published_, next_state_in_, settings_.state_period);
  }
}

VacuumState VacuumPump::state() const {
  VacuumState s;
  s.in_control_range = in_control_range();
  s.part_detached = part_detached_;
  s.part_present = part_present_;
  // Air-saving control: the pump runs while it evacuates or blows off, and rests while the vacuum holds.
  s.actual_power = (pump_ == Pump::kBlowOff || (pump_ == Pump::kSuction && !s.in_control_range)) ? 100 : 0;
  s.vacuum = static_cast<uint16_t>(std::lround(std::max(vacuum_, 0.0)));
  s.message_id = published_.message_id;
  return s;
}

RigidBodyInertia VacuumPump::carried_object() const {
  if (!(part_on_cup_ && part_present_)) return {};
  return point_mass(settings_.part->mass, settings_.suction_point);
}

// ---------------------------------------------------------------------------------------------
// Scenario sections

namespace {

HeldObject read_object(const Field& f, bool with_width) {
  if (with_width) f.allow_only({"width", "mass", "friction"});
  else f.allow_only({"mass", "friction"});
  HeldObject o;
  if (with_width) o.width = non_negative(f["width"]);
  o.mass = non_negative(f["mass"]);
  if (o.mass > 3.0) f["mass"].fail("at most 3 kg (the robot's payload)");
  if (f.has("friction")) o.friction = positive(f["friction"]);
  return o;
}

}  // namespace

HandSettings read_hand_settings(const Field& f) {
  f.allow_only({"object", "homed", "initial_width", "reaction_time", "ambient_temperature"});
  HandSettings s;
  if (f.has("object")) {
    s.object = read_object(f["object"], true);
    if (s.object->width > s.max_width) f["object"]["width"].fail("at most the hand's 0.08 m");
  }
  if (f.has("homed")) s.homed = f["homed"].boolean();
  if (f.has("initial_width")) {
    s.initial_width = non_negative(f["initial_width"]);
    if (s.initial_width > s.max_width) f["initial_width"].fail("at most the hand's 0.08 m");
  }
  if (f.has("reaction_time")) s.reaction_time = non_negative(f["reaction_time"]);
  if (f.has("ambient_temperature")) s.ambient_temperature = f["ambient_temperature"].number();
  return s;
}

VacuumSettings read_vacuum_settings(const Field& f) {
  f.allow_only({"part", "reaction_time"});
  VacuumSettings s;
  if (f.has("part")) s.part = read_object(f["part"], false);
  if (f.has("reaction_time")) s.reaction_time = non_negative(f["reaction_time"]);
  return s;
}

}  // namespace csp::rt
