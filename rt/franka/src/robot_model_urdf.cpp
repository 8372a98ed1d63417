#include "robot_model_urdf.hpp"

#include <cmath>
#include <limits>
#include <locale>
#include <sstream>

namespace csp {
namespace {

// URDF's rpy of a rotation: R = RotZ(yaw) RotY(pitch) RotX(roll).
Vector3 roll_pitch_yaw(const Matrix3& r) {
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  if (std::hypot(r(0, 0), r(1, 0)) < 1e-12) {   // pitch +-90 deg: only roll -+ yaw is defined; roll 0
    return {0.0, pitch, std::atan2(-r(0, 1), r(1, 1))};
  }
  return {std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0))};
}

class UrdfWriter {
 public:
  UrdfWriter() {
    out_.imbue(std::locale::classic());
    out_.precision(std::numeric_limits<double>::max_digits10);   // every double read back exactly
  }

  std::ostringstream& out() { return out_; }

  void vector(const Vector3& v) { out_ << v.x() << ' ' << v.y() << ' ' << v.z(); }

  void origin(const Vector3& xyz, const Matrix3& rotation) {
    out_ << "      <origin xyz=\"";
    vector(xyz);
    out_ << "\" rpy=\"";
    vector(roll_pitch_yaw(rotation));
    out_ << "\"/>\n";
  }

  void link(const std::string& name, const RigidBodyInertia* body) {
    if (body == nullptr) {
      out_ << "  <link name=\"" << name << "\"/>\n";
      return;
    }
    const Matrix3& i = body->inertia;   // about the centre of mass, in the link frame's axes
    out_ << "  <link name=\"" << name << "\">\n    <inertial>\n";
    origin(body->com, Matrix3::Identity());
    out_ << "      <mass value=\"" << body->mass << "\"/>\n"
         << "      <inertia ixx=\"" << i(0, 0) << "\" ixy=\"" << i(0, 1) << "\" ixz=\"" << i(0, 2) << "\" iyy=\""
         << i(1, 1) << "\" iyz=\"" << i(1, 2) << "\" izz=\"" << i(2, 2) << "\"/>\n"
         << "    </inertial>\n  </link>\n";
  }

 private:
  std::ostringstream out_;
};

}  // namespace

std::string robot_model_urdf(const ModelParameters& model, const std::string& name) {
  UrdfWriter urdf;
  auto& out = urdf.out();
  const auto link_name = [&name](int i) { return name + "_link" + std::to_string(i); };
  out << "<?xml version=\"1.0\"?>\n"
      << "<!-- The arm CSP emulates (its modified-DH kinematics, link inertials and joint limits). -->\n"
      << "<robot name=\"" << name << "\">\n";
  urdf.link(link_name(0), nullptr);
  const JointLimits& limits = model.joint_limits;
  for (int i = 0; i < kNumJoints; ++i) {
    // ^{i-1}T_i = RotX(alpha) TransX(a) RotZ(theta_offset + q) TransZ(d)
    //           = Trans(a, -sin(alpha) d, cos(alpha) d) RotX(alpha) RotZ(theta_offset) RotZ(q).
    const MdhParameters& row = model.joints[i];
    const Vector3 xyz(row.a, -std::sin(row.alpha) * row.d, std::cos(row.alpha) * row.d);
    const Matrix3 rotation = (Eigen::AngleAxisd(row.alpha, Vector3::UnitX()) *
                                   Eigen::AngleAxisd(row.theta_offset, Vector3::UnitZ()))
                                      .toRotationMatrix();
    out << "  <joint name=\"" << name << "_joint" << i + 1 << "\" type=\"revolute\">\n"
        << "      <parent link=\"" << link_name(i) << "\"/>\n"
        << "      <child link=\"" << link_name(i + 1) << "\"/>\n";
    urdf.origin(xyz, rotation);
    out << "      <axis xyz=\"0 0 1\"/>\n"
        << "      <limit lower=\"" << limits.q_min[i] << "\" upper=\"" << limits.q_max[i] << "\" effort=\""
        << limits.tau_max[i] << "\" velocity=\"" << limits.dq_max[i] << "\"/>\n"
        << "  </joint>\n";
    urdf.link(link_name(i + 1), &model.links[i]);
  }
  out << "  <joint name=\"" << name << "_joint8\" type=\"fixed\">\n"
      << "      <parent link=\"" << link_name(7) << "\"/>\n"
      << "      <child link=\"" << link_name(8) << "\"/>\n";
  urdf.origin(model.link7_T_flange.translation, model.link7_T_flange.rotation);
  out << "  </joint>\n";
  urdf.link(link_name(8), nullptr);
  out << "</robot>\n";
  return out.str();
}

}  // namespace csp
