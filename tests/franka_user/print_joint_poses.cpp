// Prints the pose of every frame (joint 1 to end effector) in the base frame, computed by
// franka::Model from one robot state.
#include <array>
#include <iostream>

#include <franka/exception.h>
#include <franka/model.h>

namespace {
template <class T, size_t N>
std::ostream& operator<<(std::ostream& stream, const std::array<T, N>& array) {
  stream << "[";
  for (size_t i = 0; i < N; ++i) {
    stream << (i == 0 ? "" : ",") << array[i];
  }
  return stream << "]";
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  try {
    franka::Robot robot(argv[1]);
    const franka::RobotState state = robot.readOnce();
    const franka::Model model(robot.loadModel());

    for (franka::Frame frame = franka::Frame::kJoint1; frame <= franka::Frame::kEndEffector;
         frame++) {
      std::cout << model.pose(frame, state) << std::endl;
    }
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
