#include "csp/io/robot_config.hpp"

#include <cmath>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <optional>
#include <set>
#include <system_error>

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>

#include "csp/io/yaml_field.hpp"

namespace csp {
namespace {

// Bounds far outside any arm CSP models, so that a typo such as 1e200 is named where it is
// written instead of surfacing later as a non-finite torque.
constexpr double kMaxLength = 10.0;     // [m]: link lengths, offsets, CoM distances
constexpr double kMaxMass = 1000.0;     // [kg]
constexpr double kMaxInertia = 1000.0;  // [kg m^2], any tensor entry
constexpr double kMaxFrictionTorque = 100.0;    // [N m]: above any joint's torque limit
constexpr double kMaxStribeckVelocity = 10.0;   // [rad/s]: above any joint's speed limit

double length(const Field& field) {
  const double v = field.number();
  if (std::abs(v) > kMaxLength) field.fail("a length within +-" + std::to_string(static_cast<int>(kMaxLength)) + " m");
  return v;
}

double angle(const Field& field) {
  const double v = field.number();
  if (std::abs(v) > 2.0 * M_PI) field.fail("an angle within +-2 pi rad");
  return v;
}

Matrix3 inertia_tensor(const Field& field) {
  const Eigen::Matrix<double, 6, 1> v = field.vector<6>();   // xx, xy, xz, yy, yz, zz
  if (v.cwiseAbs().maxCoeff() > kMaxInertia) field.fail("inertia entries within +-1000 kg m^2");
  Matrix3 I;
  I << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
  return I;
}

Vector3 center_of_mass(const Field& field) {
  const Vector3 c = field.vector<3>();
  if (c.norm() > kMaxLength) field.fail("a centre of mass within 10 m of the frame");
  return c;
}

double mass(const Field& field) {
  const double m = field.number();
  if (m > kMaxMass) field.fail("a mass of at most 1000 kg");
  return m;
}

RigidBodyInertia rigid_body(const Field& field, bool require_physical) {
  field.allow_only({"mass", "com", "inertia"});
  RigidBodyInertia body{mass(field["mass"]), center_of_mass(field["com"]), inertia_tensor(field["inertia"])};
  if (body.mass <= 0.0) field["mass"].fail("a positive mass");
  if (require_physical && !is_physical_inertia(body.inertia))
    field["inertia"].fail("a positive-definite inertia satisfying the triangle inequality "
                          "(mark the set `physical: false` if it is knowingly not physical)");
  return body;
}

MdhParameters mdh_row(const Field& field, bool with_offset) {
  if (with_offset) field.allow_only({"a", "d", "alpha", "theta_offset"});
  else field.allow_only({"a", "d", "alpha"});
  return {length(field["a"]), length(field["d"]), angle(field["alpha"]), with_offset ? angle(field["theta_offset"]) : 0.0};
}

Vector7 positive7(const Field& field) {
  const Vector7 v = field.vector<7>();
  if ((v.array() <= 0.0).any()) field.fail("7 positive numbers");
  return v;
}

JointLimits joint_limit_set(const Field& f) {
  f.allow_only({"source", "q_min", "q_max", "dq_max", "ddq_max", "dddq_max", "tau_max", "dtau_max", "power_max",
                "position_based_velocity"});
  JointLimits limits;
  limits.q_min = f["q_min"].vector<7>();
  limits.q_max = f["q_max"].vector<7>();
  for (int i = 0; i < kNumJoints; ++i)
    if (limits.q_min[i] >= limits.q_max[i])
      f["q_max"].fail("q_min < q_max for every joint (joint " + std::to_string(i + 1) + " is not)");
  limits.dq_max = positive7(f["dq_max"]);
  limits.ddq_max = positive7(f["ddq_max"]);
  limits.dddq_max = positive7(f["dddq_max"]);
  limits.tau_max = positive7(f["tau_max"]);
  limits.dtau_max = positive7(f["dtau_max"]);
  if (f.has("power_max")) limits.power_max = positive(f["power_max"]);   // else JointLimits' (ISO 10218-1)
  if (f.has("position_based_velocity")) {
    const Field p = f["position_based_velocity"];
    p.allow_only({"dq_offset", "ddq_dec"});
    limits.position_based_velocity = true;
    limits.dq_offset = p["dq_offset"].vector<7>();
    if ((limits.dq_offset.array() < 0.0).any()) p["dq_offset"].fail("7 non-negative numbers");
    limits.ddq_dec = positive7(p["ddq_dec"]);
  }
  return limits;
}

CartesianLimits::Axis cartesian_axis(const Field& f) {
  f.allow_only({"v_max", "a_max", "j_max"});
  CartesianLimits::Axis axis{f["v_max"].number(), f["a_max"].number(), f["j_max"].number()};
  if (axis.v_max <= 0 || axis.a_max <= 0 || axis.j_max <= 0) f.fail("positive v_max, a_max, j_max");
  return axis;
}

// Static friction on top of a sliding law: {source, breakaway: [7] N m, stribeck_velocity: [7] rad/s}.
void static_friction(const Field& f, FrictionModel& friction) {
  f.allow_only({"source", "breakaway", "stribeck_velocity"});
  friction.breakaway = f["breakaway"].vector<7>();
  if ((friction.breakaway.array() < 0.0).any() || (friction.breakaway.array() > kMaxFrictionTorque).any())
    f["breakaway"].fail("7 numbers from 0 to 100 N m");
  friction.stribeck_velocity = positive7(f["stribeck_velocity"]);
  if ((friction.stribeck_velocity.array() > kMaxStribeckVelocity).any())
    f["stribeck_velocity"].fail("7 positive numbers of at most 10 rad/s");
}

FrictionModel friction_set(const Field& f) {
  FrictionModel friction;
  const std::string type = f["type"].text();
  if (f.has("static_friction")) static_friction(f["static_friction"], friction);
  if (type == "gaz_sigmoid") {
    f.allow_only({"source", "type", "phi1", "phi2", "phi3", "static_friction"});
    friction.type = FrictionModel::Type::kGazSigmoid;
    friction.phi1 = f["phi1"].vector<7>();
    friction.phi2 = positive7(f["phi2"]);
    friction.phi3 = f["phi3"].vector<7>();
  } else if (type == "linear") {
    f.allow_only({"source", "type", "viscous", "coulomb", "offset", "static_friction"});
    friction.type = FrictionModel::Type::kLinear;
    friction.viscous = f["viscous"].vector<7>();
    friction.coulomb = f["coulomb"].vector<7>();
    friction.offset = f["offset"].vector<7>();
  } else {
    f["type"].fail("gaz_sigmoid or linear");
  }
  return friction;
}

// A block of named sets: {default: NAME, sets: {NAME: ...}}; `implicit` names need no entry.
template <typename Parse>
auto named_sets(const Field& f, std::string& default_name, const std::string& implicit, Parse parse) {
  f.allow_only({"default", "sets"});
  std::map<std::string, decltype(parse(f))> sets;
  const Field entries = f["sets"];
  for (const auto& name : entries.keys()) {
    if (name == implicit) entries[name].fail("another name (`" + implicit + "` is built in)");
    sets.emplace(name, parse(entries[name]));
  }
  default_name = f["default"].text();
  if (default_name != implicit && !sets.contains(default_name)) f["default"].fail("the name of one of the sets");
  return sets;
}


[[noreturn]] void unknown_name(const RobotConfig& config, const std::string& what, const std::string& name,
                               const std::vector<std::string>& known) {
  std::string list;
  for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
  throw ConfigError(config.path + ": unknown " + what + " `" + name + "` (available: " + list + ")");
}

template <typename Map>
std::vector<std::string> names_of(const Map& map, const char* implicit = nullptr) {
  std::vector<std::string> out;
  if (implicit) out.emplace_back(implicit);
  for (const auto& [name, value] : map) out.push_back(name);
  return out;
}

}  // namespace

Transform flange_to_tcp(const Field& pose) {
  pose.allow_only({"rotation_z", "translation"});
  return {Eigen::AngleAxisd(pose["rotation_z"].number(), Vector3::UnitZ()).toRotationMatrix(),
          pose["translation"].vector<3>()};
}

RigidBodyInertia flange_load(const Field& field) {
  field.allow_only({"mass", "com", "inertia"});
  RigidBodyInertia body;
  body.mass = mass(field["mass"]);
  if (body.mass < 0.0) field["mass"].fail("a non-negative mass");
  if (field.has("com")) body.com = center_of_mass(field["com"]);
  if (field.has("inertia")) {
    body.inertia = inertia_tensor(field["inertia"]);
    if (body.mass > 0.0 && body.inertia != Matrix3::Zero() && !is_physical_inertia(body.inertia))
      field["inertia"].fail("a physical inertia (positive definite, triangle inequality)");
  }
  return body;
}

RigidBodyInertia flange_body(const Field& field) {
  RigidBodyInertia body{mass(field["mass"]), center_of_mass(field["com"]), inertia_tensor(field["inertia"])};
  if (body.mass < 0.0) field["mass"].fail("a non-negative mass");
  if (body.mass > 0.0 && !is_physical_inertia(body.inertia))
    field["inertia"].fail("a physical inertia (positive definite, triangle inequality)");
  return body;
}

Armature read_armature(const Field& field) {
  field.allow_only({"values", "source"});
  const Vector7 values = non_negative7(field["values"]);
  if (values.maxCoeff() > kMaxInertia) field["values"].fail("7 rotor inertias of at most 1000 kg m^2");
  return {values, field["source"].text()};
}

namespace {

// Bounds on what a YAML file of CSP's may hold, checked before yaml-cpp builds a single node (each
// node costs it about 500 bytes: a 10 MB list under an unknown key took 1.4 GB before the key was
// refused). The largest shipped files (a robot file, a plan) are 15 kB, about 1500 nodes, fewer
// than 10 levels deep; trajectories and logs are CSV files.
// An alias counts as the whole node it names, as every reader of the document sees it: 8 levels of
// ten aliases each (450 bytes) would be 10^8 nodes.
constexpr std::size_t kMaxYamlBytes = 1 << 20;      // 70x the largest shipped file
constexpr std::size_t kMaxYamlNodes = 100'000;      // 60x; a few tens of MB while building
constexpr std::size_t kMaxYamlDepth = 50;           // far below yaml-cpp's own guard, which says only "bad file"

std::string line_of(const YAML::Mark& mark) { return "line " + std::to_string(mark.line + 1); }

// One pass over the parser's events, before any node is built: the document's size once aliases
// are expanded, its depth, and keys given twice. yaml-cpp keeps every pair of a mapping but looks
// keys up by their first occurrence, so a key written twice would silently ignore its second value
// (appending `duration: 0.5` to a scenario would not change it). An anchored node is checked once,
// where it is written; an alias adds its size without a second walk.
class YamlShape final : public YAML::EventHandler {
 public:
  explicit YamlShape(std::string name) : name_(std::move(name)) {}

  void OnDocumentStart(const YAML::Mark&) override { anchors_.clear(); }   // yaml-cpp numbers anchors per document
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { leaf(mark, anchor, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string& value) override {
    leaf(mark, anchor, &value);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto named = anchors_.find(anchor);
    if (named == anchors_.end())   // the alias is inside the node it names
      fail(mark, "no alias inside the node its anchor names (a cycle)");
    const std::string* scalar = named->second.scalar ? &*named->second.scalar : nullptr;
    child(mark, scalar);
    add(mark, named->second.nodes);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(mark, anchor, false);
  }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(mark, anchor, true);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapEnd() override { close(); }

 private:
  struct Collection {
    bool map = false;
    std::string path;               // key path, as Field names it
    std::size_t children = 0;       // keys and values of a map, items of a list
    std::string key;                // a map's current key
    std::set<std::string> keys;     // a map's keys so far
    YAML::anchor_t anchor = 0;
    std::size_t first_node = 0;     // nodes_ when it opened
  };
  struct Anchored {
    std::size_t nodes = 0;
    std::optional<std::string> scalar;   // an anchored scalar may be used as a key
  };

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& expected) const {
    throw ConfigError(name_ + ": " + line_of(mark) + ": expected " + expected);
  }

  // A new node in the open collection: a map's key is checked against the keys before it.
  void child(const YAML::Mark& mark, const std::string* scalar) {
    if (open_.empty()) return;
    Collection& c = open_.back();
    if (c.map && c.children % 2 == 0) {
      c.key = scalar ? printable_key(*scalar) : "?";
      if (scalar && !c.keys.insert(c.key).second)
        throw ConfigError(name_ + ": " + path_of(c) + ": key given twice (" + line_of(mark) + "); expected each key once");
    }
    ++c.children;
  }

  // The key path of the node the open collection is receiving.
  std::string path_of(const Collection& c) const {
    if (c.map) return c.path.empty() ? c.key : c.path + "." + c.key;
    return c.path + "[" + std::to_string(c.children - 1) + "]";
  }

  void add(const YAML::Mark& mark, std::size_t nodes) {
    nodes_ += nodes;
    if (nodes_ > kMaxYamlNodes)
      fail(mark, "at most " + std::to_string(kMaxYamlNodes) + " nodes once aliases are expanded (CSP's files have a few "
                 "thousand; trajectories belong in CSV files)");
  }

  void leaf(const YAML::Mark& mark, YAML::anchor_t anchor, const std::string* scalar) {
    child(mark, scalar);
    add(mark, 1);
    if (anchor) anchors_[anchor] = {1, scalar ? std::optional<std::string>(*scalar) : std::nullopt};
  }

  void open(const YAML::Mark& mark, YAML::anchor_t anchor, bool map) {
    child(mark, nullptr);
    if (open_.size() == kMaxYamlDepth)
      fail(mark, "at most " + std::to_string(kMaxYamlDepth) + " levels of nesting (CSP's files have fewer than 10)");
    const std::string path = open_.empty() ? "" : path_of(open_.back());
    add(mark, 1);
    open_.push_back({map, path, 0, {}, {}, anchor, nodes_ - 1});
  }

  void close() {
    const Collection& c = open_.back();
    if (c.anchor) anchors_[c.anchor] = {nodes_ - c.first_node, std::nullopt};
    open_.pop_back();
  }

  std::string name_;
  std::vector<Collection> open_;
  std::map<YAML::anchor_t, Anchored> anchors_;   // the anchors whose node is complete
  std::size_t nodes_ = 0;                        // so far, aliases expanded
};

}  // namespace

void check_yaml_layout(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  std::string line;
  bool started = false;   // the first key has been seen
  for (int number = 1; std::getline(in, line); ++number) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const bool marker = line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0;
    if (started) {
      if (marker) throw ConfigError(path + ": expected one YAML document, found a second at line " + std::to_string(number));
      continue;
    }
    if (line[0] == '%') continue;   // a directive
    if (line.rfind("---", 0) == 0 && line.find_first_not_of(" \t\r", 3) == std::string::npos) continue;
    // yaml-cpp 0.7 loops forever on a document that does not start with a mapping key but meets a
    // ',' (for instance `"s"` then `, x`, or `--- , x`): CSP's files are mappings, so say so first.
    std::size_t end = 0;
    while (end < line.size() && (std::isalnum(static_cast<unsigned char>(line[end])) || line[end] == '_')) ++end;
    const std::size_t colon = line.find_first_not_of(" \t", end);
    if (end == 0 || !std::isalpha(static_cast<unsigned char>(line[0])) || colon == std::string::npos || line[colon] != ':' ||
        (colon + 1 < line.size() && line[colon + 1] != ' ' && line[colon + 1] != '\t' && line[colon + 1] != '\r'))
      throw ConfigError(path + ": expected a mapping of keys at the top level (`name: ...`), line " + std::to_string(number));
    started = true;
  }
}

YAML::Node parse_yaml_text(const std::string& text, const std::string& name) {
  if (text.size() > kMaxYamlBytes)
    throw ConfigError(name + ": expected at most " + std::to_string(kMaxYamlBytes >> 20) + " MB of YAML (CSP's files have "
                      "tens of kB), found " + std::to_string(text.size()) + " bytes");
  check_yaml_layout(text, name);
  std::vector<YAML::Node> documents;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    YamlShape shape(name);
    while (parser.HandleNextDocument(shape)) {
    }
    documents = YAML::LoadAll(text);
  } catch (const YAML::DeepRecursion& e) {   // yaml-cpp says only "bad file"; YamlShape should stop it first
    throw ConfigError(name + ": " + line_of(e.mark) + ": expected at most " + std::to_string(kMaxYamlDepth) +
                      " levels of nesting");
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ": not valid YAML: " + printable_key(e.msg) + " (" + line_of(e.mark) + ")");
  }
  if (documents.size() > 1)
    throw ConfigError(name + ": expected one YAML document, found " + std::to_string(documents.size()) +
                      " (the second starts at " + line_of(documents[1].Mark()) + ")");
  return documents.empty() ? YAML::Node() : documents.front();
}

YAML::Node load_yaml_file(const std::string& path, const std::string& what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw ConfigError(path + ": cannot open the " + what + " (missing, or not a regular file)");
  // Refused before it is read: a file of gigabytes would not fit in memory.
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (!error && size > kMaxYamlBytes)
    throw ConfigError(path + ": expected at most " + std::to_string(kMaxYamlBytes >> 20) + " MB for a " + what +
                      " (CSP's files have tens of kB), found " + std::to_string(size) + " bytes");
  std::ostringstream text;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in || (!(text << in.rdbuf()) && in.peek() != std::ifstream::traits_type::eof()))
      throw ConfigError(path + ": cannot read the " + what);
  }
  return parse_yaml_text(text.str(), path);
}

RobotConfig load_robot_config(const std::string& path) {
  const YAML::Node root = load_yaml_file(path, "robot file");
  const Field top(root, path, "");
  top.allow_only({"name", "kinematics", "end_effectors", "limits", "inertia", "friction", "armature"});

  RobotConfig config;
  config.path = path;
  config.name = top["name"].text();

  const Field kinematics = top["kinematics"];
  kinematics.allow_only({"source", "mdh", "flange"});
  const Field mdh = kinematics["mdh"];
  if (mdh.sequence_size() != kNumJoints) mdh.fail("7 rows, one per joint");
  for (std::size_t i = 0; i < kNumJoints; ++i) config.mdh[i] = mdh_row(mdh[i], true);
  config.link7_T_flange = mdh_transform(mdh_row(kinematics["flange"], false), 0.0);

  const Field end_effectors = top["end_effectors"];
  for (const auto& name : end_effectors.keys()) {
    const Field ee = end_effectors[name];
    if (name == "none") ee.fail("another name (`none` is built in)");
    ee.allow_only({"source", "F_T_EE", "mass", "com", "inertia"});
    config.end_effectors.emplace(name, EndEffectorDescription{flange_to_tcp(ee["F_T_EE"]), flange_body(ee)});
  }

  const Field limits = top["limits"];
  limits.allow_only({"joint", "cartesian"});
  config.joint_limits = named_sets(limits["joint"], config.default_joint_limits, "", joint_limit_set);
  const Field cartesian = limits["cartesian"];
  cartesian.allow_only({"source", "translation", "rotation", "elbow"});
  config.cartesian_limits = {cartesian_axis(cartesian["translation"]), cartesian_axis(cartesian["rotation"]),
                             cartesian_axis(cartesian["elbow"])};

  config.inertia_sets = named_sets(top["inertia"], config.default_inertia, "", [](const Field& f) {
    f.allow_only({"source", "physical", "links"});
    InertiaSet set;
    set.physical = f["physical"].boolean();
    const Field links = f["links"];
    if (links.sequence_size() != kNumJoints) links.fail("7 links");
    for (std::size_t i = 0; i < kNumJoints; ++i) set.links[i] = rigid_body(links[i], set.physical);
    return set;
  });

  config.friction_sets = named_sets(top["friction"], config.default_friction, "none", friction_set);
  if (top.has("armature")) config.armature = read_armature(top["armature"]);
  return config;
}

ModelParameters model_parameters(const RobotConfig& config, const ModelOptions& options) {
  ModelParameters p;
  p.joints = config.mdh;
  p.link7_T_flange = config.link7_T_flange;

  const std::string inertia = options.inertia.empty() ? config.default_inertia : options.inertia;
  const auto set = config.inertia_sets.find(inertia);
  if (set == config.inertia_sets.end()) unknown_name(config, "inertial set", inertia, names_of(config.inertia_sets));
  p.links = set->second.links;
  p.physically_consistent = set->second.physical;

  const std::string friction = options.friction.empty() ? config.default_friction : options.friction;
  if (friction != "none") {
    const auto model = config.friction_sets.find(friction);
    if (model == config.friction_sets.end())
      unknown_name(config, "friction set", friction, names_of(config.friction_sets, "none"));
    p.friction = model->second;
  }

  const std::string limits = options.joint_limits.empty() ? config.default_joint_limits : options.joint_limits;
  const auto joint_limits = config.joint_limits.find(limits);
  if (joint_limits == config.joint_limits.end())
    unknown_name(config, "joint limit set", limits, names_of(config.joint_limits));
  p.joint_limits = joint_limits->second;
  p.cartesian_limits = config.cartesian_limits;

  if (options.end_effector != "none") {
    const auto ee = config.end_effectors.find(options.end_effector);
    if (ee == config.end_effectors.end())
      unknown_name(config, "end effector", options.end_effector, names_of(config.end_effectors, "none"));
    p.F_T_EE = ee->second.F_T_EE;
    p.end_effector = ee->second.inertia;
  }
  if (options.load) p.load = *options.load;
  if (options.gravity) p.gravity = *options.gravity;
  return p;
}

}  // namespace csp
