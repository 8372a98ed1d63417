#include "csp/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

#include "csp/io/yaml_field.hpp"

namespace csp {
namespace {

// Every block that carries numbers names where they come from (or says `assumption: ...`).
void require_source(const Field& field) {
  if (field["source"].text().empty()) field["source"].fail("a non-empty source (a citation or `assumption: ...`)");
}

Vector3 unit_vector(const Field& field) {
  const Vector3 v = field.vector<3>();
  if (std::abs(v.norm() - 1.0) > 1e-6) field.fail("a unit vector (norm 1 within 1e-6)");
  return v;
}

Matrix3 rotation_rpy(const Vector3& rpy) {   // URDF convention: R = Rz(yaw) Ry(pitch) Rx(roll)
  return (Eigen::AngleAxisd(rpy[2], Vector3::UnitZ()) * Eigen::AngleAxisd(rpy[1], Vector3::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Vector3::UnitX()))
      .toRotationMatrix();
}

Box box(const Field& f) {
  Box b;
  if (f.has("min") || f.has("max")) {   // axis-aligned, by its corners
    f.allow_only({"min", "max"});
    const Vector3 lo = f["min"].vector<3>(), hi = f["max"].vector<3>();
    if ((hi.array() <= lo.array()).any()) f["max"].fail("max > min on every axis");
    b.pose.translation = 0.5 * (lo + hi);
    b.half_size = 0.5 * (hi - lo);
    return b;
  }
  f.allow_only({"center", "size", "rpy"});
  b.pose.translation = f["center"].vector<3>();
  const Vector3 size = f["size"].vector<3>();
  if ((size.array() <= 0.0).any()) f["size"].fail("3 positive edge lengths");
  b.half_size = 0.5 * size;
  if (f.has("rpy")) b.pose.rotation = rotation_rpy(f["rpy"].vector<3>());
  return b;
}

Capsule capsule(const Field& f, std::initializer_list<const char*> keys) {
  f.allow_only(keys);
  return {f["a"].vector<3>(), f["b"].vector<3>(), positive(f["radius"])};
}

Shape shape(const Field& obstacle) {
  int kinds = 0;
  for (const char* kind : {"box", "capsule", "sphere", "half_space"}) kinds += obstacle.has(kind) ? 1 : 0;
  if (kinds != 1) obstacle.fail("exactly one shape: box, capsule, sphere or half_space");
  if (obstacle.has("box")) return box(obstacle["box"]);
  if (obstacle.has("capsule")) return capsule(obstacle["capsule"], {"a", "b", "radius"});
  if (obstacle.has("sphere")) {
    const Field s = obstacle["sphere"];
    s.allow_only({"center", "radius"});
    return Sphere{s["center"].vector<3>(), positive(s["radius"])};
  }
  const Field h = obstacle["half_space"];
  h.allow_only({"point", "normal"});
  return HalfSpace{h["point"].vector<3>(), unit_vector(h["normal"])};
}

// materials: {name: {stiffness, exponent, damping, friction, source}}; the law's ranges are
// material_problem's (csp/dynamics/contact.hpp), reported on the offending key.
std::map<std::string, Material> materials(const Field& f) {
  std::map<std::string, Material> out;
  for (const auto& name : f.keys()) {
    const Field m = f[name];
    m.allow_only({"stiffness", "exponent", "damping", "friction", "source"});
    require_source(m);
    const Material material{m["stiffness"].number(), m["exponent"].number(), m["damping"].number(),
                            m["friction"].number()};
    if (const auto problem = material_problem(material)) m[std::string(problem->key)].fail(std::string(problem->expected));
    out[name] = material;
  }
  return out;
}

ObstacleMotion motion(const Field& f) {
  f.allow_only({"amplitude", "frequency_hz", "source"});
  require_source(f);
  // A motion the 1 kHz loop can sample (below its Nyquist frequency), within a robot's reach.
  const Vector3 amplitude = f["amplitude"].vector<3>();
  if (amplitude.norm() > 10.0) f["amplitude"].fail("an amplitude within 10 m");
  const double frequency_hz = positive(f["frequency_hz"]);
  if (frequency_hz >= 500.0) f["frequency_hz"].fail("a frequency below 500 Hz (the 1 kHz loop's Nyquist frequency)");
  return {amplitude, frequency_hz};
}

Tool tool(const Field& f) {
  f.allow_only({"name", "source", "capsules", "F_T_EE", "mass", "com", "inertia"});
  require_source(f);
  Tool tool;
  tool.name = f["name"].text();
  const Field capsules = f["capsules"];
  if (capsules.sequence_size() == 0) capsules.fail("at least one capsule");
  for (std::size_t i = 0; i < capsules.sequence_size(); ++i) {
    const Field c = capsules[i];
    tool.capsules.push_back({c["name"].text(), capsule(c, {"name", "a", "b", "radius"})});
  }
  tool.F_T_EE = flange_to_tcp(f["F_T_EE"]);
  tool.inertia = flange_body(f);
  if (tool.inertia.mass == 0.0) f["mass"].fail("a positive mass");
  return tool;
}

Task task(const Field& f) {
  const std::string type = f["type"].text();
  if (type == "ultrasound_scan") {
    f.allow_only({"type", "source", "start", "end", "tool_axis", "speed", "hover"});
    require_source(f);
    UltrasoundScan scan{f["start"].vector<3>(), f["end"].vector<3>(), unit_vector(f["tool_axis"]),
                        positive(f["speed"]), positive(f["hover"])};
    if ((scan.end - scan.start).norm() == 0.0) f["end"].fail("an end different from the start");
    return scan;
  }
  if (type == "rcm_pivot") {
    f.allow_only({"type", "source", "trocar", "insertion", "max_pivot_deg", "hover"});
    require_source(f);
    RcmPivot rcm;
    rcm.trocar = f["trocar"].vector<3>();
    const Eigen::Vector2d insertion = f["insertion"].vector<2>();
    if (insertion[0] < 0.0 || insertion[1] <= insertion[0]) f["insertion"].fail("[min, max] with 0 <= min < max");
    rcm.insertion_min = insertion[0];
    rcm.insertion_max = insertion[1];
    const double pivot = positive(f["max_pivot_deg"]);
    if (pivot >= 90.0) f["max_pivot_deg"].fail("an angle below 90 degrees");
    rcm.max_pivot = pivot * std::numbers::pi / 180.0;
    rcm.hover = positive(f["hover"]);
    return rcm;
  }
  if (type == "burr_hole") {
    f.allow_only({"type", "source", "entry", "axis", "standoff", "advance", "speed"});
    require_source(f);
    return BurrHole{f["entry"].vector<3>(), unit_vector(f["axis"]), positive(f["standoff"]), positive(f["advance"]),
                    positive(f["speed"])};
  }
  f["type"].fail("ultrasound_scan, rcm_pivot or burr_hole");
}

}  // namespace

Vector3 ObstacleMotion::displacement(double t) const {
  return amplitude * std::sin(2.0 * std::numbers::pi * frequency_hz * t);
}

Vector3 ObstacleMotion::velocity(double t) const {
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  return amplitude * (w * std::cos(w * t));
}

int Scene::obstacle_index(const std::string& name) const {
  for (std::size_t i = 0; i < obstacles.size(); ++i)
    if (obstacles[i].name == name) return static_cast<int>(i);
  return -1;
}

const NamedPose& Scene::pose(const std::string& name) const {
  for (const auto& p : poses)
    if (p.name == name) return p;
  std::string list;
  for (const auto& p : poses) list += (list.empty() ? "" : ", ") + p.name;
  throw ConfigError(path + ": no pose named `" + name + "` (poses: " + list + ")");
}

Scene load_scene(const std::string& path) {
  const YAML::Node root = load_yaml_file(path, "scene file");
  const Field top(root, path, "");
  top.allow_only({"name", "description", "frame", "clearance", "materials", "obstacles", "tool", "poses", "start", "task"});

  Scene scene;
  scene.path = path;
  scene.name = top["name"].text();
  top["description"].text();   // free text, required so that every scene says what it is
  top["frame"].text();         // ... and in which frame its numbers are

  const Field clearance = top["clearance"];
  require_source(clearance);
  for (const auto& key : clearance.keys())
    if (key != "source") scene.clearance[key] = non_negative(clearance[key]);
  if (!scene.clearance.contains("self")) clearance.fail("a `self` clearance besides one per obstacle class");

  scene.tool = tool(top["tool"]);
  if (top.has("materials")) scene.materials = materials(top["materials"]);

  // Names an exemption may refer to: the arm's capsules and the tool's.
  std::set<std::string> capsule_names;
  for (const auto& c : franka_arm_capsules()) capsule_names.emplace(c.name);
  for (const auto& c : scene.tool.capsules) {
    if (!capsule_names.insert(c.name).second)
      top["tool"]["capsules"].fail("distinct capsule names (`" + c.name + "` is taken)");
  }

  const Field obstacles = top["obstacles"];
  std::set<std::string> obstacle_names;
  for (std::size_t i = 0; i < obstacles.sequence_size(); ++i) {
    const Field o = obstacles[i];
    o.allow_only({"name", "class", "source", "box", "capsule", "sphere", "half_space", "exempt", "material", "motion"});
    require_source(o);
    Obstacle obstacle{o["name"].text(), o["class"].text(), shape(o), {}};
    if (!obstacle_names.insert(obstacle.name).second) o["name"].fail("a name not used by another obstacle");
    if (obstacle.obstacle_class == "self" || !scene.clearance.contains(obstacle.obstacle_class))
      o["class"].fail("an obstacle class with a clearance in `clearance`");
    if (o.has("exempt")) {
      const Field exempt = o["exempt"];
      for (std::size_t k = 0; k < exempt.sequence_size(); ++k) {
        const std::string name = exempt[k].text();
        if (!capsule_names.contains(name)) exempt[k].fail("the name of an arm or tool capsule");
        obstacle.exempt.push_back(name);
      }
    }
    if (o.has("material")) {
      obstacle.material = o["material"].text();
      if (!scene.materials.contains(obstacle.material)) o["material"].fail("the name of a material in `materials`");
    }
    if (o.has("motion")) obstacle.motion = motion(o["motion"]);
    scene.obstacles.push_back(std::move(obstacle));
  }

  const Field poses = top["poses"];
  for (const auto& name : poses.keys()) {
    const Field p = poses[name];
    p.allow_only({"q", "source"});
    require_source(p);
    scene.poses.push_back({name, p["q"].vector<7>()});
  }
  scene.start = top["start"].text();
  if (std::none_of(scene.poses.begin(), scene.poses.end(), [&](const NamedPose& p) { return p.name == scene.start; }))
    top["start"].fail("the name of a pose in `poses`");

  scene.task = task(top["task"]);
  return scene;
}

std::vector<FrameCapsule> arm_and_tool_capsules(const Tool& tool) {
  std::vector<FrameCapsule> capsules;
  for (const auto& c : franka_arm_capsules()) capsules.push_back({std::string(c.name), c.frame, c.capsule});
  for (const auto& c : tool.capsules) capsules.push_back({c.name, CapsuleFrame::kFlange, c.capsule});
  return capsules;
}

CollisionWorld collision_world(const Scene& scene) {
  std::vector<CollisionObstacle> obstacles;
  for (const Obstacle& o : scene.obstacles) obstacles.push_back({o.name, o.shape, o.exempt});
  return CollisionWorld(arm_and_tool_capsules(scene.tool), std::move(obstacles));
}

int tool_tip_capsule(const Tool& tool) {
  const Vector3& tcp = tool.F_T_EE.translation;
  int tip = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < tool.capsules.size(); ++i) {
    const Capsule& c = tool.capsules[i].capsule;
    const double d = std::min((c.a - tcp).norm(), (c.b - tcp).norm()) - c.radius;
    if (d < best) best = d, tip = static_cast<int>(i);
  }
  return tip;
}

ModelParameters with_tool(ModelParameters parameters, const Tool& tool) {
  parameters.F_T_EE = tool.F_T_EE;
  parameters.end_effector = tool.inertia;
  return parameters;
}

}  // namespace csp
