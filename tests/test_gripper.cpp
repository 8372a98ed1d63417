// The Franka Hand and the Cobot Pump: csp::rt::Hand / VacuumPump stepped in simulated time, and
// franka::Gripper / VacuumGripper as a libfranka program uses them, in wall time.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include <yaml-cpp/yaml.h>

#include "csp/io/yaml_field.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/hand.hpp"
#include "csp/rt/scenario.hpp"
#include "franka/exception.h"
#include "franka/gripper.h"
#include "franka/vacuum_gripper.h"

namespace {

using csp::rt::CommandStatus;
using csp::rt::Hand;
using csp::rt::HandSettings;
using csp::rt::HeldObject;
using csp::rt::VacuumPump;
using csp::rt::VacuumSettings;

constexpr double kStep = 1e-3;   // [s] the tests step the models like the emulator's cycle

// Steps the device until the command is answered (at most `limit` seconds); returns the time taken.
template <typename Device>
double run_until_answered(Device& device, uint64_t command, double limit = 30.0) {
  double t = 0.0;
  while (device.answer(command) == CommandStatus::kRunning && t < limit) {
    device.step(kStep);
    t += kStep;
  }
  return t;
}

HandSettings hand_with_object(double width, double mass) {
  HandSettings s;
  s.object = HeldObject{width, mass, 0.5};
  return s;
}

// --- Hand: grasping -------------------------------------------------------------------------

TEST(Hand, GraspsAnObjectOfKnownWidthAndHoldsIt) {
  Hand hand(hand_with_object(0.03, 0.2));
  const uint64_t grasp = hand.grasp(0.03, 0.1, 60.0, 0.005, 0.005);
  run_until_answered(hand, grasp);
  EXPECT_EQ(hand.answer(grasp), CommandStatus::kSuccess);
  // The fingers stopped at the rigid object and press it with the commanded force.
  EXPECT_DOUBLE_EQ(hand.state().width, 0.03);
  EXPECT_TRUE(hand.state().is_grasped);
  EXPECT_DOUBLE_EQ(hand.force(), 60.0);
  // Held for 3 s (libfranka's grasp_object waits 3 s): still grasped, the arm carries its mass at
  // the hand's TCP.
  hand.step(3.0);
  EXPECT_TRUE(hand.state().is_grasped);
  EXPECT_DOUBLE_EQ(hand.state().width, 0.03);
  const csp::RigidBodyInertia carried = hand.carried_object();
  EXPECT_DOUBLE_EQ(carried.mass, 0.2);
  EXPECT_DOUBLE_EQ(carried.com.z(), 0.1034);
  // stop releases the grip: no longer grasped, nothing carried.
  const uint64_t stop = hand.stop();
  run_until_answered(hand, stop);
  EXPECT_EQ(hand.answer(stop), CommandStatus::kSuccess);
  EXPECT_FALSE(hand.state().is_grasped);
  EXPECT_EQ(hand.carried_object().mass, 0.0);
}

TEST(Hand, ObjectOutsideTheToleranceBandFailsTheGrasp) {
  // libfranka: grasped iff width - epsilon_inner < d < width + epsilon_outer, d where the fingers stop.
  struct Case {
    double object, commanded;
    bool grasped;
  };
  const Case cases[] = {
      {0.040, 0.030, false},   // too wide: the fingers stop 10 mm outside the band
      {0.020, 0.030, false},   // too narrow: they close past the band onto it
      {0.0349, 0.030, true},   // just inside epsilon_outer
      {0.0251, 0.030, true},   // just inside epsilon_inner
      {0.0350, 0.030, false},  // on the band's edge: the inequality is strict
  };
  for (const Case& c : cases) {
    Hand hand(hand_with_object(c.object, 0.2));
    const uint64_t grasp = hand.grasp(c.commanded, 0.1, 40.0, 0.005, 0.005);
    run_until_answered(hand, grasp);
    EXPECT_EQ(hand.answer(grasp), c.grasped ? CommandStatus::kSuccess : CommandStatus::kUnsuccessful)
        << "object " << c.object << " m, commanded " << c.commanded << " m";
    EXPECT_DOUBLE_EQ(hand.state().width, c.object);   // rigid: the fingers stop at its width
    EXPECT_EQ(hand.state().is_grasped, c.grasped);
    EXPECT_EQ(hand.carried_object().mass, c.grasped ? 0.2 : 0.0);
  }
}

TEST(Hand, NothingBetweenTheFingersClosesThemFully) {
  Hand hand{HandSettings{}};
  const uint64_t grasp = hand.grasp(0.03, 0.1, 40.0, 0.005, 0.005);
  run_until_answered(hand, grasp);
  EXPECT_EQ(hand.answer(grasp), CommandStatus::kUnsuccessful);
  EXPECT_DOUBLE_EQ(hand.state().width, 0.0);
  // A grasp of "nothing" with a band that contains 0 succeeds, carrying nothing (libfranka issue #13).
  Hand empty{HandSettings{}};
  const uint64_t zero = empty.grasp(0.0, 0.1, 40.0, 0.005, 0.005);
  run_until_answered(empty, zero);
  EXPECT_EQ(empty.answer(zero), CommandStatus::kSuccess);
  EXPECT_EQ(empty.carried_object().mass, 0.0);
}

TEST(Hand, TooLittleForceLetsTheObjectSlip) {
  // Friction of two pads carries 2 mu F: 2 x 0.5 x 10 N = 10 N < 2 kg x 9.81 m/s^2 = 19.6 N.
  Hand hand(hand_with_object(0.03, 2.0));
  const uint64_t grasp = hand.grasp(0.03, 0.1, 10.0, 0.005, 0.005);
  run_until_answered(hand, grasp);
  EXPECT_EQ(hand.answer(grasp), CommandStatus::kSuccess);   // the fingers did stop in the band
  hand.step(1.0);   // the object slides out, the pressing fingers close on nothing
  EXPECT_FALSE(hand.state().is_grasped);
  EXPECT_DOUBLE_EQ(hand.state().width, 0.0);
  EXPECT_EQ(hand.carried_object().mass, 0.0);
  // The same object with 20 N (2 x 0.5 x 20 = 20 N > 19.6 N) stays.
  Hand firm(hand_with_object(0.03, 2.0));
  const uint64_t grasp20 = firm.grasp(0.03, 0.1, 20.0, 0.005, 0.005);
  run_until_answered(firm, grasp20);
  firm.step(1.0);
  EXPECT_TRUE(firm.state().is_grasped);
  EXPECT_DOUBLE_EQ(firm.carried_object().mass, 2.0);
}

TEST(Hand, GraspWhileHoldingIsUnsuccessfulAndKeepsTheGrip) {
  Hand hand(hand_with_object(0.03, 0.2));
  run_until_answered(hand, hand.grasp(0.03, 0.1, 40.0, 0.005, 0.005));
  const uint64_t again = hand.grasp(0.03, 0.1, 20.0, 0.005, 0.005);
  run_until_answered(hand, again);
  EXPECT_EQ(hand.answer(again), CommandStatus::kUnsuccessful);   // libfranka issue #108
  EXPECT_TRUE(hand.state().is_grasped);
  EXPECT_DOUBLE_EQ(hand.force(), 40.0);
}

// --- Hand: timing, homing, limits -----------------------------------------------------------

TEST(Hand, MoveTakesDistanceOverSpeedPlusTheReactionTime) {
  const HandSettings settings;
  for (const double speed : {0.1, 0.05, 0.02}) {
    Hand hand(settings);   // starts open at 0.08 m
    const uint64_t move = hand.move(0.02, speed);
    const double taken = run_until_answered(hand, move);
    EXPECT_EQ(hand.answer(move), CommandStatus::kSuccess);
    EXPECT_NEAR(taken, settings.reaction_time + 0.06 / speed, kStep) << speed << " m/s";
    EXPECT_DOUBLE_EQ(hand.state().width, 0.02);
  }
}

TEST(Hand, FingersMoveAtConstantSpeed) {
  Hand hand{HandSettings{}};
  hand.move(0.0, 0.05);
  hand.step(0.1 + 0.4);   // reaction, then 0.4 s at 0.05 m/s
  EXPECT_NEAR(hand.state().width, 0.08 - 0.02, 1e-12);
}

TEST(Hand, MoveIntoAnObjectStopsThereUnsuccessfully) {
  Hand hand(hand_with_object(0.03, 0.2));
  const uint64_t move = hand.move(0.01, 0.1);
  run_until_answered(hand, move);
  EXPECT_EQ(hand.answer(move), CommandStatus::kUnsuccessful);
  EXPECT_DOUBLE_EQ(hand.state().width, 0.03);
  EXPECT_FALSE(hand.state().is_grasped);
}

TEST(Hand, HomingMeasuresTheMaximumWidth) {
  HandSettings settings;
  settings.homed = false;
  settings.initial_width = 0.05;
  Hand hand(settings);
  EXPECT_EQ(hand.state().max_width, 0.0);
  // Before homing the hand knows no range: any width above 0 is refused.
  EXPECT_THROW(hand.move(0.04, 0.1), csp::rt::CommandRefused);
  const uint64_t homing = hand.homing();
  const double taken = run_until_answered(hand, homing);
  EXPECT_EQ(hand.answer(homing), CommandStatus::kSuccess);
  EXPECT_DOUBLE_EQ(hand.state().max_width, 0.08);
  EXPECT_DOUBLE_EQ(hand.state().width, 0.08);
  // Close 0.05 m, then open 0.08 m, at the homing speed.
  EXPECT_NEAR(taken, settings.reaction_time + (0.05 + 0.08) / settings.homing_speed, kStep);
}

TEST(Hand, HomingThenGraspingTheScenarioObject) {
  // libfranka's grasp_object with <homing> 1: the object is placed after homing, then grasped.
  Hand hand(hand_with_object(0.03, 0.2));
  const uint64_t homing = hand.homing();
  run_until_answered(hand, homing);
  EXPECT_EQ(hand.answer(homing), CommandStatus::kSuccess);
  const uint64_t grasp = hand.grasp(0.03, 0.1, 60.0, 0.005, 0.005);
  run_until_answered(hand, grasp);
  EXPECT_EQ(hand.answer(grasp), CommandStatus::kSuccess);
  // A second grasp at the width the fingers already rest at closes onto the object at once.
  run_until_answered(hand, hand.stop());
  const uint64_t again = hand.grasp(0.03, 0.1, 60.0, 0.005, 0.005);
  const double taken = run_until_answered(hand, again);
  EXPECT_EQ(hand.answer(again), CommandStatus::kSuccess);
  EXPECT_NEAR(taken, HandSettings{}.reaction_time, kStep);
}

TEST(Hand, RefusesWhatTheHandCannotDo) {
  Hand hand{HandSettings{}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto refuses = [&](auto command, const std::string& named) {
    try {
      command();
      ADD_FAILURE() << "not refused: " << named;
    } catch (const csp::rt::CommandRefused& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  };
  refuses([&] { hand.move(-0.01, 0.1); }, "width");
  refuses([&] { hand.move(0.09, 0.1); }, "width");
  refuses([&] { hand.move(nan, 0.1); }, "width");
  refuses([&] { hand.move(0.04, 0.2); }, "speed");
  refuses([&] { hand.move(0.04, -0.1); }, "speed");
  refuses([&] { hand.move(0.04, 0.0); }, "speed");
  refuses([&] { hand.grasp(0.04, 0.1, 150.0, 0.005, 0.005); }, "force");
  refuses([&] { hand.grasp(0.04, 0.1, -1.0, 0.005, 0.005); }, "force");
  refuses([&] { hand.grasp(0.04, 0.1, 60.0, -0.005, 0.005); }, "epsilon_inner");
  refuses([&] { hand.grasp(0.04, 0.1, 60.0, 0.005, nan); }, "epsilon_outer");
  // Up to the maximum force the hand accepts; above the continuous 70 N only briefly (it heats).
  EXPECT_NO_THROW(hand.grasp(0.0, 0.1, 140.0, 0.005, 0.005));
}

TEST(Hand, HoldingForceHeatsTheMotorAsItsSquare) {
  // First-order heating: after one time constant the rise is (1 - 1/e) of rise_70 (F / 70 N)^2.
  HandSettings settings;
  Hand hand(settings);
  run_until_answered(hand, hand.grasp(0.0, 0.1, 140.0, 0.005, 0.005));
  hand.step(settings.thermal_time_constant);
  const double expected = settings.ambient_temperature +
                          settings.temperature_rise_at_continuous_force * 4.0 * (1.0 - std::exp(-1.0));
  EXPECT_NEAR(hand.state().temperature, expected, 0.5 + 1e-9);   // whole degrees, as GripperState has them
}

TEST(Hand, StateMessagesComeAtTheStatePeriod) {
  const HandSettings settings;
  Hand hand(settings);
  hand.step(1.0 + 1e-9);
  EXPECT_EQ(hand.published_state().message_id, static_cast<uint64_t>(std::floor(1.0 / settings.state_period)));
}

TEST(Hand, ANewCommandAbortsTheRunningOne) {
  Hand hand{HandSettings{}};
  const uint64_t move = hand.move(0.0, 0.01);
  hand.step(0.5);
  const uint64_t stop = hand.stop();
  EXPECT_EQ(hand.answer(move), CommandStatus::kAborted);
  run_until_answered(hand, stop);
  EXPECT_EQ(hand.answer(stop), CommandStatus::kSuccess);
  const double width = hand.state().width;
  hand.step(1.0);
  EXPECT_EQ(hand.state().width, width);   // the fingers stay where the stop left them
}

// --- The arm carries what the hand holds ------------------------------------------------------

TEST(Hand, TheArmCarriesTheGraspedObject) {
  csp::rt::Scenario scenario = csp::rt::load_scenario(csp::rt::default_scenario_path());
  csp::rt::Emulator emulator(scenario.emulator);
  Hand hand(hand_with_object(0.03, 1.0));
  run_until_answered(hand, hand.grasp(0.03, 0.1, 60.0, 0.005, 0.005));
  emulator.set_carried_object(hand.carried_object());
  // The plant gains the object's mass at the TCP; the robot's own model does not (setLoad does that).
  const double carried = scenario.emulator.plant.end_effector.mass + scenario.emulator.plant.load.mass;
  EXPECT_NEAR(emulator.plant_model().total_flange_load().mass, carried + 1.0, 1e-12);
  EXPECT_NEAR(emulator.internal_model().total_flange_load().mass, scenario.emulator.internal.end_effector.mass, 1e-12);
  // Releasing takes it off again.
  emulator.set_carried_object({});
  EXPECT_NEAR(emulator.plant_model().total_flange_load().mass, carried, 1e-12);
}

// --- Vacuum pump ------------------------------------------------------------------------------

VacuumSettings pump_with_part(bool part) {
  VacuumSettings s;
  if (part) s.part = HeldObject{0.0, 0.3, 0.5};
  return s;
}

TEST(VacuumPump, PartPresentReachesTheControlRange) {
  VacuumPump pump(pump_with_part(true));
  const uint64_t vacuum = pump.vacuum(50, 1.0, csp::rt::VacuumProfile::kP0);   // 500 mbar
  const double taken = run_until_answered(pump, vacuum);
  EXPECT_EQ(pump.answer(vacuum), CommandStatus::kSuccess);
  EXPECT_TRUE(pump.state().in_control_range);
  EXPECT_TRUE(pump.state().part_present);
  // First order towards 500 mbar: in range at 450 mbar, after tau ln(500 / 50).
  const VacuumSettings s;
  EXPECT_NEAR(taken, s.reaction_time + s.evacuation_time_constant * std::log(10.0), 2 * kStep);
  EXPECT_DOUBLE_EQ(pump.carried_object().mass, 0.3);
  // Drop off: the part is blown off and detached.
  const uint64_t drop = pump.drop_off(1.0);
  run_until_answered(pump, drop);
  EXPECT_EQ(pump.answer(drop), CommandStatus::kSuccess);
  EXPECT_TRUE(pump.state().part_detached);
  EXPECT_FALSE(pump.state().part_present);
  EXPECT_EQ(pump.carried_object().mass, 0.0);
}

TEST(VacuumPump, NoPartTimesOutUnsuccessfully) {
  VacuumPump pump(pump_with_part(false));
  const uint64_t vacuum = pump.vacuum(50, 0.5, csp::rt::VacuumProfile::kP1);
  const double taken = run_until_answered(pump, vacuum);
  EXPECT_EQ(pump.answer(vacuum), CommandStatus::kUnsuccessful);
  EXPECT_NEAR(taken, VacuumSettings{}.reaction_time + 0.5, 2 * kStep);
  EXPECT_FALSE(pump.state().part_present);
  EXPECT_FALSE(pump.state().in_control_range);
  EXPECT_LT(pump.vacuum_level(), VacuumSettings{}.part_present_threshold);
}

TEST(VacuumPump, PartPresentHasHysteresis) {
  VacuumPump pump(pump_with_part(true));
  run_until_answered(pump, pump.vacuum(50, 1.0, csp::rt::VacuumProfile::kP0));
  run_until_answered(pump, pump.stop());
  // Pump off on a sealed part: the vacuum leaks slowly; the part stays present until the vacuum
  // falls below H2 - h2, not already below H2.
  const VacuumSettings s;
  while (pump.vacuum_level() > s.part_present_threshold - 1.0) pump.step(kStep);
  EXPECT_TRUE(pump.state().part_present);
  while (pump.vacuum_level() > s.part_present_threshold - s.part_present_hysteresis - 1.0) pump.step(kStep);
  EXPECT_FALSE(pump.state().part_present);
}

TEST(VacuumPump, RefusesBadArguments) {
  VacuumPump pump(pump_with_part(true));
  EXPECT_THROW(pump.vacuum(0, 1.0, csp::rt::VacuumProfile::kP0), csp::rt::CommandRefused);
  EXPECT_THROW(pump.vacuum(200, 1.0, csp::rt::VacuumProfile::kP0), csp::rt::CommandRefused);
  EXPECT_THROW(pump.vacuum(50, 0.0, csp::rt::VacuumProfile::kP0), csp::rt::CommandRefused);
  EXPECT_THROW(pump.drop_off(-1.0), csp::rt::CommandRefused);
}

// --- Scenario sections ------------------------------------------------------------------------

// The default scenario with its `hand:` and `vacuum_gripper:` sections replaced (YAML flow text,
// empty: none), written to a temporary file with its robot file named by absolute path.
std::string write_scenario(const std::string& name, const std::string& hand, const std::string& vacuum_gripper = "") {
  YAML::Node scenario = YAML::LoadFile(csp::rt::default_scenario_path());
  scenario["robot"] = CSP_SOURCE_DIR "/configs/robots/panda.yaml";
  scenario.remove("hand");
  scenario.remove("vacuum_gripper");
  if (!hand.empty()) scenario["hand"] = YAML::Load(hand);
  if (!vacuum_gripper.empty()) scenario["vacuum_gripper"] = YAML::Load(vacuum_gripper);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "csp_gripper_tests";
  std::filesystem::create_directories(dir);
  const std::filesystem::path path = dir / name;
  std::ofstream(path) << scenario << "\n";
  return path.string();
}

TEST(Scenario, TheDefaultScenarioHoldsAnObjectForTheHandAndAPartForThePump) {
  const csp::rt::Scenario s = csp::rt::load_scenario(csp::rt::default_scenario_path());
  ASSERT_TRUE(s.hand.object.has_value());
  EXPECT_DOUBLE_EQ(s.hand.object->width, 0.03);
  EXPECT_DOUBLE_EQ(s.hand.object->mass, 0.2);
  ASSERT_TRUE(s.vacuum_gripper.part.has_value());
  EXPECT_DOUBLE_EQ(s.vacuum_gripper.part->mass, 0.3);
}

TEST(Scenario, HandAndPumpSectionsAreRead) {
  const std::string path = write_scenario("hand.yaml", "{object: {width: 0.05, mass: 0.4, friction: 0.8}, homed: false}",
                                          "{reaction_time: 0.2}");
  const csp::rt::Scenario s = csp::rt::load_scenario(path);
  ASSERT_TRUE(s.hand.object.has_value());
  EXPECT_DOUBLE_EQ(s.hand.object->width, 0.05);
  EXPECT_DOUBLE_EQ(s.hand.object->mass, 0.4);
  EXPECT_DOUBLE_EQ(s.hand.object->friction, 0.8);
  EXPECT_FALSE(s.hand.homed);
  EXPECT_FALSE(s.vacuum_gripper.part.has_value());
  EXPECT_DOUBLE_EQ(s.vacuum_gripper.reaction_time, 0.2);
}

TEST(Scenario, BadHandSectionNamesTheKey) {
  const std::string path = write_scenario("bad_hand.yaml", "{object: {width: 0.12, mass: 0.2}}");
  try {
    csp::rt::load_scenario(path);
    FAIL() << "accepted a 0.12 m object";
  } catch (const csp::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("hand.object.width"), std::string::npos) << e.what();
  }
}

// --- franka::Gripper / VacuumGripper in wall time -------------------------------------------------

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Wall-time bounds: never earlier than the hand's time, late by at most the 1 ms polling and the
// scheduler (generous for a loaded 2-core machine; only the lower bound is exact).
constexpr double kLate = 0.05;

TEST(FrankaGripper, GraspObjectAsLibfrankasExample) {
  const std::string path = write_scenario("grasp.yaml", "{object: {width: 0.03, mass: 0.2}, reaction_time: 0.02}");
  franka::Gripper gripper(path);
  franka::GripperState state = gripper.readOnce();
  EXPECT_DOUBLE_EQ(state.max_width, 0.08);
  const auto start = Clock::now();
  ASSERT_TRUE(gripper.grasp(0.03, 0.1, 60));
  const double taken = seconds_since(start);
  const double expected = 0.02 + 0.05 / 0.1;   // reaction, then 0.08 -> 0.03 m at 0.1 m/s
  EXPECT_GE(taken, expected);
  EXPECT_LT(taken, expected + kLate);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  state = gripper.readOnce();
  EXPECT_TRUE(state.is_grasped);
  EXPECT_DOUBLE_EQ(state.width, 0.03);
  EXPECT_GT(state.time.toMSec(), 0u);
  EXPECT_TRUE(gripper.stop());
  EXPECT_FALSE(gripper.readOnce().is_grasped);
  std::ostringstream json;
  json << state;
  EXPECT_EQ(json.str().find("{\"width\": 0.03, \"max_width\": 0.08, \"is_grasped\": 1"), 0u) << json.str();
}

TEST(FrankaGripper, WrongWidthReturnsFalseAndBadArgumentsThrow) {
  const std::string path = write_scenario("grasp_wide.yaml", "{object: {width: 0.05, mass: 0.2}, reaction_time: 0.0}");
  franka::Gripper gripper(path);
  EXPECT_FALSE(gripper.grasp(0.03, 0.1, 60));   // 0.05 m object, band 0.025..0.035 m
  try {
    gripper.move(0.04, 0.5);
    FAIL() << "0.5 m/s accepted";
  } catch (const franka::CommandException& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find("libfranka gripper: Command failed!"), 0u) << what;
    EXPECT_NE(what.find("speed"), std::string::npos) << what;
  }
  EXPECT_THROW(gripper.grasp(0.03, 0.1, 200), franka::CommandException);
}

TEST(FrankaGripper, StopAbortsAMoveInAnotherThread) {
  const std::string path = write_scenario("stop.yaml", "{reaction_time: 0.0}");
  franka::Gripper gripper(path);
  bool aborted = false;
  std::thread mover([&] {
    try {
      gripper.move(0.0, 0.02);   // 4 s
    } catch (const franka::CommandException& e) {
      aborted = std::string(e.what()) == "libfranka gripper: Command aborted!";
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto start = Clock::now();
  EXPECT_TRUE(gripper.stop());
  mover.join();
  EXPECT_TRUE(aborted);
  EXPECT_LT(seconds_since(start), 0.5);
  EXPECT_GT(gripper.readOnce().width, 0.05);   // stopped after ~0.2 s of closing at 0.02 m/s
}

// An IP address finds the hand of the robot franka::Robot finds there (libfranka_panda: the hand with
// a 30 mm object between its fingers, and no pump).
TEST(FrankaGripper, AnIpAddressIsTheLibfrankaScenariosHand) {
  franka::Gripper gripper("172.16.0.2");
  EXPECT_EQ(gripper.serverVersion(), 3);
  EXPECT_DOUBLE_EQ(gripper.readOnce().max_width, 0.08);
  EXPECT_TRUE(gripper.grasp(0.03, 0.1, 20.0));
}

TEST(FrankaVacuumGripper, NoPumpMountedCannotBeConnected) {
  EXPECT_THROW(franka::VacuumGripper("172.16.0.2"), franka::NetworkException);
}

TEST(FrankaVacuumGripper, VacuumObjectAsLibfrankasExample) {
  franka::VacuumGripper gripper(csp::rt::default_scenario_path());
  // libfranka's vacuum_object: setpoint 100 (the pump regulates at the most it reaches), 1 s timeout.
  ASSERT_TRUE(gripper.vacuum(100, std::chrono::milliseconds(1000)));
  franka::VacuumGripperState state = gripper.readOnce();
  EXPECT_TRUE(state.in_control_range);
  EXPECT_TRUE(state.part_present);
  EXPECT_GT(state.vacuum, 600);
  EXPECT_TRUE(gripper.dropOff(std::chrono::milliseconds(1000)));
  state = gripper.readOnce();
  EXPECT_TRUE(state.part_detached);
  EXPECT_FALSE(state.part_present);
  std::ostringstream json;
  json << state;
  EXPECT_NE(json.str().find("\"device_status\": \"Green\""), std::string::npos) << json.str();
}

TEST(FrankaVacuumGripper, NoPartFailsAtTheTimeout) {
  franka::VacuumGripper gripper(write_scenario("pump_without_part.yaml", "", "{reaction_time: 0.05}"));
  const auto start = Clock::now();
  EXPECT_FALSE(gripper.vacuum(100, std::chrono::milliseconds(300)));
  EXPECT_GE(seconds_since(start), 0.3);
  EXPECT_FALSE(gripper.readOnce().part_present);
  EXPECT_THROW(gripper.vacuum(100, std::chrono::milliseconds(0)), franka::CommandException);
}

}  // namespace
