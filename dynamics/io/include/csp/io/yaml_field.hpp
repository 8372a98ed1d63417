// Reading validated YAML files: a node that knows the file and key path it came from, so that
// every error names exactly where it is (robot files, scenario files).
#pragma once

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "csp/io/robot_config.hpp"

namespace csp {

// Parse a YAML file; a missing, unreadable or malformed file throws ConfigError naming it, and so
// does one too big for a file of CSP's: more than 1 MB, more than 100000 nodes once aliases are
// expanded (an alias bomb), more than 50 levels deep. Keys given twice are refused too.
YAML::Node load_yaml_file(const std::string& path, const std::string& what);

// The same for YAML text (a scenario recorded in a log); `name` starts every message.
YAML::Node parse_yaml_text(const std::string& text, const std::string& name);

// The layout CSP's YAML files must have before yaml-cpp parses them: one document whose first
// content line is a top-level mapping key. Throws ConfigError naming `path` and the line.
void check_yaml_layout(const std::string& text, const std::string& path);

// A key as it may appear in a one-line message: control characters (a newline in a quoted key)
// shown as `?`.
inline std::string printable_key(std::string key) {
  for (char& c : key)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return key;
}

// A YAML node together with the file and key path it came from, so that every error can say
// exactly where it is.
class Field {
 public:
  Field(const YAML::Node& node, std::string file, std::string path)
      : node_(node), file_(std::move(file)), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& expected) const {
    throw ConfigError(file_ + ": " + (path_.empty() ? "top level" : path_) + ": expected " + expected);
  }

  bool has(const std::string& key) const { return node_.IsMap() && node_[key]; }

  Field operator[](const std::string& key) const {
    if (!node_.IsMap()) fail("a mapping");
    const YAML::Node child = node_[key];
    const std::string child_path = path_.empty() ? printable_key(key) : path_ + "." + printable_key(key);
    if (!child) Field(node_, file_, child_path).fail("this key (missing)");
    return Field(child, file_, child_path);
  }

  Field operator[](std::size_t index) const {
    return Field(node_[index], file_, path_ + "[" + std::to_string(index) + "]");
  }

  // Reject keys other than the allowed ones (a typo must not become a silent default).
  void allow_only(std::initializer_list<const char*> keys) const {
    const std::set<std::string> allowed(keys.begin(), keys.end());
    for (const std::string& key : this->keys()) {
      if (!allowed.contains(key)) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        Field(node_, file_, path_.empty() ? printable_key(key) : path_ + "." + printable_key(key)).fail("no such key (allowed: " + list + ")");
      }
    }
  }

  // The keys of a mapping; each must be a plain word (a key that is itself a list or mapping is refused).
  std::vector<std::string> keys() const {
    if (!node_.IsMap()) fail("a mapping");
    std::vector<std::string> out;
    for (const auto& item : node_) {
      if (!item.first.IsScalar()) fail("keys that are plain words (line " + std::to_string(item.first.Mark().line + 1) + ")");
      out.push_back(item.first.Scalar());
    }
    return out;
  }

  std::size_t sequence_size() const {
    if (!node_.IsSequence()) fail("a list");
    return node_.size();
  }

  double number() const {
    double value = 0.0;
    if (!node_.IsScalar() || !YAML::convert<double>::decode(node_, value)) fail("a number");
    if (!std::isfinite(value)) fail("a finite number");
    return value;
  }

  // A whole number in [min, max]; checked as a double first, so that 1e18 or 1.5 never reaches an
  // integer conversion.
  int64_t whole_number(int64_t min, int64_t max) const {
    const double value = number();
    if (value != std::floor(value) || value < static_cast<double>(min) || value > static_cast<double>(max))
      fail("a whole number from " + std::to_string(min) + " to " + std::to_string(max));
    return static_cast<int64_t>(value);
  }

  bool boolean() const {
    bool value = false;
    if (!node_.IsScalar() || !YAML::convert<bool>::decode(node_, value)) fail("true or false");
    return value;
  }

  std::string text() const {
    if (!node_.IsScalar()) fail("a string");
    return node_.as<std::string>();
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vector() const {
    if (!node_.IsSequence() || node_.size() != N) fail("a list of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v[i] = (*this)[static_cast<std::size_t>(i)].number();
    return v;
  }

  const std::string& file() const { return file_; }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

inline double positive(const Field& field) {
  const double value = field.number();
  if (value <= 0.0) field.fail("a positive number");
  return value;
}

inline double non_negative(const Field& field) {
  const double value = field.number();
  if (value < 0.0) field.fail("a non-negative number");
  return value;
}

inline Vector7 non_negative7(const Field& field) {
  const Vector7 v = field.vector<7>();
  if ((v.array() < 0.0).any()) field.fail("7 non-negative numbers");
  return v;
}

// A load on the flange as libfranka's setLoad takes it: mass [kg] >= 0, optional CoM [m] in the
// flange frame and inertia about the CoM (xx, xy, xz, yy, yz, zz) [kg m^2], physical when given.
RigidBodyInertia flange_load(const Field& field);

// A body the flange carries (a robot file's end effector, a scene's tool) from `field`'s keys
// `mass` [kg] >= 0, `com` [m] in the flange frame and `inertia` about the CoM (6 numbers) [kg m^2],
// within a robot file's bounds (1000 kg, 10 m, 1000 kg m^2) and physical when it has a mass. The
// caller allows its other keys.
RigidBodyInertia flange_body(const Field& field);

// A flange -> TCP pose (libfranka's F_T_EE) as the files write it: a rotation about the flange's z
// [rad] (`rotation_z`) and a translation [m] (`translation`).
Transform flange_to_tcp(const Field& pose);

// The motors' rotor inertia, `{values: [7] kg m^2 >= 0, source: "..."}` (robot file, scenario plant).
Armature read_armature(const Field& field);

}  // namespace csp
