#include "csp/fci/model_parameter_block.hpp"

#include "csp/dynamics/arrays.hpp"

namespace csp::fci {

std::array<double, kParameterCount> encode_parameters(const ModelParameters& robot_model) {
  std::array<double, kParameterCount> values{};
  std::size_t count = 0;
  auto put = [&](double value) { values[count++] = value; };
  for (const MdhParameters& row : robot_model.joints) {
    put(row.a);
    put(row.d);
    put(row.alpha);
    put(row.theta_offset);
  }
  for (const double value : to_array(robot_model.link7_T_flange)) put(value);
  for (const RigidBodyInertia& link : robot_model.links) {
    put(link.mass);
    for (const double value : to_array(link.com)) put(value);
    for (const double value : to_array(link.inertia)) put(value);
  }
  return values;
}

ModelParameters decode_parameters(const double* values) {
  ModelParameters robot_model;
  for (MdhParameters& row : robot_model.joints) {
    row = {values[0], values[1], values[2], values[3]};
    values += 4;
  }
  robot_model.link7_T_flange = transform_from_matrix(from_data<Eigen::Matrix4d>(values));
  values += 16;
  for (RigidBodyInertia& link : robot_model.links) {
    link.mass = values[0];
    link.com = from_data<Vector3>(values + 1);
    link.inertia = from_data<Matrix3>(values + 4);
    values += 13;
  }
  return robot_model;
}

}  // namespace csp::fci
