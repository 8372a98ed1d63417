// csp model: model quantities at one state, as one JSON object (a contract other tools rely on).
#include <cmath>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli_options.hpp"
#include "commands.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp::cli {
namespace {

template <typename Matrix>
nlohmann::json column_major(const Matrix& m) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r) out.push_back(m(r, c));
  return out;
}

}  // namespace

Command add_model_command(CLI::App& app) {
  struct Arguments {
    ModelArguments model;
    std::string q, dq, ddq;
  };
  auto args = std::make_shared<Arguments>();
  CLI::App* command = app.add_subcommand(
      "model", "Print poses, Jacobian, mass matrix, Coriolis, gravity, inverse dynamics and friction at one state (JSON)");
  args->model.add_to(*command);
  command->add_option("--q", args->q, "Joint positions q1,...,q7 [rad]")->required();
  command->add_option("--dq", args->dq, "Joint velocities [rad/s] (default 0)");
  command->add_option("--ddq", args->ddq, "Joint accelerations [rad/s^2] (default 0)");

  return [args] {
    const Model model = args->model.build();
    const Vector7 q = parse_joint_vector(args->q, "--q");
    const Vector7 dq = args->dq.empty() ? Vector7::Zero() : parse_joint_vector(args->dq, "--dq");
    const Vector7 ddq = args->ddq.empty() ? Vector7::Zero() : parse_joint_vector(args->ddq, "--ddq");

    Data data;
    forward_kinematics(model, data, q);
    Matrix6x7 jacobian;
    zero_jacobian(data, Frame::kEndEffector, jacobian);
    crba(model, data, q);
    Vector7 coriolis, gravity, tau;
    coriolis_torque(model, data, q, dq, coriolis);
    gravity_torque(model, data, q, gravity);
    rnea(model, data, q, dq, ddq, tau);
    const Vector7 friction = friction_torque(model.parameters().friction, dq);

    const nlohmann::json out = {
        {"O_T_F", column_major(data.O_T_F.matrix())},
        {"O_T_EE", column_major(data.O_T_EE.matrix())},
        {"zero_jacobian", column_major(jacobian)},
        {"mass", column_major(data.mass_matrix)},
        {"coriolis", column_major(coriolis)},
        {"gravity", column_major(gravity)},
        {"tau", column_major(tau)},
        {"friction", column_major(friction)},
        {"tau_total", column_major(Vector7(tau + friction))},
    };
    // JSON has no inf or NaN (nlohmann writes null): a result that overflowed is an input error.
    for (const auto& [key, values] : out.items())
      for (const auto& v : values)
        if (!std::isfinite(v.get<double>()))
          throw UsageError(key + " is not finite at this state (the inputs are too large for double precision)");
    std::cout << out.dump() << '\n';
    return 0;
  };
}

}  // namespace csp::cli
