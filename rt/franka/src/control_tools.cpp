#include "franka/control_tools.h"

#include <pthread.h>
#include <sched.h>

#include <cstring>
#include <fstream>

namespace franka {

bool hasRealtimeKernel() {
  std::ifstream realtime("/sys/kernel/realtime");
  int flag = 0;
  return realtime >> flag && flag == 1;
}

bool setCurrentThreadToHighestSchedulerPriority(std::string* error_message) {
  sched_param parameters{};
  parameters.sched_priority = sched_get_priority_max(SCHED_FIFO);
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &parameters);
  if (error != 0) {
    if (error_message) *error_message = std::string("libfranka: unable to set realtime scheduling: ") + std::strerror(error);
    return false;
  }
  return true;
}

}  // namespace franka
