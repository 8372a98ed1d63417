// The emulator's clock: franka::Duration, a whole number of milliseconds.
#pragma once

#include "franka/duration.h"

namespace csp::rt {

using Duration = franka::Duration;

}  // namespace csp::rt
