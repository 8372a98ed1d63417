// The RobotState field list (CSP_ROBOT_STATE_FIELDS in csp/rt/robot_state.hpp) against the
// places a field must appear: the struct itself, the JSON writer, the LCM message file
// bridge/lcm/robot_state_t.lcm and the conversion to and from it. A field added to one of them
// and not to the list fails here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "csp/bridge/messages.hpp"
#include "csp/rt/robot_state.hpp"

namespace csp {
namespace {

using rt::RobotState;

// How many fields an aggregate has: the most initializers `T{...}` accepts (an initializer that
// converts to any type stands for each field; the first one too many is ill-formed).
struct AnyField {
  template <typename T>
  operator T() const;   // NOLINT: implicit on purpose, only in unevaluated context
};

template <typename T, std::size_t... I>
constexpr bool initializable_with(std::index_sequence<I...>) {
  return requires { T{(static_cast<void>(I), AnyField{})...}; };
}

template <typename T, std::size_t N = 0>
constexpr std::size_t field_count() {
  if constexpr (initializable_with<T>(std::make_index_sequence<N + 1>{})) return field_count<T, N + 1>();
  else return N;
}

struct Listed {
  const char* name;
  std::size_t offset, size, doubles;   // doubles: how many for a field of doubles, 0 for the others
};

template <typename Field>
constexpr std::size_t doubles_in() {
  if constexpr (std::is_same_v<Field, double>) return 1;
  else return sizeof(Field) / sizeof(double);
}

// A field's offset measured on an object: RobotState is not standard-layout (franka::Errors holds
// references), where offsetof is only conditionally supported.
template <typename Field>
std::size_t offset_of(Field RobotState::*field) {
  static const RobotState state{};
  return static_cast<std::size_t>(reinterpret_cast<const char*>(&(state.*field)) - reinterpret_cast<const char*>(&state));
}

const std::vector<Listed>& listed_fields() {
  static const std::vector<Listed> fields = {
#define CSP_DOUBLES(name) {#name, offset_of(&RobotState::name), sizeof(RobotState::name), doubles_in<decltype(RobotState::name)>()},
#define CSP_OTHER(name) {#name, offset_of(&RobotState::name), sizeof(RobotState::name), 0},
      CSP_ROBOT_STATE_FIELDS(CSP_DOUBLES, CSP_OTHER)
#undef CSP_DOUBLES
#undef CSP_OTHER
  };
  return fields;
}

TEST(RobotStateFields, TheListHoldsEveryFieldOfTheStructInOrder) {
  EXPECT_EQ(listed_fields().size(), field_count<RobotState>()) << "a field of RobotState is missing from CSP_ROBOT_STATE_FIELDS";
  // In declaration order, each listed field ends where padding up to the next one begins.
  std::size_t end = 0;
  for (const Listed& field : listed_fields()) {
    EXPECT_GE(field.offset, end) << field.name << " is out of declaration order";
    EXPECT_LT(field.offset - end, alignof(double)) << "an unlisted field before " << field.name;
    end = field.offset + field.size;
  }
  EXPECT_LT(sizeof(RobotState) - end, alignof(RobotState)) << "an unlisted field at the end";
}

// The JSON writer names every listed field, once, in order.
TEST(RobotStateFields, JsonWriterWritesEveryField) {
  std::ostringstream out;
  out << RobotState{};
  const std::string json = out.str();
  std::size_t position = 0;
  for (const Listed& field : listed_fields()) {
    const std::string key = '"' + std::string(field.name) + "\":";
    const std::size_t at = json.find(key, position);
    ASSERT_NE(at, std::string::npos) << field.name << " missing or out of order in " << json;
    position = at + key.size();
  }
  EXPECT_EQ(std::count(json.begin(), json.end(), ':'), static_cast<long>(listed_fields().size()));
}

// The message file declares every listed field with the right type and length, and nothing else
// besides the message's own fields.
TEST(RobotStateFields, LcmMessageFileDeclaresEveryField) {
  const std::string path = std::string(CSP_SOURCE_DIR) + "/bridge/lcm/robot_state_t.lcm";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  // "  double O_T_EE[16];  // ..." -> type, name, length (1 without brackets); constants skipped.
  const std::regex declaration(R"(^\s*(double|boolean|int8_t|int64_t)\s+(\w+)\s*(?:\[(\d+)\])?\s*;)");
  std::map<std::string, std::pair<std::string, std::size_t>> declared;
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, declaration))
      declared[m[2]] = {m[1], m[3].matched ? std::stoul(m[3]) : std::size_t{1}};
  }
  const std::map<std::string, std::pair<std::string, std::size_t>> message_only = {
      {"utime", {"int64_t", 1}}, {"message_id", {"int64_t", 1}}, {"command_received", {"boolean", 1}}};
  const std::map<std::string, std::pair<std::string, std::size_t>> by_hand = {
      {"current_errors", {"boolean", rt::kNumErrors}},
      {"last_motion_errors", {"boolean", rt::kNumErrors}},
      {"robot_mode", {"int8_t", 1}},
      {"time", {"int64_t", 1}}};

  std::set<std::string> expected;
  for (const Listed& field : listed_fields()) {
    expected.insert(field.name);
    ASSERT_TRUE(declared.count(field.name)) << field.name << " is not declared in " << path;
    const auto& [type, length] = declared.at(field.name);
    if (field.doubles > 0) {
      EXPECT_EQ(type, "double") << field.name;
      EXPECT_EQ(length, field.doubles) << field.name;
    } else {
      ASSERT_TRUE(by_hand.count(field.name)) << field.name << ": a field of another type than double needs its own conversion";
      EXPECT_EQ(std::make_pair(type, length), by_hand.at(field.name)) << field.name;
    }
  }
  for (const auto& [name, type_length] : message_only) {
    expected.insert(name);
    EXPECT_EQ(declared.count(name) ? declared.at(name) : std::make_pair(std::string(), std::size_t{0}), type_length) << name;
  }
  for (const auto& [name, type_length] : declared)
    EXPECT_TRUE(expected.count(name)) << path << " declares " << name << ", which is not a RobotState field";
}

// to_message and from_message carry every number of every field: distinct values survive the
// round trip, and each lands in the message field of the same name.
TEST(RobotStateFields, LcmConversionCarriesEveryField) {
  RobotState state;
  double next = 1.0;
  const auto fill = [&](auto& field) {
    if constexpr (std::is_same_v<std::decay_t<decltype(field)>, double>) field = next++;
    else
      for (double& v : field) v = next++;
  };
#define CSP_FILL(name) fill(state.name);
#define CSP_SKIP(name)
  CSP_ROBOT_STATE_FIELDS(CSP_FILL, CSP_SKIP)
#undef CSP_FILL
  rt::ErrorSet current, last;
  current.set(rt::Error::joint_reflex);
  last.set(rt::Error::cartesian_reflex);
  state.current_errors = current.errors();
  state.last_motion_errors = last.errors();
  state.robot_mode = rt::RobotMode::kMove;
  state.time = rt::Duration(4321);

  const robot_state_t message = bridge::to_message(state, 99, true);
  const RobotState back = bridge::from_message(message);
  double expected = 1.0;
  const auto check = [&](const char* name, const auto& in_state, const auto& in_message, const auto& after) {
    if constexpr (std::is_same_v<std::decay_t<decltype(in_state)>, double>) {
      EXPECT_EQ(in_message, expected) << name;
      EXPECT_EQ(after, expected++) << name;
    } else {
      for (std::size_t i = 0; i < in_state.size(); ++i) {
        EXPECT_EQ(in_message[i], expected) << name << "[" << i << "]";
        EXPECT_EQ(after[i], expected++) << name << "[" << i << "]";
      }
    }
  };
#define CSP_CHECK(name) check(#name, state.name, message.name, back.name);
  CSP_ROBOT_STATE_FIELDS(CSP_CHECK, CSP_SKIP)
#undef CSP_CHECK
#undef CSP_SKIP
  EXPECT_EQ(expected, next);
  EXPECT_TRUE(back.current_errors.joint_reflex);
  EXPECT_TRUE(back.last_motion_errors.cartesian_reflex);
  EXPECT_EQ(back.robot_mode, rt::RobotMode::kMove);
  EXPECT_EQ(back.time.toMSec(), 4321u);
}

}  // namespace
}  // namespace csp
