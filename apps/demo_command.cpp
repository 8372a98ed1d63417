// csp demo: the main job of the foundation: model quantities of both robots at the ready pose,
// the Panda's identified model next to the robot's own (libfranka) model, and the workspace figures.
#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp::cli {
namespace {

void print_row(const char* label, const Vector7& v) {
  std::printf("  %-34s", label);
  for (int i = 0; i < kNumJoints; ++i) std::printf(" %8.3f", v[i]);
  std::printf("\n");
}

// Ready pose of libfranka's examples.
const Vector7 kReady = (Vector7() << 0.0, -M_PI_4, 0.0, -3.0 * M_PI_4, 0.0, M_PI_2, M_PI_4).finished();

void describe(const std::string& robot, const std::string& inertia, const std::string& friction) {
  ModelArguments arguments;
  arguments.robot = std::string(CSP_SOURCE_DIR) + "/configs/robots/" + robot + ".yaml";
  arguments.inertia = inertia;
  arguments.friction = friction;
  arguments.end_effector = "hand";
  const Model model = arguments.build();
  Data data;
  const Vector7 dq = Vector7::Constant(0.5), ddq = Vector7::Constant(1.0);
  Vector7 gravity, tau;
  forward_kinematics(model, data, kReady);
  gravity_torque(model, data, kReady, gravity);
  crba(model, data, kReady);
  rnea(model, data, kReady, dq, ddq, tau);
  const Vector3 p = data.O_T_EE.translation;
  std::printf("%s, inertia %s, Franka Hand, friction %s, ready pose\n", robot.c_str(), inertia.c_str(), friction.c_str());
  std::printf("  %-34s %8.4f %8.4f %8.4f\n", "O_T_EE position [m]", p.x(), p.y(), p.z());
  print_row("gravity g(q) [N m]", gravity);
  print_row("mass matrix diagonal [kg m^2]", data.mass_matrix.diagonal());
  print_row("M ddq + c + g, dq=0.5, ddq=1 [N m]", tau);
  print_row("friction at dq = 0.5 rad/s [N m]", friction_torque(model.parameters().friction, dq));
  if (robot == "panda") {
    arguments.inertia = "libfranka_fit";
    const Model robot_model = arguments.build();
    Vector7 believed;
    gravity_torque(robot_model, data, kReady, believed);
    print_row("g(q) in libfranka's model [N m]", believed);
    print_row("identified - libfranka [N m]", gravity - believed);
  }
  std::printf("\n");
}

}  // namespace

Command add_demo_command(CLI::App& app) {
  auto workspace = std::make_shared<WorkspaceArguments>();
  workspace->samples = 200'000;
  workspace->out = "demo_out";
  CLI::App* command = app.add_subcommand("demo", "Model quantities of the Panda and FR3 at the ready pose, and the workspace figures");
  command->add_option("--samples", workspace->samples, "Workspace samples")->capture_default_str();
  command->add_option("--out", workspace->out, "Directory for the workspace figures")->capture_default_str();
  return [workspace] {
    // Before anything is printed (run_workspace checks them again, after the model quantities).
    if (workspace->samples <= 0 || workspace->samples > kMaxWorkspaceSamples)
      throw UsageError("--samples: expected 1 to " + std::to_string(kMaxWorkspaceSamples) + " samples, got " +
                       std::to_string(workspace->samples));
    Outputs().directory("--out", workspace->out, {"workspace_side.svg", "workspace_top.svg"}).check();
    std::printf("CSP demo: q_ready = [0, -pi/4, 0, -3pi/4, 0, pi/2, pi/4] rad\n\n");
    describe("panda", "gaz2019", "gaz2019");
    describe("fr3", "franka_description", "none");
    WorkspaceArguments arguments = *workspace;
    arguments.model.end_effector = "none";
    return run_workspace(arguments);
  };
}

}  // namespace csp::cli
