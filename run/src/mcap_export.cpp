#include "csp/run/mcap_export.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/mcap.hpp"
#include "csp/io/robot_config.hpp"

namespace csp::run {
namespace {

// Keys in the order written: a user's x_ columns come back in their file order.
using Json = nlohmann::ordered_json;

// The schemas, written after Foxglove's JSON schemas (github.com/foxglove/schemas, schemas/jsonschema)
// for the fields CSP fills; `required` lists what every message of CSP has (tests/mcap checks it).
constexpr const char* kTimeSchema =
    R"({"type":"object","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0,"maximum":999999999}}})";
constexpr const char* kVector3Schema =
    R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}})";
constexpr const char* kQuaternionSchema =
    R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}})";

std::string joint_state_schema() {
  Json properties = {{"timestamp", Json::parse(kTimeSchema)},
                     {"name", {{"type", "array"}, {"items", {{"type", "string"}}}}},
                     {"position", {{"type", "array"}, {"items", {{"type", "number"}}}, {"description", "q [rad]"}}},
                     {"velocity", {{"type", "array"}, {"items", {{"type", "number"}}}, {"description", "dq [rad/s]"}}},
                     {"effort", {{"type", "array"}, {"items", {{"type", "number"}}}, {"description", "tau_J [N m]"}}}};
  for (const ColumnGroup& group : kJointLogSchema) {
    if (group.name == "q" || group.name == "dq" || group.name == "tau_J") continue;
    Json item = {{"type", group.text ? "string" : "number"}};
    Json property = group.width == 1 ? item : Json{{"type", "array"}, {"items", item}};
    property["description"] = std::string(group.meaning) + (group.unit.empty() ? "" : " [" + std::string(group.unit) + "]");
    properties[std::string(group.name)] = property;
  }
  const Json schema = {{"title", "csp.JointState"},
                       {"description", "One row of a CSP joint log (docs/joint-log.md), as ROS sensor_msgs/JointState plus its other columns"},
                       {"type", "object"},
                       {"properties", properties},
                       {"patternProperties", {{"^x_", {{"type", "number"}}}}},
                       {"required", {"timestamp", "name", "position", "velocity", "effort", "t"}}};
  return schema.dump();
}

std::string frame_transforms_schema() {
  const Json transform = {{"title", "foxglove.FrameTransform"},
                          {"type", "object"},
                          {"properties",
                           {{"timestamp", Json::parse(kTimeSchema)},
                            {"parent_frame_id", {{"type", "string"}}},
                            {"child_frame_id", {{"type", "string"}}},
                            {"translation", Json::parse(kVector3Schema)},
                            {"rotation", Json::parse(kQuaternionSchema)}}},
                          {"required", {"timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"}}};
  const Json schema = {{"title", "foxglove.FrameTransforms"},
                       {"type", "object"},
                       {"properties", {{"transforms", {{"type", "array"}, {"items", transform}}}}},
                       {"required", {"transforms"}}};
  return schema.dump();
}

std::string scene_update_schema() {
  const Json pose = {{"type", "object"},
                     {"properties", {{"position", Json::parse(kVector3Schema)}, {"orientation", Json::parse(kQuaternionSchema)}}}};
  const Json color = {{"type", "object"},
                      {"properties", {{"r", {{"type", "number"}}}, {"g", {{"type", "number"}}}, {"b", {{"type", "number"}}}, {"a", {{"type", "number"}}}}}};
  const Json primitive = {{"type", "array"},
                          {"items", {{"type", "object"}, {"properties", {{"pose", pose}, {"size", Json::parse(kVector3Schema)}, {"color", color}}}}}};
  const Json entity = {{"title", "foxglove.SceneEntity"},
                       {"type", "object"},
                       {"properties",
                        {{"timestamp", Json::parse(kTimeSchema)},
                         {"frame_id", {{"type", "string"}}},
                         {"id", {{"type", "string"}}},
                         {"lifetime", Json::parse(kTimeSchema)},
                         {"frame_locked", {{"type", "boolean"}}},
                         {"metadata", {{"type", "array"}}},
                         {"cubes", primitive},
                         {"spheres", primitive},
                         {"cylinders", primitive}}},
                       {"required", {"timestamp", "frame_id", "id", "lifetime", "frame_locked"}}};
  const Json schema = {{"title", "foxglove.SceneUpdate"},
                       {"type", "object"},
                       {"properties", {{"deletions", {{"type", "array"}}}, {"entities", {{"type", "array"}, {"items", entity}}}}},
                       {"required", {"deletions", "entities"}}};
  return schema.dump();
}

std::string log_schema() {
  const Json schema = {{"title", "foxglove.Log"},
                       {"type", "object"},
                       {"properties",
                        {{"timestamp", Json::parse(kTimeSchema)},
                         {"level", {{"type", "integer"}, {"description", "0 UNKNOWN, 1 DEBUG, 2 INFO, 3 WARNING, 4 ERROR, 5 FATAL"}}},
                         {"message", {{"type", "string"}}},
                         {"name", {{"type", "string"}}},
                         {"file", {{"type", "string"}}},
                         {"line", {{"type", "integer"}, {"minimum", 0}}}}},
                       {"required", {"timestamp", "level", "message", "name", "file", "line"}}};
  return schema.dump();
}

Json time_json(uint64_t ns) { return {{"sec", ns / 1'000'000'000}, {"nsec", ns % 1'000'000'000}}; }

Json vector3_json(const Vector3& v) { return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }

Json quaternion_json(const Matrix3& rotation) {
  const Eigen::Quaterniond q(rotation);
  return {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}};
}

Json pose_json(const Vector3& position, const Matrix3& rotation) {
  return {{"position", vector3_json(position)}, {"orientation", quaternion_json(rotation)}};
}

// The row's time in ns; an MCAP time stamp is unsigned.
uint64_t log_time(const JointLog& log, std::size_t row) {
  if (!(log.t[row] >= 0.0))
    throw JointLogError(log.source + ": row " + std::to_string(row + 1) + ": t = " + std::to_string(log.t[row]) +
                        " s is before 0, which an MCAP time stamp cannot hold");
  return static_cast<uint64_t>(std::llround(log.t[row] * 1e9));
}

template <typename Value>
Json numbers_json(const Value& value) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < value.size(); ++i) array.push_back(value[i]);
  return array;
}

// The value of `group` in `row`, as JSON: a number, a word, or an array of numbers.
Json group_json(const JointLog& log, const ColumnGroup& group, std::size_t row) {
  return std::visit(
      [&](auto member) -> Json {
        const auto& value = (log.*member)[row];
        using Value = std::decay_t<decltype(value)>;
        if constexpr (std::is_same_v<Value, double> || std::is_same_v<Value, std::string>) return value;
        else return numbers_json(value);
      },
      group.member);
}

bool group_present(const JointLog& log, const ColumnGroup& group) {
  return std::visit([&](auto member) { return !(log.*member).empty(); }, group.member);
}

std::string joint_state_json(const JointLog& log, std::size_t row, uint64_t ns, const Json& names) {
  Json message = {{"timestamp", time_json(ns)},
                  {"name", names},
                  {"position", numbers_json(log.q[row])},
                  {"velocity", numbers_json(log.dq[row])},
                  {"effort", numbers_json(log.tau_J[row])}};
  for (const ColumnGroup& group : kJointLogSchema) {
    if (group.name == "q" || group.name == "dq" || group.name == "tau_J" || !group_present(log, group)) continue;
    message[std::string(group.name)] = group_json(log, group, row);
  }
  for (const ExtensionColumn& column : log.extensions) message[column.name] = column.values[row];
  return message.dump();
}

Json frame_transform(uint64_t ns, const std::string& parent, const std::string& child, const Transform& O_T_parent,
                     const Transform& O_T_child) {
  const Matrix3 parent_R_child = O_T_parent.rotation.transpose() * O_T_child.rotation;
  const Vector3 translation = O_T_parent.rotation.transpose() * (O_T_child.translation - O_T_parent.translation);
  return {{"timestamp", time_json(ns)},
          {"parent_frame_id", parent},
          {"child_frame_id", child},
          {"translation", vector3_json(translation)},
          {"rotation", quaternion_json(parent_R_child)}};
}

std::string transforms_json(const Model& model, Data& data, const std::string& robot, const Vector7& q, uint64_t ns,
                            bool with_end_effector) {
  forward_kinematics(model, data, q);
  Json transforms = Json::array();
  Transform O_T_parent;   // link0, the base
  for (int link = 1; link <= 8; ++link) {
    const Transform& O_T_link = link <= kNumJoints ? data.O_T_joint[link - 1] : data.O_T_F;   // link8: the flange
    transforms.push_back(frame_transform(ns, robot + "_link" + std::to_string(link - 1), robot + "_link" + std::to_string(link),
                                         O_T_parent, O_T_link));
    O_T_parent = O_T_link;
  }
  if (with_end_effector) transforms.push_back(frame_transform(ns, robot + "_link8", robot + "_EE", data.O_T_F, data.O_T_EE));
  return Json{{"transforms", transforms}}.dump();
}

// One obstacle as a scene entity: a box as a cube, a sphere, a capsule as a cylinder with a sphere at
// each end, a half-space as a 4 m x 4 m plate 1 cm thick under its plane (Foxglove draws nothing infinite).
Json obstacle_entity(const Obstacle& obstacle, const std::string& frame, uint64_t ns) {
  const Json color = {{"r", 0.6}, {"g", 0.6}, {"b", 0.65}, {"a", 0.5}};
  const auto primitive = [&](const Vector3& position, const Matrix3& rotation, const Vector3& size) {
    return Json{{"pose", pose_json(position, rotation)}, {"size", vector3_json(size)}, {"color", color}};
  };
  // The rotation turning z onto `axis` (a cylinder's and a plate's axis).
  const auto z_onto = [](const Vector3& axis) {
    return Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), axis).toRotationMatrix();
  };
  Json cubes = Json::array(), spheres = Json::array(), cylinders = Json::array();
  std::visit(
      [&](const auto& shape) {
        using Shape = std::decay_t<decltype(shape)>;
        if constexpr (std::is_same_v<Shape, Box>) {
          cubes.push_back(primitive(shape.pose.translation, shape.pose.rotation, 2.0 * shape.half_size));
        } else if constexpr (std::is_same_v<Shape, Sphere>) {
          spheres.push_back(primitive(shape.center, Matrix3::Identity(), Vector3::Constant(2.0 * shape.radius)));
        } else if constexpr (std::is_same_v<Shape, Capsule>) {
          const Vector3 axis = shape.b - shape.a;
          const double diameter = 2.0 * shape.radius;
          const Matrix3 rotation = axis.norm() > 0.0 ? z_onto(axis.normalized()) : Matrix3::Identity();
          cylinders.push_back(primitive(0.5 * (shape.a + shape.b), rotation, Vector3(diameter, diameter, axis.norm())));
          for (const Vector3& end : {shape.a, shape.b})
            spheres.push_back(primitive(end, Matrix3::Identity(), Vector3::Constant(diameter)));
        } else {
          constexpr double kThickness = 0.01;
          cubes.push_back(primitive(shape.point - 0.5 * kThickness * shape.normal, z_onto(shape.normal),
                                    Vector3(4.0, 4.0, kThickness)));
        }
      },
      obstacle.shape);
  Json metadata = Json::array({{{"key", "class"}, {"value", obstacle.obstacle_class}}});
  if (!obstacle.material.empty()) metadata.push_back({{"key", "material"}, {"value", obstacle.material}});
  return {{"timestamp", time_json(ns)}, {"frame_id", frame},     {"id", obstacle.name}, {"lifetime", time_json(0)},
          {"frame_locked", false},      {"metadata", metadata},  {"cubes", cubes},      {"spheres", spheres},
          {"cylinders", cylinders}};
}

std::string log_json(uint64_t ns, int level, const std::string& message) {
  return Json{{"timestamp", time_json(ns)}, {"level", level}, {"message", message}, {"name", "csp"}, {"file", ""}, {"line", 0}}
      .dump();
}

}  // namespace

McapSession mcap_session(const SessionRobot& robot, std::shared_ptr<const Scene> scene) {
  const RobotConfig config = load_robot_config(robot.robot_file);
  ModelOptions options;
  options.end_effector = robot.end_effector;
  ModelParameters parameters = model_parameters(config, options);
  if (scene && robot.recorded && robot.recorded->scene_tool) parameters = with_tool(parameters, scene->tool);
  return McapSession{Model(parameters), config.name, std::move(scene), robot.record};
}

McapExportReport write_session_mcap(const std::string& path, const JointLog& log, const McapSession& session) {
  check_joint_log(log);
  mcap::Writer writer(path, "", "csp log export");
  const std::string encoding = "jsonschema";
  const uint16_t joint_states = writer.add_channel(writer.add_schema("csp.JointState", encoding, joint_state_schema()),
                                                   kJointStatesTopic, "json");
  const uint16_t tf = writer.add_channel(writer.add_schema("foxglove.FrameTransforms", encoding, frame_transforms_schema()),
                                         kTransformsTopic, "json");
  const uint16_t errors = writer.add_channel(writer.add_schema("foxglove.Log", encoding, log_schema()), kErrorsTopic, "json");
  writer.write_metadata({kSessionMetadata,
                         {{"scenario_path", session.record.path},
                          {"scenario_text", session.record.text},
                          {"robot_path", session.record.robot_path},
                          {"robot_text", session.record.robot_text}}});

  McapExportReport report;
  const std::string& robot = session.robot_name;
  if (session.scene) {
    const uint16_t scene_channel = writer.add_channel(
        writer.add_schema("foxglove.SceneUpdate", encoding, scene_update_schema()), kSceneTopic, "json");
    const uint64_t ns = log_time(log, 0);
    Json entities = Json::array();
    for (const Obstacle& obstacle : session.scene->obstacles) entities.push_back(obstacle_entity(obstacle, robot + "_link0", ns));
    writer.write_message(scene_channel, ns, Json{{"deletions", Json::array()}, {"entities", entities}}.dump());
    report.obstacles = session.scene->obstacles.size();
  }

  Json names = Json::array();
  for (int joint = 1; joint <= kNumJoints; ++joint) names.push_back(robot + "_joint" + std::to_string(joint));
  Data data;
  const bool with_end_effector = !log.O_T_EE.empty();
  for (std::size_t row = 0; row < log.size(); ++row) {
    const uint64_t ns = log_time(log, row);
    writer.write_message(joint_states, ns, joint_state_json(log, row, ns, names));
    writer.write_message(tf, ns, transforms_json(session.model, data, robot, log.q[row], ns, with_end_effector));
    // A reflex or an error shows as it begins and ends: the columns' changes, not every row.
    if (!log.current_errors.empty() && log.current_errors[row] != (row == 0 ? "[]" : log.current_errors[row - 1])) {
      const bool errors_now = log.current_errors[row] != "[]";
      writer.write_message(errors, ns, log_json(ns, errors_now ? 4 : 2, "current_errors " + log.current_errors[row]));
      ++report.error_messages;
    }
    if (!log.robot_mode.empty() && row > 0 && log.robot_mode[row] != log.robot_mode[row - 1]) {
      const bool reflex = log.robot_mode[row] == "Reflex";
      writer.write_message(errors, ns, log_json(ns, reflex ? 3 : 2, "robot_mode " + log.robot_mode[row]));
      ++report.error_messages;
    }
  }
  writer.close();
  report.rows = log.size();
  return report;
}

namespace {

// One /joint_states message's values into row `row` of `log`; `where` names it for errors.
class JointStateReader {
 public:
  JointStateReader(JointLog& log, const std::string& where) : log_(log), where_(where) {}

  void read(const Json& message, bool first) {
    if (!message.is_object()) fail("not a JSON object");
    for (const ColumnGroup& group : kJointLogSchema) {
      const char* key = group.name == "q" ? "position" : group.name == "dq" ? "velocity" : group.name == "tau_J" ? "effort" : nullptr;
      const std::string name = key ? key : std::string(group.name);
      const auto found = message.find(name);
      std::visit([&](auto member) { take(group, found == message.end() ? nullptr : &*found, log_.*member, name, first); },
                 group.member);
    }
    std::size_t extension = 0;
    for (const auto& [key, value] : message.items()) {
      if (key.rfind(kExtensionPrefix, 0) != 0) continue;
      if (first) log_.extensions.push_back({key, {}});
      if (extension >= log_.extensions.size() || log_.extensions[extension].name != key)
        fail("column `" + key + "` differs from the first message's columns");
      log_.extensions[extension++].values.push_back(number(value, key));
    }
    if (extension != log_.extensions.size()) fail("fewer x_ columns than the first message");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw JointLogError(where_ + ": " + what); }

  double number(const Json& value, const std::string& name) const {
    if (!value.is_number()) fail("`" + name + "`: expected a number, got " + quote_input(value.dump()));
    return value.get<double>();
  }

  // A group is present in every message or in none (as a joint log's column).
  template <typename Value>
  void take(const ColumnGroup& group, const Json* value, std::vector<Value>& column, const std::string& name, bool first) {
    if (!value) {
      if (group.required) fail("no `" + name + "`");
      if (!column.empty()) fail("no `" + name + "`, which the first message had");
      return;
    }
    if (!first && column.empty()) fail("`" + name + "`, which the first message did not have");
    if constexpr (std::is_same_v<Value, std::string>) {
      if (!value->is_string()) fail("`" + name + "`: expected a string, got " + quote_input(value->dump()));
      column.push_back(value->get<std::string>());
    } else if constexpr (std::is_same_v<Value, double>) {
      column.push_back(number(*value, name));
    } else {
      if (!value->is_array() || value->size() != static_cast<std::size_t>(group.width))
        fail("`" + name + "`: expected an array of " + std::to_string(group.width) + " numbers, got " + quote_input(value->dump()));
      Value vector;
      for (int i = 0; i < group.width; ++i) vector[i] = number((*value)[i], name);
      column.push_back(vector);
    }
  }

  JointLog& log_;
  const std::string& where_;
};

}  // namespace

JointLog read_joint_log_mcap(const std::string& path) {
  mcap::File file;
  try {
    file = mcap::read_file(path);
  } catch (const mcap::McapError& e) {
    throw JointLogError(e.what());
  }
  const mcap::Channel* channel = file.channel(kJointStatesTopic);
  if (!channel || channel->message_encoding != "json")
    throw JointLogError(path + ": no " + std::string(kJointStatesTopic) + " channel of JSON messages (csp.JointState, docs/mcap.md)");
  JointLog log;
  log.source = path;
  std::size_t count = 0;
  for (const mcap::Message& message : file.messages) {
    if (message.channel_id != channel->id) continue;
    const std::string where = path + ": " + kJointStatesTopic + " message " + std::to_string(count + 1) +
                              " (log_time " + std::to_string(message.log_time) + " ns)";
    const Json json = Json::parse(message.data, nullptr, false);
    if (json.is_discarded()) throw JointLogError(where + ": not JSON");
    JointStateReader(log, where).read(json, count == 0);
    ++count;
  }
  check_joint_log(log);
  return log;
}

std::optional<scenario_t> recorded_session(const std::string& path) {
  const mcap::File file = mcap::read_file(path);
  for (const mcap::Metadata& metadata : file.metadata) {
    if (metadata.name != kSessionMetadata) continue;
    const auto value = [&](const char* key) {
      const auto found = metadata.entries.find(key);
      return found == metadata.entries.end() ? std::string() : found->second;
    };
    scenario_t record{};
    record.path = value("scenario_path");
    record.text = value("scenario_text");
    record.robot_path = value("robot_path");
    record.robot_text = value("robot_text");
    return record;
  }
  return std::nullopt;
}

}  // namespace csp::run
