// franka::Duration: CSP's clock type under libfranka's name (whole milliseconds).
#pragma once

#include "csp/rt/duration.hpp"

namespace franka {

using Duration = csp::rt::Duration;

}  // namespace franka
