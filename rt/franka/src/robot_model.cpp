// franka::RobotModel: a URDF read with tinyxml2 into CSP's model (modified-DH rows, link inertials,
// joint limits), computed with franka::Model.
#include "franka/robot_model.h"

#include <cmath>
#include <locale>
#include <map>
#include <sstream>
#include <stdexcept>

#include <tinyxml2.h>

#include "franka/model.h"
#include "model_impl.hpp"

namespace franka {
namespace {

// Round-off allowed when recognising the modified-DH form in a URDF's decimal numbers.
constexpr double kFormTolerance = 1e-9;

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("franka::RobotModel: " + what); }

csp::Vector3 read_vector(const tinyxml2::XMLElement* element, const char* attribute, const csp::Vector3& absent) {
  const char* text = element == nullptr ? nullptr : element->Attribute(attribute);
  if (text == nullptr) return absent;
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  csp::Vector3 v;
  if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite()) {
    fail(std::string("<") + element->Name() + " " + attribute + "=\"" + text + "\">: expected three finite numbers");
  }
  return v;
}

double read_number(const tinyxml2::XMLElement* element, const char* attribute) {
  double value = 0.0;
  if (element == nullptr || element->QueryDoubleAttribute(attribute, &value) != tinyxml2::XML_SUCCESS ||
      !std::isfinite(value)) {
    fail(std::string("expected a finite number in ") + attribute + " of <" +
         (element == nullptr ? std::string("(missing element)") : element->Name()) + ">");
  }
  return value;
}

// A URDF <origin>: Trans(xyz) RotZ(yaw) RotY(pitch) RotX(roll).
csp::Transform read_origin(const tinyxml2::XMLElement* parent) {
  const tinyxml2::XMLElement* origin = parent->FirstChildElement("origin");
  const csp::Vector3 rpy = read_vector(origin, "rpy", csp::Vector3::Zero());
  csp::Transform t;
  t.translation = read_vector(origin, "xyz", csp::Vector3::Zero());
  t.rotation = (Eigen::AngleAxisd(rpy.z(), csp::Vector3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), csp::Vector3::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), csp::Vector3::UnitX()))
                   .toRotationMatrix();
  return t;
}

// The MDH row whose ^{i-1}T_i at q = 0 is `origin`: rotation RotX(alpha) RotZ(theta_offset),
// translation (a, -sin(alpha) d, cos(alpha) d).
csp::MdhParameters mdh_row(const csp::Transform& origin, const std::string& joint) {
  const csp::Matrix3& r = origin.rotation;
  csp::MdhParameters row;
  row.alpha = std::atan2(-r(1, 2), r(2, 2));
  row.theta_offset = std::atan2(-r(0, 1), r(0, 0));
  const csp::Matrix3 form = (Eigen::AngleAxisd(row.alpha, csp::Vector3::UnitX()) *
                             Eigen::AngleAxisd(row.theta_offset, csp::Vector3::UnitZ()))
                                .toRotationMatrix();
  if ((form - r).cwiseAbs().maxCoeff() > kFormTolerance) {
    fail("joint " + joint + ": its origin's rotation is not RotX(alpha) RotZ(theta) (modified DH)");
  }
  const csp::Vector3 z_axis(0.0, -std::sin(row.alpha), std::cos(row.alpha));
  row.a = origin.translation.x();
  row.d = z_axis.dot(origin.translation);
  if ((origin.translation - csp::Vector3(row.a, 0.0, 0.0) - row.d * z_axis).cwiseAbs().maxCoeff() > kFormTolerance) {
    fail("joint " + joint + ": its origin's offset is not (a, -sin(alpha) d, cos(alpha) d) (modified DH)");
  }
  return row;
}

csp::RigidBodyInertia read_inertial(const tinyxml2::XMLElement* link) {
  csp::RigidBodyInertia body;
  const tinyxml2::XMLElement* inertial = link->FirstChildElement("inertial");
  if (inertial == nullptr) return body;   // a massless link
  const csp::Transform frame = read_origin(inertial);
  body.mass = read_number(inertial->FirstChildElement("mass"), "value");
  const tinyxml2::XMLElement* i = inertial->FirstChildElement("inertia");
  const double ixx = read_number(i, "ixx"), ixy = read_number(i, "ixy"), ixz = read_number(i, "ixz");
  const double iyy = read_number(i, "iyy"), iyz = read_number(i, "iyz"), izz = read_number(i, "izz");
  csp::Matrix3 about_com;
  about_com << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
  body.com = frame.translation;
  body.inertia = frame.rotation * about_com * frame.rotation.transpose();   // in the link frame's axes
  return body;
}

struct UrdfJoint {
  const tinyxml2::XMLElement* element = nullptr;
  std::string name, type, parent, child;
};

// CSP's model of the URDF's arm: from the root link, the chain's first 7 revolute joints and the
// fixed joint after the 7th (the flange; none: the flange is link 7's frame).
csp::ModelParameters read_arm(const std::string& urdf) {
  tinyxml2::XMLDocument document;
  if (document.Parse(urdf.c_str(), urdf.size()) != tinyxml2::XML_SUCCESS) {
    fail(std::string("the URDF is not well-formed XML: ") + document.ErrorStr());
  }
  const tinyxml2::XMLElement* robot = document.FirstChildElement("robot");
  if (robot == nullptr) fail("the URDF has no <robot> element");
  std::map<std::string, const tinyxml2::XMLElement*> links;
  for (auto* link = robot->FirstChildElement("link"); link != nullptr; link = link->NextSiblingElement("link")) {
    links[link->Attribute("name") == nullptr ? "" : link->Attribute("name")] = link;
  }
  std::map<std::string, UrdfJoint> joint_from;   // by parent link; a branch keeps the first joint
  std::map<std::string, bool> is_child;
  for (auto* e = robot->FirstChildElement("joint"); e != nullptr; e = e->NextSiblingElement("joint")) {
    UrdfJoint joint;
    joint.element = e;
    joint.name = e->Attribute("name") == nullptr ? "" : e->Attribute("name");
    joint.type = e->Attribute("type") == nullptr ? "" : e->Attribute("type");
    const auto* parent = e->FirstChildElement("parent");
    const auto* child = e->FirstChildElement("child");
    if (parent == nullptr || child == nullptr || parent->Attribute("link") == nullptr ||
        child->Attribute("link") == nullptr) {
      fail("joint " + joint.name + " lacks its <parent link> or <child link>");
    }
    joint.parent = parent->Attribute("link");
    joint.child = child->Attribute("link");
    is_child[joint.child] = true;
    joint_from.emplace(joint.parent, joint);
  }
  std::string root;
  for (const auto& [name, element] : links) {
    if (!is_child[name] && joint_from.count(name) != 0) root = name;
  }
  if (root.empty()) fail("the URDF has no root link with a joint");

  csp::ModelParameters p;
  p.F_T_EE = csp::Transform();
  p.EE_T_K = csp::Transform();
  int revolute = 0;
  std::string link = root;
  // At most one step per joint: a URDF whose joints loop ends too.
  std::size_t steps = 0;
  for (auto next = joint_from.find(link); next != joint_from.end() && steps < joint_from.size();
       next = joint_from.find(link), ++steps) {
    const UrdfJoint& joint = next->second;
    if (joint.type == "revolute" || joint.type == "continuous") {
      if (revolute == csp::kNumJoints) break;
      const csp::Vector3 axis = read_vector(joint.element->FirstChildElement("axis"), "xyz", csp::Vector3::UnitX());
      if ((axis - csp::Vector3::UnitZ()).cwiseAbs().maxCoeff() > kFormTolerance) {
        fail("joint " + joint.name + ": its axis is not z (0 0 1)");
      }
      p.joints[revolute] = mdh_row(read_origin(joint.element), joint.name);
      if (const auto* limit = joint.element->FirstChildElement("limit"); limit != nullptr) {
        p.joint_limits.q_min[revolute] = limit->DoubleAttribute("lower");
        p.joint_limits.q_max[revolute] = limit->DoubleAttribute("upper");
        p.joint_limits.dq_max[revolute] = limit->DoubleAttribute("velocity");
        p.joint_limits.tau_max[revolute] = limit->DoubleAttribute("effort");
      }
      const auto child = links.find(joint.child);
      if (child == links.end()) fail("joint " + joint.name + ": its child link " + joint.child + " is not in the URDF");
      p.links[revolute] = read_inertial(child->second);
      ++revolute;
    } else if (joint.type == "fixed") {
      if (revolute == csp::kNumJoints) {
        p.link7_T_flange = read_origin(joint.element);
        break;
      }
      if (revolute > 0) fail("joint " + joint.name + ": a fixed joint inside the arm is not supported");
    } else {
      fail("joint " + joint.name + ": type \"" + joint.type + "\" (expected revolute or fixed)");
    }
    link = joint.child;
  }
  if (revolute != csp::kNumJoints) {
    fail("the URDF's chain from " + root + " has " + std::to_string(revolute) +
         " revolute joints (expected 7)");
  }
  return p;
}

}  // namespace

class RobotModel::Impl {
 public:
  explicit Impl(const std::string& urdf) : model(std::make_unique<Model::Impl>(csp::Model(read_arm(urdf)))) {}
  Model model;
};

RobotModel::RobotModel(const std::string& urdf) : impl_(std::make_unique<Impl>(urdf)) {}
RobotModel::~RobotModel() = default;

void RobotModel::coriolis(const std::array<double, 7>& q, const std::array<double, 7>& dq,
                          const std::array<double, 9>& i_total, double m_total,
                          const std::array<double, 3>& f_x_ctotal, std::array<double, 7>& c_ne) {
  c_ne = impl_->model.coriolis(q, dq, i_total, m_total, f_x_ctotal);
}

void RobotModel::gravity(const std::array<double, 7>& q, const std::array<double, 3>& g_earth, double m_total,
                         const std::array<double, 3>& f_x_ctotal, std::array<double, 7>& g_ne) {
  g_ne = impl_->model.gravity(q, m_total, f_x_ctotal, g_earth);
}

void RobotModel::mass(const std::array<double, 7>& q, const std::array<double, 9>& i_total, double m_total,
                      const std::array<double, 3>& f_x_ctotal, std::array<double, 49>& m_ne) {
  m_ne = impl_->model.mass(q, i_total, m_total, f_x_ctotal);
}

}  // namespace franka
