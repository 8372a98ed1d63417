#include "csp/view/view_model.hpp"

#include <cmath>
#include <type_traits>
#include <variant>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/geometry.hpp"

namespace csp::view {
namespace {

using nlohmann::json;

// Positions to the micrometre and rotations to 1e-6: finer than a pixel at any zoom the page has,
// and a tenth of the bytes of full precision.
double rounded(double x) { return std::round(x * 1e6) / 1e6; }

json vector_json(const auto& v) {
  json out = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(rounded(v[i]));
  return out;
}

// A pose as three.js's Matrix4.fromArray reads it: 16 numbers, column-major.
json pose_json(const Transform& pose) {
  const Eigen::Matrix4d m = pose.matrix();
  return vector_json(Eigen::Map<const Eigen::Matrix<double, 16, 1>>(m.data()));
}

json capsule_json(const Capsule& c) {
  return {{"a", vector_json(c.a)}, {"b", vector_json(c.b)}, {"radius", c.radius}};
}

json shape_json(const Shape& shape) {
  return std::visit(
      [](const auto& s) -> json {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Box>)
          return {{"type", "box"}, {"pose", pose_json(s.pose)}, {"half_size", vector_json(s.half_size)}};
        else if constexpr (std::is_same_v<S, Capsule>) {
          json c = capsule_json(s);
          c["type"] = "capsule";
          return c;
        } else if constexpr (std::is_same_v<S, Sphere>)
          return {{"type", "sphere"}, {"center", vector_json(s.center)}, {"radius", s.radius}};
        else
          return {{"type", "half_space"}, {"point", vector_json(s.point)}, {"normal", vector_json(s.normal)}};
      },
      shape);
}

json task_json(const Task& task) {
  return std::visit(
      [](const auto& t) -> json {
        using T = std::decay_t<decltype(t)>;
        if constexpr (std::is_same_v<T, UltrasoundScan>)
          return {{"type", "ultrasound_scan"}, {"start", vector_json(t.start)}, {"end", vector_json(t.end)}};
        else if constexpr (std::is_same_v<T, RcmPivot>)
          return {{"type", "rcm_pivot"}, {"trocar", vector_json(t.trocar)}};
        else
          return {{"type", "burr_hole"}, {"entry", vector_json(t.entry)}, {"axis", vector_json(t.axis)}};
      },
      task);
}

// Franka's meshes (docs/view.md): the Panda's are franka_description's "fer" set.
json mesh_set(const std::string& robot_name) {
  if (robot_name == "panda") return "fer";
  if (robot_name == "fr3") return "fr3";
  return nullptr;   // another robot: its collision capsules are drawn
}

}  // namespace

ViewModel::ViewModel(ViewRobot robot) : robot_(std::move(robot)), model_(robot_.parameters) {
  if (robot_.scene && !robot_.scene->obstacles.empty()) world_.emplace(collision_world(*robot_.scene));
}

json ViewModel::description() const {
  const JointLimits& limits = robot_.parameters.joint_limits;
  json arm_capsules = json::array();
  for (const LinkCapsule& c : franka_arm_capsules())
    arm_capsules.push_back({{"name", c.name}, {"frame", static_cast<int>(c.frame)}, {"capsule", capsule_json(c.capsule)}});
  json robot = {{"name", robot_.name},
                {"meshes", mesh_set(robot_.name)},
                {"hand", robot_.hand && !robot_.scene},
                {"arm_capsules", arm_capsules},
                {"F_T_EE", pose_json(robot_.parameters.F_T_EE)},
                {"limits",
                 {{"q_min", vector_json(limits.q_min)},
                  {"q_max", vector_json(limits.q_max)},
                  {"dq_max", vector_json(limits.dq_max)},
                  {"tau_max", vector_json(limits.tau_max)}}}};
  json scene = nullptr;
  if (robot_.scene) {
    const Scene& s = *robot_.scene;
    json tool_capsules = json::array();
    for (const NamedCapsule& c : s.tool.capsules) tool_capsules.push_back({{"name", c.name}, {"capsule", capsule_json(c.capsule)}});
    robot["tool"] = {{"name", s.tool.name}, {"capsules", tool_capsules}};
    json obstacles = json::array();
    for (const Obstacle& o : s.obstacles)
      obstacles.push_back({{"name", o.name},
                           {"class", o.obstacle_class},
                           {"material", o.material},
                           {"moves", o.motion.frequency_hz > 0.0},
                           {"shape", shape_json(o.shape)}});
    scene = {{"name", s.name}, {"obstacles", obstacles}, {"task", task_json(s.task)}};
  }
  return {{"robot", robot}, {"scene", scene}};
}

std::optional<Clearance> ViewModel::clearance(const Vector7& q, double t) {
  forward_kinematics(model_, data_, q);
  return closest_obstacle(t);
}

std::optional<Clearance> ViewModel::closest_obstacle(double t) const {
  if (!world_) return std::nullopt;
  std::optional<Clearance> closest;
  for (const CapsuleObstaclePair& pair : world_->pairs()) {
    // A moving obstacle (breathing) meets the capsule moved back by its displacement, as in rt's contact.
    const Vector3 displacement = robot_.scene->obstacles[pair.obstacle].motion.displacement(t);
    const Distance d = distance(shifted(world_->placed_capsule(data_, pair.capsule), -displacement),
                                world_->obstacles()[pair.obstacle].shape);
    if (closest && d.distance >= closest->distance) continue;
    closest = Clearance{d.distance, d.on_a + displacement, d.on_b + displacement, pair.capsule, pair.obstacle};
  }
  return closest;
}

json ViewModel::frame(const JointLog& log, std::size_t row) {
  const double t = log.t[row];
  forward_kinematics(model_, data_, log.q[row]);
  const std::optional<Clearance> closest = closest_obstacle(t);
  json links = json::array();
  for (const Transform& pose : data_.O_T_joint) links.push_back(pose_json(pose));
  json frame = {{"t", t}, {"q", vector_json(log.q[row])}, {"links", links}, {"flange", pose_json(data_.O_T_F)},
                {"ee", pose_json(data_.O_T_EE)}};
  if (!log.q_d.empty()) {
    forward_kinematics(model_, data_, log.q_d[row]);
    frame["ee_d"] = vector_json(data_.O_T_EE.translation);
  }
  if (!log.O_F_ext_hat_K.empty()) frame["force"] = vector_json(log.O_F_ext_hat_K[row].head<3>());
  if (!log.robot_mode.empty()) frame["mode"] = log.robot_mode[row];
  if (!log.current_errors.empty() && log.current_errors[row] != "[]") {
    const std::string& text = log.current_errors[row];
    json errors = json::array();
    for (std::size_t begin = 1; begin < text.size() - 1;) {   // "[a|b]" (the joint log's form)
      const std::size_t end = std::min(text.find('|', begin), text.size() - 1);
      const std::string name = text.substr(begin, end - begin);
      errors.push_back({{"name", name}, {"joint", joint_of_error(name, log, row, robot_.parameters.joint_limits)}});
      begin = end + 1;
    }
    frame["errors"] = errors;
  }
  if (closest) {
    frame["clearance"] = {{"distance", rounded(closest->distance)},
                          {"on_arm", vector_json(closest->on_arm)},
                          {"on_obstacle", vector_json(closest->on_obstacle)},
                          {"obstacle", closest->obstacle}};
  }
  if (robot_.scene) {
    json moved = json::object();
    for (std::size_t i = 0; i < robot_.scene->obstacles.size(); ++i) {
      const ObstacleMotion& motion = robot_.scene->obstacles[i].motion;
      if (motion.frequency_hz > 0.0) moved[std::to_string(i)] = vector_json(motion.displacement(t));
    }
    if (!moved.empty()) frame["obstacles"] = moved;
  }
  return frame;
}

int joint_of_error(const std::string& error, const JointLog& log, std::size_t row, const JointLimits& limits) {
  const auto has = [&](const char* word) { return error.find(word) != std::string::npos; };
  const auto largest = [](const Vector7& usage) {
    Eigen::Index joint = 0;
    usage.maxCoeff(&joint);
    return static_cast<int>(joint);
  };
  if (has("joint") && (has("position") || has("joint_limit"))) {
    // The joint nearest a position limit, as a share of its range.
    const Vector7& q = log.q[row];
    const Vector7 range = limits.q_max - limits.q_min;
    return largest(-((limits.q_max - q).cwiseMin(q - limits.q_min)).cwiseQuotient(range));
  }
  if (has("joint") && has("velocity")) return largest(log.dq[row].cwiseAbs().cwiseQuotient(limits.dq_max));
  if (error == "joint_reflex" && !log.tau_ext_hat_filtered.empty())   // the collision threshold is on tau_ext
    return largest(log.tau_ext_hat_filtered[row].cwiseAbs());
  if (error == "joint_reflex" || has("tau_j") || has("torque")) return largest(log.tau_J[row].cwiseAbs().cwiseQuotient(limits.tau_max));
  return -1;
}

}  // namespace csp::view
